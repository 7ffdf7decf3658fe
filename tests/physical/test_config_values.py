"""A configuration as a parameter space: values changed by dotted key, the machine rebuilt."""

import pytest

from impactbar.physical import build, config_value, load, read_config, with_values


def test_changed_value_reaches_the_machine_and_the_original_is_untouched():
    config, _ = read_config("circuit-drifter")
    changed = with_values(config, {"supply.pump_flow": "90 L/min", "accumulator.precharge": "12 MPa"})
    assert config_value(config, "supply.pump_flow") == "70 L/min"
    drifter = build(changed)
    assert drifter.si["pump_flow_m3_s"] == pytest.approx(90e-3 / 60, rel=1e-15)
    assert drifter.si["precharge_Pa"] == pytest.approx(12e6, rel=1e-15)


def test_a_file_reads_as_load_does():
    config, folder = read_config("examples/circuit_drifter_rock.toml")
    a, b = build(config, folder), load("examples/circuit_drifter_rock.toml")
    assert a.si == b.si and a.drill == b.drill


def test_rod_segment_key():
    config, _ = read_config("examples/circuit_drifter_rock.toml")
    changed = with_values(config, {"rod.segments.0.length": "3 m"})
    assert build(changed).drill != build(config).drill
    with pytest.raises(ValueError, match="segment"):
        with_values(config, {"rod.segments.7.length": "3 m"})


@pytest.mark.parametrize("key, match", [("supply.pump_flo", "unknown key supply.pump_flo"),
                                        ("nosection.x", "unknown key"), ("pump_flow", "section.key")])
def test_unknown_keys_refused(key, match):
    with pytest.raises(ValueError, match=match):
        with_values(read_config("circuit-drifter")[0], {key: "1"})


def test_a_wrong_value_is_named_when_built():
    changed = with_values(read_config("circuit-drifter")[0], {"supply.pump_flow": "90 MPa"})
    with pytest.raises(ValueError, match="supply.pump_flow"):
        build(changed)


def test_unknown_source():
    with pytest.raises(ValueError, match="neither a file nor a preset"):
        read_config("no-such-preset")
