"""The position-switched drive (theory §10): simulate with switching against the same motion
without it, and find_orbit with an unknown period.

Run: ``python benchmarks/bench_drive.py`` (``--quick`` for a short run). For 0, 8 and 32 flexible
modes, impacts per second of ``simulate`` under ``PositionSwitchedDrive(1, 1, 1)`` (``R = 0.215``,
``d = 0.05``, ``s = 10``), and of the same run without switching: the time-periodic square wave that
carries the same motion (theory §10, the limiting case: time rescaled by ``k = 2 pi / T``, so the
model's ``s/k``, ``d/k`` and the level ``1/k^2``, ``kappa = 2 h3 / T``), which the compiled driver
follows alone. The goal: a ratio of at least 0.5. The square wave's one-impact orbit is
unstable (eq. 41), so from the same start its run chatters (many small impacts per period, each
cheap): the table also gives the impacts per period of both runs and the ratio of periods (blows)
per second. Then the cost of ``find_orbit`` with the drive (goal: rigid <= 1 ms, 8 modes <= 5 ms).
Compilation is done before the clock starts.
"""

from __future__ import annotations

import argparse
import math
import time

from impactbar import BarModel, InitialState, PositionSwitchedDrive, SquareWaveLoad, find_orbit, simulate


def rate(model, load, t_end):
    start = InitialState.rigid(-0.3, 0.7, model.n_modes)
    simulate(model, load, start, min(t_end, 50.0))  # warm-up (compilation, caches)
    t = time.perf_counter()
    tr = simulate(model, load, start, t_end)
    return tr.n_impacts / (time.perf_counter() - t), tr.n_impacts, tr.t_end - tr.t0


def main(quick=False):
    drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    t_end = 2000.0 if quick else 20000.0
    print(f"{'modes':>5} {'switched imp/s':>15} {'square imp/s':>13} {'ratio':>6} {'imp/period':>11} "
          f"{'periods/s ratio':>15} {'orbit ms':>9}")
    for n in (0, 8, 32):
        model = BarModel(s=10.0, d=0.05, R=0.215, n_modes=n)
        o = find_orbit(model, drive)
        reps = 10 if quick else 50
        orbit_ms = math.inf
        for _ in range(5):  # the best of five: the machine's other load only adds
            t = time.perf_counter()
            for _ in range(reps):
                find_orbit(model, drive)
            orbit_ms = min(orbit_ms, (time.perf_counter() - t) / reps * 1e3)
        k = 2 * math.pi / o.period
        square = SquareWaveLoad(1.0 / k**2, 2 * o.durations[3] / o.period)
        scaled = BarModel(s=10.0 / k, d=0.05 / k, R=0.215, n_modes=n)
        r_sw, n_sw, span_sw = rate(model, drive, t_end)
        r_sq, n_sq, span_sq = rate(scaled, square, t_end * k)
        per_sw = n_sw * o.period / span_sw  # impacts per period
        per_sq = n_sq * 2 * math.pi / span_sq
        periods = (r_sw / per_sw) / (r_sq / per_sq)
        print(f"{n:>5} {r_sw:>15.0f} {r_sq:>13.0f} {r_sw / r_sq:>6.2f} {per_sw:>5.1f}/{per_sq:<5.1f} "
              f"{periods:>15.2f} {orbit_ms:>9.2f}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    main(ap.parse_args().quick)
