"""Designs of the whole-drifter optimiser without a one-impact orbit from ``orbit()``'s default chain
(its one start, rest on the stop): what their evaluation costs (about what a design with an orbit
costs) and what their record says, what the drill does there from rest and whether an orbit exists
all the same (from rest at the switch point). The designs are those the documented search met with
the blows ended at the law's fixed window, and are built so (``drifter_optimum.window_end``)."""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest
from cache_log import cache_log
from drifter_optimum import BUZZING, EXAMPLE, SEARCHED, collar, window_end

import impactbar
from impactbar.orbits import coupled
from impactbar.physical import CircuitDrifter, build, read_config, settle, with_values
from impactbar.physical.optimize_cache import dumps
from impactbar.physical.optimize_drifter import DEFAULT_CONSTRAINTS, _design_record
from impactbar.physical.optimize_failures import (
    MOTION_BLOWS,
    MOTION_MOST_BLOWS,
    NOT_CLASSIFIED,
    classify_failed,
    failures_table,
)

pytest.importorskip("pint")


@pytest.fixture(autouse=True)
def _window_end(monkeypatch):
    """The designs' blows ended at the law's window, where they were found."""
    window_end(monkeypatch)


def _page() -> str:
    """docs/optimising_a_drifter.md, its whitespace runs one space (the figures it quotes here)."""
    return re.sub(r"\s+", " ", (EXAMPLE.parents[1] / "docs" / "optimising_a_drifter.md").read_text())


def _blows(monkeypatch, changes: dict, **options):
    """The coupled blows an ``orbit(**options)`` of the design solves (each some 20 ms, most of an
    orbit's cost), and its orbit or error."""
    count, solve = [0], coupled.blow_state

    def counted(*args, **kwargs):
        count[0] += 1
        return solve(*args, **kwargs)

    cfg, folder = read_config(EXAMPLE)
    with monkeypatch.context() as m:
        m.setattr(coupled, "blow_state", counted)
        try:
            out = build(with_values(cfg, changes), folder).orbit(**options)
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
    quoted = re.search(r"solves ([0-9]+) coupled blows against ([0-9]+) for its neighbour", _page())
    assert quoted is not None and (int(quoted[1]), int(quoted[2])) == (n_fail, n_ok)
    quoted = re.search(r"Newton's steps circle at ([0-9.]+e-[0-9]+) \(relative\)", _page())
    stalled = re.search(r"smallest before it, ([0-9.]+e-[0-9]+) relative", str(err))
    assert quoted is not None and float(quoted[1]) == pytest.approx(float(stalled[1]), rel=0.05)


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


def _counted_settles(monkeypatch) -> list:
    """``settle_point``'s calls from now on (its arguments), the function itself still run."""
    calls, point = [], settle.settle_point

    def counted(*args, **kwargs):
        calls.append((args, kwargs))
        return point(*args, **kwargs)

    monkeypatch.setattr(settle, "settle_point", counted)
    return calls


def test_a_failed_design_s_record_says_why_what_it_cost_and_what_the_drill_does_there(monkeypatch):
    cfg, folder = read_config(EXAMPLE)
    changes = collar(1.01)
    calls = _counted_settles(monkeypatch)
    rec = _design_record(changes, cfg, folder, dict(DEFAULT_CONSTRAINTS, mean_supply_pressure=None))
    assert rec["ok"] is False and rec["feasible"] is False
    assert "no periodic orbit" in rec["error"] and "Newton stalled" in rec["error"]
    # the search's evaluation runs no motion from rest (160 blows, several evaluations' cost): its
    # record says so, and the motion is classified where the result reports the design
    assert not calls and "motion" not in rec and rec["motion_summary"] == NOT_CLASSIFIED
    assert classify_failed(rec, build(with_values(cfg, changes), folder)) is rec and len(calls) == 1
    assert 0.0 < rec["seconds"] < 60.0 and rec["motion_seconds"] > 0.0
    # the same figures, to the bit, as the settle task's on a design built afresh
    direct = settle.settle_point(build(with_values(cfg, changes), folder), MOTION_BLOWS,
                                 most_blows=MOTION_MOST_BLOWS)
    assert json.dumps(direct, sort_keys=True) == json.dumps(rec["motion"], sort_keys=True)
    # what the drill does there: the settle task's classification of its motion from rest, run until
    # it can tell (40 blows still rise with the supply pressure; 160 are classified), checked against
    # a run of simulate from rest of the same length
    motion = rec["motion"]
    assert motion["period_blows"] == 3 and motion["chatter_per_blow"] == 0.0 and motion["n_blows"] == 160
    assert rec["motion_summary"].startswith("settles into a period-3 motion (3 blows per cycle, 0.07")
    quoted = re.search(r'over 160 blows it "(settles into a period-3 motion[^"]*)"', _page())
    assert quoted is not None and quoted[1] == rec["motion_summary"]
    run = build(with_values(cfg, changes), folder).simulate(motion["simulated_time"] * (1 + 1e-9),
                                                            histories=False)
    t, v = run["impact_times_s"], run["impact_velocities_m_s"]
    assert v.size == 160 and np.all(v >= 0.25 * v.max())  # 160 blows, no chatter impact among them
    # the last blows repeat every third to 1e-5 and differ within the cycle 100 times more (9.064,
    # 9.077, 9.078 m/s); every blow and the one before differ by less than the settle tolerance (1 %)
    again, within = np.abs(v[-3:] - v[-6:-3]), np.abs(np.diff(v[-4:]))
    assert np.all(again <= 1e-5 * v[-1]) and within.max() >= 1e-3 * v[-1] and within.max() <= 0.01 * v[-1]
    # (the run ends at its last blow here, at the classification's end there: steps differ, by 1e-10)
    assert motion["impact_velocity"] == pytest.approx(np.mean(v[-3:]), rel=1e-8)
    assert motion["impact_velocity_spread"] == pytest.approx(np.std(v[-3:]), rel=1e-5)
    assert motion["blow_frequency"] == pytest.approx(3.0 / (t[-1] - t[-4]), rel=1e-8)

    # the JSON result's history keeps why and the classified motion; the table (the CLI's) says both
    kept = json.loads(dumps(rec))
    assert kept["error"] == rec["error"] and kept["motion"]["period_blows"] == 3
    assert kept["motion_summary"] == rec["motion_summary"]
    diameter = 0.04721879723846864 * 1.01
    vary = {"piston.collar_diameter": {"low": 0.047, "high": 0.052, "unit": "m"}}
    history = [{"ok": True, "seconds": 0.3}, dict(rec, values={"piston.collar_diameter": diameter})]
    table = failures_table(history, vary).splitlines()
    assert table[0].startswith("1 of 2 designs without an operating point (")
    # nor from rest at the switch point (Newton stalls there too, in some 30 blows)
    assert rec["switch_summary"].startswith("from rest at the switch point: no one-impact orbit either "
                                            "(find_orbit: Newton stalled")
    assert table[1] == ("  piston.collar_diameter 47.691 mm: find_orbit found no periodic orbit of the drive "
                        f"with one impact per period; {rec['motion_summary']}; {rec['switch_summary']}")


def test_the_searched_design_s_record_says_the_two_blow_cycle_that_simulate_from_rest_shows():
    """The design the documented search met without a one-impact orbit (SEARCHED): from rest its blows
    rise with the supply pressure for some 80 blows, each within 1 % of the one before (what 40 blows
    called a period-1 motion), then alternate 0.16 % apart. The record's period and the spread of its
    cycle against a longer run of simulate from rest (4 s, some 200 blows)."""
    cfg, folder = read_config(EXAMPLE)
    rec = _design_record(SEARCHED, cfg, folder, dict(DEFAULT_CONSTRAINTS, mean_supply_pressure=None))
    motion = classify_failed(rec, build(with_values(cfg, SEARCHED), folder))["motion"]
    assert "no periodic orbit" in rec["error"] and motion["period_blows"] == 2
    # (nor from rest at the switch point: Newton stalls there too)
    assert rec["switch_summary"].startswith("from rest at the switch point: no one-impact orbit either "
                                            "(find_orbit: Newton stalled")
    assert motion["chatter_per_blow"] == 0.0 and motion["n_blows"] == 160
    assert rec["motion_summary"].startswith("settles into a period-2 motion (2 blows per cycle, 0.081 % "
                                            "spread), no chatter")
    run = build(with_values(cfg, SEARCHED), folder).simulate(4.0, histories=False)
    v = run["impact_velocities_m_s"]
    assert v.size > 200 and np.all(v >= 0.25 * v.max())
    # the long run's last blows: a cycle of two repeating to 1e-6, its two blows 0.16 % apart
    assert np.all(np.abs(v[-2:] - v[-4:-2]) <= 1e-6 * v[-1])
    assert abs(v[-1] - v[-2]) == pytest.approx(1.6e-3 * v[-1], rel=0.02)
    # the record's cycle (its last two of 160 blows) is that cycle, still settling by 5e-6
    assert motion["impact_velocity"] == pytest.approx(np.mean(v[-2:]), rel=2e-5)
    assert motion["impact_velocity_spread"] == pytest.approx(np.std(v[-2:]), rel=1e-3)


def test_a_design_whose_piston_buzzes_on_the_shank_is_classified_in_a_bounded_number_of_impacts(monkeypatch):
    """A design the restarts' benchmark met (BUZZING: a front annulus of 0.39 mm^2): no one-impact orbit
    from the default chain's start, rest on the stop; from rest two blows, then the piston buzzes on
    the shank, every impact a coupled contact with the rock. Its classification runs once, to its
    impacts' bound (4 a blow wanted: 160), and says it stalls, where it ran from rest 1 s, then 16 s
    (some 11,000 impacts), then more: over 16 minutes. Checked against a run of simulate from rest of
    the same length, without the bound. The drill has a one-impact orbit all the same, stable, that
    rest does not reach: the record says so (from rest at the switch point), checked against a run of
    simulate from there."""
    cfg, folder = read_config(EXAMPLE)
    rec = _design_record(BUZZING, cfg, folder, dict(DEFAULT_CONSTRAINTS, mean_supply_pressure=None))
    assert rec["ok"] is False and "no periodic orbit" in rec["error"]
    assert "front chamber empties" in rec["error"]
    runs, simulate, bound = [], CircuitDrifter.simulate, 4 * MOTION_BLOWS

    def counted(self, duration_s, **kwargs):
        # (refused once the bound is spent: without it the classification does not return)
        assert sum(n for _, n in runs) < bound, runs
        out = simulate(self, duration_s, **kwargs)
        runs.append((duration_s, out["impact_times_s"].size))
        return out

    with monkeypatch.context() as m:
        m.setattr(CircuitDrifter, "simulate", counted)
        motion = classify_failed(rec, build(with_values(cfg, BUZZING), folder))["motion"]
    assert settle.SETTLE_IMPACTS_PER_BLOW * MOTION_BLOWS == bound
    assert runs == [(MOTION_BLOWS / settle.SETTLE_FIRST_HZ, bound)]
    assert (motion["n_blows"], motion["n_impacts"], motion["period_blows"]) == (2, 160, 0)
    assert rec["motion_summary"] == ("stalls: 2 blows from rest, then 158 chatter impacts to "
                                     f"{motion['simulated_time']:.3g} s, under two blows in its second half")
    assert f'"{rec["motion_summary"]}"' in _page()  # (quoted there)
    # what the drill does there, by simulate from rest to the classification's end (no bound): as many
    # 160 impacts, two blows, then a buzz: impacts under 1 % of the first blow's velocity, at a steady
    # interval (to 1 %, under 2 ms: above 500 a second)
    # (to half a millisecond past it, a third of the buzz's interval)
    run = build(with_values(cfg, BUZZING), folder).simulate(motion["simulated_time"] + 5e-4, histories=False)
    t, v = run["impact_times_s"], run["impact_velocities_m_s"]
    assert t.size == 160 and t[-1] == pytest.approx(motion["simulated_time"], rel=1e-8)
    assert np.all(v[:2] >= 0.25 * v[0]) and np.all(v[2:] < 0.25 * v[0])
    late, gaps = v[-100:], np.diff(t[-101:])
    assert np.all(late < 0.01 * v[0]) and np.ptp(gaps) <= 0.01 * gaps.mean() and gaps.mean() < 2e-3
    # and what exists: a one-impact orbit the buzz never reaches, found from rest at the switch point
    # (checked there by a restart), stable, the relief valve opening during its period
    found = rec["switch_orbit"]
    assert found["stable"] and found["max_multiplier"] == pytest.approx(0.575, abs=1e-3)
    assert found["relief_opens"] and found["relief_margin_Pa"] < -0.5e6 and not found["cavitates"]
    assert rec["switch_summary"] == ("from rest at the switch point: a stable one-impact orbit (|mu| 0.575), "
                                     "50.3 Hz, 8.92 m/s, relief open")
    assert rec["switch_summary"] in _page()  # (quoted there)
    # simulate from rest at the switch point, the supply at the relief's setting (no Newton): its blows
    # go to the orbit's (to 1e-8 by the 30th, 40 blows), each blow's distance from the orbit 0.575 of
    # the one before (the largest multiplier: no other left, from the 8th to the 14th)
    drifter = build(with_values(cfg, BUZZING), folder)
    drive = drifter.drive()
    p_rel, tank = drive.supply.relief_pressure, drive.supply.tank_pressure
    charged = dataclasses.replace(drive, start_pressures=(p_rel, tank, p_rel, 1.0))
    start = impactbar.InitialState.rigid(-drive.valve.switch_out, 0.0, drifter.n_modes)
    run = impactbar.simulate(drifter.model(), charged, start, 0.8 * drifter.omega_rad_s, histories=False)
    t, v = np.asarray(run.impact_times) / drifter.omega_rad_s, np.asarray(run.impact_velocities)
    v = v * drifter.bar.length_m * drifter.omega_rad_s
    assert t.size == 40 and np.all(v > 0.25 * v.max())  # blows, no buzz
    assert np.allclose(np.diff(t[30:]), found["period_s"], rtol=1e-8, atol=0.0)
    assert np.allclose(v[30:], found["impact_velocity_m_s"], rtol=1e-8, atol=0.0)
    off = v[7:15] - found["impact_velocity_m_s"]
    assert np.allclose(off[1:] / off[:-1], found["max_multiplier"], rtol=1e-2, atol=0.0)


def test_orbit_finds_from_the_switch_point_what_its_default_chain_misses(monkeypatch):
    """``orbit(switch_start=True)``: where the default chain (rest on the stop) finds no orbit, the
    start from rest at the switch point; on BUZZING the classification's orbit, in some 30 coupled
    blows (an orbit's cost: 35 on ``collar(1.003)``); where it finds none either (``collar(1.01)``,
    Newton stalls from both) the error says both. The option is off by default: the default chain's
    error, unchanged."""
    n_plain, err = _blows(monkeypatch, BUZZING)
    assert isinstance(err, ValueError) and "no periodic orbit" in str(err) and "switch point" not in str(err)
    n_both, point = _blows(monkeypatch, BUZZING, switch_start=True)
    assert 20 <= n_both - n_plain <= 40, (n_both, n_plain)
    assert point.stable and abs(np.abs(point.orbit.multipliers).max() - 0.575) < 1e-3
    assert point.border_margins_Pa["relief"] < 0.0  # the relief valve opens during the period
    cfg, folder = read_config(EXAMPLE)
    with pytest.raises(ValueError, match=r"no periodic orbit.*; from rest at the valve's switch point: "
                                         r"find_orbit: Newton stalled"):
        build(with_values(cfg, collar(1.01)), folder).orbit(switch_start=True)


_NO_ORBIT = "find_orbit found no periodic orbit of the drive with one impact per period; tried"
#: what the settle task's stand-in says (the classification's own figures: the tests above)
_MOTION = {"period_blows": 2, "chatter_per_blow": 0.0, "blow_frequency": 50.0, "impact_velocity": 9.0,
           "impact_velocity_spread": 0.009, "n_blows": 160}


def test_only_the_designs_a_result_lists_are_classified_the_others_say_they_are_not(monkeypatch):
    """Eight designs without an operating point (the third's oil cavitates: no motion to classify):
    the table lists five, and only the four of those without an orbit are classified, each once."""
    from impactbar.physical.optimize_failures import classify_listed, failed_record

    got = []
    monkeypatch.setattr(settle, "settle_point", lambda d, blows, **kw: got.append((d, blows, kw)) or _MOTION)
    history = [{"ok": True, "seconds": 0.3}]
    for i in range(8):
        err = ValueError("the oil cavitates" if i == 2 else _NO_ORBIT)
        rec = failed_record(err, 1.0, f"drifter {i}", classify=False)
        history.append(dict(rec, values={"x": 0.020 + i * 1e-4}, n=i))
    assert not got and "motion_summary" not in history[3]
    assert classify_listed(history, lambda r: f"drifter {r['n']}") == 4
    assert got == [(f"drifter {i}", MOTION_BLOWS, {"most_blows": MOTION_MOST_BLOWS}) for i in (0, 1, 3, 4)]
    assert all(r["motion"] is _MOTION for r in history[1:6] if r["n"] != 2)
    assert all(r["motion_summary"] == NOT_CLASSIFIED and "motion" not in r for r in history[6:])
    assert classify_listed(history, lambda r: f"drifter {r['n']}") == 0 and len(got) == 4  # (done once)
    table = failures_table(history, {"x": {"low": 0.02, "high": 0.023, "unit": "m"}}).splitlines()
    assert table[1] == ("  x 20 mm: find_orbit found no periodic orbit of the drive with one impact per "
                        "period; settles into a period-2 motion (2 blows per cycle, 0.1 % spread), no "
                        "chatter, 50 Hz, 9 m/s")
    assert table[3] == "  x 20.2 mm: the oil cavitates"
    assert table[-1] == "  and 3 more (the JSON result's history)"
    with pytest.raises(ValueError, match="record must be a design's without a one-impact orbit"):
        classify_failed(history[3], "drifter 2")
    with pytest.raises(ValueError, match="record must be a design's without a one-impact orbit"):
        classify_failed(history[0], "a drifter")


def test_the_search_classifies_no_motion_and_after_it_those_its_result_lists(monkeypatch, tmp_path):
    """A search in which every design with its switch point past the start's (21.5 mm) has no orbit:
    no motion from rest is run while it evaluates; after it, each design its table lists is
    classified once, that design's own (its switch point), and the cache file keeps it."""
    import importlib

    from impactbar.physical import optimize_drifter

    module = importlib.import_module("impactbar.physical.optimize_drifter")
    evaluate, calls, got = module.evaluate_design, [0], []

    def failing(drifter, *args, **kwargs):
        calls[0] += 1
        if drifter.si["switch_out_m"] > 0.0215 + 1e-9:
            raise ValueError(_NO_ORBIT)
        return evaluate(drifter, *args, **kwargs)

    monkeypatch.setattr(module, "evaluate_design", failing)
    monkeypatch.setattr(settle, "settle_point", lambda d, blows, **kw: got.append(
        (calls[0], d.si["switch_out_m"])) or _MOTION)
    cache = tmp_path / "cache.json"
    res = optimize_drifter("circuit-drifter", {"valve.switch_out": ("19 mm", "24 mm")},
                           objective="impact_power", max_evaluations=8, cache=cache, progress=False)
    failed = [r for r in res.history if not r["ok"]]
    assert len(failed) >= 2 and all(r["error"] == _NO_ORBIT for r in failed)
    # every classification after the search's last evaluation (its designs evaluated, the start among them)
    assert [n for n, _ in got] == [res.evaluations] * min(len(failed), 5)
    assert [x for _, x in got] == [r["values"]["valve.switch_out"] for r in failed[:5]]
    assert all(r["motion"] == _MOTION for r in failed[:5])
    assert all(r["motion_summary"] == NOT_CLASSIFIED for r in failed[5:])
    kept = {r["id"]: r for r in cache_log(cache)[1]}
    assert all(kept[r["id"]]["motion"] == _MOTION for r in failed[:5])
    assert "settles into a period-2 motion" in res.table()
