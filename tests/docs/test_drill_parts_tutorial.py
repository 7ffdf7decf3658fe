"""The tutorial "A drill with the parts a real drifter has" (``docs/tutorials_src/plot_4_drill_parts.py``)
and the map it reads (``docs/data/drill_cushion_map.csv``, made by
``benchmarks/make_drill_cushion_map.py`` on a local dask cluster).

- The stored map is the 15 x 15 grid over the cushion's volume and coefficient, and a sample of its
  points (two corners and the middle) is the operating point computed here afresh from the example's
  config with those values (each stored point was continued from its neighbour), to 1e-6.
- The same of the spool drill's map (``docs/data/drill_spool_map.csv``, made by
  ``benchmarks/make_drill_spool_map.py``) over the spool's mass and control end's area.
- The tutorial runs as a script (its figures and numbers, the map's figure from the store, the
  optimiser over the cushion): slow, some minutes of CPU.
"""

import csv
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from impactbar.physical import build, read_config, with_values

ROOT = Path(__file__).resolve().parents[2]
MAP = ROOT / "docs" / "data" / "drill_cushion_map.csv"
TUTORIAL = ROOT / "docs" / "tutorials_src" / "plot_4_drill_parts.py"
DRILL = ROOT / "examples" / "circuit_drill_parts.toml"
VOLUME, COEFFICIENT = "parts.cushion.volume", "parts.cushion.coefficient"
SPOOL_MAP = ROOT / "docs" / "data" / "drill_spool_map.csv"
SPOOL = ROOT / "examples" / "circuit_drill_spool.toml"
MASS, AREA = "parts.main_spool.mass", "parts.main_spool.large_area"


def _read(path):
    with path.open() as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def rows():
    return _read(MAP)


@pytest.fixture(scope="module")
def spool_rows():
    return _read(SPOOL_MAP)


def test_the_stored_map_is_the_15_by_15_grid(rows):
    v = np.array([float(r[VOLUME]) for r in rows])
    k = np.array([float(r[COEFFICIENT]) for r in rows])
    np.testing.assert_allclose(np.unique(v), np.linspace(5e-6, 40e-6, 15), rtol=1e-12)
    np.testing.assert_allclose(np.unique(k), np.linspace(2.5e-6, 1.5e-5, 15), rtol=1e-12)
    assert len(rows) == 225 and all(r["status"] == "0" for r in rows)


@pytest.mark.parametrize("i", [0, 112, 224])
def test_a_sample_of_the_maps_points_is_the_operating_point_computed_afresh(rows, i):
    r = rows[i]
    _is_afresh(DRILL, r, {VOLUME: f"{float(r[VOLUME])!r} m^3",
                          COEFFICIENT: f"{float(r[COEFFICIENT])!r} m^3/s/Pa^0.5"})


def _is_afresh(path, r, changes):
    """The stored point ``r`` is the operating point of the config at ``path`` with ``changes``."""
    point = build(with_values(read_config(str(path))[0], changes)).orbit()
    assert point.blow_frequency_Hz == pytest.approx(float(r["blow_frequency"]), rel=1e-6)
    assert point.impact_energy_J == pytest.approx(float(r["impact_energy"]), rel=1e-6)
    assert point.hydraulic_efficiency == pytest.approx(float(r["hydraulic_efficiency"]), rel=1e-6)


def test_the_stored_spool_map_is_the_15_by_15_grid(spool_rows):
    for key, (low, high) in ((MASS, (0.1, 0.3)), (AREA, (1.4e-4, 2.2e-4))):
        values = np.unique([float(r[key]) for r in spool_rows])
        np.testing.assert_allclose(values, np.linspace(low, high, 15), rtol=1e-12)
    assert len(spool_rows) == 225  # (the spool's)


@pytest.mark.parametrize("i", [0, 112, 224])
def test_a_sample_of_the_spool_maps_points_is_the_operating_point_afresh(spool_rows, i):
    r = spool_rows[i]
    assert r["status"] == "0"
    _is_afresh(SPOOL, r, {MASS: f"{float(r[MASS])!r} kg", AREA: f"{float(r[AREA])!r} m^2"})


@pytest.mark.slow
def test_the_tutorial_runs(tmp_path):
    env = {**os.environ, "MPLBACKEND": "Agg"}
    out = subprocess.run([sys.executable, str(TUTORIAL)], capture_output=True, text=True, env=env,
                         cwd=tmp_path, timeout=1800)
    assert out.returncode == 0, out.stderr[-3000:]
    assert "part cushion (cushion): valve_return -> cushion -> return_line" in out.stdout
    assert "225 points: impact power" in out.stdout and "impact_power *" in out.stdout
