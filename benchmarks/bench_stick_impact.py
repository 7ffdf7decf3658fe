"""Benchmark of stick-impact runs: a 4-mode stick-impact run (chatter, contact, undone releases) must cost
time linear in its length. Baseline in the same run: the previous ``_SegmentLog.truncate``, which
rescanned every stored chatter state on each undone release (quadratic in the run's length).

Run: ``python benchmarks/bench_stick_impact.py [--periods 250 500 1000 2000]``. Prints a table of
seconds per run and per 1000 periods; nothing is asserted.
"""

from __future__ import annotations

import argparse
import importlib
import math
import time

from impactbar import BarModel, CosineLoad, InitialState, simulate

TWO_PI = 2 * math.pi
S = importlib.import_module("impactbar.simulation.simulate")


def _old_truncate(self, count):
    """The truncate of 4351d85 (the baseline)."""
    while self.count > count:
        blk = self.blocks.pop()
        self.count -= blk[0].size
    for j in [j for j in self.frozen if j >= count]:
        del self.frozen[j]


def run(periods):
    model = BarModel(2.0, 0.2, 0.6, 4)
    load = CosineLoad(1.0, 1.0)
    t = time.perf_counter()
    tr = simulate(model, load, InitialState.rigid(-0.1, 0.0, 4), TWO_PI * periods)
    return time.perf_counter() - t, tr


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--periods", type=int, nargs="*", default=[250, 500, 1000, 2000])
    args = ap.parse_args(argv)
    run(10)  # compile
    new = S._SegmentLog.truncate
    print(f"{'periods':>8} {'impacts':>8} {'retries':>8} {'chatters':>9} {'baseline s':>11} "
          f"{'this s':>8} {'baseline s/1000 P':>18} {'this s/1000 P':>14}")
    for P in args.periods:
        S._SegmentLog.truncate = _old_truncate
        t_old, tr_old = run(P)
        S._SegmentLog.truncate = new
        t_new, tr = run(P)
        assert tr.n_impacts == tr_old.n_impacts  # the same run either way
        print(f"{P:8d} {tr.n_impacts:8d} {tr.n_release_retries:8d} {len(tr._segments.frozen):9d} "
              f"{t_old:11.2f} {t_new:8.2f} {1000 * t_old / P:18.2f} {1000 * t_new / P:14.2f}",
              flush=True)


if __name__ == "__main__":
    main()
