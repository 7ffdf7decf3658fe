"""A stepped piston under the rod-rock law in the simulator (theory §4d, §12): its modal state to
the cells of its segments' impedances at impact and back after the blow (``_stepped_maps``), checked
against the uniform piston's closed forms, against the lattice's free flight (which carries the
segments by characteristics, independently of the modes) and against single blows; simulate's
energy account and a periodic orbit that the simulator keeps."""

import numpy as np
import pytest

import impactbar as ib
from impactbar.laws.rodrock.blow import solve_blow
from impactbar.laws.rodrock.contact import (
    BlowMap,
    _field_basis,
    _modal,
    _projection,
    _stepped_maps,
)
from impactbar.laws.rodrock.step import rock_contact

#: three segments whose boundaries (0.3, 0.75) fall on every grid of 20 * 2^j cells
THREE = ib.SteppedPiston([0.3, 0.45, 0.25], [1.0, 0.5, 2.0])


def _law(length=1.0, impedance=1.0, k=20.0, gamma=10.0, **kw):
    return ib.RodRock(segments=[ib.RodSegment(length=length, impedance=impedance)],
                      rock=ib.BilinearRock(k=k, k_u=gamma * k), **kw)


@pytest.mark.parametrize("first", [0.5, 0.25])
def test_an_even_split_has_the_uniform_pistons_maps(first):
    """Two segments of one section are the uniform piston: the maps from brentq's modes equal the
    cosine series' closed forms (``_field_basis``, ``_projection``) to rounding."""
    s, n_p, M = 7.0, 16, 7
    A, f, Pv, Pq = _stepped_maps(s, ib.SteppedPiston([first, 1.0 - first], [1.0, 1.0]), n_p, M)
    A0, f0 = _field_basis(s, n_p, M)
    Pv0, Pq0 = _projection(s, n_p, M)
    np.testing.assert_allclose(A, A0, atol=1e-10)
    np.testing.assert_allclose(f, f0, atol=1e-13)
    np.testing.assert_allclose(Pv, Pv0, atol=1e-13)
    np.testing.assert_allclose(Pq, Pq0, atol=1e-13)


def _free_flight(cells, p=0.7, tau=0.6, N=5, s=4.0, static=True):
    """A three-segment piston in a random modal state at impact, flying free (the shank far away)
    under a constant drive ``p`` for ``tau`` on the lattice; returns the lattice's piston waves, the
    maps' waves of the exact modal solution at ``tau`` and the lattice's waves projected on the modes
    against that modal state (the largest difference over ``(q, q')``)."""
    model = ib.BarModel(s=s, d=0.0, R=0.0, n_modes=N, impact=_law(), piston=THREE)
    rng = np.random.default_rng(3)
    n = 1.0 + np.arange(N + 1)
    q, v = rng.normal(size=N + 1) * 0.01 / n**2, rng.normal(size=N + 1) * 0.1 / n**2
    bm = BlowMap(model, ib.CosineLoad(p, 0.0), 0.0, cells_per_piston=cells)
    if not static:
        bm.p_end = 0.0
    F, G = bm.fields(q, v)
    dt = bm.grid.cell_time
    j = round(tau / dt)
    assert abs(j * dt - tau) < 1e-12
    b = solve_blow(bm.grid, F, G, np.full(j, p), *bm.params, t_max=j * dt, n_steps=j, gap=100.0)
    assert b.gap > 99.0  # never near the shank
    # the modal equations q_n'' + w_n^2 q_n = p, exactly
    w = model.frequencies[1:]
    qs = p / w**2
    qe = np.concatenate(([q[0] + v[0] * tau + 0.5 * p * tau**2],
                         qs + (q[1:] - qs) * np.cos(w * tau) + v[1:] / w * np.sin(w * tau)))
    ve = np.concatenate(([v[0] + p * tau], -(q[1:] - qs) * w * np.sin(w * tau) + v[1:] * np.cos(w * tau)))
    Fe, Ge = bm.fields(qe, ve)
    qa, va = _modal(model, cells, b, float(model.end_weights @ qe))
    err = max(np.max(np.abs(qa - qe)), np.max(np.abs(va - ve)))
    return b.piston_waves, (Fe[:cells], Ge[:cells]), err


def test_free_flight_on_the_lattice_is_the_modal_flight():
    """The lattice carries a free piston's cell averages exactly (whole cells a step, the steps'
    scattering pointwise, the drive constant), independently of the modes: under a constant drive
    the modes dropped stay at their static deflection, so the lattice's waves after the flight are
    the maps' waves of the exact modal solution, static correction included, to rounding; without
    the correction they are off by a quarter of the waves. Projected back, the modal state is the
    exact one to second order in the cells."""
    errs = []
    for cells in (20, 40, 80):
        (F, G), (Fe, Ge), err = _free_flight(cells)
        scale = float(np.max(np.abs(Fe)))
        tol = 1e-13 * scale * cells
        assert np.max(np.abs(F - Fe)) < tol and np.max(np.abs(G - Ge)) < tol
        errs.append(err)
    assert errs[-1] < 1e-4
    assert 3.8 < errs[0] / errs[1] < 4.2 and 3.8 < errs[1] / errs[2] < 4.2
    (F, G), (Fe, Ge), _ = _free_flight(20, static=False)
    assert np.max(np.abs(F - Fe)) > 0.1 * np.max(np.abs(Fe))


def test_the_fields_energy_is_the_modal_energy_with_the_static_correction():
    """The cells' wave energy at impact against the modes' energy ``1/2 sum kappa_n (q_n'^2 + w_n^2
    q_n^2)`` plus the static correction's, computed independently of the cells: the inertia-relief
    strain energy ``int p^2 (1 - m)^2 / (2 s^2 mu)`` less the kept modes' ``p^2 kappa_n / (2 w_n^2)``;
    second order in the cells."""
    N, s, p = 4, 3.0, 0.9
    model = ib.BarModel(s=s, d=0.0, R=0.0, n_modes=N, impact=_law(), piston=THREE)
    rng = np.random.default_rng(5)
    q, v = rng.normal(size=N + 1) * 0.02, rng.normal(size=N + 1) * 0.2
    kappa, w = model.drive_weights, model.frequencies
    # int_0^1 (1 - m)^2 / mu dx segment by segment: m linear in each, slope mu
    mu, ls = THREE.mass_per_length, THREE.lengths
    m0 = np.concatenate(([0.0], np.cumsum(mu * ls)[:-1]))
    m1 = m0 + mu * ls
    relief = float(np.sum(((1 - m0) ** 3 - (1 - m1) ** 3) / (3.0 * mu * mu))) / (2.0 * s * s)
    expected = (0.5 * float(kappa @ v**2) + 0.5 * float(kappa[1:] @ (w[1:] * q[1:]) ** 2)
                + p * p * (relief - 0.5 * float(np.sum(kappa[1:] / w[1:] ** 2))))
    errs = []
    for cells in (80, 160):
        bm = BlowMap(model, ib.CosineLoad(p, 0.0), 0.0, cells_per_piston=cells)
        F, G = bm.fields(q, v)
        Z = bm.grid.Z[:cells]
        E = float(np.sum((F[:cells] ** 2 + G[:cells] ** 2) / Z)) * bm.grid.cell_time
        errs.append(abs(E - expected) / expected)
    assert errs[1] < 5e-4
    assert 3.5 < errs[0] / errs[1] < 4.5


def test_a_rigid_arrival_is_the_single_blow():
    """No drive, the piston rigid at impact: the contact step's blow is :func:`single_blow`'s on
    the lattice of the same grid (the model's stepped piston taken by default), and the piston leaves
    with its rebound velocity; the exact blow of the model's piston is the one of ``piston=``."""
    law = _law(length=2.0, k=20.0, bit_mass=0.3, feed=0.5)
    model = ib.BarModel(s=4.0, d=0.0, R=0.0, n_modes=6, impact=law, piston=THREE)
    z = np.zeros(7)
    v = z.copy()
    v[0] = 1.3
    for method in ("lattice", "exact"):
        if method == "lattice":
            b = ib.single_blow(model, 1.3, method="lattice")
            cells = b.piston_cells
        else:
            b = ib.single_blow(model, 1.3, method="exact", t_max=6.0)
            cells = None
        rc = rock_contact(model, ib.CosineLoad(0.0, 0.0), 1.0, z, v, duration=b.duration,
                          cells_per_piston=cells)
        assert rc.blow.method == method and rc.duration == b.duration
        for name in ("work_on_rock", "efficiency", "permanent_penetration", "piston_energy",
                     "rebound_velocity"):
            assert getattr(rc, name) == pytest.approx(getattr(b, name), rel=1e-12, abs=1e-15)
        assert rc.v_after[0] == pytest.approx(b.rebound_velocity, rel=1e-12)
    uniform = model.with_(piston=None)
    no_feed = law.with_parameter("feed", 0.0)
    e1 = ib.single_blow(model.with_(impact=no_feed), 1.0, method="exact")
    e2 = ib.single_blow(uniform.with_(impact=no_feed), 1.0, method="exact", piston=THREE)
    assert e1.efficiency == e2.efficiency and e1.rebound_velocity == e2.rebound_velocity
    with pytest.raises(ValueError, match="the model's is"):
        ib.single_blow(model, 1.0, piston=ib.SteppedPiston([0.5, 0.5], [1.0, 2.0]))


def _stepped_model(N=4, d=0.3):
    law = _law(length=2.0, impedance=2.0, k=20.0)
    return ib.BarModel(s=10.0, d=d, R=0.0, n_modes=N, impact=law,
                       piston=ib.SteppedPiston([0.6, 0.4], [1.0, 2.0]))


def test_simulate_a_stepped_piston_keeps_its_energy_account():
    """``simulate`` with a stepped piston under the rod-rock law: the run's energy account closes,
    the loss is the blows' ``energy_out``, and each flight starts where its blow left the piston."""
    model = _stepped_model(N=6, d=0.05)
    tr = ib.simulate(model, ib.CosineLoad(0.5, 1.0), ib.InitialState.rigid(-0.1, 0.0, n_modes=6), 30.0)
    assert len(tr.impacts) >= 8
    assert tr.energy.relative_residual < 1e-10
    assert tr.energy.impact_loss == pytest.approx(
        sum(b.account(min(tr.t_end - b.t0, b.duration))[1] for b in tr.impacts), rel=1e-12)
    for b in tr.impacts:
        assert b.energy_error < 1e-12 and 0.0 < b.efficiency <= 1.0
        if b.t0 + b.duration < tr.t_end:
            _, V = tr.modal_state(np.array([b.t0 + b.duration]))
            np.testing.assert_allclose(V[:, 0], b.v_after, rtol=1e-9, atol=1e-12)


def test_a_stepped_pistons_orbit_is_the_settled_motion():
    """A heavy-headed piston (its struck end twice the tail's section) on a stiff rod and a soft rock
    settles to one blow a period; find_orbit from the run finds it, stable, and a run started on it
    stays on it (phases and velocities to 1e-9)."""
    model = _stepped_model()
    load = ib.CosineLoad(0.3, 1.0)
    tr = ib.simulate(model, load, ib.InitialState.rigid(-0.1, 0.0, n_modes=4), 600.0)
    orbit = ib.find_orbit(model, load, impacts=1, periods=1, guess=tr)
    assert orbit.admissible and orbit.stable
    np.testing.assert_allclose(tr.impact_times[-3:] % (2 * np.pi), orbit.phases[0], atol=1e-6)
    y = orbit.states_after_impact[0]
    M = model.n_modes + 1
    t0 = orbit.impact_times[0] + model.law.window(model)
    run = ib.simulate(model, load, ib.InitialState(modal_displacement=y[:M], modal_velocity=y[M:]),
                      t0 + 2 * np.pi * 4, t0=t0)
    np.testing.assert_allclose(np.mod(run.impact_times, 2 * np.pi), orbit.phases[0], atol=1e-9)
    np.testing.assert_allclose(run.impact_velocities, orbit.impact_velocities[0], rtol=1e-9)
    # followed in the rock's stiffness: the branch's end is the orbit found there afresh
    branch = ib.continue_orbit(orbit, "rock.k", 24.0)
    assert branch.status == "reached"
    there = model.with_(impact=model.law.with_parameter("rock.k", 24.0))
    fresh = ib.find_orbit(there, load, impacts=1, periods=1, guess=tr)
    assert branch.orbits[-1].impact_velocities[0] == pytest.approx(fresh.impact_velocities[0], rel=1e-8)
    # the head's section against the uniform piston's: not the same motion
    uniform = ib.find_orbit(model.with_(piston=None), load, impacts=1, periods=1, guess=tr)
    assert abs(uniform.impact_velocities[0] - orbit.impact_velocities[0]) > 1e-3


@pytest.mark.parametrize("piston, bit_mass, feed", [(None, 0.0, 0.0), (THREE, 0.3, 0.5)])
def test_the_impact_maps_lean_blow_is_the_contact_record(piston, bit_mass, feed):
    """``BlowMap.__call__`` (the impact map's blows, without their record) gives the state after the
    blow of :meth:`BlowMap.contact`'s record, for a uniform and a stepped piston, with a bit mass and
    a feed."""
    law = _law(length=2.0, impedance=2.0, bit_mass=bit_mass, feed=feed)
    model = ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law, piston=piston)
    rng = np.random.default_rng(1)
    y = np.concatenate((rng.normal(size=5) * 0.001, [1.2], rng.normal(size=4) * 0.05))
    bm = BlowMap(model, ib.CosineLoad(0.3, 1.0), 0.7)
    q = y[:5].copy()
    q[0] -= model.end_weights @ q
    rec = bm.contact(q, y[5:])
    assert rec.blow.permanent_penetration > 0.0 and rec.blow.gap > 0.0  # a blow that left the shank
    np.testing.assert_array_equal(bm(y), np.concatenate((rec.q_after, rec.v_after)))


def test_the_simulators_cells_converge_to_the_exact_orbit_and_are_checked():
    """The simulator's exact blows (the default) against its lattice: ``RodRock(cells_per_piston=...)``
    sets the lattice's grid, and an orbit's impact velocities on it converge to the exact blows'
    orbit at second order (its errors fall about four times per doubling of the cells, 2.3e-5 at the
    default 8: the figures of RodRock's docstring and theory §4d), the default grid the commensurate
    8; a count out of range is refused by name."""
    load = ib.CosineLoad(0.3, 1.0)
    orbits = []
    for cells in (None, 8, 16, 32):
        law = _law(length=2.0, impedance=2.0, cells_per_piston=cells)
        model = ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law)
        start = ib.InitialState.rigid(-0.1, 0.0, n_modes=4)
        guess = orbits[-1] if orbits else ib.simulate(model, load, start, 200.0)
        orbits.append(ib.find_orbit(model, load, 2, 2, guess=guess))
    assert BlowMap(model.with_(impact=_law(length=2.0, impedance=2.0)), load, 0.0).grid.piston_cells == 8
    assert orbits[0].contacts[0].blow.method == "exact" and orbits[1].contacts[0].blow.method == "lattice"
    v = np.array([o.impact_velocities for o in orbits])
    e = np.max(np.abs(v[1:] - v[0]), axis=1)
    assert e[0] == pytest.approx(2.3e-5, rel=0.05) and 3.0 < e[0] / e[1] < 4.5 and 3.5 < e[1] / e[2] < 4.5
    for bad in (0, 5000, 2.5):
        with pytest.raises(ValueError, match="cells_per_piston"):
            _law(cells_per_piston=bad)
