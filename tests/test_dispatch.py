"""One decision of the forcing's family: each entry point chooses its solver once, from a table keyed by
the family a forcing declares (a load, periodic in time, or a drive with state of its own); no solver
asks again, and nothing tests a forcing's class to choose."""

import ast
import re
from pathlib import Path

import pytest

import impactbar
from impactbar import (
    BarModel,
    CosineLoad,
    InitialState,
    PositionSwitchedDrive,
    continue_orbit,
    find_orbit,
    periodic_orbits,
    simulate,
)
from impactbar._shared.forcing import FAMILIES

SRC = Path(impactbar.__file__).parent
HOME = SRC / "_shared" / "forcing.py"
#: the entry points that choose a solver family, each by one table
ENTRY_POINTS = {"find_orbit", "periodic_orbits", "simulate", "continue_orbit"}


def _modules():
    for path in sorted(SRC.rglob("*.py")):
        yield path, ast.parse(path.read_text(encoding="utf-8"))


def _enclosing_functions(tree):
    """Map each call node to the name of the function it sits in (module level: None)."""
    where = {}

    def visit(node, fn):
        for child in ast.iter_child_nodes(node):
            name = child.name if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) else fn
            if isinstance(child, ast.Call):
                where[child] = fn
            visit(child, name)

    visit(tree, None)
    return where


def _callee(call):
    f = call.func
    return f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else None


def test_each_entry_point_chooses_its_solver_once_from_a_table():
    """Every ``dispatch`` call is in an entry point, once, on a module-level table whose keys are
    forcing families; every entry point has one."""
    found = {}
    for path, tree in _modules():
        tables = {t.id: node.value for node in tree.body if isinstance(node, ast.Assign)
                  for t in node.targets if isinstance(t, ast.Name)}
        for call, fn in _enclosing_functions(tree).items():
            if _callee(call) != "dispatch" or path == HOME:
                continue
            assert fn in ENTRY_POINTS, f"{path.name}: dispatch in {fn}, not an entry point"
            table = call.args[0]
            assert isinstance(table, ast.Name) and isinstance(tables.get(table.id), ast.Dict), \
                f"{path.name}:{call.lineno}: dispatch's table must be a module-level dict"
            keys = {k.value for k in tables[table.id].keys}
            assert keys and keys <= set(FAMILIES), (path.name, keys)
            found[fn] = found.get(fn, 0) + 1
    assert found == dict.fromkeys(ENTRY_POINTS, 1)


def test_no_solver_asks_the_family_again():
    """Outside the dispatch module nothing reads a forcing's ``family``, calls ``forcing_family``, or
    tests a forcing's class against Drive (the drive's old ``autonomous`` question is gone)."""
    bad = []
    for path, tree in _modules():
        if path == HOME:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and node.attr in ("family", "autonomous") \
                    and isinstance(node.ctx, ast.Load):
                bad.append(f"{path.relative_to(SRC)}:{node.lineno} .{node.attr}")
            if isinstance(node, ast.Call) and _callee(node) in ("forcing_family", "autonomous"):
                bad.append(f"{path.relative_to(SRC)}:{node.lineno} {_callee(node)}()")
            if isinstance(node, ast.Call) and _callee(node) == "isinstance" and len(node.args) == 2 \
                    and re.search(r"\bDrive\b", ast.unparse(node.args[1])):
                bad.append(f"{path.relative_to(SRC)}:{node.lineno} isinstance(..., Drive)")
            if isinstance(node, ast.Call) and _callee(node) in ("getattr", "hasattr") and len(node.args) > 1:
                name = node.args[1]
                if isinstance(name, ast.Constant) and name.value in ("family", "autonomous"):
                    bad.append(f"{path.relative_to(SRC)}:{node.lineno} {_callee(node)}(.., {name.value!r})")
    assert bad == []


def test_the_scan_sees_a_planted_decision():
    """The scans above can fail: a planted ``forcing_family`` call in a solver is seen, with the
    function it sits in."""
    tree = ast.parse("def solve(load):\n    if forcing_family(load) == 'drive':\n        pass\n")
    calls = [c for c in ast.walk(tree) if isinstance(c, ast.Call) and _callee(c) == "forcing_family"]
    assert len(calls) == 1 and _enclosing_functions(tree)[calls[0]] == "solve"


MODEL = BarModel(s=10.0, d=0.1, R=0.5, n_modes=0)
DRIVE = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)


@pytest.mark.parametrize("call", [
    lambda f: find_orbit(MODEL, f),
    lambda f: periodic_orbits(MODEL, f),
    lambda f: simulate(MODEL, f, InitialState.rigid(-0.5, 0.0), 5.0),
], ids=["find_orbit", "periodic_orbits", "simulate"])
def test_what_is_neither_a_load_nor_a_drive_gets_one_line(call):
    with pytest.raises(ValueError, match=r"^load must be a Load \(periodic in time.*or a Drive.*got str$"):
        call("cosine")


def test_the_same_entry_point_takes_either_family():
    """One entry point, two families: the load's orbit is one of its one-impact orbits (period
    ``2 pi``), the drive's an autonomous orbit whose period is an output; each continues."""
    load_orbit = find_orbit(MODEL, CosineLoad(0.3, 1.0))
    assert load_orbit.period == pytest.approx(2 * 3.141592653589793, rel=1e-14)
    drive_orbit = find_orbit(MODEL, DRIVE)
    assert drive_orbit.drive == DRIVE and drive_orbit.period > 0
    assert continue_orbit(load_orbit, "p0", to=0.35).values[-1] == pytest.approx(0.35)
    assert continue_orbit(drive_orbit, "stroke", to=1.1).values[-1] == pytest.approx(1.1)
