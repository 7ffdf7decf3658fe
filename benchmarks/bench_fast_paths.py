"""Benchmark of the fast paths: each fast path against the path it replaces, in the same run.

Rows (baseline | new | ratio | the goal):

- rigid bar, cosine load, one grid point: ``periodic_orbits`` by the general path (certified
  searches, dense Jacobian) against the closed forms; the closed forms on 1-element numpy arrays
  against the same formulas in plain floats (cosine and square wave); and per point of a
  vectorised call over a 40,000-point grid;
- the sweep ``orbits`` task, rigid bar: ``compute_chunk`` point by point against the vectorised
  chunk (400 points); and 4,000-point chunks of a 200 x 200 grid by the vectorised numpy closed
  forms (the reference of ``"orbits.rigid_arrays"``) against the compiled loop over the points;
- ``periodic_orbits`` with 8 and 64 modes (cosine, square wave) and 256 modes (cosine): with the
  dense eigenvalue problem for the multipliers against the structured method; the multipliers alone
  at 256 modes;
- ``periodic_orbits`` with 8 modes (cosine) and 64 modes (square wave): the certified admissibility
  search by numpy (the reference) against the compiled search;
- ``import impactbar`` and ``impactbar orbits --help`` (fresh processes, wall time): everything the
  package used to import eagerly against the lazy imports;
- ``simulate``: impacts per second, the general certified impact search (the reference of
  ``"simulate.impact_search"``)
  against the specialised ones (rigid bar in scalars, flexible modes in folded form), and a
  100-impact run, with the kernel data rebuilt on every call (as before) against the cached core;
  the rigid bar's 1-impact run against a compiled minimal loop for it (``_peers.py``).

Times are medians of repeated runs of CPU time (``time.process_time``) for the in-process rows and
of wall time for the fresh processes, so that other load on a shared machine weighs less. BLAS runs
on one thread (``OMP_NUM_THREADS`` etc. default to 1 here), since CPU time counts every thread.

Run: ``python benchmarks/bench_fast_paths.py [--quick]``. Prints a table; nothing is asserted.

``--against SRC`` instead times the same user-level calls (``periodic_orbits``, ``simulate``, and the
rigid bar's 2-per-2 ``continue_orbit`` branch per point; ``periodic_orbits`` from 64 to
1024 modes and the exponent of its growth; the rigid bar's ``simulate`` over one load
period asked by ``t_end`` (one impact in it), with ``max_impacts=10`` too, and by ``max_impacts=1``,
each beside the compiled minimal loop of ``_peers.py`` for the same run, alternated in the same
process, and the ratio; over 2e5 load periods beside the same loop and beside the event kernel
alone, into arrays made beforehand) in
fresh processes on the package tree ``SRC`` (e.g. ``git archive <commit> src | tar -x -C /tmp/old``
then ``--against /tmp/old/src``) and on this one, alternately, and prints both side by side.

``--cold [--against SRC] [--kernels]`` times the first call of each entry point
(``periodic_orbits`` and ``simulate``: rigid bar, 8 and 64 modes, the wave law) in a fresh process
with an empty numba cache (``NUMBA_CACHE_DIR`` set to a new folder), as on a new machine: CPU time
of the call, and with ``--kernels`` the slowest kernels to compile (each without its callees'
compiles), on ``SRC`` and on this tree alternately.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time

# process_time counts every thread of the process: one BLAS thread, so that CPU time is the work
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from impactbar import BarModel, CosineLoad, InitialState, SquareWaveLoad, periodic_orbits, simulate  # noqa: E402
from impactbar.dynamics import monodromy  # noqa: E402
from impactbar.dynamics.implementations import use_reference  # noqa: E402
from impactbar.orbits import stability  # noqa: E402
from impactbar.orbits.one_impact import _periodic_orbits_general  # noqa: E402
from impactbar.orbits.rigid import rigid_cosine_orbits  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _peers import minimal_loop_rigid  # noqa: E402

ROWS = []


def cpu_median(fn, repeat):
    fn()
    ts = []
    for _ in range(repeat):
        t = time.process_time()
        fn()
        ts.append(time.process_time() - t)
    return float(np.median(ts))


def wall_median(cmd, repeat):
    ts = []
    for _ in range(repeat):
        t = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        ts.append(time.perf_counter() - t)
    return float(np.median(ts))


def row(task, base, new, unit, goal, higher_is_better=False):
    ratio = new / base if higher_is_better else base / new
    ROWS.append((task, base, new, unit, ratio, goal))
    print(f"{task:<52} {base:>12.4g} {new:>12.4g} {unit:<9} {ratio:>8.1f}x   {goal}", flush=True)


def bench_rigid(rep):
    model, load = BarModel(5.0, 0.1, 0.5, 0), CosineLoad(0.6, 1.0)
    base = cpu_median(lambda: _periodic_orbits_general(model, load), rep)
    new = cpu_median(lambda: periodic_orbits(model, load), rep * 10)
    row("rigid, cosine, one periodic_orbits call", base * 1e3, new * 1e3, "ms", "<= 0.3 ms")
    for name, ld in (("cosine", load), ("square wave", SquareWaveLoad(1.0, 1.2))):
        with use_reference("orbits.rigid_scalar"):  # the numpy closed form on 1-element arrays
            vec1 = cpu_median(lambda ld=ld: periodic_orbits(model, ld), rep * 10)
        flt = cpu_median(lambda ld=ld: periodic_orbits(model, ld), rep * 10)
        row(f"rigid, {name}, one call: numpy closed form vs floats", vec1 * 1e3, flt * 1e3, "ms",
            "<= 0.3 ms")
    R, p0 = np.meshgrid(np.linspace(0.0, 0.95, 200), np.linspace(0.2, 0.45, 200))
    vec = cpu_median(lambda: rigid_cosine_orbits(0.1, R.ravel(), p0.ravel(), 1.0, 1), 5) / R.size
    row("rigid, cosine, per point of a 40,000-point array", base * 1e3, vec * 1e3, "ms", "2.5 us (numpy)")


def bench_chunk(quick):
    from impactbar.sweeps import tasks
    from impactbar.sweeps.spec import parse_spec

    spec = parse_spec({
        "task": "orbits",
        "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
        "load": {"kind": "cosine", "p0": 0.3, "pk": 1.0, "k": 1},
        "axes": {"R": {"start": 0.0, "stop": 0.95, "num": 200},
                 "p0": {"start": 0.2, "stop": 0.45, "num": 200}},
        "chunk_points": 400,
    })
    chunks = range(2 if quick else 6)
    new = cpu_median(lambda: [tasks.compute_chunk(spec, c) for c in chunks], 5)
    fast = tasks._rigid_chunk
    tasks._rigid_chunk = lambda *a: None
    try:
        base = cpu_median(lambda: tasks.compute_chunk(spec, 0), 1) * len(chunks)
    finally:
        tasks._rigid_chunk = fast
    n = 400 * len(chunks)
    row("sweep orbits task, rigid: compute_chunk", n / base, n / new, "points/s", ">= 100,000 /s per core",
        higher_is_better=True)
    # 4,000-point chunks over the whole 200 x 200 grid (its ten chunks: the points without
    # an orbit are cheap, so one chunk alone flatters), the numpy closed forms (the reference of
    # "orbits.rigid_arrays", what a sweep below 100,000 points takes) against the compiled loop over
    # the points (what a larger sweep takes), at d = 0 and d = 0.05
    for d in (0.0, 0.05):
        spec = parse_spec({
            "task": "orbits",
            "model": {"s": 100.0, "d": d, "R": 0.5, "n_modes": 0},
            "load": {"kind": "cosine", "p0": 0.3, "pk": 1.0, "k": 1},
            "axes": {"R": {"start": 0.0, "stop": 0.95, "num": 200},
                     "p0": {"start": 0.2, "stop": 0.45, "num": 200}},
            "chunk_points": 4000,
        })
        chunks = range(spec.n_chunks)
        with use_reference("orbits.rigid_arrays"):
            base = cpu_median(lambda spec=spec, chunks=chunks: [tasks.compute_chunk(spec, c) for c in chunks],
                              3)
        small, tasks.COMPILED_CLOSED_FORMS_FROM = tasks.COMPILED_CLOSED_FORMS_FROM, 0  # as a large sweep
        try:
            new = cpu_median(lambda spec=spec, chunks=chunks: [tasks.compute_chunk(spec, c) for c in chunks],
                             3)
        finally:
            tasks.COMPILED_CLOSED_FORMS_FROM = small
        n = spec.n_points
        row(f"compute_chunk, 4,000 points, d = {d}: numpy vs compiled", n / base, n / new, "points/s",
            ">= 1,000,000 /s", higher_is_better=True)


def bench_modes(rep):
    cases = [("cosine, 8 modes", BarModel(5.0, 0.1, 0.5, 8), CosineLoad(0.6, 1.0), rep, "<= 1.5 ms"),
             ("cosine, 64 modes", BarModel(5.0, 0.1, 0.5, 64), CosineLoad(0.6, 1.0), rep // 2, "<= 10 ms"),
             ("square wave, 64 modes", BarModel(5.0, 0.1, 0.5, 64), SquareWaveLoad(1.0, 1.2), 3, "<= 40 ms"),
             ("cosine, 256 modes", BarModel(5.0, 0.1, 0.5, 256), CosineLoad(0.6, 1.0), 3, "<= 30 ms")]
    for name, model, load, r, goal in cases:
        keep = monodromy.STRUCTURED_FROM
        monodromy.STRUCTURED_FROM = 10**9  # every multiplier by the dense eigenvalue problem
        try:
            base = cpu_median(lambda model=model, load=load: periodic_orbits(model, load), max(r, 3))
        finally:
            monodromy.STRUCTURED_FROM = keep
        new = cpu_median(lambda model=model, load=load: periodic_orbits(model, load), max(r, 3))
        row(f"periodic_orbits, {name}", base * 1e3, new * 1e3, "ms", goal)
    model, load = BarModel(5.0, 0.1, 0.5, 256), CosineLoad(0.6, 1.0)
    o = periodic_orbits(model, load)[0]
    args = (model, load, o.phase, o.state_after_impact, o.state_before_impact)
    base = cpu_median(lambda: stability.floquet_multipliers(*args, method="dense"), 3)
    new = cpu_median(lambda: stability.floquet_multipliers(*args, method="structured"), 5)
    row("multipliers alone, 256 modes (one orbit)", base * 1e3, new * 1e3, "ms", "O(N^2)")


def bench_admissibility(rep):
    """The certified admissibility search by numpy (the reference path) against the compiled
    search, inside the whole periodic_orbits call (flexible bars)."""
    cases = [("cosine, 8 modes", BarModel(5.0, 0.1, 0.5, 8), CosineLoad(0.6, 1.0), rep, "<= 1.5 ms"),
             ("square wave, 64 modes", BarModel(5.0, 0.1, 0.5, 64), SquareWaveLoad(1.0, 1.2), 5,
              "<= 40 ms")]
    for name, model, load, r, goal in cases:
        with use_reference("admissibility.search"):
            base = cpu_median(lambda model=model, load=load: periodic_orbits(model, load), max(r, 3))
        new = cpu_median(lambda model=model, load=load: periodic_orbits(model, load), max(r, 3))
        row(f"periodic_orbits, {name}: numpy vs compiled search", base * 1e3, new * 1e3, "ms", goal)


def bench_startup(rep):
    py = sys.executable
    eager = ("import impactbar, impactbar.orbits, impactbar.simulation, impactbar.physical.results, "
             "impactbar.sweeps, scipy.optimize")
    base = wall_median([py, "-c", eager], rep)
    new = wall_median([py, "-c", "import impactbar"], rep)
    row("import impactbar (fresh process, wall)", base, new, "s", "<= 0.5 s")
    cli_eager = eager + "; from impactbar.cli import main; main(['orbits', '--help'])"
    cli_new = "import sys; from impactbar.cli import main; main(['orbits', '--help'])"
    base = wall_median([py, "-c", cli_eager], rep)
    new = wall_median([py, "-c", cli_new], rep)
    row("impactbar orbits --help (fresh process, wall)", base, new, "s", "<= 0.5 s")
    numpy_only = wall_median([py, "-c", "import numpy"], rep)
    print(f"{'   (import numpy alone, same machine)':<52} {numpy_only:>12.4g}")


def bench_simulate(quick):
    import importlib

    sim = importlib.import_module("impactbar.simulation.simulate")
    for n_modes, n in ((0, 20000), (8, 5000), (64, 1000)):
        if quick:
            n //= 5
        model, load = BarModel(1.37, 0.02, 0.8, n_modes), CosineLoad(1.2, 1.0)
        orbit = next(o for o in periodic_orbits(model, load) if o.stable)
        q, v = orbit.modal_state_after_impact
        q = q.copy()
        q[0] -= 1e-3
        st, t0 = InitialState(q, v), orbit.phase
        fresh = sim._core_for

        def run(k, st=st, t0=t0, model=model, load=load):
            return simulate(model, load, st, t0 + 1e7, t0=t0, max_impacts=k)

        new = cpu_median(lambda n=n: run(n), 3)
        with use_reference("simulate.impact_search"):  # the general certified search
            base = n / cpu_median(lambda n=n: run(n), 3)
        new100 = cpu_median(lambda: run(100), 50)
        sim._core_for = lambda m, ld: sim._Core(m, ld)  # the kernel data rebuilt on every call
        try:
            base100 = cpu_median(lambda: run(100), 50)
        finally:
            sim._core_for = fresh
        row(f"simulate, {n_modes} modes, one harmonic", base, n / new, "impacts/s",
            ">= 2 M/s rigid, 2x at 8, 64" if n_modes == 0 else ">= 2x the baseline",
            higher_is_better=True)
        row(f"simulate, {n_modes} modes, a 100-impact run", base100 * 1e6, new100 * 1e6, "us",
            "fixed cost <= 50 us")
        if n_modes == 0:  # against a compiled minimal loop for the same run (benchmarks/_peers.py)
            new1 = cpu_median(lambda: run(1), 201)
            peer1 = cpu_median(lambda q=q, v=v, t0=t0: minimal_loop_rigid(q[0], v[0], t0, t0 + 1e7, 1, 1.2,
                                                                          1.0, 0.02, 0.8), 201)
            row("simulate, rigid, a 1-impact run: vs a minimal loop", peer1 * 1e6, new1 * 1e6, "us",
                "<= 2x the peer")


_USER_LEVEL = r"""
import json, sys, time
import numpy as np
from impactbar import BarModel, CosineLoad, InitialState, SquareWaveLoad, periodic_orbits, simulate

def cpu(fn, rep):
    fn()
    ts = []
    for _ in range(rep):
        t = time.process_time()
        fn()
        ts.append(time.process_time() - t)
    return float(np.median(ts))

out = {}
po = periodic_orbits
out["periodic_orbits, rigid, cosine (ms)"] = cpu(
    lambda: po(BarModel(5, 0.1, 0.5, 0), CosineLoad(0.6, 1)), 101) * 1e3
out["periodic_orbits, rigid, square wave (ms)"] = cpu(
    lambda: po(BarModel(5, 0.1, 0.5, 0), SquareWaveLoad(1, 1.2)), 51) * 1e3
for n in (8, 64):
    out[f"periodic_orbits, cosine, {n} modes (ms)"] = cpu(
        lambda: po(BarModel(5, 0.1, 0.5, n), CosineLoad(0.6, 1)), 11) * 1e3
out["periodic_orbits, square wave, 64 modes (ms)"] = cpu(
    lambda: po(BarModel(5, 0.1, 0.5, 64), SquareWaveLoad(1, 1.2)), 3) * 1e3
for n, rep in ((256, 5), (1024, 5)):
    out[f"periodic_orbits, cosine, {n} modes (ms)"] = cpu(
        lambda: po(BarModel(5, 0.1, 0.5, n), CosineLoad(0.6, 1)), rep) * 1e3
for N, n in ((0, 20000), (8, 5000), (64, 1000)):
    model, load = BarModel(1.37, 0.02, 0.8, N), CosineLoad(1.2, 1.0)
    o = next(o for o in po(model, load) if o.stable)
    q, v = o.modal_state_after_impact
    q = q.copy()
    q[0] -= 1e-3
    st = InitialState(q, v)
    run = lambda k: simulate(model, load, st, o.phase + 1e7, t0=o.phase, max_impacts=k)
    out[f"simulate, {N} modes (impacts/s)"] = n / cpu(lambda: run(n), 3)
    out[f"simulate, {N} modes, 1-impact run (us)"] = cpu(lambda: run(1), 101) * 1e6
    out[f"simulate, {N} modes, 100-impact run (us)"] = cpu(lambda: run(100), 51) * 1e6
    if N == 0:  # the peer: a compiled minimal loop for the same run (benchmarks/_peers.py)
        from _peers import minimal_loop_rigid

        peer = lambda k: minimal_loop_rigid(q[0], v[0], o.phase, o.phase + 1e7, k, 1.2, 1.0, 0.02, 0.8)
        out["peer: compiled minimal loop, rigid, 1-impact run (us)"] = cpu(lambda: peer(1), 101) * 1e6
        out["peer: compiled minimal loop, rigid, 100-impact run (us)"] = cpu(lambda: peer(100), 51) * 1e6
        # a run over one load period asked by t_end (from mid-flight: one impact in it), with
        # and without max_impacts; a run over 2e5 periods; each beside its peer in this process
        t1 = o.phase + np.pi
        mid = simulate(model, load, st, t1, t0=o.phase).final_state
        x1, u1 = float(mid.modal_displacement[0]), float(mid.modal_velocity[0])
        T1 = t1 + 2 * np.pi
        assert simulate(model, load, mid, T1, t0=t1).n_impacts == 1
        fixed = {
            "one load period by t_end": lambda: simulate(model, load, mid, T1, t0=t1),
            "one load period by t_end, max_impacts=10": lambda: simulate(model, load, mid, T1, t0=t1,
                                                                         max_impacts=10),
            "1-impact run by max_impacts=1": lambda: run(1),
        }
        peers = {
            "one load period by t_end": lambda: minimal_loop_rigid(x1, u1, t1, T1, 1000, 1.2, 1.0, 0.02, 0.8),
            "one load period by t_end, max_impacts=10": lambda: minimal_loop_rigid(x1, u1, t1, T1, 10, 1.2,
                                                                                   1.0, 0.02, 0.8),
            "1-impact run by max_impacts=1": lambda: peer(1),
        }
        for name, fn in fixed.items():
            ours, theirs = [], []
            for _ in range(5):  # alternated, so that both see the same moments of a loaded machine
                ours.append(cpu(fn, 41))
                theirs.append(cpu(peers[name], 41))
            ours, theirs = min(ours) * 1e6, min(theirs) * 1e6
            out[f"simulate, rigid, {name} (us)"] = ours
            out[f"peer: minimal loop, rigid, {name} (us)"] = theirs
            out[f"simulate / peer, rigid, {name} (x)"] = ours / theirs
        T = o.phase + 2 * np.pi * 2e5
        n_long = simulate(model, load, st, T, t0=o.phase).n_impacts
        long_peer = lambda: minimal_loop_rigid(q[0], v[0], o.phase, T, 10**6, 1.2, 1.0, 0.02, 0.8)
        n_peer = long_peer()[0].size
        ours = n_long / cpu(lambda: simulate(model, load, st, T, t0=o.phase), 3)
        theirs = n_peer / cpu(long_peer, 3)
        out["simulate, rigid, 2e5 load periods (impacts/s)"] = ours
        out["peer: minimal loop, rigid, 2e5 load periods (impacts/s)"] = theirs
        out["simulate / peer, rigid, 2e5 load periods (x impacts/s)"] = ours / theirs
        # the floor of a long run: the compiled event kernel alone, into arrays made beforehand
        import importlib
        core = importlib.import_module("impactbar.simulation.simulate")._core_for(model, load)
        oq, ov = np.empty((n_long + 1, 1)), np.empty((n_long + 1, 1))
        bare = lambda: core.run_free(o.phase, q.copy(), v.copy(), T, n_long + 1, oq, ov)
        theirs = n_long / cpu(bare, 3)
        out["peer: the event kernel alone, rigid, 2e5 periods (impacts/s)"] = theirs
        out["simulate / kernel alone, rigid, 2e5 load periods (x impacts/s)"] = ours / theirs
# the rigid 2-per-2 branch from the one-impact orbit's period doubling to its own (51 points; as
# bench_continuation.py's second case), per point of the branch
from impactbar import continue_orbit

rigid = BarModel(s=3.0, d=0.0, R=0.6, n_modes=0)
one = next(o for o in po(rigid, CosineLoad(0.9, 1.0)) if np.cos(o.phase) < 0)
pd = continue_orbit(one, "p0", to=0.66, stop_on=("period-doubling",)).events[-1]
points = len(continue_orbit(pd, "p0", to=0.66, stop_on=("period-doubling",)))
out["continue_orbit, rigid 2-per-2 branch, per point (ms)"] = cpu(
    lambda: continue_orbit(pd, "p0", to=0.66, stop_on=("period-doubling",)), 7) / points * 1e3
print(json.dumps(out))
"""


#: the goals for simulate's short runs that the --against table marks (each ratio taken in one
#: process, both calls alternated)
GOALS = {
    "simulate / peer, rigid, one load period by t_end (x)": "<= 2",
    "simulate / peer, rigid, one load period by t_end, max_impacts=10 (x)": "<= 2",
    "simulate / peer, rigid, 1-impact run by max_impacts=1 (x)": "<= 2",
    "simulate / peer, rigid, 2e5 load periods (x impacts/s)": ">= 1",
    "simulate / kernel alone, rigid, 2e5 load periods (x impacts/s)": "(the driver's share)",
}


def against(src, rounds=2):
    """The user-level calls on another package tree and on this one, in fresh processes."""
    import json
    from pathlib import Path

    here = str(Path(__file__).resolve().parents[1] / "src")
    peers = str(Path(__file__).resolve().parent)  # _peers.py
    runs = {"baseline": [], "new": []}
    for _ in range(rounds):
        for name, path in (("baseline", src), ("new", here)):
            env = dict(os.environ, PYTHONPATH=path + os.pathsep + peers)  # one-thread BLAS, as above
            out = subprocess.run([sys.executable, "-c", _USER_LEVEL], env=env, check=True,
                                 capture_output=True, text=True).stdout
            runs[name].append(json.loads(out.strip().splitlines()[-1]))
    head = f"call (median CPU time; best of {rounds} processes)"
    print(f"{head:<66} {'baseline':>12} {'new':>12}   goal")
    for key in runs["new"][0]:
        best = max if "/s" in key else min  # (a ratio "(x ...)" of a fixed cost: the least)
        b = best(r.get(key, np.nan) for r in runs["baseline"])
        n = best(r[key] for r in runs["new"])
        print(f"{key:<66} {b:>12.4g} {n:>12.4g}   {GOALS.get(key, '')}")
    # the growth of periodic_orbits' cost with the modes, T ~ N^exponent from 64 to 1024 (goal <= 1.2)
    lo, hi = "periodic_orbits, cosine, 64 modes (ms)", "periodic_orbits, cosine, 1024 modes (ms)"
    exps = [np.log(min(r[hi] for r in runs[k]) / min(r[lo] for r in runs[k])) / np.log(16.0)
            for k in ("baseline", "new")]
    print(f"{'periodic_orbits, exponent from 64 to 1024 modes':<52} {exps[0]:>12.3g} {exps[1]:>12.3g}")


_COLD = r"""
import json, sys, time
from collections import defaultdict
t0 = time.process_time()
import numpy as np
from impactbar import BarModel, CosineLoad, InitialState, periodic_orbits, simulate
t_import = time.process_time() - t0
kernels = defaultdict(float)
try:  # the compile time of each kernel, its callees' compiles taken out
    from numba.core import event

    stack = []

    class Listener(event.Listener):
        def on_start(self, ev):
            stack.append((ev.data["dispatcher"].py_func, time.process_time()))

        def on_end(self, ev):
            fn, t = stack.pop()
            dt = time.process_time() - t
            kernels[fn.__module__.rsplit(".", 1)[-1] + "." + fn.__name__] += dt
            if stack:
                parent = stack[-1][0]
                kernels[parent.__module__.rsplit(".", 1)[-1] + "." + parent.__name__] -= dt

    event.register("numba:compile", Listener())
except ImportError:
    pass
entry = sys.argv[1]
n = {"rigid": 0, "8": 8, "64": 64, "wave": 8}[entry.split()[-1]]
model = BarModel(5.0, 0.1, 0.5, n, impact="wave" if entry.endswith("wave") else "paper")
if entry.startswith("periodic_orbits"):
    def call():
        periodic_orbits(model, CosineLoad(0.6, 1.0))
else:
    def call():
        simulate(model, CosineLoad(0.6, 1.0), InitialState.rigid(-0.2, 0.0, n), 30.0)
t = time.process_time()
call()
first = time.process_time() - t
t = time.process_time()
call()
warm = time.process_time() - t
top = sorted(kernels.items(), key=lambda kv: -kv[1])[:8]
print(json.dumps({"import": t_import, "first": first, "warm": warm, "kernels": top}))
"""

#: the entry points of the cold-start rows: call and model (rigid, 8 or 64 modes, or the wave law)
COLD_ENTRIES = ("periodic_orbits rigid", "periodic_orbits 8", "periodic_orbits 64", "periodic_orbits wave",
                "simulate rigid", "simulate 8", "simulate wave")


def cold(src, rounds=1, verbose=False):
    """The first call of each entry point in a fresh process with an empty numba cache, on another
    package tree ``src`` (if given) and on this one, alternately (CPU time of the call)."""
    import json
    import shutil
    import tempfile
    from pathlib import Path

    here = str(Path(__file__).resolve().parents[1] / "src")
    trees = ([("baseline", src)] if src else []) + [("new", here)]
    print(f"{'first call, empty numba cache (CPU s)':<52} " + " ".join(f"{n:>12}" for n, _ in trees)
          + f" {'warm (ms)':>12}")
    for entry in COLD_ENTRIES:
        best = {}
        for _ in range(rounds):
            for name, path in trees:
                cache = tempfile.mkdtemp(prefix="impactbar-cold-")
                try:
                    env = dict(os.environ, PYTHONPATH=path, NUMBA_CACHE_DIR=cache)
                    out = subprocess.run([sys.executable, "-c", _COLD, entry], env=env, check=True,
                                         capture_output=True, text=True).stdout
                finally:
                    shutil.rmtree(cache, ignore_errors=True)
                r = json.loads(out.strip().splitlines()[-1])
                if name not in best or r["first"] < best[name]["first"]:
                    best[name] = r
        cells = " ".join(f"{best[n]['first']:>12.3g}" for n, _ in trees)
        print(f"{entry:<52} {cells} {best['new']['warm'] * 1e3:>12.3g}", flush=True)
        if verbose:
            for name, _ in trees:
                kern = ", ".join(f"{k} {v:.2f}" for k, v in best[name]["kernels"])
                print(f"    {name}: {kern}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer repetitions")
    ap.add_argument("--against", metavar="SRC", help="compare with the package tree SRC instead")
    ap.add_argument("--cold", action="store_true",
                    help="time each entry point's first call in a fresh process with an empty numba "
                    "cache (with --against: that tree too, alternately)")
    ap.add_argument("--kernels", action="store_true", help="with --cold: the slowest kernels to compile")
    a = ap.parse_args(argv)
    if a.cold:
        cold(a.against, verbose=a.kernels)
        return 0
    if a.against:
        against(a.against)
        return 0
    rep = 5 if a.quick else 21
    print(f"{'task':<52} {'baseline':>12} {'new':>12} {'unit':<9} {'gain':>9}   goal")
    print("-" * 120)
    bench_rigid(rep)
    bench_chunk(a.quick)
    bench_modes(rep)
    bench_admissibility(rep)
    bench_startup(3 if a.quick else 7)
    bench_simulate(a.quick)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
