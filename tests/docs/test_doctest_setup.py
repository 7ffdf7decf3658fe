"""Every docstring example runs as a doctest under the README's test command
(``python -m pytest -n auto``): the configuration collects the package's modules, and the examples
that exist are collected."""

import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_default_run_collects_the_package_doctests():
    ini = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert "src/impactbar" in ini["testpaths"]
    assert "--doctest-modules" in ini["addopts"].split()
    assert {"NUMBER", "ELLIPSIS", "NORMALIZE_WHITESPACE"} <= set(ini["doctest_optionflags"].split())


def test_every_docstring_example_is_collected_and_no_main_module_runs():
    out = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider",
                          "src/impactbar"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    collected = {line.split("::")[0] for line in out.stdout.splitlines() if "::" in line}
    with_examples = {str(p.relative_to(ROOT)) for p in (ROOT / "src" / "impactbar").rglob("*.py")
                     if ">>> " in p.read_text()}
    assert with_examples and with_examples <= collected
    assert not any(p.endswith("__main__.py") for p in collected)
