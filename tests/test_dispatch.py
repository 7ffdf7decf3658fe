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


def _forcing_classes() -> set[str]:
    """The names of Load, Drive and every subclass of theirs the package defines (every module of it
    imported, so that the walk of ``__subclasses__`` sees them all)."""
    import importlib
    import pkgutil

    for info in pkgutil.walk_packages(impactbar.__path__, "impactbar."):
        if not info.name.endswith("__main__"):
            importlib.import_module(info.name)

    def walk(cls):
        return {cls}.union(*(walk(sub) for sub in cls.__subclasses__()))

    return {c.__name__ for c in walk(impactbar.Load) | walk(impactbar.Drive)
            if c.__module__.startswith("impactbar.")}


#: the names a forcing goes by in the package (a class's test on a value of that name is a decision
#: on the forcing, whatever the class)
FORCING_NAMES = {"load", "drive", "forcing"}


def _class_of(node) -> bool:
    """Whether ``node`` is ``type(x)`` or ``x.__class__``."""
    return (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "type"
            and len(node.args) == 1) or (isinstance(node, ast.Attribute) and node.attr == "__class__")


def _a_forcing(node) -> bool:
    """Whether ``node`` names a forcing by the package's names for one (``load``, ``self.drive``)."""
    name = node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute) else None
    return name in FORCING_NAMES


def _class_decisions(tree, classes: set[str]) -> list[str]:
    """The decisions on a forcing's class in ``tree``: ``isinstance``/``issubclass`` against any of
    ``classes`` (the forcing classes, under their own names or an alias they were imported as);
    ``type(x)`` or ``x.__class__`` as a table's key (``T[type(x)]``, ``T.get(type(x))``,
    ``type(x) in T``) whatever ``x``; ``type(x)`` or ``x.__class__`` compared with a forcing class, or
    with anything where ``x`` is a forcing by name; and a forcing class's name compared as a string.
    ``"line: code"`` each."""
    names = set(classes)
    for node in ast.walk(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            names |= {a.asname for a in node.names if a.asname and a.name.rpartition(".")[2] in classes}
    pattern = re.compile(r"\b({})\b".format("|".join(sorted(names))))

    def names_one(node):
        return bool(pattern.search(ast.unparse(node)))

    out = []
    for node in ast.walk(tree):
        bad = False
        if isinstance(node, ast.Call) and _callee(node) in ("isinstance", "issubclass") \
                and len(node.args) == 2:
            bad = names_one(node.args[1])
        elif isinstance(node, ast.Subscript):
            bad = _class_of(node.slice)
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.args:
            bad = node.func.attr in ("get", "setdefault", "pop") and _class_of(node.args[0])
        elif isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            bad = any(isinstance(s, ast.Constant) and s.value in names for s in sides)  # a class's name
            for i, side in enumerate(sides):
                if not _class_of(side):
                    continue
                others = sides[:i] + sides[i + 1:]
                x = side.args[0] if isinstance(side, ast.Call) else side.value
                bad = bad or _a_forcing(x) or any(isinstance(op, (ast.In, ast.NotIn)) for op in node.ops) \
                    or any(names_one(o) or _class_of(o) and _a_forcing(o.args[0] if isinstance(o, ast.Call)
                                                                          else o.value) for o in others)
        if bad:
            out.append(f"{node.lineno}: {ast.unparse(node)}")
    return out


def test_nothing_outside_the_dispatch_asks_a_forcing_s_class():
    """No module but the dispatch's tests a forcing's class: not by ``isinstance`` or ``issubclass``
    against Load, Drive or any of their subclasses, not by ``type(x)`` in a table keyed by class, not
    by comparing a forcing's ``type``. What a caller needs of a forcing, the forcing declares (an
    attribute of its base: ``traits``, ``abilities``), or the dispatch says
    (:func:`~impactbar._shared.forcing.of_family`, :func:`~impactbar._shared.forcing.alike`)."""
    classes = _forcing_classes()
    assert {"Load", "Drive", "CosineLoad", "SquareWaveLoad", "FourierLoad", "PiecewiseConstantLoad",
            "PositionSwitchedDrive", "HydraulicCircuitDrive"} <= classes
    bad = [f"{path.relative_to(SRC)}:{found}" for path, tree in _modules() if path != HOME
           for found in _class_decisions(tree, classes)]
    assert bad == []


def test_the_class_scan_sees_planted_decisions():
    """Each form the scan above reports, planted, is seen; a type test that is no decision on a
    forcing (a value's own ``__eq__``, a float's type) is not."""
    planted = ("from ..loads import SquareWaveLoad as _Sq\n"
               "def f(load, drive, x, other):\n"
               "    a = isinstance(load, CosineLoad)\n"
               "    b = issubclass(type(x), (int, PositionSwitchedDrive))\n"
               "    c = isinstance(x, _Sq)\n"
               "    d = SOLVERS[type(x)]\n"
               "    e = TABLE.get(drive.__class__)\n"
               "    g = type(load) is FourierLoad\n"
               "    h = type(self.drive) is type(drive)\n"
               "    i = type(x).__name__ == 'Load'\n"
               "    j = type(x) in KNOWN\n"
               "    k = type(other) is not type(self)\n"
               "    m = type(x) is float\n"
               "    n = isinstance(x, _Drive)\n")
    found = _class_decisions(ast.parse(planted), {"Load", "Drive", "CosineLoad", "FourierLoad",
                                                  "SquareWaveLoad", "PositionSwitchedDrive"})
    assert [f.partition(":")[0] for f in found] == [str(n) for n in range(3, 12)], found


def _probes(tree, declared) -> list[str]:
    """``hasattr(x, "name")`` and ``getattr(x, "name", default)`` on a forcing by name (``load``,
    ``self.drive``) where ``name`` is not in ``declared[x's name]`` (what its family's base
    declares): a probe for what one class has stands in for a test of the class. ``"line: code"``
    each."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and _callee(node) in ("hasattr", "getattr") and len(node.args) >= 2 \
                and _a_forcing(node.args[0]) and isinstance(node.args[1], ast.Constant):
            x = node.args[0]
            if node.args[1].value not in declared[x.id if isinstance(x, ast.Name) else x.attr]:
                out.append(f"{node.lineno}: {ast.unparse(node)}")
    return out


def _declared() -> dict[str, set[str]]:
    """What a forcing of each name is asked for: a load what :class:`~impactbar.Load` declares, a
    drive what :class:`~impactbar.Drive` declares, a forcing of either family what both do."""
    load, drive = set(dir(impactbar.Load)), set(dir(impactbar.Drive))
    return {"load": load, "drive": drive, "forcing": load & drive}


def test_no_probe_stands_in_for_a_forcing_s_class():
    """Outside the dispatch, what code asks of a forcing by ``hasattr``/``getattr`` is declared on
    its base (:class:`~impactbar.Load` or :class:`~impactbar.Drive`, with a default there): a
    Fourier load's ``orders`` or a piecewise one's jumps are asked of every load, never probed to
    tell the classes apart (a load's are in its ``abilities``)."""
    bad = [f"{path.relative_to(SRC)}:{found}" for path, tree in _modules() if path != HOME
           for found in _probes(tree, _declared())]
    assert bad == []


def test_the_probe_scan_sees_planted_probes():
    planted = ("def f(load, self, x):\n"
               "    a = getattr(load, 'breaks', None)\n"
               "    b = hasattr(self.load, 'levels')\n"
               "    c = getattr(self.drive, 'compiled', True)\n"
               "    d = getattr(load, 'traits', None)\n"
               "    e = hasattr(x, 'levels')\n")
    assert [f.partition(":")[0] for f in _probes(ast.parse(planted), _declared())] == ["2", "3", "4"]


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
