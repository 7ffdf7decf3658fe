"""The circuit's variational equations over a blow (:mod:`impactbar.drives.circuit.endtangent`): the
Radau IIA steps of ``x' = J x + f_a da`` against the closed form of a constant stiff system, their
order, and an impulse of ``da`` as a jump of ``x``."""

import numpy as np
from scipy.linalg import expm

from impactbar.drives.circuit.endtangent import RADAU_A, RADAU_C, radau_linear

#: a stiff constant system (eigenvalues -1e4 and about -0.5 +- 2i) and its forcing's direction
J0 = np.array([[-1e4, 3.0, 0.0], [0.0, -0.5, 2.0], [1.0, -2.0, -0.5]])
FA = np.array([1.0, -0.5, 0.25])


def _closed(x0, t, da=1.0):
    """``x(t)`` of ``x' = J0 x + FA da`` (``da`` constant) from ``x0`` (rows: directions)."""
    E = expm(J0 * t)
    part = np.linalg.solve(J0, (E - np.eye(3)) @ FA) * da
    return x0 @ E.T + part[None, :]


def _run(steps, T=2.0, kick_at=None, kick=0.0):
    grid = np.linspace(0.0, T, steps + 1)
    h = np.diff(grid)
    S = h.size
    J = np.broadcast_to(J0, (S, 4, 3, 3)).copy()
    fa = np.broadcast_to(FA, (S, 4, 3)).copy()
    da = np.ones((S, 4, 2))
    da[:, :, 1] = 0.0
    x0 = np.array([[1.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    kicks = np.zeros((S + 1, 2))
    if kick_at is not None:
        kicks[kick_at, 1] = kick
    return grid, radau_linear(h, J, fa, da, x0, kicks, RADAU_A), x0


def test_radau_is_the_collocation_of_order_five():
    """Its nodes and matrix (row sums the nodes, the last row the weights: stiffly accurate) and its
    error against the closed form falling by about 2^5 a halving of the steps."""
    assert np.allclose(RADAU_A.sum(axis=1), RADAU_C, rtol=0.0, atol=1e-15)
    powers = RADAU_C[None, :] ** np.arange(5)[:, None]
    assert np.allclose(powers @ RADAU_A[2], 1.0 / np.arange(1, 6), atol=1e-15)
    errors = []
    for steps in (20, 40, 80):
        grid, (X, R), x0 = _run(steps)
        exact = np.vstack((_closed(x0[:1], 2.0), _closed(x0[1:], 2.0, 0.0)))
        errors.append(np.max(np.abs(X[-1, 1] - exact)))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all(ratios > 20.0), (errors, ratios)  # measured 32.3 and 32.2
    assert errors[-1] < 1e-8


def test_rates_and_an_impulse():
    """The rates are the field at the values; an impulse of ``da`` at a time jumps ``x`` by ``f_a``
    times its weight there (the second direction: no forcing, so the closed form from the jump)."""
    steps, at, m = 80, 30, 0.7
    grid, (X, R), x0 = _run(steps, kick_at=at, kick=m)
    assert np.allclose(R[:, 1, 0], X[:, 1, 0] @ J0.T + FA, rtol=1e-14, atol=1e-10)
    assert np.allclose(X[at, 1, 1] - X[at, 0, 1], FA * m, rtol=0.0, atol=1e-15)
    exact = _closed(_closed(x0[1:], grid[at], 0.0) + FA * m, 2.0 - grid[at], 0.0)
    assert np.max(np.abs(X[-1, 1, 1] - exact[0])) < 1e-8
