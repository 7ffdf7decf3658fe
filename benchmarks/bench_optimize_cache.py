"""Benchmark: an optimiser run started again on its own cache file, against the same run on another
package tree, in the same session.

SLSQP (``optimize_drifter(method="slsqp")``) on the preset circuit drifter's switch point and
pre-charge (the tests' problem, ``--evaluations`` its iterations' budget), first into an empty cache
file, then again on that file: the second run reads every design from it, and on a tree that keeps
the gradients in the cache it reads those too instead of computing them (SLSQP's, and the
multistart polish's the same way). Prints for each tree the second run's CPU seconds (the least of
``--rounds`` fresh processes), its designs and gradients computed and read back, and whether the two
trees' optima agree to the bit. Nothing is asserted.

Run: ``python benchmarks/bench_optimize_cache.py --against REF`` (a git ref, e.g. the commit before
the gradients were kept) ``[--rounds N] [--evaluations E]``.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from _timing import fresh_runs, ref_tree  # this folder's shared timer

VARY = {"valve.switch_out": ("19 mm", "24 mm"), "accumulator.precharge": ("8 MPa", "12 MPa")}


def _run(evaluations: int) -> dict:
    """Both runs in this process (the first compiles and fills the cache); the second one timed."""
    from impactbar.physical import optimize_drifter

    kwargs = {"objective": "impact_power", "method": "slsqp", "max_evaluations": evaluations,
              "progress": False}
    with tempfile.TemporaryDirectory() as folder:
        cache = Path(folder) / "cache.json"
        first = optimize_drifter("circuit-drifter", VARY, cache=cache, **kwargs)
        t = time.process_time()
        again = optimize_drifter("circuit-drifter", VARY, cache=cache, **kwargs)
        cpu = time.process_time() - t
    return {"cpu_s": cpu, "designs": again.evaluations, "designs_read": again.cached,
            "gradients": again.gradients, "gradients_read": getattr(again, "cached_gradients", 0),
            "first_gradients": first.gradients, "optimum": json.dumps(again.optimum["values"])}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", metavar="REF", help="the baseline's git ref")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--evaluations", type=int, default=12)
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # (--against's child)
    args = parser.parse_args(argv)
    if args.json:
        print(json.dumps(_run(args.evaluations)))
        return 0
    if args.against is None:
        row = _run(args.evaluations)
        print(json.dumps(row, indent=1))
        return 0
    runs = fresh_runs(__file__, ref_tree(args.against), args.rounds, ("--evaluations", str(args.evaluations)))
    print(f"{'run again on its cache (SLSQP, ' + str(args.evaluations) + ' iterations)':52s} "
          f"{'baseline':>10s} {'new':>10s}")
    best = {k: min(runs[k], key=lambda r: r["cpu_s"]) for k in runs}
    cpu = [f"{best[k]['cpu_s']:10.2f}" for k in ("baseline", "new")]
    print(f"{'CPU s (the least of ' + str(args.rounds) + ' processes)':52s} {cpu[0]} {cpu[1]}")
    for label, a, b in (("designs computed / read", "designs", "designs_read"),
                        ("gradients computed / read", "gradients", "gradients_read")):
        cells = [f"{best[k][a]} / {best[k][b]}" for k in ("baseline", "new")]
        print(f"{label:52s} {cells[0]:>10s} {cells[1]:>10s}")
    same = best["baseline"]["optimum"] == best["new"]["optimum"]
    print(f"the same optimum, to the bit: {'yes' if same else 'no'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
