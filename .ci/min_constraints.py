"""Print a pip constraints file pinning every dependency of pyproject.toml to its declared floor.

``python .ci/min_constraints.py > constraints.txt`` then ``pip install -c constraints.txt ".[all]"``
installs the oldest versions the project says it supports (CI's minimum-versions run).
"""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

REQ = re.compile(r"^\s*([A-Za-z0-9_.-]+)\s*(\[[^\]]*\])?\s*>=\s*([0-9][0-9A-Za-z.]*)\s*$")


def floors(pyproject: Path) -> dict[str, str]:
    """``{name: floor}`` for every requirement written ``name[extras]>=floor`` (self-references skipped)."""
    doc = tomllib.loads(pyproject.read_text())
    project = doc["project"]
    reqs = list(project.get("dependencies", []))
    for group in project.get("optional-dependencies", {}).values():
        reqs += group
    out: dict[str, str] = {}
    for req in reqs:
        m = REQ.match(req)
        if m is None:
            continue  # impactbar[...] self-references and unbounded requirements
        name = m.group(1).lower()
        if name == project["name"]:
            continue
        out[name] = m.group(3)
        if m.group(2) and "distributed" in m.group(2) and name == "dask":
            out["distributed"] = m.group(3)  # dask[distributed] pins distributed to dask's version
    return out


def main(argv: list[str]) -> int:
    path = Path(argv[1]) if len(argv) > 1 else Path(__file__).resolve().parents[1] / "pyproject.toml"
    skip = {"ruff", "import-linter"}  # linters: their floors are not runtime floors
    for name, ver in sorted(floors(path).items()):
        if name not in skip:
            print(f"{name}=={ver}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
