"""Newton's method gives up where its steps stall (circle instead of shrinking), and a converging one
is untouched: the stall test of :mod:`impactbar.drives.orbitproblem`."""

from __future__ import annotations

import numpy as np
import pytest

from impactbar.drives.orbitproblem import STALL_STEPS, newton


def _counted(residual):
    calls = []

    def wrapped(X):
        calls.append(X.copy())
        return residual(X)

    return wrapped, calls


def test_newton_gives_up_on_a_two_cycle_and_not_on_a_run_that_converges():
    def cubic(X):
        return X ** 3 - 2 * X + 2, np.diag(3 * X ** 2 - 2)

    # from 0, Newton's classic two-cycle 0 -> 1 -> 0 (f(0) = 2, f'(0) = -2; f(1) = 1, f'(1) = 1),
    # every step of size 1: given up after the stall steps (before, all max_iter steps were taken)
    residual, calls = _counted(cubic)
    with pytest.raises(ValueError, match="Newton stalled"):
        newton(residual, np.array([0.0]), np.zeros(0, int), 1e-12, 50)
    assert [float(x[0]) for x in calls[:4]] == [0.0, 1.0, 0.0, 1.0]
    assert len(calls) == STALL_STEPS + 1  # the first step, then STALL_STEPS without progress
    # from -3 the steps converge quadratically to the real root (numpy's roots of the cubic),
    # the very iterates of Newton's formula, to the bit
    residual, calls = _counted(cubic)
    x = newton(residual, np.array([-3.0]), np.zeros(0, int), 1e-14, 50)
    assert x[0] == pytest.approx(min(np.roots([1, 0, -2, 2]).real), rel=1e-15)
    ref = -3.0
    for X in calls:
        assert float(X[0]) == ref
        ref = ref - (ref ** 3 - 2 * ref + 2) / (3 * ref ** 2 - 2)
