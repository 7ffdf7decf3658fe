"""The drifter's oil circuit as a drive with state: ``HydraulicCircuitDrive``.

Checked against independent numbers:

- one flight of CVODE against scipy's ``Radau`` on the same compiled right-hand side (rtol 1e-12);
- the energy account: the oil's work on the rigid, undamped piston against the piston's kinetic
  energy at the flights' ends, the accumulator's and the supply hose's terms against their closed
  forms in the supply pressure at the ends (the quadratures' sum closes by construction; these do not);
- the ideal limit (bulk modulus and flow coefficients times ``k``, switching time over ``k``, the supply
  held): the orbit converges to the ideal valve's (theory §10) at first order in ``1/k``;
- the operating point: the shooting Jacobian from the variational equations against central
  differences of the same flights, and a run restarted on the orbit staying on it.
"""

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import circuit_field_reference as K
from impactbar import BarModel, InitialState, PositionSwitchedDrive, continue_orbit, find_orbit, simulate
from impactbar.drives import DriveState
from impactbar.drives.circuit import Accumulator, Chambers, HydraulicCircuitDrive, Oil, Supply, Valve
from impactbar.drives.circuit.flight import circuit_flight
from impactbar.drives.circuit.settings import CircuitFlightSettings
from impactbar.drives.flight import ARRIVAL

RIGID = BarModel(s=52, d=0, R=0.215, n_modes=0)


def pumped(**changes):
    """A pump-fed drifter (units of theory §11): about 70 L/min, 20 MPa, a 5.6 kg piston."""
    kw = dict(pump_flow=0.07, precharge=0.5, volume=2.0)
    kw.update(changes)
    return HydraulicCircuitDrive(
        Chambers(area_ratio=0.5, rear_volume=0.4, front_volume=0.2),
        Valve(switch_out=0.048, coefficient=2.0, switching_time=0.05),
        Supply(pump_flow=kw["pump_flow"], hose_volume=1.0, front_coefficient=2.0, tank_pressure=0.03),
        Oil(bulk_modulus=70.0, transition_pressure=0.01),
        Accumulator(precharge=kw["precharge"], volume=kw["volume"]))


def held(k=1.0, ps=1.0, pt=0.03):
    """A supply held at ``ps``, the oil ``k`` times stiffer and the openings ``k`` times wider."""
    return HydraulicCircuitDrive(
        Chambers(area_ratio=0.5, rear_volume=0.4, front_volume=0.2),
        Valve(switch_out=0.048, coefficient=2.0 * k, switching_time=0.05 / k),
        Supply(pump_flow=None, pressure=ps, hose_volume=1.0, front_coefficient=2.0 * k, tank_pressure=pt),
        Oil(bulk_modulus=70.0 * k, transition_pressure=0.01 / k))


@pytest.fixture(scope="module")
def orbit():
    return find_orbit(RIGID, pumped())


def test_flight_against_radau():
    drive = pumped()
    q, v = np.array([-0.08]), np.array([0.0])  # out past the switch, at rest: the stroke
    state = DriveState((1, 0, 1, 0), np.array([0.9, 0.9, 0.9, 1.0]))
    fl = circuit_flight(drive, RIGID, state, 0.0, q, v, 50.0)
    assert fl.end == ARRIVAL
    par = K.preset_par(drive, RIGID, state.mode)
    n = 2 + 4 + K.N_ENERGY

    def f(t, y):
        out = np.empty(n)
        K.rhs(t, y, out, par)
        return out

    def arrival(t, y):
        return y[0]

    arrival.terminal, arrival.direction = True, 1
    y0 = np.concatenate((q, v, state.z, np.zeros(K.N_ENERGY)))
    ref = solve_ivp(f, (0.0, 50.0), y0, method="Radau", rtol=1e-12, atol=1e-14, events=arrival)
    assert ref.status == 1
    assert fl.t == pytest.approx(ref.t_events[0][0], rel=1e-8)
    assert np.allclose(fl.v, ref.y_events[0][0][1], rtol=1e-8)
    assert np.allclose(fl.z, ref.y_events[0][0][2:6], rtol=1e-8, atol=1e-10)
    assert np.allclose(fl.piece.energies(), ref.y_events[0][0][6:], rtol=1e-7, atol=1e-10)


def test_energy_account():
    drive = pumped()
    run = simulate(RIGID, drive, InitialState.rigid(0.0, 0.0), 12.0)
    assert run.n_impacts >= 5
    acc = drive.energy(run)
    assert abs(acc["relative_residual"]) < 1e-10
    V0, p0, npol = 2.0, 0.5, 1.4
    beta, Vs = 70.0, 1.0

    def gas(p):  # int p dV_a from p0: V_a = V0 (1 - (p0 / p)^(1/n)) above the pre-charge
        p = max(p, p0)
        return V0 * p0 ** (1 / npol) * (p ** (1 - 1 / npol) - p0 ** (1 - 1 / npol)) / (npol - 1)

    pieces = [run.pieces[j] for j in range(len(run.pieces)) if hasattr(run.pieces[j], "energies")]
    E = np.sum([p.energies() for p in pieces], axis=0)
    ps0, ps1 = pieces[0].y[0, 4], pieces[-1].y[-1, 4]
    assert E[7] == pytest.approx(gas(ps1) - gas(ps0), rel=1e-8)
    assert E[6] == pytest.approx(Vs / (2 * beta) * (ps1 ** 2 - ps0 ** 2), rel=1e-8)
    for p in pieces:  # the rigid, undamped piston: the oil's work is its kinetic energy's change
        ke = 0.5 * (p.y[-1, 1] ** 2 - p.y[0, 1] ** 2)
        assert p.energies()[1] == pytest.approx(ke, rel=1e-8, abs=1e-12)


def test_ideal_limit_first_order():
    ps, pt, a = 1.0, 0.03, 0.5
    ideal = find_orbit(RIGID, PositionSwitchedDrive(stroke=ps * (1 - a), ret=a * ps - pt, switch_out=0.048))
    v = math.sqrt(2 * 0.048 * (ps - pt) / (1 - 0.215 ** 2))  # theory §10's closed form
    assert ideal.impact_velocity == pytest.approx(v, rel=1e-12)
    errs = []
    for k in (10.0, 100.0):
        o = find_orbit(RIGID, held(k))
        errs.append((abs(o.period - ideal.period), abs(o.impact_velocity - v)))
        assert o.multipliers[0] == pytest.approx(0.215 ** 2, rel=2 / k)  # R^2, the p_s direction gone
        assert o.stable
    assert errs[1][0] < 1e-3 and errs[1][1] < 2e-4
    for j in range(2):  # first order: ten times closer for ten times stiffer
        assert 7.0 < errs[0][j] / errs[1][j] < 13.0


def test_orbit_outputs(orbit):
    assert orbit.stable and orbit.admissible
    assert 1.0 < orbit.period < 2.0 and 0.2 < orbit.impact_velocity < 0.5
    ps = orbit.drive_states[0][2]
    assert 0.5 < ps < 1.5  # the supply settles where the pump's oil is used


def test_variational_jacobian_against_differences(orbit):
    problem = orbit._problem
    assert problem.variational
    X = np.asarray(orbit._unknowns, dtype=float)
    r, J = problem.residual(X)
    assert np.max(np.abs(r)) < 1e-8
    problem.variational = False
    try:
        _, Jfd = problem.residual(X)
    finally:
        problem.variational = True
    assert np.allclose(J, Jfd, rtol=1e-4, atol=1e-5 * np.max(np.abs(J)))
    mu = np.sort(np.abs(np.linalg.eigvals(Jfd + np.eye(X.size))))[::-1]
    assert mu[0] == pytest.approx(abs(orbit.multipliers[0]), rel=1e-4)


def test_second_integration_agrees(orbit):
    """The same orbit solved again with CVODE at rtol 1e-12 (the default 1e-10), from this one."""
    from impactbar.drives import FlightSettings
    from impactbar.orbits.driven import ShootingProblem, orbit_of

    problem = ShootingProblem(RIGID, orbit.drive, 1, FlightSettings(method="CVODE", rtol=1e-12, atol=1e-14))
    fine = orbit_of(problem, problem.solve(problem.initial(orbit, 1e-13, 20), 1e-13, 20))
    assert fine.period == pytest.approx(orbit.period, rel=1e-8)
    assert fine.impact_velocity == pytest.approx(orbit.impact_velocity, rel=1e-8)
    assert fine.drive_states[0] == pytest.approx(orbit.drive_states[0], rel=1e-8)
    # the multipliers from the variational equations (measured: 5e-10 apart; period 4e-10, impact
    # velocity 1e-9, pressures 1.2e-9)
    assert np.allclose(fine.multipliers[:2], orbit.multipliers[:2], rtol=1e-6, atol=1e-8)


def test_simulate_stays_on_orbit(orbit):
    z = orbit.drive_states[0]
    q, v = orbit.states_after_impact[0]
    restart = HydraulicCircuitDrive(*(getattr(orbit.drive, f) for f in ("chambers", "valve", "supply", "oil",
                                                                          "accumulator")),
                                    start_pressures=tuple(z))
    run = simulate(RIGID, restart, InitialState.rigid(0.0, v), 100.5 * orbit.period)
    assert run.n_impacts == 100
    assert np.allclose(np.diff(run.impact_times), orbit.period, rtol=1e-8)
    assert np.allclose(run.impact_velocities, orbit.impact_velocity, rtol=1e-8)


def test_continuation_options_trade_flights_not_orbits(orbit, monkeypatch):
    """The continuation's own numerics where the flights are integrated (the parameter's column by a
    forward difference, a chord step first) against the way before (``forward_lambda=False,
    chord=False``): the same points, the same orbits to the corrector's tolerance, fewer flights
    (measured: 220 against 276 to 0.51)."""
    from impactbar.continuation.driven import continue_driven
    from impactbar.continuation.one_parameter import _detect
    from impactbar.drives.circuit import flight as F

    flights = [0]
    fly = F._integrate_compiled if F._compiled_driver() is not None else F._integrate_binding

    def counted(*a):
        flights[0] += 1
        return fly(*a)

    monkeypatch.setattr(F, fly.__name__, counted)
    out = []
    for kw in ({}, {"forward_lambda": False, "chord": False}):
        flights[0] = 0
        b = continue_driven(orbit, "precharge", 0.51, _detect, events=False, **kw)
        out.append((b, flights[0]))
    (now, n_now), (before, n_before) = out
    assert str(now.status) == str(before.status) == "reached"
    # the same points while the step control decides alike (a corrector that just fails in one and
    # not the other cuts a step there: the rounding of another CPU moved the twelfth point of 14),
    # and at every parameter value both reached the same orbit
    common = [(o.period, before.orbits[j].period) for v, o in zip(now.values, now.orbits, strict=True)
              for j in np.flatnonzero(np.isclose(before.values, v, rtol=1e-9, atol=0.0))]
    assert len(common) >= 0.7 * len(now.values), (now.values, before.values)
    assert np.allclose(*np.transpose(common), rtol=1e-8)
    assert n_now < 0.9 * n_before, (n_now, n_before)


@pytest.mark.slow  # 20 s: a start from rest and about ten continuation points of about 1 s
def test_continuation_locates_the_accumulator_emptying():
    start = find_orbit(RIGID, pumped(precharge=1.11))
    branch = continue_orbit(start, "precharge", to=1.116)
    assert str(branch.status) == "reached"
    (ev,) = [e for e in branch.events if e.kind == "border-collision"]
    assert ev.surface == "accumulator" and 1.111 < ev.value < 1.115
    # at the event the least supply pressure over the period is the pre-charge: sampled densely here
    problem = ev.orbit.problem
    lows = [np.min(p.drive_state(np.linspace(p.t0, p.t_end, 2001))[2])
            for p in problem.flights(problem.unknowns(ev.orbit))]
    assert min(lows) == pytest.approx(ev.value, abs=1e-6)
    # the multipliers jump there: the accumulator's compliance leaves the supply node for a while
    before = [o for o in branch.orbits if o.drive.value("precharge") < ev.value]
    after = [o for o in branch.orbits if o.drive.value("precharge") > ev.value + 2e-3]
    assert abs(before[-1].multipliers[0]) > 0.95 > 0.93 > abs(after[0].multipliers[0])


def test_bad_input():
    with pytest.raises(ValueError, match="precharge must be below the relief pressure"):
        HydraulicCircuitDrive(*(getattr(pumped(), f) for f in ("chambers", "valve")),
                              Supply(pump_flow=0.07, hose_volume=1.0, front_coefficient=2.0,
                                     tank_pressure=0.03, relief_pressure=0.4, relief_coefficient=1.0),
                              Oil(70.0, 0.01), Accumulator(precharge=0.5, volume=2.0))
    with pytest.raises(ValueError, match="area_ratio"):
        Chambers(area_ratio=1.2, rear_volume=0.4, front_volume=0.2)
    with pytest.raises(ValueError, match="exactly one of pump_flow"):
        Supply(pump_flow=0.07, pressure=1.0, hose_volume=1.0, front_coefficient=2.0, tank_pressure=0.03)
    with pytest.raises(ValueError, match="rear chamber empties"):  # the stroke overruns a small chamber
        simulate(RIGID, pumped().with_(rear_volume=0.02), InitialState.rigid(0.0, 0.0), 10.0)
    with pytest.raises(ValueError, match="singular"):  # a pump far too small: the supply collapses
        find_orbit(RIGID, pumped(pump_flow=0.001))
    # a start above the oil's bulk modulus (70 here) ran 265 s before failing
    with pytest.raises(ValueError, match="below the oil's bulk modulus 70"):
        dataclasses.replace(pumped(), start_pressures=(1e8, 1e8, 1e8))


def test_a_failing_flight_says_why_in_its_error_only(capsys):
    """CVODE's failure reaches the caller as the ValueError's reason, not printed on stdout (the
    binding prints its error handler's message there)."""
    with pytest.raises(ValueError, match="could not be integrated \\(Convergence tests failed"):
        circuit_flight(pumped(), RIGID, DriveState((1, 0, 1, 0), np.array([0.9, 0.9, -50.0, 1.0])), 0.0,
                       np.array([-0.08]), np.array([0.0]), 50.0)
    assert "cvHandleFailure" not in capsys.readouterr().out


@pytest.mark.slow  # 40 s: a start from rest and some thirty continuation points
def test_continuation_locates_the_relief_opening():
    drive = pumped(pump_flow=0.0725).with_(relief_pressure=1.25, relief_coefficient=1.0)
    branch = continue_orbit(find_orbit(RIGID, drive), "pump_flow", to=0.075)
    (ev,) = [e for e in branch.events if e.kind == "border-collision"]
    assert ev.surface == "relief" and 0.0729 < ev.value < 0.0735  # measured: 0.0731904
    # at the event the greatest supply pressure over the period is the relief pressure (sampled)
    problem = ev.orbit.problem
    highs = [np.max(p.drive_state(np.linspace(p.t0, p.t_end, 2001))[2])
             for p in problem.flights(problem.unknowns(ev.orbit))]
    assert max(highs) == pytest.approx(1.25, abs=1e-6)
    # the relief flow stiffens the supply node: the slow multiplier drops (0.913 -> below 0.6)
    after = [o for o in branch.orbits if o.drive.value("pump_flow") > ev.value + 1e-3]
    assert abs(after[0].multipliers[0]) < 0.8 < 0.9 < abs(ev.orbit.multipliers[0])


@pytest.mark.parametrize("compiled", [True, False])
def test_a_flight_that_starts_on_the_relief_level_sees_it_close_at_once(compiled):
    """A flight that starts with the supply exactly at the relief pressure, the relief open (the event
    that ended the last flight), and the supply falling: the relief closes at once. CVODE leaves an
    event function that is 0 at the start unwatched until it moves off 0 by more than its first
    increment's rounding, and a pressure of 1.25 does not move by 1e-20: the crossing back was
    missed, and the flight went on with the relief open below its setting (oil back from the tank)."""
    drive = pumped(pump_flow=0.0725).with_(relief_pressure=1.25, relief_coefficient=1.0)
    model = BarModel(s=52, d=0, R=0.215, n_modes=0)
    z = np.array([1.2, 0.03, 1.25, 1.0])  # the valve open onto an empty rear chamber: p_s falls
    assert drive.rate((1, 0, 1, 1), z, np.array([-0.06]), np.array([0.0]), model)[2] < 0.0
    q, v = np.array([-0.06]), np.array([0.0])
    f = circuit_flight(drive, model, DriveState((1, 0, 1, 1), z), 3.0, q, v, 4.0,
                       CircuitFlightSettings(compiled=compiled))
    assert [e.name for e in f.events] == ["relief"]
    assert f.t - 3.0 < 1e-9
