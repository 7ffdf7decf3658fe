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


def test_no_module_over_800_lines():
    import impactbar

    top = Path(impactbar.__file__).parent
    long = {str(p.relative_to(top)): n for p in top.rglob("*.py")
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > 800}
    assert long == {}


SOLVERS = ("impactbar.orbits", "impactbar.simulation", "impactbar.continuation")


def test_laws_and_the_model_import_no_solver():
    """Each contact law is a package below the solvers (issue 37): no module of ``impactbar.laws``,
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
    assert {"impact_map", "window", "orbit_state", "phase_roots", "contact"} <= called
    missing = sorted(n for n in called if not hasattr(ContactLaw, n))
    assert missing == []
    for n in called:  # a method has its docstring, a flag its entry among the class's attributes
        member = getattr(ContactLaw, n)
        assert member.__doc__ if callable(member) else f"    {n} : " in ContactLaw.__doc__, n
