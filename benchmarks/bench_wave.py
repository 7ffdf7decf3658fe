"""Benchmark for issue 9: ``periodic_orbits`` and ``simulate`` under the wave impact law
(``BarModel(impact="wave")``, the contact with a long rod solved by characteristics) against the
paper's law (eq. 10), the baseline, in the same run. Goal: within 2x.

Run: ``python benchmarks/bench_wave.py [--quick]``. Prints a table; nothing is asserted.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from impactbar import InitialState, periodic_orbits, physical, simulate

TWO_PI = 2 * math.pi


def median_time(fn, repeat):
    fn()  # warm-up (numba compilation, caches)
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def cases():
    for name in ("pneumatic-drill", "hydraulic-drill"):
        h = physical.preset(name)
        yield name, h.model, h.load


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="fewer repeats and shorter runs")
    args = ap.parse_args(argv)
    repeat = 3 if args.quick else 7
    periods = 20 if args.quick else 100
    rows = []
    for name, model, load in cases():
        for what in ("periodic_orbits", "simulate"):
            t, n = {}, {}
            for law in ("paper", "wave"):
                m = model.with_(impact=law)
                if what == "periodic_orbits":
                    def fn(m=m, load=load):
                        return periodic_orbits(m, load)
                else:
                    start = InitialState.rigid(-0.05, 0.0, n_modes=m.n_modes)

                    def fn(m=m, load=load, start=start):
                        return simulate(m, load, start, periods * TWO_PI)
                t[law] = median_time(fn, repeat)
                n[law] = fn().n_impacts if what == "simulate" else None
            rows.append((name, what, t["paper"], t["wave"], n["paper"], n["wave"]))
    print("simulate: from rest 0.05 L off the stop; per impact = time / impacts (the paper law may "
          "end in permanent contact, which costs nothing per period)")
    print(f"{'case':<17} {'function':<16} {'paper law/s':>12} {'wave law/s':>11} {'ratio':>6} "
          f"{'impacts p/w':>12} {'per impact ratio':>17}")
    for name, what, tp, tw, np_, nw in rows:
        extra = "" if np_ is None else f" {np_:5d}/{nw:<6d} {(tw / nw) / (tp / np_):17.2f}"
        print(f"{name:<17} {what:<16} {tp:12.4f} {tw:11.4f} {tw / tp:6.2f}{extra}")


if __name__ == "__main__":
    main()
