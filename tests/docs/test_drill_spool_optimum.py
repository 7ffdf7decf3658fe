"""The optimiser's run on the spool drill (``docs/data/drill_spool_optimum.json``, made by
``benchmarks/make_drill_spool_optimum.py`` on a local dask cluster over the spool's mass and control end
and the cushion's volume and coefficient), which the tutorial "A drill with the parts a real drifter
has" reads: at most 30 designs, its baseline the example's own operating point, and its optimum the
best feasible design of its history and a fresh orbit of the config with the stored changes (to 1e-6).
"""

import importlib.util
import json
from pathlib import Path

import pytest

from impactbar.physical import build, read_config, with_values

ROOT = Path(__file__).resolve().parents[2]
STORED = ROOT / "docs" / "data" / "drill_spool_optimum.json"
SPOOL = ROOT / "examples" / "circuit_drill_spool.toml"
_spec = importlib.util.spec_from_file_location("make_drill_spool_optimum",
                                               ROOT / "benchmarks" / "make_drill_spool_optimum.py")
MAKER = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(MAKER)
SEARCH, VARY, CONSTRAINTS = MAKER.SEARCH, MAKER.VARY, MAKER.CONSTRAINTS


@pytest.fixture(scope="module")
def stored():
    return json.loads(STORED.read_text())


def test_the_stored_run_is_the_scripts_search(stored):
    assert stored["objective"] == SEARCH["objective"] and set(stored["vary"]) == set(VARY)
    assert {k.split(".")[1] for k in VARY} == {"main_spool", "cushion"}
    assert stored["evaluations"] <= SEARCH["max_evaluations"] <= 30
    feasible = [r for r in stored["history"] if r.get("ok") and r.get("feasible")]
    best = max(r["objectives"]["impact_power_kW"] for r in feasible)
    assert stored["optimum"]["objectives"]["impact_power_kW"] == pytest.approx(best, rel=1e-6)
    assert stored["gain"] > 0.0


@pytest.mark.parametrize("which", ["baseline", "optimum"])
def test_a_fresh_orbit_of_the_stored_design_gives_its_objective(stored, which):
    record = stored[which]
    point = build(with_values(read_config(str(SPOOL))[0], record["changes"])).orbit()
    assert point.impact_power_kW == pytest.approx(record["objectives"]["impact_power_kW"], rel=1e-6)
    assert point.mean_supply_pressure_Pa <= 26e6 and CONSTRAINTS == {"mean_supply_pressure": "26 MPa"}
