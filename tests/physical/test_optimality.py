"""The first-order (KKT) certificate of ``optimize_drifter``'s reported design, on the circuit's ideal
limit (seconds a run): a converged search is certified with the piston's mass active and its multiplier
the work a kilogram more buys; a search cut at its budget, and the unoptimised baseline, are not."""

from __future__ import annotations

import functools
import json
import math
import os
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
from drifter_optimum import documented_problem  # noqa: E402
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
    the CLI's output calls the design an optimum (its JSON carries the certificate). (``tol`` 1e-4: at
    the default 2e-3 the fifth design, 1.6e-4 of its scale under the mass limit, is within the
    search's resolution of it and stationary there, KKT residual 0.0018, and is certified.)"""
    res = _run(max_evaluations=5, tol=1e-4)
    assert "MAXFUN" in res.message or "Maximum number of function evaluations" in res.message  # (older scipy)
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


def _plane(margin):
    """The largest ``u0 + u1`` with ``u0 + u1 <= 1`` (closed form: any point of that edge, the
    multiplier 1): the design on the diagonal whose scaled margin is ``margin``, its record and a
    blow of fresh figures."""
    u = np.full(2, (1.0 - margin) / 2)

    def blow(v):
        return {"objectives": {"f": float(v[0] + v[1])},
                "constraints": {"c": {"scaled": float(1.0 - v[0] - v[1])}}}

    rec = {"values": {"a": u[0], "b": u[1]}, **blow(u)}
    return rec, blow


class _Stopped:
    message = "Return from COBYLA because the trust region radius reaches its lower bound."


def test_a_constraint_within_the_search_resolution_is_active():
    """A margin of 5e-4 (above the fixed band 1e-4, under COBYLA's last step 2e-3 times the
    constraint's gradient norm sqrt 2): the search cannot tell it from active, so it is, and the
    design is certified with the closed form's multiplier 1; a margin of 5e-3 is beyond the search's
    resolution, and without a resolution (SLSQP's) the fixed band alone decides."""
    scaling = (np.zeros(2), np.ones(2))
    rec, blow = _plane(5e-4)
    cert = certify_search(rec, [], ["a", "b"], scaling, _Stopped, 2e-3, "f", blow, None)
    assert cert.verdict == "converged" and cert.active == ["c"] and cert.residual < 1e-6
    assert cert.multipliers["c"] == pytest.approx(1.0, rel=1e-6)
    assert certify_search(rec, [], ["a", "b"], scaling, _Stopped, 2e-3, "f", blow, None,
                          resolution=0.0).verdict == "not stationary"
    far, blow = _plane(5e-3)
    cert = certify_search(far, [], ["a", "b"], scaling, _Stopped, 2e-3, "f", blow, None)
    assert cert.verdict == "not stationary" and cert.active == [] and cert.residual == 1.0
    with pytest.raises(ValueError, match="resolution must be a finite number >= 0"):
        certify([1.0, 1.0], [[-1.0, -1.0]], rec, [0.5, 0.5], ["a", "b"], method="exact", resolution=-1.0)


def _branches(v, drop: float) -> dict:
    """A design's fresh figures on a function with a jump: ``f = u0 + u1`` and the scaled margin
    ``c = 1 - u0 - u1`` smooth, both less ``drop`` past ``u0 = 0.3`` (another branch)."""
    jump = drop if v[0] > 0.3 else 0.0
    return {"ok": True, "values": {"a": float(v[0]), "b": float(v[1])},
            "objectives": {"f": float(v[0] + v[1] - jump)},
            "constraints": {"c": {"scaled": float(1.0 - v[0] - v[1] - jump)}}}


def test_a_jump_in_the_figures_of_a_design_within_the_search_s_last_step_is_a_border():
    """At ``u = (0.2995, 0.2)`` (no constraint active: KKT residual 1) a design of the search 1e-3
    away lies past a jump of 0.01 in the objective and the margin: 0.01 against the 1e-3 the gradient
    predicts, 7 times the most it lets them change over that step (sqrt 2 times 1e-3); a border, not
    "not stationary". A smooth neighbour (no jump, or the same jump 0.005 beyond the search's reach
    of twice its last step 2e-3) is none; nor are figures that differ by the orbits' accuracy."""
    scaling, u = (np.zeros(2), np.ones(2)), np.array([0.2995, 0.2])
    rec, blow = _branches(u, 0.0), (lambda v: _branches(v, 0.01))
    history = [rec, _branches(u + [1e-3, 0.0], 0.01), _branches(u - [1e-3, 0.0], 0.01)]
    cert = certify_search(rec, history, ["a", "b"], scaling, _Stopped, 2e-3, "f", blow, None)
    assert cert.residual == pytest.approx(1.0, abs=1e-6) and cert.verdict == "stopped at a border"
    assert cert.border.startswith("a jump: the objective changes by -0.009 over 0.001 (scaled) where its "
                                  "gradient predicts 0.001")
    assert "; figures jump beyond: a jump: the objective" in str(cert)
    smooth = [rec, _branches(u + [1e-3, 0.0], 0.0), _branches(u + [5e-3, 0.0], 0.01)]
    cert = certify_search(rec, smooth, ["a", "b"], scaling, _Stopped, 2e-3, "f", blow, None)
    assert cert.verdict == "not stationary" and cert.border == ""
    # (a neighbour 1e-7 away whose figures differ by 1e-9 relative from the gradient's: noise)
    noisy = _branches(u + [1e-7, 0.0], 0.0)
    noisy["objectives"]["f"] *= 1.0 + 1e-9
    cert = certify_search(rec, [rec, noisy], ["a", "b"], scaling, _Stopped, 2e-3, "f", blow, None)
    assert cert.verdict == "not stationary"
    with pytest.raises(ValueError, match="objective: the design's objective must be given with neighbours"):
        certify([1.0, 1.0], [[-1.0, -1.0]], rec, u, ["a", "b"], method="exact", neighbours=history)


def test_a_variable_within_the_search_resolution_of_its_bound_is_at_it():
    """``u0`` 5e-4 under its upper bound, the objective ``u0`` alone: at the bound within COBYLA's
    last step 2e-3, its multiplier the whole gradient."""
    cert = certify([1.0, 0.0], [[0.0, 1.0]], {"constraints": {"c": {"scaled": 0.5}}}, [1.0 - 5e-4, 0.5],
                   ["a", "b"], method="exact", resolution=2e-3)
    assert cert.verdict == "converged" and cert.bounds == {"a": "high"} and cert.multipliers["a high"] == 1.0
    assert certify([1.0, 0.0], [[0.0, 1.0]], {"constraints": {"c": {"scaled": 0.5}}}, [1.0 - 5e-4, 0.5],
                   ["a", "b"], method="exact").verdict == "not stationary"


def test_an_infeasible_start_is_searched_from_with_start_any():
    """The piston 5.31 kg against a limit of 5 kg: refused by default, searched from with
    ``start="any"``, the reported design feasible (the mass at its limit, the baseline not)."""
    with pytest.raises(ValueError, match="infeasible start: constraint piston_mass"):
        _run(5.0, max_evaluations=40)
    res = _run(5.0, max_evaluations=40, start="any")
    assert not res.baseline["feasible"] and res.optimum["feasible"]
    assert res.optimum["constraints"]["piston_mass"]["value"] <= 5.0 * (1 + 1e-8)
    assert res.certificate.verdict != "infeasible" and "no feasible design" not in res.message


def test_a_search_without_a_feasible_design_says_so():
    """A limit of 4 kg, under the lightest piston of the bounds (every diameter at its low bound:
    7850 kg/m3 x pi/4 x sum L d^2 = 4.415 kg): no design is feasible, the design reported is the
    least infeasible, that lightest piston, and the certificate, the message and the table say it is
    infeasible."""
    res = _run(4.0, max_evaluations=40, start="any")
    lightest = 7850.0 * math.pi / 4 * sum(le * d ** 2 for le, d in zip(LENGTHS, (20e-3, 44e-3, 27.5e-3),
                                                                          strict=True))
    assert not res.optimum["feasible"] and res.certificate.verdict == "infeasible"
    assert "no feasible design found" in res.message
    assert res.optimum["constraints"]["piston_mass"]["value"] == pytest.approx(lightest, rel=1e-3)
    assert res.table().splitlines()[0].split()[-1] == "infeasible"
    with pytest.raises(ValueError, match="start must be 'feasible' or 'any'; got 'none'"):
        _run(4.0, start="none")


def _disc():
    """The largest ``u0 + 2 u1`` in the disc ``u0**2 + u1**2 <= 1`` (closed form: ``(1, 2) / sqrt 5``,
    the multiplier of the scaled margin ``1 - |u|**2`` is ``sqrt 5 / 2``): objective, margins, exact
    gradients, and a record of a design."""
    def objective(u):
        return float(u[0] + 2.0 * u[1])

    def margins(u):
        return np.array([1.0 - float(np.dot(u, u))])

    def gradients(u):
        return np.array([1.0, 2.0]), -2.0 * np.asarray(u, dtype=float)[None, :]

    def record(u):
        return {"feasible": True, "constraints": {"c": {"scaled": float(margins(u)[0])}}}

    return objective, margins, gradients, record


def test_the_polish_takes_a_search_s_design_to_a_certified_optimum():
    """From a design 1.4 % of the scale inside the disc (where COBYLA's last step of 2e-3 cannot see
    the constraint: the certificate says not stationary, residual 0.02), the polish reaches the
    closed form's optimum to 1e-6, certified converged with the multiplier sqrt 5 / 2; a start
    whose every step has no value (no orbit) is kept, and a budget of one design says so."""
    from impactbar.physical.optimality import stopped_at_budget
    from impactbar.physical.optimize_polish import polish

    objective, margins, gradients, record = _disc()
    u = np.array([0.44, 0.89])
    cert = certify(*gradients(u), record(u), u, ["a", "b"], method="exact", resolution=2e-3)
    assert cert.verdict == "not stationary" and cert.residual > 1e-2
    res = polish(objective, margins, gradients, u, designs=30)
    assert res.improved and res.nfev <= 30
    np.testing.assert_allclose(res.x, np.array([1.0, 2.0]) / math.sqrt(5.0), atol=1e-6)
    assert res.fun == pytest.approx(math.sqrt(5.0), rel=1e-8) and margins(res.x)[0] >= -1e-8
    cert = certify(*gradients(res.x), record(res.x), res.x, ["a", "b"], method="exact")
    assert cert.verdict == "converged" and cert.residual < 1e-6 and cert.active == ["c"]
    assert cert.multipliers["c"] == pytest.approx(math.sqrt(5.0) / 2.0, rel=1e-5)
    blocked = polish(lambda v: objective(v) if np.array_equal(v, u) else None, margins, gradients, u,
                     designs=30)
    assert not blocked.improved and np.array_equal(blocked.x, u) and blocked.fun == objective(u)
    spent = polish(objective, margins, gradients, u, designs=1)
    assert spent.nfev == 1 and stopped_at_budget(spent)
    with pytest.raises(ValueError, match=r"^designs must be an integer >= 1"):
        polish(objective, margins, gradients, u, designs=0)


def test_the_polish_scores_a_design_without_a_value_by_the_border_model_given():
    r"""The largest :math:`u_0 + 2u_1` in the unit disc where only :math:`u_0 + u_1 \le 1.3` has values
    (no orbit beyond; the disc's optimum :math:`(1, 2)/\sqrt 5` lies there): with the far side scored by
    a border model (the objective and the disc's margin extrapolated, exact here) and the existence
    constraint :math:`1.3 - u_0 - u_1` with its gradient, the polish ends where both hold, at the
    closed form's corner :math:`u_0 = (1.3 - \sqrt{0.31})/2` to 1e-6, a design with a value; the
    constraint without its gradient is refused in one line."""
    from impactbar.physical.optimize_polish import polish

    objective, margins, gradients, _ = _disc()
    seen = []

    def valued(v):
        return objective(v) if v[0] + v[1] <= 1.3 + 1e-9 else None

    def border(v):
        seen.append(v.copy())
        return objective(v), margins(v)

    res = polish(valued, margins, gradients, [0.4, 0.8], designs=40, border=border,
                 existence=lambda v: 1.3 - v[0] - v[1], d_existence=lambda v: np.array([-1.0, -1.0]))
    corner = (1.3 - math.sqrt(0.31)) / 2.0
    assert res.improved and valued(res.x) is not None
    np.testing.assert_allclose(res.x, [corner, 1.3 - corner], atol=1e-6)
    assert all(v[0] + v[1] > 1.3 + 1e-9 for v in seen)  # (asked only where there is no value)
    with pytest.raises(ValueError, match=r"^existence and d_existence: give both"):
        polish(valued, margins, gradients, [0.4, 0.8], designs=40, existence=lambda v: 1.0)


def test_the_polish_stops_at_the_first_best_iterate_that_is_certified():
    """With ``stationary`` (the certificate's test at each best iterate, its gradients those SLSQP asks
    for), the polish of the disc problem stops at the first iterate whose KKT residual is at most the
    tolerance, whatever budget is left: fewer designs than SLSQP's own stop, the residual returned is
    that of :func:`certify` at the design returned (recomputed here), and the design is the closed
    form's to the accuracy that residual implies; a tolerance that no iterate meets leaves SLSQP's
    path and stop unchanged (the same designs to the bit)."""
    from impactbar.physical.optimality import stopped_at_budget
    from impactbar.physical.optimize_polish import polish, polish_search

    objective, margins, gradients, record = _disc()
    u = np.array([0.44, 0.89])
    asked = []

    def stationary(tol):
        def test(v, g, G):
            asked.append(v.copy())
            r = certify(g, G, record(v), v, ["a", "b"], method="exact").residual
            return r if r <= tol else None
        return test

    full = polish(objective, margins, gradients, u, designs=60)
    early = polish(objective, margins, gradients, u, designs=60, stationary=stationary(1e-2))
    assert early.success and not stopped_at_budget(early) and early.message.startswith("stationary")
    assert early.improved and early.nfev < full.nfev and early.residual <= 1e-2
    again = certify(*gradients(early.x), record(early.x), early.x, ["a", "b"], method="exact")
    assert again.residual == early.residual and again.verdict == "converged"
    assert np.linalg.norm(early.x - np.array([1.0, 2.0]) / math.sqrt(5.0)) < 0.1
    assert all(objective(v) <= early.fun for v in asked)  # (asked at best iterates alone)
    never = polish(objective, margins, gradients, u, designs=60, stationary=stationary(-1.0))
    assert never.residual is None and np.array_equal(never.x, full.x) and never.nfev == full.nfev
    named = r"^tolerance must be (a (finite )?real number )?in \[0, inf\); got "  # (the name, the range)
    for bad in (-1e-3, float("nan"), float("inf"), True, "0.01"):
        with pytest.raises(ValueError, match=named):
            polish_search(None, None, None, [], {}, "f", designs=10, ftol=1e-9, tolerance=bad)


def test_the_polish_runs_slsqp_on_one_blas_thread_whatever_the_caller_s():
    """SLSQP's iterates differ in their last bits between one and two OpenBLAS threads (the documented
    multistart's polish, replayed from its stored designs: its third iterate's pre-charge 0 against
    1.1e-17, and a budget of 40 designs then ends on other designs, certified or not), and a process
    that started a dask cluster before scipy loaded its OpenBLAS has one (distributed sets
    OPENBLAS_NUM_THREADS=1 for its workers in the caller's environment). The polish takes one thread
    itself: its callbacks see one BLAS thread under a caller's two, and the caller's two after it."""
    threadpoolctl = pytest.importorskip("threadpoolctl")
    from impactbar.physical.optimize_polish import polish

    objective, margins, gradients, _ = _disc()
    seen = []

    def counted(v):  # (called by SLSQP alone; the objective and margins at the start before it too)
        seen.extend(i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas")
        return gradients(v)

    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):
        res = polish(objective, margins, counted, np.array([0.44, 0.89]), designs=30)
        after = [i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"]
    assert res.improved and seen and set(seen) == {1}
    assert after and set(after) == {min(2, os.cpu_count() or 1)}

@functools.cache
def _documented_certificate():
    """The page's design of the search with the blows ended at the law's window
    (``drifter_optimum.WINDOW_OPTIMUM``; the callers build under ``window_end``) scaled, its fresh
    record, the objective's and the scaled margins' gradients by central differences of fresh orbits
    (step 1e-4 of the spans) and its certificate at COBYLA's resolution 2e-3 (computed once for the
    slow tests that use them)."""
    from drifter_optimum import WINDOW_OPTIMUM as OPTIMUM

    from impactbar.physical.optimality import central_gradients

    *_, keys, _, _, fresh, scaled = documented_problem()
    fkey = "drilling_rate_per_kW"
    u = scaled(OPTIMUM)
    rec = fresh(u)[0]

    def point(v):
        r = fresh(v)[0]
        return [r["objectives"][fkey], *(c["scaled"] for c in r["constraints"].values())]

    g, G, how = central_gradients(point, u, 1e-4)
    return u, rec, g, G, certify(g, G, rec, u, keys, method=how, resolution=2e-3)


@pytest.mark.slow
def test_the_certificate_s_gradients_refine_their_step_at_a_border(monkeypatch):
    """The whole drifter's best design found by the multistart (docs/optimising_a_drifter.md, to the
    digits printed there) lies within 1e-3 of its span of designs without an orbit (the front rod 1e-3
    thinner has none): the implicit function theorem's differences at their default step straddle the
    border (the switch point's derivative of the drilling rate per kilowatt 48 times too large, of
    the other sign); refined, the objective's and the drilling rate's gradients agree with central
    differences of fresh orbits (1e-3 of the span; forward for the front rod) to 1 %, and the
    certificate finds the drilling rate binding (multiplier 0.28), where the default step's left no
    multiplier and a residual of 1."""
    from drifter_optimum import window_end

    window_end(monkeypatch)  # (where the page's figures of this design were measured)
    from impactbar.physical.optimize_problem import _design_gradient, _refined_gradient

    cfg, folder, spec, keys, span, limits, fresh, scaled = documented_problem()
    fkey = "drilling_rate_per_kW"
    best = ["47.77 mm", "46.593 mm", "41.383 mm", "0.0796 L", "23.57 mm", "8 MPa"]
    u = scaled(dict(zip(keys, best, strict=True)))
    rec, orbit = fresh(u)
    default = _design_gradient(cfg, folder, rec, orbit, spec, limits, fkey, span)
    g, G = _refined_gradient(cfg, folder, rec, orbit, spec, limits, fkey, span)
    h = 1e-3
    for j, side in ((1, "forward"), (2, "central"), (4, "central")):
        up = fresh(u + h * np.eye(6)[j])[0]
        down = rec if side == "forward" else fresh(u - h * np.eye(6)[j])[0]
        drill = [r["constraints"]["min_drilling_rate"]["scaled"] for r in (up, down)]
        fd = np.array([up["objectives"][fkey] - down["objectives"][fkey], drill[0] - drill[1]])
        fd /= h if side == "forward" else 2 * h
        np.testing.assert_allclose([g[j], G[-1][j]], fd, rtol=1e-2, atol=1e-5)
    assert default[0][4] < -20 * g[4] < 0.0  # (the switch point's: -0.088 against 0.0018)
    rec["feasible"] = True  # (to the digits printed the design misses the drilling rate by 3e-5 of its scale)
    cert = certify(g, G, rec, u, keys, method="refined", resolution=2e-3)
    assert "min_drilling_rate" in cert.active and cert.multipliers["min_drilling_rate"] == pytest.approx(0.28,
                                                                                                          abs=0.01)
    assert cert.residual < 0.2
    old = certify(*default, rec, u, keys, method="default", resolution=2e-3)
    assert old.multipliers["min_drilling_rate"] == 0.0 and old.residual > 0.99


@pytest.mark.slow
def test_the_documented_design_lies_before_a_border_of_its_orbit(monkeypatch):
    """Why the page's design (six variables, the drilling rate held) is not certified: its KKT residual
    is the design's, not its gradients' or its active set's. Central differences of fresh orbits
    (step 1e-4 of the spans) give the page's residual, active set and multiplier; along the projected
    gradient (the drilling rate's margin held to first order) fresh orbits rise as that gradient says
    as far as 0.006 of the spans, have no one-impact orbit at 0.008 and, at 0.01, one on another
    branch that drills slower than the limit: the best design of its branch lies at that border,
    where the drilling rate jumps, not at a smooth stationary point. The page's figures of it to the
    digits it prints."""
    from drifter_optimum import window_end

    window_end(monkeypatch)  # (where the page's figures of this design were measured)
    import re

    *_, fresh, _ = documented_problem()
    fkey = "drilling_rate_per_kW"
    u, rec, g, G, cert = _documented_certificate()
    text = re.sub(r"\s+", " ", (Path(__file__).resolve().parents[2] / "docs" / "optimising_a_drifter.md")
                  .read_text())
    m = re.search(r"fixed window, the default before .*? the same search reported .*?"
                  r"\(\"stopped at a budget\", KKT residual ([0-9.]+), the drilling rate active with the "
                  r"multiplier ([0-9.]+)\)", text)
    assert cert.active == ["min_drilling_rate"] and not cert.bounds
    assert cert.residual == pytest.approx(float(m[1]), abs=5e-4)
    assert cert.multipliers["min_drilling_rate"] == pytest.approx(float(m[2]), abs=5e-3)
    p = g + cert.multipliers["min_drilling_rate"] * G[-1]  # the projected gradient (the limit held)
    assert abs(p @ G[-1]) < 1e-12 * np.linalg.norm(p) * np.linalg.norm(G[-1])
    m = re.search(r"raises the objective by ([0-9.]+) m/min/kW per span\) fresh orbits follow that "
                  r"first-order rise to ([0-9.]+) % as far as ([0-9.]+) of the spans \(\+([0-9.]+) %, the "
                  r"drilling rate unchanged\); at ([0-9.]+) of them the design has no one-impact orbit, "
                  r"and at ([0-9.]+) one on another branch, drilling ([0-9.]+) m/min slower", text)
    assert m is not None, "the page's account of the border is gone; update this test with the text"
    f0, rate0 = rec["objectives"][fkey], rec["objectives"]["drilling_rate_m_min"]
    assert float(m[1]) == pytest.approx(np.linalg.norm(p), abs=5e-5)
    s = float(m[3])
    near = fresh(u + s * p / np.linalg.norm(p))[0]
    rise = near["objectives"][fkey] - f0
    assert abs(rise / (s * np.linalg.norm(p)) - 1.0) <= float(m[2]) / 100
    assert 100 * rise / f0 == pytest.approx(float(m[4]), abs=5e-4)
    assert near["feasible"] and near["objectives"]["drilling_rate_m_min"] == pytest.approx(rate0, abs=1e-5)
    with pytest.raises(ValueError, match="no periodic orbit of the drive with one impact per period"):
        fresh(u + float(m[5]) * p / np.linalg.norm(p))
    far = fresh(u + float(m[6]) * p / np.linalg.norm(p))[0]
    assert rate0 - far["objectives"]["drilling_rate_m_min"] == pytest.approx(float(m[7]), abs=5e-5)
    assert not far["feasible"] and far["objectives"][fkey] < f0


def _recontact(point):
    """The lattice blow's re-contact of a converged circuit orbit ``point`` (theory §11, "The coupled
    blow"; the contact's rule, :mod:`impactbar.laws.rodrock.blow`: contact again from the first step
    that starts with the summed gap closed): the step ``k`` of the first re-contact after the
    piston separates and its margin, the fraction of step ``k - 1`` by which the gap had closed at that
    step's end, ``-(gap + closing) / |closing|`` in steps (at 0 the gap closes at the step's end, and
    past it the re-contact falls a step later). The blow is re-run one step at a time through the same
    compiled loop, its figures checked against the orbit's (to 1e-9: the loop's sums run in chunks
    there)."""
    import impactbar.laws.rodrock.coupled as coupled

    steps, log = coupled._steps, []

    def one_at_a_time(grid, F, G, bs, bp, gap, drive, record, bounds=None):
        if record:  # (the waves arriving ahead, read on copies)
            return steps(grid, F, G, bs, bp, gap, drive, record, bounds)
        jc, Z, shank = grid.piston_cells - 1, grid.Z, 0.0
        for i in range(drive.size):  # the free ends' closing speed times the step (contact_step's)
            closing = (-2.0 * G[jc + 1] / Z[jc + 1] - 2.0 * F[jc] / Z[jc]) * grid.cell_time
            before = float(gap[0])
            gap, _, shank = steps(grid, F, G, bs, bp, gap, drive[i:i + 1], False, bounds)
            log.append((before, closing, shank))
        return gap, np.zeros((0, F.size)), shank

    problem = point.orbit.problem
    problem._last = None  # (the flights it keeps: integrated again)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(coupled, "_steps", one_at_a_time)
        pieces = problem.flights(problem.unknowns(point.orbit))
    blow = next(p for p in pieces if hasattr(p, "record")).record.blow
    kept = next(p for p in point._pieces if hasattr(p, "record")).record.blow
    assert blow.work_on_rock == pytest.approx(kept.work_on_rock, rel=1e-9)  # (sums in another order)
    before, closing, shank = np.array(log).T
    on = shank != 0.0
    k = int(np.flatnonzero(on[1:] & ~on[:-1])[0]) + 1
    return k, float(-(before[k - 1] + closing[k - 1]) / abs(closing[k - 1]))


@pytest.mark.slow
def test_the_border_is_the_lattice_blow_s_recontact_moving_a_step(monkeypatch):
    """The border along the page's design's projected gradient is the lattice blow's re-contact of the
    piston on the shank (after it separates, some 71 steps into the blow) moving one step later: the
    gap's closing at the end of the step before it (:func:`_recontact`'s margin) goes to 0 smoothly
    there, its gradient (central differences of continued orbits, step 1e-4 of the spans) predicts
    the border's distance along the projected gradient to 2e-6 of the spans against a bisection of
    orbits continued along it (to 1e-6), and the other branch's orbit beyond (0.01) re-contacts a step
    later. Counted active with the drilling rate, the border leaves the KKT residual at 0.060 (from
    0.074): the design is not stationary on that border either; and at its margin it is not within
    COBYLA's last step (2e-3 of the spans) of it. With 16 cells a piston (the example's 8) the orbit
    goes on through the border to 0.01 (the drilling rate within 5e-5 m/min, 2e-3 m/min above the
    8 cells' figure): the border is the lattice's."""
    from drifter_optimum import window_end

    window_end(monkeypatch)  # (where the page's figures of this design were measured)
    cfg, folder, spec, keys, span, *_ = documented_problem()
    u, rec, g, G, cert = _documented_certificate()
    p = g + cert.multipliers["min_drilling_rate"] * G[-1]
    ph = p / np.linalg.norm(p)
    lo = np.array([spec[k]["low"] for k in keys])

    def orbit(v, guess=None):
        changes = {k: f"{float(x)!r} {spec[k]['unit']}" for k, x in zip(keys, lo + span * v, strict=True)}
        return build(with_values(cfg, changes), folder).orbit(guess)

    base = orbit(u)
    k0, m0 = _recontact(base)
    h, Gm = 1e-4, []
    for e in np.eye(u.size) * 1e-4:
        (ka, ma), (kb, mb) = _recontact(orbit(u + e, base)), _recontact(orbit(u - e, base))
        assert ka == kb == k0
        Gm.append((ma - mb) / (2.0 * h))
    Gm = np.array(Gm)
    predicted = -m0 / float(Gm @ ph)  # the margin's zero along the projected gradient (spans)
    a, b = 0.9 * predicted, 1.1 * predicted
    last = orbit(u + a * ph, base)
    assert _recontact(last)[0] == k0
    while b - a > 1e-6:
        s = 0.5 * (a + b)
        try:
            trial = orbit(u + s * ph, last)
        except ValueError:
            b = s
            continue
        if _recontact(trial)[0] == k0:
            a, last = s, trial
        else:
            b = s
    print(f"margin {m0:.6g} steps, its gradient's norm {np.linalg.norm(Gm):.6g}; border predicted at "
          f"{predicted:.7f}, bisected in [{a:.7f}, {b:.7f}] of the spans")
    assert abs(predicted - 0.5 * (a + b)) < 2e-6
    assert _recontact(orbit(u + 0.01 * ph))[0] == k0 + 1
    assert m0 > 2e-3 * np.linalg.norm(Gm)  # (not within COBYLA's last step of the border)
    fine = dict.fromkeys(["rock.cells_per_piston"], 16)  # the lattice refined: no border there
    rates = []
    for s in (0.0, 0.5 * predicted, predicted, 0.01):
        changes = {k: f"{float(x)!r} {spec[k]['unit']}" for k, x in zip(keys, lo + span * (u + s * ph),
                                                                        strict=True)}
        rates.append((last := build(with_values(cfg, changes | fine), folder).orbit(
            last if s else None)).rock()["drilling_rate_m_min"])
    assert np.ptp(rates) < 5e-5 and rates[0] - rec["objectives"]["drilling_rate_m_min"] > 2e-3
    with_border = dict(rec, constraints={**rec["constraints"], "lattice re-contact": {"scaled": 0.0}})
    both = certify(g, np.vstack([G, Gm]), with_border, u, keys, method="central differences",
                   resolution=2e-3)
    print(both)
    assert both.active == ["min_drilling_rate", "lattice re-contact"] and not both.converged
    assert both.residual == pytest.approx(0.060, abs=1e-3)
    import re

    text = re.sub(r"\s+", " ", (Path(__file__).resolve().parents[2] / "docs" / "optimising_a_drifter.md")
                  .read_text())
    m = re.search(r"the gap closes ([0-9.]+) % of a step before the end of the step before the re-contact; "
                  r"along the projected gradient that margin falls smoothly to 0 at ([0-9.]+) of the spans.*?"
                  r"leaves the KKT residual at ([0-9.]+):", text)
    assert m is not None, "the page's account of the border's mechanism is gone; update this test with it"
    assert re.search(rf"meets it again some {k0} steps into the blow", text)
    assert (float(m[1]), float(m[2]), float(m[3])) == (round(100 * m0, 2), round(predicted, 4),
                                                       round(both.residual, 3))
