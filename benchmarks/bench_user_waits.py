"""What a user waits for on the oil circuit's tasks: each task's first call with an empty numba cache,
its first call in a new process once the cache holds its kernels, and its later calls.

Tasks (the SI layer as the README shows it, or the model layer where the docs show that):

- ``circuit orbit, rigid``: ``circuit_preset("circuit-drifter").orbit()``;
- ``circuit orbit, 8 modes``: the same preset with ``model.n_modes = 8``;
- ``continuation, 8 modes (a point)``: ``continue_orbit`` of that orbit in the pre-charge, three
  points (the orbit itself is not counted; the time is per point after the first);
- ``circuit on rock orbit``: ``examples/circuit_drifter_rock.toml``'s ``orbit()``;
- ``circuit simulate, 20 periods``: ``simulate`` of the rigid preset from rest, 20 of its periods.

Each task runs in its own fresh processes with its own numba cache (``NUMBA_CACHE_DIR``): the first
with the cache empty (the task's first call, nearly all of it numba compiling, then two later calls:
the least CPU time), the second with the cache the first filled (the task's first call: loading the
kernels, the caches of the process). CPU seconds of the call only (imports not counted).

Run: ``python benchmarks/bench_user_waits.py [--only TASK ...]``.
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

ROOT = Path(__file__).resolve().parents[1]

_CHILD = r"""
import json, sys, time
import impactbar as ib
from impactbar import physical as ph

task, root = sys.argv[1], sys.argv[2]


def call():
    if task == "circuit orbit, rigid":
        return ph.circuit_preset("circuit-drifter").orbit()
    if task == "circuit orbit, 8 modes":
        cfg, _ = ph.read_config("circuit-drifter")
        return ph.build(ph.with_values(cfg, {"model.n_modes": 8})).orbit()
    if task == "circuit on rock orbit":
        cfg, _ = ph.read_config(root + "/examples/circuit_drifter_rock.toml")
        return ph.build(cfg).orbit()
    if task == "circuit simulate, 20 periods":
        d = ph.circuit_preset("circuit-drifter")
        model, drive = d.model(), d.drive()
        return ib.simulate(model, drive, ib.InitialState.rigid(0.0, 0.0, n_modes=0), 20 * 1.0343)
    raise SystemExit("unknown task " + task)


if task == "continuation, 8 modes (a point)":
    cfg, _ = ph.read_config("circuit-drifter")
    d = ph.build(ph.with_values(cfg, {"model.n_modes": 8}))
    model, drive = d.model(), d.drive()
    orbit = ib.find_orbit(model, drive)  # (not counted)
    to = drive.accumulator.precharge * 1.05

    def timed():
        t = time.process_time()
        b = ib.continue_orbit(orbit, "precharge", to=to, max_points=3, events=False)
        return (time.process_time() - t) / max(1, len(b.orbits) - 1)
else:
    def timed():
        t = time.process_time()
        call()
        return time.process_time() - t

first = timed()
later = min(timed() for _ in range(int(sys.argv[3])))
print(json.dumps({"first": first, "later": later}))
"""

TASKS = ("circuit orbit, rigid", "circuit orbit, 8 modes", "continuation, 8 modes (a point)",
         "circuit on rock orbit", "circuit simulate, 20 periods")


def _child(task: str, cache: str, later: int) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
               MKL_NUM_THREADS="1", PYTHONPATH=str(ROOT / "src"))
    env.pop("NUMBA_OPT", None)
    out = subprocess.run([sys.executable, "-c", _CHILD, task, str(ROOT), str(later)], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def measure(task: str) -> dict:
    """``{"empty": first call with an empty cache, "warm": first call with the cache filled,
    "later": the least of the later calls}``, CPU seconds."""
    cache = tempfile.mkdtemp(prefix="impactbar-waits-")
    try:
        cold = _child(task, cache, 2)
        warm = _child(task, cache, 1)
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    return {"empty": cold["first"], "warm": warm["first"], "later": min(cold["later"], warm["later"])}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", nargs="*", choices=TASKS, help="these tasks only")
    a = ap.parse_args(argv)
    print(f"{'task (CPU s)':<36} {'first, empty cache':>18} {'first, cache warm':>18} {'later':>8}")
    for task in a.only or TASKS:
        r = measure(task)
        print(f"{task:<36} {r['empty']:>18.2f} {r['warm']:>18.3f} {r['later']:>8.3f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
