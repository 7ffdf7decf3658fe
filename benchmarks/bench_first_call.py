"""The first exact rod-rock blow and rock orbit, empty numba cache: the compile, here and on another tree.

Run: ``python benchmarks/bench_first_call.py [--rock-orbit] [--against SRC] [--rounds N] [--kernels K]``.
Each cell is a fresh process with a new, empty numba cache (``NUMBA_CACHE_DIR``) that makes the README's
exact blow (``single_blow`` under ``RodRock``: a 40-long rod on a bilinear rock, no feed), as a new
user's first call: the CPU time of the call (nearly all of it numba compiling the exact blow's kernels),
the count of compiles and the result (``efficiency``, to the bit). ``--rock-orbit`` times instead the
first periodic orbit with exact blows, ``impactbar warmup``'s task "rod and rock orbits, exact blows"
(a 2-mode bar on a short rod and rock: ``simulate``, then ``find_orbit`` from the settled run; the two
parts' CPU times apart, and the orbit's impact times, states and multipliers to the bit). With
``--against SRC`` (a package tree, the folder holding ``impactbar``) that tree is timed too, alternately
with this one; ``--kernels K`` lists the K slowest kernels to compile in each (each kernel's own time,
its callees' compiles taken out, summed over its signatures, and how many signatures it compiled for).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

_CHILD = r"""
import json, sys, time
from collections import defaultdict
from numba.core import event
from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow

own, count, stack = defaultdict(float), defaultdict(int), []


def name(fn):
    return fn.__module__.rsplit(".", 1)[-1] + "." + fn.__name__


class Listener(event.Listener):  # each kernel's compile time, its callees' compiles taken out
    def on_start(self, ev):
        stack.append((ev.data["dispatcher"].py_func, time.process_time()))

    def on_end(self, ev):
        fn, t = stack.pop()
        dt = time.process_time() - t
        own[name(fn)] += dt
        count[name(fn)] += 1
        if stack:
            own[name(stack[-1][0])] -= dt


event.register("numba:compile", Listener())
out = {}
if sys.argv[1] == "blow":
    law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
    model = BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law)
    t = time.process_time()
    blow = single_blow(model, 1.0, t_max=39.0)
    first = time.process_time() - t
    out["efficiency"] = repr(blow.efficiency)
else:  # impactbar warmup's "rod and rock orbits, exact blows" (cli/warmup.py's rock_orbit(on_rock))
    from impactbar import CosineLoad, InitialState, find_orbit, simulate
    short = RodRock(segments=[RodSegment(length=2.0, impedance=2.0)], rock=BilinearRock(k=20.0, k_u=200.0))
    model, gentle = BarModel(10.0, 0.3, 0.0, 2, impact=short), CosineLoad(0.3, 1.0)
    t = time.process_time()
    run = simulate(model, gentle, InitialState.rigid(-0.1, 0.0, 2), 60.0)
    out["simulate"] = time.process_time() - t
    orbit = find_orbit(model, gentle, impacts=2, periods=2, guess=run)
    first = time.process_time() - t
    out["find_orbit"] = first - out["simulate"]
    out["orbit"] = repr((orbit.period, orbit.impact_times.tolist(), orbit.states_after_impact.tolist(),
                         orbit.multipliers.tolist()))
top = sorted(own.items(), key=lambda kv: -kv[1])
print(json.dumps(dict(out, first=first, compiles=sum(count.values()),
                      kernels=[(k, v, count[k]) for k, v in top])))
"""


def first_call(src: str, case: str = "blow") -> dict:
    """One fresh process with an empty numba cache on the package tree ``src``: the first exact blow
    (``case`` ``"blow"``) or the first periodic orbit with exact blows (``"orbit"``)."""
    cache = tempfile.mkdtemp(prefix="impactbar-first-")
    try:
        env = dict(os.environ, PYTHONPATH=src, NUMBA_CACHE_DIR=cache, OMP_NUM_THREADS="1",
                   OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
        env.pop("NUMBA_OPT", None)
        env.pop("IMPACTBAR_TIERED", None)
        out = subprocess.run([sys.executable, "-c", _CHILD, case], env=env, check=True, capture_output=True,
                             text=True).stdout
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    return json.loads(out.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--against", metavar="SRC", help="also time the package tree SRC (alternately)")
    ap.add_argument("--rounds", type=int, default=1, help="processes per tree (the least CPU time kept)")
    ap.add_argument("--kernels", type=int, default=0, metavar="K", help="list the K slowest kernels")
    ap.add_argument("--rock-orbit", action="store_true",
                    help="time the first periodic orbit with exact blows (impactbar warmup's task)")
    a = ap.parse_args(argv)
    case = "orbit" if a.rock_orbit else "blow"
    here = str(Path(__file__).resolve().parents[1] / "src")
    trees = ([("baseline", a.against)] if a.against else []) + [("new", here)]
    best = {}
    for _ in range(max(1, a.rounds)):
        for label, src in trees:
            r = first_call(src, case)
            if label not in best or r["first"] < best[label]["first"]:
                best[label] = r
    rows = (("first", "CPU time (s)", "{:>20.1f}"), ("compiles", "kernels compiled", "{:>20d}"))
    if case == "blow":
        title = "first exact blow, empty numba cache"
        rows += (("efficiency", "efficiency (repr)", "{:>20s}"),)
    else:
        title = "first exact rock orbit, empty cache"
        rows += (("simulate", "  of which simulate (s)", "{:>20.1f}"),
                 ("find_orbit", "  of which find_orbit (s)", "{:>20.1f}"))
    print(f"{title:<36} " + " ".join(f"{n:>20}" for n, _ in trees))
    for key, title, fmt in rows:
        print(f"{title:<36} " + " ".join(fmt.format(best[n][key]) for n, _ in trees))
    if case == "orbit":
        same = len({best[n]["orbit"] for n, _ in trees}) == 1
        print(f"{'orbit (times, states, multipliers)':<36} "
              + ("the same to the bit" if same else "DIFFERENT") + ": " + best[trees[-1][0]]["orbit"][:120])
    for label, _ in trees if a.kernels else ():
        print(f"\n{label}: the slowest kernels to compile (own CPU s, signatures)")
        for k, v, c in best[label]["kernels"][:a.kernels]:
            print(f"    {k:<40} {v:>6.2f} {c:>4d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
