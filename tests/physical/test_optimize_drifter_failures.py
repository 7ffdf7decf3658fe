"""Designs of the whole-drifter optimiser without a one-impact orbit: what their evaluation costs
(about what a design with an orbit costs) and what their record says."""

from __future__ import annotations

import json

import numpy as np
import pytest
from drifter_optimum import EXAMPLE, SEARCHED, collar

from impactbar.orbits import coupled
from impactbar.physical import build, read_config, with_values
from impactbar.physical.optimize_cache import dumps
from impactbar.physical.optimize_drifter import DEFAULT_CONSTRAINTS, _design_record
from impactbar.physical.optimize_failures import failures_table

pytest.importorskip("pint")


def _blows(monkeypatch, changes: dict):
    """The coupled blows an ``orbit()`` of the design solves (each some 20 ms, most of an orbit's
    cost), and its orbit or error."""
    count, solve = [0], coupled.blow_state

    def counted(*args, **kwargs):
        count[0] += 1
        return solve(*args, **kwargs)

    cfg, folder = read_config(EXAMPLE)
    with monkeypatch.context() as m:
        m.setattr(coupled, "blow_state", counted)
        try:
            out = build(with_values(cfg, changes), folder).orbit()
        except ValueError as exc:
            out = exc
    return count[0], out


def test_a_design_without_an_orbit_costs_about_what_one_with_an_orbit_costs(monkeypatch):
    n_ok, orbit = _blows(monkeypatch, collar(1.003))
    n_fail, err = _blows(monkeypatch, collar(1.01))
    assert not isinstance(orbit, Exception) and orbit.stable
    # Newton's steps circled (a step of 1.7e-3 relative, again and again): given up when they stall,
    # where before the chord and then Newton's method took their 50 steps each (907 blows, 15 s)
    assert isinstance(err, ValueError) and "Newton stalled" in str(err)
    assert n_fail <= 3 * n_ok, (n_fail, n_ok)  # 64 against 35 blows


def test_a_design_whose_motion_from_rest_alternates_hands_newton_its_start_at_once(monkeypatch):
    """A design the optimiser's search met (SEARCHED): followed from rest to Newton's start its
    impact velocities alternate; Newton starts there, not after the 400 impacts of a motion that never
    settles into one impact a period, and gives up as before (it stalls); a run of simulate from rest
    alternates the same way."""
    n_ok, _ = _blows(monkeypatch, collar(1.003))
    n_fail, err = _blows(monkeypatch, SEARCHED)
    assert isinstance(err, ValueError) and "Newton stalled" in str(err)
    assert "followed until its impacts settle (into 2 impacts per period by its" in str(err)
    assert n_fail <= 3 * n_ok, (n_fail, n_ok)  # 63 against 35 blows (443 when followed 400 impacts)
    cfg, folder = read_config(EXAMPLE)
    v = build(with_values(cfg, SEARCHED), folder).simulate(2.2, histories=False)["impact_velocities_m_s"]
    # from rest the blows grow with the supply pressure, then (about the 80th) alternate 0.16 % apart,
    # a cycle of two repeating to 3e-5 by the 110th
    assert v.size > 100 and np.all(np.abs(v[-6:] - v[-8:-2]) <= 1e-4 * v[-1])
    assert np.all(np.abs(np.diff(v[-6:])) >= 1.5e-3 * v[-1])


def test_a_failed_design_s_record_says_why_what_it_cost_and_what_the_drill_does_there():
    cfg, folder = read_config(EXAMPLE)
    changes = collar(1.01)
    rec = _design_record(changes, cfg, folder, dict(DEFAULT_CONSTRAINTS, mean_supply_pressure=None))
    assert rec["ok"] is False and rec["feasible"] is False
    assert "no periodic orbit" in rec["error"] and "Newton stalled" in rec["error"]
    assert 0.0 < rec["seconds"] < 60.0 and rec["motion_seconds"] > 0.0
    # what the drill does there: the settle task's classification of its motion from rest, checked
    # against a run of simulate from rest of the same length
    motion = rec["motion"]
    assert motion["period_blows"] == 1 and motion["chatter_per_blow"] == 0.0 and motion["n_blows"] == 40
    assert rec["motion_summary"].startswith("settles into a period-1 motion (1 blow per cycle), no chatter")
    run = build(with_values(cfg, changes), folder).simulate(motion["simulated_time"] * (1 + 1e-9),
                                                            histories=False)
    t, v = run["impact_times_s"], run["impact_velocities_m_s"]
    assert v.size == 40 and np.all(v >= 0.25 * v.max())  # 40 blows, no chatter impact among them
    # each of the last blows within the settle tolerance (1 %) of the one before: one blow per cycle
    # to that tolerance, while the supply still drifts (8.69 to 8.79 m/s over those six; followed to
    # 150 blows the drill settles at 9.07 m/s into three blows per cycle 0.15 % apart)
    assert np.all(np.abs(np.diff(v[-6:])) <= 0.01 * v[-1]) and np.ptp(v[-6:]) > 0.01 * v[-1]
    # (the run ends at its last blow here, at 1 s there: the integrator's steps differ, by some 1e-10)
    assert motion["impact_velocity"] == pytest.approx(v[-1], rel=1e-8)
    assert motion["blow_frequency"] == pytest.approx(1.0 / (t[-1] - t[-2]), rel=1e-8)

    # the JSON result's history keeps why and the classified motion; the table (the CLI's) says both
    kept = json.loads(dumps(rec))
    assert kept["error"] == rec["error"] and kept["motion"]["period_blows"] == 1
    assert kept["motion_summary"] == rec["motion_summary"]
    diameter = 0.04721879723846864 * 1.01
    vary = {"piston.collar_diameter": {"low": 0.047, "high": 0.052, "unit": "m"}}
    history = [{"ok": True, "seconds": 0.3}, dict(rec, values={"piston.collar_diameter": diameter})]
    table = failures_table(history, vary).splitlines()
    assert table[0].startswith("1 of 2 designs without an operating point (")
    assert table[1] == ("  piston.collar_diameter 47.691 mm: find_orbit found no periodic orbit of the drive "
                        f"with one impact per period; {rec['motion_summary']}")
