"""``optimize_drifter(method="differential_evolution")``: a population search whose generations are
evaluated together. Checked without trusting it: a run on a local dask cluster visits the same designs
with the same records, bit for bit, as one in this process; the reported optimum is rebuilt from its
config values and solved by a fresh ``orbit()``, its constraints recomputed; it is no worse than the
best design of the first generation; bad input is one line."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cache_log import cache_log

from impactbar.physical import build, optimize_drifter, read_config, with_values
from impactbar.physical.optimize_population import FAILED, PENALTY, check_population, penalised

pytest.importorskip("pint")

VARY = {"valve.switch_out": ("20 mm", "23 mm"), "accumulator.precharge": ("8 MPa", "12 MPa")}
#: popsize 3 on two variables: 6 members a generation; 18 evaluations: the first and two more
KW = {"objective": "impact_power", "method": "differential_evolution", "popsize": 3, "max_evaluations": 18,
      "progress": False}


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    cache = tmp_path_factory.mktemp("population") / "cache.json"
    return optimize_drifter("circuit-drifter", VARY, cache=cache, **KW), cache


def _record(rec):
    return rec["id"], rec["ok"], rec["objectives"], rec["constraints"], rec["feasible"]


def test_a_local_cluster_gives_the_same_search_bit_for_bit(serial):
    res, _ = serial
    par = optimize_drifter("circuit-drifter", VARY, workers=2, **KW)
    assert par.evaluations == res.evaluations == 18
    # the same designs in the same order, each with the same figures (== on floats: bit for bit)
    assert [_record(r) for r in par.history] == [_record(r) for r in res.history]
    assert par.optimum["values"] == res.optimum["values"]
    assert par.optimum["objectives"] == res.optimum["objectives"]


def test_the_optimum_is_a_fresh_orbits_feasible_and_beats_the_first_generation(serial):
    res, cache = serial
    config = read_config("circuit-drifter")[0]
    d = build(with_values(config, res.optimum["changes"]))
    o = d.orbit()
    for key, figure in (("impact_power_kW", o.impact_power_kW), ("pump_power_kW", o.pump_power_kW),
                        ("blow_frequency_Hz", o.blow_frequency_Hz)):
        assert res.optimum["objectives"][key] == pytest.approx(figure, rel=1e-9)
    # the constraints met, recomputed from the fresh orbit
    assert np.max(np.abs(o.multipliers)) <= 0.95
    assert min(o.minimum_pressures_Pa.values()) >= 0.0
    assert o.mean_supply_pressure_Pa <= d.si["relief_pressure_Pa"]
    h = o.histories(200)
    assert min(h["V_f_m3"].min(), h["V_r_m3"].min()) > 0.0
    for key, (low, high) in {"valve.switch_out": (0.020, 0.023),
                             "accumulator.precharge": (8e6, 12e6)}.items():
        assert low <= res.optimum["values"][key] <= high
    # the first generation: the start and five more; the optimum no worse than its best feasible design
    first = [r for r in res.history[:6] if r.get("feasible")]
    assert res.history[0]["changes"] == {"valve.switch_out": "21.5 mm", "accumulator.precharge": "10 MPa"}
    assert o.impact_power_kW >= max(r["objectives"]["impact_power_kW"] for r in first) * (1 - 1e-9)
    # and it is the best feasible design of all evaluated
    best = max(r["objectives"]["impact_power_kW"] for r in res.history if r.get("feasible"))
    assert o.impact_power_kW == pytest.approx(best, rel=1e-9)
    # a second run reads every design from the cache: the same path, nothing evaluated
    again = optimize_drifter("circuit-drifter", VARY, cache=cache, **KW)
    assert again.evaluations == 0 and again.cached == 18
    assert again.optimum["values"] == res.optimum["values"]
    assert "gain in impact_power" in res.table()
    # a run stopped part-way resumes on the same path, its new designs the same to the bit (each a
    # fresh orbit, none continued from a design read from the cache; the history lists a generation's
    # new designs before those it read)
    # (from a file of the format before the cache's log: one JSON document, read and written as a log)
    tag, designs, _ = cache_log(cache)
    cache.write_text(json.dumps({"problem": tag, "evaluations": designs[:8], "gradients": []}))
    resumed = optimize_drifter("circuit-drifter", VARY, cache=cache, **KW)
    assert resumed.cached == 8 and resumed.evaluations == 10
    assert {r["id"]: _record(r) for r in resumed.history} == {r["id"]: _record(r) for r in res.history}
    assert resumed.optimum["values"] == res.optimum["values"]


def test_the_score_penalises_the_margins_missed():
    rec = {"ok": True, "objectives": {"p": 3.0}, "constraints": {"a": {"scaled": 0.5}, "b": {"scaled": -0.2}}}
    assert penalised(rec, "p", 2.0) == pytest.approx(-1.5 + PENALTY * 0.2, rel=1e-15)
    assert penalised({"ok": False}, "p", 2.0) == FAILED
    assert penalised(dict(rec, objectives={"p": float("nan")}), "p", 2.0) == FAILED
    # the generations after the first that the budget allows: 6 members a generation
    assert check_population(None, 3, 0, 18, 2) == 2 and check_population(4, 3, 7, 23, 2) == 2
    assert check_population(None, 2, 0, 10, 1) == 1  # at least 5 members


@pytest.mark.parametrize(("kw", "match"), [
    ({"workers": 0}, r"workers must be None, an integer >= 1 or a distributed.Client; got 0"),
    ({"workers": "two"}, r"workers must be None, an integer >= 1 .*got 'two'"),
    ({"popsize": 1}, r"popsize must be an integer >= 2 \(members per variable\); got 1"),
    ({"seed": -1}, r"seed must be an integer >= 0; got -1"),
    ({"max_evaluations": 11}, r"max_evaluations must be at least two generations .* \(12 = 2 x 6\).*got 11"),
    ({"method": "cobyla", "workers": 2}, r"workers: only with method='differential_evolution'"),
    ({"method": "nelder-mead"}, r"method must be 'cobyla', 'slsqp', 'differential_evolution' or 'multi"),
])
def test_bad_population_input_is_one_line(kw, match):
    with pytest.raises(ValueError, match=match) as info:
        optimize_drifter("circuit-drifter", VARY, **dict(KW, **kw))
    assert "\n" not in str(info.value)


def test_cli_differential_evolution(tmp_path, capsys):
    from impactbar.cli import main

    out = tmp_path / "result.json"
    assert main(["optimize", "circuit-drifter", "--vary", "valve.switch_out=20mm:23 mm", "--objective",
                 "impact_power", "--method", "differential_evolution", "--popsize", "2",
                 "--max-evaluations", "10", "--quiet", "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["evaluations"] == 10 and doc["optimum"]["continued_vs_fresh"] == 0.0
    assert "gain in impact_power" in capsys.readouterr().out
    assert main(["optimize", "circuit-drifter", "--vary", "valve.switch_out=20mm:23 mm", "--objective",
                 "impact_power", "--method", "differential_evolution", "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert "workers must be None, an integer >= 1" in err and err.count("\n") == 1


@pytest.mark.slow
def test_a_given_client_gives_the_same_search(serial):
    import logging

    from distributed import Client, LocalCluster

    res, _ = serial
    with (LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                       dashboard_address=None, silence_logs=logging.ERROR) as cluster,
          Client(cluster) as client):
        par = optimize_drifter("circuit-drifter", VARY, workers=client, **KW)
        assert client.status == "running"  # left open
    assert [_record(r) for r in par.history] == [_record(r) for r in res.history]


@pytest.mark.parametrize("method", ["cobyla", "differential_evolution"])
def test_a_dropped_constraint_stays_dropped(method):
    budget = 10 if method == "differential_evolution" else 3
    res = optimize_drifter("circuit-drifter", {"valve.switch_out": ("20 mm", "23 mm")},
                           objective="impact_power", constraints={"max_multiplier": None}, method=method,
                           popsize=2, max_evaluations=budget, progress=False)
    assert all("max_multiplier" not in r["constraints"] for r in [*res.history, res.optimum, res.baseline])
    assert "minimum_pressure" in res.optimum["constraints"]
