"""``impactbar orbits``: one-impact orbits of any bar and load, as a table or JSON."""

from __future__ import annotations

from ..laws import LAWS
from ..loads import LOADS, Load, load_from_record
from ._common import load_record, print_json, refuse

#: the options of each load kind: the loads of the table whose parameters are all numbers
LOAD_OPTIONS = {kind: cls.traits.parameters.names for kind, cls in LOADS.items()
                if all(f.per is None for f in cls.traits.parameters)}
#: the dimensionless inputs, which a hammer in SI (CONFIG.toml or --preset) sets itself
DIMENSIONLESS = ("s", "d", "R", "n_modes", "load",
                 *dict.fromkeys(p for options in LOAD_OPTIONS.values() for p in options))


#: the one set of defaults of the dimensionless bar and load options (``orbits`` and ``continue``)
DEFAULTS = {"s": 10.0, "d": 0.05, "R": 0.5, "n_modes": 4, "p0": 0.3, "pk": 1.0, "k": 1, "q": 1.0,
            "kappa": 1.2}


def add_bar_and_load_arguments(p) -> None:
    """The dimensionless bar (``--s --d --R --n-modes --impact``) and load (``--load --p0 --pk --k
    --q --kappa``) options with the defaults :data:`DEFAULTS` (shared by ``impactbar orbits`` and
    ``impactbar continue``)."""
    d, n_modes = DEFAULTS["d"], DEFAULTS["n_modes"]
    g = p.add_argument_group("bar (dimensionless, eq. 2)")
    g.add_argument("--s", type=float, default=10.0, help="wave-speed ratio C/(L Omega) > 0 (default 10)")
    g.add_argument("--d", type=float, default=d, help=f"damping D/(M Omega) >= 0 (default {d:g})")
    g.add_argument("--R", type=float, default=0.5, help="restitution coefficient in [0, 1] (default 0.5)")
    g.add_argument("--n-modes", type=int, default=n_modes,
                   help=f"flexible modes kept, >= 0 (default {n_modes})")
    g.add_argument("--impact", choices=tuple(LAWS), default=None,
                   help="impact law: 'paper' (eq. 10, default) or 'wave' (the stop as a long rod, "
                        "the contact solved by characteristics); overrides a config's [model] impact")
    lg = p.add_argument_group("load")
    kinds = tuple(LOAD_OPTIONS)
    lg.add_argument("--load", choices=kinds, default=kinds[0],
                    help="; ".join(f"{k}: {LOADS[k].traits.description}" for k in kinds))
    for kind in kinds:  # each load's parameters, from the table of loads
        for f in LOADS[kind].traits.parameters:
            lg.add_argument(f"--{f.name}", type=int if f.dtype.startswith("i") else float,
                            default=DEFAULTS[f.name],
                            help=f"{kind}: {f.long_name} (default {DEFAULTS[f.name]:g})")


def add_physical_arguments_if_installed(p) -> None:
    """The SI options (a hammer's CONFIG.toml or ``--preset``) where the SI layer is installed
    (shared by ``impactbar orbits`` and ``impactbar continue``)."""
    try:
        from .physical import add_physical_arguments
    except ImportError:
        return
    add_physical_arguments(p)


def add_parser(sub) -> None:
    p = sub.add_parser(
        "orbits",
        help="one-impact periodic orbits of a bar and load, with stability",
        description="Every one-impact-per-period orbit (paper Section 2) with admissibility, exact "
        "Floquet multipliers and the paper's Schur criterion. Dimensionless inputs (eq. 2).",
    )
    add_bar_and_load_arguments(p)
    p.add_argument("--json", action="store_true",
                   help="print JSON instead of a table (strict JSON: non-finite numbers as null)")
    add_physical_arguments_if_installed(p)
    p.set_defaults(func=run)


def load_from_args(args) -> Load:
    """The load ``--load`` names, from its options (the table of loads)."""
    return load_from_record({"kind": args.load, **{n: getattr(args, n) for n in LOAD_OPTIONS[args.load]}})


def check_options(args) -> None:
    """Refuse the options the chosen mode ignores or that conflict: a CONFIG.toml with ``--preset``,
    the dimensionless inputs with a hammer in SI, the other load's options with ``--load``.

    Raises
    ------
    UsageError
    """
    hammer = getattr(args, "config", None) is not None or getattr(args, "preset", None) is not None
    if hammer:
        from .physical import check_one_source

        check_one_source(args)
        refuse(args, DIMENSIONLESS, because="with a hammer in SI units (CONFIG.toml or --preset), "
               "which sets the bar, the load and R itself")
        return
    for kind, options in LOAD_OPTIONS.items():
        if kind != args.load:
            refuse(args, options, because=f"with --load {args.load} (for --load {kind} only)")


def run(args) -> int:
    check_options(args)
    if getattr(args, "config", None) or getattr(args, "preset", None):
        from .drifter import drifter_from_args, run_drifter_orbits
        from .physical import run_physical_orbits

        drifter = drifter_from_args(args)  # a valve switched on the piston's position (theory §10)
        if drifter is not None:
            return run_drifter_orbits(args, drifter)

        return run_physical_orbits(args)
    from ..model import BarModel
    from ..orbits import PeriodicOrbit, periodic_orbits

    model = BarModel(s=args.s, d=args.d, R=args.R, n_modes=args.n_modes,
                     impact=getattr(args, "impact", None) or "paper")
    load = load_from_args(args)
    orbits = periodic_orbits(model, load)
    if args.json:
        doc = {
            "model": {"s": model.s, "d": model.d, "R": model.R, "n_modes": model.n_modes,
                      "impact": model.impact},
            "load": load_record(load),
            "orbits": [o.to_dict() for o in orbits],
        }
        print_json(doc)
        return 0
    print(f"{model!r}\n{load!r}")
    if not orbits:
        print("no one-impact orbit exists (above the existence edge, eq. 38)")
        return 0
    print("\n".join(PeriodicOrbit.fields.select("cli").table(orbits, width=2)))  # the orbit's CLI columns
    return 0

