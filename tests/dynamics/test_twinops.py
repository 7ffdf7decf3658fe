"""The operations a kernel's twin does as its machine code does (``impactbar._shared.twinops``): a
complex quotient and a float's integer power rounded as numba's compiled ``a / b`` and ``x ** n``
(which numpy's scalars do not: the comparison with them shows the check can fail), and the
checkpoint at which a twin past its budget hands its call to the machine code."""

import math

import numba
import numpy as np
import pytest

from impactbar._shared import twinops
from impactbar._shared.twinops import checkpoint, ipow, python_form, quot
from impactbar.dynamics import _tiers


@numba.njit(cache=False)
def _quotients(a, b, n, q):
    """numba's own ``/`` and :func:`quot` on complex by complex, complex by int, int by complex and
    float by float: the columns of ``q``."""
    for i in range(a.size):
        q[i, 0] = a[i] / b[i]
        q[i, 1] = quot(a[i], b[i])
        q[i, 2] = a[i] / n[i]
        q[i, 3] = quot(a[i], n[i])
        q[i, 4] = n[i] / b[i]
        q[i, 5] = quot(n[i], b[i])
        q[i, 6] = a[i].real / b[i].imag
        q[i, 7] = quot(a[i].real, b[i].imag)


@numba.njit(cache=False)
def _powers(x, n, p):
    for i in range(x.size):
        p[i, 0] = x[i] ** n[i]
        p[i, 1] = ipow(x[i], n[i])


def _complex(rng, size):
    return (rng.standard_normal(size) * 10.0 ** rng.uniform(-8, 8, size)
            + 1j * rng.standard_normal(size) * 10.0 ** rng.uniform(-8, 8, size))


def test_quot_is_numbas_division_compiled_and_interpreted():
    """Compiled, ``quot`` is numba's ``/`` to the bit; its Python form on numpy's scalars gives the
    same bits, where numpy's own ``/`` differs in a large share of the complex quotients."""
    rng = np.random.default_rng(11)
    a, b = _complex(rng, 4000), _complex(rng, 4000)
    n = rng.integers(1, 60, 4000) * rng.choice([-1, 1], 4000)
    q = np.empty((a.size, 8), dtype=complex)
    _quotients(a, b, n, q)
    assert q[:, 0].tobytes() == q[:, 1].tobytes() and q[:, 2].tobytes() == q[:, 3].tobytes()
    assert q[:, 4].tobytes() == q[:, 5].tobytes() and q[:, 6].tobytes() == q[:, 7].tobytes()
    py = python_form(quot)
    here = np.array([[py(x, y), py(x, k), py(k, y), py(x.real, y.imag)]
                     for x, y, k in zip(a, b, n, strict=True)])
    assert here.tobytes() == q[:, [1, 3, 5, 7]].tobytes()
    numpys = np.array([[x / y, x / k] for x, y, k in zip(a, b, n, strict=True)])
    assert np.mean(numpys != q[:, [0, 2]]) > 0.1  # (numpy's reciprocal: some 40 % an ulp apart)
    with pytest.raises(ZeroDivisionError):
        py(np.complex128(1.0), 0)


def test_ipow_is_numbas_power_compiled_and_interpreted():
    """Compiled, ``ipow`` is numba's ``x ** n`` (repeated squaring) to the bit; its Python form gives
    the same bits, where numpy's scalar power (the C library's ``pow``) differs in some."""
    rng = np.random.default_rng(12)
    x = 10.0 ** rng.uniform(-3, 3, 4000)
    n = rng.integers(-40, 41, 4000)
    p = np.empty((x.size, 2))
    _powers(x, n, p)
    assert p[:, 0].tobytes() == p[:, 1].tobytes()
    py = python_form(ipow)
    assert np.array([py(a, k) for a, k in zip(x, n, strict=True)]).tobytes() == p[:, 0].tobytes()
    assert np.any(np.array([a ** k for a, k in zip(x, n, strict=True)]) != p[:, 0])
    assert py(2.0, 0) == 1.0 and py(-2.0, 3) == -8.0 and py(0.5, -2) == 4.0


@numba.njit(cache=False)
def _spin(out, n):
    for _ in range(n):
        checkpoint()
        out[0] += 1.0
    return out[0]


def test_a_twin_past_its_budget_hands_the_call_to_the_machine_code(monkeypatch):
    """A kernel's loop calls ``checkpoint``: compiled nothing; in a twin that has spent its budget
    it stops the twin, whose call the machine code then runs from the arguments as they came."""
    monkeypatch.setattr(_tiers, "_FIRST", {})
    out = np.zeros(1)
    first = _tiers.interpreted_first(_spin, budget=0.02)
    assert isinstance(first, _tiers._Twin)
    assert first(out, 2_000_000) == 2_000_000.0 and out[0] == 2_000_000.0  # (not 2e6 + what the twin added)
    assert _spin.signatures  # compiled for the call
    assert _tiers._FIRST[_spin] >= 0.02
    assert _tiers.interpreted_first(_spin, budget=0.02) is _spin
    assert twinops.deadline(math.inf) == math.inf  # (put back after the call)
    with pytest.raises(twinops.OverBudget):
        old = twinops.deadline(0.0)
        try:
            python_form(checkpoint)()
        finally:
            twinops.deadline(old)
    with pytest.raises(ValueError, match="at must be"):
        twinops.deadline(math.nan)
