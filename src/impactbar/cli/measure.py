"""``impactbar measure SPEC.toml``: a split-Hopkinson (Kolsky) bar recording from its raw channels to
the pulses' windows, the striker's impact velocity, the waves' energies, the specimen's stress-strain
summary and the diagnostics (the gauges of a bar compared, the force balance, the noise's lines);
``--out`` writes the waves at the specimen and its stress-strain curves as CSV, and the figure. A drill
rod's spec (its ``[bit]``) gives the waves at the bit from two gauges, its force, penetration and
energy, the rock's stiffnesses from the force-penetration curve and the model's blow fitted."""

from __future__ import annotations

from ._common import docs_page, output_folder, print_json


def add_parser(sub) -> None:
    p = sub.add_parser(
        "measure",
        help="a Kolsky-bar or drill-rod recording to waves, forces, energies, stress-strain or the rock",
        description="Read the channels a TOML spec names (Tektronix CSV, .npz, plain CSV columns), "
        "convert them to strain by their bridges, find the incident, reflected and transmitted pulses "
        "where the bars leave their noise band, shift them to the specimen and print the windows, the "
        "striker's impact velocity, the wave energies, the one-, two- and three-wave stress-strain "
        "summary and the diagnostics; for a drill rod's spec (its [bit]) the waves at the bit from two "
        "gauges, its force, penetration and energy, the rock's stiffnesses and the model's blow fitted "
        f"(see {docs_page('Measurements')}).",
    )
    p.add_argument("measurement", metavar="SPEC.toml",
                   help="the measurement's TOML spec: its files, channels, bars, specimen (e.g. "
                        "examples/shpb_pmma13.toml)")
    p.add_argument("--json", action="store_true", help="print the whole report as JSON")
    p.add_argument("--out", default=None,
                   help="folder for waves.csv (the strains at the specimen's faces), stress_strain.csv and "
                        "kolsky.png (the bars' strains with the windows found, the waves, the curves); for "
                        "a drill rod bit.csv (the waves, force, velocity, penetration, energy) and "
                        "drill_rod.png")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..measure import DrillRodTest, run_spec

    out = output_folder(args.out) if args.out is not None else None
    test = run_spec(args.measurement)
    drill = isinstance(test, DrillRodTest)
    if out is not None:
        (_write_bit_csv if drill else _write_csv)(out, test)
        test.plot(out / ("drill_rod.png" if drill else "kolsky.png"))
    if args.json:
        print_json(test.report)
    else:
        print(drill_text(test.report) if drill else summary_text(test.report))
    return 0


def _write_bit_csv(out, test) -> None:
    import numpy as np

    w, b = test.waves, test.bit
    np.savetxt(out / "bit.csv", np.column_stack([w.time * 1e6, w.toward, w.away, b.force, b.velocity,
                                                 b.displacement, b.energy_fv]),
               delimiter=",", header="time_us,toward,away,force_N,velocity_m_s,penetration_m,energy_J",
               comments="")


def drill_text(report: dict) -> str:
    """A drill rod's report in a few lines."""
    s, b, r = report["separation"], report["bit"], report["rock_from_curve"]
    (near, far), (near_m, far_m) = s["channels"], s["stations_m"]
    lines = [f"two-point separation: {near} at {near_m:g} m, {far} at "
             f"{far_m:g} m from the bit; first failing frequency "
             f"{s['first_failing_Hz'] / 1e3:.1f} kHz, low-passed at {s['cutoff_Hz'] / 1e3:.1f} kHz",
             f"bit: peak force {b['peak_force_kN']:.1f} kN, max penetration {b['max_penetration_mm']:.3f} mm",
             f"energies (J): incident {b['incident_energy_J']:.2f}, into the bit (force-velocity) "
             f"{b['energy_fv_J']:.2f}, force-squared {b['energy_f2_J']:.2f}",
             f"rock from the force-penetration curve: k {r['k']:.4g} +- {r['k_std']:.2g} N/m, "
             f"k_u {r['k_u']:.4g} +- {r['k_u_std']:.2g} N/m"]
    if "model_fit" in report:
        f = report["model_fit"]
        lines.append(f"model's blow fitted (misfit {100 * f['misfit']:.2f} %): " + ", ".join(
            f"{n} {f['values'][n]:.5g} +- {e:.2g}" for n, e in f["errors"].items()))
    return "\n".join(lines)


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
    f = a["reflection_fit"]
    lines.append(f"incident bar's wave speed from the reflection's delay {f['delay_us']:.3f} +- "
                 f"{f['delay_std_us']:.3f} us: {f['wave_speed_m_s']:.0f} +- "
                 f"{f['wave_speed_std_m_s']:.0f} m/s "
                 f"(ratio {f['ratio']:.3f}, misfit {100 * f['misfit']:.0f} %)")
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
            first, second = g["channels"]
            lines.append(f"{bar} bar: {second} = {g['scale']:.4f} x {first}, "
                         f"r.m.s. difference {100 * g['rms_difference']:.1f} % of the peak")
    lines.append(f"force balance: median |2 (F1 - F2) / (F1 + F2)| {d['force_balance']['median_abs']:.3f}")
    lines.append("noise lines: " + ", ".join(f"{c} {n['frequency_MHz']:.3f} MHz"
                                             for c, n in d["noise_lines"].items()))
    return "\n".join(lines)
