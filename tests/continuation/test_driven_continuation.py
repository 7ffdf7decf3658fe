"""Continuation of periodic motions under a position-switched drive (theory §10): the rigid
piston's branch against its closed form, a period doubling located in the valve delay and
reproduced by simulate on both sides (the deviation from the orbit flips sign at every blow, and
shrinks before the doubling and grows after it, by the located multiplier), folds in the switch
position of a flexible bar."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

from impactbar import BarModel, PositionSwitchedDrive, continue_orbit, find_orbit, simulate
from impactbar.simulation import InitialState


def test_rigid_branch_in_switch_out_is_the_closed_form():
    model = BarModel(s=10.0, d=0.0, R=0.3, n_modes=0)
    drive = PositionSwitchedDrive(stroke=1.2, ret=0.8, switch_out=0.5)
    b = continue_orbit(find_orbit(model, drive), "switch_out", to=2.0)
    assert b.status == "reached" and len(b) > 5 and b.events == ()
    for x1, o in zip(b.values, b.orbits, strict=True):
        closed = PositionSwitchedDrive(stroke=1.2, ret=0.8, switch_out=x1).rigid_orbit(0.3)
        assert o.impact_velocity == pytest.approx(closed["impact_velocity"], rel=1e-10)
        assert o.period == pytest.approx(closed["period"], rel=1e-10)
        assert o.multipliers[0] == pytest.approx(0.09, abs=1e-10)
    assert b.values[-1] == 2.0


def _deviation_ratios(model, drive, orbit, blows=14):
    """Successive ratios of the impact velocity's deviation from the orbit's, simulated from the
    orbit's state where the valve switches to return (rigid, d = 0: ``q_0 = -R v tau + tau^2/2``
    under the stroke force), its velocity nudged by 1e-7."""
    R, v, tau, a = model.R, orbit.impact_velocity, drive.delay, drive.stroke
    q0, w0 = -R * v * tau + 0.5 * a * tau * tau, -R * v + a * tau
    tr = simulate(model, drive, InitialState.rigid(q0, w0 * (1.0 + 1e-7)), 1e4, max_impacts=blows)
    dev = tr.impact_velocities - v
    return dev[1:] / dev[:-1]


def test_period_doubling_in_the_delay_is_reproduced_by_simulate():
    model = BarModel(s=10.0, d=0.0, R=0.3, n_modes=0)
    o = find_orbit(model, PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=0.3, delay=1.0))
    b = continue_orbit(o, "delay", to=2.0)
    pd = [e for e in b.events if e.kind == "period-doubling"]
    assert len(pd) == 1
    ev = pd[0]
    assert ev.multiplier == pytest.approx(-1.0, abs=1e-6) and 1.0 < ev.value < 2.0
    assert ev.orbit.admissibility == "admissible"
    theory = re.sub(r"\s+", " ", (Path(__file__).resolve().parents[2] / "docs" / "theory.md").read_text())
    quoted = re.search(r"passes \$-1\$ at \$\\tau \\approx ([0-9]+\.[0-9]+)\$", theory).group(1)
    assert abs(float(quoted) - ev.value) <= 0.5e-4  # the theory page quotes it to 4 decimals
    for delay in (ev.value - 0.08, ev.value + 0.08):
        drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=0.3, delay=delay)
        orbit = find_orbit(model, drive, guess=ev.orbit)
        mu = float(orbit.multipliers[0])
        ratios = _deviation_ratios(model, drive, orbit)
        assert np.all(ratios < 0)  # the deviation flips at every blow
        np.testing.assert_allclose(ratios, mu, rtol=1e-3)
        assert (abs(mu) < 1.0) == (delay < ev.value)  # decays before, grows after


def test_folds_in_the_switch_position_of_a_flexible_bar():
    model = BarModel(s=2.0, d=0.1, R=0.3, n_modes=2)
    o = find_orbit(model, PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0))
    b = continue_orbit(o, "switch_out", to=3.0, max_points=40)
    folds = [e for e in b.events if e.kind == "fold"]
    assert folds
    for e in folds:
        assert abs(e.multiplier - 1.0) < 1e-6
        i = e.index  # the branch turns back in switch_out there
        assert (b.values[i] - e.value) * (b.values[i - 1] - e.value) > 0
        assert e.orbit.drive.switch_out == e.value


def test_switched_continuation_refuses_a_load_parameter():
    o = find_orbit(BarModel(s=10.0, d=0.0, R=0.3, n_modes=0), PositionSwitchedDrive(1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match=r"parameter must be one of .*'switch_out'.* \(of the BarModel and "
                                         r"the PositionSwitchedDrive\); got 'q'"):
        continue_orbit(o, "q", to=2.0)
    with pytest.raises(ValueError, match="to must differ"):
        continue_orbit(o, "delay", to=0.0)
    assert math.isfinite(o.switch_velocity) and o.switch_velocity > 0
