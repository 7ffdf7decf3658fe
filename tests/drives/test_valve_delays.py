"""The valve's two delays (theory §10): ``delay_out`` after the ``switch_out`` crossing, ``delay_in``
after the impact, ``delay`` both. The rigid undamped piston's orbit against the fixed point of its
map of arrival velocities in elementary kinematics (no modal flows), its multiplier against that
map's slope; the flexible bar's orbit against the motion simulate settles on."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from impactbar import BarModel, InitialState, PositionSwitchedDrive, continue_orbit, find_orbit, simulate


def _fixed_point(args):
    return brentq(lambda v: _cycle(v, *args)[0] - v, 1e-3, 100.0, xtol=1e-15, rtol=1e-15)


def _cycle(v, a_s, a_r, x1, t_in, t_out, R):
    """Rigid piston, no damping: arrival velocity ``v`` -> the next one, and the time between. Gap
    ``y``: stroke (``y'' = -a_s``) for t_in, return (``y'' = a_r``) until ``y = x1``, return for
    t_out, stroke until ``y = 0``."""
    y, w = R * v * t_in - 0.5 * a_s * t_in**2, R * v - a_s * t_in
    u1 = math.sqrt(w * w + 2.0 * a_r * (x1 - y))  # the gap's rate at the crossing (rising)
    h1 = (u1 - w) / a_r
    w2 = u1 + a_r * t_out
    y2 = x1 + u1 * t_out + 0.5 * a_r * t_out**2
    v_next = math.sqrt(w2 * w2 + 2.0 * a_s * y2)
    return v_next, t_in + h1 + t_out + (w2 + v_next) / a_s


@pytest.mark.parametrize("t_out, t_in", [(0.1, 0.0), (0.0, 0.1), (0.3, 0.05), (0.05, 0.3)])
def test_rigid_orbit_is_the_fixed_point_of_the_kinematic_map(t_out, t_in):
    R, a_s, a_r, x1 = 0.3, 1.0, 0.7, 0.4
    drive = PositionSwitchedDrive(a_s, a_r, x1, delay_out=t_out, delay_in=t_in)
    o = find_orbit(BarModel(s=10.0, d=0.0, R=R, n_modes=0), drive)
    args = (a_s, a_r, x1, t_in, t_out, R)
    v = _fixed_point(args)
    assert o.impact_velocity == pytest.approx(v, rel=1e-12)
    assert o.period == pytest.approx(_cycle(v, *args)[1], rel=1e-12)
    assert o.switch_times[0] == pytest.approx(t_in, abs=1e-14)  # to return, t_in after the impact
    h = 1e-6
    slope = (_cycle(v + h, *args)[0] - _cycle(v - h, *args)[0]) / (2 * h)
    assert float(o.multipliers[0]) == pytest.approx(slope, abs=1e-8)
    assert o.admissibility == "admissible" and o.stable


def test_delay_is_both_delays():
    a = PositionSwitchedDrive(1.0, 1.0, 0.5, delay=0.2)
    b = PositionSwitchedDrive(1.0, 1.0, 0.5, delay_out=0.2, delay_in=0.2)
    assert a == b and a.delay == 0.2 and (a.delay_out, a.delay_in) == (0.2, 0.2)
    c = PositionSwitchedDrive(1.0, 1.0, 0.5, delay=0.2, delay_in=0.1)
    assert (c.delay_out, c.delay_in, c.delay) == (0.2, 0.1, None)
    assert c.with_(delay=0.3) == PositionSwitchedDrive(1.0, 1.0, 0.5, delay=0.3)
    assert c.with_(delay_in=0.2) == a
    model = BarModel(s=10.0, d=0.05, R=0.3, n_modes=2)
    oa, ob = find_orbit(model, a), find_orbit(model, b)
    assert oa.period == ob.period and np.array_equal(oa.state, ob.state)
    for kw in ({"delay_out": -1.0}, {"delay_in": math.nan}, {"delay_in": "x"}):
        with pytest.raises(ValueError, match=next(iter(kw))):
            PositionSwitchedDrive(1.0, 1.0, 0.5, **kw)


@pytest.mark.parametrize("t_out, t_in", [(0.08, 0.0), (0.0, 0.08), (0.1, 0.03)])
def test_flexible_orbit_is_the_motion_simulate_settles_on(t_out, t_in):
    model = BarModel(s=10.0, d=0.3, R=0.3, n_modes=3)
    drive = PositionSwitchedDrive(1.0, 1.0, 1.0, delay_out=t_out, delay_in=t_in)
    o = find_orbit(model, drive)
    assert o.admissibility == "admissible" and o.stable
    run = simulate(model, drive, InitialState.rigid(0.0, 0.0, 3), 250.0)  # from rest on the stop
    ti = run.impact_times
    assert ti[-1] - ti[-2] == pytest.approx(o.period, rel=1e-9)
    assert run.impact_velocities[-1] == pytest.approx(o.impact_velocity, rel=1e-8)
    after = run.switch_times[run.switch_times >= ti[-2]][:2] - ti[-2]
    assert after == pytest.approx(o.switch_times, abs=1e-8)
    # the switch to return t_in after the impact; to stroke t_out after the crossing of switch_out
    assert o.switch_times[0] == pytest.approx(t_in, abs=1e-14)
    assert o.durations[2] == t_out


def test_continuation_in_each_delay():
    model = BarModel(s=10.0, d=0.0, R=0.3, n_modes=0)
    drive = PositionSwitchedDrive(1.0, 0.7, 0.4, delay_out=0.1, delay_in=0.05)
    o = find_orbit(model, drive)
    for name, other in (("delay_in", "delay_out"), ("delay_out", "delay_in")):
        branch = continue_orbit(o, name, to=0.2, max_points=30)
        end = branch.orbits[-1]
        assert getattr(end.drive, name) == pytest.approx(0.2)
        assert getattr(end.drive, other) == getattr(drive, other)
        t_out, t_in = end.drive.delay_out, end.drive.delay_in
        args = (1.0, 0.7, 0.4, t_in, t_out, 0.3)
        v = _fixed_point(args)
        assert end.impact_velocity == pytest.approx(v, rel=1e-10)
    with pytest.raises(ValueError, match="delay_out"):
        continue_orbit(o, "delay", to=0.2)
