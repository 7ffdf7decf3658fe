"""The CLI's one-line note while numba compiles (impactbar.cli._compiling)."""

import io

import numba
import pytest

from impactbar.cli._compiling import compile_note


def _fresh_kernel():
    @numba.njit(cache=False)
    def f(x):
        s = 0.0
        for i in range(x.size):
            s += x[i] * x[i]
        return s

    return f


def test_a_long_compile_prints_one_line_once():
    import numpy as np

    out = io.StringIO()
    with compile_note("impactbar test", after=1e-4, stream=out):
        _fresh_kernel()(np.ones(3))  # a compile of far more than 0.1 ms
        _fresh_kernel()(np.ones(3))  # another: no second line
    lines = out.getvalue().splitlines()
    assert len(lines) == 1 and lines[0].startswith("impactbar test: compiling kernels")


def test_no_compile_or_a_short_one_prints_nothing():
    import numpy as np

    f = _fresh_kernel()
    f(np.ones(3))  # compiled before the block
    out = io.StringIO()
    with compile_note(after=60.0, stream=out):
        f(np.ones(4))  # no compile
        _fresh_kernel()(np.ones(3))  # a compile far shorter than a minute
    assert out.getvalue() == ""
    # and the listener is gone after the block: a compile there prints nothing either
    _fresh_kernel()(np.ones(3))
    assert out.getvalue() == ""


def test_after_must_be_positive():
    with pytest.raises(ValueError, match="after"), compile_note(after=0.0):
        pass
