"""The exact blow's break points and its pool: arrivals equal but for rounding are one
break point, and a blow whose pieces outgrow their memory bound says what it measured.

A wave that reaches a junction along two paths whose travel times were summed in different orders
arrives at two times an ulp or two apart. Each such pair was two break points with a sliver piece
between them, whose value mixes the old wave on one input with the new on the other (a force that
never acts); the slivers multiplied downstream, and one made a spurious separation of the piston and
the shank. Checked against the independent solution of ``tests/laws/_reference_blow.py``."""

import math

import numba
import numpy as np
import pytest
from _reference_blow import reference_blow

from impactbar.laws.rodrock import _exactpieces as P
from impactbar.laws.rodrock.exact import PoolOverflow, exact_blow


@numba.njit
def _emit(c, a, B, N, valid, flag, ref, pool, S, NS, tol, Lb):
    """``emit``, called from a kernel (it has no Python wrapper of its own)."""
    return P.emit(c, a, B, N, valid, flag, ref, pool, S, NS, tol, Lb)

#: arrivals closer than this (relative) are one break point (_exactpieces.SNAP)
SNAP = 64 * np.finfo(float).eps


def _slivers(ex, junctions):
    """The break points of the junctions' force histories closer than ``SNAP`` to the one before."""
    out = []
    for j in junctions:
        b = ex.junction_breaks(j)
        out.extend(b[1:][np.diff(b) <= SNAP * b[1:]])
    return np.array(out)


def test_a_spurious_separation_at_a_sliver_is_gone():
    """A uniform piston on a uniform rod of incommensurate travel time (0.831 and 0.260), a bit of
    mass 0.19 bouncing on the rock: the piston leaves the shank 7 times and strikes it 6 times
    (the reference); the exact blow counted 8 and 7, one separation and re-contact at a sliver of
    the shank's force (five slivers there), its numbers otherwise the reference's to 1e-15."""
    args = dict(k=0.406723401440983, k_u=2.772040388841514, bit_mass=0.18750482694834514,
                impact_velocity=1.0)
    chain = ([0.83095443583531], [1.5830668263354208], [0.25951139443571763], [0.9941853944132228])
    ex = exact_blow(*chain, **args)
    assert ex.ended_by == "separated"
    ref = reference_blow(*chain, t_end=ex.duration, **args)
    assert (ex.separations, ex.recontacts) == (ref.separations, ref.recontacts) == (7, 6)
    for name in ("efficiency", "rebound_velocity", "max_penetration", "advance", "piston_energy"):
        assert getattr(ex, name) == pytest.approx(getattr(ref, name), rel=1e-9), name
    values, _ = ex.peak_forces()
    np.testing.assert_allclose(values, ref.peak_values, rtol=1e-9)
    assert _slivers(ex, [ex.contact_junction]).size == 0


def test_a_stepped_pistons_arrivals_along_paths_of_equal_length_are_one():
    """A two-segment piston on a two-segment rod (the reference tests' "stepped piston"): 776 of the
    1147 break points at its three junctions were slivers and the blow stored 5808 pieces; now only
    a window's end can still part two arrivals (the one before it is processed in its window, the
    one after it at the next window's start: two left, at multiples of the shortest travel time),
    and it stores 1948 pieces, its numbers the reference's to 1.4e-14 as before (1.1e-14)."""
    Tp, Zp, Tr, Zr = [0.6, 0.4], [0.7, 1.6], [1.3, 0.9], [1.1, 0.5]
    ex = exact_blow(Tp, Zp, Tr, Zr, k=0.8, k_u=3.0, impact_velocity=1.0)
    left = _slivers(ex, [1, 2, 3])
    h = min(Tp + Tr)
    assert left.size <= 2
    np.testing.assert_allclose(left / h, np.round(left / h), rtol=0.0, atol=1e-9)
    assert ex.pieces < 2500


def test_an_overflow_says_how_many_pieces_and_terms():
    """A bit of mass 0.3 (not a light one) whose pieces outgrow a pool of 512 kB: the message said
    that a light bit's fast branches make long series; it now gives the pieces and their terms by
    then, and both causes."""
    with pytest.raises(PoolOverflow, match=r"by t = [0-9.]+: \d+ pieces of [0-9.]+ terms on average.*"
                                           r"incommensurate segments.*method='lattice'") as err:
        exact_blow([1.0], [1.0], [1.0, 0.5, 2.0], [1.0, 0.5, 1.0], k=0.7, k_u=7.0, bit_mass=0.3,
                   impact_velocity=1.0, max_pool_bytes=2 ** 19)
    assert "light bit" not in str(err.value)
    assert math.isfinite(float(str(err.value).split("by t = ")[1].split(":")[0]))


def test_a_jump_under_a_large_cubic_is_a_new_piece():
    """A piece emitted where the open one (a drive's cubic over a step of 1e-6 of a travel time: its
    cubic coefficient 4.6e20, its value 0.4) has its value 0.396 lower is a new piece; the open piece
    continued is none. (The continuation test weighed every coefficient against the largest: the jump
    passed for rounding, and the coupled exact blow on a rod of whole piston lengths was 1.7e-6 off.)"""
    from impactbar.laws.rodrock import _records as S
    from impactbar.laws.rodrock.exact import _binomials

    lam = np.zeros(1, dtype=complex)
    PF, PI = np.zeros((8, 5)), np.zeros((8, 4), dtype=np.int64)
    TK, TC = np.zeros(64, dtype=np.int64), np.zeros(64, dtype=complex)
    CNT, CHI = np.zeros(S.CNT_SIZE, dtype=np.int64), np.full((1, 2), -1, dtype=np.int64)
    pool = (PF, PI, TK, TC, CNT, CHI, lam, _binomials())
    cubic = np.array([0.4005844830041129, 2.310113533041259, -448309225.5409106, 4.63976562664008e20])

    def emit(a, coefs):
        B, N = np.zeros((1, P.DC), dtype=complex), np.array([4])
        B[0, :4] = coefs
        Sc, NS = np.zeros((1, P.DC), dtype=complex), np.zeros(1, dtype=np.int64)
        assert _emit(0, a, B, N, math.inf, 0, 0.0, pool, Sc, NS, 1e-19, 0.04)
        return int(CNT[S.CNT_PIECES])

    t0 = 0.004094745475215822
    delta = (t0 + 5e-18) - t0
    assert emit(t0, cubic) == 1
    shifted = np.array([sum(cubic[d] * math.comb(d, k) * delta ** (d - k) for d in range(k, 4))
                        for k in range(4)])
    assert emit(t0 + delta, shifted) == 1  # (the open piece continued: none)
    jump = shifted - np.array([0.3956, 0.0, 0.0, 0.0])
    assert emit(t0 + delta, jump) == 2


#: a three-segment piston (the piston design's optimum at alpha = 3, impedances rounded) on a rod 20
#: times as long, and a uniform piston on a two-segment rod; massless bits
_SPIKED = {
    "stepped piston": (([15 / 48, 16 / 48, 17 / 48], [0.0137, 1.85, 1.07], [20.0], [1.0]), 1.5, 44.0),
    "two-segment rod": (([1.0], [1.0], [0.3, 0.9], [0.5, 1.0]), 3.0, 12.4),
}


@pytest.mark.parametrize("case", sorted(_SPIKED))
def test_a_stiff_unloadings_spike_is_read_from_its_own_start(case):
    """The rock unloads where the incident wave steps down, so the bit reflects a spike of width
    ``Z/k_u`` whose height is set by the step, not by ``k_u``: the peak forces at every junction are
    the same for ``gamma = 1e12`` as for ``gamma = 1e6`` (to ``1e-6``, the spike's width), where the
    independent reference resolves it. Where the spike reached a junction within rounding (1e-13)
    after another arrival, snapped onto it, its term was read back from there, scaled by
    ``e^{k_u delta/Z}``: the stepped piston's shank force peaked 17 % high (0.0020979 for 0.0017898
    in the design's units), the rod's junction 0.16 % high. The peak is the top of the spike, the
    shank's force at that time (a piece's value at its start is its right limit)."""
    chain, k, t_max = _SPIKED[case]
    stiff = exact_blow(*chain, k=k, k_u=1e12 * k, impact_velocity=1.0, t_max=t_max, record=True)
    soft = exact_blow(*chain, k=k, k_u=1e6 * k, impact_velocity=1.0, t_max=t_max, record=True)
    values, times = stiff.peak_forces()
    np.testing.assert_allclose(values, soft.peak_forces()[0], rtol=1e-6)
    np.testing.assert_allclose(times, soft.peak_forces()[1], rtol=1e-12)
    for j in range(1, values.size):
        assert stiff.junction_force(j, times[j - 1]) == pytest.approx(values[j - 1], rel=1e-14)
    if case == "two-segment rod":  # (the stepped piston's long rod takes the reference minutes)
        ref = reference_blow(*chain, k=k, k_u=1e6 * k, impact_velocity=1.0, t_end=soft.duration)
        # (its clock: eps t k_u/Z)
        np.testing.assert_allclose(soft.peak_forces()[0], ref.peak_values, rtol=1e-8)
        np.testing.assert_allclose(values, ref.peak_values, rtol=1e-6)


#: a two-segment piston on a uniform rod, and a uniform piston on a three-segment rod; massless bits
_STIFF = {
    "two-segment piston": (([0.5, 0.5], [0.5, 1.5], [3.0], [1.0]), 1.5),
    "three-segment rod": (([1.0], [1.0], [0.1, 0.2, 0.3], [1.0, 0.5, 1.0]), 2.0),
}


@pytest.mark.parametrize("case", sorted(_STIFF))
def test_a_stiff_unloadings_spike_ends_certified_with_its_peak(case):
    """At ``gamma = 1e12`` both blows ended ``"failed"``: the bit solved on a piece a few spike widths
    ``Z/k_u`` long, the stiff exponent within ``NEAR / L`` of the slow ones, by a series whose
    coefficients ``(k_u/Z)^d / d!`` overflowed (7e292 at degree 26; its derivatives infinite); the
    spike's pieces (5e-13 long) were skipped by the largest force as slivers (below 1e-11 of the
    time), and a spike that began an ulp before a window's end reached the next junction decayed by
    that ulp (9e-4 low). Now they end certified, their peak forces those of ``gamma = 1e6`` to 1e-6
    (the spike's width), their energy accounts closed; at ``gamma = 1e6`` the independent reference's
    efficiency to 1e-8 and its peak forces to 1e-7 (its clock's resolution of the spike)."""
    chain, k = _STIFF[case]
    t_max = 4.0 * sum(chain[2]) + 4.0
    soft = exact_blow(*chain, k=k, k_u=1e6 * k, impact_velocity=1.0, record=True)
    assert soft.ended_by == "lifted"
    for gamma in (1e12, 1e8):
        stiff = exact_blow(*chain, k=k, k_u=gamma * k, impact_velocity=1.0, record=True)
        assert stiff.ended_by == "lifted", gamma
        assert stiff.energy_error < 1e-13
        np.testing.assert_allclose(stiff.peak_forces()[0], soft.peak_forces()[0], rtol=1e-6)
        np.testing.assert_allclose(stiff.peak_forces()[1], soft.peak_forces()[1], rtol=1e-6)
        assert stiff.efficiency == pytest.approx(soft.efficiency, rel=1e-5)
        horizon = exact_blow(*chain, k=k, k_u=gamma * k, impact_velocity=1.0, t_max=t_max, record=True)
        assert horizon.ended_by in ("lifted", "t_max") and horizon.energy_error < 1e-13
        np.testing.assert_allclose(horizon.peak_forces()[0], soft.peak_forces()[0], rtol=1e-6)
    ref = reference_blow(*chain, k=k, k_u=1e6 * k, impact_velocity=1.0, t_end=soft.duration)
    # (the reference's clock steps through the spike: its peak at the piston's step 0.54 + 3.7e-8)
    np.testing.assert_allclose(soft.peak_forces()[0], ref.peak_values, rtol=1e-7)
    assert soft.efficiency == pytest.approx(ref.efficiency, rel=1e-8)
