"""The documentation's sources: the theory page keeps its numbered sections and anchors (docstrings
cite "theory §N"), nothing points outside the repository, the gallery covers Figs. 4-8 and Section 5.
The site itself is built, with its examples executed, by .ci/run (sphinx -W)."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
SECTIONS = ["1", "2", "3", "4", "4b", "5", "6", "7", "8", "9", "10", "11", "12"]


def test_theory_keeps_the_numbered_sections_with_stable_anchors():
    text = (DOCS / "theory.md").read_text()
    found = re.findall(r"^\(theory-([0-9a-z]+)\)=\n## ([0-9a-z]+)\. ", text, flags=re.M)
    assert [label for label, _ in found] == SECTIONS
    assert all(label == number for label, number in found)
    for extra in ("theory-si", "theory-corrections", "theory-findings"):
        assert f"({extra})=" in text


@pytest.mark.parametrize("path", sorted([*DOCS.glob("*.md"), ROOT / "README.md",
                                         *(ROOT / "src" / "impactbar" / "cli").glob("*.py")]),
                         ids=lambda p: p.name)
def test_nothing_points_outside_the_repository(path):
    text = path.read_text()
    assert "MODEL.md" not in text and "../shared" not in text


def test_gallery_covers_the_paper():
    names = {p.stem for p in (DOCS / "gallery_src").glob("plot_*.py")}
    assert {f"plot_fig{i}" for i in range(4, 9)} | {"plot_section5_experiments"} <= names
    tutorials = {p.stem for p in (DOCS / "tutorials_src").glob("plot_*.py")}
    assert len(tutorials) >= 2


def test_public_modules_of_the_api_reference_import():
    import importlib

    text = (DOCS / "conf.py").read_text()
    mods = re.search(r"PUBLIC_MODULES = \(([^)]*)\)", text, flags=re.S).group(1)
    for name in re.findall(r'"([a-z_.]+)"', mods):
        importlib.import_module(name)
