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


@pytest.mark.parametrize("source, key, value, named", [
    ("examples/stepped_drifter_rock.toml", "rod.segments.1.diameter", "-32 mm",
     r"rod\.segments\[1\]\.diameter"),
    ("examples/circuit_drifter_rock.toml", "rod.segments.0.diameter", "-45 mm",
     r"rod\.segments\[0\]\.diameter"),
    ("examples/circuit_drifter_rock.toml", "rod.segments.1.length", "0 m", r"rod\.segments\[1\]\.length"),
    ("examples/circuit_drifter_rock.toml", "rod.segments.1.E", "-210 GPa", r"rod\.segments\[1\]\.E"),
    ("examples/circuit_drifter_rock.toml", "rod.segments.1.density", "0 kg/m^3",
     r"rod\.segments\[1\]\.density"),
    ("examples/circuit_drifter_rock_piston.toml", "piston.E", "-210 GPa", r"piston\.E"),
    ("examples/circuit_drifter_rock_piston.toml", "piston.density", "-7850 kg/m^3", r"piston\.density"),
    ("examples/circuit_drifter_rock.toml", "bar.diameter", "-45 mm", r"bar\.diameter"),
    ("examples/circuit_drifter_rock.toml", "chambers.rear_volume", "-0.15 L", r"chambers\.rear_volume"),
])
def test_a_non_positive_size_is_refused_naming_the_key_and_the_range(source, key, value, named):
    """A length, diameter, area, modulus or density at or below 0 is refused in one line naming the
    key, its range and the value as written (a rod's diameter of -32 mm was squared into +32 mm)."""
    config, folder = read_config(source)
    with pytest.raises(ValueError, match=named + r" must be (in \(0, inf\)|positive)") as err:
        build(with_values(config, {key: value}), folder)
    assert "\n" not in str(err.value)
    if key.startswith(("rod", "piston")):
        assert str(err.value).endswith(f"got {value!r}")
