"""Periodic orbits under the rod-rock law (theory §4d): find_orbit on the contact step's map, whose
flights start off the shank (``q_0`` among the unknowns), with its finite-difference Jacobian."""

import numpy as np
import pytest

import impactbar as ib


@pytest.fixture(scope="module")
def case():
    """A piston on a stiffer rod (impedance 2) over a soft rock: a stable motion of two blows in two
    load periods, reached by simulation and then by find_orbit from it."""
    law = ib.RodRock(segments=[ib.RodSegment(length=2.0, impedance=2.0)],
                     rock=ib.BilinearRock(k=20.0, k_u=200.0), feed=0.0)
    model = ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law)
    load = ib.CosineLoad(0.3, 1.0)
    tr = ib.simulate(model, load, ib.InitialState.rigid(-0.1, 0.0, n_modes=4), 200.0)
    orbit = ib.find_orbit(model, load, impacts=2, periods=2, guess=tr)
    return model, load, tr, orbit


def test_orbit_is_the_simulated_motion(case):
    """The orbit's blows are the settled simulation's, and a simulation started on the orbit stays on
    it (impact phases and velocities to 1e-9): the orbit is a fixed point of the simulator's map."""
    model, load, tr, orbit = case
    assert orbit.admissible and orbit.stable
    np.testing.assert_allclose(np.sort(orbit.phases), np.sort(tr.impact_times[-2:] % (2 * np.pi)),
                               atol=1e-3)
    T = model.law.window(model)
    y = orbit.states_after_impact[0]
    M = model.n_modes + 1
    t0 = orbit.impact_times[0] + T
    run = ib.simulate(model, load, ib.InitialState(modal_displacement=y[:M], modal_velocity=y[M:]),
                      t0 + 4 * np.pi * 3, t0=t0)
    ph = np.mod(run.impact_times, 2 * np.pi)
    np.testing.assert_allclose(ph[:6], np.tile(np.roll(orbit.phases, -1), 3), atol=1e-9)
    np.testing.assert_allclose(run.impact_velocities[:6], np.tile(np.roll(orbit.impact_velocities, -1), 3),
                               rtol=1e-9)


def test_orbit_advance_and_energy_per_period(case):
    """On the orbit the rod advances per blow by the blow's permanent penetration (the stop of the next
    flight), and the energy drawn from the drive per period is the work on rock plus the losses: the
    rod's residual energy discarded between blows, the grid's, the damping, less the feed's and the
    modal projections' share (a run of one period started on the orbit)."""
    model, load, _, orbit = case
    blows = orbit.contacts
    assert len(blows) == 2
    for b in blows:
        assert b.stop_advance == b.permanent_penetration > 0.0
    T = model.law.window(model)
    M = model.n_modes + 1
    y = orbit.states_after_impact[0]
    t0 = orbit.impact_times[0] + T
    run = ib.simulate(model, load, ib.InitialState(modal_displacement=y[:M], modal_velocity=y[M:]),
                      t0 + 4 * np.pi, t0=t0)
    e = run.energy
    assert abs(e.final - e.initial) < 1e-8 * e.work  # periodic
    rock = sum(b.work_on_rock for b in run.impacts)
    assert rock == pytest.approx(sum(b.work_on_rock for b in blows), rel=1e-8)
    losses = sum(b.rod_loss for b in run.impacts)
    assert e.work == pytest.approx(rock + losses + e.damping_loss - e.projection
                                   + (e.final - e.initial), rel=1e-10)
    for b in run.impacts:  # the piston's loss in a blow is the rock's work and the rod's loss
        assert b.energy_out == pytest.approx(b.work_on_rock + b.rod_loss, rel=1e-10)
    assert 0.0 < rock / e.work < 1.0


def test_finite_difference_jacobian_of_the_blow_map(case):
    """The impact map's finite-difference Jacobian against a step ten times larger (the map is smooth
    here: no return to the shank inside the blow): agreement to 1e-6."""
    model, load, _, orbit = case
    law = model.law
    t, y = orbit.impact_times[1], orbit.states_before_impact[1]
    _, J, Jt = law.impact_map(model, load, t, y)
    h = 1e-5

    def step(tt, yy):
        rec = law.blow(model, load, tt, yy)
        return np.concatenate((rec.q_after, rec.v_after))

    for j in (1, 3, 6):
        e = np.zeros(y.size)
        e[j] = h
        col = (step(t, y + e) - step(t, y - e)) / (2 * h)
        np.testing.assert_allclose(J[:, j], col, atol=1e-6 * max(1.0, np.max(np.abs(col))))


def test_continuation_in_the_drive_under_the_rod_rock_law(case):
    """``continue_orbit`` follows the rod-rock orbit in ``p0`` (the segment problem's unknowns include
    ``q_0``: the continuation sizes its arclength weights by the problem's own size); each point is
    an orbit of the problem at its ``p0`` (residual zero)."""
    from impactbar.orbits.multi_impact import _Segments, _unknowns_from

    model, load, _, orbit = case
    branch = ib.continue_orbit(orbit, "p0", 0.35, max_points=4)
    assert len(branch.orbits) == 4 and branch.values[-1] > 0.3
    o = branch.orbits[-1]
    problem = _Segments(model, o.load, 2, 2)
    F, _, _ = problem.evaluate(_unknowns_from(problem, o.impact_times, o.states_after_impact),
                               jacobian=False)
    assert np.max(np.abs(F)) < 1e-9


def test_momentum_per_period(case):
    """The piston's momentum over a period of the orbit, independent of the energy account: the
    blows' impulses on the shank (their force histories) equal the drive's impulse ``2 pi n p0`` less
    the damping's, ``d`` times the piston's rigid displacement over the flights (no damping inside a
    blow)."""
    model, load, _, orbit = case
    impulse = sum(c.blow.junction_impulse(0) for c in orbit.contacts)
    flights = float(np.sum(np.roll(orbit.states_before_impact, -1, axis=0)[:, 0]
                           - orbit.states_after_impact[:, 0]))
    expected = 2 * np.pi * orbit.periods * load.p0 - model.d * flights
    assert impulse == pytest.approx(expected, rel=1e-9)
