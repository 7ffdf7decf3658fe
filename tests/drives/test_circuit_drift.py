"""The oil circuit's start for Newton where the supply pressure still drifts (a large accumulator
charging from its pre-charge toward the relief's setting): the motion is followed on until it stops
drifting, instead of Newton taking over from the pre-charge, whose linear model of that mode pointed
to negative pressures ("the oil circuit's flight ... could not be integrated")."""

import numpy as np

from impactbar.orbits._settling import drifting
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
    orbit = _stiff(100).orbit()
    assert orbit.mean_supply_pressure_Pa >= 16e6 * (1 - 1e-4)
    assert 40.0 < orbit.blow_frequency_Hz < 45.0
