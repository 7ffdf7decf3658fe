"""A flexible bar's orbit under the valve from what a user has. A settled run of
``simulate`` is read as the guess (its flights' modal states after the impacts; it was refused, "read
for the rigid bar only"), and the default guess goes on from the rigid orbit lifted to the modes to
a run from rest when Newton fails there (it did not converge in 50 steps on the first of the valve
cases of tests/drives/test_drive_orbits.py) or reaches an orbit that is not stable (then the search
of every orbit: tests/drives/test_drive_orbits.py)."""

import numpy as np
import pytest

from impactbar import BarModel, InitialState, PositionSwitchedDrive, find_orbit, simulate

CASE1 = BarModel(3, 0.1, 0.6, 6), PositionSwitchedDrive(1, 0.5, 0.15)


@pytest.fixture(scope="module")
def settled():
    model, drive = CASE1
    return simulate(model, drive, InitialState.rigid(-0.1, 0.0, 6), 300.0)


def test_a_settled_flexible_run_is_a_guess(settled):
    model, drive = CASE1
    orbit = find_orbit(model, drive, guess=settled)
    assert orbit.admissible and orbit.stable
    # the run has settled on it: its last intervals and impact velocities (to the run's own settling)
    assert orbit.period == pytest.approx(np.mean(np.diff(settled.impact_times)[-4:]), rel=1e-6)
    assert orbit.impact_velocities[0] == pytest.approx(settled.impact_velocities[-1], rel=1e-5)
    # and it is a fixed point: a run started on it repeats it over ten periods (the simulator's own
    # event location, independent of the orbit's Newton)
    start = InitialState(orbit.state[:7], orbit.state[7:])
    again = simulate(model, drive, start, 10.5 * orbit.period)
    assert np.allclose(np.diff(again.impact_times), orbit.period, rtol=1e-9)
    assert np.allclose(again.impact_velocities, orbit.impact_velocities[0], rtol=1e-9)


def test_the_default_guess_reaches_the_stable_orbit(settled):
    model, drive = CASE1
    default = find_orbit(model, drive)
    from_run = find_orbit(model, drive, guess=settled)
    assert default.stable and default.admissible
    assert default.period == pytest.approx(from_run.period, rel=1e-12)
    np.testing.assert_allclose(default.state, from_run.state, rtol=1e-10, atol=1e-12)
