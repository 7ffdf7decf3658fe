"""The package's Brent search (``impactbar._shared.roots.brentq``) against scipy's: the same points
evaluated, in the same order, and the same root to the bit (the charts' edges and the wave law's
phase roots come from it)."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq as scipy_brentq

from impactbar._shared.roots import brentq


def _recorded(f):
    xs = []

    def g(x):
        xs.append(float(x))
        return f(x)

    return g, xs


FUNCTIONS = [
    (lambda x: x**3 - 2.0 * x - 5.0, 2.0, 3.0),                       # Brent's own example
    (lambda x: math.cos(x) - x, 0.0, 1.0),
    (lambda x: math.expm1(x) - 1e-3, -1.0, 2.0),
    (lambda x: (x - 0.3) ** 3, 0.0, 0.7),                             # a flat root: not converged
    (lambda x: math.atan(1e6 * (x - 0.123456789)), -3.0, 5.0),        # a step: secant steps refused
    (lambda x: x - 1e-300, -1.0, 1.0),
    (lambda x: math.sin(10.0 * x) + 0.5, 0.3, 0.5),
]


@pytest.mark.parametrize("xtol, rtol", [(2e-12, 8.881784197001252e-16), (1e-14, 1e-15), (1e-11, 8.9e-16),
                                        (1e-3, 1e-10)])
@pytest.mark.parametrize("case", range(len(FUNCTIONS)))
def test_same_iterates_and_root_as_scipy(case, xtol, rtol):
    f, a, b = FUNCTIONS[case]
    g1, xs1 = _recorded(f)
    g2, xs2 = _recorded(f)
    try:
        r2 = scipy_brentq(g2, a, b, xtol=xtol, rtol=rtol)
    except RuntimeError:  # not converged in 100 iterations: the same iterates, the same refusal
        with pytest.raises(RuntimeError, match="converge"):
            brentq(g1, a, b, xtol=xtol, rtol=rtol)
        assert xs1 == xs2
        return
    r1 = brentq(g1, a, b, xtol=xtol, rtol=rtol)
    assert xs1 == xs2
    assert r1 == r2 and math.copysign(1.0, r1) == math.copysign(1.0, r2)


def test_random_cubics_the_same_as_scipy():
    rng = np.random.default_rng(7)
    for _ in range(200):
        c = rng.normal(size=4)
        a, b = -3.0, 3.0

        def f(x, c=c):
            return ((c[0] * x + c[1]) * x + c[2]) * x + c[3]

        if f(a) * f(b) >= 0.0:
            continue
        g1, xs1 = _recorded(f)
        g2, xs2 = _recorded(f)
        assert brentq(g1, a, b, xtol=1e-13, rtol=1e-15) == scipy_brentq(g2, a, b, xtol=1e-13, rtol=1e-15)
        assert xs1 == xs2


def test_a_root_at_an_end_and_the_errors():
    assert brentq(lambda x: x, 0.0, 1.0) == 0.0
    assert brentq(lambda x: x - 1.0, 0.0, 1.0) == 1.0
    with pytest.raises(ValueError, match="different signs"):
        brentq(lambda x: x + 2.0, 0.0, 1.0)
    with pytest.raises(ValueError, match="xtol"):
        brentq(lambda x: x, -1.0, 1.0, xtol=0.0)
    with pytest.raises(ValueError, match="rtol"):
        brentq(lambda x: x, -1.0, 1.0, rtol=1e-16)
    with pytest.raises(ValueError, match="NaN"):
        brentq(lambda x: math.nan if x > -1.0 else -1.0, -1.0, 1.0)
    with pytest.raises(RuntimeError, match="converge"):
        brentq(lambda x: math.cos(x) - x, 0.0, 1.0, maxiter=2)
