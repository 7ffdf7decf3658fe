"""Each output of a drifter is declared once, in :mod:`impactbar.physical.outputs`: the names the map
stores, the optimiser, the sensitivities and the CLI use are the registry's, and no module of the SI
layers (physical, sweeps, cli) lists output names by hand (a scan of their literals, as
``tests/test_record_slots.py`` scans the kernels). Nor does a result type's schema declare an output's
name and unit again (a ``Field``, an ``SI`` column): the two registries share each quantity, one
declaring it and the other reading it (``Output.from_field``, ``Output.column``)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from impactbar.physical.optimize_drifter import DEFAULT_CONSTRAINTS, IDEAL_CONSTRAINTS, OBJECTIVES
from impactbar.physical.optimize_outputs import constraint_output
from impactbar.physical.outputs import OUTPUTS, _named, _suffix, outputs
from impactbar.physical.sensitivity import FIGURE_UNITS
from impactbar.sweeps.map_spec import map_variables
from impactbar.sweeps.map_task import EDGE_FLAGS

SRC = Path(__file__).resolve().parents[2] / "src" / "impactbar"
#: the SI layers, whose tools read the registry
LAYERS = ("physical", "sweeps", "cli", "continuation")
#: the modules that compute the figures the registry reads (a blow's, the rock's, a run's records),
#: and the registry itself
PRODUCERS = {"physical/outputs.py", "physical/rock.py", "physical/piston.py", "physical/results.py"}
#: literals that name outputs for another reason: the constraints' names (a constraint may share its
#: output's name), a run's per-impact columns and summary (not an operating point's outputs)
ALLOWED = {("physical/optimize_problem.py", "DEFAULT_CONSTRAINTS"),
           ("physical/optimize_problem.py", "IDEAL_CONSTRAINTS"),
           ("physical/optimize_outputs.py", "_CONSTRAINTS"),
           ("cli/drifter.py", "run_circuit_simulate")}


def _names() -> set:
    return {n for o in OUTPUTS.values() for n in (o.name, o.key, o.shown_key)}


def hand_lists(source: str, names: set) -> list:
    """The literals (tuple, list, set, dict keys) of ``source`` that hold two output names or more:
    ``(line, where, names)``, ``where`` the enclosing top-level assignment's target or function."""
    tree = ast.parse(source)
    found = []
    for top in tree.body:
        if isinstance(top, ast.ClassDef):
            tops = [(f, getattr(f, "name", top.name)) for f in top.body]
        else:
            tops = [(top, None)]
        for node, name in tops:
            where = name or getattr(node, "name", None) or next(
                (t.id for t in getattr(node, "targets", [getattr(node, "target", None)])
                 if isinstance(t, ast.Name)), None)
            for sub in ast.walk(node):
                items = sub.keys if isinstance(sub, ast.Dict) else \
                    sub.elts if isinstance(sub, ast.Tuple | ast.List | ast.Set) else []
                hits = [k.value for k in items if isinstance(k, ast.Constant) and k.value in names]
                if len(hits) >= 2:
                    found.append((sub.lineno, where, hits))
    return found


def test_the_tools_name_only_registered_outputs():
    keys = {o.key for o in OUTPUTS.values()}
    stored = set(map_variables("circuit", True).names) - {"origin", "status", "failure"}
    assert stored <= set(OUTPUTS) and set(map_variables("drifter", True).names) - stored <= {
        "origin", "status", "failure"}
    assert set(FIGURE_UNITS) <= keys and set(EDGE_FLAGS) <= set(OUTPUTS)
    assert {key for key, _, _ in OBJECTIVES.values()} <= keys
    assert all(constraint_output(c) is not None for c in (*DEFAULT_CONSTRAINTS, *IDEAL_CONSTRAINTS))
    for o in outputs("summary"):  # the summaries' keys are the outputs' display keys
        assert o.shown_key.startswith(o.name)


@pytest.mark.parametrize("layer", LAYERS)
def test_no_hand_list_of_output_names(layer):
    names = _names()
    bad = []
    for path in sorted((SRC / layer).rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        if rel in PRODUCERS:
            continue
        bad += [f"{rel}:{line} ({where}): {hits}" for line, where, hits in hand_lists(path.read_text(), names)
                if (rel, where) not in ALLOWED]
    assert not bad, "outputs listed by hand (declare them in impactbar.physical.outputs):\n" + "\n".join(bad)


def test_a_planted_hand_list_is_found():
    planted = ('COLUMNS = ("blow_frequency_Hz", "mean_supply_pressure_MPa")\n'
               "def f(p):\n    return {'pump_power_kW': p.a, 'hydraulic_efficiency': p.b}\n"
               "class C:\n    def g(self):\n        return ['relief_margin', 'peak_rod_stress']\n")
    found = hand_lists(planted, _names())
    assert [(line, where) for line, where, _ in found] == [(1, "COLUMNS"), (3, "f"), (6, "g")]
    assert not hand_lists('ONE = ("blow_frequency_Hz", "speed")\n', _names())


def test_a_second_declaration_is_refused():
    from impactbar.physical.outputs import Output, register_output, unregister_output

    with pytest.raises(ValueError, match="'pump_power' .* registered already"):
        register_output(Output("pump_power", "kW", "again", lambda r: 0.0))
    # another name, the same key
    with pytest.raises(ValueError, match="'mean_supply_pressure_Pa'.*registered already"):
        register_output(Output("x", "Pa", "again", lambda r: 0.0, key="mean_supply_pressure_Pa"))
    with pytest.raises(ValueError, match="not an output added by register_output"):
        unregister_output("blow_frequency")
    with pytest.raises(ValueError, match="give of="):
        Output("x", "m", "no way to compute it", views={"store"})


def _declared(call: ast.Call) -> set:
    """The quantities ``(key, dtype)`` (the key the name with its unit, as :attr:`Output.key`) a literal
    declaration ``Field(name, long_name, units)``, ``SI(name, units)`` or ``Output(name, unit, ...)``
    writes; empty where its name or unit is not written as a literal. (A complex multiplier is not
    the real modulus of the same name.)"""
    kind = call.func.id if isinstance(call.func, ast.Name) else None
    args, kw = call.args, {k.arg: k.value for k in call.keywords}
    if kind not in ("Field", "SI", "Output") or not args or not isinstance(args[0], ast.Constant):
        return set()
    name = args[0].value
    at = {"Field": 2, "SI": 1, "Output": 1}[kind]
    unit = args[at] if len(args) > at else kw.get("units" if kind != "Output" else "unit")
    if unit is None and kind == "Field":
        unit = ast.Constant("1")  # (a Field's default units)
    if not isinstance(unit, ast.Constant):
        return set()
    keys = {name if kind == "SI" or name.endswith(_suffix(unit.value)) else _named(name, unit.value)}
    if kind == "Output" and isinstance(kw.get("key"), ast.Constant):
        keys.add(kw["key"].value)
    dtype = kw["dtype"].value if isinstance(kw.get("dtype"), ast.Constant) and kind != "SI" else "f8"
    return {(k, dtype) for k in keys}


def declarations(source: str, keys: set) -> list:
    """``(line, key)`` of each literal declaration in ``source`` of one of ``keys`` (``(key, dtype)``)."""
    return sorted((node.lineno, k) for node in ast.walk(ast.parse(source)) if isinstance(node, ast.Call)
                  for k, _ in _declared(node) & keys)


def test_each_output_is_declared_in_one_place():
    """An output's name and unit are written in one declaration in the whole package: the registry's
    ``Output``, or the result type's field the output is read from; a second (a schema's field of
    the same name and unit, the SI column of an orbit's field) is a count above 0."""
    keys = {(k, o.dtype) for o in OUTPUTS.values() for k in (o.key, _named(o.name, o.unit))}
    where: dict = {}
    for path in sorted(SRC.rglob("*.py")):
        for line, key in declarations(path.read_text(), keys):
            where.setdefault(key, []).append(f"{path.relative_to(SRC).as_posix()}:{line}")
    twice = {k: v for k, v in where.items() if len(v) > 1}
    assert len(twice) == 0, "outputs declared in more than one place:\n" + "\n".join(
        f"{k}: {', '.join(v)}" for k, v in sorted(twice.items()))


def test_a_second_declaration_is_counted():
    keys = {("blow_frequency_Hz", "f8"), ("impact_velocity_m_s", "f8"), ("stable", "b1"),
            ("multiplier", "f8")}
    planted = ('A = Schema(Field("blow_frequency_Hz", "blows per second", "Hz"),\n'
               '           Field("blow_frequency", "blows", "Hz"), Field("stable", "", "", dtype="b1"),\n'
               '           Field("impact_velocity", "dimensionless", per="impact"),\n'
               '           Field("x", "y", si=SI("impact_velocity_m_s", "m/s", "velocity_m_s")))\n'
               'B = Output("blow_frequency", "Hz", "blow frequency", lambda r: 0.0)\n'
               'E = Field("multiplier", "the critical multiplier", dtype="c16")\n')
    assert declarations(planted, keys) == [(1, "blow_frequency_Hz"), (2, "blow_frequency_Hz"), (2, "stable"),
                                           (4, "impact_velocity_m_s"), (5, "blow_frequency_Hz")]
    assert not declarations('C = OUTPUTS["blow_frequency"].column(views={"dict"})\n', keys)


def test_the_shared_outputs_read_one_declaration():
    """The orbit's fields and the SI results' columns that are outputs carry the registry's name and
    unit (the same objects' values, not equal copies)."""
    from impactbar.orbits.orbit import ORBIT_FIELDS
    from impactbar.physical.results import PHYSICAL_ORBIT_FIELDS

    v, si = OUTPUTS["impact_velocity"], ORBIT_FIELDS["impact_velocity"].si
    assert (v.key, v.unit) == (si.name, si.units)
    for name in ("stable", "max_abs_multiplier", "admissibility"):
        assert (OUTPUTS[name].name, OUTPUTS[name].unit, OUTPUTS[name].dtype) == (
            name, ORBIT_FIELDS[name].units, ORBIT_FIELDS[name].dtype)
    for name in ("blow_frequency", "rod_energy", "work_on_rock", "penetration", "drilling_rate"):
        o = OUTPUTS[name]
        assert PHYSICAL_ORBIT_FIELDS[o.key].units == o.unit
    settle = map_variables("circuit", False, "settle")
    stored = map_variables("circuit", False)
    assert settle["impact_velocity"].units == stored["impact_velocity"].units == "m/s"
    assert settle["blow_frequency_spread"].units == "Hz"


#: the CLI's functions that print a run's own figures (a hammer's run, the per-impact columns of a
#: circuit's run), not an operating point's outputs
RUNS = {("cli/simulate.py", None), ("cli/drifter.py", "run_circuit_simulate")}


def keys_with_units(source: str, keys: set) -> list:
    """``(line, where, key)`` of each string literal of ``source`` (an f-string's subscript too) that is
    one of ``keys``, ``where`` the enclosing top-level function."""
    found = []
    for top in ast.parse(source).body:
        for sub in ast.walk(top):
            if isinstance(sub, ast.Constant) and sub.value in keys:
                found.append((sub.lineno, getattr(top, "name", None), sub.value))
    return found


def test_the_cli_reads_keys_and_display_units_from_the_registry():
    """The CLI's lines of an operating point name no output's key with its unit (``blow_frequency_Hz``,
    ``mean_supply_pressure_MPa``): they read the key and the display unit from the registry."""
    keys = {k for o in OUTPUTS.values() for k in (o.key, o.shown_key) if k != o.name}
    bad = []
    for path in sorted((SRC / "cli").rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        found = keys_with_units(path.read_text(), keys)
        bad += [f"{rel}:{line} ({where}): {key}" for line, where, key in found
                if (rel, None) not in RUNS and (rel, where) not in RUNS]
    assert not bad, "keys with their units written in the CLI:\n" + "\n".join(bad)
    planted = "def line(s):\n    return f\"{s['pump_power_kW']:.4g} kW\"\n"
    assert keys_with_units(planted, keys) == [(2, "line", "pump_power_kW")]
