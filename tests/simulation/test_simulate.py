"""The event-driven simulator against independent answers: scipy ``solve_ivp`` with events, the
closed-form rigid orbits (theory §4, §6), the bouncing-ball accumulation point, the static
fixed-free bar, and the energy balance."""

import math

import numpy as np
import pytest

from impactbar import (
    BarModel,
    CosineLoad,
    FourierLoad,
    InitialState,
    SquareWaveLoad,
    simulate,
)
from impactbar.simulation._core import _Core
from modal_reference import solve_modal

TWO_PI = 2.0 * math.pi


# ----------------------------------------------------------------------------------------------
# an independent reference: solve_ivp on the modal equations, restarted at each impact event
# ----------------------------------------------------------------------------------------------
def ivp_impacts(model, load, q0, v0, t_end, n_max, t0=0.0):
    """Impact times and arrival velocities from DOP853 (rtol 1e-12), restarted at every event and
    at every jump of a piecewise-constant load."""
    M = model.n_modes + 1
    c = model.end_weights
    t, y = t0, np.concatenate((q0, v0)).astype(float)
    times, vels = [], []
    while t < t_end and len(times) < n_max:
        # a short bounce inside one step would be missed: cap the step
        t, y, _, hit = solve_modal(model.frequencies**2, model.d, load, y, t, t_end, end_weights=c,
                                   max_step=0.01)
        if hit:
            times.append(t)
            vels.append(c @ y[M:])
            y[M:] *= -model.R
            y[0] -= c @ y[:M]
    return np.array(times), np.array(vels)


def flexible_start(model, rng, end=-0.3, amp=0.002):
    N = model.n_modes
    q = np.zeros(N + 1)
    v = np.zeros(N + 1)
    n = np.arange(1, N + 1)
    q[1:] = amp * rng.standard_normal(N) / n
    v[1:] = 20 * amp * rng.standard_normal(N) / n
    q[0] = end - model.end_weights[1:] @ q[1:]
    return InitialState(q, v)


# ----------------------------------------------------------------------------------------------
# the compiled flow
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("d", [0.0, 0.3, 40.0])
def test_compiled_flow_matches_load_propagate(rng, d):
    model = BarModel(s=2.2, d=d, R=0.5, n_modes=6)
    load = FourierLoad(0.4, [0.8, 0.3 - 0.2j, 0.0, 0.05j])
    core = _Core(model, load)
    q0 = rng.standard_normal(7) * 0.1
    v0 = rng.standard_normal(7)
    t = np.sort(rng.uniform(1.3, 9.0, 20))
    q_ref, v_ref = load.propagate(model.frequencies**2, d, 1.3, q0, v0, t)
    q, v = core.propagate(0, 1.3, q0, v0, t)
    assert np.max(np.abs(q - q_ref)) < 1e-12 * (1 + np.max(np.abs(q_ref)))
    assert np.max(np.abs(v - v_ref)) < 1e-12 * (1 + np.max(np.abs(v_ref)))


def test_compiled_flow_square_wave_matches_solve_ivp(rng):
    """Exact piece by piece, including jumps met at times n 2 pi + kappa pi."""
    model = BarModel(s=3.3, d=0.05, R=0.5, n_modes=4)
    load = SquareWaveLoad(1.0, 1.5)
    core = _Core(model, load)
    q0 = rng.standard_normal(5) * 0.01
    v0 = rng.standard_normal(5) * 0.1
    t0, t1 = 17.039120776338564, 27.5
    q, _ = core.propagate(0, t0, q0, v0, [t1])
    _, y, _, _ = solve_modal(model.frequencies**2, 0.05, load, np.concatenate((q0, v0)), t0, t1)
    assert np.max(np.abs(q[:, 0] - y[:5])) < 1e-9


# ----------------------------------------------------------------------------------------------
# impacts against solve_ivp
# ----------------------------------------------------------------------------------------------
CASES = {
    "cosine-8-modes": (BarModel(s=3.3, d=0.05, R=0.7, n_modes=8), CosineLoad(0.8, 1.0)),
    "fourier-rigid": (BarModel(s=1.0, d=0.1, R=0.6, n_modes=0), FourierLoad(0.5, [1.0, 0.4j])),
    "square-4-modes": (BarModel(s=3.3, d=0.05, R=0.7, n_modes=4), SquareWaveLoad(1.0, 1.5)),
    "pneumatic-k2-3-modes": (BarModel(s=1.7, d=0.0, R=0.8, n_modes=3), CosineLoad(0.3, 1.0, k=2)),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_impact_times_match_solve_ivp(name, rng):
    model, load = CASES[name]
    start = flexible_start(model, rng)
    tr = simulate(model, load, start, 40.0, max_impacts=20)
    # the reference knows no chatter jump and misses short bounces (see the next test): compare
    # the impacts before the first slow one
    n = int(np.argmax(np.append(tr.impact_velocities, 0.0) < 1e-2))
    assert n >= 6
    t_ref, v_ref = ivp_impacts(model, load, start.modal_displacement, start.modal_velocity, 40.0,
                               n)
    assert t_ref.size == n
    np.testing.assert_allclose(tr.impact_times[:n], t_ref[:n], rtol=0, atol=1e-8)
    np.testing.assert_allclose(tr.impact_velocities[:n], v_ref[:n], rtol=0, atol=1e-7)
    assert np.all(tr.impact_velocities > 0)


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_flight_checked_by_dense_solve_ivp(name, rng):
    """Each flight, integrated on its own by DOP853 from the state just after an impact, stays
    off the stop and comes back to it at the next impact time: no impact missed, none invented
    (solve_ivp's own event search misses some of the short bounces near chatter)."""
    model, load = CASES[name]
    tr = simulate(model, load, flexible_start(model, rng), 40.0, max_impacts=20)
    M = model.n_modes + 1
    w2 = model.frequencies**2
    c = model.end_weights
    segs = [s for s in tr._segments if s.entry in ("start", "impact")]

    checked = 0
    for seg, t_next in zip(segs, tr.impact_times, strict=False):
        if t_next - seg.t < 1e-6:
            continue
        t = np.linspace(seg.t, t_next, 4001)[1:-1]
        _, y_end, dense, _ = solve_modal(w2, model.d, load, np.concatenate((seg.q, seg.v)), seg.t,
                                         t_next, ts=t, max_step=0.05)
        g = c @ dense[:M]
        scale = np.max(np.abs(g))
        assert np.max(g) < 1e-9 * max(scale, 1.0)
        assert abs(c @ y_end[:M]) < 1e-8
        checked += 1
    assert checked >= 6


def test_trajectory_never_penetrates_and_touches_at_impacts(rng):
    model, load = CASES["cosine-8-modes"]
    tr = simulate(model, load, flexible_start(model, rng), 30.0, max_impacts=25)
    t = np.linspace(tr.t0, tr.t_end, 20001)
    u1 = tr.end_displacement(t)
    assert np.max(u1) < 1e-12
    assert np.max(np.abs(tr.end_displacement(tr.impact_times))) < 1e-12
    # the field at x = 1 is the end displacement
    np.testing.assert_allclose(tr.displacement([1.0], t[::1000])[:, 0], u1[::1000], atol=1e-14)


def test_grazing_impact_is_found():
    """Constant pull ``p = -1``: the end rises to ``u(1) = h delta`` for a short while. A step or
    sample grid misses it; the certified search must not."""
    model = BarModel(s=1.0, d=0.0, R=0.5, n_modes=0)
    load = FourierLoad(-1.0, [])
    h = 0.5
    for delta, hits in ((1e-11, 1), (-1e-11, 0)):
        v = math.sqrt(2 * h * (1 + delta))
        tr = simulate(model, load, InitialState([-h], [v]), 3.0)
        assert tr.n_impacts == hits
        if hits:
            t_hit = v - math.sqrt(v * v - 2 * h)
            assert tr.impact_times[0] == pytest.approx(t_hit, abs=1e-9)
            assert tr.impact_velocities[0] == pytest.approx(math.sqrt(2 * h * delta), rel=1e-3)


# ----------------------------------------------------------------------------------------------
# energy account
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(CASES))
def test_energy_balance_free_flights(name, rng):
    model, load = CASES[name]
    tr = simulate(model, load, flexible_start(model, rng), 25.0, max_impacts=15)
    e = tr.energy
    assert tr.n_impacts >= 3
    assert e.impact_loss > 0
    assert (e.damping_loss > 0) == (model.d > 0)
    assert e.relative_residual < 1e-8


def test_energy_balance_with_chatter_and_contact_rigid():
    model = BarModel(s=1.0, d=0.02, R=0.5, n_modes=0)
    tr = simulate(model, CosineLoad(0.8, 1.0), InitialState.rigid(-0.3, 0.0), 60.0)
    assert tr.contact_intervals.shape[0] >= 3
    e = tr.energy
    assert e.chatter_loss >= 0
    assert e.projection == 0.0  # a rigid bar: nothing to project
    assert e.relative_residual < 1e-8


def test_energy_balance_with_contact_flexible_reports_projection(rng):
    model = BarModel(s=3.3, d=0.05, R=0.5, n_modes=8)
    tr = simulate(model, CosineLoad(0.8, 1.0), flexible_start(model, rng), 30.0)
    assert tr.contact_intervals.shape[0] >= 1
    e = tr.energy
    assert e.projection != 0.0
    assert e.relative_residual < 1e-8


# ----------------------------------------------------------------------------------------------
# closed-form orbits of the rigid bar (theory §6)
# ----------------------------------------------------------------------------------------------
def rigid_orbits(p0, pk, R):
    """Phases and impact velocity of the one-impact orbits, cosine load, d = 0 (eq. 35)."""
    s = math.pi * p0 / pk * (1 - R) / (1 + R)
    phi = math.asin(s)
    return [phi, math.pi - phi], 2 * math.pi * p0 / (1 + R)


@pytest.mark.parametrize("R", [0.3, 0.5, 0.8])
def test_settles_on_stable_rigid_orbit(R):
    p0, pk = 0.9 * (1 + R) / (math.pi * (1 - R)), 1.0  # in the stable band (eqs. 38, 39)
    phases, V = rigid_orbits(p0, pk, R)
    stable = [ph for ph in phases if -((1 - R) / (1 + R)) ** 2 < (p0 + pk * math.cos(ph)) / p0 < 1]
    assert len(stable) == 1
    model = BarModel(s=1.0, d=0.0, R=R, n_modes=0)
    ph = stable[0]
    start = InitialState([-1e-3], [-R * V * 1.01])
    tr = simulate(model, CosineLoad(p0, pk), start, ph + TWO_PI * 400, t0=ph)
    assert tr.contact_intervals.size == 0
    last = tr.impact_times[-5:]
    np.testing.assert_allclose(np.diff(last), TWO_PI, atol=1e-8)
    assert abs(math.remainder(last[-1] - ph, TWO_PI)) < 1e-8
    np.testing.assert_allclose(tr.impact_velocities[-5:], V, rtol=1e-8)


def test_leaves_unstable_rigid_orbit():
    R, p0, pk = 0.5, 0.8, 1.0
    phases, V = rigid_orbits(p0, pk, R)
    unstable = [ph for ph in phases if (p0 + pk * math.cos(ph)) / p0 > 1][0]
    model = BarModel(s=1.0, d=0.0, R=R, n_modes=0)
    start = InitialState([-1e-9], [-R * V])
    tr = simulate(model, CosineLoad(p0, pk), start, unstable + TWO_PI * 60, t0=unstable)
    first = np.mod(tr.impact_times[0] - unstable, TWO_PI)
    assert min(first, TWO_PI - first) < 1e-6  # starts on it
    late = np.mod(tr.impact_times[-1] - unstable, TWO_PI)
    assert min(late, TWO_PI - late) > 0.1  # and has left it


def test_flexible_bar_near_stable_orbit_settles():
    """Not the rigid closed form: a stiff 4-mode bar started near the rigid orbit settles on a
    2 pi-periodic orbit whose impact velocity is the exact ``2 pi p0 / (1 + R)`` (theory §4, any
    load and any number of modes)."""
    R, p0, pk = 0.5, 0.8, 1.0
    phases, V = rigid_orbits(p0, pk, R)
    model = BarModel(s=7.3, d=0.05, R=R, n_modes=4)
    ph = phases[1]
    tr = simulate(model, CosineLoad(p0, pk), InitialState([-1e-3], [-R * V]), ph + TWO_PI * 200,
                  t0=ph)
    last = tr.impact_times[-4:]
    np.testing.assert_allclose(np.diff(last), TWO_PI, atol=1e-8)
    np.testing.assert_allclose(tr.impact_velocities[-1], V, rtol=1e-3)  # rigid-mode part only
    q, v = tr.modal_state([last[-1]])
    # rigid mode velocity just after impact: -R times just before; just before it is exactly V
    assert -v[0, 0] / R == pytest.approx(V, rel=1e-8)


# ----------------------------------------------------------------------------------------------
# chatter, permanent contact, release
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("R", [0.2, 0.5, 0.9])
def test_chatter_accumulates_into_permanent_contact(R):
    """Bouncing ball: constant load ``p``, rigid bar from rest at ``u(1) = -h``. First impact at
    ``sqrt(2h/p)`` with speed ``sqrt(2hp)``; the bounces sum to ``2 R v / (p (1 - R))``."""
    p, h = 1.3, 0.4
    model = BarModel(s=1.0, d=0.0, R=R, n_modes=0)
    tr = simulate(model, FourierLoad(p, []), InitialState.rigid(-h, 0.0), 20.0)
    v1 = math.sqrt(2 * h * p)
    t_acc = math.sqrt(2 * h / p) + 2 * R * v1 / (p * (1 - R))
    assert tr.contact_intervals.shape == (1, 2)
    assert tr.contact_intervals[0, 0] == pytest.approx(t_acc, abs=1e-8)
    assert tr.contact_intervals[0, 1] == 20.0
    np.testing.assert_allclose(tr.impact_velocities[:5], v1 * R ** np.arange(5), rtol=1e-10)
    t = np.linspace(t_acc + 1e-6, 20.0, 50)
    assert np.all(tr.end_displacement(t) == 0.0)
    assert tr.in_contact_at_end
    assert tr.energy.relative_residual < 1e-8


def test_release_when_reaction_turns_tensile():
    """Rigid bar on the stop: the reaction is ``p(t)``; it leaves when ``p0 + pk cos t`` turns
    negative, at ``t = arccos(-p0/pk)``."""
    p0, pk = 0.5, 1.0
    model = BarModel(s=1.0, d=0.0, R=0.0, n_modes=0)
    tr = simulate(model, CosineLoad(p0, pk), InitialState.rigid(0.0, 0.0), 3.0, t0=0.0)
    t_rel = math.acos(-p0 / pk)
    assert tr.contact_intervals[0, 0] == 0.0
    assert tr.contact_intervals[0, 1] == pytest.approx(t_rel, abs=1e-9)
    assert tr.end_displacement(t_rel + 0.3) < 0


def test_flexible_bar_settles_into_static_contact():
    """A pressed, damped 12-mode bar chatters, then rests on the stop in the static fixed-free
    shape ``u = (p / s^2)(1 - x)``."""
    p, s = 1.0, 2.0
    model = BarModel(s=s, d=2.0, R=0.5, n_modes=12)
    tr = simulate(model, FourierLoad(p, []), InitialState.rigid(-0.1, 0.0, n_modes=12), 40.0)
    assert tr.in_contact_at_end
    x = np.linspace(0, 1, 11)
    u = tr.displacement(x, [40.0])[0]
    mu = (np.arange(1, 13) - 0.5) * np.pi
    u_truncated = 2 * np.cos(np.outer(x, mu)) @ (p / (s * mu) ** 2)  # r_m = p / w_m^2, static
    np.testing.assert_allclose(u, u_truncated, atol=1e-9)
    np.testing.assert_allclose(u, p / s**2 * (1 - x), atol=0.02 * p / s**2)
    assert tr.end_displacement(40.0) == 0.0


def stick_cycle_run(periods):
    model = BarModel(s=1.0, d=0.0, R=0.5, n_modes=0)
    return simulate(model, CosineLoad(0.8, 1.0), InitialState.rigid(-0.5, 0.0), TWO_PI * periods)


def test_stick_impact_release_cycle():
    tr = stick_cycle_run(50)
    ci = tr.contact_intervals
    assert ci.shape[0] >= 45
    # each contact ends where the load turns negative: cos t = -0.8
    phase = np.mod(ci[:-1, 1], TWO_PI)
    np.testing.assert_allclose(phase, math.acos(-0.8), atol=1e-9)
    assert tr.energy.relative_residual < 1e-8


def test_stick_impact_release_runs_thousands_of_periods():
    tr = stick_cycle_run(3000)
    assert tr.status == "t_end" and tr.t_end == TWO_PI * 3000
    assert tr.contact_intervals.shape[0] >= 2990


# ----------------------------------------------------------------------------------------------
# API
# ----------------------------------------------------------------------------------------------
def test_load_is_evaluated_at_absolute_time():
    model = BarModel(s=1.0, d=0.1, R=0.5, n_modes=0)
    load = CosineLoad(0.8, 1.0)
    a = simulate(model, load, InitialState.rigid(-0.2, 0.3), 30.0, max_impacts=8)
    b = simulate(model, load, InitialState.rigid(-0.2, 0.3), 30.0 + 6 * math.pi,
                 t0=6 * math.pi, max_impacts=8)
    np.testing.assert_allclose(b.impact_times - 6 * math.pi, a.impact_times, atol=1e-9)
    c = simulate(model, load, InitialState.rigid(-0.2, 0.3), 31.0, t0=1.0, max_impacts=8)
    assert np.max(np.abs(c.impact_times - 1.0 - a.impact_times)) > 1e-3


def test_max_impacts_and_final_state():
    model, load = CASES["cosine-8-modes"]
    tr = simulate(model, load, InitialState.rigid(-0.3, 0.0, n_modes=8), 100.0, max_impacts=7)
    assert tr.n_impacts == 7 and tr.status == "max_impacts"
    assert tr.t_end == tr.impact_times[-1]
    q = tr.final_state.modal_displacement
    assert abs(model.end_weights @ q) < 1e-14


def test_initial_state_constructors():
    model = BarModel(s=1.0, d=0.0, R=0.5, n_modes=3)
    st = InitialState.from_fields(lambda x: -0.1 + 0.01 * np.cos(np.pi * x),
                                  lambda x: 0.2 + 0 * x, model)
    np.testing.assert_allclose(st.modal_displacement, [-0.1, 0.005, 0, 0], atol=1e-15)
    np.testing.assert_allclose(st.modal_velocity, [0.2, 0, 0, 0], atol=1e-15)
    r = InitialState.rigid(-0.5, 1.0, n_modes=3)
    np.testing.assert_array_equal(r.modal_displacement, [-0.5, 0, 0, 0])
    with pytest.raises(ValueError):
        r.modal_displacement[0] = 1.0  # frozen


@pytest.mark.parametrize(
    ("call", "word"),
    [
        (lambda m, ld: simulate(m, ld, InitialState.rigid(-1, 0), 0.0), "t_end"),
        (lambda m, ld: simulate(m, ld, InitialState.rigid(-1, 0), math.nan), "t_end"),
        (lambda m, ld: simulate(m, ld, InitialState.rigid(-1, 0), 1.0, max_impacts=0),
         "max_impacts"),
        (lambda m, ld: simulate(m, ld, InitialState([0.0, 0.0], [0, 0]), 1.0), "initial"),
        (lambda m, ld: simulate(m, ld, InitialState([0.1], [0.0]), 1.0), "penetrates"),
        (lambda m, ld: simulate(m, ld, "start", 1.0), "initial"),
        (lambda m, ld: simulate("bar", ld, InitialState.rigid(-1, 0), 1.0), "model"),
        (lambda m, ld: simulate(m, object(), InitialState.rigid(-1, 0), 1.0), "load"),
        (lambda m, ld: InitialState.rigid(0.1, 0.0), "end_displacement"),
        (lambda m, ld: InitialState([0.0, 1.0], [0.0]), "modal_velocity"),
        (lambda m, ld: InitialState([math.inf], [0.0]), "modal_displacement"),
        (lambda m, ld: InitialState.from_fields(lambda x: 0.1 + 0 * x, lambda x: 0 * x, m), "u0"),
        (lambda m, ld: simulate(BarModel(s=1 / math.pi, d=0.0, R=0.5, n_modes=2), ld,
                                InitialState.rigid(-1, 0), 1.0), "resonance"),
    ],
)
def test_bad_inputs_raise_value_error_naming_the_parameter(call, word):
    model = BarModel(s=1.0, d=0.0, R=0.5, n_modes=0)
    load = CosineLoad(0.8, 1.0)
    with pytest.raises(ValueError, match=word):
        call(model, load)


def test_times_outside_the_run_raise():
    tr = simulate(BarModel(s=1.0, d=0.0, R=0.5, n_modes=0), CosineLoad(0.8, 1.0),
                  InitialState.rigid(-0.1, 0.0), 5.0)
    with pytest.raises(ValueError, match="t must lie"):
        tr.end_displacement(6.0)


# ----------------------------------------------------------------------------------------------
# periodic_orbits (orbits/one_impact.py): settle on the stable one, leave the unstable one
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("model", "load"),
    [
        (BarModel(s=3.3, d=0.05, R=0.5, n_modes=8), CosineLoad(0.8, 1.0)),
        (BarModel(s=7.3, d=0.02, R=0.6, n_modes=4), CosineLoad(0.9, 1.0)),
    ],
)
def test_settles_on_stable_and_leaves_unstable_periodic_orbit(model, load):
    from impactbar import periodic_orbits

    orbits = [o for o in periodic_orbits(model, load) if o.admissible]
    assert {o.stable for o in orbits} == {True, False}
    rng = np.random.default_rng(7)
    c = model.end_weights
    for orbit in orbits:
        q, v = orbit.modal_state_after_impact
        dq = 1e-5 * rng.standard_normal(q.size)
        dq[0] = -1e-6 - c[1:] @ dq[1:]  # a small step back from the stop
        start = InitialState(q + dq, v + 1e-5 * rng.standard_normal(v.size))
        tr = simulate(model, load, start, orbit.phase + TWO_PI * 150, t0=orbit.phase)
        lag = np.mod(tr.impact_times[-3:] - orbit.phase + math.pi, TWO_PI) - math.pi
        dv = tr.impact_velocities[-3:] - orbit.impact_velocity
        if orbit.stable:
            assert np.max(np.abs(lag)) < 1e-8
            assert np.max(np.abs(dv)) < 1e-8
        else:
            assert np.max(np.abs(lag)) > 1e-3 or np.max(np.abs(dv)) > 1e-3


def test_flexible_grazing_between_samples_is_found():
    """The end of an 8-mode bar, pulled away by ``p = -0.2``, wobbles with its high modes; shift
    the mean so that the highest wobble peak of the free flight (found on a 200 001-point grid of
    the reference flow ``Load.propagate``) pokes ``1e-9`` past the stop: an impact there. Shifted
    the other way by ``1e-9``: none."""
    model = BarModel(s=2.0, d=0.0, R=0.5, n_modes=8)
    load = FourierLoad(-0.2, [])
    w2 = model.frequencies**2
    c = model.end_weights
    q = np.zeros(9)
    v = np.zeros(9)
    q[8] = 0.01
    v[0] = 0.3
    t = np.linspace(0.0, 3.0, 200001)
    qq, _ = load.propagate(w2, 0.0, 0.0, q, v, t)
    g = c @ qq
    i = int(np.argmax(g))
    assert 0 < i < t.size - 1
    for shift, hits in ((1e-9, 1), (-1e-9, 0)):
        q0 = q.copy()
        q0[0] += shift - g[i]
        tr = simulate(model, load, InitialState(q0, v), 3.0, max_impacts=1)
        assert tr.n_impacts == hits
        if hits:
            assert abs(tr.impact_times[0] - t[i]) < 1e-3
            assert 0 < tr.impact_velocities[0] < 1e-2


@pytest.mark.parametrize("seed", range(6))
def test_random_models_balance_energy_and_never_penetrate(seed):
    rng = np.random.default_rng(seed)
    n_modes = int(rng.integers(0, 7))
    model = BarModel(s=float(rng.uniform(0.7, 6.0)), d=float(rng.uniform(0, 0.3)),
                     R=float(rng.uniform(0, 0.95)), n_modes=n_modes)
    if rng.uniform() < 0.5:
        load = CosineLoad(float(rng.uniform(0.2, 1.5)), float(rng.uniform(0.2, 1.5)),
                          k=int(rng.integers(1, 3)))
    else:
        load = SquareWaveLoad(float(rng.uniform(0.5, 1.5)), float(rng.uniform(1.1, 1.9)))
    tr = simulate(model, load, flexible_start(model, rng), 40.0)
    assert tr.energy.relative_residual < 1e-8
    t = np.linspace(tr.t0, tr.t_end, 40001)
    assert np.max(tr.end_displacement(t)) < 1e-10
    assert np.all(tr.impact_velocities > 0)


def test_max_impacts_landing_on_a_chatter_jump():
    """The impact that triggers the jump to the accumulation point can be the last one allowed."""
    model = BarModel(s=1.0, d=0.0, R=0.5, n_modes=0)
    load = FourierLoad(1.3, [])
    full = simulate(model, load, InitialState.rigid(-0.4, 0.0), 20.0)
    n = full.n_impacts
    for m in (n, n - 1, 1):
        tr = simulate(model, load, InitialState.rigid(-0.4, 0.0), 20.0, max_impacts=m)
        assert tr.n_impacts == m and tr.status == "max_impacts"
        np.testing.assert_array_equal(tr.impact_times, full.impact_times[:m])
