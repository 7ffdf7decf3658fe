"""A handful of cases of each fuzz category of a designer's path (``benchmarks/fuzz_campaign.py``:
stores damaged and resumed, integer axes, grid sizes, sets of changes, the optimiser's arguments),
run as the campaign runs them (each in a forked child with a time limit), so that the suite sees
every category work and none finds a bad case. The campaign itself runs thousands
(``python benchmarks/fuzz_campaign.py --only map_stores map_axes grid_size change_sets optimizer_args``)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("zarr")
pytest.importorskip("pint")

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
CASES = {"map_stores": 2, "map_axes": 6, "grid_size": 6, "change_sets": 12, "optimizer_args": 4}


#: one category's cases in a fresh process: the campaign forks a child a case, which must not inherit
#: the threads (zarr's event loop, dask's) that earlier tests start in the test process
_RUN = """
import json, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
import fuzz_campaign as campaign
category, n = sys.argv[2], int(sys.argv[3])
fn, _ = campaign.CATEGORIES[category]
rng = np.random.default_rng([0, list(campaign.CATEGORIES).index(category)])
print(json.dumps(dict(fn(rng, n, 120.0))))
"""


@pytest.mark.parametrize("category", CASES)
def test_a_few_cases_of_each_category_find_nothing_bad(category):
    done = subprocess.run([sys.executable, "-c", _RUN, str(BENCH), category, str(CASES[category])],
                          capture_output=True, text=True, timeout=540)
    assert done.returncode == 0, done.stderr[-3000:]
    counts = json.loads(done.stdout.strip().splitlines()[-1])
    assert sum(counts.values()) >= CASES[category]
    bad = {k: v for k, v in counts.items() if k.startswith("BAD")}
    assert not bad, bad


def _circuit():
    from impactbar.physical import circuit_preset

    d = circuit_preset("circuit-drifter")
    return d.model(), d.drive()


@pytest.mark.parametrize("changes, says", [
    ({"valve_coefficient": float("inf")},
     "valve_coefficient must be a finite real number in (0, inf); got inf"),
    ({"valve_coefficient": float("inf"), "relief_pressure": 2.0},
     "valve_coefficient must be a finite real number in (0, inf); got inf"),
    ({"tank_pressure": 2.0**63}, "relief_pressure must be above tank_pressure (9.22337e+18); got 2.5"),
    ({"supply_pressure": 2.0}, "(a supply held at a pressure; the drive's supply_pressure)"),
    ({"precharge": 3.0}, "a lower precharge or a higher relief_pressure"),
])
def test_what_the_change_sets_found_names_the_changed_parameter(changes, says):
    """The valve's coefficient at ``inf`` was refused as the part's ``coefficient``; a tank pressure
    raised past the relief's named only ``relief_pressure``; a held supply pressure on a pump's
    supply named ``pressure``."""
    from impactbar.parameters import with_parameters

    model, drive = _circuit()
    with pytest.raises(ValueError) as info:
        with_parameters(model, drive, changes)
    assert says in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("kwargs, says", [
    ({"objective": [1.0]}, "objective must be one of"),
    ({"constraints": 1e-300}, "constraints must be a dict of limits or None; got 1e-300"),
    ({"vary": {"supply.pump_flow": ("68.8 L/min", 10**400)}}, "must be a number within the floats' range"),
])
def test_what_the_optimizer_arguments_found_is_one_line(kwargs, says, monkeypatch):
    """A list as the objective and a float as the constraints raised ``TypeError``; an integer bound
    past the floats' range an ``OverflowError``."""
    from impactbar import physical

    def never(*args, **kw):
        raise AssertionError("solved before the arguments were checked")

    monkeypatch.setattr(physical.CircuitDrifter, "orbit", never)
    args = {"vary": {"supply.pump_flow": ("60 L/min", "90 L/min")}, "objective": "impact_power", **kwargs}
    with pytest.raises(ValueError) as info:
        physical.optimize_drifter("circuit-drifter", progress=False, **args)
    assert says in str(info.value) and "\n" not in str(info.value)
