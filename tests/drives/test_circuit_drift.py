"""The oil circuit's start for Newton where the supply pressure still drifts (a large accumulator
charging from its pre-charge toward the relief's setting): the motion is followed on until it stops
drifting, instead of Newton taking over from the pre-charge, whose linear model of that mode pointed
to negative pressures ("the oil circuit's flight ... could not be integrated"); where that drift is
too slow to tell at the hand-over's tolerance, it is carried to the relief's surface at once."""

import dataclasses
import functools

import numpy as np

from impactbar import InitialState, simulate
from impactbar.orbits._settling import DRIFT_AHEAD, drift_to_surface, drifting, nearing
from impactbar.orbits.driven import orbit_problem
from impactbar.physical.loader import build, read_config, with_values


def _stiff(factor):
    changes = {"oil.bulk_modulus": f"{1.4 * factor} GPa",
               "supply.front_flow_coefficient": f"{6e-6 * factor} m^3/s/Pa^0.5",
               "valve.flow_coefficient": f"{6e-6 * factor} m^3/s/Pa^0.5",
               "valve.switching_time": f"{1 / factor} ms",
               "accumulator.volume": f"{0.5 * factor} L",
               "supply.relief_pressure": "16 MPa",
               "supply.relief_coefficient": "1e-7 m^3/s/Pa"}
    return build(with_values(read_config("circuit-drifter")[0], changes))


@functools.cache
def _orbit(factor):
    return _stiff(factor).orbit()


def test_drifting_tells_a_drift_from_a_contraction():
    y = [np.array([1.0, 2.0]), np.array([1.001, 2.0]), np.array([1.002, 2.0])]
    assert drifting(*y, 1e-4)
    assert not drifting(y[0], y[1], np.array([1.0015, 2.0]), 1e-4)  # (halving: contracting)
    assert not drifting(y[0], y[1], np.array([1.00100001, 2.0]), 1e-4)  # (a step below tol)


def test_newton_start_past_the_accumulator_charging():
    # the preset with 100 times stiffer oil, openings and valve and a 50 L accumulator: from rest the
    # supply pressure rises from the 10 MPa pre-charge by some 4 kPa an impact while the impact
    # velocities repeat to 1e-4; the start handed to Newton is now at the relief's 16 MPa (it was at
    # 10.02 MPa, five impacts from rest)
    drifter = _stiff(100)
    drive = drifter.drive()
    problem = orbit_problem(drifter.model(), drive, 1)
    X = problem.initial(None, 1e-13, 50)
    ps = X[drive.layout["supply"] + 2]  # (q, v, then the drive's state)
    assert ps >= 0.999 * drive.supply.relief_pressure


def test_stiff_oil_orbit_from_rest_with_the_relief_open():
    # the same drifter's orbit from rest: its supply pressure sits on the relief's 16 MPa (the relief
    # open at impact, as the state gives), where Newton handed over with the relief's flag closed and
    # reached a root past its surface; orbit() checks that a simulate restarted from it repeats it
    orbit = _orbit(100)
    assert orbit.mean_supply_pressure_Pa >= 16e6 * (1 - 1e-4)
    assert 40.0 < orbit.blow_frequency_Hz < 45.0


def test_a_slow_steady_drift_is_carried_to_the_surface_ahead():
    # the 500 L accumulator's drift from its pre-charge: 4e-5 of the pressure scale an impact, its
    # steps growing by 1e-5 each, 15,000 impacts from the relief's setting (1.6 in the scale)
    drifter = _stiff(1000)
    drive, model = drifter.drive(), drifter.model()
    M = model.n_modes + 1
    q, v = np.zeros(M), np.zeros(M)
    state = drive.start(model, q, v)
    i = 2 * M + drive.layout["supply"]
    d = np.zeros(2 * M + state.z.size)
    d[M], d[i - 2:i + 1] = -1.4e-6, 4e-5
    y0 = np.concatenate((q, v, state.z))

    def carried(rho, y=y0, turn=0.0):  # (the last step rho d, its impact velocity's turned)
        last = rho * d
        last[M] += turn
        return drift_to_surface(drive, state.mode, y, y + d, y + d + last, M)

    last = 1.00001 * d
    y2 = y0 + d + last
    far = carried(1.00001)
    s = (1.6 - y2[i]) / last[i]  # (the steps to the relief's setting, every part along the last step)
    assert 1.6 - 1e-9 < far[i] <= 1.6
    np.testing.assert_allclose(far, y2 + s * last, rtol=0, atol=1e-9)
    assert carried(0.999) is None  # (its limit 999 steps on, short of the relief: Newton's to find)
    assert carried(0.99999) is not None  # (its limit 99,999 steps on, past the relief)
    # (the impact velocity's step still settling: not one multiple, followed on to tell)
    assert carried(1.0, turn=-3e-5) is None
    turned = d.copy()
    turned[M] -= 3e-5
    assert nearing(drive, state.mode, y0, y0 + d, y0 + d + turned, M)  # (its supply's steps the same)
    slowing = d.copy()
    slowing[i - 2:i + 1] *= 0.99
    assert not nearing(drive, state.mode, y0, y0 + d, y0 + d + slowing, M)
    near = y0.copy()
    near[i] = 1.6 - 0.5 * DRIFT_AHEAD * d[i]  # (the motion followed on gets there)
    assert carried(1.0, y=near) is None


def test_stiffer_oil_still_finds_its_orbit_with_the_relief_open():
    # the sequence one decade on: 1000 times stiffer oil and openings, the valve 1000 times faster and
    # a 500 L accumulator, whose charging by 4e-5 of the pressure an impact went under the hand-over's
    # tolerance, so that Newton started from the 10 MPa pre-charge (its step to the integrator's
    # failure); its orbit sits on the relief (the flag open at impact, as the pressure gives; orbit()
    # checks that simulate restarted from it repeats it) and the sequence converges at first order:
    # 42.179, 42.454, 42.480 Hz and 8.4242, 8.4154, 8.4140 m/s for k = 10, 100, 1000
    orbits = [_orbit(k) for k in (10, 100, 1000)]
    stiff = orbits[-1]
    drive = stiff.orbit.drive
    mode = stiff.orbit._problem.blocks[0][1]
    ps = stiff.orbit.drive_states[0][drive.layout["supply"]]
    assert ps > drive.supply.relief_pressure and drive._flags(mode)[1] == 1
    assert stiff.mean_supply_pressure_Pa >= 16e6
    for output, ratio in (("blow_frequency_Hz", 0.2), ("impact_velocity_m_s", 0.25)):
        x = [getattr(o, output) for o in orbits]
        assert abs(x[2] - x[1]) < ratio * abs(x[1] - x[0])


def test_the_next_decade_finds_its_orbit_on_the_relief():
    # 10,000 times stiffer oil and openings, the valve 10,000 times faster and a 5000 L accumulator:
    # from rest the supply pressure rises by 4.05e-6 of its scale an impact, the same to 3e-6 impact
    # after impact, while the state's step is still half the fast parts' settling (0.83 times the
    # one before along it) as the impacts repeat to 1e-4; the drift was not followed on then, and
    # Newton's first step from the 10 MPa pre-charge went to -30 MPa (its flight not integrated)
    orbits = [_orbit(k) for k in (100, 1000, 10000)]
    stiff = orbits[-1]
    # first order in the oil's compliance (1 / k): the differences shrink tenfold a decade (the
    # ratios of successive differences of the frequency 0.114 and 0.095 for k = 1 ... 1000), so the
    # next difference is 0.1 times the last, to 0.02 of it
    f = [o.blow_frequency_Hz for o in orbits]
    assert abs((f[2] - f[1]) - 0.1 * (f[1] - f[0])) < 0.02 * abs(f[1] - f[0])
    assert abs(f[2] - 42.483) < 1e-3
    v = [o.impact_velocity_m_s for o in orbits]
    assert abs(v[2] - v[1]) < 0.25 * abs(v[1] - v[0])
    # the relief open at impact, as the supply pressure above its setting gives
    orbit = stiff.orbit
    drive = orbit.drive
    ps = orbit.drive_states[0][drive.layout["supply"]]
    assert ps > drive.supply.relief_pressure and drive._flags(orbit._problem.blocks[0][1])[1] == 1
    assert stiff.mean_supply_pressure_Pa >= 16e6
    assert np.max(np.abs(orbit.multipliers)) < 1.0
    # simulate restarted from the state after the impact repeats it over five periods
    M = orbit.model.n_modes + 1
    y = np.asarray(orbit.states_after_impact[0], dtype=float)
    restart = dataclasses.replace(drive, start_pressures=tuple(orbit.drive_states[0]))
    T = orbit.period
    run = simulate(orbit.model, restart, InitialState(y[:M], y[M:]), 5.0 * T * (1.0 + 1e-3), max_impacts=5)
    np.testing.assert_allclose(run.impact_times, T * np.arange(1, 6), rtol=1e-6)
    np.testing.assert_allclose(run.impact_velocities, orbit.impact_velocity, rtol=1e-6)
    np.testing.assert_allclose(run._final_drive.z, orbit.drive_states[0], rtol=1e-6, atol=1e-9)
