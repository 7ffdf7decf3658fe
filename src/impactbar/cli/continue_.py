"""``impactbar continue``: a branch of periodic motions in one parameter, its bifurcations, the
branches born at its period doublings, and a bifurcation diagram over a brute-force simulation."""

from __future__ import annotations

import math

import numpy as np

from ._common import add_deprecated_alias, add_quiet_argument, output_folder, print_json, refuse, stage_bar
from .orbits import add_bar_and_load_arguments, add_physical_arguments_if_installed, load_from_args
from .orbits import check_options as check_bar_and_load

TWO_PI = 2.0 * math.pi


def add_parser(sub) -> None:
    p = sub.add_parser(
        "continue",
        help="continue a periodic motion in one parameter: folds, period doublings, grazing",
        description="Pseudo-arclength continuation of a periodic motion with m impacts in n load "
        "periods (theory sections 4, 5, 7) in one parameter of the bar or the load, with its folds, "
        "period doublings (and the doubled branches, --doublings), Neimark-Sacker points, grazing "
        "and losses of admissibility located on the branch. Writes the branches (CSV, and netCDF "
        "where xarray is installed) and a bifurcation diagram over a brute-force simulation. "
        "Dimensionless inputs (eq. 2); a CONFIG.toml or --preset gives the bar and load in SI "
        "units, the parameter still varies in dimensionless units.",
    )
    add_bar_and_load_arguments(p)
    cg = p.add_argument_group("continuation")
    cg.add_argument("--parameter", required=True, metavar="PARAMETER",
                    help="the parameter that varies: any real parameter of the bar, its impact law, the "
                    "load or the drive (impactbar.parameters.parameters: p0, pk, R, d, s, q, kappa; a "
                    "drifter's valve stroke, ret, switch_out, delay, delay_out, delay_in; its oil "
                    "circuit's dimensionless precharge, pump_flow, ...: pressures in 10 MPa) or a "
                    "drifter's config key in SI (accumulator.precharge, supply.pump_flow, "
                    "valve.switching_time, oil.bulk_modulus, stop.restitution, ...: every key "
                    "impactbar.physical.tree declares continuable; on a drill string rock.k, rock.k_u, "
                    "rock.feed, bit.mass; --to with its unit, '12 MPa')")
    cg.add_argument("--to", type=_number_or_quantity, required=True,
                    help="its target value (with its unit for a config key: '12 MPa', '80 L/min')")
    cg.add_argument("--impacts", type=int, default=1, help="impacts m per period of the motion (default 1)")
    cg.add_argument("--load-periods", type=int, default=1, metavar="N",
                    help="load periods n per period of the motion (default 1); with m or n > 1 the "
                    "start is found from a simulation")
    add_deprecated_alias(cg, "--periods", "--load-periods", "load_periods", type=int)
    cg.add_argument("--orbit", default="stable",
                    help="the one-impact orbit to start from: 'stable' (default: the stable one, else "
                    "the first admissible, else the first) or its index in phase order")
    cg.add_argument("--doublings", type=int, default=0,
                    help="follow this many period doublings onto the doubled branches (default 0)")
    cg.add_argument("--curve", nargs=2, metavar=("PARAM", "TO"), default=None,
                    help="also follow every fold, period doubling and grazing point of the branches in "
                    "(parameter, PARAM) up to PARAM = TO: the chart edges (writes curve_*.csv, curves.png)")
    cg.add_argument("--step", type=float, default=None, help="initial arclength step")
    cg.add_argument("--max-step", type=float, default=None, help="largest arclength step")
    cg.add_argument("--max-points", type=int, default=2000, help="points per branch (default 2000)")
    og = p.add_argument_group("output")
    og.add_argument("--out", default="out/continue", help="output folder (default out/continue)")
    og.add_argument("--brute", type=int, default=40,
                    help="parameter values of the brute-force simulation diagram (default 40; 0: none)")
    og.add_argument("--transient", type=float, default=100.0,
                    help="load periods discarded at each brute-force value (default 100)")
    og.add_argument("--record", type=float, default=20.0,
                    help="load periods recorded at each brute-force value (default 20)")
    og.add_argument("--y", choices=("phase", "impact_velocity"), default="phase",
                    help="the diagram's ordinate (default phase, which separates the two sides of a "
                    "fold; the impact velocity is 2 pi p0/(1 + R) on every one-impact orbit)")
    og.add_argument("--json", action="store_true", help="print a JSON summary instead of a table")
    add_quiet_argument(og)
    add_physical_arguments_if_installed(p)
    p.set_defaults(func=run)


def _number_or_quantity(text: str):
    """``--to``: a number, or a quantity with its unit (``"12 MPa"``) for a config key."""
    try:
        return float(text)
    except ValueError:
        return text


def _model_and_load(args):
    from ..model import BarModel

    if getattr(args, "config", None) is not None or getattr(args, "preset", None) is not None:
        from .physical import hammer_from_args

        hammer = hammer_from_args(args)
        return hammer.model, hammer.load
    model = BarModel(s=args.s, d=args.d, R=args.R, n_modes=args.n_modes,
                     impact=getattr(args, "impact", None) or "paper")
    return model, load_from_args(args)


def _start(model, load, args):
    """The orbit the first branch starts from."""
    from ..orbits import find_orbit, periodic_orbits
    from ..simulation import InitialState, simulate

    if args.impacts < 1 or args.load_periods < 1:
        raise ValueError(f"--impacts and --load-periods must be >= 1; got {args.impacts}, "
                         f"{args.load_periods}")
    if args.impacts == 1 and args.load_periods == 1:
        orbits = periodic_orbits(model, load)
        if not orbits:
            raise ValueError("no one-impact orbit exists at the start values (above the existence edge)")
        if args.orbit == "stable":
            return sorted(orbits, key=lambda o: (not o.stable, not o.admissible))[0]
        try:
            i = int(args.orbit)
        except ValueError:
            raise ValueError(f"--orbit must be 'stable' or an index; got {args.orbit!r}") from None
        if not 0 <= i < len(orbits):
            raise ValueError(f"--orbit must be an index in [0, {len(orbits) - 1}]; got {i}")
        return orbits[i]
    tr = simulate(model, load, InitialState.rigid(-0.01, 0.0, n_modes=model.n_modes),
                  TWO_PI * max(300, 20 * args.load_periods))
    return find_orbit(model, load, args.impacts, args.load_periods, guess=tr)


def _check_parameter(model, load, name: str) -> None:
    """Refuse a ``--parameter`` the bar and load cannot be continued in, before any orbit is sought
    (:func:`impactbar.parameters.check_continuable`: the message lists the parameters there are)."""
    from ..parameters import check_continuable
    from ..physical.tree import FIELDS

    try:
        check_continuable(model, load, name)
    except ValueError as exc:
        hint = ("; a config key in SI needs a drifter config with its oil circuit ([chambers] section) "
                "or the preset circuit-drifter" if name in FIELDS else "")
        raise ValueError(f"--parameter {name}: {exc}{hint}") from None


def check_options(args) -> None:
    """Refuse the options the chosen mode ignores: the dimensionless inputs with a hammer in SI,
    the other load's options with ``--load``, ``--orbit`` when the start is found from a simulation
    (``--impacts`` or ``--load-periods`` above 1), and the brute-force diagram's options with
    ``--brute 0``.

    Raises
    ------
    UsageError
    """
    check_bar_and_load(args)  # the same bar and load options as ``impactbar orbits``
    if args.impacts != 1 or args.load_periods != 1:
        refuse(args, ("orbit",), because="with --impacts or --load-periods above 1 (the start is then found "
               "from a simulation; --orbit picks a one-impact orbit)")
    if args.brute == 0:
        refuse(args, ("transient", "record"), because="with --brute 0 (no brute-force simulation)")


def run(args) -> int:
    check_options(args)
    out = output_folder(args.out)
    if getattr(args, "config", None) is not None or getattr(args, "preset", None) is not None:
        from .drifter import drifter_from_args, run_drifter_continue

        drifter = drifter_from_args(args)  # a valve switched on the piston's position (theory §10)
        if drifter is not None:
            return run_drifter_continue(args, drifter, out)
    if isinstance(args.to, str):
        raise ValueError(f"--to must be a number for --parameter {args.parameter} (dimensionless); "
                         f"got {args.to!r}")
    model, load = _model_and_load(args)
    _check_parameter(model, load, args.parameter)
    if args.doublings < 0:
        raise ValueError(f"--doublings must be >= 0; got {args.doublings}")
    if args.brute < 0:
        raise ValueError(f"--brute must be >= 0; got {args.brute}")
    stages = 2 + (args.brute > 0) + (args.curve is not None)
    with stage_bar(stages, desc="continue", first="start", quiet=args.quiet) as bar:
        start = _start(model, load, args)
        bar.stage(f"branches in {args.parameter}")
        branches, diagram, written = _branches(start, model, load, args, out, bar)
        curves = []
        if args.curve:
            bar.stage("two-parameter curves")
            curves = _curves(branches, args, out, written)
        bar.stage("done")
    if args.json:
        doc = {"parameter": args.parameter, "to": args.to,
               "branches": [{"impacts": b.impacts, "periods": b.periods, "points": len(b),
                             "status": b.status, "start": float(b.values[0]), "end": float(b.values[-1]),
                             "events": [e.to_dict() for e in b.events]} for b in branches],
               "curves": [{"kind": c.kind, "parameters": list(c.parameters), "points": len(c),
                           "status": c.status, "start": c.values[0].tolist(), "end": c.values[-1].tolist()}
                          for c in curves],
               "files": [str(p) for p in written]}
        print_json(doc)
        return 0
    print(f"{model!r}\n{load!r}")
    for i, b in enumerate(branches):
        print(f"branch {i}: {b.impacts} impact(s) in {b.periods} period(s), {len(b)} points, "
              f"{args.parameter} from {b.values[0]:.10g} to {b.values[-1]:.10g} ({b.status})")
        for e in b.events:
            mu = "" if math.isnan(e.multiplier.real) else f"  multiplier {e.multiplier.real:+.6f}" \
                f"{e.multiplier.imag:+.6f}i"
            print(f"  {e.kind:>16} at {args.parameter} = {e.value:.12g}{mu}")
    for c in curves:
        print(f"{c.kind} curve in ({c.parameters[0]}, {c.parameters[1]}): {len(c)} points from "
              f"{c.values[0].round(10).tolist()} to {c.values[-1].round(10).tolist()} ({c.status})")
    for p in written:
        print(f"wrote {p}")
    return 0


def _branches(start, model, load, args, out, bar):
    """The cascade of branches from ``start``, written out, and the brute-force diagram."""
    from ..continuation import doubling_cascade, parameter_value, simulated_diagram

    kw = {"step": args.step, "max_step": args.max_step, "max_points": args.max_points}
    branches = list(doubling_cascade(start, args.parameter, args.to, doublings=args.doublings,
                                     **kw).branches)
    written = []
    for i, b in enumerate(branches):
        path = out / f"branch_{i}_{b.impacts}per{b.periods}.csv"
        b.to_dataframe().to_csv(path)
        written.append(path)
    events = [dict(e.to_dict(), branch=i) for i, b in enumerate(branches) for e in b.events]
    ev_path = out / "events.csv"
    _write_events(ev_path, events)
    written.append(ev_path)
    try:
        import xarray as xr  # noqa: F401
    except ImportError:
        pass
    else:
        for i, b in enumerate(branches):
            path = out / f"branch_{i}_{b.impacts}per{b.periods}.nc"
            b.to_xarray().to_netcdf(path)
            written.append(path)
    diagram = None
    if args.brute:
        bar.stage("brute-force diagram")
        lam0 = parameter_value(model, load, args.parameter)
        lo, hi = min(b.values.min() for b in branches), max(b.values.max() for b in branches)
        values = np.linspace(lam0, args.to, args.brute)
        values = values[(values >= lo) & (values <= hi)] if values.size > 1 else values
        q, v = start.modal_state_after_impact
        from ..simulation import InitialState

        # the flight starts after the impact (under the wave law: at the end of its window 2/s)
        t0 = float(start.impact_times[0]) if hasattr(start, "impact_times") else start.phase
        t0 += model.law.window(model)
        diagram = simulated_diagram(model, load, args.parameter, values, transient=args.transient,
                                    record=args.record, start=InitialState(q, v), t0=t0)
    try:
        path = _plot(branches, diagram, args, out)
    except ImportError:
        path = None
    if path is not None:
        written.append(path)
    return branches, diagram, written


def _curves(branches, args, out, written):
    """Two-parameter curves of every fold, period doubling and grazing point of the branches."""
    from ..continuation import continue_bifurcation

    name, to = args.curve
    to = float(to)
    curves = []
    for b in branches:
        for e in b.events:
            if e.kind in ("fold", "period-doubling", "grazing"):
                try:
                    curves.append(continue_bifurcation(e, name, to))
                except ValueError as exc:
                    print(f"warning: {e.kind} at {e.value:.10g} not followed: {exc}")
    for i, c in enumerate(curves):
        path = out / f"curve_{i}_{c.kind}.csv"
        c.to_dataframe().to_csv(path)
        written.append(path)
    if curves:
        try:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            return curves
        from ..plotting.continuation import plot_bifurcation_curves

        fig, ax = plt.subplots(figsize=(6, 4.5))
        plot_bifurcation_curves(curves, ax)
        path = out / "curves.png"
        fig.tight_layout()
        fig.savefig(path, dpi=130)
        plt.close(fig)
        written.append(path)
    return curves


def _write_events(path, events):
    cols = ["branch", "kind", "parameter", "value", "index", "phase", "impacts", "periods",
            "multiplier_real", "multiplier_imag"]
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(",".join(cols) + "\n")
        for e in events:
            real, imag = e["multiplier"]
            row = dict(e, multiplier_real=real, multiplier_imag=imag)
            fh.write(",".join(repr(row[c]) if isinstance(row[c], float) else str(row[c]) for c in cols)
                     + "\n")


def _plot(branches, diagram, args, out):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plotting.continuation import plot_bifurcation_diagram

    fig, ax = plt.subplots(figsize=(7, 4.5))
    plot_bifurcation_diagram(branches, diagram, ax, y=args.y)
    path = out / "diagram.png"
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path
