"""One tree of parameters: each field of a drifter with its oil circuit is declared once
(:mod:`impactbar.physical.tree`), and every table that joins its dotted SI name to another name (a
unit, a dimensionless parameter, a typical range, the sections' keys) is a view of the declaration."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import pytest

from impactbar.physical import tree

SRC = Path(__file__).resolve().parents[2] / "src" / "impactbar"
DOCS = Path(__file__).resolve().parents[2] / "docs"
ROOT = Path(__file__).resolve().parents[2]


def _written(node) -> str | None:
    """The name an entry of a literal table gives: a string, or a row's first (a tuple or list of
    literals: one key per row); ``None`` for anything else (a row computed in code)."""
    if isinstance(node, ast.Tuple | ast.List) and node.elts \
            and all(isinstance(e, ast.Constant) for e in node.elts):
        node = node.elts[0]
    return node.value if isinstance(node, ast.Constant) and isinstance(node.value, str) else None


#: Tables that name two of the declared dimensionless names and are no table of parameters: the
#: schematic draws and labels the valve's switch points by the parameters' names (its module, the
#: names).
DRAWN = {("plotting/circuit.py", frozenset({"switch_out", "switch_in"}))}


def hand_tables(source: str, fields, module: str = "") -> list[int]:
    """The lines of the literal tables (dict, set, tuple, list) in ``source`` that name two or more
    of the declared dotted keys, or two or more of the declared dimensionless parameter names (the
    ones a field sets), as plain strings: a dict's keys, a sequence's elements, or the first element
    of each of its rows (one key per row): a table written by hand beside the declaration.

    A key that is also its own dimensionless name (the rod-rock law's ``rock.k``) is the law's to
    list among its parameters, and a blow's to require; a name that is also a drifter's SI record's
    (``valve_coefficient``) counts as none; a config's section (a dict under a section's name, as a
    preset writes it) is no table; a declaration written as calls (``Field("supply.pump_flow", ...)``)
    is none either.
    """
    keys = {k for k, f in fields.items() if f.parameter != k}
    records = {f.si for f in fields.values() if f.si}
    names = {f.parameter for f in fields.values() if f.parameter} - records - set(fields)
    sections = {f.section for f in fields.values()}
    tree_ = ast.parse(source)
    configs = {id(v) for node in ast.walk(tree_) if isinstance(node, ast.Dict)
               for k, v in zip(node.keys, node.values, strict=True)
               if isinstance(k, ast.Constant) and k.value in sections and isinstance(v, ast.Dict)}
    found = []
    for node in ast.walk(tree_):
        if id(node) in configs:
            continue
        elts = node.keys if isinstance(node, ast.Dict) else \
            node.elts if isinstance(node, ast.Tuple | ast.Set | ast.List) else ()
        written = [_written(e) for e in elts if e is not None]
        dotted = [w for w in written if w in keys]
        named = frozenset(w for w in written if w in names)
        if len(dotted) >= 2 or (len(named) >= 2 and (module, named) not in DRAWN):
            found.append(node.lineno)
    return found


def test_the_scan_finds_a_planted_hand_table():
    """The scan can fail: the old hand table of SI names and planted ones are found (one key per
    row, keyed by the dimensionless names, a tuple of them), a view, a declaration by calls, a
    config's sections and rows computed in code are not."""
    planted = ('SI = {"supply.pump_flow": ("pump_flow", "m**3/s"), "valve.switch_out": ("switch_out", "m")}\n'
               'INTEGER_KEYS = ("model.n_modes", "rock.cells_per_piston")\n'
               'VIEW = {k: f.unit for k, f in FIELDS.items()}\n'
               'ROWS = (("supply.pump_flow", "pump_flow_m3_s", "positive"), ("oil.bulk_modulus", "Pa"))\n'
               'PARTS = {"pump_flow": ("supply", "pump_flow"), "precharge": ("accumulator", "precharge")}\n'
               'RANGES = {"hose_volume": {"low": 0.0}, "bulk_modulus": {"low": 0.0, "low_open": True}}\n'
               'NAMES = ("rock.k", "rock.k_u", "bit_mass", "feed", "segment<i>.length")\n'
               'KEYS = ("k", "bit_mass", "feed")\n'
               'DECLARED = (P("pump_flow", "supply"), P("precharge", "accumulator"))\n'
               'PRESET = {"supply": {"pump_flow": "70 L/min", "hose_volume": "0.25 L"}}\n'
               'MARKS = (("switch_out", x_out, "C3"), ("switch_in", x_in, "C0"))\n'
               'RECORD = ("valve_coefficient", "front_coefficient")\n')
    assert hand_tables(planted, tree.FIELDS) == [1, 2, 4, 5, 6, 7, 8]


def test_no_module_writes_a_table_of_the_declared_names():
    """Hand tables joining parameter names: 0 (every module of the package but the tree itself)."""
    every = {k: f for fields in tree.MACHINES.values() for k, f in fields.items()}
    tables = {str(p.relative_to(SRC)): lines for p in sorted(SRC.rglob("*.py"))
              if p.name != "tree.py"
              and (lines := hand_tables(p.read_text(), every, p.relative_to(SRC).as_posix()))}
    assert tables == {}


def test_the_old_tables_are_views_of_the_tree():
    """Each public table the tools read is what the declarations give."""
    from impactbar.continuation.parameters import MODEL_PARAMETERS
    from impactbar.physical import circuit, design_keys, geometry, plausibility

    declared = tree.FIELDS
    assert circuit.SI_PARAMETERS == {k: (f.parameter, f.unit, f.example) for k, f in declared.items()
                                     if f.holder in ("drive", "law")}
    rock = {k for k in circuit.SI_PARAMETERS if declared[k].needs == "rock"}
    assert set(circuit.ROCK_SI_PARAMETERS) == rock
    assert set(design_keys.INTEGER_KEYS) == {k for k, f in declared.items() if f.integer}
    assert plausibility.TYPICAL == tree.typical_ranges()
    for section, keys in circuit._KEYS.items():
        assert keys == {f.name for f in declared.values() if f.section == section}, section
    assert geometry.PISTON_KEYS == {k.split(".")[1] for k in declared if k.startswith("piston.")}
    assert MODEL_PARAMETERS == ("s", "d", "R")
    from impactbar.physical._circuit_checks import _RANGES

    assert [row[:2] for row in _RANGES] == [(f.key, f.si) for f in tree.in_sections() if f.bound]


def test_the_tree_names_the_parameters_the_parts_declare():
    """Each field's dimensionless parameter is one its holder declares (the drive's, the rod-rock
    law's, the bar model's own declarations: the tree reads them, none reads the tree), and the
    tables of the circuit drive, the law and a sweep's ``[rock]`` and ``[model]`` keys are views of
    those declarations."""
    from impactbar import BarModel, BilinearRock, RodRock, RodSegment
    from impactbar.drives.circuit.drive import _RANGES, PARAMETERS, HydraulicCircuitDrive
    from impactbar.drives.circuit.parameters import DECLARED
    from impactbar.sweeps.bar_spec import MODEL_FIELDS, ROCK_KEYS

    held = {"drive": {p.name for p in DECLARED}, "law": set(RodRock.parameters),
            "model": set(BarModel.parameters.names)}
    for key, f in ((k, f) for fields in tree.MACHINES.values() for k, f in fields.items() if f.parameter):
        assert f.parameter in held[f.holder], key
    names = tuple(p.name for p in DECLARED)
    assert HydraulicCircuitDrive.parameters == tuple(PARAMETERS) == tuple(_RANGES) == names
    assert all(_RANGES[p.name]["description"] == p.description for p in DECLARED)
    assert {p.name for p in RodRock(segments=[RodSegment(length=1.0, impedance=1.0)],
                                    rock=BilinearRock(k=1.0, k_u=2.0)).parameter_table()} \
        == {*RodRock.parameters[:-1], "segment0.length"}
    assert MODEL_FIELDS == ("s", "d", "R", "n_modes")
    assert ROCK_KEYS[:4] == ("k", "k_u", "bit_mass", "feed")


def test_a_fields_own_bound_is_its_parameters_range():
    """A field's bound in SI (checked before the conversion) is its dimensionless parameter's lower
    bound in the drive's declaration (the scales are positive, so 0 stays 0): above 0 for a range
    open at 0, 0 or above, with what 0 means, for one closed there."""
    from impactbar.drives.circuit.parameters import DECLARED

    ranges = {p.name: p for p in DECLARED}
    bounded = [f for f in tree.FIELDS.values() if f.bound]
    assert len(bounded) == 16
    for f in bounded:
        assert f.bound in ("positive", "non_negative"), f.key
        assert bool(f.zero) == (f.bound == "non_negative"), f.key
        if f.holder == "drive":
            p = ranges[f.parameter]
            assert (p.low, p.low_open) == (0.0, f.bound == "positive"), f.key


def test_every_declared_field_is_complete():
    """Of every kind of machine: a unit pint reads, an example in that unit, a scale known for every
    parameter set, and for a field that cannot be continued a reason the tools show."""
    from impactbar.physical.units import to_si

    for key, f in ((k, f) for fields in tree.MACHINES.values() for k, f in fields.items()):
        if f.text:
            assert not f.parameter and not f.unit, key
            continue
        if f.parameter:
            assert isinstance(f.scale, str) and f.scale in tree.SCALES, key
            assert f.holder in ("drive", "law", "model"), key
        if not f.many:
            assert math.isfinite(to_si(key, f.example.strip("'") if f.unit else float(f.example), f.unit,
                                       f.example)), key
        assert f.continuable or f.why_not, key
        if f.typical:
            assert f.typical[0] <= f.typical[1], key


@pytest.mark.parametrize("key", ["bar.diameter", "chambers.rear_area", "model.n_modes", "piston.end_lengths"])
def test_continuation_refuses_a_key_with_its_declared_reason(key):
    """A key a design map varies but that continuation cannot follow is refused with the reason its
    declaration gives, by every tool that continues."""
    from impactbar.physical import circuit_preset

    with pytest.raises(ValueError, match=f"parameter {key} cannot be continued: it "):
        circuit_preset("circuit-drifter").to_dimensionless(key, "1 m")


def test_the_docs_list_every_key_of_the_circuit():
    """docs/physical.md names every declared key of the circuit's sections and the piston's shape."""
    text = (DOCS / "physical.md").read_text()
    missing = [k for k, f in tree.FIELDS.items()
               if f.section in (*tree.CIRCUIT_SECTIONS, "piston") and f"`{k}`" not in text]
    assert missing == []


def test_the_docs_table_of_keys_is_the_trees():
    """docs/physical.md holds the table generated from the declarations, as it is now."""
    assert tree.markdown_table() in (DOCS / "physical.md").read_text()


def test_a_key_the_maps_vary_is_continued_where_it_sets_one_parameter():
    """``stop.restitution``, swept by the design maps and varied by the optimiser, is continued too:
    its declaration sets the bar model's ``R``."""
    from impactbar.physical import circuit_preset, continue_circuit

    b = continue_circuit(circuit_preset("circuit-drifter"), "stop.restitution", 0.25, max_points=3)
    assert b.unit == "" and b.values[0] == 0.215 and len(b) == 3
    assert b.branch.values[0] == 0.215 and b.values[-1] > 0.215


@pytest.mark.parametrize("kind", ["hammer", "drifter", "circuit"])
def test_each_kind_of_config_takes_the_keys_the_tree_declares(kind):
    """The keys each reader takes (a hammer's, a valve drifter's, a drifter with its oil circuit's,
    the drill string's and its segments') are the tree's declarations of that kind, each with its
    unit: no reader keeps a table of its own."""
    from impactbar.physical import config_keys

    keys = config_keys(kind)
    listed = {f"{section}.{name}" for section, names in keys.items() for name in names
              if (section, name) != ("rod", "segments")}
    hammers = {"force.k", "force.max_harmonics"} if kind == "circuit" else set()  # (its integer keys)
    assert listed == set(tree.MACHINES[kind]) - hammers
    assert tree.declared("rod.segments.2.diameter", kind).unit == "m"
    assert tree.declared("rod.segments.x.diameter", kind) is None


def test_a_key_of_a_hammer_or_a_rod_segment_has_its_declared_unit():
    """A design map's unit of a key is the tree's, not the base units of the config's value: a
    hammer's frequency in Hz (given in bpm), a rod segment's modulus in Pa (given in GPa), a valve
    drifter's delay in s."""
    from impactbar.physical.design_keys import design_key
    from impactbar.physical.loader import read_config

    hammer = read_config("pneumatic-drill")[0]
    hammer["drive"]["frequency"] = "2400 bpm"
    assert design_key(hammer, "drive.frequency") == ("Hz", "2400 bpm")
    rock = read_config(Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter_rock.toml")[0]
    rock["rod"]["segments"][0]["E"] = "210 GPa"
    assert design_key(rock, "rod.segments.0.E") == ("Pa", "210 GPa")
    drifter = read_config(Path(__file__).resolve().parents[2] / "examples" / "drifter_rock.toml")[0]
    drifter["valve"]["delay"] = "1 ms"
    assert design_key(drifter, "valve.delay")[0] == "s"


def test_a_rod_segment_and_a_valve_drifter_read_their_units_from_the_tree():
    """A bare number or another dimension is refused naming the key as the config writes it, in
    the words the tree gives its unit."""
    from impactbar.physical import build
    from impactbar.physical.loader import read_config, with_values

    rock = read_config(Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter_rock.toml")[0]
    with pytest.raises(ValueError, match=r"rod.segments\[0\].E.*a pressure"):
        build(with_values(rock, {"rod.segments.0.E": "210 kg"}))
    with pytest.raises(ValueError, match="rod.segments\\[1\\].diameter must be in \\(0, inf\\)"):
        build(with_values(rock, {"rod.segments.1.diameter": "-32 mm"}))
    drifter = read_config(Path(__file__).resolve().parents[2] / "examples" / "drifter_rock.toml")[0]
    with pytest.raises(ValueError, match="valve.delay.*a time"):
        build(with_values(drifter, {"valve.delay": "3 kg"}))


def _drive_names() -> set:
    """The drive's dimensionless names: its parameters, its parts' fields and the drifter's SI records
    of them (``precharge``, ``volume``, ``precharge_Pa``)."""
    from impactbar.drives.circuit.parameters import DECLARED

    return {n for p in DECLARED for n in (p.name, p.field)} | {f.si for f in tree.FIELDS.values() if f.si}


def named_by_hand(source: str, names) -> list[str]:
    """The names of ``names`` that ``source`` writes: a call's keyword (``precharge=``) or a string
    (``si["precharge_Pa"]``)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.keyword) and node.arg in names:
            found.append(node.arg)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
            found.append(node.value)
    return found


def test_the_drive_builder_names_no_dimensionless_field():
    """``CircuitDrifter.drive`` builds the parts from the tree's declarations: 0 of the drive's
    parameters, its parts' fields or their SI records written in it (the scan finds the old hand
    join's)."""
    import inspect
    import textwrap

    from impactbar.physical.circuit import CircuitDrifter

    old = ('Accumulator(precharge=si["precharge_Pa"] / P, volume=si["accumulator_volume_m3"] / V)\n'
           'Valve(switch_out=si["switch_out_m"] / L, coefficient=si["valve_coefficient"] * k)\n')
    assert len(named_by_hand(old, _drive_names())) == 8
    assert named_by_hand(textwrap.dedent(inspect.getsource(CircuitDrifter.drive)), _drive_names()) == []


def test_a_field_declared_with_another_scale_reaches_the_drive(monkeypatch):
    """A field's scale changed in its declaration alone (a function, or a new named scale of steps)
    changes the drive's value of its parameter, and nothing else of the drive."""
    import dataclasses

    from impactbar.physical import circuit_preset

    before = circuit_preset("circuit-drifter")
    was = before.drive()
    P = tree.PRESSURE_SCALE
    f = tree.FIELDS["oil.transition_pressure"]
    monkeypatch.setitem(tree.FIELDS, f.key, dataclasses.replace(f, scale=lambda d: 0.5 / P))
    after = circuit_preset("circuit-drifter")
    assert after.drive().oil.transition_pressure == before.si["transition_pressure_Pa"] * (0.5 / P)
    assert after.drive().oil.transition_pressure == 0.5 * was.oil.transition_pressure
    monkeypatch.setitem(tree.SCALE_STEPS, "bar_pressure", (("/", lambda d: 1e5),))
    monkeypatch.setitem(tree.FIELDS, f.key, dataclasses.replace(f, scale="bar_pressure"))
    drive = circuit_preset("circuit-drifter").drive()
    assert drive.oil.transition_pressure == 2.0  # 0.2 MPa in bar
    assert dataclasses.replace(drive, oil=was.oil) == was


def test_every_field_the_drive_holds_reaches_it():
    """Each of the drive's declared parameters that a tree field sets is set by :func:`drive_values`
    in its declared part and field (the accumulator's only with a volume above 0); the one no field
    sets (a held supply's pressure) is not."""
    from impactbar.drives.circuit.parameters import DECLARED
    from impactbar.physical import circuit_preset

    set_ = {f.parameter for f in tree.FIELDS.values() if f.holder == "drive"}
    assert {p.name for p in DECLARED} - set_ == {"supply_pressure"}
    assert all(f.si for f in tree.FIELDS.values() if f.holder == "drive")
    reached = {(part, name) for part, values in tree.drive_values(circuit_preset("circuit-drifter")).items()
               for name in values}
    assert reached == {(p.part, p.field) for p in DECLARED if p.name in set_}
    bare = circuit_preset("circuit-drifter", accumulator={"volume": "0 L"})
    assert "accumulator" not in tree.drive_values(bare) and bare.drive().accumulator is None


def test_the_drive_rounds_each_field_as_its_scale_declares():
    """Each dimensionless value of the drive is its SI value divided or multiplied by its scale as
    the theory writes it (§11, eq. 2), to the bit: ``x / P``, ``x / (A_r L)``, ``K sqrt(P) / Q``
    as ``K * (sqrt(P) / Q)``, the relief's ``K P / Q`` as ``(K P) / Q``, ``tau * Omega``; a value
    at odd SI values, where ``x * (1 / P)`` and ``x / P`` differ in the last bit."""
    from impactbar.physical import circuit_preset

    d = circuit_preset("circuit-drifter", valve={"switch_in": "7.3 mm", "switching_time": "1.37 ms"},
                       supply={"tank_pressure": "0.29 MPa", "relief_coefficient": "3.3e-10 m^3/s/Pa",
                               "pump_flow": "73.3 L/min"},
                       oil={"bulk_modulus": "1.37 GPa", "transition_pressure": "0.17 MPa"})
    si, dr, P, L = d.si, d.drive(), tree.PRESSURE_SCALE, d.bar.length_m
    V, Q, om = si["rear_area_m2"] * L, si["rear_area_m2"] * L * d.omega_rad_s, d.omega_rad_s
    by_hand = {"chambers.area_ratio": si["front_area_m2"] / si["rear_area_m2"],
               "chambers.rear_volume": si["rear_volume_m3"] / V, "valve.switch_out": si["switch_out_m"] / L,
               "valve.switch_in": si["switch_in_m"] / L, "valve.switching_time": si["switching_time_s"] * om,
               "valve.coefficient": si["valve_coefficient"] * (math.sqrt(P) / Q),
               "supply.pump_flow": si["pump_flow_m3_s"] / Q,
               "supply.tank_pressure": si["tank_pressure_Pa"] / P,
               "supply.relief_coefficient": si["relief_coefficient"] * P / Q,
               "accumulator.polytropic_exponent": si["polytropic_exponent"],
               "oil.bulk_modulus": si["bulk_modulus_Pa"] / P,
               "oil.transition_pressure": si["transition_pressure_Pa"] / P}
    got = {k: getattr(getattr(dr, k.split(".")[0]), k.split(".")[1]) for k in by_hand}
    assert got == by_hand
    # (the odd values are odd: a factor would round some of them otherwise)
    assert si["tank_pressure_Pa"] * (1.0 / P) != by_hand["supply.tank_pressure"]
    assert si["transition_pressure_Pa"] * (1.0 / P) != by_hand["oil.transition_pressure"]


@pytest.mark.parametrize("key", ["supply.tank_pressure", "supply.pump_flow", "chambers.rear_volume",
                                 "valve.switch_in", "supply.relief_coefficient", "rock.k"])
def test_a_continued_value_is_the_configs_to_the_bit(key):
    """A value a continuation is asked to reach (``to_dimensionless``, as ``continue_circuit`` and the
    CLI convert it) is the parameter of the drifter whose config sets that value, to the bit: one
    conversion, the scale's declared steps (:func:`tree.convert`), for a scale of one step and for a
    product of scales (the relief's ``K P / Q``, the rock's ``K / (m Omega^2)``); and converted back
    (``from_dimensionless``, a branch's points in SI), the SI value within an ulp of rounding."""
    from impactbar.continuation.parameters import parameter_value
    from impactbar.physical.loader import build, read_config, with_values

    source = ROOT / "examples" / "circuit_drifter_rock.toml" if key.startswith("rock.") else "circuit-drifter"
    config, f = read_config(source)[0], tree.FIELDS[key]
    example = tree.read_si(key, f.example.strip("'"))
    for factor in (0.731, 1.137, 0.917, 1.291, 0.613):  # (odd values: a factor 1 / P rounds some apart)
        value = f"{example * factor!r} {f.unit}"
        drifter = build(with_values(config, {key: value}))
        name, x = drifter.to_dimensionless(key, value)
        assert x.hex() == parameter_value(drifter.model(), drifter.drive(), name).hex(), (key, value)
        assert abs(drifter.from_dimensionless(key, x) - example * factor) <= math.ulp(example * factor)
