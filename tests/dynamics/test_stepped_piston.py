"""The stepped piston's exact free-free modes (theory §12) against a finite-element solution of the
same bar, their orthogonality, the uniform bar as one segment, and the arguments."""

import math

import numpy as np
import pytest
from scipy.linalg import eigh_tridiagonal

from impactbar.dynamics.stepped import SteppedPiston


def fe_wavenumbers(piston, elements, count):
    """Wavenumbers of the first ``count`` flexible modes by linear finite elements (nodes on the
    steps, lumped masses), Richardson-extrapolated over ``elements``, 2x, 4x (error O(h^2) per level,
    even powers only): an independent solution of the same eigenproblem."""
    levels = []
    for n in (elements, 2 * elements, 4 * elements):
        per = np.rint(piston.lengths * n).astype(int)
        assert np.allclose(per / n, piston.lengths, rtol=0, atol=1e-12), "mesh must fit the steps"
        h = np.repeat(piston.lengths / per, per)
        z = np.repeat(piston.impedances, per)
        mu = z  # one material: the mass per length goes with the impedance, the wave speed is 1
        stiff = z / h
        diag_k = np.zeros(h.size + 1)
        diag_k[:-1] += stiff
        diag_k[1:] += stiff
        mass = np.zeros(h.size + 1)
        mass[:-1] += mu * h / 2
        mass[1:] += mu * h / 2
        w = 1.0 / np.sqrt(mass)
        lam = eigh_tridiagonal(diag_k * w * w, -stiff * w[:-1] * w[1:], eigvals_only=True,
                               select="i", select_range=(1, count))
        levels.append(np.sqrt(lam))
    k1, k2, k4 = levels
    r1, r2 = (4 * k2 - k1) / 3, (4 * k4 - k2) / 3
    return (16 * r2 - r1) / 15


@pytest.mark.parametrize("lengths, impedances", [([0.3, 0.7], [2.0, 1.0]),
                                                 ([0.25, 0.25, 0.5], [1.0, 0.4, 1.6]),
                                                 ([0.125, 0.5, 0.375], [3.0, 1.0, 2.0])])
def test_frequencies_agree_with_finite_elements(lengths, impedances):
    p = SteppedPiston(lengths, impedances)
    exact = p.modes(6).wavenumbers[1:]
    fe = fe_wavenumbers(p, 800, 6)
    np.testing.assert_allclose(exact, fe, rtol=1e-8)
    assert np.max(np.abs(p.end_force(exact))) < 1e-12 * exact.max()


def test_one_segment_is_the_uniform_bar_to_rounding():
    m = SteppedPiston([2.5], [7.0]).modes(64)
    n = np.arange(65)
    np.testing.assert_allclose(m.wavenumbers, n * math.pi, rtol=4e-16, atol=0)
    x = np.linspace(0.0, 1.0, 101)
    ref = np.sqrt(2.0) * np.cos(np.pi * np.outer(x, n))
    ref[:, 0] = 1.0
    phi = m.shapes(x)
    np.testing.assert_allclose(np.abs(phi), np.abs(ref), atol=1e-13)


def test_modes_are_mass_orthonormal():
    p = SteppedPiston([0.2, 0.3, 0.5], [3.0, 1.0, 2.0])
    m = p.modes(64)
    # Gauss-Legendre per segment with more nodes than the fastest mode's wavelength asks: exact to
    # rounding for these trigonometric products
    gram = np.zeros((65, 65))
    xg, wg = np.polynomial.legendre.leggauss(200)
    for x0, le, mu in zip(p.starts, p.lengths, p.mass_per_length, strict=True):
        x = x0 + le * (xg + 1) / 2
        phi = m.shapes(np.clip(x, 0.0, 1.0))
        gram += mu * (phi * (wg * le / 2)[:, None]).T @ phi
    np.testing.assert_allclose(gram, np.eye(65), atol=1e-12)


def test_every_mode_has_as_many_nodes_as_its_index():
    p = SteppedPiston([0.05, 0.9, 0.05], [1.0, 50.0, 1.0])  # near-decoupled ends: roots close together
    m = p.modes(40)
    x = np.linspace(0.0, 1.0, 20001)
    nodes = np.count_nonzero(np.diff(np.signbit(m.shapes(x)), axis=0), axis=0)
    np.testing.assert_array_equal(nodes, np.arange(41))
    assert np.all(np.diff(m.wavenumbers) > 0)


def test_only_ratios_count():
    a = SteppedPiston([0.3, 0.7], [2.0, 1.0]).modes(8).wavenumbers
    b = SteppedPiston([3e-3, 7e-3], [2e9, 1e9]).modes(8).wavenumbers
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("kw, match", [
    ({"lengths": [], "impedances": []}, "non-empty"),
    ({"lengths": [0.5, -0.5], "impedances": [1, 1]}, "lengths must be finite and > 0"),
    ({"lengths": [1.0], "impedances": [float("nan")]}, "impedances must be finite"),
    ({"lengths": [1.0, 1.0], "impedances": [1.0]}, "same length"),
    ({"lengths": [1.0, 1.0], "impedances": [1.0, 1e7]}, "within a factor"),
    ({"lengths": "ab", "impedances": [1.0]}, "lengths must be"),
])
def test_bad_pistons_are_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        SteppedPiston(**kw)


@pytest.mark.parametrize("n", [-1, 4097, 2.0, True, "3"])
def test_bad_mode_counts_are_refused(n):
    with pytest.raises(ValueError, match="n_modes"):
        SteppedPiston([1.0], [1.0]).modes(n)
