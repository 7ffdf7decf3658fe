"""What a user reads speaks of the project, not of its tracker: no "issue 38", "issue #5",
"issues 20, 41" or "issue-40" in the documentation's sources, the README, the examples, or the
package's code, comments and docstrings. The CHANGELOG, a history, may name them."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ISSUE = re.compile(r"\bissues?[ \t_#-]*\d+", flags=re.I)

#: what the documentation's build writes (``.gitignore``): copies of the sources scanned here
GENERATED = {"_build", "api", "gallery", "tutorials", "api.rst", "sg_execution_times.rst", "guides.md"}

def _scanned() -> list[Path]:
    docs = [p for p in (ROOT / "docs").rglob("*")
            if p.suffix in (".md", ".py", ".rst") and not GENERATED & set(p.relative_to(ROOT / "docs").parts)]
    examples = [p for p in (ROOT / "examples").rglob("*") if p.is_file() and p.suffix != ".csv"]
    code = list((ROOT / "src" / "impactbar").rglob("*.py"))
    return sorted({ROOT / "README.md", *docs, *examples, *code})


def _citations(path: Path) -> list[str]:
    text = path.read_text(encoding="utf-8")
    return [f"{path.relative_to(ROOT).as_posix()}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)!r}"
            for m in ISSUE.finditer(text)]


def test_the_scan_covers_what_a_user_reads():
    names = {p.relative_to(ROOT).as_posix() for p in _scanned()}
    assert {"README.md", "docs/performance.md", "docs/theory.md", "docs/conf.py",
            "docs/gallery_src/README.rst", "examples/circuit_drifter.toml", "examples/circuit_drifter.py",
            "src/impactbar/cli/drifter.py", "src/impactbar/physical/drifter.py"} <= names
    assert "CHANGELOG.md" not in names


def test_the_pattern_finds_each_way_of_writing_an_issue_number():
    found = ISSUE.findall("(issue 38) Issue #5, issues 20, 41; the issue-40 cases; drifter-issue19")
    assert found == ["issue 38", "Issue #5", "issues 20", "issue-40", "issue19"]
    assert ISSUE.findall("the issue of the valve's delay, tissue 3") == []


def test_no_issue_numbers_reach_the_user():
    found = [c for p in _scanned() for c in _citations(p)]
    assert not found, "issue numbers cited (say what the text means instead):\n" + "\n".join(found)
