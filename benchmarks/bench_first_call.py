"""A designer's first call of each entry point with an empty numba cache, here and on another tree.

Run: ``python benchmarks/bench_first_call.py [--rows ROW ...] [--quick] [--against SRC] [--kernels K]
[--jobs N ...]``.

Each cell is a fresh process with a new, empty numba cache (``NUMBA_CACHE_DIR``), one-thread BLAS and
neither ``NUMBA_OPT`` nor ``IMPACTBAR_TIERED``, that makes one row's first call:

- ``paper``: ``impactbar paper`` (Figs. 4-8), the whole command (its process's CPU time, the
  interpreter's start and the imports included);
- ``simulate``: a rigid bar's ``simulate`` under a cosine load (30 time units);
- ``orbits8``: ``periodic_orbits`` of an 8-mode bar under a cosine load;
- ``circuit``: the preset ``circuit-drifter``'s ``orbit()`` with 4 flexible modes, then in the same
  process with 16 (the second call's time and compiles are in the notes);
- ``rock``: ``examples/circuit_drifter_rock.toml``'s ``orbit()`` (the oil circuit on a rod and rock);
- ``blow``: the README's first exact blow (``single_blow`` under ``RodRock``, a 40-long rod on a
  bilinear rock);
- ``warmup``: ``impactbar warmup``, the whole command; with ``--jobs N ...``, one row a count of its
  worker processes (``impactbar warmup --jobs N``; the baseline's row is its plain ``impactbar
  warmup``, timed once, which compiles in one process as ``--jobs 1`` does);
- ``cluster``: a fresh local dask cluster (2 workers, one thread each) whose workers read a shared
  numba cache that ``impactbar warmup`` filled (:class:`impactbar.sweeps.NumbaCacheFolder`), each
  worker's first point of a small sweep against a warm worker's (the same workers' second point);
  the cell is the worst worker's difference, the goal within 2 s. (Only on this tree: the baseline
  has no such way, its cell is a fresh cluster without a shared cache.)

The figure of a row is the CPU time of its call inside the child (``time.process_time``, imports not
counted), or for the commands (``paper``, ``warmup``) the child's whole CPU time (``getrusage`` of
the finished child, its own children included: a parallel warm-up's workers); a row's notes give the
child's wall time too (which a parallel warm-up's workers shorten). CPU time, not wall time: the
development machine is shared by many jobs, which change the wall time far more than the CPU time
(though a loaded machine's caches still slow a compile some 10-30 %). Each row also counts numba's
compiles (``numba:compile`` events in the child, not in a parallel warm-up's workers, whose count
is in the warm-up's last line; the oil circuit's C callbacks, compiled at import without that
event, are not counted) and, without ``--quick``, times the same call again in a new process on the cache
the first filled (``warm``). With ``--against SRC`` (a package tree, the folder holding
``impactbar``) that tree is timed too, alternately with this one, and the rows' results (a digest of
each call's numbers) are compared to the bit. A row that misses its goal lists its ``--kernels K``
slowest kernels to compile (each kernel's own CPU time, its callees' compiles taken out, summed
over its signatures, and how many signatures it compiled for): the reason. Every row lists, per
tree, the package's kernels compiled for more than one signature, with the arguments whose types
differ (a literal constant, an integer's width, an array's layout or writability, ...).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: the child's listener of numba's compiles (also ``probes/circuit_first_compiles.py``'s): each kernel's
#: own CPU time in ``own``, its compiles in ``count``, by ``name``, and each of the package's kernels'
#: signatures (its arguments' types) in ``sigs``, by name and dispatcher
_LISTENER = r"""
import json, sys, time
from collections import defaultdict
from numba.core import event

own, count, sigs, stack = defaultdict(float), defaultdict(int), defaultdict(list), []


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
        if fn.__module__.startswith("impactbar"):  # (by dispatcher: two made of one function are two)
            sigs[name(fn) + "@" + hex(id(ev.data["dispatcher"]))].append([str(a) for a in ev.data["args"]])
        if stack:
            own[name(stack[-1][0])] -= dt


event.register("numba:compile", Listener())
"""

_CHILD = _LISTENER + r"""
row, root, out_dir = sys.argv[1], sys.argv[2], sys.argv[3]
out = {}


def compiles():
    return sum(count.values())


def timed(call):
    t = time.process_time()
    result = call()
    return time.process_time() - t, result


if row in ("paper", "warmup"):
    from impactbar.cli import main
    argv = ["paper", "--out", out_dir, "--quiet"] if row == "paper" else ["warmup", *sys.argv[4:]]
    first, status = timed(lambda: main(argv))
    assert status == 0, status
    digest = open(out_dir + "/fig5.csv").read() if row == "paper" else ""
    import resource  # (the largest resident memory of this process and of its workers, finished)
    out["largest process (MB)"] = max(resource.getrusage(w).ru_maxrss / 1024
                                      for w in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
elif row == "simulate":
    from impactbar import BarModel, CosineLoad, InitialState, simulate
    first, run = timed(lambda: simulate(BarModel(5.0, 0.1, 0.5, 0), CosineLoad(0.6, 1.0),
                                        InitialState.rigid(-0.2, 0.0), 30.0))
    digest = repr((run.impact_times.tolist(), run.final_state.modal_displacement.tolist(),
                   run.final_state.modal_velocity.tolist()))
elif row == "orbits8":
    from impactbar import BarModel, CosineLoad, periodic_orbits
    first, orbits = timed(lambda: periodic_orbits(BarModel(5.0, 0.1, 0.5, 8), CosineLoad(0.6, 1.0)))
    digest = repr([(o.phases.tolist(), o.impact_velocities.tolist(), o.multipliers.tolist()) for o in orbits])
elif row in ("circuit", "rock"):
    from impactbar import physical as ph
    if row == "circuit":
        cfg, _ = ph.read_config("circuit-drifter")
        first, orbit = timed(lambda: ph.build(ph.with_values(cfg, {"model.n_modes": 4})).orbit())
        before = compiles()
        out["then 16 modes (s)"], more = timed(
            lambda: ph.build(ph.with_values(cfg, {"model.n_modes": 16})).orbit())
        out["then 16 modes: compiles"] = compiles() - before
        digest = repr((orbit.blow_frequency_Hz, orbit.impact_velocity_m_s, more.blow_frequency_Hz))
    else:
        cfg, _ = ph.read_config(root + "/examples/circuit_drifter_rock.toml")
        first, orbit = timed(lambda: ph.build(cfg).orbit())
        digest = repr((orbit.blow_frequency_Hz, orbit.impact_velocity_m_s))
elif row == "blow":
    from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow
    law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
    first, blow = timed(lambda: single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0,
                                            t_max=39.0))
    digest = repr(blow.efficiency)
else:
    raise SystemExit("unknown row " + row)
top = sorted(own.items(), key=lambda kv: -kv[1])
print(json.dumps(dict(out, first=first, compiles=compiles(), digest=digest,
                      kernels=[(k, v, count[k]) for k, v in top],
                      twice={k.split("@")[0]: v for k, v in sigs.items() if len(v) > 1})))
"""

#: row: (title, goal in CPU seconds, the figure is the whole child's CPU time)
ROWS = {
    "paper": ("impactbar paper (Figs. 4-8), whole", 10.0, True),
    "simulate": ("rigid simulate", 10.0, False),
    "orbits8": ("8-mode periodic_orbits", 10.0, False),
    "circuit": ("circuit drifter orbit(), 4 then 16 modes", 10.0, False),
    "rock": ("circuit on rock orbit()", 10.0, False),
    "blow": ("first exact blow", 10.0, False),
    "warmup": ("impactbar warmup, whole", 60.0, True),
    "cluster": ("fresh cluster's first point - warm's (worst worker)", 2.0, False),
}
QUICK = ("simulate", "orbits8", "blow")


def _env(src: str, cache: str) -> dict:
    env = dict(os.environ, PYTHONPATH=src, NUMBA_CACHE_DIR=cache, OMP_NUM_THREADS="1",
               OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1", MPLBACKEND="Agg")
    env.pop("NUMBA_OPT", None)
    env.pop("IMPACTBAR_TIERED", None)
    return env


def _child(src: str, row: str, cache: str, extra: tuple = ()) -> dict:
    """One fresh process on the package tree ``src`` and the numba cache ``cache``: the row's call
    (the command's options ``extra`` after its own)."""
    out = tempfile.mkdtemp(prefix="impactbar-first-out-")
    try:
        before, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
        done = subprocess.run([sys.executable, "-c", _CHILD, row, str(ROOT), out, *extra],
                              env=_env(src, cache), capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    finally:
        shutil.rmtree(out, ignore_errors=True)
    if done.returncode:
        raise RuntimeError(f"{row} on {src} failed:\n{done.stderr[-3000:]}")
    r = json.loads(done.stdout.strip().splitlines()[-1])
    r["whole"] = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    r["wall"] = wall
    if row == "warmup":  # (its own count: numba's compiles and the C callbacks, in its workers too)
        r["its last line"] = next(x for x in done.stdout.splitlines() if " kernels compiled in " in x)
    if ROWS[row][2]:
        r["first"] = r["whole"]
    return r


def first_call(src: str, row: str, warm: bool = False, extra: tuple = ()) -> dict:
    """The row's first call in a fresh process with a new, empty numba cache on the package tree
    ``src`` (the command's options ``extra``); with ``warm``, also the same call in a second fresh
    process on the cache the first filled (``r["warm"]``, its CPU seconds, and ``r["warm
    compiles"]``)."""
    if row == "cluster":
        from _cluster import cluster_first_points

        return cluster_first_points(src, _env(src, ""))
    cache = tempfile.mkdtemp(prefix="impactbar-first-")
    try:
        r = _child(src, row, cache, extra)
        if warm:
            w = _child(src, row, cache, extra)
            r["warm"], r["warm compiles"] = w["first"], w["compiles"]
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    return r


def _differing(signatures: list) -> str:
    """The arguments in which a kernel's signatures differ (a literal, a dtype, a layout, ...): each
    such argument's position and its types, ``"arg 2: int64 | Literal[int](1)"``."""
    if len({len(s) for s in signatures}) > 1:
        return "argument counts " + " | ".join(str(len(s)) for s in signatures)
    return ", ".join(f"arg {i}: " + " | ".join(dict.fromkeys(s[i] for s in signatures))
                     for i in range(len(signatures[0])) if len({s[i] for s in signatures}) > 1)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", nargs="+", choices=tuple(ROWS), metavar="ROW",
                    help="the rows to run (default all): " + ", ".join(ROWS))
    ap.add_argument("--quick", action="store_true",
                    help="only " + ", ".join(QUICK) + " (unless --rows), and no warm run")
    ap.add_argument("--against", metavar="SRC", help="also time the package tree SRC (alternately)")
    ap.add_argument("--rounds", type=int, default=1, help="processes per tree (the least CPU time kept)")
    ap.add_argument("--kernels", type=int, default=3, metavar="K",
                    help="the K slowest kernels of a row that misses its goal (default 3)")
    ap.add_argument("--jobs", type=int, nargs="+", metavar="N",
                    help="the warmup row once for each N, as impactbar warmup --jobs N on this tree")
    a = ap.parse_args(argv)
    rows = a.rows or (QUICK if a.quick else tuple(ROWS))
    plan = [(row, j) for row in rows for j in (a.jobs if row == "warmup" and a.jobs else [None])]
    measured = {}  # (tree, row, options): its result (the baseline's warm-up timed once for all N)
    here = str(ROOT / "src")
    trees = ([("baseline", a.against)] if a.against else []) + [("now", here)]
    print("CPU seconds of each first call with an empty numba cache, each in a fresh process (CPU "
          "time, not wall time: this machine is shared, which disturbs the wall time far more)")
    print(f"{'row':<52} {'baseline':>9} {'now':>9} {'goal':>6}  {'':<7} {'compiles':>13} {'warm':>6}")
    for row, jobs in plan:
        title, goal, _ = ROWS[row]
        title = title.replace(", whole", f" --jobs {jobs}, whole") if jobs else title
        best = {}
        for k in range(max(1, a.rounds)):
            for label, src in trees:
                extra = ("--jobs", str(jobs)) if jobs and label == "now" else ()
                key = (label, row, extra, k)
                if key not in measured:
                    measured[key] = first_call(src, row, warm=label == "now" and not a.quick, extra=extra)
                r = measured[key]
                if label not in best or r["first"] < best[label]["first"]:
                    best[label] = r
        now = best["now"]
        base = best.get("baseline")
        met = now["first"] <= goal
        cells = f"{base['first']:>9.1f}" if base else f"{'-':>9}"
        comp = (f"{base['compiles']:>5d} -> " if base else " " * 9) + f"{now['compiles']:<4d}"
        warm = f"{now['warm']:>6.2f}" if "warm" in now else f"{'-':>6}"
        print(f"{title:<52} {cells} {now['first']:>9.1f} {goal:>6.0f}  {'met' if met else 'MISSED':<7}"
              f" {comp:>13} {warm}", flush=True)
        notes = [f"{k} {v:.2f}" if isinstance(v, float) else f"{k} {v}" for k, v in now.items()
                 if k not in ("first", "compiles", "digest", "kernels", "whole", "warm", "twice")]
        if not ROWS[row][2] and row != "cluster":
            notes.append(f"whole process {now['whole']:.1f} s")
        if base and "wall" in base:
            notes.append(f"baseline wall {base['wall']:.1f} s")
        if base and row != "cluster":
            notes.append("results the same to the bit" if base["digest"] == now["digest"]
                         else "results DIFFERENT")
        if notes:
            print("    " + "; ".join(notes))
        for label, r in best.items():
            if r.get("twice"):
                print(f"    {label}: compiled for more than one signature: " + "; ".join(
                    f"{k} {len(v)} ({_differing(v)})" for k, v in sorted(r["twice"].items())))
        if not met and now.get("kernels"):
            print("    slowest to compile (own CPU s, signatures): " + ", ".join(
                f"{k} {v:.1f} ({c})" for k, v, c in now["kernels"][:a.kernels]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
