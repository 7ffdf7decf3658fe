"""A value far outside its key's typical range (the documentation's table of the circuit's keys) is
warned of, naming the key, the value as written and the range, and run; the command line prints it
once, as one line."""

import warnings

import pytest

from impactbar.physical import build, read_config, with_values
from impactbar.physical.plausibility import ImplausibleValueWarning

pytest.importorskip("pint")


def _warned(config, folder=None):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        build(config, folder)
    return [str(w.message) for w in caught if issubclass(w.category, ImplausibleValueWarning)]


@pytest.mark.parametrize("key, value, expected", [
    ("accumulator.precharge", "12 bar", "accumulator.precharge = '12 bar' (1.2 MPa) is far outside its "
                                        "typical range 6-22.5 MPa (beyond a factor 4)"),
    ("supply.tank_pressure", "0 MPa", "supply.tank_pressure = '0 MPa' (0 MPa) is far outside its typical "
                                      "range 0.2-1 MPa (beyond a factor 4)"),
    ("supply.pump_flow", "85 L/s", "supply.pump_flow = '85 L/s' (5100 L/min) is far outside its typical "
                                   "range 40-150 L/min (beyond a factor 4)"),
])
def test_a_value_far_outside_its_typical_range_is_warned_of(key, value, expected):
    config, folder = read_config("examples/circuit_drifter.toml")
    assert _warned(with_values(config, {key: value}), folder) == [expected]
    assert issubclass(ImplausibleValueWarning, UserWarning)


@pytest.mark.parametrize("source", ["circuit-drifter", "examples/circuit_drifter.toml",
                                    "examples/circuit_drifter_rock.toml",
                                    "examples/circuit_drifter_rock_piston.toml"])
def test_the_presets_and_examples_are_plausible(source):
    assert _warned(*read_config(source)) == []


def test_a_value_just_inside_far_is_not_warned_of():
    config, folder = read_config("examples/circuit_drifter.toml")
    assert _warned(with_values(config, {"supply.pump_flow": "590 L/min", "supply.tank_pressure": "0.06 MPa"}),
                   folder) == []


def test_the_command_line_prints_it_once_as_one_line(tmp_path, capsys):
    from impactbar.cli import main

    text = open("examples/circuit_drifter.toml").read()
    path = tmp_path / "drifter.toml"
    path.write_text("\n".join('tank_pressure = "0 MPa"' if line.startswith("tank_pressure") else line
                              for line in text.splitlines()))
    assert main(["drifter", str(path)]) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert err == ["impactbar drifter: warning: supply.tank_pressure = '0 MPa' (0 MPa) is far outside its "
                   "typical range 0.2-1 MPa (beyond a factor 4)"]
