"""The short run's untyped entry point (``_shortrun.entry_point``): it must be the overload compiled
for the Python call's argument types, not one a compiled caller made. The valve's loop calls
``run_free`` with ``max_imp`` the literal 1; where that overload was the only one when a short run
first asked (a cold numba cache, a driven run first in the process), every later short run of
the process stopped after one impact (``simulate(..., max_impacts=256)`` gave 1 impact)."""

import numba
import numpy as np

from impactbar.simulation._shortrun import _ENTRY_POINTS, entry_point


@numba.njit
def _count(x, k):
    return x.size + k


@numba.njit
def _caller(x):
    return _count(x, 1)  # (numba may compile _count for the literal 1)


def test_entry_point_is_the_overload_of_the_python_call():
    x = np.zeros(3)
    assert _caller(x) == 4
    _ENTRY_POINTS.pop(_count, None)
    try:
        first = entry_point(_count, (x, 256))
        assert first(x, 256) == 259  # the dispatcher, or an entry point for (array, int64)
        again = entry_point(_count, (x, 256))  # compiled for the call's types by now
        assert again is not _count and again(x, 256) == 259 and again(x, 7) == 10
    finally:
        _ENTRY_POINTS.pop(_count, None)
