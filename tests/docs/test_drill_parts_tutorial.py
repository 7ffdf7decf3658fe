"""The tutorial "A drill with the parts a real drifter has" (``docs/tutorials_src/plot_4_drill_parts.py``)
and the map it reads (``docs/data/drill_cushion_map.csv``, made by
``benchmarks/make_drill_cushion_map.py`` on a local dask cluster).

- The stored map is the 15 x 15 grid over the cushion's volume and coefficient, and a sample of its
  points (two corners and the middle) is the operating point computed here afresh from the example's
  config with those values (each stored point was continued from its neighbour), to 1e-6.
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


@pytest.fixture(scope="module")
def rows():
    with MAP.open() as fh:
        return list(csv.DictReader(fh))


def test_the_stored_map_is_the_15_by_15_grid(rows):
    v = np.array([float(r[VOLUME]) for r in rows])
    k = np.array([float(r[COEFFICIENT]) for r in rows])
    np.testing.assert_allclose(np.unique(v), np.linspace(5e-6, 40e-6, 15), rtol=1e-12)
    np.testing.assert_allclose(np.unique(k), np.linspace(2.5e-6, 1.5e-5, 15), rtol=1e-12)
    assert len(rows) == 225 and all(r["status"] == "0" for r in rows)


@pytest.mark.parametrize("i", [0, 112, 224])
def test_a_sample_of_the_maps_points_is_the_operating_point_computed_afresh(rows, i):
    r = rows[i]
    config = with_values(read_config(str(DRILL))[0], {VOLUME: f"{float(r[VOLUME])!r} m^3",
                                                      COEFFICIENT: f"{float(r[COEFFICIENT])!r} m^3/s/Pa^0.5"})
    point = build(config).orbit()
    assert point.blow_frequency_Hz == pytest.approx(float(r["blow_frequency"]), rel=1e-6)
    assert point.impact_energy_J == pytest.approx(float(r["impact_energy"]), rel=1e-6)
    assert point.hydraulic_efficiency == pytest.approx(float(r["hydraulic_efficiency"]), rel=1e-6)


@pytest.mark.slow
def test_the_tutorial_runs(tmp_path):
    env = {**os.environ, "MPLBACKEND": "Agg"}
    out = subprocess.run([sys.executable, str(TUTORIAL)], capture_output=True, text=True, env=env,
                         cwd=tmp_path, timeout=1800)
    assert out.returncode == 0, out.stderr[-3000:]
    assert "part cushion (cushion): valve_return -> cushion -> return_line" in out.stdout
    assert "225 points: impact power" in out.stdout and "impact_power *" in out.stdout
