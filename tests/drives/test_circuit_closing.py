"""The close of the oil circuit's orbit with a flexible piston: the Jacobians that only steer Newton's
method (the chord's first, its closing step) take Magnus' fundamental matrix with coarser steps
(``FlightSettings.magnus_theta``, ``STEER_THETA``), the multipliers' variational period the drive's own
steps. Checked against Newton's method with the drive's own variational flights at every step
(``newton="full"``), the plain flights at the variational flights' state tolerance and a variational
flight at the found orbit taken directly."""

import dataclasses
import math

import numpy as np
import pytest

from impactbar import find_orbit
from impactbar.drives.base import DriveState, FlightSettings
from impactbar.drives.circuit.flight import MAGNUS_STATE_TOLERANCE
from impactbar.orbits import shooting
from impactbar.orbits.driven import orbit_of
from impactbar.orbits.shooting import STEER_THETA, ShootingProblem
from impactbar.physical import circuit_preset


@pytest.fixture(scope="module")
def case():
    """The preset's drive, its model with 4 modes and the orbit found (the chord, steered)."""
    d = circuit_preset("circuit-drifter")
    model, drive = d.model().with_(n_modes=4), d.drive()
    return drive, model, find_orbit(model, drive)


def _start(orbit):
    """The orbit's first flight's start ``(state, t, q, v)``."""
    problem, X = orbit._problem, np.asarray(orbit._unknowns, dtype=float)
    M, n = problem.M, problem.n
    tau, mode = problem.blocks[0]
    y = X[:n]
    return DriveState(mode, y[2 * M:]), tau, y[:M], y[M:2 * M]


@pytest.mark.parametrize("theta", [0.0, -1.0, math.nan, math.inf])
def test_flight_settings_refuse_a_bad_magnus_step(theta):
    with pytest.raises(ValueError, match="magnus_theta"):
        FlightSettings(method="CVODE", magnus_theta=theta)


def test_a_steering_phi_is_the_same_flight_with_coarser_magnus_steps(case):
    """The same states to the bit (Magnus only takes ``Phi`` over the plain flight), ``Phi`` another
    but within 3e-5 of its largest entry (measured 1.5e-5, 4.9e-5 with 8 modes: enough for a step of
    1e-7 to leave 5e-12), and above 1e-6: the steps are ``STEER_THETA``'s (at twice the drive's own
    steps it is 2.4e-7)."""
    drive, model, orbit = case
    start = _start(orbit)
    own = drive.flight(model, *start, math.inf, None, True)
    steer = drive.flight(model, *start, math.inf,
                         dataclasses.replace(drive.integrator, magnus_theta=STEER_THETA), True)
    assert steer.t == own.t and np.array_equal(steer.q, own.q) and np.array_equal(steer.z, own.z)
    err = np.max(np.abs(steer.sensitivity - own.sensitivity)) / np.max(np.abs(own.sensitivity))
    assert 1e-6 < err <= 3e-5, err


def test_one_variational_period_at_the_drives_own_steps(case, monkeypatch):
    """``find_orbit`` takes its variational periods with the steering steps but for one at the
    drive's own (the multipliers')."""
    drive, model, _ = case
    seen = []
    fly = ShootingProblem._fly

    def spy(self, tau, mode, y, keep, variational, settings):
        if variational and self.M > 1:
            seen.append((settings or self.settings).magnus_theta)
        return fly(self, tau, mode, y, keep, variational, settings)

    monkeypatch.setattr(ShootingProblem, "_fly", spy)
    find_orbit(model, drive)
    assert seen.count(None) == 1, seen
    assert seen.count(STEER_THETA) == len(seen) - 1 >= 2, seen  # (the chord's first, the closing step's)


def test_the_orbit_is_full_newtons_and_the_variational_flights(case):
    """Against Newton's method with the drive's own variational flights at every step (from the same
    start, to their root: residual 5e-14): the unknowns within 1e-10 of their size, the impact velocity
    within 1e-9, the multipliers within 1e-8 (measured 5.8e-11, 3.5e-10, 6.1e-9: the chord's closing
    step's, the same with the drive's own steps); the residual by plain flights at the variational
    flights' state tolerance below 1e-10 (measured 1.8e-11), and the multipliers those of a variational
    flight at the orbit."""
    drive, model, orbit = case
    full = ShootingProblem(model, drive, newton="full")
    ref = orbit_of(full, full.solve(full.initial(None, 1e-13, 50), 1e-13, 50))
    X, Xr = np.asarray(orbit._unknowns), np.asarray(ref._unknowns)
    assert np.max(np.abs(X - Xr)) <= 1e-10 * np.max(np.abs(Xr))
    assert orbit.period == pytest.approx(ref.period, rel=1e-10)
    np.testing.assert_allclose(orbit.impact_velocities, ref.impact_velocities, rtol=1e-9)
    np.testing.assert_allclose(orbit.multipliers, ref.multipliers, rtol=0, atol=1e-8)
    problem = orbit._problem
    s = problem.settings
    rtol = max(s.rtol * MAGNUS_STATE_TOLERANCE, 1e-13)
    tight = dataclasses.replace(s, rtol=rtol, atol=s.atol * rtol / s.rtol)
    problem._last = None
    assert np.max(np.abs(_tight_residual(problem, X, tight))) <= 1e-10
    problem._last = None
    np.testing.assert_array_equal(problem.orbit(X).multipliers, orbit.multipliers)


@pytest.mark.slow  # about 15 s: the orbit with 16 modes twice
def test_the_16_mode_orbit_is_full_newtons():
    """With 16 modes, where the closing step's steering Jacobian is the least accurate: the orbit
    against full Newton's within 1e-10 in its unknowns, its impact velocity within 1e-9 and its
    multipliers within 1e-8 (measured 7.1e-12, 1.4e-10, 1.6e-9; over BDF's plain flights it was
    4.9e-10, 1.4e-8 and 1.2e-7)."""
    d = circuit_preset("circuit-drifter")
    model, drive = d.model().with_(n_modes=16), d.drive()
    orbit = find_orbit(model, drive)
    full = ShootingProblem(model, drive, newton="full")
    ref = orbit_of(full, full.solve(full.initial(None, 1e-13, 50), 1e-13, 50))
    assert np.max(np.abs(np.asarray(orbit._unknowns) - np.asarray(ref._unknowns))) <= 1e-10
    assert abs(orbit.impact_velocity - ref.impact_velocity) <= 1e-9
    np.testing.assert_allclose(orbit.multipliers, ref.multipliers, rtol=0, atol=1e-8)


def _tight_residual(problem, X, settings):
    """The shooting residual by plain flights with ``settings``."""
    n, m = problem.n, problem.impacts
    r = np.empty(X.size)
    for k in range(m):
        tau, mode = problem.blocks[k]
        nxt = ((k + 1) % m) * n
        r[k * n:(k + 1) * n] = problem._flight(tau, mode, X[k * n:(k + 1) * n], settings=settings)[0] - \
            X[nxt:nxt + n]
    return r


def test_the_rigid_pistons_jacobian_ignores_the_steering_steps():
    """The rigid piston's variational flights are CVODE's (no Magnus): the steering settings give the
    same residual and Jacobian to the bit."""
    d = circuit_preset("circuit-drifter")
    orbit = find_orbit(d.model(), d.drive())
    problem, X = orbit._problem, np.asarray(orbit._unknowns, dtype=float)
    r, J = problem.residual(X)
    problem._last = None
    rs, Js = problem.residual(X, settings=dataclasses.replace(problem.settings, magnus_theta=STEER_THETA))
    assert np.array_equal(r, rs) and np.array_equal(J, Js)


def _continued(orbit, chord, max_points):
    """The continuation in the pre-charge, 5 % up, without events, by ``continue_driven`` with the
    corrector ``chord``."""
    from impactbar.continuation.driven import continue_driven
    from impactbar.continuation.engine import _settings
    from impactbar.continuation.one_parameter import _detect

    to = orbit.drive.accumulator.precharge * 1.05
    return continue_driven(orbit, "precharge", to, _detect, events=False, chord=chord,
                             settings=_settings(None, max_points=max_points))


@pytest.fixture(scope="module")
def branches():
    """A short continuation in the pre-charge of the 2-mode orbit by the correctors of before
    (``chord=True``: a chord step, then Newton's steps with the steering Jacobians), and the same with
    the drive's own steps throughout (``STEER_THETA`` the drive's)."""
    d = circuit_preset("circuit-drifter")
    drive = d.drive()
    orbit = find_orbit(d.model().with_(n_modes=2), drive)
    steered = _continued(orbit, True, 4)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(shooting, "STEER_THETA", drive.integrator.magnus_theta)
        own = _continued(orbit, True, 4)
    return steered, own


def test_the_steered_correctors_branch_is_the_drives_own_steps(branches):
    """Against the branch whose correctors take the drive's own steps: the parameter values within 1e-8
    (the tangents, from the correctors' last Jacobians, tilt by the steering's error and the points
    slide along the branch by as much: measured 8.6e-10), the orbits within 1e-10 of their size and the
    multipliers within 1e-8 (measured 1.9e-12, 1.8e-9; those of a steering Jacobian are some 1e-6
    off)."""
    steered, own = branches
    assert len(steered.orbits) == len(own.orbits) == 4
    np.testing.assert_allclose(steered.values, own.values, rtol=1e-8)
    for ob, ref in zip(steered.orbits, own.orbits, strict=True):
        X, Xr = np.asarray(ob._unknowns), np.asarray(ref._unknowns)
        assert np.max(np.abs(X - Xr)) <= 1e-10 * np.max(np.abs(Xr))
        np.testing.assert_allclose(ob.multipliers, ref.multipliers, rtol=0, atol=1e-8)


def test_the_steered_continuations_variational_periods(monkeypatch):
    """In the continuation by the correctors of before (``chord=True``), the variational flights at the
    drive's own steps are the orbits' (one each: their multipliers, the next corrector's chord); the
    correctors' take the steering steps."""
    d = circuit_preset("circuit-drifter")
    drive = d.drive()
    orbit = find_orbit(d.model().with_(n_modes=2), drive)
    seen = []
    fly = ShootingProblem._fly

    def spy(self, tau, mode, y, keep, variational, settings):
        if variational:
            seen.append((settings or self.settings).magnus_theta)
        return fly(self, tau, mode, y, keep, variational, settings)

    monkeypatch.setattr(ShootingProblem, "_fly", spy)
    b = _continued(orbit, True, 3)
    assert seen.count(drive.integrator.magnus_theta) == len(b.orbits), seen
    assert seen.count(STEER_THETA) == len(seen) - len(b.orbits) >= 2, seen
