"""The oil circuit under the wave and the rod-rock laws: each blow solved with the circuit's
state (theory §11, "The coupled blow").

Checked against independent numbers:

- the rod-rock lattice's coupled blow (a method of steps, chunk by chunk of the round trip) on a rod of
  the wave law's impedance converges, at second order in the cells, to the wave law's coupled window
  (characteristics and one integration of the circuit): two couplings built on different solvers;
- the method of steps against a waveform relaxation of the same lattice and circuit (the whole blow's
  force iterated to a fixed point), on a stepped piston whose first change of impedance shortens the
  chunks;
- against freezing: the pressures change during the blow by what the chambers' compression by the
  piston's travel gives (the circuit driven by the frozen blow's motion: the relaxation's first
  iterate), far beyond the integrator's tolerance;
- the ideal limit (the oil and the openings ``k`` times stiffer, the spool ``k`` times faster, the
  supply held): the runs tend to those of the ideal valve under the same law at first order in ``1/k``;
- the energy accounts over runs with blows: the circuit's (pump work = work on the piston + losses +
  compression + accumulator) to rounding, the piston's (the drive's work = its energy's change + what
  the blows took) to the integrator's tolerance, the energy the lattice's step averages of the force
  drop second order in the cells;
- periodic orbits: the residual, a run restarted on the orbit staying on it, the multipliers of the
  coupled blow's Jacobian against a finite-difference return map of runs (slow).
"""

import numpy as np
import pytest

from impactbar import (
    BarModel,
    BilinearRock,
    InitialState,
    PositionSwitchedDrive,
    RodRock,
    RodSegment,
    continue_orbit,
    find_orbit,
    simulate,
)
from impactbar.drives import DriveState
from impactbar.drives.circuit import Accumulator, Chambers, HydraulicCircuitDrive, Oil, Supply, Valve
from impactbar.laws.rodrock.blow import solve_blow
from impactbar.laws.rodrock.contact import BlowMap
from impactbar.loads import FourierLoad

S = 52.0


def held(k=1.0, ps=1.0, pt=0.03, start=None):
    """A supply held at ``ps``, the oil ``k`` times stiffer and the openings ``k`` times wider."""
    return HydraulicCircuitDrive(
        Chambers(area_ratio=0.5, rear_volume=0.4, front_volume=0.2),
        Valve(switch_out=0.048, coefficient=2.0 * k, switching_time=0.05 / k),
        Supply(pump_flow=None, pressure=ps, hose_volume=1.0, front_coefficient=2.0 * k, tank_pressure=pt),
        Oil(bulk_modulus=70.0 * k, transition_pressure=0.01 / k), start_pressures=start)


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


def rock(length=2.0, cells=None, **kw):
    """A rod of ``length`` piston lengths on a rock of Lundberg's ``alpha = 1.26``, ``gamma = 10``, its
    blows under the circuit ended at the law's window (``driven_end="window"``, unless ``kw`` names
    another end): this file checks the method of steps over that fixed window (its chunks against a
    waveform relaxation, a frozen force, the step averages' energy, a switch crossed inside a long
    blow); the default end, where the piston is free for good, is checked on the example drifter
    (``tests/drives/test_circuit_rock_orbit.py``, ``tests/laws/test_coupled_lattice_end.py``)."""
    kw.setdefault("driven_end", "window")
    return RodRock(segments=[RodSegment(length=length, impedance=1.0)],
                   rock=BilinearRock(k=0.63 * S * S, k_u=6.3 * S * S), feed=0.05, cells_per_piston=cells,
                   **kw)


def test_the_lattice_blow_converges_to_the_wave_window():
    """A rod of the wave law's impedance ``(1 + R)/(1 - R)``, long enough that nothing returns within
    ``2/s``, a blow of ``2/s``: the lattice's coupled blow tends to the wave law's coupled window, the
    piston's momentum and the drive's work at second order in the cells (measured 4.0 per doubling), the
    pressures toward it (6.2e-8 at 128 cells: theory §11)."""
    drive = held()
    s, R = 20.0, 0.3
    q, v = np.zeros(1), np.array([0.35])
    st = DriveState((1, 0, 0, 0), np.array([1.0, 0.6, 1.0, 1.0]))  # the rear chamber filling: a transient
    wave = BarModel(s=s, d=0, R=R, n_modes=0, impact="wave")
    ref = wave.law.driven_contact(wave, drive, st, 0.3, q, v)
    assert ref.record.separations == 0 and abs(ref.drive_state.z[1] - 0.6) > 0.3  # the rear chamber fills
    errors = []
    for cells in (32, 64, 128):
        law = RodRock(segments=[RodSegment(length=1.5, impedance=(1 + R) / (1 - R))],
                      rock=BilinearRock(k=1.0, k_u=10.0), blow_time=2.0 / s, cells_per_piston=cells,
                      driven_end="window")  # (the wave law's window: the blow of 2/s)
        res = law.driven_contact(wave.with_(impact=law), drive, st, 0.3, q, v)
        errors.append((abs(res.v_after[0] - ref.v_after[0]), abs(res.drive_work - ref.drive_work),
                       float(np.max(np.abs(res.drive_state.z - ref.drive_state.z)))))
    e = np.array(errors)
    assert np.all(e[:-1, :2] / e[1:, :2] > 3.5) and np.all(e[:-1, :2] / e[1:, :2] < 4.5)
    assert e[-1, 0] < 1e-9 and e[-1, 1] < 1e-9 and e[-1, 2] == pytest.approx(6.2e-8, rel=0.05)
    assert np.all(e[:-1, 2] > e[1:, 2])


def _relaxed(model, drive, st, t0, q, v, tol=1e-13, max_iter=200):
    """The coupled lattice blow by a waveform relaxation (independent of the method of steps): the
    whole blow's step averages of the force iterated, each round the lattice with the last averages
    (its driven end's arriving waves from the recorded field) and the circuit over the whole blow."""
    law = model.law
    p0 = drive.force(st.mode, st.z, q, v)
    bm = BlowMap(model, FourierLoad(p0, []), t0)
    grid, n = bm.grid, bm.n_max
    dt, Z0 = grid.cell_time, float(grid.Z[0])
    F, G = bm.fields(q, v)
    w0 = -float(model.drive_weights @ q)
    avg = np.full(n, p0)
    for it in range(max_iter):
        blow = solve_blow(grid, F, G, avg, law.rock.k, law.rock.k_u, law.bit_mass, law.feed, t_max=n * dt,
                          n_steps=n, record_field=True)
        arriving = np.empty(n)
        arriving[0] = G[0]
        for k in range(1, n):  # F[0] after step k - 1 is the drive less the wave that arrived
            arriving[k] = blow.field[k, 0] - (avg[k - 1] - arriving[k - 1])
        fl = drive.end_flight(model, st, t0 + dt * np.arange(n + 1), w0, list(-2.0 * arriving / Z0), Z0)
        new = fl.impulses / dt
        change = float(np.max(np.abs(new - avg)))
        avg = new
        if change <= tol * float(np.max(np.abs(avg))):
            return avg, fl, it + 1
    raise AssertionError("the relaxation did not converge")  # pragma: no cover


@pytest.mark.parametrize("piston", [None, (0.25, 0.75)])
def test_method_of_steps_against_a_waveform_relaxation(piston):
    from impactbar.dynamics.stepped import SteppedPiston
    from impactbar.laws.rodrock.coupled import causal_cells

    stepped = None if piston is None else SteppedPiston(list(piston), [1.0, 0.6])
    model = BarModel(s=S, d=0, R=0.0, n_modes=2, impact=rock(1.0, cells=8), piston=stepped)
    drive = pumped()
    q, v = np.zeros(3), np.array([0.35, 0.01, -0.004])
    q[1] = 1e-5
    q[0] -= float(model.end_weights @ q)
    st = DriveState((1, 0, 1, 0), np.array([1.1, 1.05, 1.1, 1.0]))
    res = model.law.driven_contact(model, drive, st, 0.0, q, v)
    grid = BlowMap(model, FourierLoad(0.0, []), 0.0).grid
    assert causal_cells(grid.Z, grid.piston_cells) == (grid.piston_cells if piston is None else 2)
    avg, fl, rounds = _relaxed(model, drive, st, 0.0, q, v)
    assert rounds >= 3  # a fixed point reached in rounds, where the method of steps needs none
    assert np.max(np.abs(res.record._drive - avg)) <= 1e-9 * np.max(np.abs(avg))
    assert np.allclose(res.drive_state.z, fl.state.z, rtol=1e-10, atol=1e-12)


def test_the_blow_against_the_frozen_force():
    """The circuit's pressures change during the blow (here the rear chamber's by 3 % of its level):
    the frozen force of the arrival misses it, and the piston leaves the blow at another speed. The
    change is the chambers' compression by the piston's travel: the circuit driven by the frozen
    blow's motion (a relaxation's first round) gives the coupled blow's pressures to 1e-5 of their
    swing, the force's feedback on the motion being small."""
    model = BarModel(s=S, d=0, R=0.0, n_modes=0, impact=rock(2.0, cells=8))
    drive = pumped()
    q, v = np.zeros(1), np.array([0.34])
    st = DriveState((1, 0, 1, 0), np.array([1.15, 1.15, 1.15, 1.0]))
    res = model.law.driven_contact(model, drive, st, 0.0, q, v)
    lo, hi = (min(p.extremes(1)[0] for p in res.pieces), max(p.extremes(1)[1] for p in res.pieces))
    swing = hi - lo
    assert swing > 0.02 * 1.15
    _, first, _ = _relaxed(model, drive, st, 0.0, q, v, tol=np.inf, max_iter=1)
    assert np.max(np.abs(first.state.z - res.drive_state.z)) < 1e-3 * swing
    p0 = drive.force(st.mode, st.z, q, v)
    _, v_frozen, _, frozen = model.law.contact(model, FourierLoad(p0, []), 0.0, q, v)
    assert abs(res.v_after[0] - v_frozen[0]) > 1e-4  # the integrator's tolerance is 1e-10
    assert abs(res.record.work_on_rock - frozen.work_on_rock) > 1e-4 * frozen.work_on_rock


@pytest.mark.parametrize("law", [rock(2.0, cells=8), rock(2.0, cells=8, driven_end="free"), "wave"])
def test_the_energy_accounts_of_a_run_with_blows(law):
    """The circuit's account closes to rounding; the piston's (its energy's change, the work the drive
    did along its integration, what the blows took) to the integrator's tolerance: 1e-8 at the drive's
    ``rtol = 1e-10``, 2e-10 at ``1e-12`` (measured 1.0e-8 and 2.2e-10 under the rod-rock law, 7.0e-9
    and 1.6e-10 under the wave law; with the blows ended where the piston is free for good, the
    default, 2.1e-7 and 5.0e-9: the same fall with the tolerance, on another run); the records are the
    law's, one a blow."""
    from impactbar.drives import FlightSettings
    from impactbar.simulation.blows import BlowPiece
    from impactbar.simulation.driven import run_stateful

    model = BarModel(s=S, d=0.0, R=0.215, n_modes=1, impact=law)
    drive = pumped()
    residuals = []
    for rtol in (1e-10, 1e-12):
        run = run_stateful(model, drive, np.array([-0.06, 0.0]), np.zeros(2), 0.0, 20.0, 4, InitialState,
                           FlightSettings(method="CVODE", rtol=rtol, atol=1e-2 * rtol))
        assert run.n_impacts == 4 and len(run.impacts) == 4
        assert abs(drive.energy(run)["relative_residual"]) < 1e-13
        residuals.append(run.energy.relative_residual)
        blows = [p for p in run.pieces if isinstance(p, BlowPiece)]
        assert [b.record for b in blows] == list(run.impacts)
        # the pressures and the valve logged through the blows too: at the circuit's steps in each
        h = drive.histories(run)
        for b in blows:
            inside = (h["t"] > b.t0) & (h["t"] < b.t_end)
            assert np.count_nonzero(inside) > 10
            z = b.drive_state(h["t"][inside])
            assert np.array_equal(h["p_r"][inside], z[1]) and np.array_equal(h["x_v"][inside], z[3])
        dropped = [b.account()[0] - b.account()[1] for b in blows]  # the lattice's averages' loss
        assert all(x >= -1e-15 for x in dropped) if law != "wave" else max(map(abs, dropped)) < 1e-10
    free = getattr(law, "driven_end", None) == "free"
    assert residuals[0] < (3e-7 if free else 1.5e-8) and residuals[1] < (7e-9 if free else 5e-10)
    assert residuals[0] / residuals[1] > 20.0  # (the integrator's tolerance, not a term left out)


def test_the_energy_the_step_averages_drop_falls_with_the_cells():
    """``int (p - p_k)^2 dt / Z_0`` over a blow: first order in the cells while a step is longer than
    the oil's relaxation, second order beyond (9.2e-9, 6.7e-9, 3.8e-9, 1.4e-9, 4.3e-10 at 4 to 64
    cells, of a work on the piston of about 5e-3: theory §11)."""
    drive = pumped()
    q, v = np.zeros(1), np.array([0.34])
    st = DriveState((1, 0, 1, 0), np.array([1.15, 1.15, 1.15, 1.0]))
    dropped = []
    for cells in (4, 8, 16, 32, 64):
        model = BarModel(s=S, d=0, R=0.0, n_modes=0, impact=rock(2.0, cells=cells))
        res = model.law.driven_contact(model, drive, st, 0.0, q, v)
        dropped.append(res.drive_work - res.record.blow.drive_work)
        assert res.drive_work == pytest.approx(5e-3, rel=0.1)
    d = np.array(dropped)
    assert np.allclose(d, [9.2e-9, 6.7e-9, 3.8e-9, 1.4e-9, 4.3e-10], rtol=0.05)
    assert np.all(d > 0.0) and np.all(d[:-1] / d[1:] > 1.3) and d[-1] / d[-2] < 0.35


@pytest.mark.parametrize("law", [rock(2.0, cells=4), "wave"])
def test_the_ideal_limit_is_the_ideal_valve_under_the_same_law(law):
    """With the supply held at ``p_s``, the oil and the openings ``k`` times stiffer and the spool
    ``k`` times faster, three impacts from a start at rest tend to those of the valve of theory §10
    (stroke ``p_s (1 - alpha)``, return ``alpha p_s - p_t``, the stroke force held through the blow)
    at first order in ``1/k`` (measured 9.9 and 10.0 per decade)."""
    ps, pt, a = 1.0, 0.03, 0.5
    model = BarModel(s=S, d=0, R=0.215, n_modes=0, impact=law)
    start = InitialState.rigid(-0.06, 0.0)
    ideal = simulate(model, PositionSwitchedDrive(stroke=ps * (1 - a), ret=a * ps - pt, switch_out=0.048),
                     start, 50.0, max_impacts=3)
    errors = []
    for k in (10.0, 100.0, 1000.0):
        run = simulate(model, held(k, ps, pt, start=(ps, ps, ps, 1.0)), start, 50.0, max_impacts=3)
        errors.append((np.max(np.abs(run.impact_times - ideal.impact_times)),
                       np.max(np.abs(run.impact_velocities - ideal.impact_velocities))))
    e = np.array(errors)
    assert np.all(e[:-1] / e[1:] > 8.0) and np.all(e[:-1] / e[1:] < 12.5)
    assert e[-1, 0] < 5e-4 and e[-1, 1] < 3e-5


def test_refusals_name_what_is_missing():
    drive = held(start=(1.0, 1.0, 1.0, 1.0))
    # the wave law's window ending with the end still moving into the rod: its sustained contact is not
    # coupled to the circuit (R = 0: the piston gives the rod all its energy, the stroke pushes on)
    with pytest.raises(ValueError, match="sustained contact"):
        simulate(BarModel(s=S, d=0, R=0.0, n_modes=0, impact="wave"), drive, InitialState.rigid(-0.06, 0.0),
                 5.0)
    # a switch position crossed inside a blow: the valve closed before the arrival (``switch_in``), its
    # opening armed through the blow, which on a rod of 14 piston lengths lasts long enough for the
    # rebounding piston to pass it
    far = rock(14.0, cells=2)
    closing = Valve(switch_out=0.048, coefficient=2.0, switching_time=0.05, switch_in=0.01)
    valve = HydraulicCircuitDrive(drive.chambers, closing, drive.supply, drive.oil,
                                  start_pressures=(1.0, 1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="inside a blow"):
        simulate(BarModel(s=S, d=0, R=0.0, n_modes=0, impact=far), valve, InitialState.rigid(-0.06, 0.0), 5.0)


@pytest.fixture(scope="module", params=["rock", "wave"])
def orbit(request):
    law = rock(2.0, cells=4) if request.param == "rock" else "wave"
    return find_orbit(BarModel(s=S, d=0, R=0.215, n_modes=0, impact=law), pumped())


def test_orbits_under_the_laws(orbit):
    """The operating point under the law: stable, admissible, the residual at the integrator's
    accuracy, its record the law's (a blow solved with the circuit), and a run restarted on it with
    the circuit's state after the blow staying on it (measured 2e-10)."""
    assert orbit.stable and orbit.admissible and orbit.problem.coupled
    problem = orbit.problem
    X = np.asarray(orbit._unknowns, dtype=float)
    assert np.max(np.abs(problem.value(X))) < 1e-9
    (rec,) = orbit.contacts
    assert rec.t0 > 0.0 and rec.duration == pytest.approx(orbit.contact_time)
    assert 0.3 < orbit.impact_velocity < 0.45 and 1.2 < orbit.period < 1.8
    z = orbit.drive_states[0]
    y = orbit.states_after_impact[0]
    d = orbit.drive
    restart = HydraulicCircuitDrive(d.chambers, d.valve, d.supply, d.oil, d.accumulator,
                                    start_pressures=tuple(z))
    run = simulate(orbit.model, restart, InitialState(y[:1], y[1:]), 4.5 * orbit.period)
    assert run.n_impacts == 4
    assert np.allclose(np.diff(run.impact_times), orbit.period, rtol=1e-8)
    assert np.allclose(run.impact_velocities, orbit.impact_velocity, rtol=1e-8)


def test_the_blows_jacobian_against_differences_of_the_return_map(orbit):
    """The shooting Jacobian (the flights' variational equations and the coupled blow's central
    differences) against central differences of the whole return map (flight and blow flown again for
    each step): to 1e-4, the differences' accuracy; the leading multiplier (the supply's slow mode) the
    same."""
    problem = orbit.problem
    X = np.asarray(orbit._unknowns, dtype=float)
    _, J = problem.residual(X)
    problem.variational = False
    try:
        _, Jfd = problem.residual(X)
    finally:
        problem.variational = True
    # A blow that leaves the piston on the stop (the rod-rock law's at its window here) makes the
    # piston's position after it a structural unknown: the flight starts on the stop, its column
    # -e_0; central differences of it straddle the stop, their side off it flown from the gap (as a
    # run flies a gap a blow leaves), so that column is checked as the structure, the rest against
    # the differences.
    on_stop = float(orbit.states_after_impact[0][0]) == 0.0
    cols = slice(1, None) if on_stop else slice(None)
    if on_stop:
        assert np.array_equal(J[:, 0], -np.eye(X.size)[:, 0])
    assert np.allclose(J[:, cols], Jfd[:, cols], rtol=1e-4, atol=1e-4 * np.max(np.abs(J)))
    mu = np.sort(np.abs(np.linalg.eigvals(Jfd + np.eye(X.size))))[::-1]
    assert mu[0] == pytest.approx(abs(orbit.multipliers[0]), rel=1e-4)


def test_a_stepped_piston_on_the_rod_and_rock_under_the_circuit():
    """A stepped piston (theory §12: a heavy head, a light tail) with two modes under the circuit on
    the rod and rock: the chunks of its coupled blows end at the step's echo, the accounts close as
    the uniform piston's (the piston's to the flights' integration, measured 2.1e-8 of its largest
    term here, 4.5e-10 at rtol 1e-12), and two segments of one impedance give the uniform piston's
    run."""
    from impactbar.dynamics.stepped import SteppedPiston

    drive = pumped()
    runs = []
    for piston in (SteppedPiston([0.5, 0.5], [1.0, 1.0]), None, SteppedPiston([0.6, 0.4], [0.8, 1.4])):
        model = BarModel(s=S, d=0.0, R=0.0, n_modes=2, impact=rock(2.0, cells=8), piston=piston)
        run = simulate(model, drive, InitialState.rigid(-0.06, 0.0, 2), 20.0, max_impacts=3)
        assert run.n_impacts == 3 and len(run.impacts) == 3
        assert abs(drive.energy(run)["relative_residual"]) < 1e-13 and run.energy.relative_residual < 5e-8
        runs.append(run)
    assert np.allclose(runs[0].impact_times, runs[1].impact_times, rtol=1e-9)
    assert np.allclose(runs[0].impact_velocities, runs[1].impact_velocities, rtol=1e-8)
    assert np.max(np.abs(runs[2].impact_velocities - runs[1].impact_velocities)) > 1e-3  # another piston


def test_continuation_in_the_pump_flow(orbit):
    """``continue_orbit`` of the operating point under the law in the pump flow: each point an orbit
    (its residual at the integrator's accuracy), the period falling as the pump gives more oil."""
    branch = continue_orbit(orbit, "pump_flow", to=0.075, max_points=3, events=False)
    assert len(branch.orbits) == 3
    for o in branch.orbits:
        X = np.asarray(o._unknowns, dtype=float)
        assert np.max(np.abs(o.problem.value(X))) < 1e-9 and o.stable
    flows = [o.drive.value("pump_flow") for o in branch.orbits]
    periods = [o.period for o in branch.orbits]
    assert flows[-1] > flows[0] and periods[-1] < periods[0]


def test_continuation_on_rock_in_the_rocks_stiffness(orbit):
    """``continue_orbit`` of the operating point on the rock in the rod-rock law's own ``"rock.k"``
    (theory §4d): the stiffness moves and each point is an orbit at its value (the residual of the
    problem built there at the integrator's accuracy)."""
    if orbit.model.law.name == "wave":
        pytest.skip("the wave law has no rock")
    k0 = orbit.model.law.rock.k
    branch = continue_orbit(orbit, "rock.k", to=1.5 * k0, max_points=3, events=False)
    ks = [o.model.law.rock.k for o in branch.orbits]
    assert len(ks) == 3 and ks[0] == k0 < ks[1] < ks[2]
    for o in branch.orbits:
        X = np.asarray(o._unknowns, dtype=float)
        assert np.max(np.abs(o.problem.value(X))) < 1e-9 and o.stable
