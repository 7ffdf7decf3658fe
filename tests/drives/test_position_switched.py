"""The position-switched drive (theory §10): a hydraulic drifter's valve switching on the piston's
position, an autonomous system whose period is an output.

Independent checks: the rigid piston's orbit in closed form (stroke and return accelerations, switch
out at x1, switch to return at impact), the SI drifter example done by hand, simulate
(the compiled event search plus the valve's closed-form crossings) against find_orbit (Newton on the
segment problem), the multipliers against finite differences of the simulated Poincare map, and the
time-periodic square wave recovered when the switch instants are those of the square wave.
"""

import math

import numpy as np
import pytest

from impactbar import (
    BarModel,
    DrivenOrbit,
    DrivenTrajectory,
    PositionSwitchedDrive,
    SquareWaveLoad,
    continue_orbit,
    find_orbit,
    periodic_orbits,
    simulate,
)
from impactbar.drives.valve import first_rising_crossing
from impactbar.orbits import phase_roots
from impactbar.simulation import InitialState


def _closed_form(a_s, a_r, x1, R):
    """The rigid piston: impact velocity, period, multiplier (undamped, no delay)."""
    v = math.sqrt(2 * x1 * (a_s + a_r) / (1 - R * R))
    u1 = math.sqrt(R * R * v * v + 2 * a_r * x1)
    return v, (u1 - R * v) / a_r + (u1 + v) / a_s, R * R


# -- validation --------------------------------------------------------------------------------------
@pytest.mark.parametrize("kw, name", [
    (dict(stroke=0.0), "stroke"), (dict(stroke=-1.0), "stroke"), (dict(ret=0.0), "ret"),
    (dict(switch_out=0.0), "switch_out"), (dict(switch_out=math.nan), "switch_out"),
    (dict(delay=-0.1), "delay"), (dict(stroke=math.inf), "stroke"), (dict(ret="1"), "ret"),
])
def test_drive_is_validated(kw, name):
    args = dict(stroke=1.0, ret=1.0, switch_out=1.0, delay=0.0) | kw
    with pytest.raises(ValueError, match=name):
        PositionSwitchedDrive(**args)


def test_drive_is_frozen_and_refused_by_the_time_periodic_machinery():
    drive = PositionSwitchedDrive(stroke=1.0, ret=2.0, switch_out=0.5)
    assert drive == PositionSwitchedDrive(stroke=1.0, ret=2.0, switch_out=0.5)
    with pytest.raises(AttributeError):
        drive.stroke = 2.0
    model = BarModel(s=10.0, d=0.0, R=0.5, n_modes=0)
    listed = periodic_orbits(model, drive)  # every one-impact orbit in a window of periods
    assert any(abs(o.period - find_orbit(model, drive).period) < 1e-12 for o in listed)
    assert not hasattr(drive, "harmonics")  # not a function of time: the loads' solvers never see it
    with pytest.raises(ValueError, match="not periodic in time"):
        phase_roots(model, drive)
    with pytest.raises(ValueError, match="parameter must be one of"):  # a load's parameter
        continue_orbit(find_orbit(model, drive), "kappa", to=1.5)
    with pytest.raises(ValueError, match="impacts"):
        find_orbit(model, drive, impacts=2)
    # every law now (the wave law's contact: tests/orbits/test_driven_contact.py)
    assert find_orbit(model.with_(impact="wave"), drive).contact_time == pytest.approx(2.0 / model.s)


# -- the rising crossing in closed form ------------------------------------------------------------
@pytest.mark.parametrize("d", [0.0, 0.3, 2.0])
def test_first_rising_crossing_is_the_first(d, rng):
    for _ in range(100):
        y0, w0, a, level = rng.uniform(-1, 1), rng.uniform(-3, 3), rng.uniform(-2, 2), rng.uniform(-1, 2)
        t = first_rising_crossing(d, y0, w0, a, level)
        ts = np.linspace(0.0, 40.0, 100001)
        e = -np.expm1(-d * ts) / d if d else ts
        c = (ts - e) / d if d else 0.5 * ts * ts
        y = y0 + w0 * e + a * c
        up = np.flatnonzero((y[:-1] < level) & (y[1:] >= level))
        if up.size == 0:
            assert t == math.inf or t > 39.99
        else:
            assert t == pytest.approx(ts[up[0]], abs=5e-4)


# -- the rigid piston in closed form -----------------------------------------------------------------
@pytest.mark.parametrize("a_s, a_r, x1, R", [(1.0, 1.0, 1.0, 0.215), (2.0, 0.5, 0.3, 0.0),
                                             (0.7, 3.0, 2.0, 0.8)])
def test_rigid_orbit_matches_the_closed_form(a_s, a_r, x1, R):
    v, T, mu = _closed_form(a_s, a_r, x1, R)
    o = find_orbit(BarModel(s=10.0, d=0.0, R=R, n_modes=0),
                   PositionSwitchedDrive(stroke=a_s, ret=a_r, switch_out=x1))
    assert isinstance(o, DrivenOrbit)
    assert o.impact_velocity == pytest.approx(v, rel=1e-10)
    assert o.period == pytest.approx(T, rel=1e-10)
    assert o.blow_frequency == pytest.approx(1 / T, rel=1e-10)
    assert o.multipliers.shape == (1,)
    assert o.multipliers[0] == pytest.approx(mu, abs=1e-10)
    assert o.trivial_multiplier == pytest.approx(1.0, abs=1e-10)
    assert o.admissibility == "admissible" and o.stable
    assert o.impact_energy == pytest.approx(0.5 * v * v, rel=1e-10)


def test_si_drifter_example_by_hand():
    """5.6 kg piston, 5.6 kN each way, switch at 21.5 mm, R = 0.215. Scales: length L = 21.5 mm (so
    x1 = 1), mass m = 5.6 kg, time 1/Omega = sqrt(L m / F) (so stroke = ret = F / (m L Omega^2) = 1)."""
    m, F, L, R = 5.6, 5.6e3, 0.0215, 0.215
    omega = math.sqrt(F / (m * L))
    o = find_orbit(BarModel(s=10.0, d=0.0, R=R, n_modes=0),
                   PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0))
    v_si = o.impact_velocity * L * omega
    T_si = o.period / omega
    assert v_si == pytest.approx(9.495684, abs=5e-7)
    assert T_si * 1e3 == pytest.approx(21.189907, abs=5e-7)
    assert 1 / T_si == pytest.approx(47.19, abs=5e-3)
    assert 0.5 * m * v_si**2 == pytest.approx(252.47, abs=5e-3)
    assert o.impact_energy * m * L**2 * omega**2 == pytest.approx(252.47, abs=5e-3)
    assert o.multipliers[0] == pytest.approx(0.046225, abs=1e-12)


# -- simulate settles on the orbit ------------------------------------------------------------------
@pytest.mark.parametrize("d, delay", [(0.0, 0.0), (0.2, 0.0), (0.2, 0.15)])
def test_simulate_rigid_settles_on_the_orbit(d, delay, rng):
    model = BarModel(s=10.0, d=d, R=0.215, n_modes=0)
    drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0, delay=delay)
    o = find_orbit(model, drive)
    tr = simulate(model, drive, InitialState.rigid(-rng.uniform(0.1, 3.0), rng.uniform(-1, 1)), 150.0)
    assert isinstance(tr, DrivenTrajectory)
    assert tr.impact_velocities[-1] == pytest.approx(o.impact_velocity, rel=1e-10)
    assert np.diff(tr.impact_times)[-1] == pytest.approx(o.period, rel=1e-10)
    # the switches: alternate, stroke ones at (or, delayed, a little beyond) switch_out
    kinds = tr.switch_kinds[-4:]
    assert kinds in (("return", "stroke") * 2, ("stroke", "return") * 2)
    last_imp = tr.impact_times[-1]
    after = tr.switch_times[tr.switch_times >= tr.impact_times[-2]]
    assert after[0] - tr.impact_times[-2] == pytest.approx(o.switch_times[0], abs=1e-9)
    assert after[1] - tr.impact_times[-2] == pytest.approx(o.switch_times[1], abs=1e-9)
    if delay == 0.0:
        stroke = tr.switch_positions[np.array(tr.switch_kinds) == "stroke"]
        assert np.allclose(stroke, 1.0, atol=1e-12)
    assert tr.end_displacement([last_imp])[0] == pytest.approx(0.0, abs=1e-12)


def test_simulate_flexible_settles_on_the_orbit_and_multipliers_by_finite_differences():
    model = BarModel(s=10.0, d=0.5, R=0.215, n_modes=2)
    drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    o = find_orbit(model, drive)
    assert o.admissibility == "admissible" and o.stable
    tr = simulate(model, drive, InitialState.rigid(-0.5, 0.3, 2), 200.0)
    assert np.diff(tr.impact_times)[-1] == pytest.approx(o.period, rel=1e-9)
    assert tr.impact_velocities[-1] == pytest.approx(o.impact_velocity, rel=1e-8)
    # the Poincare map just after an impact, by simulate, on the section u(1) = 0
    M = 3
    c = model.end_weights
    B = np.linalg.svd(np.concatenate((c, np.zeros(M)))[None, :])[2][1:].T  # the section's tangent

    def P(z):
        t = simulate(model, drive, InitialState(z[:M], z[M:]), 50.0, max_impacts=1)
        return np.concatenate((t.final_state.modal_displacement, t.final_state.modal_velocity))

    h = 1e-6
    D = np.column_stack([(P(o.state + h * b) - P(o.state - h * b)) / (2 * h) for b in B.T])
    mu_fd = np.sort(np.abs(np.linalg.eigvals(B.T @ D)))
    assert np.allclose(mu_fd, np.sort(np.abs(o.multipliers)), atol=1e-6)


def test_flexible_orbit_converges_in_modes_and_to_the_rigid_one():
    """Damped bar (d = 0.5): the period converges as n_modes grows, and to the rigid bar's as s
    grows (the flexible correction vanishes with 1/s)."""
    drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    rigid = find_orbit(BarModel(s=10.0, d=0.5, R=0.215, n_modes=0), drive).period
    T = {N: find_orbit(BarModel(s=10.0, d=0.5, R=0.215, n_modes=N), drive).period for N in (4, 16, 32)}
    assert abs(T[16] - T[32]) < 0.2 * abs(T[4] - T[32])
    gaps = [abs(find_orbit(BarModel(s=s, d=0.5, R=0.215, n_modes=8), drive).period - rigid)
            for s in (10.0, 100.0, 1000.0)]
    assert gaps[0] > gaps[1] > gaps[2] and gaps[2] < 2e-7


def test_square_wave_recovered_when_the_switch_instants_are_forced():
    """Rigid, equal levels q: the driven orbit has the stroke on for h3 of its period T and the
    switch to return at the impact. Rescaling time by k = 2 pi / T (forces by 1/k^2, velocities by
    1/k, eq. 2) makes it a motion of the square wave SquareWaveLoad(q / k^2, kappa = 2 h3 / T)
    (eq. 34) with the impact at the stroke's end: periodic_orbits finds it (the same motion; the
    time-periodic drive's multipliers differ: eq. 41 makes it unstable)."""
    q, R = 1.0, 0.215
    o = find_orbit(BarModel(s=10.0, d=0.0, R=R, n_modes=0),
                   PositionSwitchedDrive(stroke=q, ret=q, switch_out=1.0))
    k = 2 * math.pi / o.period
    kappa = 2 * o.durations[3] / o.period
    load = SquareWaveLoad(q / k**2, kappa)
    orbits = periodic_orbits(BarModel(s=10.0, d=0.0, R=R, n_modes=0), load)
    match = [p for p in orbits if abs(p.impact_velocity - o.impact_velocity / k) < 1e-10]
    assert match
    # the impact at the switch from +q to -q: phase kappa pi from the start of the stroke
    assert any(abs(p.phase - (kappa * math.pi) % (2 * math.pi)) < 1e-8 for p in match)
    assert not any(p.stable for p in match) and o.stable


def test_simulate_under_the_wave_law_settles_on_a_periodic_motion():
    """The wave law's contact window (2/s) under the stroke force, the switch to return counted from
    the window's end: the blows settle to a period close to the paper law's plus about the window."""
    drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    model = BarModel(s=10.0, d=0.5, R=0.215, n_modes=0, impact="wave")
    tr = simulate(model, drive, InitialState.rigid(-0.5, 0.2), 100.0)
    dt = np.diff(tr.impact_times)[-3:]
    assert np.ptp(dt) < 1e-9
    paper = find_orbit(model.with_(impact="paper"), drive).period
    assert paper < dt[-1] < paper + 2 * (2 / model.s)
    assert tr.switch_kinds[-2:] in (("return", "stroke"), ("stroke", "return"))


@pytest.mark.parametrize("d, delay, R", [(0.0, 0.0, 0.215), (0.3, 0.4, 0.5), (0.1, 0.2, 0.0)])
def test_rigid_closed_forms_agree_with_the_general_driver(d, delay, R, choose):
    """The rigid bar's scalar closed forms (fast) against the general driver piece by piece
    (reference): the same impacts and switches to rounding, resting on the stop (R = 0) included."""
    model = BarModel(s=10.0, d=d, R=R, n_modes=0)
    drive = PositionSwitchedDrive(stroke=1.3, ret=0.7, switch_out=0.8, delay=delay)
    start = InitialState.rigid(-1.2, 0.4)
    fast = simulate(model, drive, start, 60.0)
    choose("simulate.valve_rigid", False)
    ref = simulate(model, drive, start, 60.0)
    assert fast.n_impacts == ref.n_impacts > 5
    assert np.allclose(fast.impact_times, ref.impact_times, rtol=0, atol=1e-9)
    assert np.allclose(fast.impact_velocities, ref.impact_velocities, rtol=1e-8, atol=1e-10)
    assert fast.switch_kinds == ref.switch_kinds
    assert np.allclose(fast.switch_times, ref.switch_times, rtol=0, atol=1e-9)
    t = np.linspace(0.0, 60.0, 301)
    assert np.allclose(fast.end_displacement(t), ref.end_displacement(t), atol=1e-9)


def test_a_delay_longer_than_the_rebound_makes_the_one_impact_orbit_inadmissible():
    """Rigid, d = 0: after an impact at v the piston leaves at R v under the stroke force for the
    delay; it is back on the stop after 2 R v / a_s. With a longer delay the one-impact solution
    passes through the stop."""
    model = BarModel(s=10.0, d=0.0, R=0.215, n_modes=0)
    short = find_orbit(model, PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0, delay=0.2))
    assert short.admissibility == "admissible"
    assert 2 * model.R * short.impact_velocity > 0.2
    drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0, delay=5.0)
    o = find_orbit(model, drive)
    assert 2 * model.R * o.impact_velocity < 5.0
    assert o.admissibility == "penetrates" and not o.stable
