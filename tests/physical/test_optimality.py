"""The first-order (KKT) certificate of ``optimize_drifter``'s reported design, on the circuit's ideal
limit (seconds a run): a converged search is certified with the piston's mass active and its multiplier
the work a kilogram more buys; a search cut at its budget, and the unoptimised baseline, are not."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from impactbar.cli import main
from impactbar.physical import build, optimize_drifter, with_values
from impactbar.physical.optimality import certify, certify_search
from impactbar.physical.optimize_drifter import evaluate_blow

pytest.importorskip("pint")
sys.path.insert(0, str(Path(__file__).parent))
from test_optimize_drifter_checks import MASS, V, _ideal_drifter_config  # noqa: E402

# optimize_piston's three segments at the example's mass and length (its lengths: the searched
# diameters' optimum is then its, tests/physical/test_optimize_drifter_checks.py)
LENGTHS = (0.056067795, 0.33640677, 0.056067795)
VARY = {"piston.rear_rod_diameter": ("20 mm", "27 mm"), "piston.collar_diameter": ("44 mm", "54 mm"),
        "piston.front_rod_diameter": ("27.5 mm", "33 mm")}
KEYS = list(VARY)


def _run(mass=MASS, **kw):
    return optimize_drifter(_ideal_drifter_config(LENGTHS), VARY, objective="work_on_rock_per_blow",
                            constraints={"piston_mass": mass}, impact_velocity=V, progress=False, **kw)


@pytest.fixture(scope="module")
def converged():
    return _run(max_evaluations=60)


def _figures(res, diameters):
    """A fresh blow of the design of these diameters (m): the work and the mass's scaled margin."""
    d = build(with_values(res.config, {k: f"{float(x)!r} m" for k, x in zip(KEYS, diameters, strict=True)}))
    rec = evaluate_blow(d, V, {"piston_mass": MASS})
    return np.array([rec["objectives"]["work_on_rock_J"], rec["constraints"]["piston_mass"]["scaled"]])


def test_a_converged_search_is_certified_with_its_active_mass(converged):
    """COBYLA stopped by its trust region: the KKT residual below 1e-3, the mass active with a
    positive multiplier; the mass's gradient is the closed form's (rho L pi d / 2 per metre, over the
    limit), the work's agrees with central differences of fresh blows at ten times the certificate's
    step, and the multiplier (J per unit scaled margin, over 5.6 kg) is the work a relaxed limit buys
    (a run at 5.65 kg: 0.05 kg more)."""
    cert = converged.certificate
    assert cert.verdict == "converged" and not cert.budget and cert.residual < 1e-3
    assert cert.active == ["piston_mass"] and cert.bounds == {}
    assert cert.multipliers["piston_mass"] > 0
    d = np.array([converged.optimum["values"][k] for k in KEYS])
    span = np.array([converged.vary[k]["high"] - converged.vary[k]["low"] for k in KEYS])
    dmass = 7850.0 * np.array(LENGTHS) * math.pi * d / 2 * span
    np.testing.assert_allclose(cert.constraint_gradients["piston_mass"], -dmass / MASS, rtol=1e-5)
    h = 1e-3
    fd = np.array([(_figures(converged, d + h * span * e) - _figures(converged, d - h * span * e)) / (2 * h)
                   for e in np.eye(3)]).T
    np.testing.assert_allclose(cert.objective_gradient, fd[0], rtol=1e-3)
    np.testing.assert_allclose(cert.constraint_gradients["piston_mass"], fd[1], rtol=1e-6)
    heavier = _run(MASS + 0.05, max_evaluations=60)
    gain = heavier.optimum["objectives"]["work_on_rock_J"] - converged.optimum["objectives"]["work_on_rock_J"]
    assert gain == pytest.approx(cert.multipliers["piston_mass"] * 0.05 / MASS, rel=0.02)
    assert json.loads(converged.to_json())["certificate"]["verdict"] == "converged"
    assert converged.table().splitlines()[0].split()[-1] == "optimum"


def test_a_search_cut_at_its_budget_is_not_called_an_optimum(capsys):
    """Five designs: COBYLA evaluated MAXFUN times; the certificate says so, and neither the table nor
    the CLI's output calls the design an optimum (its JSON carries the certificate)."""
    res = _run(max_evaluations=5)
    assert "MAXFUN" in res.message
    assert res.certificate.verdict == "stopped at a budget" and res.certificate.residual > 1e-2
    assert "optimum" not in res.table()
    example = Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter_rock_piston.toml"
    argv = ["optimize", str(example), "--quiet", "--impact-velocity", "10 m/s", "--objective",
            "work_on_rock_per_blow", "--constraint", "piston_mass=5.7 kg", "--max-evaluations", "4",
            "--vary", "piston.collar_diameter=47mm:52mm", "--vary", "piston.front_rod_diameter=44mm:46mm"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "stopped at a budget" in out and "best found" in out and "optimum" not in out
    assert main([*argv, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["certificate"]["verdict"] == "stopped at a budget"


def test_the_baseline_is_not_certified(converged):
    """The unoptimised start (the mass 0.29 kg under its limit, no bound active) is no stationary point:
    the certificate's residual is the whole gradient's."""
    res = converged
    lo = np.array([res.vary[k]["low"] for k in KEYS])
    span = np.array([res.vary[k]["high"] - res.vary[k]["low"] for k in KEYS])

    class Stopped:
        message = "Return from COBYLA because the trust region radius reaches its lower bound."

    cert = certify_search(res.baseline, res.history, KEYS, (lo, span), Stopped, 2e-3, "work_on_rock_J",
                          lambda u: evaluate_blow(build(with_values(res.config, {
                              k: f"{float(x)!r} m" for k, x in zip(KEYS, lo + span * u, strict=True)})), V,
                              {"piston_mass": MASS}), None)
    assert cert.verdict == "not stationary" and cert.active == [] and cert.residual == 1.0
    assert not cert.converged


def test_a_negative_multiplier_is_not_certified():
    """A constraint active on the wrong side (its gradient along the objective's): the non-negative
    fit leaves the whole gradient, not a negative multiplier."""
    rec = {"constraints": {"mass": {"scaled": 0.0}}}
    cert = certify([1.0, 0.0], [[1.0, 0.0]], rec, [0.5, 0.5], ["a", "b"], method="exact")
    assert cert.verdict == "not stationary" and cert.multipliers == {"mass": 0.0} and cert.residual == 1.0
    with pytest.raises(ValueError, match="verdict must be one of"):
        type(cert)(**{**cert.to_dict(), "verdict": "optimum"})
