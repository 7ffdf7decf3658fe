"""The drifter with its oil circuit off its happy path (``impactbar.physical.circuit``): a stop that
keeps the piston (``restitution = 0``, a rest phase on the stop), the config's values checked in SI
with the user's key, and orbits that are no motion at all refused."""

import numpy as np
import pytest

from impactbar.physical.circuit import CIRCUIT_PRESETS, circuit_preset


def test_a_run_with_restitution_zero_rests_on_the_stop_and_its_energy_account_closes():
    """With ``R = 0`` every arrival ends the piston's motion: it rests on the stop while the oil
    presses it there (the circuit's state integrated alone), then leaves when the force turns. The
    rest phase was integrated with the circuit's CVODE name handed to scipy (refused); now the rest
    carries the circuit's energy terms, so that the account closes over the whole run."""
    from impactbar.drives.flight import QuadratureRestPiece

    d = circuit_preset("circuit-drifter", stop={"restitution": 0})
    out = d.simulate(0.04)
    run = out["run"]
    assert out["impact_times_s"].size >= 1 and run.contact_intervals.shape[0] >= 1
    rests = [p for p in run.pieces if isinstance(p, QuadratureRestPiece)]
    assert len(rests) == run.contact_intervals.shape[0]
    alpha = run.drive.chambers.area_ratio
    for p in rests:
        assert p.t_end > p.t0
        t = np.linspace(p.t0, p.t_end, 201)
        z = p.drive_state(t)
        force = z[1] - alpha * z[0]
        assert np.all(force > -1e-9)  # the oil presses the piston onto the stop throughout
        assert abs(force[-1]) < 1e-8  # and it leaves where the force turns
        q, v = run.modal_state(t)
        assert np.all(q == 0.0) and np.all(v == 0.0)
        assert p.energies()[0] > 0.0 and p.energies()[1] == 0.0  # the pump works, the piston does not
    acc = run.drive.energy(run)
    assert abs(acc["relative_residual"]) < 1e-9
    # the account without the rests' terms would be off by the pump's work during them
    assert sum(p.energies()[0] for p in rests) > 1e-4 * acc["pump"]


_PRESET = CIRCUIT_PRESETS["circuit-drifter"]
#: every key of the circuit's sections with a value to turn negative (the preset's, or one in range)
_KEYS = [(sec, key, value) for sec in ("chambers", "valve", "supply", "accumulator", "oil")
         for key, value in _PRESET[sec].items()] + [("valve", "switch_in", "10 mm")]


def _negative(value):
    if isinstance(value, str):
        number, unit = value.split(" ", 1)
        return f"-{number} {unit}", unit
    return -value, ""


def _refused(**changes) -> str:
    with pytest.raises(ValueError) as info:
        circuit_preset("circuit-drifter", **changes)
    message = str(info.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize(("sec", "key", "value"), _KEYS, ids=[f"{s}.{k}" for s, k, _ in _KEYS])
def test_a_key_given_none_is_refused_naming_it_and_its_unit(sec, key, value):
    """``None`` reached the arithmetic (a TypeError) or read as the key left out."""
    message = _refused(**{sec: {key: None}})
    assert message.startswith(f"{sec}.{key} must be ") and "got None" in message
    if isinstance(value, str):  # the unit it needs, with an example
        assert "e.g. '" in message and any(u in message for u in ("m^2", "m^3", "m^3/s", "Pa", "m", "s"))


@pytest.mark.parametrize(("sec", "key", "value"), _KEYS, ids=[f"{s}.{k}" for s, k, _ in _KEYS])
def test_a_negative_value_is_refused_in_si_naming_the_key_and_quoting_the_value(sec, key, value):
    """Each refused before the conversion to the dimensionless circuit: the key as ``section.key``
    and the value as the user wrote it, with its unit (not a bare name and a dimensionless number),
    ``accumulator.volume = "-0.5 L"`` among them (it read as no accumulator)."""
    negative, unit = _negative(value)
    message = _refused(**{sec: {key: negative}})
    assert message.startswith(f"{sec}.{key} must be ")
    assert message.endswith(f"; got {negative}".rstrip()) and (unit == "" or unit in message)


@pytest.mark.parametrize(("changes", "expected"), [
    ({"supply": {"relief_pressure": "0.2 MPa"}},
     "supply.relief_pressure must be above supply.tank_pressure (0.3 MPa); got 0.2 MPa"),
    ({"chambers": {"rear_volume": "-0.1 L"}}, "chambers.rear_volume must be positive; got -0.1 L"),
    ({"accumulator": {"volume": "-0.5 L"}},
     "accumulator.volume must be 0 or above (0: no accumulator); got -0.5 L"),
    ({"accumulator": {"precharge": "30 MPa"}},
     "accumulator.precharge must be below supply.relief_pressure (25 MPa): the accumulator would never take "
     "oil; got 30 MPa"),
    ({"chambers": {"front_area": "6 cm^2"}},
     "chambers.front_area must be below chambers.rear_area (5.6 cm^2) for the stroke to push toward the "
     "stop; got 6 cm^2"),
    ({"valve": {"switch_in": "30 mm"}},
     "valve.switch_in must be above 0 and below valve.switch_out (21.5 mm); got 30 mm"),
    ({"accumulator": {"polytropic_exponent": 2.5}},
     "accumulator.polytropic_exponent must be in [1, 2] (1 isothermal, 1.4 adiabatic nitrogen); got 2.5"),
    ({"stop": {"restitution": 1.0}}, "stop.restitution must be in [0, 1); got 1"),
    ({"supply": {"relief_coefficient": "0 m^3/s/Pa"}},
     "supply.relief_coefficient must be positive with a supply.relief_pressure; got 0 m^3/s/Pa"),
])
def test_range_errors_speak_si(changes, expected):
    assert _refused(**changes) == expected


def test_an_accumulator_of_no_volume_is_still_none():
    d = circuit_preset("circuit-drifter", accumulator={"volume": "0 L"})
    assert d.drive().accumulator is None
