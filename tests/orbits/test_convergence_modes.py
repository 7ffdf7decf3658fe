"""Convergence in the number of modes: a flexible orbit's impact velocities against a fine reference.

A one-impact orbit under eq. 10 strikes at ``2 pi p0 / (1 + R)`` whatever ``n_modes`` is (momentum over a
period), so the measured quantity is the pair of impact velocities of a 2-per-2 orbit, which the
flexible modes split unequally. The reference is the same orbit with 256 modes; the truncated orbits
(8, 16, 32 modes) must approach it with an algebraic order of at least 2 (the modal load response
decays as ``1/n^2``; the measured least-squares order is about 2.7).
"""

import math

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, continue_orbit, find_orbit, periodic_orbits

S, D, R = 10.0, 0.05, 0.5


def _padded(states, n_from, n_to):
    """States ``(m, 2 n_from + 2)`` padded with zero modes to ``(m, 2 n_to + 2)``."""
    m = states.shape[0]
    q = np.zeros((m, n_to + 1))
    v = np.zeros((m, n_to + 1))
    k = min(n_from, n_to) + 1
    q[:, :k] = states[:, :k]
    v[:, :k] = states[:, n_from + 1:n_from + 1 + k]
    return np.hstack((q, v))


@pytest.fixture(scope="module")
def doubled_orbits():
    model = BarModel(s=S, d=D, R=R, n_modes=8)
    start = next(o for o in periodic_orbits(model, CosineLoad(0.3, 1.0)) if math.cos(o.phase) < 0)
    branch = continue_orbit(start, "p0", to=1.0)
    pd = next(e for e in branch.events if e.kind == "period-doubling")
    guess = continue_orbit(pd, "p0", to=0.3).orbit_at(0.5)
    out = {}
    times, states, n_prev = guess.impact_times, guess.states_after_impact, 8
    for n in (8, 16, 32, 64, 256):
        o = find_orbit(BarModel(s=S, d=D, R=R, n_modes=n), guess.load, impacts=2, periods=2,
                       guess=(times, _padded(states, n_prev, n)))
        out[n] = o
        times, states, n_prev = o.impact_times, o.states_after_impact, n
    return out


def test_impact_velocities_converge_in_n_modes_with_order_at_least_two(doubled_orbits):
    ref = doubled_orbits[256].impact_velocities
    ns = np.array([8, 16, 32])
    err = np.array([np.max(np.abs(doubled_orbits[n].impact_velocities - ref)) for n in ns])
    assert np.all(np.diff(err) < 0), err  # every doubling of the modes reduces the error
    order = -np.polyfit(np.log(ns), np.log(err), 1)[0]
    assert order >= 2.0, (order, err)
    # the two impacts stay distinct (a genuine 2-per-2 orbit, not the one-impact orbit twice)
    assert abs(ref[0] - ref[1]) > 0.1
    # and doubling once more (64 modes) still gains at least a factor 4
    assert np.max(np.abs(doubled_orbits[64].impact_velocities - ref)) < err[-1] / 4
