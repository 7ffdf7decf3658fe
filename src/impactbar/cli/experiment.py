"""``impactbar experiment pneumatic|hydraulic``: the paper's Section 5 experiments from random
starts; prints the class fractions and the impact-interval statistics, writes three plots."""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

from ._common import add_quiet_argument, given, output_folder, progress_bar, refuse, refuse_together, require

#: the options of each hammer's load
LOAD_OPTIONS = {"pneumatic": ("p0", "pk", "k"), "hydraulic": ("q", "kappa")}


def add_parser(sub) -> None:
    p = sub.add_parser(
        "experiment",
        help="random-start experiments of the paper's Section 5 (pneumatic or hydraulic hammer)",
        description="Simulate many seeded random starts, classify the long-run motion of each "
        "(one impact per k load periods, permanent contact, stick-impact cycles, periodic with "
        "several impacts, not periodic), print the fractions and the impact-interval mean and "
        "standard deviation, and write end_displacement.png, impact_map.png and "
        "interval_histogram.png.",
    )
    p.add_argument("hammer", choices=("pneumatic", "hydraulic"),
                   help="pneumatic: p0 + pk cos(k t) (eq. 33); hydraulic: square wave (eq. 34)")
    p.add_argument("--starts", type=int, default=200, help="random starts (default 200)")
    p.add_argument("--periods", type=float, default=300.0,
                   help="length of each run in load periods (2 pi each); the last 25 %% are "
                        "classified (default 300)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random starts (default 0)")
    p.add_argument("--workers", type=int, default=None,
                   help="runs computed at once, in threads (default: the cores)")
    p.add_argument("--s", type=float, default=10.0, help="wave-speed ratio s (default 10)")
    p.add_argument("--d", type=float, default=0.03 / (2 * math.pi),
                   help="damping d (default 0.03 / 2 pi, the paper's 2 pi d = 0.03)")
    p.add_argument("--R", type=float, default=None,
                   help="restitution (default 0.8 pneumatic, 0.5 hydraulic)")
    p.add_argument("--n-modes", type=int, default=4, help="flexible modes N (default 4)")
    p.add_argument("--modes", dest="modes", type=int, default=None,
                   help=argparse.SUPPRESS)  # deprecated alias of --n-modes
    p.add_argument("--p0", type=float, default=1.2, help="pneumatic mean load (default 1.2)")
    p.add_argument("--pk", type=float, default=1.0, help="pneumatic harmonic (default 1)")
    p.add_argument("--k", type=int, default=1, help="pneumatic harmonic order (default 1)")
    p.add_argument("--q", type=float, default=1.0, help="hydraulic level q (default 1)")
    p.add_argument("--kappa", type=float, default=1.5, help="hydraulic kappa (default 1.5)")
    p.add_argument("--out", default=None,
                   help="folder for the plots (default out/experiment-<hammer>)")
    p.add_argument("--no-plots", action="store_true", help="skip the plots")
    add_quiet_argument(p)
    p.set_defaults(func=run)


def check_options(args) -> int:
    """Refuse what the chosen hammer ignores and what conflicts; returns the number of modes.

    Raises
    ------
    UsageError
    """
    for hammer, options in LOAD_OPTIONS.items():
        if hammer != args.hammer:
            refuse(args, options, because=f"for the {args.hammer} hammer (for {hammer} only)")
    refuse_together(args, "no_plots", "out", because="--out names the folder for the plots")
    refuse_together(args, "n_modes", "modes", because="--modes is the old name of --n-modes")
    if given(args, "modes") and args.modes is not None:
        print("impactbar experiment: warning: --modes is deprecated; use --n-modes", file=sys.stderr)
        return args.modes
    return args.n_modes


def run(args) -> int:
    from ..plotting import plot_experiment
    from ..simulation.experiments import hydraulic_setup, pneumatic_setup, run_experiment

    n_modes = check_options(args)
    out = None
    if not args.no_plots:  # the plots' extra and folder, before the computing
        require("matplotlib")
        out = output_folder(args.out or f"out/experiment-{args.hammer}")
    if args.hammer == "pneumatic":
        R = 0.8 if args.R is None else args.R
        model, load = pneumatic_setup(p0=args.p0, pk=args.pk, k=args.k, s=args.s, d=args.d, R=R,
                                      n_modes=n_modes)
    else:
        R = 0.5 if args.R is None else args.R
        model, load = hydraulic_setup(q=args.q, kappa=args.kappa, s=args.s, d=args.d, R=R,
                                      n_modes=n_modes)
    t0 = time.perf_counter()
    starts = max(int(args.starts), 0)
    with progress_bar(starts, desc=f"{args.hammer} starts", unit="run", quiet=args.quiet) as bar:
        result = run_experiment(model, load, starts=args.starts, periods=args.periods,
                                seed=args.seed, workers=args.workers or (os.cpu_count() or 1),
                                progress=lambda n: bar.update(n - bar.n))
    print(result.summary())
    print(f"({time.perf_counter() - t0:.1f} s)")
    if out is not None:
        files = plot_experiment(result, out)
        print("wrote " + ", ".join(str(f) for f in files))
    return 0
