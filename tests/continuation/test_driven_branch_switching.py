"""Branch switching at a period doubling of a driven orbit (theory §10): a supercritical doubling
on a flexible bar, where the two-impact branch started from the event is stable past the doubling
and simulate settles onto it (impact velocities to 1e-8), and onto the one-impact orbit before it."""

import re
from pathlib import Path

import numpy as np
import pytest

from impactbar import BarModel, InitialState, PositionSwitchedDrive, continue_orbit, find_orbit, simulate
from impactbar.orbits.valve_segment import _legs

MODEL = BarModel(s=1.0, d=0.05, R=0.3, n_modes=2)


def _drive(delay):
    return PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=0.3, delay=delay)


@pytest.fixture(scope="module")
def doubling():
    b = continue_orbit(find_orbit(MODEL, _drive(0.09)), "delay", to=0.1)
    (pd,) = [e for e in b.events if e.kind == "period-doubling"]
    return pd, continue_orbit(pd, "delay", to=0.1, stop_on=("period-doubling",))


def _settled(delay, guess_orbit, blows=3000):
    """Impact velocities of the last two blows of a run started near the one-impact orbit (its
    state where the valve switches to return, velocities nudged by 1e-3)."""
    o1 = find_orbit(MODEL, _drive(delay), guess=guess_orbit)
    za = _legs(MODEL, o1.drive, o1.state, o1.durations)[0]
    M = MODEL.n_modes + 1
    tr = simulate(MODEL, o1.drive, InitialState(za[:M], za[M:] * (1 + 1e-3)), 1e6, max_impacts=blows)
    assert tr.n_impacts == blows
    return o1, np.sort(tr.impact_velocities[-2:])


def test_supercritical_doubling_simulate_settles_on_the_two_impact_branch(doubling):
    pd, branch = doubling
    assert abs(pd.multiplier + 1.0) < 1e-6 and pd.orbit.admissible
    assert branch.impacts == 2 and branch.values[0] == pd.value
    assert branch.status == "stopped at period-doubling"  # the cascade's next doubling
    assert np.all(branch.values[1:] > pd.value)  # supercritical: born past the doubling
    inside = branch.orbits[1:-1]
    assert all(o.stable for o in inside)  # and stable until the next doubling
    second = branch.events[-1].value
    theory = re.sub(r"\s+", " ", (Path(__file__).resolve().parents[2] / "docs" / "theory.md").read_text())
    quoted = re.search(r"doubles at \$\\tau \\approx ([0-9.]+)\$ and again at \$\\tau \\approx ([0-9.]+)\$",
                       theory).groups()
    assert abs(float(quoted[0]) - pd.value) <= 0.5e-6 and abs(float(quoted[1]) - second) <= 0.5e-6
    # past the doubling: simulate from the (now unstable) one-impact orbit settles on the period-2 one
    delay = pd.value + 0.6 * (second - pd.value)
    near = branch.orbits[int(np.argmin(np.abs(branch.values - delay)))]
    o2 = find_orbit(MODEL, _drive(delay), impacts=2, guess=near)
    assert o2.stable and o2.admissible and abs(np.diff(o2.impact_velocities)[0]) > 0.1
    o1, v = _settled(delay, pd.orbit)
    assert not o1.stable
    np.testing.assert_allclose(v, np.sort(o2.impact_velocities), rtol=0, atol=1e-8)
    # before it: onto the one-impact orbit
    o1, v = _settled(pd.value - 0.6 * (second - pd.value), pd.orbit)
    assert o1.stable
    np.testing.assert_allclose(v, o1.impact_velocity, rtol=0, atol=1e-8)
