"""Benchmark of the continuation of periodic motions, against the baselines a user would
otherwise write in the same run.

1. A one-impact branch of the 8-mode bar (pneumatic load, ``p0`` from 0.3 through the period
   doubling and the fold, about 200 points, every event located): against ``periodic_orbits`` at the
   same 200 parameter values plus the chart's root-finding of the period doubling
   (``pneumatic_stability_edges``), which is what one would do without continuation.
2. A 2-per-2 branch of the rigid bar, started by branch switching at the period doubling of the
   one-impact orbit and followed to its own period doubling (located): against a brute-force
   ``simulate`` diagram over the same parameter range (60 values, 100 + 20 load periods each),
   which shows the doubled motion but neither its unstable part nor where it doubles.
3. The same 8-mode bar under the wave impact law (theory §4b), ``p0`` from 0.3 to 1.0 through its
   period doubling (located): against ``periodic_orbits`` at the same parameter values.

Run: ``python benchmarks/bench_continuation.py [--quick]``. Prints a table; nothing is asserted.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from impactbar import BarModel, CosineLoad, InitialState, continue_orbit, periodic_orbits
from impactbar.continuation import simulated_diagram
from impactbar.orbits.charts import pneumatic_stability_edges


def median_time(fn, repeat):
    fn()  # warm-up
    ts = []
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts)), float(np.min(ts)), out


def stable_side(model, p0):
    return next(o for o in periodic_orbits(model, CosineLoad(p0, 1.0)) if math.cos(o.phase) < 0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    rep = 1 if a.quick else 5
    print("impactbar benchmark: continuation of periodic motions")
    print(f"{'case':<58} {'median s':>9} {'min s':>7}  result")

    # 1. one-impact branch of the 8-mode bar
    m8 = BarModel(s=10.0, d=0.05, R=0.5, n_modes=8)
    start = stable_side(m8, 0.3)

    def branch8():
        return continue_orbit(start, "p0", to=1.0, step=0.007, max_step=0.007)

    med, mn, b = median_time(branch8, rep)
    ev = ", ".join(f"{e.kind} {e.value:.10f}" for e in b.events)
    print(f"{'continue_orbit: 8-mode one-impact branch, events':<58} {med:9.3f} {mn:7.3f}  "
          f"{len(b)} points; {ev}")

    def baseline8():
        orbits = [periodic_orbits(m8, CosineLoad(v, 1.0)) for v in b.values]
        edges = pneumatic_stability_edges(m8)
        return orbits, edges

    med_b, mn_b, (_, edges) = median_time(baseline8, rep)
    print(f"{'baseline: periodic_orbits at the same points + PD edge':<58} {med_b:9.3f} {mn_b:7.3f}  "
          f"{len(b)} values; PD edge {edges[0][0]:.10f}")

    # 2. the rigid 2-per-2 branch with its period doubling
    R = 0.6
    rigid = BarModel(s=3.0, d=0.0, R=R, n_modes=0)
    b1 = continue_orbit(stable_side(rigid, 0.9), "p0", to=0.66, stop_on=("period-doubling",))
    pd = b1.events[-1]

    def branch2():
        return continue_orbit(pd, "p0", to=0.66, stop_on=("period-doubling",))

    med, mn, b2 = median_time(branch2, max(rep, 3))
    print(f"{'continue_orbit: rigid 2-per-2 branch from the PD to its PD':<58} {med:9.3f} {mn:7.3f}  "
          f"{len(b2)} points; PD at {b2.events[-1].value:.10f}")

    o = b1.orbits[0]
    values = np.linspace(pd.value, b2.events[-1].value, 60)

    def brute():
        return simulated_diagram(rigid, CosineLoad(pd.value, 1.0), "p0", values, transient=100,
                                 record=20, start=InitialState(*o.modal_state_after_impact),
                                 t0=o.phase)

    med_b, mn_b, diag = median_time(brute, 1)
    print(f"{'baseline: brute-force simulate diagram, 60 values':<58} {med_b:9.3f} {mn_b:7.3f}  "
          f"{diag['parameter'].size} impacts recorded")

    # 3. the wave law's one-impact branch of the 8-mode bar
    w8 = BarModel(s=10.0, d=0.05, R=0.5, n_modes=8, impact="wave")
    start_w = next(o for o in periodic_orbits(w8, CosineLoad(0.3, 1.0)) if o.admissible)

    def branch_wave():
        return continue_orbit(start_w, "p0", to=1.0)

    med, mn, bw = median_time(branch_wave, rep)
    ev = ", ".join(f"{e.kind} {e.value:.10f}" for e in bw.events)
    print(f"{'continue_orbit: 8-mode wave-law branch, events':<58} {med:9.3f} {mn:7.3f}  "
          f"{len(bw)} points; {ev}")

    def baseline_wave():
        return [periodic_orbits(w8, CosineLoad(v, 1.0)) for v in bw.values]

    med_b, mn_b, _ = median_time(baseline_wave, rep)
    print(f"{'baseline: wave-law periodic_orbits at the same points':<58} {med_b:9.3f} {mn_b:7.3f}  "
          f"{len(bw)} values")


if __name__ == "__main__":
    main()
