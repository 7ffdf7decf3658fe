"""Every one-impact orbit of the position-switched drive: the cost of
``periodic_orbits(model, drive)`` beside the old ``find_orbit`` from the rigid piston's orbit.

Run: ``python benchmarks/bench_drive_orbits.py`` (``--quick`` for fewer repetitions). For the two
valve cases of ``tests/drives/test_drive_orbits.py`` and the drive benchmark's (``bench_drive.py``),
at 8 flexible modes (and 32 for the latter): the best of five wall times of

- ``periodic_orbits(model, drive)``: the certified search over its default window of periods, each
  root polished by Newton's method and its admissibility and multipliers computed (the goal:
  <= 0.5 s at 8 modes);
- the baseline: Newton's method from the rigid piston's orbit (``find_orbit``'s only start before
  the search of every orbit), with whether it converged and to what;
- ``find_orbit(model, drive)`` now (the default chain: the rigid orbit, a run from rest, the search).

Numba's compilation and the first imports are done before the clock starts.
"""

from __future__ import annotations

import argparse
import math
import time

from impactbar import BarModel, PositionSwitchedDrive, find_orbit, periodic_orbits
from impactbar.orbits.driven import orbit_of, orbit_problem

CASES = [
    ("valve case 1", BarModel(3, 0.1, 0.6, 6), PositionSwitchedDrive(1, 0.5, 0.15)),
    ("valve case 2", BarModel(10, 0.02, 0.3, 8), PositionSwitchedDrive(2, 1, 0.2, delay=0.05)),
    ("bench_drive", BarModel(10, 0.05, 0.215, 8), PositionSwitchedDrive(1, 1, 1)),
    ("bench_drive", BarModel(10, 0.05, 0.215, 32), PositionSwitchedDrive(1, 1, 1)),
]


def best(fn, reps):
    out, t_best = None, math.inf
    for _ in range(reps):
        t = time.perf_counter()
        try:
            out = fn()
        except ValueError as err:
            out = err
        t_best = min(t_best, time.perf_counter() - t)
    return out, t_best


def rigid_start(model, drive):
    problem = orbit_problem(model, drive)
    return orbit_of(problem, problem.solve(problem.initial(None, 1e-13, 50), 1e-13, 50))


def describe(o):
    if isinstance(o, Exception):
        return "fails"
    return f"T={o.period:.6f} {'adm' if o.admissible else 'inadm'} {'stable' if o.stable else 'unstable'}"


def main(quick=False):
    reps = 3 if quick else 5
    for _, model, drive in CASES:  # warm-up: compilation, imports
        periodic_orbits(model, drive)
        find_orbit(model, drive)
    print(f"{'case':<16} {'N':>3} {'orbits':>6} {'adm':>4} {'stab':>4} {'periodic_orbits s':>18} "
          f"{'rigid-start s':>14} {'rigid start gives':<28} {'find_orbit s':>12} {'find_orbit gives':<28}")
    for name, model, drive in CASES:
        listed, t_all = best(lambda m=model, d=drive: periodic_orbits(m, d), reps)
        base, t_base = best(lambda m=model, d=drive: rigid_start(m, d), reps)
        now, t_now = best(lambda m=model, d=drive: find_orbit(m, d), reps)
        n_adm = sum(o.admissible for o in listed)
        n_st = sum(o.stable for o in listed)
        print(f"{name:<16} {model.n_modes:>3} {len(listed):>6} {n_adm:>4} {n_st:>4} {t_all:>18.3f} "
              f"{t_base:>14.4f} {describe(base):<28} {t_now:>12.4f} {describe(now):<28}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    main(parser.parse_args().quick)
