"""``impactbar measure SPEC.toml``: a split-Hopkinson (Kolsky) bar recording from its raw channels to
the pulses' windows, the striker's impact velocity, the waves' energies, the specimen's stress-strain
summary and the diagnostics (the gauges of a bar compared, the force balance, the noise's lines);
``--out`` writes the waves at the specimen and its stress-strain curves as CSV, and the figure."""

from __future__ import annotations

from ._common import docs_page, output_folder, print_json


def add_parser(sub) -> None:
    p = sub.add_parser(
        "measure",
        help="a Kolsky-bar recording to waves, impact velocity, energies and stress-strain",
        description="Read the channels a TOML spec names (Tektronix CSV, .npz, plain CSV columns), "
        "convert them to strain by their bridges, find the incident, reflected and transmitted pulses "
        "where the bars leave their noise band, shift them to the specimen and print the windows, the "
        "striker's impact velocity, the wave energies, the one-, two- and three-wave stress-strain "
        f"summary and the diagnostics (see {docs_page('Measurements')}).",
    )
    p.add_argument("measurement", metavar="SPEC.toml",
                   help="the measurement's TOML spec: its files, channels, bars, specimen (e.g. "
                        "examples/shpb_pmma13.toml)")
    p.add_argument("--json", action="store_true", help="print the whole report as JSON")
    p.add_argument("--out", default=None,
                   help="folder for waves.csv (the strains at the specimen's faces), stress_strain.csv and "
                        "kolsky.png (the bars' strains with the windows found, the waves, the curves)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..measure import run_spec

    out = output_folder(args.out) if args.out is not None else None
    test = run_spec(args.measurement)
    if out is not None:
        _write_csv(out, test)
        test.plot(out / "kolsky.png")
    if args.json:
        print_json(test.report)
    else:
        print(summary_text(test.report))
    return 0


def _write_csv(out, test) -> None:
    import numpy as np

    t_us = test.time * 1e6
    np.savetxt(out / "waves.csv", np.column_stack([t_us, test.incident, test.reflected, test.transmitted]),
               delimiter=",", header="time_us,incident,reflected,transmitted", comments="")
    sp = test.specimen
    cols = [t_us] + [a[k] for k in ("1", "2", "3") for a in (sp.strain, sp.stress, sp.strain_rate)]
    names = ",".join(f"{q}_{k}wave" for k in ("1", "2", "3") for q in ("strain", "stress_Pa", "strain_rate"))
    np.savetxt(out / "stress_strain.csv", np.column_stack(cols), delimiter=",", header="time_us," + names,
               comments="")


def summary_text(report: dict) -> str:
    """The report in a few lines."""
    lines = ["windows (us):"]
    for name, w in report["windows"].items():
        lines.append(f"  {name:12s} {w['start_us']:9.3f} .. {w['stop_us']:9.3f}")
    a = report["arrivals"]
    lines.append(f"reflected foot {a['reflected_early_us']:.2f} us before the computed "
                 f"{a['reflected_computed_us']:.2f} us")
    v = report["impact_velocity"]
    lines.append(f"impact velocity {v['velocity']:.2f} +- {v['uncertainty']:.2f} m/s")
    e = report["energies_J"]
    lines.append("energies (mJ): " + ", ".join(f"{k} {1e3 * x:.2f}" for k, x in e.items()))
    for k, s in report["stress_strain"].items():
        lines.append(f"{k}-wave: peak stress {s['peak_stress_MPa']:.1f} MPa at strain "
                     f"{s['strain_at_peak']:.4f}, "
                     f"mean strain rate {s['mean_strain_rate']:.0f} /s")
    d = report["diagnostics"]
    for bar, g in d["gauges"].items():
        if g:
            lines.append(f"{bar} bar: {g['channels'][1]} = {g['scale']:.4f} x {g['channels'][0]}, "
                         f"r.m.s. difference {100 * g['rms_difference']:.1f} % of the peak")
    lines.append(f"force balance: median |2 (F1 - F2) / (F1 + F2)| {d['force_balance']['median_abs']:.3f}")
    lines.append("noise lines: " + ", ".join(f"{c} {n['frequency_MHz']:.3f} MHz"
                                             for c, n in d["noise_lines"].items()))
    return "\n".join(lines)
