"""``bench_first_call.py``'s row ``cluster``: a fresh local dask cluster's first sweep point per worker
against a warm worker's (the same worker's next point).

A driver process (fresh, on the package tree under test) starts a local cluster of 2 worker processes,
one thread each, and submits to each worker, pinned, two chunks of one point each of an ``orbits``
sweep of an 8-mode bar (``compute_chunk``; the workers' first points at once, then their second):
the first imports impactbar in the worker and loads or
compiles its kernels, the second is a warm worker's point. Each point's time is the CPU time of the
worker's thread that ran it (``time.thread_time``, the import of impactbar included in the first).
On a tree that has :func:`impactbar.sweeps.use_numba_cache`, the workers are pointed at a shared
numba cache folder filled once beforehand by one process computing the same points (some points
need kernels that others do not; what
``NUMBA_CACHE_DIR=FOLDER impactbar warmup`` does for every kind of call); on one without it, the
workers start with an empty cache (one folder, but both compile at once, as two fresh nodes do).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent

SPEC = {"task": "orbits", "model": {"s": 5.0, "d": 0.1, "R": 0.5, "n_modes": 8},
        "load": {"kind": "cosine", "p0": 0.6, "pk": 1.0, "k": 1}, "chunk_points": 1,
        "axes": {"R": {"values": [0.40, 0.45, 0.50, 0.55]}}}


def point(chunk: int) -> dict:
    """One sweep point on this worker: its thread's CPU seconds (the import of impactbar included
    when it is the worker's first) and the kernels numba compiled meanwhile."""
    import time

    t = time.thread_time()
    from numba.core import event

    compiled = []

    class Count(event.Listener):
        def on_start(self, ev):
            pass

        def on_end(self, ev):
            compiled.append(1)

    listener = Count()
    event.register("numba:compile", listener)
    try:
        from impactbar.sweeps import compute_chunk, parse_spec

        compute_chunk(parse_spec(SPEC), chunk)
    finally:
        event.unregister("numba:compile", listener)
    return {"cpu": time.thread_time() - t, "compiles": len(compiled)}


_DRIVER = r"""
import json, logging, sys
from distributed import Client, LocalCluster
import _cluster

shared = sys.argv[1]
with (LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                   dashboard_address=None, silence_logs=logging.ERROR) as cluster, Client(cluster) as cl):
    if shared:
        from impactbar.sweeps import use_numba_cache
        use_numba_cache(cl, shared)
    workers = sorted(cl.scheduler_info()["workers"])
    # the workers' first points at once (with a cache of their own, as two fresh nodes), then the next
    first, warm = ([cl.submit(_cluster.point, 2 * k + j, workers=[w], pure=False)
                    for k, w in enumerate(workers)] for j in (0, 1))
    first = cl.gather(first)
    warm = cl.gather(warm)
print(json.dumps(list(zip(first, warm))))
"""


def _run(code: str, args, env) -> str:
    done = subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True, text=True)
    if done.returncode:
        raise RuntimeError(f"cluster row failed:\n{done.stderr[-3000:]}")
    return done.stdout.strip().splitlines()[-1]


def cluster_first_points(src: str, env: dict) -> dict:
    """The row on the package tree ``src`` (``env``: the benchmark's child environment): ``first``
    the worst worker's first point less its warm point (CPU s), with each worker's figures."""
    shared = tempfile.mkdtemp(prefix="impactbar-shared-numba-")
    own = tempfile.mkdtemp(prefix="impactbar-own-numba-")
    env = dict(env, PYTHONPATH=src + os.pathsep + str(HERE), NUMBA_CACHE_DIR=own)
    try:
        has_plugin = (Path(src) / "impactbar" / "sweeps" / "numba_cache.py").exists()
        r = {}
        if has_plugin:  # the shared folder, filled once by one process computing the points
            fill = "import json, _cluster; print(json.dumps([_cluster.point(k) for k in range(4)]))"
            filled = json.loads(_run(fill, [], dict(env, NUMBA_CACHE_DIR=shared)))
            r["filling the shared cache (s)"] = sum(p["cpu"] for p in filled)
        workers = json.loads(_run(_DRIVER, [shared if has_plugin else ""], env))
    finally:
        shutil.rmtree(shared, ignore_errors=True)
        shutil.rmtree(own, ignore_errors=True)
    r["first"] = max(f["cpu"] - w["cpu"] for f, w in workers)
    r["compiles"] = sum(f["compiles"] + w["compiles"] for f, w in workers)
    r["workers' first points (s)"] = " / ".join(f"{f['cpu']:.2f}" for f, _ in workers)
    r["warm points (s)"] = " / ".join(f"{w['cpu']:.2f}" for _, w in workers)
    r["cache"] = "shared, filled once" if has_plugin else "each worker's own, empty"
    r["kernels"], r["digest"], r["whole"] = [], "", 0.0
    return r
