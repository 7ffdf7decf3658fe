"""Probe: what the oil circuit's first ``orbit()`` compiles, counted in a fresh process with an empty
numba cache (the preset ``circuit-drifter`` with 4 flexible modes, as ``bench_first_call.py``'s
``circuit`` row): numba's compiles (``numba:compile`` events) and C callbacks (``numba.cfunc``,
compiled without that event, listed with ``C``), each one's own CPU time (its callees' compiles taken
out) and signatures (the dispatcher's ``signatures`` after the call), and the LLVM
libraries turned into machine code (numba's ``JITCodeLibrary`` finalised with machine code: a kernel's
own, or a link-only kernel's none); then the orbit's numbers to the bit (a digest), to compare trees.

Run: ``python benchmarks/probes/circuit_first_compiles.py [--tree SRC ...] [--top K]`` (each tree a
package folder, default this one's ``src``; each run a fresh child process with a new empty
``NUMBA_CACHE_DIR`` and a new generated-code folder). Library behaviour is not changed.
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

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_first_call import _LISTENER  # noqa: E402  (the benchmark's listener of numba's compiles)

_CHILD = _LISTENER + r"""
import gc, hashlib
from numba.core import codegen
from numba.core.dispatcher import Dispatcher

emitted = [0]
plain = codegen.JITCodeLibrary._finalize_final_module


def finalize(self):  # a library whose machine code is made (a link-only one is another class)
    if type(self) is codegen.JITCodeLibrary:
        emitted[0] += 1
    return plain(self)


codegen.JITCodeLibrary._finalize_final_module = finalize
from numba.core.ccallback import CFunc

uncached = CFunc._compile_uncached


def callback(self):  # a C callback compiles without numba's event: timed and counted here as one
    stack.append((self._pyfunc, time.process_time()))
    try:
        return uncached(self)
    finally:
        fn, t = stack.pop()
        dt = time.process_time() - t
        own["C " + name(fn)] += dt
        count["C " + name(fn)] += 1
        if stack:
            own[name(stack[-1][0])] -= dt


CFunc._compile_uncached = callback
from impactbar import physical as ph

cfg, _ = ph.read_config("circuit-drifter")
t = time.process_time()
orbit = ph.build(ph.with_values(cfg, {"model.n_modes": 4})).orbit()
cpu = time.process_time() - t
sigs = {}
for obj in gc.get_objects():
    if isinstance(obj, Dispatcher) and obj.overloads:
        sigs[name(obj.py_func)] = sigs.get(name(obj.py_func), 0) + len(obj.overloads)
digest = hashlib.sha1(repr((orbit.blow_frequency_Hz, orbit.impact_velocity_m_s)).encode()).hexdigest()[:12]
print(json.dumps(dict(cpu=cpu, compiles=sum(v for k, v in count.items() if not k.startswith("C ")),
                      callbacks=sum(v for k, v in count.items() if k.startswith("C ")),
                      machine_code=emitted[0], digest=digest,
                      kernels=sorted(((k, own[k], count[k], sigs.get(k, 0)) for k in own),
                                     key=lambda r: -r[1]))))
"""


def run(src: str) -> dict:
    """One fresh process on the package tree ``src``, an empty numba cache and generated-code folder."""
    tmp = tempfile.mkdtemp(prefix="impactbar-probe-")
    try:
        env = dict(os.environ, PYTHONPATH=src, NUMBA_CACHE_DIR=tmp + "/numba", XDG_CACHE_HOME=tmp + "/xdg",
                   OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
        env.pop("NUMBA_OPT", None)
        env.pop("IMPACTBAR_TIERED", None)
        done = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True, text=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if done.returncode:
        raise RuntimeError(done.stderr[-3000:])
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tree", nargs="+", default=[str(ROOT / "src")], help="package trees (alternately)")
    ap.add_argument("--top", type=int, default=25, help="kernels listed (slowest own compile first)")
    a = ap.parse_args(argv)
    for src in a.tree:
        r = run(src)
        print(f"{src}: call {r['cpu']:.1f} s CPU, {r['compiles']} compiles, {r['callbacks']} C callbacks, "
              f"{r['machine_code']} libraries with machine code, digest {r['digest']}")
        print(f"    {'kernel':<40} {'own s':>6} {'compiles':>8} {'signatures':>10}")
        for k, s, c, n in r["kernels"][:a.top]:
            print(f"    {k:<40} {s:>6.2f} {c:>8d} {n:>10d}")
        multi = [(k, c) for k, _, c, _ in r["kernels"] if c > 1]
        print("    compiled more than once: " + (", ".join(f"{k} {c}" for k, c in multi) or "none"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
