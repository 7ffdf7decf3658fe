"""Benchmark of the grid points per second of ``impactbar sweep`` on a local
``dask.distributed`` cluster of 1 and of 2 worker processes, side by side.

- ``orbits``: the rigid bar (``n_modes = 0``) under ``p0 + cos t``, a 200 x 200 grid over ``R`` and
  ``p0`` (the Fig. 5 chart as a grid), 400 points per chunk.
- ``montecarlo``: the rigid pneumatic hammer, 6 x 4 points over ``p0`` and ``R``, 20 random starts of
  200 load periods each per point, 2 points per chunk.

The time is that of :func:`impactbar.sweeps.run_sweep` after the cluster has started: workers
importing impactbar, computing every chunk, the driver writing each into the zarr store. Each run
writes a fresh store in a temporary folder.

Run: ``python benchmarks/bench_sweep.py [--grid N] [--quick]`` (``--quick``: a 40 x 40 grid and 8
starts). Prints a table; nothing is asserted. With ``--workers 1 2 4`` other sizes are timed.

``--process [--against SRC]`` instead times the whole ``impactbar sweep`` command of the rigid
``orbits`` spec in fresh processes (``--workers 2``, wall time: interpreter start, imports, cluster
or threads, store creation, every chunk, exit) at the grid sizes of ``--grids`` (default 200 and
632, about 40,000 and 400,000 points), with the spec's 400-point chunks and with the default
chunking; with ``--against SRC`` the package tree ``SRC`` (e.g. ``git archive <commit> src | tar -x
-C /tmp/old``) is timed alternately with this one, in the same run. Each cell's runs alternate with
the vectorised peer's: a fresh process that computes the same grid by the numpy closed
forms (the reference of ``"orbits.rigid_arrays"``) in one call over all its points and saves the
sweep's variables with ``np.savez``; the last column is the peer's wall time over this tree's.
"""

from __future__ import annotations

import argparse
import logging
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from distributed import Client, LocalCluster

from impactbar.sweeps import parse_spec, run_sweep


def orbits_spec(n: int):
    return parse_spec({
        "task": "orbits",
        "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
        "load": {"kind": "cosine", "p0": 0.3, "pk": 1.0, "k": 1},
        "axes": {"R": {"start": 0.0, "stop": 0.95, "num": n}, "p0": {"start": 0.2, "stop": 0.45, "num": n}},
        "chunk_points": 400,
    })


def montecarlo_spec(starts: int):
    return parse_spec({
        "task": "montecarlo",
        "model": {"s": 10.0, "d": 0.0047746, "R": 0.8, "n_modes": 0},
        "load": {"kind": "cosine", "p0": 1.2, "pk": 1.0, "k": 1},
        "axes": {"p0": {"start": 0.4, "stop": 1.6, "num": 6}, "R": {"values": [0.5, 0.6, 0.7, 0.8]}},
        "montecarlo": {"starts": starts, "periods": 200.0, "seed": 1},
        "chunk_points": 2,
    })


def points_per_second(spec, workers: int, folder: Path) -> tuple[float, float, float]:
    """Points per second of wall time, the wall time (s) and the CPU time of the workers (s):
    on a shared machine the CPU time shows whether the workers got their cores."""
    with (LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                       dashboard_address=None, silence_logs=logging.ERROR) as cluster,
          Client(cluster) as client):
        cpu0 = client.run(time.process_time)
        run = run_sweep(spec, folder / f"{spec.task}-{workers}.zarr", client=client, progress=False)
        cpu1 = client.run(time.process_time)
    assert run.complete
    cpu = sum(cpu1[w] - cpu0[w] for w in cpu0)
    return spec.n_points / run.seconds, run.seconds, cpu


def _toml(n: int, chunk_points: int | None) -> str:
    chunk = "" if chunk_points is None else f"chunk_points = {chunk_points}\n"
    return (f'task = "orbits"\n{chunk}[model]\ns = 100.0\nd = 0.0\nR = 0.5\nn_modes = 0\n'
            '[load]\nkind = "cosine"\np0 = 0.3\npk = 1.0\nk = 1\n'
            f'[axes.R]\nstart = 0.0\nstop = 0.95\nnum = {n}\n'
            f'[axes.p0]\nstart = 0.2\nstop = 0.45\nnum = {n}\n')


def process_seconds(spec_file: Path, out: Path, src: str, workers: int) -> float:
    """Wall time of one ``impactbar sweep`` command in a fresh process on the package tree ``src``."""
    env = dict(os.environ, PYTHONPATH=src)
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "impactbar.cli", "sweep", str(spec_file), "--out", str(out),
                    "--workers", str(workers), "--overwrite", "--no-progress"],
                   check=True, capture_output=True, env=env)
    return time.perf_counter() - t


#: the vectorised peer: one process that computes the same grid's orbits by the numpy
#: closed forms in one call over all its points and saves the sweep's variables with ``np.savez``
_PEER = """
import sys
import numpy as np
from impactbar.dynamics.implementations import use_reference
from impactbar.orbits.rigid import rigid_cosine_orbits
n = int(sys.argv[1])
R, p0 = np.meshgrid(np.linspace(0.0, 0.95, n), np.linspace(0.2, 0.45, n), indexing="ij")
with use_reference("orbits.rigid_arrays"):
    res = rigid_cosine_orbits(0.0, R, p0, 1.0, 1)
np.savez(sys.argv[2], n_orbits=res.n_orbits, phase=res.phase, impact_velocity=res.impact_velocity,
         admissible=res.admissible, stable=res.stable, schur_stable=res.schur_stable,
         max_abs_multiplier=res.max_abs_multiplier)
"""


def peer_seconds(n: int, out: Path, src: str) -> float:
    """Wall time of the vectorised peer process for the ``n x n`` grid."""
    env = dict(os.environ, PYTHONPATH=src)
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", _PEER, str(n), str(out)], check=True, capture_output=True, env=env)
    return time.perf_counter() - t


def main_process(args) -> None:
    here = str(Path(__file__).resolve().parents[1] / "src")
    trees = [("baseline", args.against)] if args.against else []
    trees.append(("this tree", here))
    print(f"cores: {os.cpu_count()}, load average at start: {os.getloadavg()[0]:.2f}")
    print("| points | chunk_points | " + " | ".join(f"{name}: points/s (median wall s)" for name, _ in trees)
          + (" | ratio" if len(trees) > 1 else "")
          + " | vectorised peer: points/s (wall s) | this tree / peer |")
    print("|" + "---|" * (4 + len(trees) + (len(trees) > 1)))
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.grids:
            for chunk in (400, None):
                spec_file = Path(tmp) / f"orbits-{n}-{chunk}.toml"
                spec_file.write_text(_toml(n, chunk))
                times = {name: [] for name, _ in trees} | {"peer": []}
                for _ in range(args.repeat):
                    for name, src in trees:  # alternately, so that both see the same load
                        times[name].append(process_seconds(spec_file, Path(tmp) / "s.zarr", src,
                                                           args.workers[-1]))
                    times["peer"].append(peer_seconds(n, Path(tmp) / "peer.npz", here))
                med = [statistics.median(times[name]) for name, _ in trees]
                peer = statistics.median(times["peer"])
                cells = " | ".join(f"{n * n / m:,.0f} ({m:.2f} s)" for m in med)
                ratio = f" | {med[0] / med[-1]:.2f}" if len(trees) > 1 else ""
                print(f"| {n * n:,} | {chunk or 'default'} | {cells}{ratio} | "
                      f"{n * n / peer:,.0f} ({peer:.2f} s) | {peer / med[-1]:.2f} |", flush=True)
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grid", type=int, default=200, help="orbits grid is GRID x GRID (default 200)")
    ap.add_argument("--starts", type=int, default=20, help="montecarlo starts per point (default 20)")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="cluster sizes (default 1 2)")
    ap.add_argument("--quick", action="store_true", help="40 x 40 grid, 8 starts")
    ap.add_argument("--process", action="store_true",
                    help="time the whole `impactbar sweep` command (rigid orbits, fresh processes)")
    ap.add_argument("--against", metavar="SRC", help="with --process: also time the package tree SRC")
    ap.add_argument("--grids", type=int, nargs="+", default=[200, 632],
                    help="with --process: grid sizes N (N x N points; default 200 632)")
    ap.add_argument("--repeat", type=int, default=3, help="with --process: runs per tree (default 3)")
    args = ap.parse_args()
    if args.process:
        main_process(args)
        return
    if args.quick:
        args.grid, args.starts = 40, 8
    specs = [(f"orbits, rigid, {args.grid} x {args.grid}", orbits_spec(args.grid)),
             (f"montecarlo, rigid, 6 x 4 points x {args.starts} starts x 200 periods",
              montecarlo_spec(args.starts))]
    print(f"cores: {os.cpu_count()}, load average at start: {os.getloadavg()[0]:.2f}")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, spec in specs:
            row = [label, spec.n_points, spec.n_chunks]
            for w in args.workers:
                row.append(points_per_second(spec, w, Path(tmp)))
            rows.append(row)
    cols = [f"{w} worker{'s' if w > 1 else ''}: points/s (wall s, worker CPU s)" for w in args.workers]
    head = "| sweep | points | chunks | " + " | ".join(cols) + " | speed-up |"
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for label, n, c, *cells in rows:
        speed = cells[-1][0] / cells[0][0]
        print(f"| {label} | {n} | {c} | " + " | ".join(f"{p:.1f} ({s:.1f}, {cpu:.1f})" for p, s, cpu in cells)
              + f" | {speed:.2f} |")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
