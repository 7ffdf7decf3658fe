r"""Probe: where numba spends the oil circuit's first ``orbit()`` (the preset ``circuit-drifter`` with 4
flexible modes, ``bench_first_call.py``'s ``circuit`` row), by numba's compiler passes, in a fresh
process with an empty numba cache and a new generated-code folder.

Each pass's own CPU time is summed over every compile of the call (the time of the compiles it starts
inside itself, a callee's typing for instance, taken out), with LLVM's work on a finished library
timed apart: its module optimisation (``_optimize_final_module``) and its machine code
(``_finalize_final_module``). With ``--opt N`` the child runs with ``NUMBA_OPT=N`` (LLVM's
optimisation level; numba's default 3), and with ``--cheap-flags`` it replaces numba's
``TargetConfig.values``, ``__eq__`` and ``__hash__`` (called some 150,000 times in the call, by the
overloads' implementation caches keyed on the compile's flags) with forms that give the same answers
without a property call per option: how much of the compile that bookkeeping is. The orbit's
numbers are printed to the bit, to compare runs.

Measured on 0abc7a7d (2-core machine, load about 1, one child each, CPU s of the call):

| child | call | numba's typing | lowering (the lean pass and numba's) | LLVM optimisation | machine code |
| --- | ---: | ---: | ---: | ---: | ---: |
| default | 20.3 (under the probe's timers) | 3.2 | 7.8 | 2.1 | 2.6 |

``bench_first_call.py --rows circuit`` with ``NUMBA_OPT`` let through (the bench removes it) read
18.1 s (``NUMBA_OPT=3``), 17.5 s (1) and 19.4 s (0; warm 19.1 s against 1.6 s): LLVM's optimisation
is not what the first call waits for. The cheap flags, two pairs of fresh processes alternately:
17.61 and 17.57 s plain, 16.91 and 16.95 s with them (the same numbers to the bit): 0.65 s, 4 %.
Not taken into the library: it would change numba's class for every user of numba in the process.

Run: ``python benchmarks/probes/compile_passes.py [--opt N] [--cheap-flags] [--top K]``.
Library behaviour is not changed.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

_CHILD = r"""
import collections, sys, time
from numba.core import codegen
from numba.core import compiler_machinery as cm

own = collections.Counter()
stack = [0.0]


def timed(name, fn, *args):
    stack.append(0.0)
    t = time.process_time()
    try:
        return fn(*args)
    finally:
        dt = time.process_time() - t
        inner = stack.pop()
        own[name] += dt - inner
        stack[-1] += dt


run_pass = cm.PassManager._runPass
cm.PassManager._runPass = lambda self, i, pss, state: timed(pss.name(), run_pass, self, i, pss, state)
finalize = codegen.CPUCodeLibrary._finalize_final_module
codegen.CPUCodeLibrary._finalize_final_module = lambda self: timed("(LLVM: machine code)", finalize, self)
optimize = codegen.CPUCodeLibrary._optimize_final_module
codegen.CPUCodeLibrary._optimize_final_module = lambda self: timed("(LLVM: module optimisation)",
                                                                   optimize, self)
if sys.argv[1] == "1":
    from numba.core import targetconfig as tc

    def values(self):
        v = self._values
        return {k: v.get(k, o.default) for k, o in self.options.items()}

    def equal(self, other):
        if self is other:
            return True
        if isinstance(other, tc.TargetConfig):
            if type(self) is type(other) and self._values == other._values:
                return True
            return values(self) == values(other)
        return NotImplemented

    tc.TargetConfig.values = values
    tc.TargetConfig.__eq__ = equal
    tc.TargetConfig.__hash__ = lambda self: hash(tuple(sorted(self.options)))
from impactbar import physical as ph

cfg, _ = ph.read_config("circuit-drifter")
model = ph.build(ph.with_values(cfg, {"model.n_modes": 4}))
t = time.process_time()
orbit = model.orbit()
print(f"call {time.process_time() - t:.2f} s CPU; orbit {orbit.blow_frequency_Hz!r} Hz, "
      f"{orbit.impact_velocity_m_s!r} m/s")
for name, s in own.most_common(int(sys.argv[2])):
    print(f"{s:8.2f}  {name}")
"""


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--opt", type=int, choices=(0, 1, 2, 3), default=None, help="NUMBA_OPT in the child")
    ap.add_argument("--cheap-flags", action="store_true")
    ap.add_argument("--top", type=int, default=12)
    args = ap.parse_args(argv)
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), NUMBA_CACHE_DIR=tempfile.mkdtemp(),
               XDG_CACHE_HOME=tempfile.mkdtemp(), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    env.pop("NUMBA_OPT", None)
    env.pop("IMPACTBAR_TIERED", None)
    if args.opt is not None:
        env["NUMBA_OPT"] = str(args.opt)
    done = subprocess.run([sys.executable, "-c", _CHILD, "1" if args.cheap_flags else "0", str(args.top)],
                          env=env, capture_output=True, text=True)
    print(done.stdout, end="")
    if done.returncode:
        print(done.stderr, file=sys.stderr)
        raise SystemExit(done.returncode)


if __name__ == "__main__":
    main()
