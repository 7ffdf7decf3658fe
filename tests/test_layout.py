"""The package's layout contract, beyond what ``lint-imports`` checks: no import cycles at all (imports
made only for type checkers, under ``if TYPE_CHECKING:``, are not imports at run time and do not count)."""

from pathlib import Path

import grimp


def _strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's algorithm: the strongly connected components of more than one module."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_tarjan_finds_a_planted_cycle():
    assert _strongly_connected({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _strongly_connected({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles_between_modules():
    g = grimp.build_graph("impactbar", cache_dir=None, exclude_type_checking_imports=True)
    # a package's __init__ re-exports its submodules by design; a cycle through an __init__ alone
    # (package -> submodule -> sibling imported via the package) is still a cycle and reported
    graph = {m: set(g.find_modules_directly_imported_by(m)) for m in g.modules}
    assert _strongly_connected(graph) == []


def test_at_most_eight_modules_at_the_top_level():
    import impactbar

    top = Path(impactbar.__file__).parent
    modules = sorted(p.name for p in top.glob("*.py"))
    assert len(modules) <= 8, modules


def test_tests_mirror_the_package():
    """Every test folder is named after a subpackage of impactbar, or is ``docs`` (the built site and
    the numbers the pages quote); the tests of top-level modules and cross-cutting tests stay in
    tests/ itself."""
    import impactbar

    top = Path(impactbar.__file__).parent
    subpackages = {p.parent.name for p in top.glob("*/__init__.py")}
    here = Path(__file__).parent
    folders = {p.parent.relative_to(here).parts[0] for p in here.rglob("test_*.py") if p.parent != here}
    assert folders <= subpackages | {"docs"}, folders - subpackages
    assert len(folders) >= 6


#: at most this many modules of the package may have :data:`LONG_MODULE` lines or more (none over 800):
#: none, a module within 50 lines of the cap is split by its concepts, not trimmed to fit
MAX_LONG_MODULES = 0
LONG_MODULE = 750


def test_no_module_over_800_lines():
    """No module over 800 lines, and at most :data:`MAX_LONG_MODULES` of :data:`LONG_MODULE` lines or
    more: a module that grows past it is split by the concepts it holds."""
    import impactbar

    top = Path(impactbar.__file__).parent
    sizes = {str(p.relative_to(top)): len(p.read_text(encoding="utf-8").splitlines())
             for p in top.rglob("*.py")}
    assert {m: n for m, n in sizes.items() if n > 800} == {}
    long = {m: n for m, n in sorted(sizes.items()) if n >= LONG_MODULE}
    assert len(long) <= MAX_LONG_MODULES, f"{len(long)} modules of {LONG_MODULE}+ lines: {long}"


SOLVERS = ("impactbar.orbits", "impactbar.simulation", "impactbar.continuation")


def test_laws_and_the_model_import_no_solver():
    """Each contact law is a package below the solvers: no module of ``impactbar.laws``,
    nor ``impactbar.model`` (which holds a law), reaches the orbit solvers, the simulator or the
    continuation, directly or through another module; so following a model through
    ``periodic_orbits`` never climbs back up a layer."""
    g = grimp.build_graph("impactbar", cache_dir=None, exclude_type_checking_imports=True)
    laws = sorted(m for m in g.modules if m.startswith("impactbar.laws"))
    assert {"impactbar.laws.paper", "impactbar.laws.wave", "impactbar.laws.rodrock"} <= set(laws)
    for m in [*laws, "impactbar.model"]:
        up = {u for u in g.find_upstream_modules(m) if u.startswith(SOLVERS)}
        assert up == set(), (m, sorted(up))


def test_every_law_hook_the_solvers_call_is_declared_on_the_base():
    """Every ``law.<name>`` the solvers read (orbits, simulation, continuation, drives) is declared on
    :class:`~impactbar.laws.ContactLaw` with a docstring, so that a new law knows what to provide."""
    import re

    import impactbar
    from impactbar.laws import ContactLaw

    top = Path(impactbar.__file__).parent
    called = set()
    for sub in ("orbits", "simulation", "continuation", "drives"):
        for p in (top / sub).rglob("*.py"):
            code = [ln for ln in p.read_text(encoding="utf-8").splitlines()
                    if not ln.lstrip().startswith(">>>")]  # (not a docstring's example)
            called |= set(re.findall(r"\blaw\.([a-z_]+)\b", "\n".join(code)))
    assert {"impact_map", "window", "ability", "traits", "contact"} <= called
    missing = sorted(n for n in called if not hasattr(ContactLaw, n))
    assert missing == []
    for n in called:  # a method has its docstring, a flag its entry among the class's attributes
        member = getattr(ContactLaw, n)
        assert member.__doc__ if callable(member) else f"    {n} : " in ContactLaw.__doc__, n


def _module_statements(body):
    """The statements that run at a module's import: its body and, recursively, the bodies of the
    ``if``/``try``/``with``/``for``/``while`` blocks in it (not those of functions and classes)."""
    import ast

    for node in body:
        yield node
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            continue
        for field in ("body", "orelse", "finalbody", "handlers"):
            yield from _module_statements(getattr(node, field, ()))


def _module_bool_switches(source: str) -> list[str]:
    """The module-level assignments of ``True`` or ``False`` to a name in ``source`` (plain,
    annotated or augmented; a tuple of names each counted): ``"NAME = True"`` each. An assignment to
    an attribute or an item (``array.flags.writeable = False``) sets no switch of the module and is
    not counted; no name is excluded."""
    import ast

    out = []
    for node in _module_statements(ast.parse(source).body):
        if isinstance(node, ast.Assign):
            pairs = []
            for target in node.targets:
                if isinstance(target, ast.Tuple) and isinstance(node.value, ast.Tuple):
                    pairs += zip(target.elts, node.value.elts, strict=False)
                else:
                    pairs.append((target, node.value))
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign)) and node.value is not None:
            pairs = [(node.target, node.value)]
        else:
            continue
        out += [f"{t.id} = {v.value}" for t, v in pairs if isinstance(t, ast.Name)
                and isinstance(v, ast.Constant) and isinstance(v.value, bool)]
    return out


def test_the_switch_finder_finds_planted_switches():
    src = ("A = True\nB: bool = False\nif x:\n    C = True\nelse:\n    D = 1\ntry:\n    E = False\n"
           "except OSError:\n    pass\nF, G = 1, True\nH = I = False\nflags.writeable = False\n"
           "def f():\n    J = True\nclass K:\n    L = True\nM = bool(1)\nN = None\n")
    assert _module_bool_switches(src) == ["A = True", "B = False", "C = True", "E = False", "G = True",
                                          "H = False", "I = False"]


def test_no_module_level_switches():
    """No module of the package sets a name to ``True`` or ``False`` at its top level (nor in an
    ``if``/``try`` block there): a choice of the way a computation runs is an argument of the
    function, or an option of the object, that runs it, never a module global that a test or a
    benchmark patches (what the switches of the oil circuit's flights and of the switched
    continuation were). A fact found at import (numba's cache writable) is a function's value."""
    import impactbar

    top = Path(impactbar.__file__).parent
    found = {str(p.relative_to(top)): s for p in sorted(top.rglob("*.py"))
             if (s := _module_bool_switches(p.read_text(encoding="utf-8")))}
    assert found == {}


def _package_of(module: list[str]) -> str | None:
    """The top-level package of a module's dotted name, split (``impactbar.orbits.orbit`` ->
    ``orbits``, ``impactbar.model`` -> ``model``); ``None`` for ``impactbar`` itself."""
    return module[1] if len(module) > 1 else None


def _imports(top: Path):
    """Every import of every module under ``top`` (the package's folder), those inside functions and
    under ``if TYPE_CHECKING:`` included: ``(importing module, imported module, imported name or
    None, line)``, each module a list of its dotted name's parts (relative imports resolved)."""
    import ast

    for p in sorted(top.rglob("*.py")):
        parts = [top.name, *p.relative_to(top).with_suffix("").parts]
        package = p.name == "__init__.py"
        if package:
            parts = parts[:-1]
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = parts if package else parts[:-1]
                    base = base[:len(base) - node.level + 1]
                    mod = base + (node.module.split(".") if node.module else [])
                else:
                    mod = node.module.split(".")
                for alias in node.names:
                    yield parts, mod, alias.name, node.lineno
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    yield parts, alias.name.split("."), None, node.lineno


def _package_graph(top: Path) -> dict[str, dict[str, list[str]]]:
    """``{A: {B: ["a.module:line", ...]}}``: the imports by which top-level package ``A`` reaches
    package ``B`` (every import, :func:`_imports`)."""
    graph: dict[str, dict[str, list[str]]] = {}
    for importer, mod, name, line in _imports(top):
        a = _package_of(importer)
        if mod[0] != top.name or a is None:
            continue
        b = _package_of(mod if len(mod) > 1 or name is None else [*mod, name])
        if b is not None and b != a:
            graph.setdefault(a, {}).setdefault(b, []).append(f"{'.'.join(importer)}:{line}")
    return graph


def _two_way(graph: dict[str, dict[str, list[str]]]) -> list[str]:
    """Each pair of packages that import each other, with the imports both ways."""
    return [f"{a} <-> {b}: {graph[a][b]} / {graph[b][a]}" for a in sorted(graph) for b in sorted(graph[a])
            if a < b and a in graph.get(b, {})]


def test_the_package_graph_sees_every_import(tmp_path):
    pkg = tmp_path / "pkg"
    for folder in ("a", "b", "c"):
        (pkg / folder).mkdir(parents=True)
        (pkg / folder / "__init__.py").write_text("")
    (pkg / "a" / "x.py").write_text("def f():\n    from ..b import y\n")
    (pkg / "b" / "y.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                                    "    from pkg.a.x import f\n")
    (pkg / "c" / "z.py").write_text("import pkg.a.x\nfrom .. import b\n")
    (pkg / "m.py").write_text("from .c import z\n")
    graph = _package_graph(pkg)
    assert {a: sorted(v) for a, v in graph.items()} == {"a": ["b"], "b": ["a"], "c": ["a", "b"],
                                                        "m": ["c"]}
    assert _two_way(graph) == ["a <-> b: ['pkg.a.x:2'] / ['pkg.b.y:3']"]


def test_no_two_packages_import_each_other():
    """Between the top-level packages (the folders and modules under ``src/impactbar``; the root
    ``impactbar/__init__.py``, which gathers the public names, apart) the imports go one way only,
    counting every import: those inside functions (a result's ``plot`` method reaching the drawing)
    and those under ``if TYPE_CHECKING:`` (a law's annotations) too. What both sides need lives
    below both (the laws annotate with :class:`~impactbar.laws.base.BarModelLike`, the drawing reads
    a branch's fields from the branch)."""
    import impactbar

    graph = _package_graph(Path(impactbar.__file__).parent)
    assert {"orbits", "laws", "model", "continuation", "cli"} <= set(graph)
    assert _two_way(graph) == []


#: modules under src/impactbar that are no package of their own but the shared base every package
#: may reach into (validation, statuses, schemas, numba's cache; the version string)
SHARED_BASE = ("_shared", "_version")
#: at most this many imports of a private name or module from another package
MAX_PRIVATE_IMPORTS = 5


def _private(part: str) -> bool:
    return part.startswith("_") and not part.startswith("__")


def _private_imports(top: Path) -> list[str]:
    """Each import (every one, :func:`_imports`; an ``import from`` once per name) by a module of one
    top-level package of a name or module of another (not of :data:`SHARED_BASE`) where a part of the
    imported module's dotted path, or the imported name, starts with a single underscore
    (``from ..dynamics import _event_loop``, ``from ..orbits._newton import normalise``,
    ``from ..orbits.multi_impact import _Segments``): ``"importer:line <- module.name"`` each."""
    out = []
    for importer, mod, name, line in _imports(top):
        a = _package_of(importer)
        full = [*mod, name] if name is not None else mod
        if full[0] != top.name or a is None or len(full) < 2:
            continue
        b = full[1]
        if b in SHARED_BASE or b == a:
            continue
        if any(_private(part) for part in full[1:]):
            out.append(f"{'.'.join(importer)}:{line} <- {'.'.join(full)}")
    return out


def test_the_private_import_count_sees_each_form(tmp_path):
    pkg = tmp_path / "pkg"
    for folder in ("a", "b", "_shared"):
        (pkg / folder).mkdir(parents=True)
        (pkg / folder / "__init__.py").write_text("")
    (pkg / "a" / "x.py").write_text(
        "from ..b import _k, y\nfrom ..b._m import f, g\nimport pkg.b._m\nfrom .._shared import _s\n"
        "from . import _own\nfrom ..b.c import __doc__\ndef h():\n    from pkg.b.c import _late\n")
    assert _private_imports(pkg) == [
        "pkg.a.x:1 <- pkg.b._k", "pkg.a.x:2 <- pkg.b._m.f", "pkg.a.x:2 <- pkg.b._m.g",
        "pkg.a.x:3 <- pkg.b._m", "pkg.a.x:8 <- pkg.b.c._late"]


def test_few_private_names_cross_a_package():
    """A package takes another's private names (an underscored name, or anything from an underscored
    module) at most :data:`MAX_PRIVATE_IMPORTS` times, every import counted (those inside functions
    too): what is truly shared has a public name in a module that says it is the interface
    between the packages (``dynamics.compiled`` for the compiled building blocks, ``dynamics.monodromy``
    for the laws' multipliers, ``dynamics.invariants``, ``orbits.segments`` for what the continuation
    needs of the Newton solver). The shared base (:data:`SHARED_BASE`) is no package and is not
    counted."""
    import impactbar

    found = _private_imports(Path(impactbar.__file__).parent)
    assert len(found) <= MAX_PRIVATE_IMPORTS, "\n".join(found)


def _root_imports(top: Path) -> list[str]:
    """Each import by a module under ``top`` (the package's folder) of a name through the package's
    root ``__init__.py`` (every import, :func:`_imports`): ``from .. import X`` resolving to the
    package, ``from pkg import X``, ``import pkg``, where ``X`` is no module of the package (``from ..
    import physical`` imports the module itself). The root and the subpackages' ``__init__.py``
    (which re-export) and ``__main__`` modules are not counted. ``"importer:line <- pkg.X"`` each."""
    out = []
    for importer, mod, name, line in _imports(top):
        package = (top.joinpath(*importer[1:]) / "__init__.py").exists()
        if mod != [top.name] or importer[-1] == "__main__" or package:
            continue
        if name is not None and ((top / f"{name}.py").exists() or (top / name / "__init__.py").exists()):
            continue
        out.append(f"{'.'.join(importer)}:{line} <- {'.'.join(mod + ([name] if name else []))}")
    return out


def test_the_root_import_scan_sees_each_form(tmp_path):
    pkg = tmp_path / "pkg"
    for folder in ("a", "b"):
        (pkg / folder).mkdir(parents=True)
        (pkg / folder / "__init__.py").write_text("from .. import f\n")  # a re-export: not counted
    (pkg / "__init__.py").write_text("from .a.x import f\n")
    (pkg / "m.py").write_text("")
    (pkg / "__main__.py").write_text("from . import f\n")
    (pkg / "a" / "x.py").write_text(
        "from .. import f, b, m\nfrom . import y\nimport pkg\nfrom pkg import g\nfrom pkg.b import h\n"
        "def k():\n    from .. import late\n")
    assert _root_imports(pkg) == ["pkg.a.x:1 <- pkg.f", "pkg.a.x:3 <- pkg", "pkg.a.x:4 <- pkg.g",
                                  "pkg.a.x:7 <- pkg.late"]


def test_no_module_imports_through_the_package_root():
    """No module inside the package takes a name from the package's root ``impactbar/__init__.py``
    (``from .. import continue_orbit``, ``from impactbar import X``, ``import impactbar``): the root
    gathers the public names for users, and a module that imports through it depends on everything
    the root imports, hiding which package it reaches (the graphs above would not see it). A module
    imports from the package that defines the name."""
    import impactbar

    assert _root_imports(Path(impactbar.__file__).parent) == []


def _dict_switches(source: str) -> list[str]:
    """The switches held in a module-level dict of ``source``: inside a function, a ``True`` or
    ``False`` stored under a constant string key of a dict the module binds at its top level
    (``D["on"] = False``, ``D.update(on=False)``, ``D.setdefault("on", True)``): ``"line: D['on']"``
    each. A dict keyed by fixed names is a set of module globals in disguise, undeclared (a misspelt
    key is a new entry) and patched by tests with ``setitem``; tables keyed by computed keys (caches)
    and stores of other values are not counted."""
    import ast

    tree = ast.parse(source)
    dicts = set()
    for node in _module_statements(tree.body):
        value = getattr(node, "value", None)
        targets = node.targets if isinstance(node, ast.Assign) else [getattr(node, "target", None)]
        if isinstance(value, ast.Dict) or (isinstance(value, ast.Call) and isinstance(value.func, ast.Name)
                                           and value.func.id in ("dict", "defaultdict")):
            dicts |= {t.id for t in targets if isinstance(t, ast.Name)}

    def boolean(v):
        return isinstance(v, ast.Constant) and isinstance(v.value, bool)

    out = []
    for fn in ast.walk(tree):
        if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        for node in ast.walk(fn):
            if isinstance(node, ast.Assign) and boolean(node.value):
                out += [f"{node.lineno}: {t.value.id}[{t.slice.value!r}]" for t in node.targets
                        if isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name)
                        and t.value.id in dicts and isinstance(t.slice, ast.Constant)
                        and isinstance(t.slice.value, str)]
            elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                    and isinstance(node.func.value, ast.Name) and node.func.value.id in dicts:
                d = node.func.value.id
                if node.func.attr == "update":
                    out += [f"{node.lineno}: {d}[{k.arg!r}]" for k in node.keywords if boolean(k.value)]
                elif node.func.attr == "setdefault" and len(node.args) == 2 and boolean(node.args[1]) \
                        and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
                    out.append(f"{node.lineno}: {d}[{node.args[0].value!r}]")
    return sorted(set(out), key=lambda s: int(s.partition(":")[0]))


def test_the_dict_switch_finder_finds_planted_switches():
    src = ("_STATE = {'on': None, 'n': 0}\nCACHE: dict = {}\nT = dict()\nnot_a_dict = []\n"
           "def f(key):\n    _STATE['on'] = False\n    _STATE['n'] = 3\n    CACHE[key] = True\n"
           "    T.update(ok=True, reason='')\n    CACHE.setdefault('said', False)\n"
           "    local = {}\n    local['on'] = True\n    not_a_dict[0] = True\n"
           "class C:\n    def g(self):\n        _STATE['on'] = True\n")
    assert _dict_switches(src) == ["6: _STATE['on']", "9: T['ok']", "10: CACHE['said']", "16: _STATE['on']"]


def test_no_switch_is_held_in_a_module_level_dict():
    """No module keeps a switch (a ``True``/``False`` a function sets) in a module-level dict under a
    fixed key, which :func:`test_no_module_level_switches` would not see: the state a process keeps
    (the compile tier's, the compile note's) is an object of a class that declares and documents
    each field, and a fact found once (the SUNDIALS binding) a frozen value."""
    import impactbar

    top = Path(impactbar.__file__).parent
    found = {str(p.relative_to(top)): s for p in sorted(top.rglob("*.py"))
             if (s := _dict_switches(p.read_text(encoding="utf-8")))}
    assert found == {}
