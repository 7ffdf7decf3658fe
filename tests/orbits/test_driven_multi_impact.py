"""Orbits with m impacts per period under a position-switched drive (theory §10): the period-2
orbit that a period doubling in the valve delay gives birth to, against an independent root solve
of the rigid piston's return map of arrival velocities (elementary kinematics, no modal flows), and
as the simulator's fixed point; the one-impact orbit traversed twice."""

import math
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from impactbar import BarModel, InitialState, PositionSwitchedDrive, continue_orbit, find_orbit, simulate

MODEL = BarModel(s=10.0, d=0.0, R=0.3, n_modes=0)


def _first_root(c0, c1, c2):
    """First t > 0 with c0 + c1 t + c2 t^2 = 0 (c0 < 0 rising, or c0 > 0 falling)."""
    disc = c1 * c1 - 4.0 * c2 * c0
    roots = sorted(r for r in ((-c1 + s * math.sqrt(disc)) / (2.0 * c2) for s in (1, -1)) if r > 0)
    return roots[0]


def _return_map(v, a_s, a_r, x1, tau, R):
    """Rigid piston, no damping: arrival velocity ``v`` -> the next one, and the time between.
    Gap ``y``: stroke (``y'' = -a_s``) for tau, return (``y'' = a_r``) until ``y = x1``, return for
    tau, stroke until ``y = 0``."""
    y, w = R * v * tau - 0.5 * a_s * tau * tau, R * v - a_s * tau
    t1 = _first_root(y - x1, w, 0.5 * a_r)
    w = w + a_r * (t1 + tau)
    y = x1 + (w - a_r * tau) * tau + 0.5 * a_r * tau * tau
    t3 = _first_root(y, w, -0.5 * a_s)
    return a_s * t3 - w, 2.0 * tau + t1 + t3


@pytest.fixture(scope="module")
def doubled():
    o = find_orbit(MODEL, PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=0.3, delay=1.0))
    pd = [e for e in continue_orbit(o, "delay", to=2.0).events if e.kind == "period-doubling"][0]
    branch = continue_orbit(pd, "delay", to=2.0, max_points=40, stop_on=("admissibility",))
    assert branch.status == "stopped at admissibility"
    return pd, branch


def _last_admissible(branch):
    return [o for o in branch.orbits if o.admissible][-1]


def test_period_two_orbit_is_the_root_of_the_composed_map(doubled):
    pd, branch = doubled
    o = _last_admissible(branch)
    drive = o.drive
    assert o.impacts == 2 and o.admissibility == "admissible"
    args = (drive.stroke, drive.ret, drive.switch_out, drive.delay, MODEL.R)

    def twice(v):
        return _return_map(_return_map(v, *args)[0], *args)[0] - v

    guess = o.impact_velocities[0]  # the bracket holds no other root: the period-1 one is 0.2 off
    v1 = brentq(twice, guess - 0.05, guess + 0.05, xtol=1e-15)
    v2, T1 = _return_map(v1, *args)
    _, T2 = _return_map(v2, *args)
    np.testing.assert_allclose(o.impact_velocities, [v1, v2], rtol=1e-10)
    assert o.period == pytest.approx(T1 + T2, rel=1e-10)
    assert abs(v1 - v2) > 0.1  # a period-2 orbit, not the period-1 one twice
    # its non-trivial multiplier: the product of the map's slopes at the two arrivals
    h = 1e-6
    slope = [(_return_map(v + h, *args)[0] - _return_map(v - h, *args)[0]) / (2 * h) for v in (v1, v2)]
    assert o.multipliers[0] == pytest.approx(slope[0] * slope[1], rel=1e-6)
    assert abs(o.trivial_multiplier - 1.0) < 1e-10
    # find_orbit from the branch's orbit at a nearby delay: the same root solve
    near = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=0.3, delay=drive.delay - 0.01)
    o2 = find_orbit(MODEL, near, impacts=2, guess=o)
    args2 = (1.0, 1.0, 0.3, near.delay, MODEL.R)
    w1 = brentq(lambda v: _return_map(_return_map(v, *args2)[0], *args2)[0] - v,
                o2.impact_velocities[0] - 0.02, o2.impact_velocities[0] + 0.02, xtol=1e-15)
    assert o2.impact_velocities[0] == pytest.approx(w1, rel=1e-10)


def test_period_two_orbit_is_the_simulators_fixed_point(doubled):
    """Started where the valve switches to return after the first impact, simulate meets the two
    impacts of the period at the orbit's times and velocities (1e-9), and, the orbit being unstable
    (its multiplier > 1, a subcritical doubling), departs from it by that multiplier per period."""
    _, branch = doubled
    o = _last_admissible(branch)
    tau, R, a = o.drive.delay, MODEL.R, o.drive.stroke
    v = o.impact_velocities[-1]  # the arrival before the period's first impact
    q0, w0 = -R * v * tau + 0.5 * a * tau * tau, -R * v + a * tau
    times = np.cumsum(o.durations)[3::4] - tau  # impacts, counted from the switch to return
    tr = simulate(MODEL, o.drive, InitialState.rigid(q0, w0), 1e4, max_impacts=4)
    np.testing.assert_allclose(tr.impact_velocities[:2], o.impact_velocities, rtol=1e-9)
    np.testing.assert_allclose(tr.impact_times[:2], times, rtol=1e-9)
    assert o.multipliers[0] > 1.0
    tr = simulate(MODEL, o.drive, InitialState.rigid(q0, w0 * (1 + 1e-8)), 1e4, max_impacts=12)
    dev = tr.impact_velocities[0::2] - o.impact_velocities[0]
    np.testing.assert_allclose(dev[1:] / dev[:-1], o.multipliers[0], rtol=1e-3)


def test_branch_switching_starts_the_period_two_branch_at_the_doubling(doubled):
    pd, branch = doubled
    assert branch.impacts == 2 and branch.values[0] == pd.value
    first = branch.orbits[0]
    assert first.impact_velocities[0] == pytest.approx(first.impact_velocities[1], rel=1e-9)
    assert first.multipliers[0] == pytest.approx(pd.multiplier.real ** 2, abs=1e-6)  # (-1)^2
    gaps = [abs(o.impact_velocities[0] - o.impact_velocities[1]) for o in branch.orbits[1:]]
    assert np.all(np.diff(gaps) > 0)
    # the branch loses admissibility where theory §10 says (quoted to 4 decimals)
    theory = re.sub(r"\s+", " ", (Path(__file__).resolve().parents[2] / "docs" / "theory.md").read_text())
    quoted = re.search(r"loses admissibility at \$\\tau \\approx ([0-9.]+)\$", theory).group(1)
    assert branch.events[-1].kind == "admissibility"
    assert abs(float(quoted) - branch.events[-1].value) <= 0.5e-4
    # subcritical: the period-2 orbits lie before the doubling (delay below it) and are unstable
    assert np.all(branch.values[1:] < pd.value)
    assert all(o.multipliers[0] > 1.0 for o in branch.orbits[1:])
    # the halves grow as the square root of the distance from the doubling
    d = pd.value - branch.values[1:]
    ratio = np.array(gaps) / np.sqrt(d)
    assert np.ptp(ratio[:3]) < 0.1 * ratio[0]


def test_one_impact_orbit_traversed_twice_flexible():
    model = BarModel(s=2.0, d=0.1, R=0.3, n_modes=2)
    o = find_orbit(model, PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0, delay=0.2))
    o2 = find_orbit(model, o.drive, impacts=2, guess=o)
    assert o2.impacts == 2 and o2.period == pytest.approx(2 * o.period, rel=1e-12)
    assert o2.blow_frequency == pytest.approx(o.blow_frequency, rel=1e-12)
    assert o2.impact_energy == pytest.approx(o.impact_energy, rel=1e-12)
    np.testing.assert_allclose(np.sort(np.abs(o2.multipliers)), np.sort(np.abs(o.multipliers) ** 2),
                               rtol=1e-7, atol=1e-12)
    assert o2.admissibility == o.admissibility and o2.stable == o.stable


def test_multi_impact_needs_a_guess_of_the_right_size():
    drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=0.3)
    with pytest.raises(ValueError, match="needs a guess"):
        find_orbit(MODEL, drive, impacts=2)
    with pytest.raises(ValueError, match="guess must hold 2 states"):
        find_orbit(MODEL, drive, impacts=2, guess=(np.zeros((3, 2)), [1.0] * 3, [1.0] * 3))


def test_a_simulated_run_as_the_guess():
    """The last valve cycles of a rigid run started off the orbit: Newton from them finds the
    one-impact orbit (and, asked for two impacts, that orbit traversed twice)."""
    drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=0.3, delay=1.0)
    o = find_orbit(MODEL, drive)
    run = simulate(MODEL, drive, InitialState.rigid(-0.2, 0.0), 1e4, max_impacts=30)
    assert abs(run.impact_velocities[-1] - o.impact_velocity) > 1e-9  # not yet on it
    for m in (1, 2):
        om = find_orbit(MODEL, drive, impacts=m, guess=run)
        np.testing.assert_allclose(om.impact_velocities, o.impact_velocity, rtol=1e-12)
        assert om.period == pytest.approx(m * o.period, rel=1e-12)
    with pytest.raises(ValueError, match="at least 31"):
        find_orbit(MODEL, drive, impacts=30, guess=run)
