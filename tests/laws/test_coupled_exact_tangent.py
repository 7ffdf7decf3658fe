"""The tangent of the coupled exact blow (theory §11, "The coupled blow";
:func:`~impactbar.laws.rodrock.coupled_tangent.coupled_blow_tangent`) against central differences of
the coupled exact blows themselves, at two steps: each entry within the differences' own error (their
change between the steps), on the second arrival of ``examples/circuit_drifter_rock.toml``."""

import numpy as np
import pytest
from coupled_reference import drifter_arrival

from impactbar.drives.base import DriveState
from impactbar.laws.rodrock.coupled_tangent import coupled_blow_tangent
from impactbar.orbits.coupled import blow_jacobian, blow_state

#: the differences' steps, relative to the modal and the drive's components' largest sizes
STEPS = (1e-3, 3e-4)


@pytest.fixture(scope="module")
def blow():
    """The arrival, the blow there and its tangent."""
    model, drive, state, t0, q, v = drifter_arrival()
    y, res, after = blow_state(model, drive, t0, q, v, state)
    G = coupled_blow_tangent(model, drive, res, after, state)
    return (model, drive, state, t0, q, v), (y, res, after), G


def _column(arrival, j, rel):
    """Central differences of the blow's map along the ``j``-th component of ``(q, q', z)``."""
    model, drive, state, t0, q, v = arrival
    M = q.size
    y = np.concatenate((q, v, state.z))
    group = slice(0, 2 * M) if j < 2 * M else slice(2 * M, y.size)
    h = rel * float(np.max(np.abs(y[group])))
    out = []
    for s in (1.0, -1.0):
        yy = y.copy()
        yy[j] += s * h
        after, _, _ = blow_state(model, drive, t0, yy[:M], yy[M:2 * M], DriveState(state.mode, yy[2 * M:]))
        out.append(after)
    return (out[0] - out[1]) / (2.0 * h)


def _check(blow, cols):
    arrival, _, G = blow
    assert G is not None
    for j in cols:
        big, small = (_column(arrival, j, rel) for rel in STEPS)
        own = np.abs(big - small)  # the differences' own error (O(step^2) and their noise)
        # measured: the q_0' column within 1.5e-7 of the differences at 3e-4 (their own error 3.7e-7
        # in the p_r row, 9.3e-8 in the q_0' row); the x_v column 1.8e-7 in the p_r row (own 1.1e-6)
        bound = 2.0 * own + 1e-8 * max(float(np.max(np.abs(G[:, j]))), 1.0)
        assert np.all(np.abs(G[:, j] - small) <= bound), (j, G[:, j] - small, own)


def test_the_tangent_agrees_with_the_blows_differences(blow):
    """The piston's velocity and the rear chamber's pressure at the arrival: the piston's and the
    circuit's halves of the coupling (the drive's force moves the blow, the blow the circuit)."""
    arrival, _, _ = blow
    M = arrival[4].size
    _check(blow, [M, 2 * M + 1])


@pytest.mark.slow
def test_every_column_agrees_with_the_blows_differences(blow):
    """Every column but ``q_0``'s (the arrival's end put on the stop: no effect)."""
    _, _, G = blow
    assert np.all(G[:, 0] == 0.0)
    _check(blow, range(1, G.shape[0]))


def test_what_the_tangent_does_not_cover_is_none(blow):
    """The drive's events inside the blow (a saltation each) and a blow without the drive's coupling
    data (the lattice's records) are left to the differences."""
    arrival, (y, res, after), _ = blow
    model, drive, state = arrival[:3]
    assert coupled_blow_tangent(model, drive, res._replace(events=[(0.0, None, state.mode)]), after,
                                state) is None

    class Bare:
        coupling = None

    assert coupled_blow_tangent(model, drive, res._replace(record=Bare()), after, state) is None


def test_the_blows_jacobian_is_the_tangent_else_the_differences(blow, monkeypatch):
    """``blow_jacobian`` (the multipliers' Jacobian) is the law's tangent where the blows are exact
    and the tangent covers the blow, to the bit; where the law has none for the blow, the central
    differences: two blows a column but ``q_0``'s."""
    import impactbar as ib
    import impactbar.orbits.coupled as OC

    arrival, (y, res, after), G = blow
    model, drive, state, t0, q, v = arrival
    np.testing.assert_array_equal(blow_jacobian(model, drive, t0, q, v, state, blow=(res, after)), G)
    calls = []

    def counted(*args, **kwargs):
        calls.append(args)
        return y, res, after

    monkeypatch.setattr(ib.RodRock, "driven_tangent", lambda self, *args: None)
    monkeypatch.setattr(OC, "blow_state", counted)
    differenced = blow_jacobian(model, drive, t0, q, v, state, blow=(res, after))
    assert len(calls) == 2 * (y.size - 1)
    assert np.all(differenced == 0.0)  # (every blow the same here: no difference)


def test_the_thinned_direction_gives_the_unthinned_ones_tangent(blow, monkeypatch):
    """The drive's direction on the primal's integrator steps thinned (``DIRECTION_STEPS`` a travel
    time) gives the tangent of the direction on every step to 1e-8 of its size (measured 6.8e-10, the
    central differences' agreement 1e-7); thinned to 2 a travel time, the refinement where its cubic
    misses the derivative (``THIN_TOL``) brings it back (measured 1.9e-10), and without the
    refinement it does not (2.3e-4)."""
    import impactbar.laws.rodrock.coupled_tangent as CT

    arrival, (_, res, after), G = blow
    model, drive, state = arrival[:3]

    def tangent(steps, tol=CT.THIN_TOL):
        monkeypatch.setattr(CT, "DIRECTION_STEPS", steps)
        monkeypatch.setattr(CT, "THIN_TOL", tol)
        return coupled_blow_tangent(model, drive, res, after, state)

    every = tangent(1e12)  # (each step its own piece)

    def off(H):
        return float(np.max(np.abs(H - every))) / float(np.max(np.abs(every)))

    assert off(G) <= 1e-8
    assert off(tangent(2.0)) <= 1e-8
    assert off(tangent(2.0, np.inf)) > 1e-6


def test_the_tangent_takes_the_blows_own_switch_log(blow, monkeypatch):
    """The blow's last iterate logs its switches from the impact on (each iterate goes on from its
    predecessor's snapshot, whose log it carries): the tangent solves no blow, and it is the tangent
    of the primal blow solved again for its own log, to the bit. A log that overflowed is not kept
    (the primal then solved again, once)."""
    from impactbar.laws.rodrock._records import RD_FULL, RD_HEAD, RD_ROWS, WS_RD
    from impactbar.laws.rodrock.exactmap import ExactBlowMap

    arrival, (_, res, after), G = blow
    model, drive, state = arrival[:3]
    rec = res.record
    solves = []
    real = ExactBlowMap.solve

    def counted(self, *args, **kwargs):
        solves.append(kwargs.get("log", 0))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(ExactBlowMap, "solve", counted)
    np.testing.assert_array_equal(coupled_blow_tangent(model, drive, res, after, state), G)
    assert solves == []
    (ws, scale), _ = rec.switch_log
    assert int(ws[WS_RD][RD_HEAD, RD_ROWS].real) > 0  # (the separations and re-contacts: measured 10)
    monkeypatch.setattr(rec, "switch_log", None)
    np.testing.assert_array_equal(coupled_blow_tangent(model, drive, res, after, state), G)
    assert len(solves) == 1 and solves[0] > 0  # (the primal again, with its log)
    from impactbar.laws.rodrock.exactjac import kept_primal

    full = (*ws[:WS_RD], ws[WS_RD].copy(), *ws[WS_RD + 1:])
    full[WS_RD][RD_HEAD, RD_FULL] = 1.0
    assert kept_primal(ws, scale, rec.duration) is not None
    assert kept_primal(full, scale, rec.duration) is None


def test_the_rounds_end_where_what_is_left_is_estimated_below_the_tolerance(blow, monkeypatch):
    """The rounds end where the change left to the fixed point, estimated from the last two rounds'
    contraction, is below ``TANGENT_TOL``: 4 rounds on this blow (changes 1.7e-2, 8.8e-5, 6.6e-8 of
    its size, 4.9e-11 left estimated), where the plain rule (the last change below it) takes 5; the
    tangent then moves by 2.4e-11 of its size (measured), within the estimate."""
    import impactbar.laws.rodrock.coupled_tangent as CT
    from impactbar.laws.rodrock import exactjac as EJ

    arrival, (_, res, after), G = blow
    model, drive, state = arrival[:3]
    runs = []
    real = EJ.tangents

    def counted(*args, **kwargs):
        runs.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(EJ, "tangents", counted)
    np.testing.assert_array_equal(coupled_blow_tangent(model, drive, res, after, state), G)
    assert len(runs) == 4
    runs.clear()
    settled = CT._settled
    monkeypatch.setattr(CT, "_settled", lambda change, last: change <= CT.TANGENT_TOL)
    plain = coupled_blow_tangent(model, drive, res, after, state)
    assert len(runs) == 5
    moved = np.max(np.abs(plain - G)) / np.max(np.abs(plain))
    assert 0.0 < moved <= 1e-10, moved
    assert not settled(8.8e-5, 1.7e-2) and settled(6.6e-8, 8.8e-5) and settled(1e-11, 1e-3)
    assert not settled(2e-10, np.inf) and not settled(2e-10, 1e-10)  # (no estimate, no contraction)
