"""The circuit's orbit by the chord method (plain flights steered by one rough variational flight, then
one Newton step with the exact one) against Newton's method with a variational flight at every step
(``newton="full"``, the way before): the same orbit and multipliers."""

import numpy as np
import pytest

from impactbar import find_orbit
from impactbar.drives.orbitproblem import chord
from impactbar.orbits import find_driven_orbit
from impactbar.orbits.driven import ShootingProblem, orbit_of
from impactbar.physical import circuit_preset


@pytest.fixture(scope="module")
def drifter():
    return circuit_preset("circuit-drifter")


def _both(model, drive):
    return find_driven_orbit(model, drive, newton="full"), find_driven_orbit(model, drive)


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
    from impactbar.continuation.driven import continue_driven
    from impactbar.continuation.engine import _settings
    from impactbar.continuation.one_parameter import _detect

    drive = drifter.drive()
    o = find_orbit(drifter.model().with_(n_modes=1), drive)
    to = drive.accumulator.precharge * 1.02
    branches = [continue_driven(o, "precharge", to, _detect, events=False, chord=c,
                                  settings=_settings(None, max_points=3)) for c in (True, "all")]
    before, now = branches
    assert len(now.orbits) == len(before.orbits) >= 2
    for a, b in zip(before.orbits, now.orbits, strict=True):
        assert abs(a.period - b.period) <= 1e-9 * a.period
        assert np.allclose(a._unknowns, b._unknowns, rtol=0, atol=3e-8 * np.max(np.abs(a._unknowns)))
    with pytest.raises(ValueError, match="chord must be True, False, 'all' or 'orbit'"):
        continue_driven(o, "precharge", to, _detect, chord="every")


def _branch(orbit, chord, max_points):
    """The continuation in the pre-charge, 5 % up, without events, with the corrector ``chord``."""
    from impactbar.continuation.driven import continue_driven
    from impactbar.continuation.engine import _settings
    from impactbar.continuation.one_parameter import _detect

    to = orbit.drive.accumulator.precharge * 1.05
    return continue_driven(orbit, "precharge", to, _detect, events=False, chord=chord,
                             settings=_settings(None, max_points=max_points))


@pytest.mark.parametrize("n_modes", [2, 8])
def test_the_orbit_corrector_reaches_the_orbits_of_before(drifter, n_modes):
    """The default corrector (``chord="orbit"``: chord steps with the Jacobian the last points
    predict, the residuals by plain flights at the variational flights' tolerance, the last iterate's
    by the orbit's own variational flight) against the correctors of before (``chord=True``) and
    against ``find_orbit`` at each point's parameter value (from the point's orbit): the same steps
    (the values within 1e-7), and at each point the unknowns within 1e-9 of their size, the period
    within 1e-10 and the multipliers within 5e-8 of ``find_orbit``'s (measured with 8 modes 1.6e-10,
    6.4e-12, 1.4e-8: the point within ``EXACT_FACTOR`` of the corrector's tolerance, and the
    multipliers' own noise, some 100 times a change in the unknowns; the correctors of before
    1.1e-11, 1.2e-12, 2.8e-9), and the stability the same."""
    drive = drifter.drive()
    orbit = find_orbit(drifter.model().with_(n_modes=n_modes), drive)
    now, before = _branch(orbit, "orbit", 4), _branch(orbit, True, 4)
    assert len(now.orbits) == len(before.orbits) == 4
    np.testing.assert_allclose(now.values, before.values, rtol=1e-7)
    for ob in now.orbits[1:]:
        ref = find_orbit(ob.model, ob.drive, guess=ob)
        X, Xr = np.asarray(ob._unknowns), np.asarray(ref._unknowns)
        assert np.max(np.abs(X - Xr)) <= 1e-9 * np.max(np.abs(Xr))
        assert abs(ob.period - ref.period) <= 1e-10 * ref.period
        np.testing.assert_allclose(ob.multipliers, ref.multipliers, rtol=0, atol=5e-8)
        assert ob.stable == ref.stable


def test_a_continuation_point_takes_one_variational_period(drifter, monkeypatch):
    """With 4 modes, each new point of the default corrector takes one variational period (its
    orbit's, at the drive's own Magnus steps: the multipliers, the next points' chord), none with the
    steering steps, and at most two plain periods (the chord's; the start one more, for ``F_lam``);
    the start's orbit is ``find_orbit``'s flight, not flown again. The correctors of before took two
    steering variational periods and two plain ones a point."""
    from impactbar.orbits.shooting import STEER_THETA

    drive = drifter.drive()
    orbit = find_orbit(drifter.model().with_(n_modes=4), drive)
    seen = []
    fly = ShootingProblem._fly

    def spy(self, tau, mode, y, keep, variational, settings):
        seen.append((settings or self.settings).magnus_theta if variational else "plain")
        return fly(self, tau, mode, y, keep, variational, settings)

    monkeypatch.setattr(ShootingProblem, "_fly", spy)
    b = _branch(orbit, "orbit", 4)
    points = len(b.orbits) - 1
    assert points == 3
    assert seen.count(drive.integrator.magnus_theta) == points, seen
    assert STEER_THETA not in seen
    assert seen.count("plain") <= 2 * points + 1, seen


def _flights(monkeypatch) -> list:
    """The kinds of the shooting problem's flights from now on (``"variational"`` or ``"plain"``),
    in a list that fills as they are flown."""
    seen = []
    fly = ShootingProblem._fly

    def spy(self, tau, mode, y, keep, variational, settings):
        seen.append("variational" if variational else "plain")
        return fly(self, tau, mode, y, keep, variational, settings)

    monkeypatch.setattr(ShootingProblem, "_fly", spy)
    return seen


def _longer_branch(drifter, monkeypatch, rule):
    """The branch of eight points (the pre-charge 20 % up, 8 modes) with the corrector's rate
    predicted by ``rule``: the branch and the kinds of its flights."""
    import impactbar.continuation.driven as SW
    from impactbar import continue_orbit

    drive = drifter.drive()
    orbit = find_orbit(drifter.model().with_(n_modes=8), drive)
    seen = _flights(monkeypatch)
    monkeypatch.setattr(SW, "predicted_rate", rule)
    b = continue_orbit(orbit, "precharge", to=drive.accumulator.precharge * 1.2, max_points=8, events=False)
    monkeypatch.undo()
    return b, seen


def test_a_longer_branch_takes_one_variational_period_a_point(drifter, monkeypatch):
    """On a branch of eight points with 8 modes, each new point takes one variational period: the
    corrector flies the orbit's variational flight where the largest ratio of its chord's steps (at
    least ``CHORD_RATE`` on one ratio alone) puts the next iterate within the target. Predicted from
    the chord's last ratio alone (the rule of before), three of the seven points flew it twice, a
    chord's first ratio underestimating its rate, each such flight with its ``F_lam`` flight some
    four plain periods, where the rule takes one chord step more; the same points."""
    from impactbar.continuation.driven import predicted_rate

    now, seen = _longer_branch(drifter, monkeypatch, predicted_rate)
    before, seen_before = _longer_branch(drifter, monkeypatch, lambda ratios: ratios[-1])
    points = len(now.orbits) - 1
    assert points == len(before.orbits) - 1 == 7
    assert seen.count("variational") == points, seen
    assert seen_before.count("variational") == points + 3, seen_before
    np.testing.assert_allclose(now.values, before.values, rtol=0, atol=1e-9)


def test_the_plain_flight_at_the_variational_tolerance_is_its_state(drifter):
    """``ShootingProblem.root_value``: with a flexible piston (Magnus' fundamental matrix over a plain
    flight) the plain flight at the variational flights' tolerance, the residual of the variational
    flight to the bit; the rigid piston's variational flights are CVODE's (their state their own):
    the variational flight itself."""
    for n_modes, cheap in ((2, True), (0, False)):
        orbit = find_orbit(drifter.model().with_(n_modes=n_modes), drifter.drive())
        problem, X = orbit._problem, np.asarray(orbit._unknowns, dtype=float) * (1.0 + 1e-7)
        assert problem.state_flights is cheap
        r = problem.root_value(X)
        problem._last = None
        assert np.array_equal(r, problem.residual(X)[0])
        if cheap:  # (and not a plain flight at the drive's tolerance)
            problem._last = None
            assert not np.array_equal(r, problem.value(X))


def test_the_jacobian_along_the_branch_is_lagranges(drifter):
    """The corrector's predicted Jacobian (``_SwitchedProblem._along``): exact for a quantity
    quadratic along a straight branch from three points, linear from two, constant from one, in
    whatever order the points came (the events' location corrects points between the last two)."""
    from impactbar.continuation.driven import _SwitchedProblem
    from impactbar.continuation.one_parameter import _detect

    model = drifter.model().with_(n_modes=1)
    p = _SwitchedProblem(model, drifter.drive(), "precharge", _detect, chord="orbit")
    rng = np.random.default_rng(1)
    a, d = rng.standard_normal(p.W.size), rng.standard_normal(p.W.size)
    A, B, C = (rng.standard_normal((3, 3)) for _ in range(3))

    def value(s):
        return A + s * B + s * s * C

    at = a + 1.7 * d
    for ss in ([0.0, 1.0, 0.4], [0.3, 1.0, 0.0], [0.0, 0.5, 1.0]):
        records = [(a + s * d, value(s)) for s in ss]
        np.testing.assert_allclose(p._along(records, at), value(1.7), rtol=1e-12, atol=1e-12)
    linear = [(a + s * d, A + s * B) for s in (0.2, 0.9)]
    np.testing.assert_allclose(p._along(linear, at), A + 1.7 * B, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(p._along([(a, A)], at), A)
    # a point that the others do not set apart is left out (the older): linear from the other two
    records = [(a, value(0.0)), (a + 1e-9 * d, value(1e-9)), (a + d, value(1.0))]
    lin = value(1e-9) + (1.7 - 1e-9) / (1.0 - 1e-9) * (value(1.0) - value(1e-9))
    np.testing.assert_allclose(p._along(records, at), lin, rtol=1e-9, atol=1e-9)


def test_an_iterate_outside_the_parameters_range_shortens_the_step(drifter):
    """With 4 modes the pre-set's valve coefficient taken down: the first predictor's chord
    diverges (two real multipliers near 0.92 about to meet, the Jacobian changing fast along the
    branch) and its Newton step puts the coefficient at -486, outside its range. That iterate is a
    failed corrector (the step then shortened), not the drive's refusal of the value raised to the
    caller, who asked for nothing out of range; the points are orbits."""
    drive = drifter.drive()
    orbit = find_orbit(drifter.model().with_(n_modes=4), drive)
    from impactbar import continue_orbit

    b = continue_orbit(orbit, "valve_coefficient", to=0.8 * drive.valve.coefficient, max_points=3,
                       events=False)
    assert len(b.orbits) == 3 and b.values[-1] < b.values[0]
    last = b.orbits[-1]
    ref = find_orbit(last.model, last.drive)
    assert abs(ref.period - last.period) <= 1e-9 * ref.period
    np.testing.assert_allclose(np.sort_complex(ref.multipliers), np.sort_complex(last.multipliers), rtol=0,
                               atol=1e-7)


def test_in_the_pumps_flow_the_predicted_jacobian_stalls(drifter, monkeypatch):
    """What theory §11 says of the corrector off the pre-charge: in the pump's flow (4 modes, 20 %
    up) the chord with the Jacobian the last points predict stalls, so that points take more than
    one variational period (the Jacobian taken again at an iterate), and the branch's steps stay
    short; the points are orbits all the same."""
    from impactbar import continue_orbit

    drive = drifter.drive()
    orbit = find_orbit(drifter.model().with_(n_modes=4), drive)
    seen = _flights(monkeypatch)
    b = continue_orbit(orbit, "pump_flow", to=1.2 * drive.supply.pump_flow, max_points=4, events=False)
    monkeypatch.undo()
    points = len(b.orbits) - 1
    assert points == 3
    assert seen.count("variational") > points, seen
    last = b.orbits[-1]
    ref = find_orbit(last.model, last.drive)
    assert abs(ref.period - last.period) <= 1e-9 * ref.period
