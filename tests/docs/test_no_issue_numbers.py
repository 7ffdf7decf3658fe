"""What a user or a contributor reads speaks of the project, not of its tracker: no "issue 38",
"issue #5", "issues 20, 41", "issue-40" or "test_..._issue_19" in the documentation's sources, the
README, the examples, the package's code, comments and docstrings, the tests (their names and
parametrize ids too), the benchmarks and their probes, ``conftest.py`` or the CI scripts (``.ci``).
Histories may name them: the CHANGELOG and the benchmarks' log (``benchmarks/HISTORY.md``). This
file alone is not scanned: its examples of the pattern are what the pattern must find."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: "issue" after anything but a letter ("tissue 3" is no citation; "test_x_issue_19" is one), its
#: number after spaces, line breaks, "#", "_" or "-" (a comment's "issue\n    # 24")
ISSUE = re.compile(r"(?<![a-z])issues?[\s_#-]*\d+", flags=re.I)

#: what the documentation's build writes (``.gitignore``): copies of the sources scanned here
GENERATED = {"_build", "api", "gallery", "tutorials", "api.rst", "sg_execution_times.rst", "guides.md"}

def _scanned() -> list[Path]:
    docs = [p for p in (ROOT / "docs").rglob("*")
            if p.suffix in (".md", ".py", ".rst") and not GENERATED & set(p.relative_to(ROOT / "docs").parts)]
    examples = [p for p in (ROOT / "examples").rglob("*") if p.is_file() and p.suffix not in (".csv", ".npz")]
    code = list((ROOT / "src" / "impactbar").rglob("*.py"))
    tests = [p for p in (ROOT / "tests").rglob("*.py") if p != Path(__file__).resolve()]
    benchmarks = [p for p in (ROOT / "benchmarks").rglob("*")
                  if p.suffix in (".py", ".md") and p.name != "HISTORY.md"]
    ci = [p for p in (ROOT / ".ci").iterdir() if p.is_file()]
    return sorted({ROOT / "README.md", ROOT / "conftest.py", *docs, *examples, *code, *tests, *benchmarks,
                   *ci})


def _citations(path: Path) -> list[str]:
    text = path.read_text(encoding="utf-8")
    return [f"{path.relative_to(ROOT).as_posix()}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)!r}"
            for m in ISSUE.finditer(text)]


def test_the_scan_covers_what_a_user_reads():
    names = {p.relative_to(ROOT).as_posix() for p in _scanned()}
    assert {"README.md", "docs/performance.md", "docs/theory.md", "docs/conf.py",
            "docs/gallery_src/README.rst", "examples/circuit_drifter.toml", "examples/circuit_drifter.py",
            "src/impactbar/cli/drifter.py", "src/impactbar/physical/drifter.py"} <= names
    assert {"conftest.py", ".ci/run", ".ci/min_constraints.py", "tests/laws/_reference_blow.py",
            "tests/drives/test_drive_orbits.py", "tests/docs/test_quoted_numbers.py",
            "benchmarks/_peers.py", "benchmarks/bench_fast_paths.py", "benchmarks/fuzz_campaign.py",
            "benchmarks/probes/monodromy_magnus.py"} <= names
    assert {"CHANGELOG.md", "benchmarks/HISTORY.md", "tests/docs/test_no_issue_numbers.py"}.isdisjoint(names)
    assert not any("__pycache__" in name for name in names)


def test_the_pattern_finds_each_way_of_writing_an_issue_number():
    found = ISSUE.findall("(issue 38) Issue #5, issues 20, 41; the issue-40 cases; drifter-issue19;"
                          " def test_example_of_issue_19(); VALVE_ISSUE_7; callback, issue\n    # 24)")
    assert found == ["issue 38", "Issue #5", "issues 20", "issue-40", "issue19", "issue_19", "ISSUE_7",
                     "issue\n    # 24"]
    assert ISSUE.findall("the issue of the valve's delay, tissue 3, TISSUE_4, the issue's 2 cases") == []


def test_no_issue_numbers_reach_the_user():
    found = [c for p in _scanned() for c in _citations(p)]
    assert not found, "issue numbers cited (say what the text means instead):\n" + "\n".join(found)
