"""Checks of ``optimize_drifter`` that do not trust the optimiser: an active constraint, relaxed, lets
the optimum improve by what the constraint's sensitivity (by fresh orbits) predicts; every reported
design meets its constraints by a fresh orbit, its figures of the right sign and size."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impactbar.physical import build, optimize_drifter, read_config, with_values

pytest.importorskip("pint")

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
        # active: met, to within COBYLA's tolerance of the limit (scaled by the limit)
        assert 0.0 <= c["scaled"] < 1e-3
        # the fresh orbit of the reported design: the same pressure, under the cap
        d, o = _fresh(res.optimum["changes"])
        assert o.mean_supply_pressure_Pa == pytest.approx(c["value"], rel=1e-9)
        assert o.mean_supply_pressure_Pa <= limit
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
    print(f"impact power {p_tight:.6g} -> {p_loose:.6g} kW, predicted gain {predicted:.4g} kW")
    # and just above the tight optimum's flow the cap is broken: the optimum is the cap's, not a stall
    assert up.mean_supply_pressure_Pa > 23.0e6


def test_every_reported_figure_has_its_sign_and_size():
    """The baseline and the optimum as reported: every constraint's margin is the value's distance
    to the limit on the constraint's side (positive where met), its feasibility as the margins
    say, the efficiency in (0, 1), the impact power the impact energy times the frequency, the
    pump's power above the impact power."""
    res = _relaxed_run(23.0e6)
    for rec in (res.baseline, res.optimum):
        sides = {"max_multiplier": 1, "min_pressure": -1, "mean_supply_pressure": 1, "min_chamber_volume": -1}
        for name, c in rec["constraints"].items():
            assert c["margin"] == pytest.approx(sides[name] * (c["limit"] - c["value"]), rel=1e-12)
            assert (c["scaled"] >= 0) == (c["margin"] >= 0)
        assert rec["feasible"] == all(c["margin"] >= 0 for c in rec["constraints"].values())
        obj = rec["objectives"]
        assert 0.0 < obj["hydraulic_efficiency"] < 1.0
        power = obj["impact_energy_J"] * obj["blow_frequency_Hz"] / 1e3
        assert obj["impact_power_kW"] == pytest.approx(power, rel=1e-9)
        assert obj["pump_power_kW"] > obj["impact_power_kW"] > 0.0
        assert math.isfinite(rec["continued_vs_fresh"])
        # the multipliers reported are the fresh orbit's (the largest modulus is the constraint's value)
        mu = np.hypot(rec["multipliers_re"], rec["multipliers_im"])
        assert mu.max() == pytest.approx(rec["constraints"]["max_multiplier"]["value"], rel=1e-12)
