"""A designer's first hour, from a fresh environment: the README's first command, then a config of
their own (the example circuit drifter with two values changed), its operating point, a 3 x 3 design
map, its chart and a small optimisation, each through the installed ``impactbar`` command, and what
they print checked against the numbers the README prints for the same designs.

The environment is a new virtual environment (``python -m venv --system-site-packages``) with the
package's wheel built from this checkout (``pip wheel --no-deps``, with the build requirements of
``pyproject.toml``) and installed into it with ``pip install --no-deps`` (no editable install, no
copy of the sources on the path: the installed package and its own numba cache); the dependencies
come from the test's own environment through a ``.pth`` file of its site-packages (a full ``pip
install ".[all]"`` of every dependency takes long and needs the network). Slow: the installed copy
compiles its kernels into an empty cache."""

import os
import re
import site
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("zarr")
pytest.importorskip("matplotlib")

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _readme_map_lines() -> dict:
    """The README's design map of the preset: pump flow (L/min) to (blow frequency, efficiency)."""
    section = README[README.index("### Design maps of a drifter"):]
    shown = re.search(r"```text\n(.*?)```", section, flags=re.S).group(1)
    return {int(q): (f, eta) for q, f, eta in
            re.findall(r"^(\d+) L/min: ([\d.]+) Hz, hydraulic efficiency ([\d.]+)$", shown, flags=re.M)}


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    home = tmp_path_factory.mktemp("designer")
    # (nothing of the test's own path: pip would take the checkout on PYTHONPATH for the package)
    clean = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR")}
    env_dir = home / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(env_dir)], check=True)
    py = env_dir / "bin" / "python"
    purelib = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             check=True, capture_output=True, text=True).stdout.strip()
    # the wheel built as pip builds it (an isolated build environment of pyproject.toml's build
    # requirements, else this environment's), installed by the new environment's pip
    for isolation in ([], ["--no-build-isolation"]):
        built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", *isolation,
                                "--wheel-dir", str(home / "wheel"), str(ROOT)], cwd=home, capture_output=True,
                               text=True, env=clean)
        if built.returncode == 0:
            break
    else:
        pytest.skip(f"no build backend to build the wheel with: {built.stderr.strip()[-300:]}")
    wheel = next((home / "wheel").glob("impactbar-*.whl"))
    subprocess.run([str(py), "-m", "pip", "install", "--quiet", "--no-deps", str(wheel)], check=True,
                   cwd=home, env={**clean, "PIP_NO_INDEX": "1"})
    ours = [p for p in (*site.getsitepackages(), site.getusersitepackages()) if Path(p).is_dir()]
    # (written after the install: pip would otherwise find the checkout's own install there)
    (Path(purelib) / "_designer_deps.pth").write_text("\n".join(ours) + "\n")
    env = dict(clean)
    env.update(MPLBACKEND="Agg", PATH=f"{env_dir / 'bin'}{os.pathsep}{env['PATH']}")
    where = subprocess.run([str(py), "-c", "import impactbar; print(impactbar.__file__)"], check=True,
                           capture_output=True, text=True, cwd=home, env=env).stdout.strip()
    assert Path(where).is_relative_to(purelib), where  # the installed copy, not the checkout
    return home, env


def _run(venv, *argv, timeout=900):
    home, env = venv
    out = subprocess.run(["impactbar", *argv], cwd=home, env=env, capture_output=True, text=True,
                         timeout=timeout)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "Traceback" not in out.stderr
    return out.stdout


@pytest.mark.slow
def test_a_designers_path_in_a_fresh_environment(venv):
    home, _ = venv
    # the README's first command (after the environment is made)
    command = re.search(r"```bash\n(python3 -m venv .*?)\n```", README).group(1)
    assert command.endswith("impactbar paper --out paper-figures")
    _run(venv, "paper", "--out", "paper-figures")
    for fig in (4, 5, 6, 7, 8):
        assert any((home / "paper-figures").glob(f"*{fig}*.png")), fig

    # a config of their own: the example at 80 L/min, its pre-charge written in bar
    example = (ROOT / "examples" / "circuit_drifter.toml").read_text()
    mine = example.replace('pump_flow = "70 L/min"', 'pump_flow = "80 L/min"') \
        .replace('precharge = "10 MPa"', 'precharge = "100 bar"')
    assert mine.count("80 L/min") == 1 and mine.count("100 bar") == 1
    (home / "my.toml").write_text(mine)
    readme = _readme_map_lines()
    assert set(readme) == {60, 70, 80}
    text = _run(venv, "drifter", "my.toml")
    f80, eta80 = readme[80]
    assert f"blow frequency {f80} Hz" in text and f"hydraulic efficiency {eta80} " in text

    # a 3 x 3 map around it: the pre-charge's middle row is the README's map of the preset
    (home / "map.toml").write_text(
        'task = "operating_point"\nconfig = "my.toml"\n[axes]\n'
        '"supply.pump_flow" = { values = ["60 L/min", "70 L/min", "80 L/min"] }\n'
        '"accumulator.precharge" = { values = ["90 bar", "100 bar", "110 bar"] }\n')
    text = _run(venv, "sweep", "map.toml", "--out", "map.zarr", "--quiet")
    assert "chunks stored" in text
    edges = [line for line in text.splitlines() if line.startswith("edge: relief_opens")]
    assert edges and all("between 70 L/min and 80 L/min" in line for line in edges), text
    from impactbar.sweeps import open_sweep

    ds = open_sweep(home / "map.zarr")
    row = ds.sel({"accumulator.precharge": 1e7})
    for i, q in enumerate((60, 70, 80)):
        assert f"{float(row['blow_frequency'][i]):.2f}" == readme[q][0]
        assert f"{float(row['hydraulic_efficiency'][i]):.3f}" == readme[q][1]

    # its chart, then a small optimisation from the design
    _run(venv, "plot", "map.zarr", "--out", "map.png", "--variable", "blow_frequency")
    assert (home / "map.png").stat().st_size > 10_000
    text = _run(venv, "optimize", "my.toml", "--vary", "supply.pump_flow=75 L/min:85 L/min", "--objective",
                "impact_power", "--max-evaluations", "3", "--quiet")
    baseline = re.search(r"^blow_frequency_Hz\s+([\d.]+)\s", text, flags=re.M).group(1)
    assert f"{float(baseline):.2f}" == f80
    assert re.search(r"^gain in impact_power: [+-][\d.]+ % after 3 evaluations", text, flags=re.M), text
