"""The least and the greatest pressures of the circuit over a blow (theory §11, *Limits of this
version*: the cavitation check reads them), its cubic Hermite interpolants' extremes solved only on
the steps whose interpolant can pass the samples' extremes.

Checked against independent numbers:

- each piece's interpolant solved whole by scipy (its derivative's roots), the blow's extremes the
  least and the greatest of the pieces': the same numbers, to the bit, on a coupled blow of the
  pump-fed drifter and on random cubic histories;
- a dense evaluation of the same interpolants (a thousand points a step): within 1e-12 of the swing
  inside the extremes, never outside;
- a supply held at its pressure (and the valve's opening at an end) is its value, where scipy's roots
  mark the constant steps with ``nan``.
"""

import numpy as np
import pytest
import test_circuit_laws as laws_tests  # this folder's: the pump-fed drifter and the rod on rock
from scipy.interpolate import CubicHermiteSpline

from impactbar import BarModel
from impactbar.drives import DriveState
from impactbar.drives.circuit import extremes
from impactbar.drives.circuit.extremes import HERMITE_REACH, hermite_extremes


def _blow(drive, z):
    """A coupled blow of the drive on the rod and rock from the circuit's state ``z``: its pieces."""
    model = BarModel(s=laws_tests.S, d=0, R=0.0, n_modes=0, impact=laws_tests.rock(2.0, cells=8))
    st = DriveState((1, 0, 1, 0), np.asarray(z, float))
    return model.law.driven_contact(model, drive, st, 0.0, np.zeros(1), np.array([0.34])).pieces


def _whole(t, x, dxdt):
    """A piece's extremes from its whole interpolant: scipy's roots of its derivative (the constant
    steps' ``nan`` dropped)."""
    sp = CubicHermiteSpline(t, x, dxdt)
    r = sp.derivative().roots(extrapolate=False)
    vals = np.concatenate((x, sp(r[~np.isnan(r)])))
    return vals.min(), vals.max()


def _dense(pieces, column):
    """The extremes of the interpolants at a thousand points a step."""
    vals = []
    for p in pieces:
        sp = CubicHermiteSpline(p.t, p.y[:, column], p.f[:, column])
        s = np.linspace(0.0, 1.0, 1001)
        vals.append(sp((p.t[:-1, None] + np.diff(p.t)[:, None] * s).ravel()))
    vals = np.concatenate(vals)
    return vals.min(), vals.max()


@pytest.fixture(scope="module")
def pumped_blow():
    return _blow(laws_tests.pumped(), [1.15, 1.15, 1.15, 1.0])


def test_a_blow_s_pressure_extremes_are_those_of_its_pieces_whole_interpolants(pumped_blow, monkeypatch):
    pieces = pumped_blow
    n = pieces[0].layout.n_states
    lows, highs = pieces[0].extremes_over(pieces, range(n))
    solved = []
    whole = extremes._hermite_extremes

    def counted(t, x, dxdt):
        solved.append(t.size - 1)
        return whole(t, x, dxdt)

    monkeypatch.setattr(extremes, "_hermite_extremes", counted)
    again = pieces[0].extremes_over(pieces, range(n))
    steps = sum(p.t.size - 1 for p in pieces)
    assert len(pieces) > 20 and steps > 1000
    # the cubics solved on a few steps of the blow's (per state, each piece's whole before)
    assert sum(solved) <= 0.02 * n * steps, (sum(solved), n * steps)
    for k in range(n):
        j = pieces[0]._column(k)
        each = [_whole(p.t, p.y[:, j], p.f[:, j]) for p in pieces]
        assert lows[k] == min(lo for lo, _ in each) and highs[k] == max(hi for _, hi in each)
        assert (again[0][k], again[1][k]) == (lows[k], highs[k])
    # a dense evaluation of the interpolants comes within 1e-12 of the pressures' swing inside their
    # extremes; the front chamber's lie between steps here (below and above every sample, by some
    # 1e-8: where a sample's extremes would do, the interpolant's are those of theory §11)
    for k in range(3):
        j = pieces[0]._column(k)
        lo, hi = _dense(pieces, j)
        swing = highs[k] - lows[k]
        assert lows[k] <= lo <= lows[k] + 1e-12 * swing and highs[k] - 1e-12 * swing <= hi <= highs[k]
    j = pieces[0]._column(0)
    assert lows[0] < min(p.y[:, j].min() for p in pieces) and highs[0] > max(p.y[:, j].max() for p in pieces)


def test_random_cubic_histories_to_the_bit():
    """Random pieces (steps of widely different lengths, slopes of either sign, flat stretches, a
    single sample), three columns, one constant: the pieces' whole interpolants' extremes."""
    rng = np.random.default_rng(7)
    for _ in range(40):
        pieces, t0 = [], 0.0
        for _ in range(int(rng.integers(1, 6))):
            m = int(rng.integers(1, 30))
            t = t0 + np.cumsum(rng.exponential(1.0, m) * 10.0 ** rng.uniform(-3, 0, m))
            x = rng.normal(size=(m, 3)).cumsum(axis=0)
            d = rng.normal(size=(m, 3)) * 10.0 ** rng.uniform(-2, 2)
            x[:, 2], d[:, 2] = 1.0, 0.0
            if m > 4:
                x[1:4, 0], d[1:4, 0] = x[1, 0], 0.0
            pieces.append((t, x, d))
            t0 = t[-1]
        lows, highs = hermite_extremes(pieces, 3)
        for c in range(3):
            each = [_whole(t, x[:, c], d[:, c]) if t.size > 1 else (x[0, c], x[0, c]) for t, x, d in pieces]
            assert lows[c] == min(lo for lo, _ in each) and highs[c] == max(hi for _, hi in each)
        assert lows[2] == highs[2] == 1.0


def test_the_reach_bounds_a_hermite_step():
    """The interpolant of a step stays within its ends' values widened by 4/27 of the step times its
    slopes away from them (sampled densely; the bound attained for one slope alone)."""
    rng = np.random.default_rng(3)
    s = np.linspace(0.0, 1.0, 2001)
    for _ in range(200):
        a, b, da, db = rng.normal(size=4) * [1.0, 1.0, 5.0, 5.0]
        p = CubicHermiteSpline([0.0, 1.0], [a, b], [da, db])(s)
        assert p.min() >= min(a, b) - HERMITE_REACH * (max(-da, 0.0) + max(db, 0.0)) - 1e-12
        assert p.max() <= max(a, b) + HERMITE_REACH * (max(da, 0.0) + max(-db, 0.0)) + 1e-12
    p = CubicHermiteSpline([0.0, 1.0], [0.0, 0.0], [-1.0, 0.0])(s)
    assert p.min() == pytest.approx(-HERMITE_REACH, rel=1e-6)


def test_a_held_supply_s_extremes_are_its_pressure():
    """A supply held at its pressure: constant over the blow, its extremes that pressure (scipy's
    roots mark each constant step with nan, which a piece's extremes took before), and the valve's
    opening held at 1 likewise."""
    pieces = _blow(laws_tests.held(ps=1.0), [1.15, 1.15, 1.0, 1.0])
    for p in pieces[:2]:
        assert p.extremes("supply") == (1.0, 1.0)
        assert p.extremes("spool") == (1.0, 1.0)
    lows, highs = pieces[0].extremes_over(pieces, ["supply"])
    assert lows.tolist() == highs.tolist() == [1.0]
