"""``impactbar.physical.load``: one reader for every configuration in SI units. Each example file gives
the machine its own constructor builds from the same TOML; a wrong key is named with the kind of
machine the file was read as; ``load_config`` (hammers only) says which kind a drifter's file is."""

import tomllib
from pathlib import Path

import pytest

from impactbar import physical
from impactbar.physical import CircuitDrifter, Drifter, Hammer

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: every SI configuration in examples/ and the machine it describes (written out here, not recomputed
#: by the loader's rule)
KINDS = {
    "circuit_drifter.toml": CircuitDrifter,
    "circuit_drill_parts.toml": CircuitDrifter,
    "circuit_drill_spool.toml": CircuitDrifter,
    "circuit_drifter_parts.toml": CircuitDrifter,
    "circuit_drifter_return_line.toml": CircuitDrifter,
    "circuit_drifter_rock.toml": CircuitDrifter,
    "circuit_drifter_rock_piston.toml": CircuitDrifter,
    "drifter_rock.toml": Drifter,
    "stepped_drifter.toml": Drifter,
    "stepped_drifter_rock.toml": Drifter,
    "hydraulic_drill.toml": Hammer,
    "measured_drill.toml": Hammer,
    "pneumatic_drill.toml": Hammer,
    "rock_drill.toml": Hammer,
}


def _toml(name):
    with (EXAMPLES / name).open("rb") as fh:
        return tomllib.load(fh)


def test_every_example_is_listed():
    """The SI configurations are the example TOML files that are neither sweep specs nor a
    measurement's spec (its ``[channels]``)."""
    assert set(KINDS) == {p.name for p in EXAMPLES.glob("*.toml")
                          if not p.name.startswith("sweep_") and "channels" not in _toml(p.name)}


@pytest.mark.parametrize("name", sorted(KINDS))
def test_load_gives_the_machine_of_each_example(name):
    machine = physical.load(EXAMPLES / name)
    kind = KINDS[name]
    assert type(machine) is kind
    if kind is Hammer:
        expected = Hammer.from_config(_toml(name), base_dir=EXAMPLES)
    else:
        expected = kind.from_config(_toml(name))
    if kind is Hammer:  # a measured force holds arrays: compared through the hammer's inputs
        assert machine.to_dict() == expected.to_dict() == physical.load_config(EXAMPLES / name).to_dict()
    else:
        assert machine == expected
        assert physical.load(str(EXAMPLES / name)) == expected  # a str path as well


@pytest.mark.parametrize("name", sorted(n for n, k in KINDS.items() if k is not Hammer))
def test_load_config_names_a_drifter_s_file_and_the_reader_that_takes_it(name):
    what = "oil circuit" if KINDS[name] is CircuitDrifter else "valve switches on the piston's position"
    with pytest.raises(ValueError, match=r"describes a drifter .*, not a hammer: read it with "
                                         r"impactbar\.physical\.load") as exc:
        physical.load_config(EXAMPLES / name)
    assert what in str(exc.value) and name in str(exc.value)


@pytest.mark.parametrize("name, section, key, kind", [
    ("circuit_drifter.toml", "accumulator", "pressure", "a drifter with its oil circuit"),
    ("circuit_drifter.toml", "valve", "delay", "a drifter with its oil circuit"),
    ("stepped_drifter.toml", "valve", "switching_time", "a drifter whose valve switches"),
    ("pneumatic_drill.toml", "force", "high", "a hammer under a periodic force"),
])
def test_a_wrong_key_is_named_with_the_kind_the_file_was_read_as(tmp_path, name, section, key, kind):
    """A key of the other kinds' (``valve.delay`` is the ideal valve's, ``valve.switching_time`` the
    circuit's) is refused, the message saying which kind of machine the file was taken for."""
    text = (EXAMPLES / name).read_text()
    assert text.count(f"\n[{section}]") == 1
    path = tmp_path / name
    path.write_text(text.replace(f"\n[{section}]", f"\n[{section}]\n{key} = 1"))
    readers = [physical.load] + ([physical.load_config] if kind.startswith("a hammer") else [])
    for read in readers:
        with pytest.raises(ValueError) as exc:
            read(path)
        msg = str(exc.value)
        assert msg.startswith(f"{path}: read as {kind}") and f"{section}.{key}" in msg, msg


def test_a_misspelt_section_changes_the_kind_and_the_message_says_so(tmp_path):
    """``[chamber]`` for ``[chambers]``: no longer a circuit; read as a drifter with a valve, the
    circuit's keys are refused under that kind's name."""
    path = tmp_path / "c.toml"
    path.write_text((EXAMPLES / "circuit_drifter.toml").read_text().replace("[chambers]", "[chamber]"))
    with pytest.raises(ValueError, match=r"read as a drifter whose valve switches on the piston's position "
                                         r".*: unknown section \[accumulator\]"):
        physical.load(path)


def test_a_sweep_spec_and_a_bad_file_are_refused(tmp_path):
    with pytest.raises(ValueError, match="sweep spec .* 'impactbar sweep'"):
        physical.load(EXAMPLES / "sweep_rock.toml")
    (tmp_path / "x.toml").write_text("[bar\n")
    with pytest.raises(ValueError, match="not valid TOML"):
        physical.load(tmp_path / "x.toml")
    with pytest.raises(ValueError, match="cannot read the configuration"):
        physical.load(tmp_path / "none.toml")
