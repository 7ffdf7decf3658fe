"""The oil circuit's flight helpers compile once whatever constants their callers pass: a constant
argument (``keep_row``'s first row 0, ``state_at``'s first step 0) typed as a literal would be a
machine code of its own, a compile the designer's first ``orbit()`` waits for (counted, not timed, in
a fresh process with an empty numba cache)."""

import os
import subprocess
import sys

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
