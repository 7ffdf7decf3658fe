"""Benchmark of the exact blow: the exact blow against the lattice, same cases, same run.

For each rod (those of ``tests/laws/test_rock_exact.py`` and Lundberg's 40-long one; uniform
piston, massless bit unless said, no feed): the exact blow (``single_blow``'s default, run until its
end is certified), the lattice at its defaults (8 cells per piston, ``t_max`` 20 travel times: the
baseline) and the lattice refined to 1024 cells per piston (128 for the 40-long rod: the lattice's
size bound) up to the exact blow's end; their times (median) and the relative errors of the
efficiency and of the rebound velocity against the exact blow.

Run: ``python benchmarks/bench_exact_blow.py [--quick]``. Prints a table; nothing is asserted.

``--against SRC`` instead times the exact blow and the default lattice (``single_blow``, CPU time,
the median of 15 calls after one; the 40-long rod 5) in fresh processes on the package tree ``SRC``
(e.g. ``git worktree add /tmp/old <commit>`` then ``--against /tmp/old/src``) and on this one,
alternately, best of three processes each, and prints both side by side.
"""

from __future__ import annotations

import argparse
import json
import math
import time

from _timing import fresh_runs, median_time  # this folder's shared timer

import impactbar as ib


def _model(segs, k, k_u, s=1.0, bit_mass=0.0):
    law = ib.RodRock(segments=[ib.RodSegment(length, z) for length, z in segs],
                     rock=ib.BilinearRock(k, k_u), bit_mass=bit_mass)
    return ib.BarModel(s=s, d=0.0, R=0.0, n_modes=0, impact=law)


CASES = {
    "uniform L=1, a 2, g 5": _model([(1.0, 1.0)], 1.0, 5.0),
    "4-long Z 0.4, a 0.8, g 1e6": _model([(4.0, 0.4)], 0.4, 4e5),
    "3 segments, a 1, g 2": _model([(1.0, 1.0), (0.5, 0.5), (2.0, 1.0)], 0.5, 1.0),
    "incommensurate, 2 seg.": _model([(math.sqrt(2), 0.8), (math.pi / 2, 1.3)], 0.7, 7.0),
    "bit mass 0.3, 2 seg.": _model([(2.0, 1.0), (1.0, 0.6)], 1.0, 5.0, bit_mass=0.3),
    "Lundberg 40-long, g 1e9": _model([(40.0, 1.0)], 2.5, 2.5e9, s=2.0),
}


def _cpu_times(repeat=15):
    """``{case: (exact ms, lattice ms)}``: medians of CPU time (one untimed call first)."""
    out = {}
    for name, model in CASES.items():
        n = repeat if "40-long" not in name else 5
        row = []
        for kw in ({}, {"method": "lattice"}):
            ib.single_blow(model, 1.0, **kw)
            ts = []
            for _ in range(n):
                t0 = time.process_time()
                ib.single_blow(model, 1.0, **kw)
                ts.append(time.process_time() - t0)
            row.append(1e3 * sorted(ts)[n // 2])
        out[name] = row
    return out


def against(src, rounds=3):
    """The exact blow and the lattice on another package tree and on this one, in fresh processes."""
    runs = fresh_runs(__file__, src, rounds)
    print(f"{'case (CPU ms, best of ' + str(rounds) + ' processes)':40s} {'exact, baseline':>15s} "
          f"{'exact, new':>11s} {'lattice, baseline':>17s} {'lattice, new':>12s}")
    for case in CASES:
        b = [min(r[case][i] for r in runs["baseline"]) for i in (0, 1)]
        n = [min(r[case][i] for r in runs["new"]) for i in (0, 1)]
        print(f"{case:40s} {b[0]:15.2f} {n[0]:11.2f} {b[1]:17.2f} {n[1]:12.2f}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--against", metavar="SRC", help="compare with the package tree SRC instead")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # (--against's child)
    args = parser.parse_args(argv)
    if args.json:
        print(json.dumps(_cpu_times()))
        return
    if args.against:
        against(args.against)
        return
    repeat = 3 if args.quick else 7
    print(f"{'case':28s} {'exact ms':>9s} {'ended by':>9s} {'lattice-8 ms':>12s} {'err eff':>9s} "
          f"{'err reb':>9s} {'lattice-fine ms':>15s} {'err eff':>9s} {'err reb':>9s}")
    for name, model in CASES.items():
        exact = ib.single_blow(model, 1.0)
        t_exact = median_time(lambda m=model: ib.single_blow(m, 1.0), repeat)
        coarse = ib.single_blow(model, 1.0, method="lattice")
        t_coarse = median_time(lambda m=model: ib.single_blow(m, 1.0, method="lattice"), repeat)
        n_fine = 1024 if exact.duration < 100 else 128  # the lattice's size bound
        fine_args = dict(method="lattice", cells_per_piston=n_fine, t_max=exact.duration)
        fine = ib.single_blow(model, 1.0, **fine_args)
        t_fine = median_time(lambda m=model, a=fine_args: ib.single_blow(m, 1.0, **a), 1)

        def err(b, attr, ref=exact):
            return abs(getattr(b, attr) / getattr(ref, attr) - 1.0)

        print(f"{name:28s} {1e3 * t_exact:9.2f} {exact.ended_by:>9s} {1e3 * t_coarse:12.2f} "
              f"{err(coarse, 'efficiency'):9.1e} {err(coarse, 'rebound_velocity'):9.1e} "
              f"{1e3 * t_fine:15.1f} {err(fine, 'efficiency'):9.1e} {err(fine, 'rebound_velocity'):9.1e}")


if __name__ == "__main__":
    main()
