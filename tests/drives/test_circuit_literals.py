"""The oil circuit's flight helpers compile once whatever constants their callers pass: a constant
argument (``keep_row``'s first row 0, ``state_at``'s first step 0, the end flight's one mode) typed as
a literal would be a machine code of its own, a compile the designer's first ``orbit()`` waits for
(counted, not timed, in a fresh process with an empty numba cache)."""

import os
import subprocess
import sys

import pytest
from circuit_parts_reference import ROCK_EXAMPLE

_CALLS = """
import numba
import numpy as np
from impactbar.drives.circuit import _dop853 as DP, _magnus as MG


@numba.njit
def rows(T, Y, t, y, k):
    T, Y = DP.keep_row(T, Y, 0, t, y)
    T, Y = DP.keep_row(T, Y, 1, t, y)
    return DP.keep_row(T, Y, k, t, y)


@numba.njit
def states(t, y, f, out, k):
    j = MG.state_at(t, y, f, 0.5, 0, out)
    return j + MG.state_at(t, y, f, 1.5, k, out)


T, Y = rows(np.zeros(2), np.zeros((2, 3)), 1.0, np.arange(3.0), 2)
ts = np.array([0.0, 1.0, 2.0])
out = np.empty(2)
k = states(ts, np.ones((3, 2)), np.zeros((3, 2)), out, 1)
print(T.size, T[2], Y[2, 2], k, out[0])
print(len(DP.keep_row.signatures), len(MG.state_at.signatures))
"""


def test_keep_row_and_state_at_compile_once_for_constant_and_variable_arguments(tmp_path):
    """``keep_row`` called with the rows 0, 1 and a variable, ``state_at`` from the step 0 and a
    variable one: one signature each (a literal ``0`` or ``1`` would add its own), the same
    numbers (row 2 written after the block doubled; the interpolant of a constant state)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), NUMBA_CACHE_DIR=str(tmp_path))
    env.pop("NUMBA_DISABLE_JIT", None)
    done = subprocess.run([sys.executable, "-c", _CALLS], env=env, capture_output=True, text=True,
                          check=True)
    values, counts = done.stdout.strip().splitlines()[-2:]
    assert values.split() == ["4", "1.0", "2.0", "1", "1.0"]
    assert counts.split() == ["1", "1"]


_FLIGHT_HELPERS = """
import numba
import numpy as np
from impactbar.drives.circuit import _bar as BAR, _cvode as CV, _endcvode as EC


@numba.njit
def ends(y, par, m):
    w1, wd1 = BAR.end_motion(y, par, 1)
    w, wd = BAR.end_motion(y, par, m)
    return w1, wd1, w, wd


@numba.njit
def grown(T, Y, F, k, need):
    T1, _, _ = EC._grow(T, Y, F, 0, need)
    T2, Y2, _ = EC._grow(T, Y, F, k, need)
    return T1.size, T2.size, T2[1], Y2[1, 2]


@numba.njit
def flights(go, mem, yvec, y0, directions, par, keep, max_steps):
    if go:  # (typed and compiled, not flown: no CVODE memory here)
        a = CV.fly(mem, yvec, 0.0, y0, 1.0, 1e-6, 1e-8, directions, par, 14, max_steps)[0]
        return a + CV.fly(mem, yvec, 0.0, y0, 1.0, 1e-6, 1e-8, directions, par, keep, max_steps)[0]
    return -1


print(*ends(np.arange(1.0, 5.0), np.arange(20.0), 2))
print(*grown(np.arange(2.0), np.arange(6.0).reshape(2, 3), np.zeros((2, 3)), 2, 3))
print(flights(False, 0, 0, np.zeros(3), np.zeros(1, np.int32), np.zeros(3), 3, 10))
print(len(BAR.end_motion.signatures), len(EC._grow.signatures), len(CV.fly.signatures))
"""


def test_end_motion_grow_and_fly_compile_once_for_constant_and_variable_arguments(tmp_path):
    """The end flight's helpers called with the constants its generated code passes (``end_motion``'s
    one mode, ``_grow``'s first row 0, ``fly``'s kept components, a module's ``NE``) and with
    variables: one signature each, the same numbers as by hand (the driven end's weights from
    ``par[HEAD + 2 M:]``: ``-10 (1, 2)`` for one mode, ``-(12 + 26, 36 + 52)`` for two; the arrays
    of 2 rows doubled to 4 for 3, the second call's first 2 rows kept)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), NUMBA_CACHE_DIR=str(tmp_path))
    env.pop("NUMBA_DISABLE_JIT", None)
    done = subprocess.run([sys.executable, "-c", _FLIGHT_HELPERS], env=env, capture_output=True, text=True,
                          check=True)
    motion, grow, flown, counts = done.stdout.strip().splitlines()[-4:]
    assert motion.split() == ["-10.0", "-20.0", "-38.0", "-88.0"]
    assert grow.split() == ["4", "4", "1.0", "5.0"]
    assert flown == "-1"
    assert counts.split() == ["1", "1", "1"]


_ROCK_ORBIT = """
import gc
import sys
from numba.core.dispatcher import Dispatcher
from impactbar import physical as ph

cfg, _ = ph.read_config(sys.argv[1])
ph.build(cfg).orbit()
for obj in gc.get_objects():
    if isinstance(obj, Dispatcher) and obj.py_func.__module__.startswith("impactbar"):
        print(obj.py_func.__module__, obj.py_func.__name__, len(obj.signatures))
"""


@pytest.mark.slow  # about 25 s of CPU: the circuit on rock's first orbit into an empty cache
def test_the_rock_orbits_kernels_compile_once_each(tmp_path):
    """The circuit on rod and rock's ``orbit()`` (``examples/circuit_drifter_rock.toml``) in a new process
    with an empty numba cache: every kernel of the package it compiles takes one signature, among
    them those its end flight calls with constants (the generated network module's ``base``,
    ``jac_base`` and ``events`` for one mode, ``_cvode.fly``, ``_endcvode._grow``,
    ``_bar.end_motion``), which its circuit's flights call with variables."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), NUMBA_CACHE_DIR=str(tmp_path))
    env.pop("NUMBA_DISABLE_JIT", None)
    done = subprocess.run([sys.executable, "-c", _ROCK_ORBIT, str(ROCK_EXAMPLE)], env=env,
                          capture_output=True, text=True, check=True)
    counts = {}
    for line in done.stdout.strip().splitlines():
        module, name, n = line.split()
        if module.startswith("impactbar_netgen_"):
            module = "netgen"
        counts[f"{module}.{name}"] = max(counts.get(f"{module}.{name}", 0), int(n))
    for kernel in ("netgen.base", "netgen.jac_base", "netgen.events", "impactbar.drives.circuit._cvode.fly",
                   "impactbar.drives.circuit._endcvode._grow", "impactbar.drives.circuit._bar.end_motion"):
        assert counts.get(kernel) == 1, (kernel, counts.get(kernel))
    assert {k: n for k, n in counts.items() if n > 1} == {}
