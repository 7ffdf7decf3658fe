"""The drifter's piston given by its shape, and ``optimize_drifter``: checks that do not trust the
optimiser (each reported design rebuilt from its config values and solved by a fresh ``orbit()``, its
constraints recomputed from that orbit), the bad inputs one line each, the cache's resume."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from cache_log import cache_log

from impactbar.physical import build, optimize_drifter, read_config, with_values
from impactbar.physical.geometry import piston_geometry
from impactbar.physical.optimize_drifter import FEASIBILITY_TOLERANCE

ROOT = Path(__file__).resolve().parents[2]
PISTON_EXAMPLE = ROOT / "examples" / "circuit_drifter_rock_piston.toml"
OLD_EXAMPLE = ROOT / "examples" / "circuit_drifter_rock.toml"

pytest.importorskip("pint")


# -- the geometry ---------------------------------------------------------------------------------
def test_piston_shape_gives_the_areas_mass_and_stepped_piston():
    cfg, _ = read_config(PISTON_EXAMPLE)
    d = build(cfg)
    D, dr, df = 48.80e-3, 40.84e-3, 45e-3
    # the annuli by hand: the bore less each rod
    assert d.si["rear_area_m2"] == pytest.approx(math.pi / 4 * (D * D - dr * dr), rel=1e-14)
    assert d.si["front_area_m2"] == pytest.approx(math.pi / 4 * (D * D - df * df), rel=1e-14)
    # and the example's areas (5.6 and 2.8 cm^2) to the 0.1 % its rounded diameters allow
    old = build(read_config(OLD_EXAMPLE)[0])
    assert d.si["rear_area_m2"] == pytest.approx(old.si["rear_area_m2"], rel=1e-3)
    assert d.si["front_area_m2"] == pytest.approx(old.si["front_area_m2"], rel=1e-3)
    np.testing.assert_allclose(d.bar.lengths_m, [0.1, 0.1, 0.24854236], rtol=1e-14)
    np.testing.assert_allclose(d.bar.diameters_m, [dr, D, df], rtol=1e-14)
    mass = 7850.0 * math.pi / 4 * (dr ** 2 * 0.1 + D ** 2 * 0.1 + df ** 2 * 0.24854236)
    assert d.bar.mass_kg == pytest.approx(mass, rel=1e-13)
    assert d.bar.mass_kg == pytest.approx(old.bar.mass_kg, rel=1e-3)


def test_striking_end_steps_are_segments_after_the_front_rod():
    cfg, _ = read_config(PISTON_EXAMPLE)
    cfg["piston"]["end_lengths"] = ["30 mm"]
    cfg["piston"]["end_diameters"] = ["40 mm"]
    d = build(cfg)
    assert d.bar.n_segments == 4
    assert d.bar.diameters_m[-1] == pytest.approx(0.04)
    assert d.bar.area_m2 == pytest.approx(math.pi / 4 * 0.04 ** 2)  # the struck end


@pytest.mark.parametrize(("changes", "match"), [
    ({"piston.collar_diameter": "40 mm"},
     r"piston: the rear chamber's area .*collar_diameter.*rear_rod_diameter"),
    ({"piston.collar_diameter": "44 mm"}, r"piston: the front chamber's area .*front_rod_diameter"),
    ({"piston.rear_rod_diameter": "46 mm"}, r"front_rod_diameter must be above piston.rear_rod_diameter"),
])
def test_a_chamber_area_not_positive_is_one_line(changes, match):
    cfg, _ = read_config(PISTON_EXAMPLE)
    with pytest.raises(ValueError, match=match) as info:
        build(with_values(cfg, changes))
    assert "\n" not in str(info.value)


def test_shape_and_areas_both_refused():
    cfg, _ = read_config(PISTON_EXAMPLE)
    with pytest.raises(ValueError, match="chambers.rear_area: with a \\[piston\\]"):
        build(with_values(cfg, {"chambers.rear_area": "5 cm^2"}))
    cfg2 = dict(cfg, bar={"E": "210 GPa", "density": "7850 kg/m^3", "length": "0.4 m", "diameter": "45 mm"})
    with pytest.raises(ValueError, match="either as \\[piston\\].*or as \\[bar\\]"):
        build(cfg2)


def test_geometry_refuses_a_missing_key():
    with pytest.raises(ValueError, match="missing key piston.collar_length"):
        piston_geometry({"E": "210 GPa", "density": "7850 kg/m^3", "rear_rod_diameter": "40 mm",
                         "rear_rod_length": "0.1 m", "collar_diameter": "50 mm",
                         "front_rod_diameter": "45 mm", "front_rod_length": "0.2 m"})


# -- bad input: one line each -----------------------------------------------------------------------
@pytest.mark.parametrize(("vary", "match"), [
    ({"valve.switch_at": ("20 mm", "23 mm")}, r"'valve.switch_at' is not a parameter the optimiser varies"),
    ({"piston.collar_diameter": ("47 mm", "52 mm")}, r"vary: .*no \[piston\] section"),
    ({"valve.switch_out": ("20 MPa", "23 MPa")}, r"valve.switch_out.*low"),
    ({"valve.switch_out": ("20", "23")}, r"valve.switch_out.*unit"),
    ({"chambers.rear_volume": ("-0.1 L", "0.2 L")}, r"the low bound '-0.1 L' is outside the key's range"),
    ({"valve.switch_out": ("23 mm", "20 mm")}, r"low must be below high"),
    ({"valve.switch_out": ("22 mm", "25 mm")}, r"the start '21.5 mm' lies outside the bounds"),
])
def test_bad_variables_are_one_line(vary, match):
    with pytest.raises(ValueError, match=match) as info:
        optimize_drifter("circuit-drifter", vary, objective="impact_power", progress=False)
    assert "\n" not in str(info.value)


def test_bad_objective_constraint_and_budget_are_one_line():
    vary = {"valve.switch_out": ("20 mm", "23 mm")}
    with pytest.raises(ValueError, match="needs the drill string and the rock"):
        optimize_drifter("circuit-drifter", vary, progress=False)
    with pytest.raises(ValueError, match="unknown constraint 'stress'"):
        optimize_drifter("circuit-drifter", vary, objective="impact_power", constraints={"stress": 1.0},
                         progress=False)
    with pytest.raises(ValueError, match=r"max_evaluations must be an integer of at least .* \(3\); got 2"):
        optimize_drifter("circuit-drifter", vary, objective="impact_power", max_evaluations=2, progress=False)


def test_an_infeasible_start_names_the_constraint_and_by_how_much():
    o = build(read_config("circuit-drifter")[0]).orbit()
    worst = float(np.max(np.abs(o.multipliers)))
    pattern = r"infeasible start: constraint max_multiplier = ([0-9.]+) misses its limit 0.5 by ([0-9.]+)"
    with pytest.raises(ValueError, match=pattern) as info:
        optimize_drifter("circuit-drifter", {"valve.switch_out": ("20 mm", "23 mm")},
                         objective="impact_power", constraints={"max_multiplier": 0.5}, progress=False)
    msg = str(info.value)
    assert "\n" not in msg
    by = float(msg.rsplit("by ", 1)[1].split()[0])
    assert by == pytest.approx(worst - 0.5, rel=1e-3)


# -- a tiny problem, checked without trusting the optimiser -----------------------------------------
def _fresh_figures(config, changes):
    d = build(with_values(config, changes))
    o = d.orbit()
    return d, o


def test_tiny_problem_optimum_reevaluated_fresh_and_feasible(tmp_path):
    cache = tmp_path / "cache.json"
    vary = {"valve.switch_out": ("19 mm", "24 mm"), "accumulator.precharge": ("8 MPa", "12 MPa")}
    res = optimize_drifter("circuit-drifter", vary, objective="impact_power", max_evaluations=8,
                           cache=cache, progress=False)
    config = read_config("circuit-drifter")[0]
    # the start is the config itself
    assert res.baseline["changes"] == {"valve.switch_out": "21.5 mm", "accumulator.precharge": "10 MPa"}
    d, o = _fresh_figures(config, res.optimum["changes"])
    lo = {"valve.switch_out": 0.019, "accumulator.precharge": 8e6}
    hi = {"valve.switch_out": 0.024, "accumulator.precharge": 12e6}
    for key, value in res.optimum["values"].items():
        assert lo[key] <= value <= hi[key]
    assert res.optimum["objectives"]["impact_power_kW"] == pytest.approx(o.impact_power_kW, rel=1e-9)
    assert res.optimum["objectives"]["pump_power_kW"] == pytest.approx(o.pump_power_kW, rel=1e-9)
    assert res.optimum["objectives"]["blow_frequency_Hz"] == pytest.approx(o.blow_frequency_Hz, rel=1e-9)
    # constraints met at the optimum, recomputed from the fresh orbit
    assert np.max(np.abs(o.multipliers)) <= 0.95
    assert min(o.minimum_pressures_Pa.values()) >= 0.0
    assert o.mean_supply_pressure_Pa <= d.si["relief_pressure_Pa"]
    h = o.histories(200)
    assert min(h["V_f_m3"].min(), h["V_r_m3"].min()) > 0.0
    # the search's continued orbit agrees with the fresh one; the optimum is no worse than the start
    assert res.optimum["continued_vs_fresh"] < 1e-7
    base = build(config).orbit()
    assert o.impact_power_kW >= base.impact_power_kW
    assert res.gain == pytest.approx(o.impact_power_kW / base.impact_power_kW - 1.0, rel=1e-6, abs=1e-12)
    # every design the search evaluated lies within the bounds and the best feasible one is reported
    feasible = [r for r in res.history if r.get("feasible")]
    assert max(r["objectives"]["impact_power_kW"] for r in feasible) == pytest.approx(
        res.optimum["objectives"]["impact_power_kW"], rel=1e-7)
    # JSON out; a second run resumes from the cache, evaluating nothing new, the same optimum
    doc = json.loads(res.to_json(tmp_path / "result.json"))
    assert doc["optimum"]["values"] == res.optimum["values"]
    again = optimize_drifter("circuit-drifter", vary, objective="impact_power", max_evaluations=8,
                             cache=cache, progress=False)
    assert again.evaluations == 0 and again.cached == len(res.history)
    assert again.optimum["values"] == res.optimum["values"]
    assert "gain in impact_power" in res.table()


def test_plot_draws_the_pistons_and_multipliers(tmp_path):
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    res = optimize_drifter("circuit-drifter", {"valve.switch_out": ("20 mm", "23 mm")},
                           objective="impact_power", max_evaluations=3, progress=False)
    axes = res.plot()
    assert len(axes) == 3 and len(axes[0].patches) == 2  # one uniform piston each, before and after
    axes[0].figure.savefig(tmp_path / "f.png")


# -- on the rod and rock --------------------------------------------------------------------------
@pytest.mark.slow
def test_rock_problem_one_variable_reevaluated_fresh():
    vary = {"piston.collar_diameter": ("48 mm", "50 mm")}
    res = optimize_drifter(PISTON_EXAMPLE, vary, constraints={"peak_rod_stress": "260 MPa"},
                           max_evaluations=3, progress=False)
    d, o = _fresh_figures(read_config(PISTON_EXAMPLE)[0], res.optimum["changes"])
    rock = o.rock()
    assert res.optimum["objectives"]["drilling_rate_m_min"] == pytest.approx(rock["drilling_rate_m_min"],
                                                                             rel=1e-9)
    assert res.optimum["objectives"]["drilling_rate_per_kW"] == pytest.approx(
        rock["drilling_rate_m_min"] / o.pump_power_kW, rel=1e-9)
    assert rock["peak_rod_stress_Pa"] <= 260e6
    assert np.max(np.abs(o.multipliers)) <= 0.95 and not o.cavitates
    # the stress wave the report draws peaks at the peak incident stress it reports, before the rock's
    # first reflection is back at the shank (the drill string's round trip) or the piston's first
    # contact ends, whichever is later
    wave = res.optimum["shank_stress"]
    back = 2.0 * sum(g.length_m / g.wave_speed_m_s for g in d.drill.segments)
    end = max(back, o.orbit.contacts[0].blow.first_separation * d.scales.time_s)
    incident = np.asarray(wave["stress_Pa"])[np.asarray(wave["t_s"]) < end]
    assert incident.max() == pytest.approx(rock["peak_rod_stress_Pa"], rel=1e-9)
    assert max(wave["stress_Pa"]) >= incident.max()
    pytest.importorskip("matplotlib")
    assert len(res.plot()[1].lines) == 2


# -- the command line ---------------------------------------------------------------------------------
def test_cli_optimize_writes_json_and_refuses_bad_input_in_one_line(tmp_path, capsys):
    from impactbar.cli import main

    out = tmp_path / "result.json"
    assert main(["optimize", "circuit-drifter", "--vary", "valve.switch_out=20mm:23 mm", "--objective",
                 "impact_power", "--max-evaluations", "3", "--quiet", "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["objective"] == "impact_power" and doc["evaluations"] >= 1
    assert "gain in impact_power" in capsys.readouterr().out
    for argv, match in ((["--vary", "valve.switch_out=20mm"], "--vary must be KEY=LOW:HIGH"),
                        (["--vary", "valve.switch=20mm:23mm"], "is not a parameter the optimiser varies"),
                        (["--vary", "valve.switch_out=20mm:23mm", "--constraint", "max_multiplier"],
                         "--constraint must be NAME=VALUE")):
        assert main(["optimize", "circuit-drifter", "--objective", "impact_power", *argv]) == 2
        err = capsys.readouterr().err
        assert match in err and err.count("\n") == 1


# -- the docs page's numbers, recomputed ------------------------------------------------------------
DOCS = ROOT / "docs" / "optimising_a_drifter.md"

#: the table's rows: the figure of a fresh operating point each one prints
_ROWS = {
    "drilling rate (m/min)": lambda d, o: o.rock()["drilling_rate_m_min"],
    "drilling rate per kW (m/min/kW)": lambda d, o: o.rock()["drilling_rate_m_min"] / o.pump_power_kW,
    "work on rock per blow (J)": lambda d, o: o.rock()["work_on_rock_J"],
    "impact power (kW)": lambda d, o: o.impact_power_kW,
    "blow frequency (Hz)": lambda d, o: o.blow_frequency_Hz,
    "pump power (kW)": lambda d, o: o.pump_power_kW,
    "peak incident stress (MPa)": lambda d, o: o.rock()["peak_rod_stress_Pa"] / 1e6,
    "largest multiplier modulus": lambda d, o: float(np.max(np.abs(o.multipliers))),
    "mean supply pressure (MPa)": lambda d, o: o.mean_supply_pressure_Pa / 1e6,
    "piston mass (kg)": lambda d, o: d.bar.mass_kg,
    "impact energy (J)": lambda d, o: o.impact_energy_J,
    "hydraulic efficiency": lambda d, o: o.hydraulic_efficiency,
    "least absolute pressure (MPa)": lambda d, o: min(o.minimum_pressures_Pa.values()) / 1e6,
    "smallest chamber volume (L)": lambda d, o: min(o.histories(200)["V_f_m3"].min(),
                                                    o.histories(200)["V_r_m3"].min()) * 1e3,
}


def _docs_designs():
    """The designs the page reports (its ``changes`` blocks, in the table's column order) and its
    table's rows."""
    text = DOCS.read_text()
    blocks = [json.loads(b) for b in re.findall(r"```json\n(\{.*?\})\n```", text, flags=re.S)]
    table = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells and cells[0] in _ROWS:
            table[cells[0]] = [float(c) for c in cells[1:]]
    return blocks, table


@pytest.mark.slow
def test_docs_numbers_recomputed_by_fresh_orbits():
    """Every number of the page's table, for the baseline and each design it reports, from a fresh
    ``orbit()`` of the design rebuilt from the changes the page prints (4 significant digits), and the
    optimum's certificate (the first design) recomputed at that design (:func:`_page_certificate`)."""
    blocks, table = _docs_designs()
    assert blocks and set(table) == set(_ROWS)
    config = read_config(PISTON_EXAMPLE)[0]
    for column, changes in enumerate([{}, *blocks]):
        d = build(with_values(config, changes))
        o = d.orbit()
        for name, fn in _ROWS.items():
            assert fn(d, o) == pytest.approx(table[name][column], rel=6e-4), (name, column)
        if changes:  # each optimum meets the constraints the page states
            assert o.rock()["peak_rod_stress_Pa"] <= 250e6 and np.max(np.abs(o.multipliers)) <= 0.95
            assert not o.cavitates and o.mean_supply_pressure_Pa <= d.si["relief_pressure_Pa"]
        else:
            baseline = _ROWS["drilling rate per kW (m/min/kW)"](d, o)
    _page_certificate(blocks[0], baseline)


def _page_certificate(changes, baseline):
    """The optimum's certificate as the page states it, recomputed from a fresh orbit of the design it
    prints (``changes``): its figures feasible, the objective's and the scaled margins' gradients the
    implicit function theorem's, refined as the search's (``_refined_gradient``), the certificate at
    the polish's resolution (the active set within 1e-4): the verdict, the KKT residual, the active
    constraint and its multiplier, the bounds at which variables sit, its drilling rate, per kilowatt and
    gain over the ``baseline``'s drilling rate per kW (each to the digits printed)."""
    from drifter_optimum import documented_problem

    from impactbar.physical.optimality import KKT_TOLERANCE, certify
    from impactbar.physical.optimize_problem import _refined_gradient

    cfg, folder, spec, keys, span, limits, fresh, scaled = documented_problem()
    u = scaled(changes)
    rec, orbit = fresh(u)
    assert rec["feasible"]
    g, G = _refined_gradient(cfg, folder, rec, orbit, spec, limits, "drilling_rate_per_kW", span)
    cert = certify(g, G, rec, u, keys, method="refined")
    text = re.sub(r"\s+", " ", DOCS.read_text())
    m = re.search(r"Its certificate \"([a-z ]+)\": KKT residual ([0-9.]+) below the tolerance ([0-9.]+), the "
                  r"drilling rate active with the multiplier ([0-9.]+), at their low bounds the rear "
                  r"volume and the pre-charge", text)
    assert m is not None, "the page's certificate of the optimum is gone; update this test with the text"
    assert m[1] == cert.verdict == "converged" and float(m[3]) == KKT_TOLERANCE
    assert float(m[2]) == pytest.approx(cert.residual, abs=5e-5) and cert.residual < KKT_TOLERANCE
    assert cert.active == ["min_drilling_rate"]
    assert cert.bounds == {"chambers.rear_volume": "low", "accumulator.precharge": "low"}
    assert float(m[4]) == pytest.approx(cert.multipliers["min_drilling_rate"], abs=5e-4)
    m = re.search(r"the optimum drills ([0-9.]+) m/min for ([0-9.]+) m/min/kW, \*\*\+([0-9.]+) %\*\* per "
                  r"kilowatt", text)
    assert m is not None, "the page's figures of the optimum are gone; update this test with the text"
    assert float(m[1]) == pytest.approx(rec["objectives"]["drilling_rate_m_min"], abs=5e-4)
    assert float(m[2]) == pytest.approx(rec["objectives"]["drilling_rate_per_kW"], abs=5e-8)
    assert float(m[3]) == pytest.approx(100 * (rec["objectives"]["drilling_rate_per_kW"] / baseline - 1),
                                        abs=5e-3)


@pytest.mark.slow
def test_full_example_problem_reproduces_the_docs_optimum():
    """The benchmark's problem (six variables, 30 designs; a few minutes): the design the page reports
    (its last ``changes`` block) and the page's figures of that search (its counts, the drilling
    rate's margin, the certificate).

    The page's changes are SI strings, the result's in the keys' display units: both are compared in
    SI, as scaled variables (each bound's span 1). COBYLA's path follows the continued orbits'
    figures, which agree with fresh ones to some 1e-10, so the same code elsewhere may end some 1e-7
    of the spans from the page's design (4.5e-7 seen); the design is compared to 1e-5 of each span,
    200 times inside COBYLA's last step (``tol``, 2e-3), and its objective to 1e-6."""
    import importlib.util

    from impactbar.physical.design_keys import design_bounds
    from impactbar.physical.optimality import certify

    spec = importlib.util.spec_from_file_location("bench", ROOT / "benchmarks" / "bench_optimize_drifter.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    res = optimize_drifter(PISTON_EXAMPLE, bench.VARY, constraints=bench.CONSTRAINTS, max_evaluations=30,
                           progress=False)
    blocks, _ = _docs_designs()
    config = read_config(PISTON_EXAMPLE)[0]
    bounds = design_bounds(config, bench.VARY)
    page = design_bounds(with_values(config, blocks[-1]), bench.VARY)
    keys = list(bounds)
    u = np.array([(res.optimum["values"][k] - bounds[k]["low"]) / (bounds[k]["high"] - bounds[k]["low"])
                  for k in keys])
    u_page = np.array([(page[k]["start"] - bounds[k]["low"]) / (bounds[k]["high"] - bounds[k]["low"])
                       for k in keys])
    np.testing.assert_allclose(u, u_page, rtol=0.0, atol=1e-5)
    d, o = _fresh_figures(config, blocks[-1])
    per_kw = o.rock()["drilling_rate_m_min"] / o.pump_power_kW
    assert res.optimum["objectives"]["drilling_rate_per_kW"] == pytest.approx(per_kw, rel=1e-6)
    assert all(c["margin"] >= 0 for c in res.optimum["constraints"].values())
    assert o.rock()["drilling_rate_m_min"] >= 2.5
    # the page's figures of this search, each to the digits it prints
    text = re.sub(r"\s+", " ", DOCS.read_text())

    def quote(pattern):
        m = re.search(pattern, text)
        assert m is not None, f"the page's quote {pattern!r} is gone; update this test with the text"
        return m

    m = quote(r"after ([0-9]+) evaluations \(([0-9]+) of them continued from a neighbour\)")
    assert (int(m[1]), int(m[2])) == (res.evaluations, sum(r.get("continued", False) for r in res.history))
    m = quote(r"on the example's own setting the search below \(([0-9]+) designs, the drilling rate held\) "
              r"meets no design without an operating point")
    assert int(m[1]) == res.evaluations and all(r.get("ok") for r in res.history)
    drill = res.optimum["constraints"]["min_drilling_rate"]["scaled"]  # (of its limit, 2.5 m/min)
    m = quote(r"the drilling rate ([0-9.]+) m/min above its limit")
    assert float(m[1]) == pytest.approx(2.5 * drill, abs=5e-5)
    cert = res.certificate
    m = quote(r"the certificate says so \(\"([a-z ]+)\", KKT residual ([0-9.]+), no constraint active, the "
              r"rear volume at its low bound with the multiplier ([0-9.]+)\)")
    assert m[1] == cert.verdict and cert.active == [] and cert.bounds == {"chambers.rear_volume": "low"}
    assert float(m[2]) == pytest.approx(cert.residual, abs=5e-3)
    assert float(m[3]) == pytest.approx(cert.multipliers["chambers.rear_volume low"], abs=5e-5)
    m = quote(r"the drilling rate's margin ([0-9.]+)e-4 of its limit, beyond COBYLA's last step 2e-3 "
              r"times its gradient's norm ([0-9.]+), and the fixed band 1e-4 gives the same active set and "
              r"residual")
    norm = float(np.linalg.norm(cert.constraint_gradients["min_drilling_rate"]))
    assert float(m[1]) * 1e-4 == pytest.approx(drill, abs=5e-6) and drill > 2e-3 * norm
    assert float(m[2]) == pytest.approx(norm, abs=5e-3)
    band = certify(cert.objective_gradient, list(cert.constraint_gradients.values()), res.optimum, u, keys,
                   method=cert.method)
    assert band.active == cert.active and band.bounds == cert.bounds
    assert band.residual == pytest.approx(cert.residual, rel=1e-12)
    # the continued orbit's distance from the fresh one is the orbit's rounding, not a figure of the
    # design: compared to its order of magnitude (along the SLSQP search of the preset's cap, one
    # search's designs give 7e-12 to 4e-10), both within the feasibility tolerance
    m = quote(r"agreed with their fresh ones to ([0-9.]+e-[0-9]+) and ([0-9.]+e-[0-9]+)")
    assert abs(math.log10(float(m[2]) / res.optimum["continued_vs_fresh"])) < 1.0
    assert max(float(m[2]), res.optimum["continued_vs_fresh"]) < FEASIBILITY_TOLERANCE


def test_readme_quotes_the_docs_table():
    """README's figures of the optimised drifter are the docs page's (which the slow test recomputes)."""
    _, table = _docs_designs()
    text = re.sub(r"\s+", " ", (ROOT / "README.md").read_text())
    m = re.search(r"gives ([0-9.]+) against ([0-9.]+) m/min/kW, \+([0-9.]+) % per kilowatt at the same "
                  r"([0-9.]+) m/min", text)
    assert m is not None
    per_kw = table["drilling rate per kW (m/min/kW)"]  # (the columns: baseline, optimum, any rate, held)
    assert (float(m[1]), float(m[2])) == (per_kw[3], per_kw[0])
    assert float(m[3]) == pytest.approx(100 * (per_kw[3] / per_kw[0] - 1), abs=0.1)
    assert float(m[4]) == pytest.approx(table["drilling rate (m/min)"][3], abs=0.01)
    m = re.search(r"the multistart's certified optimum gives ([0-9.]+) m/min/kW, \+([0-9.]+) %", text)
    assert m is not None and float(m[1]) == per_kw[1]
    assert float(m[2]) == pytest.approx(100 * (per_kw[1] / per_kw[0] - 1), abs=0.1)
    m = re.search(r"drills ([0-9]+) % slower at ([0-9]+) % of the power \(\+([0-9]+) % per kW\)", text)
    rate, power = table["drilling rate (m/min)"], table["pump power (kW)"]
    assert float(m[1]) == pytest.approx(100 * (1 - rate[2] / rate[0]), abs=0.5)
    assert float(m[2]) == pytest.approx(100 * power[2] / power[0], abs=0.5)
    assert float(m[3]) == pytest.approx(100 * (per_kw[2] / per_kw[0] - 1), abs=0.5)


def test_a_stopped_run_resumes_from_its_cache(tmp_path):
    """A run cut short (4 designs) and started again with a larger budget reads the designs it stored
    and evaluates only the rest; the designs it reads are the ones the short run evaluated."""
    cache = tmp_path / "cache.json"
    vary = {"valve.switch_out": ("19 mm", "24 mm"), "accumulator.precharge": ("8 MPa", "12 MPa")}
    short = optimize_drifter("circuit-drifter", vary, objective="impact_power", max_evaluations=4,
                             cache=cache, progress=False)
    stored = cache_log(cache)[1]
    assert len(stored) == short.evaluations == len(short.history)
    full = optimize_drifter("circuit-drifter", vary, objective="impact_power", max_evaluations=8, cache=cache,
                            progress=False)
    assert full.cached == len(stored) and full.evaluations == len(full.history) - len(stored)
    assert [r["values"] for r in full.history[:len(stored)]] == [r["values"] for r in short.history]
    # another problem (another constraint) does not reuse the cache
    other = optimize_drifter("circuit-drifter", vary, objective="impact_power", max_evaluations=4,
                             cache=cache, constraints={"max_multiplier": 0.99}, progress=False)
    assert other.cached == 0
