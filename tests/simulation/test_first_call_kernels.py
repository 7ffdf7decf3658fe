"""How many numba kernels a first call compiles, counted (not timed) in a fresh process with an
empty numba cache: each compile is CPU time a designer waits for once (``bench_first_call.py``
times them). A kernel that compiles for a second signature (the same arrays with another layout, a
literal flag) is a compile no result needs."""

import json
import os
import subprocess
import sys
from collections import Counter

_RIGID = """
import json
from numba.core import event
from impactbar import BarModel, CosineLoad, InitialState, simulate

compiled = []


class Count(event.Listener):
    def on_start(self, ev):
        pass

    def on_end(self, ev):
        fn = ev.data["dispatcher"].py_func
        compiled.append(fn.__module__ + "." + fn.__qualname__)


event.register("numba:compile", Count())
simulate(BarModel(5.0, 0.1, 0.5, 0), CosineLoad(0.6, 1.0), InitialState.rigid(-0.2, 0.0), 30.0)
print(json.dumps(compiled))
"""


def test_a_rigid_simulate_compiles_each_kernel_once_and_no_more_than_15d5b20(tmp_path):
    """A rigid ``simulate`` under a cosine load compiles each of impactbar's kernels for one
    signature, 32 compiles in all (numba's own helpers included) as in release 15d5b20: the crossing
    search's scratch rows are C arrays, as the arrays Python passes it, not the 'A' arrays of an
    unpacked block that made the search and six flight kernels compile twice (39 compiles)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), NUMBA_CACHE_DIR=str(tmp_path),
               OMP_NUM_THREADS="1")
    env.pop("NUMBA_DISABLE_JIT", None)
    done = subprocess.run([sys.executable, "-c", _RIGID], env=env, capture_output=True, text=True,
                          check=True)
    compiled = json.loads(done.stdout.strip().splitlines()[-1])
    twice = {k: n for k, n in Counter(compiled).items() if k.startswith("impactbar.") and n > 1}
    assert twice == {}
    assert 20 <= len(compiled) <= 32
