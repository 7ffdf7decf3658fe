"""The oil circuit's solver options (:class:`CircuitFlightSettings`: the compiled driver, the linear
solvers, the variational flights' fundamental matrix, the plain flights' method) are handed to the
solvers, never held by the drive: two circuits of the same parts are one drive (equal, one hash)
however they are solved, and what is remembered of a solve (an orbit's problem and its last flight,
the continuation's problems) is keyed on the settings as well as on the drive."""

import dataclasses
import math

import numpy as np
import pytest
from test_circuit_cvode import RIGID, pumped

from impactbar import (
    BarModel,
    CosineLoad,
    InitialState,
    continue_orbit,
    find_orbit,
    periodic_orbits,
    simulate,
)
from impactbar.drives import FlightSettings
from impactbar.drives.circuit import CircuitFlightSettings
from impactbar.drives.circuit.settings import DEFAULT_SETTINGS, circuit_settings
from impactbar.orbits.driven import orbit_problem

#: the options of how the circuit's flights are integrated
OPTIONS = ("compiled", "band", "blocks", "sensitivity", "multistep")


def test_the_drive_holds_no_solver_option():
    a, b = pumped(), pumped()
    assert a == b and hash(a) == hash(b) and repr(a) == repr(b)
    fields = {f.name for f in dataclasses.fields(a)}
    assert not fields & set(OPTIONS)
    for name in OPTIONS:
        with pytest.raises(TypeError):
            dataclasses.replace(a, **{name: getattr(DEFAULT_SETTINGS, name)})
    assert a.integrator == DEFAULT_SETTINGS == CircuitFlightSettings()
    assert isinstance(a.integrator, FlightSettings)
    assert (a.integrator.method, a.integrator.rtol, a.integrator.atol) == ("CVODE", 1e-10, 1e-12)


@pytest.mark.parametrize("changes, message", [
    ({"method": "LSODA"}, "method must be 'CVODE'"),
    ({"rtol": 0.0}, "rtol must be positive and finite"),
    ({"atol": math.nan}, "atol must be positive and finite"),
    ({"rtol": "1e-10"}, "rtol must be positive and finite"),
    ({"compiled": 0}, "compiled must be True or False"),
    ({"band": "yes"}, "band must be True or False"),
    ({"blocks": None}, "blocks must be True or False"),
    ({"sensitivity": "exact"}, "sensitivity must be one of"),
    ({"multistep": "BDF"}, "multistep must be one of"),
    ({"magnus_theta": -1.0}, "magnus_theta must be None or positive"),
])
def test_bad_settings_are_refused(changes, message):
    with pytest.raises(ValueError, match=message):
        CircuitFlightSettings(**changes)


def test_a_plain_flight_settings_gives_its_tolerances_and_the_default_options():
    plain = FlightSettings(method="CVODE", rtol=1e-9, atol=1e-11, magnus_theta=2.0)
    s = circuit_settings(plain)
    assert (s.rtol, s.atol, s.magnus_theta) == (1e-9, 1e-11, 2.0)
    assert all(getattr(s, name) == getattr(DEFAULT_SETTINGS, name) for name in OPTIONS)
    assert circuit_settings(None) is DEFAULT_SETTINGS
    assert circuit_settings(FlightSettings()) is DEFAULT_SETTINGS  # (LSODA: not the circuit's)
    own = CircuitFlightSettings(sensitivity="cvode")
    assert circuit_settings(own) is own
    # (the tolerances changed, the options kept: the Newton start's and the steering flights')
    assert dataclasses.replace(own, rtol=1e-7).sensitivity == "cvode"


def test_settings_go_with_a_drive_only():
    model = BarModel(s=10, d=0.05, R=0.5, n_modes=0)
    with pytest.raises(ValueError, match="settings: .* only with a Drive"):
        simulate(model, CosineLoad(0.3, 1.0), InitialState.rigid(-0.01, 0.0), 1.0, settings=DEFAULT_SETTINGS)
    with pytest.raises(ValueError, match="settings: .* only with a Drive"):
        find_orbit(model, CosineLoad(0.1, 1.0), settings=DEFAULT_SETTINGS)
    with pytest.raises(ValueError, match="settings: .* only with a Drive"):
        periodic_orbits(model, CosineLoad(0.1, 1.0), settings=DEFAULT_SETTINGS)
    with pytest.raises(ValueError, match="settings must be a FlightSettings"):
        simulate(RIGID, pumped(), InitialState.rigid(0.0, 0.0), 1.0, settings={"compiled": False})
    with pytest.raises(ValueError, match="settings must be a FlightSettings"):
        find_orbit(RIGID, pumped(), settings="cvode")
    with pytest.raises(ValueError, match="settings must be a FlightSettings"):
        periodic_orbits(RIGID, pumped(), settings=1e-10)


def test_equal_drives_solved_with_other_settings_differ_only_as_the_settings_say():
    """Two circuits built alike, the rigid piston's orbit found with CVODE's variational flights and
    with Magnus' fundamental matrix: the drives are equal and hash alike; the orbits agree to the
    flights' tolerance (the period and the impact velocity to 1e-8, measured 2.1e-10 and 3.6e-10:
    Magnus' plain flights at a thousand times finer a tolerance; the multipliers to 1e-7, measured
    1.6e-9), not to the bit (the flights and the Jacobians differ); each orbit keeps its settings, a
    problem of the other settings never takes its remembered flight, a guess of the other settings
    gives its blocks only, and a continuation's points keep the start's."""
    a, b = pumped(), pumped()
    cvode, magnus = CircuitFlightSettings(sensitivity="cvode"), CircuitFlightSettings(sensitivity="magnus")
    oc = find_orbit(RIGID, a, settings=cvode)
    om = find_orbit(RIGID, b, settings=magnus)
    assert oc.drive == om.drive and hash(oc.drive) == hash(om.drive)
    assert oc.problem.settings == cvode and om.problem.settings == magnus
    assert oc.period == pytest.approx(om.period, rel=1e-8)
    assert oc.impact_velocity == pytest.approx(om.impact_velocity, rel=1e-8)
    assert np.max(np.abs(oc.multipliers - om.multipliers)) <= 1e-7
    assert oc.period != om.period and not np.array_equal(oc.multipliers, om.multipliers)
    # the default is the drive's integrator: "auto", CVODE's flights for the rigid piston, to the bit
    od = find_orbit(RIGID, a)
    assert od.problem.settings == DEFAULT_SETTINGS and od.period == oc.period
    assert np.array_equal(od.multipliers, oc.multipliers)
    # the problem's remembered flight is its settings' as well as its drive's
    assert oc.problem._last is not None
    same = orbit_problem(RIGID, b, 1, cvode).adopt(oc.problem)
    other = orbit_problem(RIGID, b, 1, magnus).adopt(oc.problem)
    assert same._last is oc.problem._last and other._last is None
    again = find_orbit(RIGID, b, guess=oc, settings=magnus)
    assert again.problem.settings == magnus
    assert again.period == pytest.approx(om.period, rel=1e-10)
    assert np.max(np.abs(again.multipliers - om.multipliers)) <= 1e-8
    # every orbit of the drive's search is its settings'
    listed = periodic_orbits(RIGID, a, settings=cvode)
    assert len(listed) == 1 and listed[0].problem.settings == cvode and listed[0].period == oc.period
    # the continuation's problems keep the start's settings
    branch = continue_orbit(oc, "pump_flow", to=0.0702, max_points=3, events=False)
    assert len(branch.orbits) >= 2
    assert all(o.problem.settings == cvode for o in branch.orbits)
