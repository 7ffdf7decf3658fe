"""How a sweep of rock orbits scales over dask workers: each worker's fixed start, the cost of a point,
the chunking, and how busy the workers stay; and a model of that, measured here, for any worker count.

The sweep is the rock-orbit sweep of ``examples/sweep_rock.toml`` (the rigid piston under a cosine load
on a rod and a bilinear rock, Newton on the blow's tangents at each point) grown to ``--points`` points
(a square grid over the rock's stiffness and the rod's length). For each worker count of
``--workers``:

- **start**: a local cluster of that many worker processes started and connected (s of wall time:
  process spawn, Python, distributed's imports);
- **warm-up**: on every worker at once, the import of impactbar and one point of the sweep's task
  computed, which loads the task's compiled kernels from numba's cache (each worker's own time, s;
  the slowest is what the cluster waits for);
- **sweep**: :func:`impactbar.sweeps.run_sweep` on that cluster (wall s, cluster start and warm-up
  excluded), the workers' compute time from dask's task stream, their **busy fraction** (compute
  time over workers x wall time) and the same counted from the cluster's start (start, warm-up and
  sweep in the wall time).

The **model** (printed after the runs) takes the per-point cost ``c`` (the task stream's compute
time over the points), the fixed start ``F`` (start plus the slowest warm-up) and the chunk count
``K`` of ``P`` points: a sweep on ``N`` workers takes ``T(N) = F + ceil(K / N) (P / K) c`` and keeps
them busy ``P c / (N T(N))`` of the time, counted from the cluster's start, or ``P c / (N (T(N) -
F))`` counted, as :class:`~impactbar.sweeps.SweepRun` counts, from the sweep's start. It is
printed for 1, 2, 4, 8, 16 and 32 workers at the spec's chunking and at other chunk sizes, so a
2-core machine predicts what a 16-core one does; a run on a many-core machine checks it.

Run: ``python benchmarks/bench_sweep_scale.py [--points 1024] [--workers 2] [--chunk-points 16]``
(the kernels cached: run ``impactbar warmup`` once first, or the first worker pays the compile).
Prints tables; nothing is asserted. ``--json FILE`` also writes every number.
"""

from __future__ import annotations

import argparse
import heapq
import json
import logging
import math
import os
import statistics
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def rock_spec(points: int, chunk_points: int | None):
    """The rock-orbit sweep of ``examples/sweep_rock.toml`` on about ``points`` points (a square grid)."""
    from impactbar.sweeps import parse_spec

    doc = tomllib.loads((ROOT / "examples" / "sweep_rock.toml").read_text())
    n = max(1, round(math.sqrt(points)))
    m = max(1, math.ceil(points / n))
    doc["axes"] = {"rock.k": {"start": 15.0, "stop": 120.0, "num": n},
                   "segment0.length": {"start": 12.0, "stop": 24.0, "num": m}}
    if chunk_points is not None:
        doc["chunk_points"] = chunk_points
    return parse_spec(doc)


def warm_worker(spec) -> float:
    """On a worker: import impactbar and compute the sweep's first point (its kernels loaded from
    numba's cache); the seconds it took."""
    t0 = time.perf_counter()
    from impactbar.sweeps import parse_spec
    from impactbar.sweeps.tasks import compute_chunk

    record = spec.to_dict()
    record["axes"] = {a.name: {"values": [float(a.values[0])]} for a in spec.axes}
    record["chunk_points"] = 1
    compute_chunk(parse_spec(record), 0)
    return time.perf_counter() - t0


def run_one(spec, workers: int, folder: Path) -> dict:
    """Start a cluster of ``workers``, warm it, run the sweep; the times of each stage."""
    from distributed import Client, LocalCluster, get_task_stream

    from impactbar.sweeps import run_sweep

    t0 = time.perf_counter()
    with (LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                       dashboard_address=None, silence_logs=logging.ERROR) as cluster,
          Client(cluster) as client):
        client.wait_for_workers(workers)
        start = time.perf_counter() - t0
        t1 = time.perf_counter()
        warm = list(client.run(warm_worker, spec).values())
        warm_wall = time.perf_counter() - t1
        with get_task_stream(client) as stream:
            store = folder / f"rock-{workers}-{spec.chunk_points}.zarr"
            run = run_sweep(spec, store, client=client, progress=False)
        total = time.perf_counter() - t0
    assert run.complete
    chunk_s = {int(rec["key"].rsplit("-", 1)[1]): sum(s["stop"] - s["start"] for s in rec["startstops"]
                                                      if s["action"] == "compute") for rec in stream.data}
    busy = sum(chunk_s.values())
    return {"workers": workers, "chunk_points": spec.chunk_points, "start_s": start, "warm_s": warm,
            "warm_wall_s": warm_wall, "sweep_s": run.seconds, "total_s": total, "compute_s": busy,
            "chunk_s": chunk_s, "busy": busy / (workers * run.seconds),
            "busy_from_start": busy / (workers * total)}


def point_costs(spec, chunk_s: dict) -> np.ndarray:
    """Each point's compute time (s), shape ``spec.shape``: a chunk's time spread evenly over its
    points (exact for chunks of one point)."""
    cost = np.zeros(spec.shape)
    for i, t in chunk_s.items():
        block = spec.block(i)
        cost[block] = t / cost[block].size
    return cost


def model(cost: np.ndarray, chunk_points: int, workers: int, fixed: float) -> tuple[float, float, float]:
    """``T(N)`` by the model and the busy fractions from the cluster's start and from the sweep's: the
    chunks of ``chunk_points`` (their costs summed from ``cost``) handed, in order, each to the worker
    free first (as dask's scheduler hands out a queue of equal-priority tasks)."""
    spec = rock_spec(cost.size, chunk_points)
    free = [0.0] * workers
    for i in range(spec.n_chunks):
        heapq.heappush(free, heapq.heappop(free) + float(cost[spec.block(i)].sum()))
    sweep, work = max(free), float(cost.sum())
    return fixed + sweep, work / (workers * (fixed + sweep)), work / (workers * sweep)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=1024)
    ap.add_argument("--workers", type=int, nargs="+", default=[2])
    ap.add_argument("--chunk-points", type=int, nargs="+", default=[None],
                    help="chunk sizes to run (each with every worker count); default: the spec's")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    spec = rock_spec(args.points, None)
    print(f"cores: {os.cpu_count()}, load average at start: {os.getloadavg()[0]:.2f}; "
          f"{spec.n_points} points, the spec's default chunks of {spec.chunk_points}")
    print("| workers | chunk points | start (s) | warm-up per worker (s, median / max) | sweep (s) | "
          "compute (s) | busy, from the sweep's start | busy, from the cluster's start |")
    print("|---|---|---|---|---|---|---|---|")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for cp, w in ((cp, w) for cp in args.chunk_points for w in args.workers):
            r = run_one(rock_spec(args.points, cp), w, Path(tmp))
            rows.append(r)
            warm = f"{statistics.median(r['warm_s']):.2f} / {max(r['warm_s']):.2f}"
            print(f"| {w} | {r['chunk_points']} | {r['start_s']:.2f} | {warm} | {r['sweep_s']:.2f} | "
                  f"{r['compute_s']:.1f} | {r['busy']:.0%} | {r['busy_from_start']:.0%} |", flush=True)
    # the model's per-point costs: from the run with the smallest chunks and, of those, the least
    # compute time (the quietest machine)
    base = min(rows, key=lambda r: (r["chunk_points"], r["compute_s"]))
    cost = point_costs(rock_spec(args.points, base["chunk_points"]), base["chunk_s"])
    fixed = statistics.median(r["start_s"] + max(r["warm_s"]) for r in rows)
    print(f"\nmodel: a point costs {1e3 * cost.mean():.0f} ms on average ({1e3 * cost.min():.0f} to "
          f"{1e3 * cost.max():.0f}; from the run of {base['workers']} workers in chunks of "
          f"{base['chunk_points']}), F = {fixed:.2f} s (start + slowest warm-up)")
    sizes = sorted({spec.chunk_points, 1, 4, 16, 64})
    print("| workers | " + " | ".join(f"chunks of {s}: T(N) s, busy from start / sweep" for s in sizes)
          + " |")
    print("|---|" + "---|" * len(sizes))
    for n in (1, 2, 4, 8, 16, 32):
        cells = []
        for s in sizes:
            t, b0, b1 = model(cost, s, n, fixed)
            cells.append(f"{t:.1f}, {b0:.0%} / {b1:.0%}")
        print(f"| {n} | " + " | ".join(cells) + " |")
    if args.json:
        args.json.write_text(json.dumps({"points": spec.n_points, "F": fixed, "point_costs": cost.tolist(),
                                         "runs": rows}, indent=1))


if __name__ == "__main__":
    main()
