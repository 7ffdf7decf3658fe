"""``impactbar orbits``: one-impact orbits of any bar and load, as a table or JSON."""

from __future__ import annotations

from ..laws import LAWS
from ._common import load_record, print_json, refuse

#: the dimensionless inputs, which a hammer in SI (CONFIG.toml or --preset) sets itself
DIMENSIONLESS = ("s", "d", "R", "n_modes", "load", "p0", "pk", "k", "q", "kappa")
#: the options of each load kind
LOAD_OPTIONS = {"cosine": ("p0", "pk", "k"), "square": ("q", "kappa")}


#: the one set of defaults of the dimensionless bar and load options (``orbits`` and ``continue``)
DEFAULTS = {"s": 10.0, "d": 0.05, "R": 0.5, "n_modes": 4, "p0": 0.3, "pk": 1.0, "k": 1, "q": 1.0,
            "kappa": 1.2}


def add_bar_and_load_arguments(p) -> None:
    """The dimensionless bar (``--s --d --R --n-modes --impact``) and load (``--load --p0 --pk --k
    --q --kappa``) options with the defaults :data:`DEFAULTS` (shared by ``impactbar orbits`` and
    ``impactbar continue``)."""
    d, n_modes, p0 = DEFAULTS["d"], DEFAULTS["n_modes"], DEFAULTS["p0"]
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
    lg.add_argument("--load", choices=("cosine", "square"), default="cosine",
                    help="cosine: pneumatic p0 + pk cos(k t) (eq. 33); square: hydraulic (eq. 34)")
    lg.add_argument("--p0", type=float, default=p0, help=f"cosine: mean load (default {p0:g})")
    lg.add_argument("--pk", type=float, default=1.0, help="cosine: amplitude (default 1)")
    lg.add_argument("--k", type=int, default=1, help="cosine: order of the harmonic (default 1)")
    lg.add_argument("--q", type=float, default=1.0, help="square: level q > 0 (default 1)")
    lg.add_argument("--kappa", type=float, default=1.2, help="square: kappa in [1, 2] (default 1.2)")


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
    try:
        from .physical import add_physical_arguments  # the SI layer, where installed
    except ImportError:
        pass
    else:
        add_physical_arguments(p)
    p.set_defaults(func=run)


def _load(args):
    from .. import CosineLoad, SquareWaveLoad

    if args.load == "cosine":
        return CosineLoad(args.p0, args.pk, args.k)
    return SquareWaveLoad(args.q, args.kappa)


def check_options(args) -> None:
    """Refuse the options the chosen mode ignores: the dimensionless inputs with a hammer in SI,
    the other load's options with ``--load``.

    Raises
    ------
    UsageError
    """
    hammer = getattr(args, "config", None) is not None or getattr(args, "preset", None) is not None
    if hammer:
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
    from .. import BarModel, periodic_orbits

    model = BarModel(s=args.s, d=args.d, R=args.R, n_modes=args.n_modes,
                     impact=getattr(args, "impact", None) or "paper")
    load = _load(args)
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
    head = f"{'phase':>9} {'impact vel.':>12} {'admissibility':>16} {'clearance':>11} " \
           f"{'max|mu|':>9} {'stable':>7} {'paper':>6}"
    print(head)
    for o in orbits:
        print(f"{o.phase:9.5f} {o.impact_velocity:12.6f} {o.admissibility:>16} {o.clearance:11.3e} "
              f"{o.max_abs_multiplier:9.5f} {str(o.stable):>7} {str(o.schur_stable):>6}")
    return 0

