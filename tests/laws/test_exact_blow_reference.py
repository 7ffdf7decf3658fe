"""The exact blow (issue 39) against an independent solution of the same blow.

``tests/laws/_reference_blow.py`` shares no code with :mod:`impactbar.laws.rodrock.exact`: its waves
are piecewise Chebyshev interpolants carried by delay lines, the bit's equation is solved by
Duhamel's integral on graded Gauss-Legendre panels, its switches are roots of colleague matrices.
The two agree to 1e-14 on the issue's rods (efficiency, work on the rock, penetrations, rebound
velocity, the peak forces at every junction and at the bit and their times, the loading episodes);
the tests ask 1e-9. Also here: the faults this comparison exposed, each with the test that failed
before its fix."""

import math

import numpy as np
import pytest
from _reference_blow import reference_blow

from impactbar.laws.rodrock import _exactpieces as P
from impactbar.laws.rodrock.exact import _binomials, exact_blow

#: (piston times, piston impedances, rod times, rod impedances, k, k_u, bit mass): the exact
#: solver's units, the piston of impedance 1 and crossing time 1 unless stepped
CASES = {
    # the rods: alpha = 2 k T_p / Z_p (Lundberg's, the piston's round trip), gamma = k_u / k
    "uniform rod of the piston's length, alpha 2, gamma 5": ([1.0], [1.0], [1.0], [1.0], 1.0, 5.0, 0.0),
    "three segments, alpha 1, gamma 2": ([1.0], [1.0], [1.0, 0.5, 2.0], [1.0, 0.5, 1.0], 0.5, 1.0, 0.0),
    "incommensurate segments": ([1.0], [1.0], [math.sqrt(2), math.pi / 2], [0.8, 1.3], 0.7, 7.0, 0.0),
    "a bit of mass 0.3, lift-off": ([1.0], [1.0], [2.0, 1.0], [1.0, 0.6], 1.0, 5.0, 0.3),
    "stepped piston": ([0.6, 0.4], [0.7, 1.6], [1.3, 0.9], [1.1, 0.5], 0.8, 3.0, 0.0),
    "stepped piston, bit of mass 0.1": ([0.5, 0.5], [1.5, 0.8], [0.7, 1.9], [0.9, 1.4], 1.2, 12.0, 0.1),
    # a short soft rod under a stiff piston: three separations, two re-contacts, a second loading
    "short rod, second loading": ([0.8991334349281379], [1.4022475364350362], [0.363115818418278],
                                  [0.625437386070403], 1.2988179874099806, 2.413001974806762, 0.0),
    # eight separations, seven re-contacts, two loadings; one re-contact 0.066 after a separation
    # that a tensile step opened (the gap rising from 0 and bending back: first_negative's fault)
    "stepped piston, a quick re-contact": ([0.5841726079153196, 1.2615293582476763],
                                           [1.3732430540965517, 0.6411929633605988], [1.2528792685202423],
                                           [1.353912855909835], 0.3268085498957647, 23.838480715886703, 0.0),
}
SCALARS = ("efficiency", "work_on_rock", "max_penetration", "permanent_penetration", "advance",
           "rebound_velocity", "piston_energy")


def _compare(case, rtol=1e-9, peak_rtol=1e-9):
    Tp, Zp, Tr, Zr, k, k_u, m = case
    ex = exact_blow(Tp, Zp, Tr, Zr, k=k, k_u=k_u, bit_mass=m, impact_velocity=1.0)
    ref = reference_blow(Tp, Zp, Tr, Zr, k=k, k_u=k_u, bit_mass=m, impact_velocity=1.0,
                         t_end=ex.duration)
    assert ref.energy_error < 1e-12  # the reference's own account
    for name in SCALARS:
        assert getattr(ex, name) == pytest.approx(getattr(ref, name), rel=rtol, abs=1e-12), name
    values, times = ex.peak_forces()
    np.testing.assert_allclose(values, ref.peak_values, rtol=peak_rtol)
    np.testing.assert_allclose(times, ref.peak_times, rtol=0.0, atol=rtol * ex.duration)
    assert (ex.separations, ex.recontacts) == (ref.separations, ref.recontacts)
    np.testing.assert_allclose(ex.loadings, ref.loadings, rtol=rtol, atol=1e-12)
    return ex, ref


@pytest.mark.parametrize("name", list(CASES))
def test_the_exact_blow_is_the_independent_solution(name):
    ex, ref = _compare(CASES[name])
    assert ex.ended_by in ("separated", "lifted", "spent")


def test_a_stiff_unloading_on_a_long_soft_rod_is_the_independent_solution():
    """The issue's 4-long rod of impedance 0.4 (alpha 0.8, gamma 1e6): two loadings, a spike of
    width ``Z/k_u = 1e-6`` at each unloading. The reference resolves time on the blow's absolute
    clock, so a value on the spike is known to its slope times a few ulps of ``t`` (``16 eps t k_u/Z``:
    2e-9 at ``t = 10``): the shank's peak, the spike's top, agrees to 8e-10, the rest to 1e-13."""
    ex, ref = _compare(([1.0], [1.0], [4.0], [0.4], 0.4, 4e5, 0.0), peak_rtol=2e-9)
    assert ex.loadings.shape[0] == 2 and ref.recontacts == 1


def _block(coefs):
    """``sum coefs[d] tau^d`` as an exact piece (exponents 0 and -1 in the table)."""
    lam = np.array([0j, -1.0 + 0j])
    B = np.zeros((2, P.DC), complex)
    N = np.zeros(2, np.int64)
    B[0, :len(coefs)] = coefs
    N[0] = len(coefs)
    D = tuple(x for _ in range(3) for x in (np.zeros((2, P.DC), complex), np.zeros(2, np.int64)))
    return B, N, lam, D


@pytest.mark.parametrize("coefs", [
    [0.0, 1.0, -1.0],  # no third derivative: the bound took the piece as rising for ever
    [0.0, 1.0, -2.0, 0.01],  # the cubic bound with the curvature taken as 0
    [0.0, 1.0, 0.5, -1.0],  # a positive curvature, bent back by the cubic (found before too)
])
def test_a_piece_rising_from_zero_and_bending_back_crosses_it(coefs):
    """``first_negative`` bounded a piece that starts at zero with a positive slope as if its
    curvature were 0 when it was clearly negative: the interval it excluded reached past the zero
    (a re-contact, a landing missed: -1 returned for the first two)."""
    B, N, lam, D = _block(coefs)
    t = P.first_negative(B, N, lam, _binomials(), 2.0, np.zeros((256, 4)), D, 0.0)
    roots = np.polynomial.polynomial.polyroots(coefs[1:])
    exact = min(x.real for x in roots if abs(x.imag) < 1e-12 and x.real > 0.0)
    assert t == pytest.approx(exact, rel=1e-12)
