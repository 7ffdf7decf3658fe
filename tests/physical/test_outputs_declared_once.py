"""Each output of a drifter is declared once, in :mod:`impactbar.physical.outputs`: the names the map
stores, the optimiser, the sensitivities and the CLI use are the registry's, and no module of the SI
layers (physical, sweeps, cli) lists output names by hand (a scan of their literals, as
``tests/test_record_slots.py`` scans the kernels)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from impactbar.physical.optimize_drifter import DEFAULT_CONSTRAINTS, IDEAL_CONSTRAINTS, OBJECTIVES
from impactbar.physical.optimize_outputs import constraint_output
from impactbar.physical.outputs import OUTPUTS, outputs
from impactbar.physical.sensitivity import FIGURE_UNITS
from impactbar.sweeps.map_spec import map_variables
from impactbar.sweeps.map_task import EDGE_FLAGS

SRC = Path(__file__).resolve().parents[2] / "src" / "impactbar"
#: the SI layers, whose tools read the registry
LAYERS = ("physical", "sweeps", "cli")
#: the modules that compute the figures the registry reads (a blow's, the rock's, a run's records),
#: and the registry itself
PRODUCERS = {"physical/outputs.py", "physical/rock.py", "physical/piston.py", "physical/results.py"}
#: literals that name outputs for another reason: the constraints' names (a constraint may share its
#: output's name), a run's per-impact columns and summary (not an operating point's outputs)
ALLOWED = {("physical/optimize_problem.py", "DEFAULT_CONSTRAINTS"),
           ("physical/optimize_problem.py", "IDEAL_CONSTRAINTS"),
           ("physical/optimize_outputs.py", "_CONSTRAINTS"),
           ("physical/drifter.py", "simulate"), ("cli/drifter.py", "run_circuit_simulate")}


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
               "class C:\n    def g(self):\n        return ['relief_margin', 'peak_incident_stress']\n")
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
