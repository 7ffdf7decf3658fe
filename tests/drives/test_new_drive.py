"""A new drive needs nothing but the :class:`impactbar.Drive` interface: two
drives are defined in this file alone, and simulate, find_orbit and continue_orbit take them.

- ``TwoLevel``: a force constant between events (no state of its own), ``+stroke`` until an impact,
  then ``-ret`` until the gap rises through ``x1``: the generic paths with closed-form flights.
  Checked against the rigid piston's orbit from energy and restitution (theory §10:
  ``v^2 (1 - R^2) = 2 x1 (stroke + ret)``, multiplier ``R^2``), against the valve's own segment
  problem with its exact Jacobian (the same motion on a flexible bar), and against the valve's run.
  A constant push with no event at all (``Push``) drops the piston onto the stop: ``sqrt(2 p y0)``,
  then ``R`` times each.
- ``Lag``: a drive with state, a first-order lag ``z' = (P - z) / lag`` of the force toward the level
  ``P`` of its mode, switched on the same rules: the generic paths with ``solve_ivp``. Checked against
  an integration of the same equations written here (scipy's DOP853 at ``rtol = 1e-12``, events as
  written below), and its Poincare map's fixed point and finite-difference multipliers.
"""

import math
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from impactbar import (
    BarModel,
    Drive,
    DriveState,
    DriveTraits,
    InitialState,
    PeriodicOrbit,
    PositionSwitchedDrive,
    Trajectory,
    continue_orbit,
    find_orbit,
    simulate,
)
from impactbar.drives import GapCrossing, TimedEvent
from impactbar.orbits import phase_roots

STROKE, RETURN = 0, 1
NAMES = ("stroke", "return")


@dataclass(frozen=True)
class TwoLevel(Drive):
    """``+stroke`` toward the stop until an impact, then ``-ret`` until the gap rises through ``x1``."""

    stroke: float
    ret: float
    x1: float

    traits = DriveTraits(parameters=("stroke", "ret", "x1"))

    def start(self, model, q, v):
        return DriveState(RETURN if -q[0] < self.x1 else STROKE, np.zeros(0))

    def mode_name(self, mode):
        return NAMES[mode]

    def force(self, mode, z, q, v):
        return self.stroke if mode == STROKE else -self.ret

    def events(self, mode):
        return (GapCrossing("x1", level=self.x1, direction=1),) if mode == RETURN else ()

    def jump(self, mode, z, event, t, q, v):
        return DriveState(STROKE, z)

    def impact(self, mode, z, t, q, v):
        return DriveState(RETURN, z)


@dataclass(frozen=True)
class Delayed(Drive):
    """The valve's rules written here: each switch takes effect ``delay`` after its trigger (the
    crossing of ``x1``, the impact). The mode is ``(level, pending)``, ``pending`` the triggered
    switches ``(time, level)``, sorted; a :class:`~impactbar.drives.TimedEvent` at the first."""

    stroke: float
    ret: float
    x1: float
    delay: float

    traits = DriveTraits(parameters=("stroke", "ret", "x1", "delay"))

    def start(self, model, q, v):
        return DriveState((RETURN if -q[0] < self.x1 else STROKE, ()), np.zeros(0))

    def mode_name(self, mode):
        return NAMES[mode[0]]

    def force(self, mode, z, q, v):
        return self.stroke if mode[0] == STROKE else -self.ret

    def events(self, mode):
        level, pending = mode
        out = ()
        if level == RETURN and all(k != STROKE for _, k in pending):
            out += (GapCrossing("x1", level=self.x1, direction=1),)
        if pending:
            out += (TimedEvent("switch", time=pending[0][0]),)
        return out

    @staticmethod
    def _due(level, pending, t):
        while pending and pending[0][0] <= t:
            level, pending = pending[0][1], pending[1:]
        return (level, pending)

    def jump(self, mode, z, event, t, q, v):
        level, pending = mode
        if event.name == "x1":
            pending = tuple(sorted(pending + ((t + self.delay, STROKE),)))
        return DriveState(self._due(level, pending, t), z)

    def impact(self, mode, z, t, q, v):
        level, pending = mode
        return DriveState(self._due(level, tuple(sorted(pending + ((t + self.delay, RETURN),))), t), z)


@dataclass(frozen=True)
class Push(Drive):
    """A constant force ``p`` toward the stop: no event, no state."""

    p: float

    traits = DriveTraits(parameters=("p",))

    def start(self, model, q, v):
        return DriveState(0, np.zeros(0))

    def force(self, mode, z, q, v):
        return self.p

    def events(self, mode):
        return ()

    def jump(self, mode, z, event, t, q, v):
        return DriveState(mode, z)

    def impact(self, mode, z, t, q, v):
        return DriveState(mode, z)


@dataclass(frozen=True)
class Lag(TwoLevel):
    """The force lags behind the level of its mode: ``p = z``, ``z' = (P - z) / lag``, ``P = +stroke``
    or ``-ret``, switched on the same rules as :class:`TwoLevel`."""

    lag: float = 0.2

    traits = DriveTraits(parameters=("stroke", "ret", "x1", "lag"), state_size=1)

    def level(self, mode):
        return self.stroke if mode == STROKE else -self.ret

    def start(self, model, q, v):
        mode = RETURN if -q[0] < self.x1 else STROKE
        return DriveState(mode, np.array([self.level(mode)]))

    def force(self, mode, z, q, v):
        return float(z[0])

    def rate(self, mode, z, q, v):
        return np.array([(self.level(mode) - z[0]) / self.lag])


def rigid_closed_form(a_s, a_r, x1, R):
    """The rigid undamped piston's orbit under TwoLevel from energy and restitution (theory §10)."""
    v = math.sqrt(2.0 * x1 * (a_s + a_r) / (1.0 - R * R))
    u1 = math.sqrt(R * R * v * v + 2.0 * a_r * x1)
    return v, (u1 - R * v) / a_r + (u1 + v) / a_s


# -- the independent integration of Lag on the rigid piston -----------------------------------------
def lag_flight(drive, d, R, y, mode, t_max=200.0, rtol=1e-12):
    """Integrate ``q' = w, w' = z - d w, z' = (P - z) / lag`` from ``y = (q, w, z)`` in ``mode`` to the
    next impact (``q`` rising through 0), switching to stroke where ``-q`` rises through ``x1``.
    Returns the time, the state after the impact (``w -> -R w``) and the arrival speed."""
    t = 0.0
    while True:
        P = drive.stroke if mode == STROKE else -drive.ret

        def f(_, y, P=P):
            return [y[1], y[2] - d * y[1], (P - y[2]) / drive.lag]

        def hit(_, y):
            return y[0]

        def out(_, y):
            return -y[0] - drive.x1

        hit.terminal, hit.direction = True, 1
        out.terminal, out.direction = True, 1
        events = [hit, out] if mode == RETURN else [hit]
        sol = solve_ivp(f, (t, t + t_max), y, method="DOP853", rtol=rtol, atol=rtol * 1e-2, events=events)
        t, y = sol.t[-1], sol.y[:, -1]
        if sol.t_events[0].size:
            return t, np.array([0.0, -R * y[1], y[2]]), y[1]
        mode = STROKE


def lag_map(drive, d, R, x):
    """The test's own Poincare map of Lag just after an impact: ``(w, z) -> (w, z)`` and the period."""
    t, y, _ = lag_flight(drive, d, R, np.array([0.0, x[0], x[1]]), RETURN)
    return y[1:], t


# -- a force constant between events ---------------------------------------------------------------
@pytest.mark.parametrize("a_s, a_r, x1, R", [(1.0, 1.0, 1.0, 0.215), (2.0, 0.5, 0.3, 0.0),
                                             (0.7, 3.0, 2.0, 0.8)])
def test_two_level_orbit_is_the_closed_form(a_s, a_r, x1, R):
    o = find_orbit(BarModel(s=10.0, d=0.0, R=R, n_modes=0), TwoLevel(a_s, a_r, x1))
    v, T = rigid_closed_form(a_s, a_r, x1, R)
    assert isinstance(o, PeriodicOrbit) and o.periods == 1 and o.impacts == 1
    assert o.impact_velocity == pytest.approx(v, rel=1e-12)
    assert o.period == pytest.approx(T, rel=1e-12)
    assert o.multipliers[0] == pytest.approx(R * R, abs=1e-8)  # central differences of closed forms
    assert o.admissibility == "admissible" and o.stable == (R < 1.0)
    assert o.switch_velocity == pytest.approx(math.sqrt(R * R * v * v + 2.0 * a_r * x1), rel=1e-12)


def test_two_level_on_a_flexible_bar_is_the_valves_orbit():
    """The same motion as the valve's (no delay), found by the generic shooting problem with
    central differences and by the valve's segment problem with its exact Jacobian."""
    model = BarModel(s=10.0, d=0.05, R=0.215, n_modes=3)
    o = find_orbit(model, TwoLevel(1.0, 1.0, 1.0))
    ref = find_orbit(model, PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0))
    assert o.period == pytest.approx(ref.period, rel=1e-12)
    np.testing.assert_allclose(o.state, ref.state, rtol=0, atol=1e-12)
    np.testing.assert_allclose(o.impact_velocities, ref.impact_velocities, rtol=1e-12)
    np.testing.assert_allclose(o.multipliers, ref.multipliers, rtol=0, atol=1e-6)
    assert o.admissibility == ref.admissibility and o.stable == ref.stable
    t = np.linspace(0.0, o.period, 50)
    np.testing.assert_allclose(o.end_displacement(t), ref.end_displacement(t), rtol=0, atol=1e-11)


def test_simulate_two_level_is_the_valves_run():
    """The generic event loop over the ordinary driver's pieces, and the valve's compiled loop: the
    same impacts and switches."""
    model = BarModel(s=10.0, d=0.05, R=0.215, n_modes=3)
    start = InitialState.rigid(-0.5, 0.3, 3)
    run = simulate(model, TwoLevel(1.0, 1.0, 1.0), start, 60.0)
    ref = simulate(model, PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0), start, 60.0)
    assert isinstance(run, Trajectory) and run.n_impacts == ref.n_impacts > 10
    np.testing.assert_allclose(run.impact_times, ref.impact_times, rtol=0, atol=1e-12)
    np.testing.assert_allclose(run.impact_velocities, ref.impact_velocities, rtol=1e-12)
    assert run.switch_kinds == ref.switch_kinds
    np.testing.assert_allclose(run.switch_times, ref.switch_times, rtol=0, atol=1e-12)
    assert run.final_valve == ref.final_valve


@pytest.mark.parametrize("n_modes", [0, 2])
def test_scheduled_switches_are_the_valves_delay(n_modes):
    """The valve's delayed switches written with the interface's timed events: the orbit is the
    valve's (its exact segment problem), and so is the branch in the delay, whose scheduled times
    the shooting problem makes again at each value (the drive's map at the impact before each
    block)."""
    model = BarModel(s=10.0, d=0.1, R=0.3, n_modes=n_modes)
    o = find_orbit(model, Delayed(1.0, 1.0, 1.0, 0.1))
    ref = find_orbit(model, PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0, delay=0.1))
    assert o.period == pytest.approx(ref.period, rel=1e-12)
    np.testing.assert_allclose(o.multipliers, ref.multipliers, rtol=0, atol=1e-6)
    np.testing.assert_allclose(o.switch_times, ref.switch_times, rtol=0, atol=1e-12)
    branch = continue_orbit(o, "delay", to=0.2)  # (on 2 modes the orbit loses admissibility at 0.218)
    end = branch.orbits[-1]
    assert branch.values[-1] == pytest.approx(0.2) and end.drive.delay == branch.values[-1]
    valve = find_orbit(model, PositionSwitchedDrive(1.0, 1.0, 1.0, delay=end.drive.delay))
    assert end.period == pytest.approx(valve.period, rel=1e-11)
    assert end.impact_velocity == pytest.approx(valve.impact_velocity, rel=1e-11)


def test_continue_two_level_follows_the_closed_form():
    branch = continue_orbit(find_orbit(BarModel(s=10.0, d=0.0, R=0.5, n_modes=0), TwoLevel(1.0, 1.0, 1.0)),
                            "x1", to=1.5)
    assert branch.values[-1] == pytest.approx(1.5) and len(branch.orbits) > 3
    for x1, o in zip(branch.values, branch.orbits, strict=True):
        v, T = rigid_closed_form(1.0, 1.0, x1, 0.5)
        assert o.drive.x1 == x1
        assert o.impact_velocity == pytest.approx(v, rel=1e-10) and o.period == pytest.approx(T, rel=1e-10)


def test_a_constant_push_drops_the_piston_by_energy_and_restitution():
    run = simulate(BarModel(s=10.0, d=0.0, R=0.5, n_modes=0), Push(2.0), InitialState.rigid(-1.0, 0.0), 10.0,
                   max_impacts=5)
    v1 = math.sqrt(2.0 * 2.0 * 1.0)
    np.testing.assert_allclose(run.impact_velocities, v1 * 0.5 ** np.arange(5), rtol=1e-13)
    flights = 2.0 * v1 * 0.5 ** np.arange(1, 5) / 2.0  # up and down again at R^k v1 under p = 2
    np.testing.assert_allclose(np.diff(run.impact_times), flights, rtol=1e-12)
    assert run.switch_kinds == ()
    with pytest.raises(ValueError, match="parameter must be one of"):
        Push(1.0).with_(q=2.0)


def test_the_push_implements_the_required_members_alone():
    """The abstract members of ``Drive`` are what ``Push`` (run above) defines; the other drives here
    define only members of the base."""
    assert {n for n, v in vars(Push).items() if callable(v) and not n.startswith("_")} == \
        set(Drive.__abstractmethods__) == {"start", "force", "events", "jump", "impact"}
    for cls in (TwoLevel, Delayed, Lag):
        own = {n for n, v in vars(cls).items() if callable(v) and not n.startswith("_")} - {"level"}
        assert own <= set(dir(Drive)), cls


# -- a drive with state ----------------------------------------------------------------------------
@pytest.mark.parametrize("d, R", [(0.0, 0.215), (0.3, 0.5)])
def test_simulate_lag_against_an_independent_integration(d, R):
    drive = Lag(1.0, 1.0, 1.0, lag=0.2)
    run = simulate(BarModel(s=10.0, d=d, R=R, n_modes=0), drive, InitialState.rigid(-0.5, 0.0), 40.0)
    y, mode, t0 = np.array([-0.5, 0.0, -1.0]), RETURN, 0.0  # the drive starts in return, z = -ret
    times, speeds = [], []
    while len(times) < run.n_impacts:
        t, y, v = lag_flight(drive, d, R, y, mode)
        t0 += t
        times.append(t0)
        speeds.append(v)
        mode = RETURN
    assert run.n_impacts >= 6
    np.testing.assert_allclose(run.impact_times, times, rtol=0, atol=1e-7)  # LSODA, rtol 1e-10
    np.testing.assert_allclose(run.impact_velocities, speeds, rtol=1e-7)
    assert run.switch_kinds[:3] == ("stroke", "return", "stroke")
    z = run.drive_state(run.impact_times)[0]  # the force at each impact: near the stroke level
    assert z.shape == (run.n_impacts,) and np.all(np.abs(z - 1.0) < 1e-3)


def test_find_orbit_of_the_lag_drive_is_the_fixed_point_of_its_map():
    """Newton on the shooting problem (the state after the impact with the drive's state; central
    differences of integrated flights): the fixed point of the map integrated here, to the flights'
    tolerance; the multipliers against central differences of that map."""
    drive, d, R = Lag(1.0, 1.0, 1.0, lag=0.5), 0.1, 0.3
    o = find_orbit(BarModel(s=10.0, d=d, R=R, n_modes=0), drive)
    x = np.array([o.state[1], o.drive_states[0, 0]])
    image, T = lag_map(drive, d, R, x)
    np.testing.assert_allclose(image, x, rtol=0, atol=1e-8)
    assert o.period == pytest.approx(T, abs=1e-8)
    assert o.impact_velocity == pytest.approx(-x[0] / R, rel=1e-8)
    h = 1e-5
    J = np.column_stack([(lag_map(drive, d, R, x + h * e)[0] - lag_map(drive, d, R, x - h * e)[0]) / (2 * h)
                         for e in np.eye(2)])
    mu = np.linalg.eigvals(J)
    mu = mu[np.argsort(-np.abs(mu))]
    np.testing.assert_allclose(o.multipliers, mu, rtol=0, atol=1e-5)
    assert o.stable and o.trivial_multiplier == 1.0
    # simulate settles on it
    run = simulate(o.model, drive, InitialState.rigid(-0.5, 0.0), 30 * o.period)
    assert run.impact_velocities[-1] == pytest.approx(o.impact_velocity, rel=1e-7)
    assert np.diff(run.impact_times)[-1] == pytest.approx(o.period, rel=1e-7)
    # a guess from the run
    again = find_orbit(o.model, drive, guess=run)
    assert again.period == pytest.approx(o.period, rel=1e-8)


def test_continue_the_lag_drive_in_its_own_parameter():
    model = BarModel(s=10.0, d=0.1, R=0.3, n_modes=0)
    o = find_orbit(model, Lag(1.0, 1.0, 1.0, lag=0.5))
    branch = continue_orbit(o, "lag", to=0.7, step=0.1, max_step=0.2)
    assert branch.values[-1] == pytest.approx(0.7) and branch.status == "reached"
    end = branch.orbits[-1]
    assert end.drive == Lag(1.0, 1.0, 1.0, lag=branch.values[-1])
    for orbit in (branch.orbits[len(branch.orbits) // 2], end):  # each point the fixed point of the map
        x = np.array([orbit.state[1], orbit.drive_states[0, 0]])
        image, T = lag_map(orbit.drive, 0.1, 0.3, x)
        np.testing.assert_allclose(image, x, rtol=0, atol=1e-8)
        assert orbit.period == pytest.approx(T, abs=1e-8)


def test_a_drive_with_state_on_a_flexible_bar():
    """Two flexible modes: simulate against the same equations integrated here (every mode
    ``q_n'' + d q_n' + (s n pi)^2 q_n = z``, the impact on ``c . q`` rising through 0)."""
    model = BarModel(s=3.0, d=0.2, R=0.3, n_modes=2)
    drive = Lag(1.0, 1.0, 1.0, lag=0.3)
    run = simulate(model, drive, InitialState.rigid(-0.5, 0.0, 2), 15.0)
    M, c, w2 = 3, model.end_weights, model.frequencies ** 2
    y, mode, t, times = np.concatenate(([-0.5, 0, 0], [0, 0, 0], [-1.0])), RETURN, 0.0, []
    while t < 15.0 and len(times) < run.n_impacts:
        P = 1.0 if mode == STROKE else -1.0

        def f(_, y, P=P):
            return np.concatenate((y[M:2 * M], y[-1] - 0.2 * y[M:2 * M] - w2 * y[:M], [(P - y[-1]) / 0.3]))

        def hit(_, y):
            return c @ y[:M]

        def out(_, y):
            return -y[0] - 1.0

        hit.terminal, hit.direction, out.terminal, out.direction = True, 1, True, 1
        sol = solve_ivp(f, (t, 15.0), y, method="DOP853", rtol=1e-12, atol=1e-14,
                        events=[hit, out] if mode == RETURN else [hit])
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.t_events[0].size:
            times.append(t)
            y[M:2 * M] *= -0.3
            mode = RETURN
        elif sol.status == 1:
            mode = STROKE
    assert run.n_impacts >= 2
    np.testing.assert_allclose(run.impact_times, times, rtol=0, atol=1e-6)


def test_the_energy_account_of_a_drives_run_closes():
    """The bar's account over the run's flights: the impacts' loss is ``(1 - R^2) v^2 / 2`` per impact
    of the rigid piston (eq. 10), and the drive's work balances the rest to the quadrature's (closed
    forms) or the integrator's (a drive with state) accuracy."""
    model = BarModel(s=10.0, d=0.05, R=0.215, n_modes=0)
    valve = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0, delay=0.2)
    for drive in (valve, TwoLevel(1.0, 1.0, 1.0), Lag(1.0, 1.0, 1.0, lag=0.5)):
        run = simulate(model, drive, InitialState.rigid(-0.5, 0.3), 40.0)
        account = run.energy
        assert run.n_impacts > 5 and account.work > 0.0
        lost = float(np.sum(0.5 * (1.0 - model.R**2) * run.impact_velocities**2))
        assert account.impact_loss == pytest.approx(lost, rel=1e-9)
        records = run.impacts  # one per impact, as a Trajectory's
        assert [r.impact_velocity for r in records] == pytest.approx(list(run.impact_velocities), rel=1e-12)
        assert account.relative_residual < (1e-12 if drive.traits.piecewise_constant else 1e-9)
    flexible = simulate(model.with_(n_modes=3), PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0),
                        InitialState.rigid(-0.5, 0.3, 3), 40.0)
    assert flexible.energy.relative_residual < 1e-12


def test_refusals_name_what_is_missing():
    model = BarModel(s=10.0, d=0.1, R=0.3, n_modes=0)
    with pytest.raises(ValueError, match="instantaneous impact law"):
        simulate(model.with_(impact="wave"), Lag(1.0, 1.0, 1.0), InitialState.rigid(-0.5, 0.0), 5.0)
    with pytest.raises(ValueError, match="not periodic in time"):  # a load's solver alone
        phase_roots(model, Lag(1.0, 1.0, 1.0))
    o = find_orbit(model, TwoLevel(1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="parameter must be one of"):
        continue_orbit(o, "lag", to=1.0)
