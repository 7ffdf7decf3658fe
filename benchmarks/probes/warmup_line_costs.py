"""Each line of ``impactbar warmup`` alone: its first call in a fresh process with a new, empty numba
cache, against the same line's in the one-process warm-up (``impactbar warmup --jobs 1``, after the
lines before it: ``impactbar.cli.warmup.LINE_COST``). A line that alone compiles many more kernels
reuses those of the lines before it, which ``impactbar.cli.warmup.LINE_AFTER`` names, so that a
parallel warm-up starts it once they have finished.

Run: ``python benchmarks/probes/warmup_line_costs.py [LABEL ...]`` (default every line).

Per line, one after another: the call's CPU seconds (``time.process_time`` in the child, its imports
not counted), the kernels it compiled (numba's compiles and the C callbacks, as the warm-up counts
them; alone, a line compiles the callees that the lines before it compile in a serial warm-up), the
child's wall time and the load average at its end; then the lines' costs alone, the longest first.
Each child also has a new, empty folder for the modules generated for the oil
circuit's network (``XDG_CACHE_HOME``).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

_CHILD = r"""
import json, sys
from impactbar.cli import warmup

warmup._start(in_worker=False)
label, dt, _, kernels = warmup._line(sys.argv[1])
print(json.dumps([label, dt, len(kernels)]))
"""


def main(argv=None) -> int:
    labels = list(sys.argv[1:] if argv is None else argv)
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    env.pop("NUMBA_DISABLE_JIT", None)
    if not labels:
        from_tree = [sys.executable, "-c", "import json; from impactbar.cli.warmup import _tasks; "
                     "print(json.dumps([label for label, _ in _tasks()]))"]
        labels = json.loads(subprocess.run(from_tree, env=env, capture_output=True, text=True,
                                           check=True).stdout)
    costs = {}
    print(f"{'line':<36} {'CPU s':>6} {'kernels':>8} {'wall s':>7} {'load':>5}")
    for label in labels:
        cache, generated = tempfile.mkdtemp(prefix="warmup-line-"), tempfile.mkdtemp(prefix="warmup-gen-")
        try:
            t0 = time.perf_counter()
            done = subprocess.run([sys.executable, "-c", _CHILD, label], capture_output=True, text=True,
                                  env=dict(env, NUMBA_CACHE_DIR=cache, XDG_CACHE_HOME=generated))
            wall = time.perf_counter() - t0
        finally:
            shutil.rmtree(cache, ignore_errors=True)
            shutil.rmtree(generated, ignore_errors=True)
        if done.returncode:
            raise RuntimeError(f"{label} failed:\n{done.stderr[-3000:]}")
        _, dt, n = json.loads(done.stdout.strip().splitlines()[-1])
        costs[label] = dt
        print(f"{label:<36} {dt:>6.1f} {n:>8d} {wall:>7.1f} {os.getloadavg()[0]:>5.1f}", flush=True)
    print("\nalone, the longest first: " + ", ".join(
        f"{label} {dt:.1f}" for label, dt in sorted(costs.items(), key=lambda kv: -kv[1])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
