"""Benchmark of ``periodic_orbits`` and ``simulate`` under the wave impact law
(``BarModel(impact="wave")``, the contact with a long rod solved by characteristics) against the
paper's law (eq. 10), the baseline, in the same run. Goal: within 2x.

For ``simulate`` the wave law is also timed with its separating contact windows solved by the
Python characteristics solver (the reference of ``"simulate.wave_separation"``, the reference of the compiled
window), the path before the compiled one, in the same run.

Run: ``python benchmarks/bench_wave.py [--quick]``. Prints a table; nothing is asserted.
"""

from __future__ import annotations

import argparse
import math

from _timing import median_time  # this folder's shared timer

from impactbar import InitialState, periodic_orbits, physical, simulate
from impactbar.dynamics.implementations import implementation

TWO_PI = 2 * math.pi
#: the simulator's module (the package ``impactbar.simulation`` re-exports the function by that name)


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
            laws = ("paper", "wave") if what == "periodic_orbits" else ("paper", "wave", "wave-py")
            for law in laws:
                m = model.with_(impact=law.removesuffix("-py"))
                if what == "periodic_orbits":
                    def fn(m=m, load=load):
                        return periodic_orbits(m, load)
                else:
                    start = InitialState.rigid(-0.05, 0.0, n_modes=m.n_modes)

                    def fn(m=m, load=load, start=start):
                        return simulate(m, load, start, periods * TWO_PI)
                with implementation("simulate.wave_separation", "reference" if law == "wave-py" else "fast"):
                    t[law] = median_time(fn, repeat)
                    n[law] = fn().n_impacts if what == "simulate" else None
            rows.append((name, what, t["paper"], t["wave"], n["paper"], n["wave"], t.get("wave-py")))
    print("simulate: from rest 0.05 L off the stop; per impact = time / impacts (the paper law may "
          "end in permanent contact, which costs nothing per period)")
    print("wave, Python sep.: the wave law with its separating windows solved in Python (the old path)")
    print(f"{'case':<17} {'function':<16} {'paper law/s':>12} {'wave law/s':>11} {'ratio':>6} "
          f"{'impacts p/w':>12} {'per impact ratio':>17} {'wave, Python sep./s':>20} {'ratio':>6}")
    for name, what, tp, tw, np_, nw, twp in rows:
        extra = "" if np_ is None else f" {np_:5d}/{nw:<6d} {(tw / nw) / (tp / np_):17.2f}"
        if twp is not None:
            extra += f" {twp:20.4f} {twp / tp:6.2f}"
        print(f"{name:<17} {what:<16} {tp:12.4f} {tw:11.4f} {tw / tp:6.2f}{extra}")


if __name__ == "__main__":
    main()
