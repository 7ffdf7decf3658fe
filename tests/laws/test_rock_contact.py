"""The rod-and-rock law's contact step in the simulator (theory §4d): the blow from a modal state with
the drive acting, against the wave law's exact window and against single blows; simulate's energy
account and per-blow records."""

import math

import numpy as np
import pytest

import impactbar as ib
from impactbar.laws.rodrock.contact import RockContact
from impactbar.laws.rodrock.step import rock_contact
from impactbar.laws.wave.impact import wave_impact


def _law(length=3.0, impedance=1.0, k=50.0, gamma=10.0, bit_mass=0.0, feed=0.0):
    return ib.RodRock(segments=[ib.RodSegment(length=length, impedance=impedance)],
                      rock=ib.BilinearRock(k=k, k_u=gamma * k), bit_mass=bit_mass, feed=feed)


def _arrival(N, seed=1):
    """A flexible piston arriving at the shank (``u(1) = 0``) with rigid velocity 1."""
    rng = np.random.default_rng(seed)
    n = 1.0 + np.arange(N + 1)
    q = rng.normal(size=N + 1) * 0.002 / n**2
    v = rng.normal(size=N + 1) * 0.05 / n**2
    v[0] = 1.0
    return q, v


@pytest.mark.parametrize("N", [4, 12])
def test_contact_window_against_the_wave_law(N):
    """A rod of impedance ``(1 + R)/(1 - R)`` long enough that the bit's reflection returns after
    ``2/s`` is the wave law's stop over its window: the state at ``2/s`` (flexible piston, a strong
    drive, averaged over each cell step) against the wave law's exact characteristics, second order in
    the cells (the step average and the cell averages of the fields at impact), and the drive's work
    and the rod energy likewise."""
    s, R = 6.0, 0.4
    law = _law(length=2.5, impedance=(1 + R) / (1 - R), k=5.0)
    model = ib.BarModel(s=s, d=0.0, R=R, n_modes=N, impact=law)
    wave = ib.BarModel(s=s, d=0.0, R=R, n_modes=N, impact="wave")
    load = ib.CosineLoad(0.8, 2.0)
    q, v = _arrival(N)
    q[0] -= model.end_weights @ q
    t0 = 0.7
    w = wave_impact(wave, load, t0, q, v)
    errors = []
    for cells in (64, 128):
        rc = rock_contact(model, load, t0, q, v, cells_per_piston=cells, duration=2.5 / s)
        qa, va = rc.state_at(2.0 / s)
        errors.append(max(np.max(np.abs(qa - w.q_after)) / np.max(np.abs(w.q_after)),
                          np.max(np.abs(va - w.v_after)) / np.max(np.abs(w.v_after))))
        drive_work, out, field = rc.account(2.0 / s)
        assert drive_work == pytest.approx(w.drive_work, rel=2e-6 * (128 / cells) ** 2)
        assert out == pytest.approx(w.rod_energy, rel=1e-4 * (128 / cells) ** 2)
        assert rc.energy_before + drive_work == pytest.approx(field + out, rel=1e-13)
    assert errors[1] < 2e-5
    assert 3.5 < errors[0] / errors[1] < 4.5  # second order


@pytest.mark.parametrize("N", [4, 12])
@pytest.mark.parametrize("load", [ib.CosineLoad(0.8, 2.0), ib.SquareWaveLoad(2.0, 1.3),
                                  ib.FourierLoad(0.3, [0.5, 0.2j, 0.1])], ids=["cosine", "square", "fourier"])
def test_exact_contact_window_is_the_wave_laws(N, load):
    """The simulator's exact blow (the default: the piston's modal state and the drive as exact
    pieces, the state projected on the modes in closed form) over the wave law's window on a rod of
    impedance ``(1 + R)/(1 - R)`` whose bit's reflection returns after it: the wave law's independent
    characteristics solution (its jumps located, the drive integrated exactly) to rounding, state,
    the drive's work and the rod's energy, under a cosine, a square wave (a jump in the window for
    ``t0 = 0.7``? no: its jumps at 0 and ``1.3 pi``) and three harmonics."""
    s, R = 6.0, 0.4
    law = _law(length=2.5, impedance=(1 + R) / (1 - R), k=5.0)
    model = ib.BarModel(s=s, d=0.0, R=R, n_modes=N, impact=law)
    wave = ib.BarModel(s=s, d=0.0, R=R, n_modes=N, impact="wave")
    q, v = _arrival(N)
    q[0] -= model.end_weights @ q
    t0 = 0.7
    w = wave_impact(wave, load, t0, q, v)
    rc = rock_contact(model, load, t0, q, v, duration=2.5 / s)
    assert rc.blow.method == "exact"
    qa, va = rc.state_at(2.0 / s)
    assert np.max(np.abs(qa - w.q_after)) <= 1e-13 * np.max(np.abs(w.q_after))
    assert np.max(np.abs(va - w.v_after)) <= 1e-13 * np.max(np.abs(w.v_after))
    drive_work, out, field = rc.account(2.0 / s)
    assert drive_work == pytest.approx(w.drive_work, rel=1e-13)
    assert out == pytest.approx(w.rod_energy, rel=1e-13)
    assert rc.energy_before + drive_work == pytest.approx(field + out, rel=1e-13)


def test_contact_without_drive_is_the_single_blow():
    """No drive, a rigid piston, the blow followed as long as the single blow: the contact step's blow
    is :func:`single_blow`'s (exact, and on the lattice with the same cells), and the piston leaves
    with its rebound velocity."""
    law = _law(length=2.0, k=20.0, bit_mass=0.3, feed=0.5)
    model = ib.BarModel(s=4.0, d=0.0, R=0.0, n_modes=0, impact=law)
    zero = ib.CosineLoad(0.0, 0.0)
    for cells in (None, 8):
        if cells is None:
            b = ib.single_blow(model, 1.3, method="exact", t_max=5.0)
        else:
            b = ib.single_blow(model, 1.3, method="lattice", cells_per_piston=cells)
        rc = rock_contact(model, zero, 1.0, [0.0], [1.3], duration=b.duration, cells_per_piston=cells)
        assert rc.blow.method == b.method
        assert rc.duration == b.duration
        for name in ("work_on_rock", "efficiency", "permanent_penetration", "piston_energy",
                     "rebound_velocity"):
            assert getattr(rc, name) == pytest.approx(getattr(b, name), rel=1e-13, abs=1e-15)
        assert rc.v_after[0] == pytest.approx(b.rebound_velocity, rel=1e-13)
        assert rc.drive_work == 0.0
        assert rc.stop_advance == b.permanent_penetration


def _run(N=8, d=0.05, t_end=40.0, **kw):
    law = _law(**kw)
    model = ib.BarModel(s=10.0, d=d, R=0.0, n_modes=N, impact=law)
    return ib.simulate(model, ib.CosineLoad(0.5, 1.0), ib.InitialState.rigid(-0.1, 0.0, n_modes=N), t_end)


@pytest.mark.parametrize("kw", [{}, {"feed": 0.3, "bit_mass": 0.2, "length": 1.5}])
def test_simulate_energy_account_and_per_blow_records(kw):
    """``simulate`` under the rod-rock law: the run's energy account closes (drive work = piston energy
    change + damping + the energy the piston lost to rod and rock, less the projections), the loss is
    the blows' ``energy_out``, each blow's own account closes (work on rock + the rod's residual +
    returned to the piston = available), and the per-blow records are the law's."""
    tr = _run(**kw)
    blows = tr.impacts
    assert len(blows) >= 3
    e = tr.energy
    assert e.relative_residual < 1e-10
    # (the last blow may be cut by the run's end)
    assert e.impact_loss == pytest.approx(
        sum(b.account(min(tr.t_end - b.t0, b.duration))[1] for b in blows), rel=1e-12)
    for b in blows:
        assert isinstance(b, RockContact)
        assert b.energy_error < 1e-12
        assert 0.0 < b.efficiency <= 1.0 and b.work_on_rock > 0.0
        assert b.permanent_penetration > 0.0
        assert b.energy_out == pytest.approx(b.energy_before + b.drive_work - b.piston_energy, rel=1e-12)
    # each flight starts where the blow left the piston, off the advanced shank
    for b, t in zip(blows, tr.impact_times, strict=True):
        assert b.t0 == t
        if t + b.duration > tr.t_end:
            continue
        Q, V = tr.modal_state(np.array([t + b.duration]))
        np.testing.assert_allclose(V[:, 0], b.v_after, rtol=1e-9, atol=1e-12)
        assert tr.end_displacement(t + b.duration) <= 0.0


def test_states_inside_a_blow_and_a_run_ending_in_one():
    """Inside a blow the trajectory's state is the blow's at the last cell step (the end on the shank
    while in contact); a run that ends inside a blow ends there with its account closed."""
    tr = _run(t_end=40.0)
    b = tr.impacts[1]
    law_t = b.t0 + 0.5 * b.duration
    q, v = b.state_at(0.0)
    np.testing.assert_array_equal(q, b.q_before)
    q1, v1 = b.state_at(0.01)
    assert abs(float(tr.model.end_weights @ q1)) < 1e-12  # pressed on the shank
    tr2 = _run(t_end=law_t)
    assert tr2.t_end == pytest.approx(law_t)
    assert tr2.energy.relative_residual < 1e-10


def test_law_blow_is_the_contact_record():
    """``RodRock.blow`` (per-blow output of an arrival state) is the contact step's record."""
    law = _law()
    model = ib.BarModel(s=10.0, d=0.0, R=0.0, n_modes=3, impact=law)
    load = ib.CosineLoad(0.5, 1.0)
    q, v = _arrival(3)
    rec = law.blow(model, load, 0.3, np.concatenate((q, v)))
    q[0] -= model.end_weights @ q
    ref = rock_contact(model, load, 0.3, q, v)
    assert rec.work_on_rock == ref.work_on_rock and math.isfinite(rec.work_on_rock)


def _two_blows(tau, feed, s=8.0, k=40.0, gamma=10.0, length=3.0, cells=16):
    """Blow 1 of a rigid piston at 1 on a 3-piston-length rod (``alpha = 1.25``); the drive then pulls
    the piston back (``-1/tau`` for ``tau``) and pushes it (``+1/tau``): blow 2 comes about
    ``(1 + sqrt 2) tau`` later. Blow 2 from the piston's exact fields at blow 1's end (the law's
    ``4/s + 2 sum of the travel times``) with the rod at rest and the shank at its rest position
    (the law's assumption), and with the rod's waves and the bit's motion carried (both on fresh rock).
    Returns the work on rock of blow 2, ``(rest, carried)``."""
    from impactbar.laws.rodrock.blow import blow_grid, solve_blow

    grid = blow_grid(s, [length], [1.0], [1.0], cells)
    n_p, dt = grid.piston_cells, grid.cell_time
    F, G = np.zeros(grid.Z.size), np.zeros(grid.Z.size)
    F[:n_p], G[:n_p] = 0.5 * s, -0.5 * s
    T = 4.0 * tau + 40.0 * (1 + length) / s
    n = math.ceil(T / dt)
    t = dt * (np.arange(n) + 0.5)
    drive = np.where(t < tau, -1.0 / tau, 1.0 / tau)
    par = (k, gamma * k, 0.0, feed)
    sep = 2.0 * (1.0 + length) / s
    m = math.ceil((4.0 + 2.0 * length) / s / dt - 1e-9)  # the law's blow: 4/s + 2 travel
    b1 = solve_blow(grid, F, G, drive, *par, t_max=m * dt, n_steps=m)
    assert b1.gap > 0.0  # the piston has left
    (Fp, Gp), (Fr, Gr) = b1.piston_waves, b1.rod_waves
    rest_gap = b1.gap + b1.shank_displacement - b1.permanent_penetration
    kw = {"t_max": (n - m) * dt, "separation_time": sep}
    rest = solve_blow(grid, np.concatenate((Fp, 0 * Fr)), np.concatenate((Gp, 0 * Gr)), drive[m:], *par,
                      gap=max(rest_gap, 0.0), **kw)
    carried = solve_blow(grid, np.concatenate((Fp, Fr)), np.concatenate((Gp, Gr)), drive[m:], *par,
                         gap=b1.gap, bit_state=(b1.penetrations[-1] - b1.permanent_penetration,
                                                b1.bit_velocity), **kw)
    assert rest.energy_error < 1e-12
    r0 = feed * feed / (2 * gamma * k)
    return rest.work_on_rock - r0, carried.work_on_rock - r0


@pytest.mark.parametrize(("tau", "feed", "lo", "hi"),
                         [(0.5, 0.2, -0.03, -0.01), (8.0, 0.2, -0.17, -0.14), (1.0, 1.0, -0.25, -0.23)])
def test_rest_between_blows_against_carried_waves(tau, feed, lo, hi):
    """The error of resting the rod on the rock between blows (the figures of the theory page,
    section 4d): against carrying the rod's residual waves (a quarter of the blow's energy here) into
    the next blow, the next blow's work on rock is low by 2 % when it comes soon (the piston back
    after ~1.2 load-time units, ``tau = 0.5``) and by 15 % after a long gap (``tau = 8``), feed 0.2;
    at feed 1 by up to 24 %."""
    rest, carried = _two_blows(tau, feed)
    assert lo < (rest - carried) / carried < hi


def test_compiled_contact_matches_the_numpy_loop():
    """The compiled blow kernel with a drive, an initial gap and a fresh-rock bit state against its
    numpy reference (``use_reference("rock.blow")``)."""
    from impactbar.dynamics.implementations import use_reference

    with use_reference("rock.blow"):
        ref = _two_blows(2.0, 0.5)
    fast = _two_blows(2.0, 0.5)
    np.testing.assert_allclose(fast, ref, rtol=1e-12)


@pytest.mark.parametrize("impact", ["paper", "wave", "rodrock", "stepped-wave"])
def test_impact_state_is_the_maps_state(impact):
    """``NewtonStart.impact_state`` (the orbit solver's residuals: one blow, no finite differences;
    the default for a law without the ability) is ``impact_map``'s ``y_plus`` to the bit, under every
    law."""
    from impactbar.laws.abilities import newton_start

    piston = ib.SteppedPiston([0.3, 0.7], [2.0, 1.0]) if impact == "stepped-wave" else None
    law = _law(length=2.0, impedance=2.0) if impact == "rodrock" else impact.replace("stepped-", "")
    model = ib.BarModel(s=10.0, d=0.1, R=0.4, n_modes=3, impact=law, piston=piston)
    q, v = _arrival(3)
    q[0] -= model.end_weights @ q
    y = np.concatenate((q, v))
    load = ib.CosineLoad(0.3, 1.0)
    y_plus = model.law.impact_map(model, load, 0.9, y)[0]
    np.testing.assert_array_equal(newton_start(model.law).impact_state(model, load, 0.9, y), y_plus)
