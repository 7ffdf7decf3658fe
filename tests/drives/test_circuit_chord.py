"""The circuit's orbit by the chord method (plain flights steered by one rough variational flight, then
one Newton step with the exact one) against Newton's method with a variational flight at every step
(``newton="full"``, the way before): the same orbit and multipliers."""

import numpy as np
import pytest

from impactbar import find_orbit
from impactbar.drives.orbitproblem import chord
from impactbar.orbits import find_switched_orbit
from impactbar.orbits.switched import ShootingProblem, orbit_of
from impactbar.physical import circuit_preset


@pytest.fixture(scope="module")
def drifter():
    return circuit_preset("circuit-drifter")


def _both(model, drive):
    return find_switched_orbit(model, drive, newton="full"), find_switched_orbit(model, drive)


def test_the_rigid_orbit_is_newtons(drifter):
    full, fast = _both(drifter.model(), drifter.drive())
    assert fast.problem.newton == "chord" and full.problem.newton == "full"
    assert np.allclose(fast._unknowns, full._unknowns, rtol=1e-8, atol=1e-10)
    assert abs(fast.period - full.period) <= 1e-8 * full.period
    assert np.max(np.abs(fast.multipliers - full.multipliers)) <= 1e-8
    assert find_orbit(drifter.model(), drifter.drive()).period == fast.period  # find_orbit's default


@pytest.mark.slow
def test_the_flexible_orbit_is_newtons_to_the_multipliers_own_noise(drifter):
    """Two modes: the unknowns to 1e-10 and 1e-11 (the modal velocities of some 1e-6 measured 1.7e-12
    apart: Newton's method with the full Jacobian started from the chord's root lands 3.3e-12 from its
    own, the root's own spread), the period to 1e-10. The multipliers are the variational flight's at
    the unknowns, and that flight's steps move with the unknowns: a change of 1e-12 in them moves the
    multipliers by some 1e-10 (shown here; 1.9e-10 and 3.0e-10 measured since the plain flights take
    Adams-Moulton's steps, ~1e-7 before), so the two ways agree to that noise, not to rounding."""
    full, fast = _both(drifter.model().with_(n_modes=2), drifter.drive())
    assert np.allclose(fast._unknowns, full._unknowns, rtol=1e-10, atol=1e-11)
    assert abs(fast.period - full.period) <= 1e-10 * full.period
    assert np.allclose(fast.impact_velocities, full.impact_velocities, rtol=1e-10)
    problem = full.problem
    problem._last = None
    noise = np.max(np.abs(orbit_of(problem, full._unknowns * (1.0 + 1e-12)).multipliers - full.multipliers))
    gap = np.max(np.abs(fast.multipliers - full.multipliers))
    assert 1e-11 < noise < 1e-6
    assert gap <= max(10.0 * noise, 1e-8)
    assert fast.stable == full.stable and fast.admissible == full.admissible


def test_the_chord_method_solves_a_system_with_one_jacobian():
    """On ``x^2 = 2, x y = 3`` from a start 10 % off, with the Jacobian at the start: the root to
    rounding, the Jacobian asked once (at the start)."""
    asked = []

    def value(X):
        return np.array([X[0] ** 2 - 2.0, X[0] * X[1] - 3.0])

    def jac(X):
        asked.append(X.copy())
        return np.array([[2.0 * X[0], 0.0], [X[1], X[0]]])

    X = chord(value, jac, np.array([1.5, 2.0]), np.zeros(0, dtype=np.int64), 1e-14, 60)
    assert np.allclose(X, [np.sqrt(2.0), 3.0 / np.sqrt(2.0)], rtol=1e-13)
    assert len(asked) == 1


def test_newton_must_be_named(drifter):
    with pytest.raises(ValueError, match="newton must be 'chord' or 'full'"):
        ShootingProblem(drifter.model(), drifter.drive(), newton="broyden")


def test_a_branch_with_chord_steps_throughout_is_the_branch_of_before(drifter):
    """The accumulator's pre-charge 2 % up with one mode: every corrector step a chord step
    (``chord="all"``) against the first only (``chord=True``, the default): the points are then the
    roots of the plain flights, not of the variational ones (the integrator's error apart: measured
    2.7e-10 in the period, 3e-8 in the pressures), so the unknowns agree to 3e-8 of their size, the
    periods to 1e-9."""
    from impactbar.continuation.core import _detect
    from impactbar.continuation.engine import _settings
    from impactbar.continuation.switched import continue_switched

    drive = drifter.drive()
    o = find_orbit(drifter.model().with_(n_modes=1), drive)
    to = drive.accumulator.precharge * 1.02
    branches = [continue_switched(o, "precharge", to, _detect, events=False, chord=c,
                                  settings=_settings(None, max_points=3)) for c in (True, "all")]
    before, now = branches
    assert len(now.orbits) == len(before.orbits) >= 2
    for a, b in zip(before.orbits, now.orbits, strict=True):
        assert abs(a.period - b.period) <= 1e-9 * a.period
        assert np.allclose(a._unknowns, b._unknowns, rtol=0, atol=3e-8 * np.max(np.abs(a._unknowns)))
    with pytest.raises(ValueError, match="chord must be True, False or 'all'"):
        continue_switched(o, "precharge", to, _detect, chord="every")
