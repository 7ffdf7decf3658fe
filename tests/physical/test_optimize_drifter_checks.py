"""Checks of ``optimize_drifter`` that do not trust the optimiser: in the circuit's ideal limit (the
piston delivered at a held impact velocity) its optimum piston is ``optimize_piston``'s; an active
constraint, relaxed, lets the optimum improve by what the constraint's sensitivity (by fresh orbits)
predicts; every reported design meets its constraints by a fresh orbit, its figures of the right sign
and size."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from impactbar.laws.rodrock import lundberg_efficiency
from impactbar.physical import build, optimize_drifter, optimize_piston, read_config, with_values
from impactbar.physical.optimize_drifter import FEASIBILITY_TOLERANCE, evaluate_blow
from impactbar.physical.piston import piston_blow
from impactbar.physical.rock import RodPiece

pytest.importorskip("pint")

ROOT = Path(__file__).resolve().parents[2]
PISTON_EXAMPLE = ROOT / "examples" / "circuit_drifter_rock_piston.toml"
DOCS = ROOT / "docs" / "optimising_a_drifter.md"


def _docs_say(*phrases):
    """The docs page states each of ``phrases`` (its numbers are these tests')."""
    text = " ".join(DOCS.read_text().split())
    for phrase in phrases:
        assert phrase in text, phrase


def _mm(xs):
    return "{:.2f}, {:.2f} and {:.2f} mm".format(*(1e3 * np.asarray(xs)))

#: a small problem on the rigid piston without rock (an evaluation about 0.3 s): impact power over
#: the pump's flow and the valve's switch point, the mean supply pressure capped
RELAX_VARY = {"supply.pump_flow": ("60 L/min", "90 L/min"), "valve.switch_out": ("19 mm", "24 mm")}
RELAX_TOL = 1e-4  # COBYLA's last step in the scaled variables


def _relaxed_run(limit_Pa: float):
    return optimize_drifter("circuit-drifter", RELAX_VARY, objective="impact_power",
                            constraints={"mean_supply_pressure": limit_Pa}, max_evaluations=40,
                            progress=False, tol=RELAX_TOL)


def _fresh(changes):
    d = build(with_values(read_config("circuit-drifter")[0], changes))
    return d, d.orbit()


def test_relaxing_the_active_constraint_improves_the_optimum():
    """Impact power grows with the pump's flow and so does the mean supply pressure: capped at
    23 MPa (the start's 21.9 MPa), the cap is active at the optimum; at 23.5 MPa the optimum gains,
    by about what the cap's sensitivity at the first optimum predicts (the power's over the
    pressure's rate in the flow, by fresh orbits either side)."""
    tight, loose = _relaxed_run(23.0e6), _relaxed_run(23.5e6)
    for res, limit in ((tight, 23.0e6), (loose, 23.5e6)):
        c = res.optimum["constraints"]["mean_supply_pressure"]
        assert c["limit"] == limit
        # active: met (to the orbit's accuracy), to within COBYLA's tolerance of the limit (scaled by it)
        assert -FEASIBILITY_TOLERANCE <= c["scaled"] < 1e-3
        # the fresh orbit of the reported design: the same pressure, under the cap
        d, o = _fresh(res.optimum["changes"])
        assert o.mean_supply_pressure_Pa == pytest.approx(c["value"], rel=1e-9)
        assert o.mean_supply_pressure_Pa <= limit * (1.0 + FEASIBILITY_TOLERANCE)
        # the switch point runs to its upper bound, the flow stops inside its bounds
        assert res.optimum["values"]["valve.switch_out"] == pytest.approx(0.024, abs=1e-5)
        assert 60 / 6e4 < res.optimum["values"]["supply.pump_flow"] < 90 / 6e4
    p_tight = tight.optimum["objectives"]["impact_power_kW"]
    p_loose = loose.optimum["objectives"]["impact_power_kW"]
    # the optimiser's own resolution of the objective: a step of RELAX_TOL in the scaled flow
    q = tight.optimum["values"]["supply.pump_flow"]
    dq = 30 / 6e4 * 0.01
    up = _fresh({**tight.optimum["changes"], "supply.pump_flow": f"{q + dq!r} m**3/s"})[1]
    down = _fresh({**tight.optimum["changes"], "supply.pump_flow": f"{q - dq!r} m**3/s"})[1]
    dpower = (up.impact_power_kW - down.impact_power_kW) / (2 * dq)
    dpress = (up.mean_supply_pressure_Pa - down.mean_supply_pressure_Pa) / (2 * dq)
    resolution = abs(dpower) * 30 / 6e4 * RELAX_TOL
    assert p_loose - p_tight > 100 * resolution
    # the cap's multiplier: the power bought per pascal along the active cap
    predicted = dpower / dpress * 0.5e6
    assert p_loose - p_tight == pytest.approx(predicted, rel=0.1)
    _docs_say("capped at 23 MPa", "active: its margin under 1e-3 of the cap", f"{p_tight:.3f} kW",
              f"the best design found gives {p_loose:.3f} kW: {p_loose - p_tight:.3f} kW more",
              f"predicts {predicted:.3f} kW")
    # and just above the tight optimum's flow the cap is broken: the optimum is the cap's, not a stall
    assert up.mean_supply_pressure_Pa > 23.0e6


def test_every_reported_figure_has_its_sign_and_size():
    """The baseline and the optimum as reported: every constraint's margin is the value's distance
    to the limit on the constraint's side (positive where met), its feasibility as the margins
    say, the efficiency in (0, 1), the impact power the impact energy times the frequency, the
    pump's power above the impact power."""
    res = _relaxed_run(23.0e6)
    assert res.optimum["feasible"] and res.baseline["feasible"]  # both met, by their fresh orbits
    for rec in (res.baseline, res.optimum):
        sides = {"max_multiplier": 1, "minimum_pressure": -1, "mean_supply_pressure": 1,
                 "min_chamber_volume": -1}
        for name, c in rec["constraints"].items():
            assert c["margin"] == pytest.approx(sides[name] * (c["limit"] - c["value"]), rel=1e-12)
            assert (c["scaled"] >= 0) == (c["margin"] >= 0)
        met = [c["scaled"] >= -FEASIBILITY_TOLERANCE for c in rec["constraints"].values()]
        assert rec["feasible"] == all(met)
        obj = rec["objectives"]
        assert 0.0 < obj["hydraulic_efficiency"] < 1.0
        power = obj["impact_energy_J"] * obj["blow_frequency_Hz"] / 1e3
        assert obj["impact_power_kW"] == pytest.approx(power, rel=1e-9)
        assert obj["pump_power_kW"] > obj["impact_power_kW"] > 0.0
        assert math.isfinite(rec["continued_vs_fresh"])
        # the multipliers reported are the fresh orbit's (the largest modulus is the constraint's value)
        mu = np.hypot(rec["multipliers_re"], rec["multipliers_im"])
        assert mu.max() == pytest.approx(rec["constraints"]["max_multiplier"]["value"], rel=1e-12)


@pytest.mark.parametrize("name", ["peak_rod_stress", "min_drilling_rate"])
def test_a_rock_constraint_without_rock_is_refused_in_one_line(name):
    """Without a drill string the rock's figures are not computed: a limit on one is refused up front
    (it was reported as an infeasible start missing its limit by nan)."""
    match = f"constraints: '{name}' needs the drill string and the rock"
    with pytest.raises(ValueError, match=match) as info:
        optimize_drifter("circuit-drifter", {"valve.switch_out": ("20 mm", "23 mm")},
                         objective="impact_power", constraints={name: 1.0}, progress=False)
    assert "\n" not in str(info.value)


# -- the circuit's ideal limit: the blow alone at a held impact velocity ------------------------------
#: the example's drill string (a 45 mm shank adapter of 0.4 m, a 32 mm rod of 1.2 m), its bit and
#: rock without the feed (so that every blow is exact), the example piston's mass and length, 10 m/s
STEEL = {"E_Pa": 2.1e11, "density_kg_m3": 7850.0}
ROD = [RodPiece(length_m=0.4, area_m2=math.pi / 4 * 0.045 ** 2, **STEEL),
       RodPiece(length_m=1.2, area_m2=math.pi / 4 * 0.032 ** 2, **STEEL)]
ROCK = (4.7e8, 4.7e9)
MASS, LENGTH, V = 5.6, 0.44854236, 10.0


def _ideal_drifter_config(lengths, diameters=(25e-3, 48e-3, 30e-3)):
    keys = ("rear_rod", "collar", "front_rod")
    changes = {f"piston.{k}_length": f"{float(x)!r} m" for k, x in zip(keys, lengths, strict=True)}
    changes.update({f"piston.{k}_diameter": f"{float(x)!r} m" for k, x in zip(keys, diameters, strict=True)})
    changes["rock.feed"] = "0 N"
    return with_values(read_config(PISTON_EXAMPLE)[0], changes)


def test_ideal_limit_optimum_is_optimize_pistons():
    """The drifter's piston (rear rod, collar, front rod) at ``optimize_piston``'s lengths, its three
    diameters searched by ``optimize_drifter`` in the ideal limit (the work on the rock per blow at
    10 m/s, the mass at most the example's 5.6 kg): the optimum has the mass at its limit and the
    shape and work of ``optimize_piston``'s three segments. Tolerances: ``optimize_piston`` finds
    the masses on the lattice's blow (the bit's cell averages at 48 cells) and scores them by the
    exact blow, which the drifter's search maximises directly: the works agree to 1e-5, the
    segments' masses to 0.2 % of the piston's; the rear rod, 3.5 % of the mass where the work is
    flattest, to 4 % of its own mass (3.0 %)."""
    best = optimize_piston(ROD, ROCK, mass=MASS, length=LENGTH, max_stress=math.inf, impact_velocity=V,
                           segments=3, bit_mass=1.5)
    d_r, d_c, d_f = best.diameters_m
    assert d_r < d_f < d_c  # a drifter's piston: the bore (the collar) above both rods, the rear the thinnest
    cfg = _ideal_drifter_config(best.lengths_m)
    vary = {"piston.rear_rod_diameter": ("20 mm", "27 mm"), "piston.collar_diameter": ("44 mm", "54 mm"),
            "piston.front_rod_diameter": ("27.5 mm", "33 mm")}
    res = optimize_drifter(cfg, vary, objective="work_on_rock_per_blow", constraints={"piston_mass": MASS},
                           impact_velocity=V, max_evaluations=150, tol=1e-5, progress=False)
    opt = res.optimum
    # the mass constraint is active: met, to its tolerance (a miss below FEASIBILITY_TOLERANCE of the
    # limit counts as met)
    assert -FEASIBILITY_TOLERANCE * MASS <= opt["constraints"]["piston_mass"]["margin"] < 1e-6 * MASS
    work = opt["objectives"]["work_on_rock_J"]
    assert work == pytest.approx(best.work_on_rock_J, rel=1e-5)
    # the same blow: the reported design's, evaluated again, is optimize_piston's scorer's
    lengths = opt["piston"]["lengths_m"]
    areas = [math.pi / 4 * x ** 2 for x in opt["piston"]["diameters_m"]]
    again = piston_blow(ROD, ROCK, lengths=lengths, areas=areas, impact_velocity=V, bit_mass=1.5)
    assert again["work_on_rock_J"] == pytest.approx(work, rel=1e-12)
    np.testing.assert_allclose(lengths, best.lengths_m, rtol=1e-12)
    masses = 7850.0 * np.asarray(lengths) * np.asarray(areas)
    masses_p = 7850.0 * best.lengths_m * best.areas_m2
    np.testing.assert_allclose(masses, masses_p, atol=2e-3 * MASS)
    assert masses[0] == pytest.approx(masses_p[0], rel=0.04)
    np.testing.assert_allclose(opt["piston"]["diameters_m"][1:], best.diameters_m[1:], rtol=2e-3)
    _docs_say(f"three segments gives {_mm(best.lengths_m)} of {_mm(best.diameters_m)}",
              f"({best.work_on_rock_J:.3f} J; the uniform piston {best.uniform_work_on_rock_J:.2f} J)",
              f"mass at its limit and {_mm(opt['piston']['diameters_m'])} ({work:.3f} J)")
    # relaxing the active mass limit by 0.1 kg: more work, about the efficiency's share of the energy added
    heavier = optimize_drifter(cfg, vary, objective="work_on_rock_per_blow",
                               constraints={"piston_mass": MASS + 0.1}, impact_velocity=V,
                               max_evaluations=150,
                               tol=1e-5, progress=False)
    gain = heavier.optimum["objectives"]["work_on_rock_J"] - work
    assert gain == pytest.approx(opt["objectives"]["efficiency"] * 0.1 * V * V / 2, rel=0.2)
    predicted = opt["objectives"]["efficiency"] * 0.1 * V * V / 2
    _docs_say(f"0.1 kg more of mass gives {gain:.2f} J more work per blow",
              f"of the energy added, {predicted:.2f} J, within 20 %")


def test_ideal_limit_blow_of_one_segment_is_lundbergs():
    """One segment: the uniform piston's blow as the ideal limit scores it is ``optimize_piston``'s
    uniform piston's, and on Lundberg's rock (a long rod of the piston's impedance, a massless bit,
    loading only) Lundberg's closed form, at its optimum alpha 1.2564312 his 0.8145288."""
    area = MASS / (7850.0 * LENGTH)
    uniform = piston_blow(ROD, ROCK, lengths=[LENGTH], areas=[area], impact_velocity=V, bit_mass=1.5)
    best = optimize_piston(ROD, ROCK, mass=MASS, length=LENGTH, max_stress=math.inf, impact_velocity=V,
                           segments=1, bit_mass=1.5)
    assert uniform["work_on_rock_J"] == pytest.approx(best.uniform_work_on_rock_J, rel=1e-12)
    assert uniform["work_on_rock_J"] == pytest.approx(best.work_on_rock_J, rel=1e-12)
    c = math.sqrt(2.1e11 / 7850.0)
    alpha = 1.2564312
    K = alpha * 7850.0 * c * area / (2 * LENGTH / c)  # alpha = K (2 L / c) / Z
    long_rod = [RodPiece(length_m=40 * LENGTH, area_m2=area, **STEEL)]
    b = piston_blow(long_rod, (K, 1e6 * K), lengths=[LENGTH], areas=[area], impact_velocity=V)
    assert b["efficiency"] == pytest.approx(lundberg_efficiency(alpha, 1e6), abs=1e-9)
    assert lundberg_efficiency(alpha, math.inf) == pytest.approx(0.8145288, abs=1e-7)


def test_ideal_limit_refuses_what_it_does_not_compute():
    """In the ideal limit the circuit's constraints and objectives are refused in one line; the
    record of a design holds the blow's figures only."""
    cfg = _ideal_drifter_config([0.1, 0.1, 0.24854236])
    vary = {"piston.collar_diameter": ("47 mm", "52 mm")}
    for kwargs, match in (({"objective": "drilling_rate"}, "the objective is 'work_on_rock_per_blow'"),
                          ({"constraints": {"max_multiplier": 0.9}}, "'max_multiplier' is the circuit's"),
                          ({"impact_velocity": "-3 m/s"}, "impact_velocity must be a positive speed")):
        args = {"objective": "work_on_rock_per_blow", "impact_velocity": V, **kwargs}
        with pytest.raises(ValueError, match=match) as info:
            optimize_drifter(cfg, vary, progress=False, **args)
        assert "\n" not in str(info.value)
    rec = evaluate_blow(build(cfg), V, {"peak_rod_stress": "300 MPa"})
    assert set(rec["constraints"]) == {"peak_rod_stress"}
    assert 0.0 < rec["objectives"]["efficiency"] < 1.0
    energy = 0.5 * build(cfg).bar.mass_kg * V * V
    assert rec["objectives"]["impact_energy_J"] == pytest.approx(energy, rel=1e-12)


def test_cli_ideal_limit(tmp_path, capsys):
    """``impactbar optimize --impact-velocity``: the ideal limit from the command line, its optimum the
    function's."""
    from impactbar.cli import main

    toml = tmp_path / "ideal.toml"  # the example without its feed
    text = PISTON_EXAMPLE.read_text()
    assert 'feed = "2 kN"' in text
    toml.write_text(text.replace('feed = "2 kN"', 'feed = "0 N"'))
    argv = ["optimize", str(toml), "--vary", "piston.collar_diameter=47mm:52mm", "--objective",
            "work_on_rock_per_blow", "--impact-velocity", "10 m/s", "--constraint", "piston_mass=5.7 kg",
            "--max-evaluations", "8", "--quiet", "--out", str(tmp_path / "r.json")]
    assert main(argv) == 0
    assert "gain in work_on_rock_per_blow" in capsys.readouterr().out
    res = optimize_drifter(toml, {"piston.collar_diameter": ("47 mm", "52 mm")},
                           objective="work_on_rock_per_blow", impact_velocity="10 m/s",
                           constraints={"piston_mass": "5.7 kg"}, max_evaluations=8, progress=False)
    doc = json.loads((tmp_path / "r.json").read_text())
    assert doc["optimum"]["values"] == res.optimum["values"]
    assert doc["optimum"]["constraints"]["piston_mass"]["margin"] >= 0.0


def test_the_ideal_limit_takes_cobyla_alone():
    """SLSQP's gradients come from the circuit's orbits, which the ideal limit does not compute."""
    example = Path(__file__).parents[2] / "examples" / "circuit_drifter_rock_piston.toml"
    with pytest.raises(ValueError, match="the method is 'cobyla'.*got 'slsqp'"):
        optimize_drifter(example, {"piston.collar_diameter": ("46 mm", "52 mm")},
                         objective="work_on_rock_per_blow", impact_velocity="10 m/s", method="slsqp",
                         progress=False)
