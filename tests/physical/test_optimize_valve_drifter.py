"""``optimize_drifter`` on what a design map sweeps besides the drifter with its oil circuit: a valve
drifter (its operating point the map's, its objectives and constraints its outputs'), and the keys that
take integers (each integer value a search over the other keys), each checked against the operating
points evaluated one by one."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from impactbar.physical import build, optimize_drifter, read_config, with_values

pytest.importorskip("pint")

ROOT = Path(__file__).resolve().parents[2]
ROCK = ROOT / "examples" / "stepped_drifter_rock.toml"
STEPPED = ROOT / "examples" / "stepped_drifter.toml"


def _orbit(path, changes: dict):
    """The operating point of the example with ``changes``, by the valve drifter's own default chain."""
    cfg, folder = read_config(path)
    return build(with_values(cfg, changes), folder).orbit()


def test_a_short_search_on_a_valve_drifter():
    """A few designs over the switch position for the drilling rate: the optimum lies within the
    bounds, is its config's fresh operating point, meets the multipliers' limit and drills no slower
    than the start (whose figures are the config's own orbit's)."""
    res = optimize_drifter(ROCK, {"valve.switch_out": ("18 mm", "26 mm")}, objective="drilling_rate",
                           max_evaluations=6, progress=False)
    x = res.optimum["values"]["valve.switch_out"]
    assert 0.018 <= x <= 0.026 * (1 + 1e-15) and 2 <= res.evaluations <= 6  # (a bound: low + span, to an ulp)
    start, best = _orbit(ROCK, {}), _orbit(ROCK, res.optimum["changes"])
    assert res.baseline["objectives"]["drilling_rate_m_min"] == start.rock()["drilling_rate_m_min"]
    assert res.optimum["objectives"]["drilling_rate_m_min"] == best.rock()["drilling_rate_m_min"]
    assert res.optimum["objectives"]["work_on_rock_J"] == best.rock()["work_on_rock_J"]
    assert res.optimum["objectives"]["impact_power_kW"] == pytest.approx(
        best.impact_energy_J * best.blow_frequency_Hz / 1e3, rel=1e-12)
    assert np.max(np.abs(best.multipliers)) <= 0.95 and res.optimum["feasible"]
    assert best.rock()["drilling_rate_m_min"] >= start.rock()["drilling_rate_m_min"]
    assert res.objective_key == "drilling_rate_m_min" and res.gain >= 0.0
    assert "valve.switch_out" in res.table() and "drilling_rate *" in res.table()
    # the records of the designs tried are the map's operating points too
    rec = next(r for r in res.history if r.get("ok") and r["values"]["valve.switch_out"] != 0.0215)
    o = _orbit(ROCK, rec["changes"])
    assert rec["objectives"]["blow_frequency_Hz"] == pytest.approx(o.blow_frequency_Hz, rel=1e-8)


def test_the_population_on_a_valve_drifter_reports_a_fresh_operating_point():
    """Differential evolution (two generations of five) over the switch position for the work per
    blow: its best design is its config's fresh orbit, feasible, at least the start's."""
    res = optimize_drifter(ROCK, {"valve.switch_out": ("18 mm", "26 mm")}, objective="work_on_rock_per_blow",
                           method="differential_evolution", popsize=2, max_evaluations=10, progress=False)
    best = _orbit(ROCK, res.optimum["changes"])
    assert res.optimum["objectives"]["work_on_rock_J"] == best.rock()["work_on_rock_J"]
    assert res.optimum["feasible"] and np.max(np.abs(best.multipliers)) <= 0.95
    assert best.rock()["work_on_rock_J"] >= _orbit(ROCK, {}).rock()["work_on_rock_J"]
    assert 2 <= res.evaluations <= 10


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"objective": "drilling_rate_per_kW"},
     "objective 'drilling_rate_per_kW' is not a valve drifter's .*; one of impact_power, "
     "work_on_rock_per_blow, drilling_rate$"),
    ({"objective": "impact_power", "constraints": {"minimum_pressure": "0 MPa"}},
     "unknown constraint 'minimum_pressure' of a valve drifter .*; one of peak_rod_stress, max_multiplier, "
     "min_drilling_rate, piston_mass,"),
    ({"objective": "impact_power", "method": "slsqp"}, "method 'slsqp': SLSQP's gradients"),
    ({"objective": "impact_power", "method": "multistart"}, "method 'multistart' with polish"),
])
def test_what_a_valve_drifter_does_not_have_is_refused_in_one_line(kwargs, match):
    with pytest.raises(ValueError, match=match) as info:
        optimize_drifter(ROCK, {"valve.switch_out": ("18 mm", "26 mm")}, max_evaluations=4, progress=False,
                         **kwargs)
    assert "\n" not in str(info.value)


def test_an_integer_key_alone_is_each_of_its_values_evaluated():
    """The modes of the stepped piston from 6 to 8: each value's operating point, the best the one of
    most impact power, as each orbit solved on its own says."""
    res = optimize_drifter(STEPPED, {"model.n_modes": (6, 8)}, objective="impact_power",
                           constraints={"max_multiplier": None}, progress=False)
    power = {n: _orbit(STEPPED, {"model.n_modes": n}).impact_power_kW for n in (6, 7, 8)}
    assert sorted(r["values"]["model.n_modes"] for r in res.history) == [6.0, 7.0, 8.0]
    assert {r["changes"]["model.n_modes"]: r["objectives"]["impact_power_kW"] for r in res.history} == \
        power
    best = max(power, key=power.get)
    assert res.optimum["changes"] == {"model.n_modes": best}
    assert res.optimum["objectives"]["impact_power_kW"] == power[best]
    assert res.baseline["changes"] == {"model.n_modes": 8} and res.evaluations == 3
    assert with_values(read_config(STEPPED)[0], {"model.n_modes": best}) == res.config
    page = (ROOT / "docs" / "optimising_a_drifter.md").read_text()
    quoted = re.search(r"the modes 6, 7 and 8 give ([\d.]+), ([\d.]+) and ([\d.]+) kW",
                       " ".join(page.split()))
    assert quoted is not None, "the optimiser's page no longer quotes the modes' impact powers"
    assert [float(x) for x in quoted.groups()] == [round(power[n], 4) for n in (6, 7, 8)]


def test_an_integer_key_with_a_real_one_is_the_best_of_a_search_at_each_integer():
    """The modes (7 or 8) with the switch position: the reported design is the better of the two
    searches over the switch, each run on its own at its number of modes."""
    vary = {"model.n_modes": (7, 8), "valve.switch_out": ("20 mm", "23 mm")}
    kwargs = {"objective": "impact_power", "constraints": {"max_multiplier": None}, "max_evaluations": 4,
              "progress": False}
    res = optimize_drifter(STEPPED, vary, **kwargs)
    cfg = read_config(STEPPED)[0]
    each = {n: optimize_drifter(with_values(cfg, {"model.n_modes": n}), {"valve.switch_out": vary[
        "valve.switch_out"]}, start="any", **kwargs) for n in (7, 8)}
    best = max(each, key=lambda n: each[n].optimum["objectives"]["impact_power_kW"])
    assert res.optimum["changes"] == {"model.n_modes": best, **each[best].optimum["changes"]}
    assert res.optimum["objectives"] == each[best].optimum["objectives"]
    assert res.evaluations == sum(r.evaluations for r in each.values())
    assert res.baseline["changes"]["model.n_modes"] == 8
    assert f"the best at model.n_modes = {best}" in res.message
    assert list(res.vary) == ["model.n_modes", "valve.switch_out"] and "model.n_modes" in res.table()


@pytest.mark.parametrize(("bounds", "match"), [
    ((6.5, 8), r"vary\['model.n_modes'\] takes integers"),
    ((0, 20), "take 21 values together within their bounds; at most 12"),
])
def test_integer_bounds_are_refused_in_one_line(bounds, match):
    with pytest.raises(ValueError, match=match) as info:
        optimize_drifter(STEPPED, {"model.n_modes": bounds}, objective="impact_power", progress=False)
    assert "\n" not in str(info.value)
