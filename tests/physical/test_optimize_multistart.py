"""``optimize_drifter(method="multistart")``: a Sobol sample of the bounds evaluated together, then
COBYLA from its best feasible designs. Checked without trusting it: the sample is scipy's scrambled
Sobol sample drawn here again; the reported optimum is rebuilt from its config values and solved by a
fresh ``orbit()``, its constraints recomputed; it is no worse than the sample's best feasible design;
the seed makes the run reproducible, bit for bit; bad input is one line."""

from __future__ import annotations

import contextlib
import json
import sys

import numpy as np
import pytest
from scipy.stats import qmc

from impactbar.physical import build, optimize_drifter, read_config, with_values
from impactbar.physical.optimize_multistart import check_multistart

pytest.importorskip("pint")

VARY = {"valve.switch_out": ("20 mm", "23 mm"), "accumulator.precharge": ("8 MPa", "12 MPa")}
LOW, HIGH = np.array([0.020, 8e6]), np.array([0.023, 12e6])
#: 8 sample designs, one local search of (16 - 8) designs
KW = {"objective": "impact_power", "method": "multistart", "sample": 8, "local_starts": 1,
      "max_evaluations": 16, "progress": False, "seed": 3}


@pytest.fixture(scope="module")
def run():
    return optimize_drifter("circuit-drifter", VARY, **KW)


def _record(rec):
    return rec["id"], rec["ok"], rec["objectives"], rec["constraints"], rec["feasible"]


def test_the_sample_is_a_scrambled_sobol_sample_of_the_bounds(run):
    # the start first, then the sample's designs in its order, each at a point of scipy's sample
    u = qmc.Sobol(d=2, scramble=True, seed=3).random(8)
    sample = np.array([[r["values"][k] for k in VARY] for r in run.history[1:9]])
    np.testing.assert_allclose(sample, LOW + (HIGH - LOW) * u, rtol=1e-12)
    assert run.history[0]["changes"] == {"valve.switch_out": "21.5 mm", "accumulator.precharge": "10 MPa"}
    assert run.evaluations <= 1 + 16 + 12  # (the polish's 12 designs at most besides)


def test_the_optimum_is_a_fresh_orbits_feasible_and_beats_the_sample(run):
    config = read_config("circuit-drifter")[0]
    d = build(with_values(config, run.optimum["changes"]))
    o = d.orbit()
    assert run.optimum["objectives"]["impact_power_kW"] == pytest.approx(o.impact_power_kW, rel=1e-9)
    assert np.max(np.abs(o.multipliers)) <= 0.95
    assert min(o.minimum_pressures_Pa.values()) >= 0.0
    assert o.mean_supply_pressure_Pa <= d.si["relief_pressure_Pa"]
    for key, low, high in zip(VARY, LOW, HIGH, strict=True):
        assert low <= run.optimum["values"][key] <= high
    sample = [r for r in run.history[1:9] if r.get("feasible")]
    best = max(r["objectives"]["impact_power_kW"] for r in sample)
    assert o.impact_power_kW >= best * (1 - 1e-9)
    # the local search started from the sample's best feasible design; its best design is listed
    (found,) = run.found
    start = max(sample, key=lambda r: r["objectives"]["impact_power_kW"])
    assert found["start"] == start["values"] and found["feasible"]
    # (a continued orbit's figures lie within some 1e-9 of the fresh one's)
    assert o.impact_power_kW >= found["objective"] * (1 - 1e-8) and found["objective"] >= best
    assert run.certificate is not None and "8 sample designs" in run.message
    assert json.loads(run.to_json())["found"] == run.found


def test_the_seed_makes_it_reproducible(run):
    again = optimize_drifter("circuit-drifter", VARY, **KW)
    assert [_record(r) for r in again.history] == [_record(r) for r in run.history]
    assert again.optimum["values"] == run.optimum["values"] and again.found == run.found
    other = optimize_drifter("circuit-drifter", VARY, **dict(KW, seed=4, max_evaluations=12))
    assert other.history[1]["values"] != run.history[1]["values"]


@pytest.mark.parametrize(("kw", "match"), [
    ({"sample": 6}, r"^sample must be a power of two >= 2 \(a Sobol sample's designs\); got 6$"),
    ({"sample": 1}, r"^sample must be a power of two >= 2"),
    ({"local_starts": 0}, r"^local_starts must be an integer in \[1, sample\] = \[1, 8\]; got 0$"),
    ({"local_starts": 9}, r"^local_starts must be an integer in \[1, sample\] = \[1, 8\]; got 9$"),
    ({"seed": -1}, r"^seed must be an integer >= 0; got -1$"),
    ({"workers": 0}, r"^workers must be None, an integer >= 1 or a distributed.Client; got 0$"),
    ({"max_evaluations": 11}, r"^max_evaluations must be at least the sample and 4 designs per local search "
                              r"\(12 = 8 \+ 1 x 4\) with method='multistart'; got 11$"),
])
def test_bad_multistart_input_is_one_line(kw, match):
    with pytest.raises(ValueError, match=match):
        optimize_drifter("circuit-drifter", VARY, **dict(KW, **kw))


def test_the_budget_is_shared_by_the_local_searches():
    assert check_multistart(None, 64, 3, 0, 100, 6) == 12
    assert check_multistart(None, 2, 2, 0, 10, 2) == 4


def test_cli_multistart(tmp_path, capsys):
    from impactbar.cli import main

    out = tmp_path / "result.json"
    assert main(["optimize", "circuit-drifter", "--vary", "valve.switch_out=20mm:23 mm", "--objective",
                 "impact_power", "--method", "multistart", "--sample", "4", "--local-starts", "1",
                 "--max-evaluations", "8", "--quiet", "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert len(doc["found"]) == 1 and doc["evaluations"] <= 9 + 12
    text = capsys.readouterr().out
    assert "gain in impact_power" in text and "local search" in text
    assert main(["optimize", "circuit-drifter", "--vary", "valve.switch_out=20mm:23 mm", "--objective",
                 "impact_power", "--method", "multistart", "--sample", "3"]) == 2
    err = capsys.readouterr().err
    assert "sample must be a power of two" in err and err.count("\n") == 1


def test_a_local_cluster_gives_the_same_search_bit_for_bit(run):
    par = optimize_drifter("circuit-drifter", VARY, workers=2, **KW)
    assert [_record(r) for r in par.history] == [_record(r) for r in run.history]
    assert par.optimum["values"] == run.optimum["values"] and par.found == run.found


def test_a_local_cluster_gives_the_same_polish_bit_for_bit():
    """A local search of four designs, so that the polish steps (three designs, a gradient each):
    its gradients' columns on the two workers, the same gradients as in this process, so the same
    designs, polish and certificate, to the bit."""
    kw = dict(KW, max_evaluations=12)
    one, par = (optimize_drifter("circuit-drifter", VARY, workers=workers, **kw) for workers in (None, 2))
    assert [_record(r) for r in par.history] == [_record(r) for r in one.history]
    assert one.gradients >= 2 and par.gradients == one.gradients
    assert "impact_power_kW 13.23" in one.message and par.message == one.message  # (it improved)
    assert par.optimum["values"] == one.optimum["values"] and par.found == one.found
    cert, again = one.certificate, par.certificate
    assert (again.verdict, again.residual, again.active) == (cert.verdict, cert.residual, cert.active)
    np.testing.assert_array_equal(again.objective_gradient, cert.objective_gradient)


def test_the_certificates_gradient_columns_on_workers_are_the_serial_ones(run, monkeypatch):
    """With workers, the certificate's refined gradient (of the optimum's fresh orbit) computes its
    columns on them too, the cluster open till then: by a map standing in for the cluster's (in this
    process, recording what it is asked), the columns of the first two steps asked together, and the
    same certificate as the search's in this process, to the bit."""
    od = sys.modules["impactbar.physical.optimize_drifter"]
    asked = []

    @contextlib.contextmanager
    def record_map(workers):
        assert workers == 2
        closed = []

        def mapped(fn, items, **common):
            assert not closed  # (asked while the cluster is open)
            items = list(items)
            if "continued_vs_fresh" in common.get("rec", {}):  # (the optimum's fresh record)
                asked.append((fn.__name__, common["rec"]["values"], sorted({step for step, _ in items})))
            return [fn(item, **common) for item in items]

        yield mapped
        closed.append(True)

    monkeypatch.setattr(od, "record_map", record_map)
    par = optimize_drifter("circuit-drifter", VARY, workers=2, **KW)
    assert asked and asked[0][0] == "_step_column" and len(asked[0][2]) == 2
    assert all(values == run.optimum["values"] for _, values, _ in asked)
    cert, again = run.certificate, par.certificate
    assert (again.verdict, again.residual, again.active) == (cert.verdict, cert.residual, cert.active)
    np.testing.assert_array_equal(again.objective_gradient, cert.objective_gradient)
    assert again.constraint_gradients == cert.constraint_gradients
    assert np.any(cert.objective_gradient != 0.0)


def test_the_refined_gradients_columns_on_workers_are_the_serial_ones():
    """:func:`_refined_gradient` with its steps' columns mapped (two a round; here by a map that
    records its calls) gives the serial ladder's gradient, to the bit, and asks for the first two
    steps together."""
    from impactbar.physical.design_keys import design_bounds
    from impactbar.physical.loader import config_value
    from impactbar.physical.optimize_problem import _limits, _refined_gradient, evaluate_design, objectives

    cfg, folder = read_config("circuit-drifter")
    base = build(cfg, folder)
    limits = _limits({}, base, ideal=False)
    spec = design_bounds(cfg, VARY, folder)
    span = np.array([spec[k]["high"] - spec[k]["low"] for k in spec])
    rec, orbit = evaluate_design(base, limits)
    rec.update(values={k: spec[k]["start"] for k in spec}, changes={k: config_value(cfg, k) for k in spec})
    fkey = objectives("circuit")["impact_power"].key
    rounds = []

    def run(fn, items, **common):
        rounds.append([step for step, _ in items])
        return [fn(item, **common) for item in items]

    serial = _refined_gradient(cfg, folder, rec, orbit, spec, limits, fkey, span)
    mapped = _refined_gradient(cfg, folder, rec, orbit, spec, limits, fkey, span, run=run)
    np.testing.assert_array_equal(mapped.objective, serial.objective)
    np.testing.assert_array_equal(mapped.constraints, serial.constraints)
    assert np.any(serial.objective != 0.0)
    assert len(rounds[0]) == 2 * len(spec) and len(set(rounds[0])) == 2
