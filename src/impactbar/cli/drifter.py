"""Command-line pieces for a hydraulic drifter (a valve switched on the piston's position, theory
§10), taken by ``impactbar orbits``, ``simulate`` and ``continue`` when the config has a ``[valve]``
section or the preset is a drifter's (:data:`impactbar.physical.DRIFTER_PRESETS`); with a
``[chambers]`` section (or a preset of :data:`impactbar.physical.CIRCUIT_PRESETS`) a drifter with
its oil circuit (theory §11), taken by ``orbits`` and ``continue``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .. import physical
from ..physical import tree
from ..physical.circuit_graph import part_lines
from ..physical.config import config_kind, read_toml
from ..physical.display_units import format_key
from ..physical.outputs import OUTPUTS
from ..physical.units import to_si
from ._common import json_ready, print_json, require

__all__ = ["add_parser", "drifter_from_args", "run_drifter_orbits", "run_drifter_simulate",
           "run_drifter_continue"]


def add_parser(sub) -> None:
    """``impactbar drifter CONFIG.toml | --preset NAME [--json]``: a drifter's operating point."""
    import argparse
    import textwrap

    from .physical import add_physical_arguments

    description = (
        "The periodic motion of a hydraulic drifter in SI units: its valve switched on the "
        "piston's position (a config with a [valve] section, theory section 10) or with its oil "
        "circuit (a [chambers] section: chambers, pump, accumulator, relief, theory section 11). "
        "Prints the blow frequency, impact velocity and energy, and, with the circuit, the impact "
        "power, mean supply pressure, pump power, hydraulic efficiency (the energy the blows deliver "
        "over the pump's work), minimum pressure, stability, and whether the relief valve opens and the "
        "accumulator empties. "
        "'impactbar continue CONFIG --parameter accumulator.precharge --to \"12 MPa\"' follows it.")
    p = sub.add_parser(
        "drifter",
        help="a hydraulic drifter's operating point (blow frequency, impact energy, pressures, stability)",
        description=textwrap.fill(description, 78), epilog=drifter_keys_help(),
        formatter_class=argparse.RawDescriptionHelpFormatter)
    add_physical_arguments(p, config_help="a drifter in SI units: a TOML file with a [valve] section "
                           "(the valve switched on the piston's position) or a [chambers] section (with "
                           "its oil circuit); the keys of each are listed below", hammers=False)
    p.add_argument("--json", action="store_true",
                   help="print JSON instead of a table (strict JSON: non-finite numbers as null)")
    p.set_defaults(func=_run_drifter)


def drifter_keys_help(width: int = 78) -> str:
    """The sections and keys of both drifters' configurations, from the tables their readers check
    (:func:`impactbar.physical.config_keys`), for ``impactbar drifter --help``."""
    import textwrap

    from ..physical.config import CONFIG_KINDS
    from ..physical.rock import ROCK_SECTIONS

    def rows(keys: dict) -> list[str]:
        return [textwrap.fill(", ".join(k), width, initial_indent=f"  {f'[{name}]':16s}",
                              subsequent_indent=" " * 18) for name, k in keys.items()]

    drill = {}
    lines = []
    for kind in ("drifter", "circuit"):
        keys = physical.config_keys(kind)
        drill = {n: k for n, k in keys.items() if n.split(".")[0] in ROCK_SECTIONS}
        what = CONFIG_KINDS[kind].what.replace("§", "section ")
        lines += [textwrap.fill(f"configuration keys of {what}:", width),
                  *rows({n: k for n, k in keys.items() if n not in drill}), ""]
    lines += [textwrap.fill("either drifter on a drill string and the rock ([stop] then left out; "
                            "[[rod.segments]] an array of tables):", width), *rows(drill)]
    return "\n".join(lines)


def _run_drifter(args) -> int:
    drifter = drifter_from_args(args)
    if drifter is None:
        from ..physical.config import CONFIG_KINDS

        what = (f"{args.config} is {CONFIG_KINDS['hammer'].what}" if getattr(args, "config", None)
                else "no input")
        presets = ", ".join(sorted({*physical.DRIFTER_PRESETS, *physical.CIRCUIT_PRESETS}))
        raise ValueError(f"impactbar drifter needs a drifter: a CONFIG.toml with a [valve] or [chambers] "
                         f"section, or --preset {presets}; got {what}")
    return run_drifter_orbits(args, drifter)


def drifter_from_args(args):
    """The drifter named by ``args.preset`` or ``args.config`` (a TOML file with a ``[valve]`` or a
    ``[chambers]`` section, read by :func:`impactbar.physical.load`), else ``None`` (a hammer's
    preset or file, or no SI input).

    Raises
    ------
    ValueError
        Both a config and a preset; a missing or unreadable file, invalid TOML (its line), a sweep
        spec, or an invalid drifter config (the key named).
    """
    from .physical import check_one_source

    check_one_source(args)
    name, config = getattr(args, "preset", None), getattr(args, "config", None)
    if name is not None and name in physical.DRIFTER_PRESETS:
        return physical.drifter_preset(name)
    if name is not None and name in physical.CIRCUIT_PRESETS:
        return physical.circuit_preset(name)
    if config is None:
        return None
    return None if config_kind(read_toml(config)) == "hammer" else physical.load(config)


def _what_is_struck(d) -> str:
    """The header's words on what the piston strikes: the stop (its restitution) or the drill string
    on the rock; a line's end."""
    if d.drill is None:
        return f"R = {d.restitution:.4g}\n"
    return (f"a drill string of {len(d.drill.segments)} segment(s) on rock "
            f"(k = {d.drill.rock_k_N_m / 1e6:.4g} kN/mm)\n")


def _circuit_header(d: physical.CircuitDrifter) -> str:
    m, dr = d.model(), d.drive()
    si = d.si
    def shown(value, unit, key):  # in the unit the config wrote the key in, else the display unit
        return format_key(value, unit, d.config or {}, key, 4)

    acc = (f"accumulator {shown(si['accumulator_volume_m3'], 'm**3', 'accumulator.volume')} at "
           f"{shown(si['precharge_Pa'], 'Pa', 'accumulator.precharge')}"
           if si["accumulator_volume_m3"] > 0 else "no accumulator")
    shape = "" if isinstance(d.bar, physical.Bar) else f" ({d.bar.describe()})"
    return (f"drifter {d.name or '(unnamed)'} with its oil circuit: piston {d.bar.mass_kg:.4g} kg{shape}, "
            f"areas {si['rear_area_m2'] * 1e4:.4g} / {si['front_area_m2'] * 1e4:.4g} cm^2, pump "
            f"{shown(si['pump_flow_m3_s'], 'm**3/s', 'supply.pump_flow')}, {acc}, "
            + _what_is_struck(d)
            + f"  dimensionless (pressures in 10 MPa): s = {m.s:.5g}, N = {m.n_modes}, "
            f"precharge = {dr.value('precharge') if dr.accumulator is not None else float('nan'):.5g}, "
            f"pump_flow = {dr.value('pump_flow'):.5g}"
            + ("" if d.valve_stand_in else f", switch_out = {dr.value('switch_out'):.5g}")
            + "".join(f"\n  {line}" for line in part_lines(d)))


def run_circuit_orbits(args, drifter: physical.CircuitDrifter) -> int:
    """``impactbar orbits CONFIG`` with a ``[chambers]`` section: the operating point of the drifter
    with its oil circuit (theory §11) in SI."""
    return _print_orbit(args, drifter, _circuit_header, _circuit_line)


def _said(s: dict, name: str, named: bool = True, fmt: str = ".4g") -> str:
    """``"name value unit"``: the output ``name``'s value in the summary ``s`` (an operating point's or
    a run's), under its key and in its display unit as the registry (:mod:`~impactbar.physical.outputs`)
    declares them, after its name in words where ``named`` (``mean supply pressure``)."""
    o = OUTPUTS[name]
    unit = "" if o.shown_unit in ("", "1") else f" {o.shown_unit}"
    return f"{o.name.replace('_', ' ')} " * named + f"{s[o.shown_key]:{fmt}}{unit}"


def _motion(s: dict) -> str:
    """The blows' frequency, velocity and energy: the line's start for both drifters."""
    return ", ".join([_said(s, "blow_frequency"), _said(s, "impact_velocity"), _said(s, "impact_energy")])


def _stability(s: dict) -> str:
    """Stable or not, and the first non-trivial multiplier's modulus."""
    return f"{'stable' if s['stable'] else 'unstable'} (|mu| = {s['multiplier']:.4g})"


def _circuit_line(s: dict) -> str:
    return (f"  {_motion(s)}, {_said(s, 'impact_power')}, {_said(s, 'mean_supply_pressure')}, "
            f"{_said(s, 'pump_power')}, {_said(s, 'hydraulic_efficiency', fmt='.3f')} "
            "(the energy the blows deliver, the impact's less the rebound's, over the pump's work), "
            f"{_said(s, 'minimum_pressure')}"
            + (" (cavitates)" if s["cavitates"] else "")
            + f", {_stability(s)}\n"
            + f"  {_borders_line(s)}" + _added_line(s))


def _added_line(s: dict) -> str:
    """The summary's outputs added by :func:`~impactbar.physical.outputs.register_output`, each with
    its long name and display unit (``""`` where there are none)."""
    from ..physical.outputs import added_outputs

    shown = [o for o in added_outputs("summary") if o.shown_key in s]
    return "".join(f"\n  {o.long_name}: " + (f"{s[o.shown_key]}" if o.dtype == "b1" else
                                             f"{s[o.shown_key]:.6g} {o.shown_unit}".rstrip())
                   for o in shown)


def _borders_line(s: dict) -> str:
    """The relief valve's opening and the accumulator's emptying over the period, from the orbit's
    border margins (in their display unit, MPa; infinite where the circuit has no such part)."""
    relief_, acc_ = OUTPUTS["relief_margin"], OUTPUTS["accumulator_margin"]
    relief, acc, unit = s[relief_.shown_key], s[acc_.shown_key], relief_.shown_unit
    if relief == float("inf"):
        words = ["no relief valve"]
    elif relief < 0.0:
        words = [f"the relief valve opens (the supply pressure reaches {-relief:.4g} {unit} above its "
                 "setting)"]
    else:
        words = [f"the relief valve stays shut (the supply pressure peaks {relief:.4g} {unit} below its "
                 "setting)"]
    unit = acc_.shown_unit
    if acc == float("inf"):
        words.append("no accumulator")
    elif acc < 0.0:
        words.append(f"the accumulator empties (the supply pressure falls {-acc:.4g} {unit} below its "
                     "pre-charge)")
    else:
        words.append(f"the accumulator never empties (the supply pressure stays {acc:.4g} {unit} above its "
                     "pre-charge)")
    return "; ".join(words)


def _print_orbit(args, drifter, header, line) -> int:
    """The orbit's summary as JSON (``--json``), else the drifter's ``header``, the orbit's ``line``
    and, with a drill string and rock (theory §4d), the blow's figures (solved with the circuit
    where there is one)."""
    s = drifter.orbit().summary()
    if getattr(args, "json", False):
        print_json({"drifter": drifter.name, "orbit": s})
        return 0
    print(header(drifter))
    print(line(s))
    if "rock" in s:
        _print_rock(s["rock"])
    return 0


def _print_rock(r: dict) -> None:
    print(f"  per blow: {_said(r, 'work_on_rock')}, {_said(r, 'penetration')}, "
          f"{_said(r, 'efficiency', fmt='.3f')} ({r['efficiency_with_rebound']:.3f} with the rebound "
          f"credited); {_said(r, 'drilling_rate')}")


def _header(d: physical.Drifter) -> str:
    m, dr = d.model(), d.drive()
    shape = (f"L = {d.bar.length_m:.4g} m" if isinstance(d.bar, physical.Bar) else d.bar.describe())
    return (f"drifter {d.name or '(unnamed)'}: piston {d.bar.mass_kg:.4g} kg, {shape}; "
            f"stroke {d.stroke_force_N:.4g} N, return {d.return_force_N:.4g} N, switch at "
            f"{d.switch_out_m * 1e3:.4g} mm, delay {d.delay_s * 1e3:.4g} ms, "
            + _what_is_struck(d)
            + f"  dimensionless: s = {m.s:.5g}, d = {m.d:.5g}, N = {m.n_modes}, ret = {dr.ret:.5g}, "
            f"switch_out = {dr.switch_out:.5g}, delay = {dr.delay:.5g}")


def run_drifter_orbits(args, drifter: physical.Drifter) -> int:
    """``impactbar orbits --preset drifter-... [--json]``: the drifter's one-impact periodic motion
    (unknown period) with its SI figures."""
    if isinstance(drifter, physical.CircuitDrifter):
        return run_circuit_orbits(args, drifter)
    return _print_orbit(args, drifter, _header, _line)


def _line(s: dict) -> str:
    return (f"  {_motion(s)}, {_said(s, 'impact_power')}, {s['admissibility']}, "
            f"{_stability(s)}")


def run_drifter_simulate(args, drifter: physical.Drifter, out: Path, gap_m: float) -> int:
    """``impactbar simulate --preset hydraulic-drifter --out DIR``: simulate ``--periods`` blow
    periods (of the periodic motion) from rest at ``--gap``; writes ``impacts.csv``,
    ``summary.json``, ``motion.png`` and ``blows.png``, and on a drill string ``forces.png`` and
    ``stress.png`` (a blow's force history, the stress along the rod)."""
    if isinstance(drifter, physical.CircuitDrifter):
        return run_circuit_simulate(args, drifter, out, gap_m)
    period = drifter.orbit().period_s
    tr, s = drifter.simulate(args.periods * period, start_gap_m=gap_m)
    om, L = drifter.omega_rad_s, drifter.bar.length_m
    lines = ["time_s,impact_velocity_m_s"]
    lines += [f"{t / om:.9g},{v * L * om:.9g}" for t, v in zip(tr.impact_times, tr.impact_velocities,
                                                                 strict=True)]
    (out / "impacts.csv").write_text("\n".join(lines) + "\n")
    summary = dict(s, n_impacts=tr.n_impacts, n_switches=len(tr.switch_kinds))
    (out / "summary.json").write_text(json.dumps(json_ready(summary), indent=2, allow_nan=False))
    written = _drifter_figures(drifter, tr, out)
    print(f"{drifter.name or 'drifter'}: {tr.n_impacts} impacts in {tr.t_end / om:.4g} s; second half: "
          f"{_said(s, 'blow_frequency', False)}, {_said(s, 'impact_velocity', False)}, "
          f"{_said(s, 'impact_energy', False)} per blow, {_said(s, 'impact_power', False)}"
          + (f"; on rock {_said(s, 'work_on_rock', False)} and {_said(s, 'penetration', False)} per blow, "
             f"{_said(s, 'drilling_rate', False)}" if OUTPUTS["drilling_rate"].shown_key in s else "")
          + f"; wrote {out}/{written}, impacts.csv, summary.json")
    return 0


def run_circuit_simulate(args, drifter: physical.CircuitDrifter, out: Path, gap_m: float) -> int:
    """``impactbar simulate --preset circuit-drifter``: the drifter with its oil circuit from rest at
    ``--gap`` for ``--periods`` periods of its operating point; writes ``impacts.csv`` (time,
    impact velocity and energy, and on a drill string each blow's work on rock and permanent
    penetration), ``pressures.csv`` (the pressures, the valve and the gap),
    ``summary.json`` and ``motion.png`` (:func:`impactbar.plotting.plot_circuit_run`)."""
    if not args.periods > 0:
        raise ValueError(f"--periods must be > 0; got {args.periods}")
    point = drifter.orbit()
    r = drifter.simulate(args.periods * point.period_s, start_gap_m=gap_m)
    m = drifter.bar.mass_kg
    t, v = r["impact_times_s"], r["impact_velocities_m_s"]
    cols = {"time_s": t, "impact_velocity_m_s": v, "impact_energy_J": 0.5 * m * v * v}
    if drifter.drill is not None:  # on the drill string: each blow's work on rock and penetration
        cols.update(work_on_rock_J=r["work_on_rock_J"], penetration_m=r["penetration_mm"] / 1e3)
    lines = [",".join(cols)] + [",".join(f"{x:.9g}" for x in row) for row in zip(*cols.values(), strict=True)]
    (out / "impacts.csv").write_text("\n".join(lines) + "\n")
    h = r["histories"]
    keys = ("t_s", "p_f_Pa", "p_r_Pa", "p_s_Pa", "x_v", "gap_m")
    rows = [",".join(keys)] + [",".join(f"{x:.9g}" for x in row) for row in zip(*(h[k] for k in keys),
                                                                              strict=True)]
    (out / "pressures.csv").write_text("\n".join(rows) + "\n")
    last, least = v[len(v) // 2:], OUTPUTS["minimum_pressure"]
    summary = {"duration_s": float(args.periods * point.period_s), "n_impacts": int(t.size),
               "last_impact_velocity_m_s": float(v[-1]) if v.size else None,
               "mean_impact_energy_second_half_J": float(np.mean(0.5 * m * last ** 2)) if last.size else None,
               "operating_point": point.summary(),
               least.shown_key: float(least.shown(min(np.min(h[k]) for k in ("p_f_Pa", "p_r_Pa", "p_s_Pa"))))}
    if drifter.drill is not None:
        half = slice(len(v) // 2, None)
        summary.update({f"mean_{k}_second_half": float(np.mean(cols[k][half])) if last.size else None
                        for k in ("work_on_rock_J", "penetration_m")})
    (out / "summary.json").write_text(json.dumps(json_ready(summary), indent=2, allow_nan=False))
    written = "impacts.csv, pressures.csv, summary.json"
    try:
        import matplotlib
    except ImportError:
        matplotlib = None
    if matplotlib is not None:
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from ..plotting.circuit import plot_circuit_run

        axes = plot_circuit_run(r, mass_kg=m)
        axes[0].figure.savefig(out / "motion.png", dpi=120)
        plt.close(axes[0].figure)
        written += ", motion.png"
    print(f"{drifter.name or 'drifter'}: {t.size} impacts in {summary['duration_s']:.4g} s from rest at "
          f"{gap_m * 1e3:.4g} mm; the last at {v[-1] if v.size else float('nan'):.4g} m/s (the operating "
          f"point's {point.impact_velocity_m_s:.4g} m/s); wrote {out}/{written}")
    return 0


def _drifter_figures(drifter: physical.Drifter, run, out: Path) -> str:
    """motion.png and blows.png, as a hammer's run gets them; on a drill string also forces.png (the
    force history of the last blow at every boundary and on the rock) and stress.png (the stress
    along the rod in that blow). Returns the names written."""
    require("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plotting.physical import (
        plot_blow_forces,
        plot_drifter_blows,
        plot_drifter_motion,
        plot_rod_stress,
    )

    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6), constrained_layout=True)
    plot_drifter_motion(drifter, run, axes)
    fig.savefig(out / "motion.png", dpi=120)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(8, 3.5), constrained_layout=True)
    plot_drifter_blows(drifter, run, ax)
    fig.savefig(out / "blows.png", dpi=120)
    plt.close(fig)
    written = "motion.png, blows.png"
    records = [r for i in range(len(run.pieces)) for r in getattr(run.pieces[i], "impacts", ())
               if getattr(r, "blow", None) is not None] if drifter.drill is not None else []
    if records:
        fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
        plot_blow_forces(drifter, records[-1], ax)
        fig.savefig(out / "forces.png", dpi=120)
        plt.close(fig)
        fig, ax = plt.subplots(figsize=(8, 3.5), constrained_layout=True)
        plot_rod_stress(drifter, records[-1], ax)
        fig.savefig(out / "stress.png", dpi=120)
        plt.close(fig)
        written += ", forces.png, stress.png"
    return written


def _user_unit(field, to):
    """The unit the user gave ``--to`` in (``"L/min"`` for ``"100 L/min"``), else the SI unit of the
    key's declaration ``field``, and the conversion of an SI value into it (the unit read as every
    config value is)."""
    si_unit = field.unit
    written = to.split(None, 1)[1].strip() if isinstance(to, str) and len(to.split(None, 1)) > 1 else ""
    if si_unit and written:
        factor = to_si(f"--to {to!r}", f"1 {written}", si_unit, field.example)  # SI per given unit
        if factor != 1.0:
            return written, lambda x: x / factor
    return si_unit.replace("**", "^"), float


def run_drifter_continue(args, drifter: physical.Drifter, out: Path) -> int:
    """``impactbar continue --preset drifter-... --parameter delay --to X``: the drifter's orbit
    continued in a dimensionless parameter (theory §10), or an oil circuit's in a config key in SI;
    writes ``branch.csv`` and ``events.csv``, every column from a declaration
    (:mod:`~impactbar.physical.branch_table`: a config key's value first, in the unit ``--to`` was
    given in; the dimensionless parameter and orbit; for a circuit the outputs of the view
    ``"branch"`` in display units)."""
    from ..continuation import continue_orbit
    from ..physical.branch_table import branch_outputs, branch_rows, event_rows

    name, to = args.parameter, args.to
    si = tree.is_config_key(name)  # a config key in SI: supply.pump_flow, a part's, ...
    circuit = isinstance(drifter, physical.CircuitDrifter)
    if si and not circuit:
        raise ValueError(f"--parameter {name} (a config key in SI) is a parameter of a drifter with its "
                         "oil circuit; this drifter's valve takes stroke, ret, switch_out, delay, "
                         "delay_out, delay_in")
    if si:
        parameter, to = drifter.to_dimensionless(name, to)
        unit, convert = _user_unit(drifter.key_field(name), args.to)

        def shown(x):
            return convert(drifter.from_dimensionless(name, x))
    else:
        if isinstance(to, str):
            raise ValueError(f"--to must be a number for --parameter {name} (dimensionless); got {to!r}")
        parameter, unit = name, ""

        def shown(x):
            return x
    diagram, points = None, ()
    if circuit:  # the SI branch and its bifurcation diagram
        sib = physical.continue_circuit(drifter, name, args.to if si else to, step=args.step,
                                        max_step=args.max_step, max_points=args.max_points)
        b, points = sib.branch, sib.points
        diagram = _circuit_diagram(sib, out)
    else:
        start = drifter.orbit().orbit
        b = continue_orbit(start, parameter, to, step=args.step, max_step=args.max_step,
                           max_points=args.max_points)
    key = (f"{name} ({unit})" if unit else name) if si else None  # (a bare number: no unit)
    rows = branch_rows(b, key=key, shown=shown, points=points, columns=branch_outputs(circuit))
    (out / "branch.csv").write_text("\n".join(rows) + "\n")
    (out / "events.csv").write_text("\n".join(event_rows(b, key=key, shown=shown)) + "\n")
    files = [out / "branch.csv", out / "events.csv"] + ([diagram] if diagram is not None else [])
    if getattr(args, "json", False):
        print_json({"parameter": name, "to": args.to, "points": len(b), "status": b.status,
                    "events": [{"kind": e.kind, "value": shown(e.value)} for e in b.events],
                    "files": [str(f) for f in files]})
        return 0
    print(_circuit_header(drifter) if isinstance(drifter, physical.CircuitDrifter) else _header(drifter))
    print(f"  {len(b)} points, {b.status}; events: "
          + (", ".join(f"{e.kind} at {name} = {shown(e.value):.6g}{' ' + unit if unit else ''}"
                       for e in b.events) or "none"))
    for f in files:
        print(f"wrote {f}")
    return 0


def _circuit_diagram(branch, out: Path):
    """``diagram.png``: the circuit's bifurcation diagram in SI (None without matplotlib)."""
    try:
        import matplotlib
    except ImportError:
        return None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    axes = branch.plot()
    path = out / "diagram.png"
    axes[0].figure.savefig(path, dpi=130)
    plt.close(axes[0].figure)
    return path
