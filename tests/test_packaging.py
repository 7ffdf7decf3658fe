"""What a user receives with the package: one version, the licence, the type marker, the citation,
the changelog, extras that cover the README, floors CI can pin."""

import importlib.metadata as md
import importlib.resources
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import impactbar

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_one_version_source():
    assert PYPROJECT["project"]["dynamic"] == ["version"]
    assert "version" not in PYPROJECT["project"]
    assert md.version("impactbar") == impactbar.__version__
    assert re.fullmatch(r"\d+\.\d+\.\d+", impactbar.__version__)
    out = subprocess.run([sys.executable, "-m", "impactbar", "--version"], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == f"impactbar {impactbar.__version__}"


def test_licence_file_is_shipped_and_matches_the_declared_licence():
    # the installed distribution (the one pip wrote, with INSTALLER), not the build's egg-info that a
    # source tree on sys.path (the doctests put src/ there) may show first
    dist = next(d for d in md.distributions(name="impactbar") if d.read_text("INSTALLER") is not None)
    assert dist.metadata["License-Expression"] == "BSD-3-Clause"
    text = dist.read_text("licenses/LICENSE")
    assert text is not None and text.startswith("BSD 3-Clause License")
    assert text == (ROOT / "LICENSE").read_text()


def test_typed_marker_is_shipped():
    assert (importlib.resources.files("impactbar") / "py.typed").is_file()
    assert "py.typed" in PYPROJECT["tool"]["setuptools"]["package-data"]["impactbar"]


def test_citation_names_the_software_and_the_paper():
    text = (ROOT / "CITATION.cff").read_text()
    assert text.startswith("cff-version: 1.2.0")
    assert f'version: "{impactbar.__version__}"' in text
    assert "license: BSD-3-Clause" in text
    for piece in ("Bjorkenstam", "Impact vibration of a bar", "International Journal of Mechanical Sciences",
                  "volume: 19", "start: 471", "end: 481", "year: 1977"):
        assert piece in text, piece


def test_changelog_has_this_version():
    text = (ROOT / "CHANGELOG.md").read_text()
    assert f"## [{impactbar.__version__}]" in text
    assert "## [Unreleased]" in text


def test_readme_first_command_installs_everything_the_readme_uses():
    readme = (ROOT / "README.md").read_text()
    first = next(line for line in readme.splitlines() if "pip install" in line)
    assert 'pip install ".[all]"' in first
    extras = PYPROJECT["project"]["optional-dependencies"]
    all_extras = set(re.findall(r"impactbar\[([^\]]*)\]", extras["all"][0])[0].split(","))
    assert {"plot", "units", "data", "distributed"} <= all_extras
    assert set(extras) - {"all", "test", "docs"} <= all_extras  # nothing optional left out of all
    assert "MODEL.md" not in readme and "../shared" not in readme


def test_min_constraints_pin_every_floor():
    sys.path.insert(0, str(ROOT / ".ci"))
    try:
        import min_constraints
    finally:
        sys.path.pop(0)
    floors = min_constraints.floors(ROOT / "pyproject.toml")
    declared = PYPROJECT["project"]["dependencies"] + [
        r for group in PYPROJECT["project"]["optional-dependencies"].values() for r in group]
    for req in declared:
        m = re.match(r"([A-Za-z0-9_.-]+)(\[[^\]]*\])?>=([0-9.]+)$", req.split(";")[0].strip())
        if m and m.group(1) != "impactbar":
            assert floors[m.group(1).lower()] == m.group(3), req
    assert floors["zarr"].startswith("3.")  # the store is zarr format 3
    assert floors["distributed"] == floors["dask"]
