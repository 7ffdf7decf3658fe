"""Designs of the whole-drifter optimiser without a one-impact orbit: what their evaluation costs
(about what a design with an orbit costs) and what their record says."""

from __future__ import annotations

from pathlib import Path

import pytest

from impactbar.orbits import coupled
from impactbar.physical import build, read_config, with_values
from impactbar.physical.optimize_drifter import DEFAULT_CONSTRAINTS, _design_record

pytest.importorskip("pint")

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter_rock_piston.toml"
#: the optimum with the drilling rate held (docs/optimising_a_drifter.md)
OPTIMUM = {"piston.collar_diameter": "0.04721879723846864 m",
           "piston.front_rod_diameter": "0.04560714397207219 m",
           "piston.rear_rod_diameter": "0.04058336647137088 m",
           "chambers.rear_volume": "8.177116598602943e-05 m**3", "valve.switch_out": "0.02140236229697432 m",
           "accumulator.precharge": "10041438.916236278 Pa"}


def _collar(factor: float) -> dict:
    """The optimum with its collar's diameter times ``factor``: at 1.01 (47.69 mm) no one-impact
    orbit, at 1.003 and 1.03 one (a band of designs without one between them)."""
    return dict(OPTIMUM, **{"piston.collar_diameter": f"{0.04721879723846864 * factor!r} m"})


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
    n_ok, orbit = _blows(monkeypatch, _collar(1.003))
    n_fail, err = _blows(monkeypatch, _collar(1.01))
    assert not isinstance(orbit, Exception) and orbit.stable
    # Newton's steps circled (a step of 1.7e-3 relative, again and again): given up when they stall,
    # where before the chord and then Newton's method took their 50 steps each (907 blows, 15 s)
    assert isinstance(err, ValueError) and "Newton stalled" in str(err)
    assert n_fail <= 3 * n_ok, (n_fail, n_ok)  # 64 against 35 blows


def test_a_failed_design_s_record_says_why_and_what_it_cost():
    cfg, folder = read_config(EXAMPLE)
    rec = _design_record(_collar(1.01), cfg, folder, dict(DEFAULT_CONSTRAINTS, mean_supply_pressure=None))
    assert rec["ok"] is False and rec["feasible"] is False
    assert "no periodic orbit" in rec["error"] and "Newton stalled" in rec["error"]
    assert 0.0 < rec["seconds"] < 60.0
