"""The simulator under the wave impact law (theory §4b): periodic orbits reproduced impact by
impact, convergence to a stable orbit, the energy account, and the per-impact force waves."""

import math

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, InitialState, SquareWaveLoad, periodic_orbits, simulate

TWO_PI = 2 * math.pi


def orbit_start(orbit):
    """The orbit's state at the end of its contact window, as an initial state at that time."""
    M = orbit.model.n_modes + 1
    y = orbit.state_after_impact
    return InitialState(y[:M], y[M:]), orbit.phase + 2 / orbit.model.s


@pytest.mark.parametrize("load", [CosineLoad(0.3, 1.0), SquareWaveLoad(1.0, 1.3)])
def test_orbit_reproduced_impact_by_impact(load):
    model = BarModel(s=10.0, d=0.005, R=0.5, n_modes=4, impact="wave")
    for orbit in periodic_orbits(model, load):
        if not orbit.admissible:
            continue
        init, t0 = orbit_start(orbit)
        tr = simulate(model, load, init, t0 + 2.5 * TWO_PI, t0=t0)
        # two periods: even an unstable orbit is followed to ~1e-9 (|mu| ~ 10 per period)
        np.testing.assert_allclose(tr.impact_times[:2], orbit.phase + TWO_PI * np.arange(1, 3),
                                   rtol=0, atol=1e-8)
        np.testing.assert_allclose(tr.impact_velocities[:2], orbit.impact_velocity, rtol=1e-7)
        assert tr.impacts[0].rod_energy == pytest.approx(orbit.impact.rod_energy, rel=1e-7)


def test_converges_to_the_stable_orbit():
    """A perturbed stable orbit returns to it (its multipliers are at most 0.47 here; the flexible
    ones about ``R e^{-pi d}``), where under eq. 10 the flexible perturbation would barely decay."""
    model = BarModel(s=20.0, d=0.01, R=0.3, n_modes=3, impact="wave")
    load = CosineLoad(0.5, 1.0)  # inside the stable band
    stable = [o for o in periodic_orbits(model, load) if o.stable]
    assert len(stable) == 1
    o = stable[0]
    init, t0 = orbit_start(o)
    kick = np.r_[0.0, 1e-3, -2e-3, 1e-3]
    tr = simulate(model, load, InitialState(init.modal_displacement, init.modal_velocity + kick),
                  t0 + 40 * TWO_PI, t0=t0)
    assert tr.n_impacts == 40
    first = abs(tr.impact_velocities[0] - o.impact_velocity)
    assert first > 1e-5
    np.testing.assert_allclose(np.mod(tr.impact_times[-3:], TWO_PI), o.phase, atol=1e-9)
    np.testing.assert_allclose(tr.impact_velocities[-3:], o.impact_velocity, rtol=1e-9)


@pytest.mark.parametrize("load", [CosineLoad(0.8, 1.0), SquareWaveLoad(3.0, 1.4)])
def test_energy_account(load):
    """``work = (final - initial) + damping + rod energy - projection`` (the projection of each
    window's exact field on the modes kept), with windows where contact is lost and regained, and a
    run that ends inside a window."""
    model = BarModel(s=6.0, d=0.02, R=0.4, n_modes=6, impact="wave")
    init = InitialState(np.r_[-0.3, 0.01 * np.arange(6)], np.r_[0.0, 0.05 * np.arange(6)])
    tr = simulate(model, load, init, 12 * TWO_PI + 0.01)
    assert tr.n_impacts >= 10
    assert len(tr.impacts) == tr.n_impacts
    acc = tr.energy
    assert abs(acc.relative_residual) < 1e-8
    last = tr.impacts[-1]
    rod = sum(w.rod_energy for w in tr.impacts[:-1])
    rod += last.account(min(tr.t_end - tr.impact_times[-1], last.duration))[1]
    assert acc.impact_loss == pytest.approx(rod, rel=1e-12)
    assert any(w.separations for w in tr.impacts)


def test_positions_from_the_rod_end():
    """Inside a window the end sits on the rod end (or off it by the gap); after it the flight
    starts with the end exactly there."""
    model = BarModel(s=8.0, d=0.0, R=0.5, n_modes=4, impact="wave")
    tr = simulate(model, CosineLoad(0.4, 1.0), InitialState.rigid(-0.2, 0.5, n_modes=4), 20.0)
    assert tr.n_impacts >= 2
    for t, w in zip(tr.impact_times, tr.impacts, strict=True):
        inside = t + np.linspace(0, w.duration, 9)[:-1]
        inside = inside[inside <= tr.t_end]
        u = tr.end_displacement(inside)
        assert np.all(u <= 1e-12)
        if w.separations == 0:
            np.testing.assert_allclose(u, 0.0, atol=1e-12)
    u = tr.end_displacement(np.linspace(tr.t0, tr.t_end, 2001))
    assert np.all(u <= 1e-10)


def test_run_ending_at_a_window_end():
    """``t_end`` at the end of a contact window, to rounding of the absolute times."""
    model = BarModel(s=10.0, d=0.005, R=0.5, n_modes=3, impact="wave")
    load = CosineLoad(0.3, 1.0)
    o = next(o for o in periodic_orbits(model, load) if o.admissible)
    init, t0 = orbit_start(o)
    tr = simulate(model, load, init, t0 + TWO_PI, t0=t0)
    assert tr.n_impacts == 1
    np.testing.assert_allclose(tr.final_state.modal_velocity, init.modal_velocity, rtol=1e-8, atol=1e-10)
    assert abs(tr.energy.relative_residual) < 1e-9


def test_compiled_window_matches_the_characteristics_solver(rng):
    """The kernel's contact window (no separation) against :func:`wave_impact`: the same verdict on
    separation and the same post-contact state, over random states, loads and wave speeds (windows
    longer than the load period and jumps of the square wave in both halves included)."""
    from impactbar import FourierLoad, wave_impact
    from impactbar.laws.wave import _window as K
    from impactbar.laws.wave.law import _GL20_W, _GL20_X
    from wave_reference import random_state

    for trial in range(60):
        N = int(rng.integers(0, 8))
        s = float(rng.choice([0.4, 2.0, 10.0, 40.0]))
        R = float(rng.uniform(0, 0.95))
        model = BarModel(s=s, d=0.0, R=R, n_modes=N)
        load = [CosineLoad(rng.uniform(-1, 3), rng.uniform(0, 3), int(rng.integers(1, 4))),
                SquareWaveLoad(rng.uniform(0.1, 3), rng.uniform(1, 2)),
                FourierLoad(0.5, [0.3 + 0.2j, -0.4, 0.1j])][trial % 3]
        q, v = random_state(rng, model, [0.02, 1.0][trial % 2])
        v[0] += 2.0  # arriving at 3
        c = model.end_weights
        t0 = float(rng.uniform(0, 20))
        D = load.kernel_view
        rate = float(np.max(D.ks)) / s if D.kind == 0 else 0.0
        qa, va = np.empty(N + 1), np.empty(N + 1)
        ok = K.wave_window(D, s, R, c, rate, t0, q, v, _GL20_X, _GL20_W, qa, va)
        imp = wave_impact(model, load, t0, q, v)
        assert ok == (imp.separations == 0)
        if ok:
            np.testing.assert_allclose(qa, imp.q_after, rtol=1e-12, atol=1e-14 * np.abs(q).max())
            np.testing.assert_allclose(va, imp.v_after, rtol=1e-12, atol=1e-13)


def test_compiled_separating_window_matches_the_characteristics_solver(rng):
    """The kernel's window with separation (``_separation.wave_contact``) against :func:`wave_impact`,
    the reference: the same contact intervals and the same post-contact state, over random states
    (arrivals down to grazing speed), loads and wave speeds (windows longer than the load's period,
    and square-wave jumps in both halves, included)."""
    from impactbar import FourierLoad, wave_impact
    from impactbar.laws.wave import _separation as WK
    from impactbar.laws.wave.law import _GL20_W, _GL20_X
    from wave_reference import random_state

    separating = 0
    for trial in range(90):
        N = int(rng.integers(0, 9))
        s = float(rng.choice([0.25, 0.4, 2.0, 10.0, 40.0]))
        R = float(rng.uniform(0, 0.95))
        model = BarModel(s=s, d=0.0, R=R, n_modes=N)
        load = [CosineLoad(rng.uniform(-1, 3), rng.uniform(0, 3), int(rng.integers(1, 4))),
                SquareWaveLoad(rng.uniform(0.1, 3), rng.uniform(1, 2)),
                FourierLoad(0.5, [0.3 + 0.2j, -0.4, 0.1j])][trial % 3]
        q, v = random_state(rng, model, [0.02, 1.0, 0.3][trial % 3])
        v[0] += rng.uniform(0.0, 3.0) - 1.0  # arriving at 0..3
        t0 = float(rng.uniform(0, 20))
        D = load.kernel_view
        rate = float(np.max(D.ks)) / s if D.kind == 0 else 0.0
        qa, va = np.empty(N + 1), np.empty(N + 1)
        contact = np.empty((WK.MAX_INTERVALS, 2))
        n = WK.wave_contact(D, s, R, rate, t0, q, v, _GL20_X, _GL20_W, qa, va, contact)
        imp = wave_impact(model, load, t0, q, v)
        assert n == len(imp.contact)
        separating += imp.separations > 0
        np.testing.assert_allclose(contact[:n] / s, imp.contact, rtol=0, atol=1e-13 / s)
        np.testing.assert_allclose(qa, imp.q_after, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(va, imp.v_after, rtol=1e-10, atol=1e-12)
    assert separating >= 20  # the case this kernel exists for


@pytest.mark.parametrize("preset", ["hydraulic-drill", "pneumatic-drill"])
def test_separating_windows_compiled_as_in_python(preset, monkeypatch):
    """A run of a drill preset with the compiled separating windows (no call of the Python solver)
    against the same run with the reference of ``"simulate.wave_separation"``: the same impacts,
    impact velocities, transmitted stress peaks and final state."""
    import sys

    from impactbar import physical
    from impactbar.dynamics.implementations import use_reference

    D = sys.modules["impactbar.laws.wave.impact"]
    h = physical.preset(preset)
    model = h.model.with_(impact="wave")
    start = InitialState.rigid(-0.05, 0.0, n_modes=model.n_modes)
    ref_impact = D.wave_impact
    # 64 periods: the sustained contact (theory §4b) replaced the chained windows of the presses
    periods = 64
    with use_reference("simulate.wave_separation"):
        ref = simulate(model, h.load, start, periods * TWO_PI)

    def refused(*args):
        raise AssertionError("the Python solver was called")

    monkeypatch.setattr(D, "wave_impact", refused)
    tr = simulate(model, h.load, start, periods * TWO_PI)
    monkeypatch.setattr(D, "wave_impact", ref_impact)
    assert tr.n_impacts == ref.n_impacts > 20
    np.testing.assert_allclose(tr.impact_times, ref.impact_times, rtol=0, atol=1e-10)
    np.testing.assert_allclose(tr.impact_velocities, ref.impact_velocities, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(tr.final_state.modal_velocity, ref.final_state.modal_velocity,
                               rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(tr.final_state.modal_displacement, ref.final_state.modal_displacement,
                               rtol=1e-10, atol=1e-12)
    sep = [i for i, imp in enumerate(ref.impacts) if imp.separations > 0]
    if preset == "hydraulic-drill":
        assert len(sep) >= 1  # a separating window was taken by the kernel (the sustained contact
        # took the others, which were chained windows of the presses)
    for i in sep:
        assert tr.impacts[i].peak_rod_stress == pytest.approx(ref.impacts[i].peak_rod_stress, rel=1e-10)
        np.testing.assert_allclose(tr.impacts[i].contact, ref.impacts[i].contact, rtol=0, atol=1e-12)


@pytest.mark.parametrize("s", [0.03, 0.012])
def test_compiled_windows_spanning_many_load_periods(s):
    """A window ``2/s`` covering 10 to 26 periods of a square wave (20 to 52 jumps): both compiled
    windows take every jump (the one without separation once kept only 16), as :func:`wave_impact`."""
    from impactbar import wave_impact
    from impactbar.laws.wave import _separation as WK
    from impactbar.laws.wave import _window as K
    from impactbar.laws.wave.law import _GL20_W, _GL20_X

    model = BarModel(s=s, d=0.0, R=0.5, n_modes=2)
    load = SquareWaveLoad(2.0, 1.5)
    D = load.kernel_view
    for v0 in (1000.0, 5.0):  # held in contact, then separating
        q, v = np.zeros(3), np.array([v0, 0.0, 0.0])
        imp = wave_impact(model, load, 0.3, q, v)
        qa, va = np.empty(3), np.empty(3)
        ok = K.wave_window(D, s, 0.5, model.end_weights, 0.0, 0.3, q, v, _GL20_X, _GL20_W, qa, va)
        assert ok == (imp.separations == 0) == (v0 > 100)
        if not ok:
            n = WK.wave_contact(D, s, 0.5, 0.0, 0.3, q, v, _GL20_X, _GL20_W, qa, va,
                                np.empty((WK.MAX_INTERVALS, 2)))
            assert n == len(imp.contact) > 1
        np.testing.assert_allclose(qa, imp.q_after, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(va, imp.v_after, rtol=1e-10, atol=1e-10)
