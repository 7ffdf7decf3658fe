"""``impactbar paper``: reproduce the paper's Figs. 4-8 (PNG + CSV) and print a summary."""

from __future__ import annotations

import time

from ._common import add_figure_arguments, add_quiet_argument, check_dpi, output_folder, progress_bar, require


def add_parser(sub) -> None:
    p = sub.add_parser("paper", help="reproduce the paper's Figs. 4-8 as PNG and CSV files",
                       description="Recompute Figs. 4-8 of Bjorkenstam (1977), with admissibility "
                       "and exact multipliers, and write figN.png (or .pdf, .svg) and figN.csv.")
    p.add_argument("--out", default="out/paper", help="output folder (default out/paper)")
    p.add_argument("--quick", action="store_true", help="fewer points per curve")
    add_figure_arguments(p, dpi=130)
    add_quiet_argument(p)
    p.set_defaults(func=run)


def run(args) -> int:
    check_dpi(args.dpi)
    require("matplotlib")
    output_folder(args.out)
    from ..paper import reproduce

    t0 = time.perf_counter()
    with progress_bar(5, desc="Figs. 4-8", unit="figure", quiet=args.quiet) as bar:
        summary = reproduce(args.out, quick=args.quick, dpi=args.dpi, format=args.format,
                            progress=lambda name: bar.set_postfix_str(name, refresh=False) or bar.update(1))
    w1 = max(len(what) for _, what, _ in summary)
    print(f"{'fig':<4} {'quantity':<{w1}}  value")
    for fig, what, val in summary:
        print(f"{fig:<4} {what:<{w1}}  {val}")
    print(f"\nwrote fig4..fig8 (.{args.format}, .csv) to {args.out}/ in {time.perf_counter() - t0:.1f} s")
    return 0
