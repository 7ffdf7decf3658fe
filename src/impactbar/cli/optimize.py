"""``impactbar optimize CONFIG --vary KEY=LOW:HIGH ... --objective drilling_rate_per_kW``: the design of a
drifter with its oil circuit (piston shape, chambers, valve, circuit), or of a valve drifter, that
maximises an objective under the designer's constraints (:func:`impactbar.physical.optimize_drifter`).
"""

from __future__ import annotations

from ._common import add_quiet_argument, output_file, print_json

__all__ = ["add_parser", "parse_vary", "parse_constraint"]


def add_parser(sub) -> None:
    """Register ``impactbar optimize``."""
    from ..physical.optimize_drifter import DEFAULT_CONSTRAINTS, OBJECTIVES

    p = sub.add_parser(
        "optimize",
        help="optimise a drifter with its oil circuit (piston shape, chambers, valve, circuit) or a valve "
             "drifter for drilling rate per kW or another objective, under constraints",
        description="Search the design of a drifter with its oil circuit, or of a valve drifter, that "
                    "maximises an objective, each design's operating point on the rod and rock solved "
                    "(theory sections 10, 11); the machines and keys impactbar sweep maps (a hammer "
                    "neither). A valve drifter has no oil circuit: objectives impact_power, "
                    "work_on_rock_per_blow and drilling_rate, constraints of its outputs, methods cobyla, "
                    "differential_evolution and multistart with --polish 0. "
                    "Prints the baseline and the best design found side by side: every variable, "
                    "objective and constraint with its margin, and the design's first-order (KKT) "
                    "certificate; it is called the optimum only where that says converged.")
    p.add_argument("config", help="a drifter with its oil circuit (a TOML file with a [chambers] section; a "
                                  "[piston] section makes its diameters variables) or a valve drifter (a "
                                  "[valve] section), or a preset's name")
    p.add_argument("--vary", action="append", required=True, metavar="KEY=LOW:HIGH",
                   help="a variable and its bounds with units, e.g. piston.collar_diameter=47mm:52mm or "
                        "'accumulator.precharge=8 MPa:14 MPa' (repeat for each variable): any key "
                        "impactbar sweep takes; an integer key (model.n_modes=6:8, "
                        "rock.cells_per_piston) is enumerated, each value a search over the others, "
                        "at most 12 integer designs")
    p.add_argument("--objective", default="drilling_rate_per_kW", choices=list(OBJECTIVES),
                   help="what is maximised (default drilling_rate_per_kW)")
    p.add_argument("--constraint", action="append", default=[], metavar="NAME=VALUE",
                   help="a constraint's limit with its unit, e.g. 'peak_rod_stress=250 MPa' or "
                        "max_multiplier=0.9, or NAME=none to drop one; names: "
                        f"{', '.join(DEFAULT_CONSTRAINTS)}, or any output's name (at most the limit; "
                        "min_NAME: at least), e.g. 'min_blow_frequency=50 Hz'")
    p.add_argument("--impact-velocity", default=None, metavar="SPEED",
                   help="the circuit's ideal limit: each design its piston's blow on the rod and rock at "
                        "this impact velocity, e.g. '10 m/s' (objective work_on_rock_per_blow; constraints "
                        "peak_rod_stress and piston_mass)")
    p.add_argument("--max-evaluations", type=int, default=60,
                   help="the most designs the search evaluates (default 60)")
    p.add_argument("--method", default="cobyla",
                   choices=["cobyla", "slsqp", "differential_evolution", "multistart"],
                   help="the search: derivative-free COBYLA (default), SLSQP with gradients by the "
                        "implicit function theorem on each design's orbit, or differential evolution "
                        "(a population, each generation's designs evaluated together, see --workers), or "
                        "multistart (COBYLA from the best feasible designs of a Sobol sample evaluated "
                        "together, see --sample)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="differential_evolution, multistart: evaluate each generation (the sample) on a "
                        "local dask cluster of N worker processes (default: in this process, one design "
                        "after another)")
    p.add_argument("--popsize", type=int, default=5,
                   help="differential_evolution: the population per variable (default 5)")
    p.add_argument("--seed", type=int, default=0,
                   help="differential_evolution: the random seed; multistart: the sample's (default 0)")
    p.add_argument("--sample", type=int, default=64, metavar="N",
                   help="multistart: the Sobol sample's designs, a power of two (default 64)")
    p.add_argument("--local-starts", type=int, default=3, metavar="K",
                   help="multistart: COBYLA from the K best feasible designs of the sample (default 3)")
    p.add_argument("--polish", type=int, default=12, metavar="N",
                   help="multistart: the most designs of SLSQP's polish of the best (0: none; default 12)")
    p.add_argument("--cache", default=None, metavar="FILE.json",
                   help="the designs evaluated, read first and written after each: a stopped run resumes")
    p.add_argument("--out", default=None, metavar="FILE.json", help="write the result as JSON")
    p.add_argument("--json", action="store_true", help="print the result as JSON instead of the table")
    add_quiet_argument(p)
    p.set_defaults(func=_run)


def parse_vary(items) -> dict:
    """``["KEY=LOW:HIGH", ...]`` as ``{KEY: (LOW, HIGH)}``, each bound checked against the key's
    unit where the optimiser knows it (a bare number refused for a key with a unit, the key's
    example given; a wrong unit; a bound that is not finite).

    Raises
    ------
    ValueError
        An item not of that form, a key given twice, or a bound that is not a finite quantity in
        the key's unit.

    Examples
    --------
    >>> from impactbar.cli.optimize import parse_vary
    >>> parse_vary(["valve.switch_out=20mm:23 mm"])
    {'valve.switch_out': ('20mm', '23 mm')}
    >>> parse_vary(["supply.pump_flow=70:100"])
    Traceback (most recent call last):
    ...
    ValueError: --vary supply.pump_flow=70:100: LOW needs a unit: it must be a quantity in m**3/s,
    e.g. '80 L/min'; got the bare number '70'
    """
    from ..physical.units import to_si

    out = {}
    for item in items:
        key, eq, rng = item.partition("=")
        low, colon, high = rng.partition(":")
        if not (eq and colon and key.strip() and low.strip() and high.strip()):
            raise ValueError(f"--vary must be KEY=LOW:HIGH with units, e.g. valve.switch_out=20mm:23mm; got "
                             f"{item!r}")
        key = key.strip()
        if key in out:
            raise ValueError(f"--vary: {key} given twice")
        unit, example = _vary_unit(key)
        for side, bound in (("LOW", low.strip()), ("HIGH", high.strip())):
            if unit is not None:  # (a key the optimiser does not know: its own message)
                to_si(f"--vary {item.strip()}: {side}", bound, unit, example)
        out[key] = (low.strip(), high.strip())
    return out


def _vary_unit(key: str) -> tuple[str | None, str]:
    """The SI unit of a variable's key and an example value, as the parameter tree declares them
    (:data:`~impactbar.physical.tree.FIELDS`); ``None`` for another key (the optimiser's own
    message)."""
    from ..physical.tree import FIELDS

    f = FIELDS.get(key)
    return (None, "") if f is None or f.integer or f.many else (f.unit, f.example)


def parse_constraint(items) -> dict:
    """``["NAME=VALUE", ...]`` as ``{NAME: VALUE}`` (``none``: dropped; the limit as given, which
    the optimiser reads in the constraint's unit, a bare number refused for a constraint with a
    unit as everywhere else).

    Raises
    ------
    ValueError
        An item not of that form, or a limit that is not finite (``inf``, ``nan``).

    Examples
    --------
    >>> from impactbar.cli.optimize import parse_constraint
    >>> parse_constraint(["max_multiplier=0.9", "mean_supply_pressure=18 MPa", "piston_mass=none"])
    {'max_multiplier': '0.9', 'mean_supply_pressure': '18 MPa', 'piston_mass': None}
    >>> parse_constraint(["max_multiplier=inf"])
    Traceback (most recent call last):
    ...
    ValueError: --constraint max_multiplier=inf: the limit must be finite
    """
    import math
    import re

    out = {}
    for item in items:
        name, eq, value = item.partition("=")
        name, v = name.strip(), value.strip()
        if not (eq and name and v):
            raise ValueError("--constraint must be NAME=VALUE, e.g. 'peak_rod_stress=250 MPa'; got "
                             f"{item!r}")
        number = re.match(r"[+-]?(?:inf(?:inity)?|nan|(?:\d+\.?\d*|\.\d+)(?:e[+-]?\d+)?)", v, re.IGNORECASE)
        if number is not None and not math.isfinite(float(number.group(0))):
            raise ValueError(f"--constraint {name}={v}: the limit must be finite")
        out[name] = None if v.lower() == "none" else v
    return out


def _run(args) -> int:
    from ..physical.optimize_drifter import optimize_drifter

    vary = parse_vary(args.vary)
    constraints = parse_constraint(args.constraint)
    if args.max_evaluations < 1:
        raise ValueError(f"--max-evaluations must be at least 1; got {args.max_evaluations}")
    out = output_file(args.out) if args.out else None
    res = optimize_drifter(args.config, vary, objective=args.objective, constraints=constraints,
                           max_evaluations=args.max_evaluations, cache=args.cache, progress=not args.quiet,
                           method=args.method, impact_velocity=args.impact_velocity, workers=args.workers,
                           popsize=args.popsize, seed=args.seed, sample=args.sample,
                           local_starts=args.local_starts, polish=args.polish)
    if out is not None:
        res.to_json(out)
    if args.json:
        import json

        print_json(json.loads(res.to_json()))
    else:
        print(res.table())
        if res.found:
            from ..physical.optimize_multistart import found_table

            print(found_table(res.found, res.vary, res.objective_key))
    return 0
