"""The command line's conversation with a designer: every command that takes a machine's
configuration (a CONFIG.toml, a preset, a sweep's SPEC.toml) is run in-process with the bad inputs a
designer makes (a file and a preset together, a missing file, broken TOML, a bare number for a
quantity with a unit, a wrong unit) and answers each with exit status 2 and exactly one line on
stderr naming the real cause (the file, the key), before any solve.

The commands come from the parser; those that take a configuration must be the documented ones (the
row ``--preset``, ``CONFIG.toml`` of the CLI page's table "One meaning per option"), and the others
are listed in :data:`NO_CONFIG` with the reason."""

import argparse
import re
from pathlib import Path

import pytest

from impactbar.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "getting_started.md"
HAMMER = (ROOT / "examples" / "pneumatic_drill.toml").read_text()
CIRCUIT = (ROOT / "examples" / "circuit_drifter.toml").read_text()

#: the commands that take no machine's configuration, and why
NO_CONFIG = {
    "paper": "recomputes the paper's figures from its own dimensionless inputs",
    "experiment": "the paper's Section 5 experiments, dimensionless options only",
    "plot": "draws a sweep's finished zarr store, not a configuration",
    "warmup": "compiles the kernels on built-in inputs",
    "measure": "reads a recording and its measurement spec (bars, gauges, specimen), not a machine's",
}


def _subparsers():
    parser = build_parser()
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices


def _takes_config(sub) -> bool:
    """A positional ``config`` or ``spec``, or ``--preset``."""
    return any(a.dest in ("config", "spec", "preset") for a in sub._actions)


def _documented():
    """The commands of the CLI page's row for ``--preset``, ``CONFIG.toml`` and its configs."""
    text = DOCS.read_text(encoding="utf-8")
    table = text[text.index("### One meaning per option"):]
    row = next(r for r in table.splitlines() if r.startswith("| `--preset`, `CONFIG.toml`"))
    return set(re.findall(r"`([a-z]+)`", row.split("|")[4]))


def _sweep_spec(tmp_path, value='"3 MPa"'):
    (tmp_path / "circuit.toml").write_text(CIRCUIT)
    return (f'task = "operating_point"\nconfig = "circuit.toml"\n[axes]\n'
            f'"accumulator.precharge" = {{ start = {value}, stop = "12 MPa", num = 2 }}\n')


#: per command: its argv around the file, the configuration it reads, how to make that file carry a
#: bare number and a wrong unit (the key named), and a preset that goes with the file (None: the
#: command takes one source, a file or a preset's name, so the two cannot be given together)
COMMANDS = {
    "orbits": dict(argv=lambda p, tmp: ["orbits", p], text=HAMMER, key="bar.E",
                   bad=lambda v: HAMMER.replace('E = "210 GPa"', f"E = {v}"), preset="pneumatic-drill"),
    "simulate": dict(argv=lambda p, tmp: ["simulate", p, "--out", str(tmp / "s"), "--quiet"], text=HAMMER,
                     key="bar.E", bad=lambda v: HAMMER.replace('E = "210 GPa"', f"E = {v}"),
                     preset="hydraulic-drill"),
    "continue": dict(argv=lambda p, tmp: ["continue", p, "--parameter", "accumulator.precharge", "--to",
                                          "12 MPa", "--out", str(tmp / "c"), "--quiet"],
                     text=CIRCUIT, key="supply.relief_pressure",
                     bad=lambda v: CIRCUIT.replace('relief_pressure = "25 MPa"', f"relief_pressure = {v}"),
                     preset="circuit-drifter"),
    "drifter": dict(argv=lambda p, tmp: ["drifter", p], text=CIRCUIT, key="supply.relief_pressure",
                    bad=lambda v: CIRCUIT.replace('relief_pressure = "25 MPa"', f"relief_pressure = {v}"),
                    preset="circuit-drifter"),
    "optimize": dict(argv=lambda p, tmp: ["optimize", p, "--vary", "supply.pump_flow=60 L/min:90 L/min",
                                          "--objective", "impact_power", "--quiet"],
                     text=CIRCUIT, key="supply.relief_pressure",
                     bad=lambda v: CIRCUIT.replace('relief_pressure = "25 MPa"', f"relief_pressure = {v}"),
                     preset=None),
    "sweep": dict(argv=lambda p, tmp: ["sweep", p, "--out", str(tmp / "s.zarr"), "--quiet"], text=None,
                  key="accumulator.precharge", bad=None, preset=None),
}


def _never(*args, **kwargs):
    raise AssertionError("solved before the inputs were checked")


@pytest.fixture(autouse=True)
def no_solving(monkeypatch):
    """Any solve fails the test: every error here must come before one."""
    from impactbar import physical

    monkeypatch.setattr(physical.CircuitDrifter, "orbit", _never)
    monkeypatch.setattr(physical.Drifter, "orbit", _never)
    monkeypatch.setattr(physical, "orbits", _never)
    monkeypatch.setattr(physical, "simulate", _never)
    monkeypatch.setattr("impactbar.sweeps.run_sweep", _never)


def _one_line(capsys, command) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"impactbar {command}: error: "), err[0]
    return err[0]


def test_every_command_is_checked_or_listed_with_its_reason():
    subs = _subparsers()
    taking = {name for name, sub in subs.items() if _takes_config(sub)}
    assert taking == set(COMMANDS), taking ^ set(COMMANDS)
    assert set(subs) == set(COMMANDS) | set(NO_CONFIG)
    assert not taking & set(NO_CONFIG)
    assert _documented() == set(COMMANDS), _documented() ^ set(COMMANDS)
    # the preset option offers only what the command takes (presets with a preset given together)
    for name, case in COMMANDS.items():
        preset = next((a for a in subs[name]._actions if a.dest == "preset"), None)
        assert (preset is None) == (case["preset"] is None), name


def _write(tmp_path, command, text) -> str:
    path = tmp_path / "my.toml"
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize("command", [c for c, case in COMMANDS.items() if case["preset"]])
def test_a_file_and_a_preset_together(command, tmp_path, capsys):
    case = COMMANDS[command]
    path = _write(tmp_path, command, case["text"])
    assert main([*case["argv"](path, tmp_path), "--preset", case["preset"]]) == 2
    line = _one_line(capsys, command)
    assert "CONFIG.toml and --preset cannot be used together" in line


@pytest.mark.parametrize("command", COMMANDS)
def test_a_missing_file(command, tmp_path, capsys):
    path = str(tmp_path / "nonexistent.toml")
    assert main(COMMANDS[command]["argv"](path, tmp_path)) == 2
    line = _one_line(capsys, command)
    assert "nonexistent.toml" in line and "No such file" in line


@pytest.mark.parametrize("command", COMMANDS)
def test_broken_toml(command, tmp_path, capsys):
    path = _write(tmp_path, command, '[bar\nE = "210 GPa"\n')
    assert main(COMMANDS[command]["argv"](path, tmp_path)) == 2
    line = _one_line(capsys, command)
    assert "my.toml" in line and "not valid TOML" in line and "line 1" in line


@pytest.mark.parametrize("value, says", [("210", "needs a unit"), ('"12 kg"', "of dimension [mass]")],
                         ids=["bare-number", "wrong-unit"])
@pytest.mark.parametrize("command", COMMANDS)
def test_a_value_without_its_unit_or_in_the_wrong_one(command, value, says, tmp_path, capsys):
    case = COMMANDS[command]
    if command == "sweep":  # the spec's axis, and the file is the spec
        text = _sweep_spec(tmp_path, value)
    else:
        text = case["bad"](value)
    path = _write(tmp_path, command, text)
    assert main(case["argv"](path, tmp_path)) == 2
    line = _one_line(capsys, command)
    assert case["key"] in line and says in line
    if command != "sweep":
        assert "my.toml" in line


@pytest.mark.parametrize("command", [c for c, case in COMMANDS.items() if case["text"] is CIRCUIT])
def test_a_switch_point_in_metres_meant_as_millimetres_names_the_cause(command, tmp_path, capsys):
    """``switch_out = "24 m"`` (meant mm): the run from rest solved, then failed with the rear chamber
    emptying "near t = 1.64831" with "rear_volume (now 0.398115)", in the model's units."""
    path = _write(tmp_path, command, CIRCUIT.replace('switch_out = "21.5 mm"', 'switch_out = "24 m"'))
    assert main(COMMANDS[command]["argv"](path, tmp_path)) == 2
    line = _one_line(capsys, command)
    assert "my.toml" in line and "valve.switch_out must be in (0, 178.571 mm): below the rear chamber's " \
        "length, chambers.rear_volume / chambers.rear_area (0.1 L / 5.6 cm^2)" in line
    assert line.endswith("got 24000 mm")


# --------------------------------------------------------------------------------------------
# the optimiser's variables and limits, read as every other quantity is
# --------------------------------------------------------------------------------------------
def _optimize(tmp_path, *extra):
    path = _write(tmp_path, "optimize", CIRCUIT)
    return ["optimize", path, "--objective", "impact_power", "--quiet", *extra]


def test_a_bare_number_limit_is_refused_naming_the_constraint(tmp_path, capsys):
    """``mean_supply_pressure=18`` was read as 18 Pa; a bare number for a quantity with a unit is
    refused, as in a config; a dimensionless limit takes one."""
    vary = ["--vary", "supply.pump_flow=60 L/min:90 L/min"]
    assert main(_optimize(tmp_path, *vary, "--constraint", "mean_supply_pressure=18")) == 2
    line = _one_line(capsys, "optimize")
    assert "mean_supply_pressure" in line and "needs a unit" in line and "'18'" in line
    assert main(_optimize(tmp_path, *vary, "--constraint", "min_chamber_volume=0")) == 2
    line = _one_line(capsys, "optimize")
    assert "min_chamber_volume" in line and "needs a unit" in line and "e.g. '0.01 L'" in line
    from impactbar.cli.optimize import parse_constraint

    assert parse_constraint(["max_multiplier=0.9"]) == {"max_multiplier": "0.9"}


@pytest.mark.parametrize("limit", ["max_multiplier=inf", "max_multiplier=nan", "max_multiplier=-Infinity",
                                   "peak_supply_pressure=inf MPa", "max_multiplier=1e400"])
def test_a_limit_that_is_not_finite_is_refused_as_the_command_line_is_read(limit, tmp_path, capsys,
                                                                           monkeypatch):
    import sys

    import impactbar.physical.optimize_drifter  # noqa: F401 (the module, which the package's name hides)

    # refused before the optimiser is reached
    monkeypatch.setattr(sys.modules["impactbar.physical.optimize_drifter"], "optimize_drifter", _never)
    vary = ["--vary", "supply.pump_flow=60 L/min:90 L/min"]
    assert main(_optimize(tmp_path, *vary, "--constraint", limit)) == 2
    line = _one_line(capsys, "optimize")
    assert f"--constraint {limit}: the limit must be finite" in line


@pytest.mark.parametrize("bounds, example", [("supply.pump_flow=70:100", "'80 L/min'"),
                                             ("accumulator.precharge=8 MPa:14", "'12 MPa'"),
                                             ("piston.collar_diameter=47:52mm", "'50 mm'")])
def test_a_bare_number_bound_is_refused_with_a_whole_example(bounds, example, tmp_path, capsys):
    assert main(_optimize(tmp_path, "--vary", bounds)) == 2
    line = _one_line(capsys, "optimize")
    assert f"--vary {bounds}: " in line and "needs a unit" in line and f"e.g. {example};" in line
    assert "..." not in line


@pytest.mark.parametrize("path", [3, None, ["a"], 2.5])
def test_load_refuses_what_is_no_path_in_one_line(path):
    from impactbar.physical import load

    with pytest.raises(ValueError, match="path must be a TOML file's path") as exc:
        load(path)
    assert "\n" not in str(exc.value)


def test_a_key_the_config_leaves_out_is_named_once(tmp_path, capsys):
    """A design map over a key the drifter's config does not give: the key once, then why."""
    (tmp_path / "circuit.toml").write_text(CIRCUIT)
    path = _write(tmp_path, "sweep", 'task = "operating_point"\nconfig = "circuit.toml"\n[axes]\n'
                  '"damping.coefficient" = { start = "1 N*s/m", stop = "2 N*s/m", num = 2 }\n')
    assert main(COMMANDS["sweep"]["argv"](path, tmp_path)) == 2
    line = _one_line(capsys, "sweep")
    assert line.count("damping.coefficient") == 1 and "the config has no [damping] section" in line


def test_a_parameter_of_a_part_the_drifter_lacks_is_refused_for_that(tmp_path, capsys):
    """``continue --parameter accumulator.precharge`` on a drifter without an accumulator says so
    before any solve (it solved the orbit, then named a valve's parameters of another drive)."""
    text = re.sub(r"\[accumulator\].*?\n\n", "", CIRCUIT, flags=re.S)
    assert "[accumulator]" not in text
    path = _write(tmp_path, "continue", text)
    assert main(COMMANDS["continue"]["argv"](path, tmp_path)) == 2
    line = _one_line(capsys, "continue")
    assert "accumulator.precharge is the accumulator's: the drifter has none" in line


@pytest.mark.parametrize("argv, says", [
    (["drifter", "--preset", "hydraulic-drill"], "argument --preset: invalid choice: 'hydraulic-drill'"),
    (["sweep", "spec.toml", "--out", "s.zarr", "--workers", "2", "--scheduler", "tcp://host:8786"],
     "argument --scheduler: not allowed with argument --workers"),
    (["optimize", "circuit-drifter"], "the following arguments are required: --vary"),
])
def test_what_the_parser_refuses_is_one_line_too(argv, says, capsys):
    """Options that conflict in the parser itself (a mutually exclusive group), an invalid choice, a
    required option left out: one line and exit status 2, as every other bad input (argparse's
    usage above it made several)."""
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    line = _one_line(capsys, argv[0])
    assert says in line and line.endswith(f"see 'impactbar {argv[0]} --help'")
