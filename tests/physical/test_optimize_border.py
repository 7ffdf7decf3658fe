"""The whole-drifter search's border model (:mod:`impactbar.physical.optimize_border`): a design without
a one-impact orbit is scored by its nearest success's first-order extrapolation and a constraint "the
one-impact orbit exists" negative there, not by a penalty. Checked against closed forms, and in a search
against central differences of fresh orbits (not the implicit function theorem's gradients the model
uses)."""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest
import scipy.optimize

from impactbar.physical import build, optimize_drifter, read_config, with_values
from impactbar.physical.optimize_border import EXISTENCE, border_score, existence_gradient, existence_margin
from impactbar.physical.optimize_problem import _limits

pytest.importorskip("pint")

_NO_ORBIT = "find_orbit found no periodic orbit of the drive with one impact per period; tried"


def test_a_failed_design_is_scored_by_the_first_order_model_of_its_nearest_success():
    """The objective and margins are the success's plus its gradients times the step; the existence
    margin's zero, where it falls on the segment, locates the border (``t``) and its extrapolation is
    the constraint's value, negative."""
    rng = np.random.default_rng(3)
    us, d = rng.random(3), np.array([0.1, -0.05, 0.2])
    g, G, ge = rng.normal(size=3), rng.normal(size=(2, 3)), np.array([-1.0, 0.5, -0.9])
    s = border_score(us + d, us, 1.5, [0.2, 0.4], 0.1, g, G, ge)
    assert s.objective == pytest.approx(1.5 + g @ d, rel=1e-15)
    assert s.margins == pytest.approx(np.array([0.2, 0.4]) + G @ d, rel=1e-15)
    slope = ge @ d  # -0.305: the margin 0.1 reaches 0 at t = 0.1 / 0.305
    assert s.located == "margin" and s.t == pytest.approx(0.1 / 0.305, rel=1e-14)
    assert s.exists == pytest.approx(0.1 + slope, rel=1e-14) and s.exists < 0.0
    # the margin rising, or falling too slowly to reach 0 before the design: the border at the radius,
    # half the nearest failure's distance, the constraint linear in the distance through 0 there
    far = border_score(us + d, us, 1.5, [0.2, 0.4], 0.1, g, G, -0.1 * ge)
    r = np.linalg.norm(d) / 2.0
    assert far.located == "radius" and far.radius == pytest.approx(r, rel=1e-14) and far.t == 0.5
    assert far.exists == pytest.approx(-0.1, rel=1e-14)
    again = border_score(us + 3.0 * d, us, 1.5, [0.2, 0.4], 0.1, g, G, None, radius=r)
    assert again.radius == r and again.exists == pytest.approx(0.1 * (1.0 - 3.0 * 2.0), rel=1e-14)
    assert existence_margin({"figures": {"max_multiplier": 0.9}}, 0.95) == pytest.approx(0.1 / 0.95)
    with pytest.raises(ValueError, match="two different designs"):
        border_score(us, us, 1.5, [0.2, 0.4], 0.1, g, G, ge)
    with pytest.raises(ValueError, match="radius must be positive"):
        border_score(us + d, us, 1.5, [0.2, 0.4], 0.1, g, G, ge, radius=0.0)
    with pytest.raises(ValueError, match="scale must be a positive number"):
        existence_margin({"figures": {"max_multiplier": 0.9}}, 0.0)


def test_the_existence_constraint_s_gradient_is_the_model_s_own():
    """:func:`existence_gradient` against central differences of :func:`border_score`'s existence
    constraint in the failed design (the success, its margin and the radius held), located by the
    margin, at the radius, and for a success past the unit circle (its margin falling, and not)."""
    rng = np.random.default_rng(5)
    us, d = rng.random(3), np.array([0.1, -0.05, 0.2])
    g, G = rng.normal(size=3), rng.normal(size=(2, 3))
    cases = [(0.1, np.array([-1.0, 0.5, -0.9]), math.inf), (0.1, np.array([0.3, 0.2, 0.1]), math.inf),
             (0.1, None, 0.08), (-0.05, np.array([-1.0, 0.5, -0.9]), math.inf),
             (-0.05, np.array([1.0, 0.5, 0.9]), math.inf)]
    for e, ge, radius in cases:
        s = border_score(us + d, us, 1.5, [0.2, 0.4], e, g, G, ge, radius)
        grad = existence_gradient(us + d, us, s, e, ge)
        # (the radius held: a hair inside the one scored, so that the steps either way keep it)
        held, h = s.radius * (1.0 - 1e-6) if s.located == "radius" else radius, 1e-7
        fd = [(border_score(us + d + h * v, us, 1.5, [0.2, 0.4], e, g, G, ge, held).exists
               - border_score(us + d - h * v, us, 1.5, [0.2, 0.4], e, g, G, ge, held).exists) / (2 * h)
              for v in np.eye(3)]
        assert grad == pytest.approx(np.array(fd), rel=1e-5, abs=1e-8), (s.located, e)
        assert np.any(grad != 0.0) or (e < 0.0 and ge @ d >= 0.0)
    with pytest.raises(ValueError, match="two different designs"):
        existence_gradient(us, us, s, 0.1)


VARY = {"valve.switch_out": ("19 mm", "24 mm"), "accumulator.precharge": ("7 MPa", "13 MPa")}
LO, SPAN = np.array([0.019, 7e6]), np.array([0.005, 6e6])
FKEY = "impact_power_kW"


def _failing_search(monkeypatch, **kw):
    """``optimize_drifter`` on the circuit preset where every design with its switch point past the
    start's (21.5 mm) has no orbit (the multistart's sample's too), with what each
    ``scipy.optimize.minimize`` is given at each design logged: the result, the log (the method, the
    callable's name, the design, the value; ``jac`` the constraints' Jacobian) and the true evaluation."""
    module = importlib.import_module("impactbar.physical.optimize_drifter")
    problem = importlib.import_module("impactbar.physical.optimize_problem")
    evaluate = module.evaluate_design

    def failing(drifter, *args, **kwargs):
        if drifter.si["switch_out_m"] > 0.0215 + 1e-9:
            raise ValueError(_NO_ORBIT)
        return evaluate(drifter, *args, **kwargs)

    seen, minimize = [], scipy.optimize.minimize

    def logged(fun, x0, *args, constraints=(), method=None, **kwargs):  # what the optimiser is given
        def watch(name, fn):
            def call(x):
                value = fn(x)
                seen.append((method, name, np.array(x, dtype=float), np.array(value, dtype=float)))
                return value
            return call
        watched = [dict(c, fun=watch(f"c{i}", c["fun"]), **({"jac": watch("jac", c["jac"])} if "jac" in c
                                                            else {})) for i, c in enumerate(constraints)]
        return minimize(watch("f", fun), x0, *args, constraints=watched, method=method, **kwargs)

    monkeypatch.setattr(module, "evaluate_design", failing)
    monkeypatch.setattr(problem, "evaluate_design", failing)
    monkeypatch.setattr(scipy.optimize, "minimize", logged)
    res = optimize_drifter("circuit-drifter", VARY, objective="impact_power", progress=False, **kw)
    return res, seen, evaluate


def _u_of(res) -> dict:
    return {r["id"]: (np.array([r["values"][k] for k in VARY]) - LO) / SPAN for r in res.history}


def _record_at(res, u_of, x):
    """The record of the design at ``x`` (scaled, clipped as the search clips it)."""
    return min(res.history, key=lambda r: float(np.sum((u_of[r["id"]] - np.clip(x, 0, 1)) ** 2)))


def _against_fresh_differences(res, failed, evaluate):
    """Each failed design's model (objective and margins) against its nearest success's figures
    extrapolated by central differences of fresh orbits (step 1e-4 of the spans): to 0.5 % of each
    gradient's norm times the step's (the multiplier's margin the least accurate, some 0.1 %; the
    objective's 2e-5); and the objective's step itself some 1 % of it, not the success's own value
    (a model of order zero fails here). Returns the successes' differences."""
    cfg, folder = read_config("circuit-drifter")
    limits = _limits(None, build(cfg, folder))
    by_id, u_of = {r["id"]: r for r in res.history}, _u_of(res)

    def fresh(u):
        changes = {k: f"{float(x)!r} {'m' if k == 'valve.switch_out' else 'Pa'}"
                   for k, x in zip(VARY, LO + SPAN * u, strict=True)}
        rec, _ = evaluate(build(with_values(cfg, changes), folder), limits)
        return np.array([rec["objectives"][FKEY], *(c["scaled"] for c in rec["constraints"].values())])

    gradients = {}
    for rec in failed:
        b = rec["border"]
        success = by_id[b["nearest"]]
        us, d = u_of[success["id"]], u_of[rec["id"]] - u_of[success["id"]]
        if success["id"] not in gradients:
            h = 1e-4
            gradients[success["id"]] = np.column_stack([(fresh(us + h * e) - fresh(us - h * e)) / (2 * h)
                                                        for e in np.eye(2)])
        J = gradients[success["id"]]
        at = np.array([success["objectives"][FKEY], *(c["scaled"] for c in success["constraints"].values())])
        model, by_differences = np.array([b["objective"], *b["margins"]]), at + J @ d
        bound = 5e-3 * np.linalg.norm(J, axis=1) * np.linalg.norm(d) + 1e-9
        assert np.all(np.abs(model - by_differences) <= bound), (model - by_differences) / bound
        assert abs(J[0] @ d) > 1e-3 * abs(at[0])
    return gradients


def test_a_search_meeting_the_no_orbit_band_sees_the_nearest_success_s_extrapolation(monkeypatch):
    """COBYLA on the circuit preset where every design with its switch point past the start's (21.5 mm)
    has no orbit: at each such design it meets, it is scored neither 1 nor -1 but by the nearest
    design with an orbit extrapolated, to the gradient's accuracy the same as central differences of
    fresh orbits at that design give (step 1e-4 of the spans), and the existence constraint there is
    negative, falling on with the distance, while it is met at every design with an orbit."""
    res, seen, evaluate = _failing_search(monkeypatch, max_evaluations=12)
    by_id, u_of = {r["id"]: r for r in res.history}, _u_of(res)
    ref = abs(res.history[0]["objectives"][FKEY])
    failed = [r for r in res.history if not r["ok"]]
    assert len(failed) >= 3 and all("border" in r for r in failed)
    for _, name, x, value in seen:  # COBYLA's view: no penalty at a failed design, the model's scores
        rec = _record_at(res, u_of, x)
        if rec["ok"]:
            assert name != "c1" or value >= 0.0
            continue
        b = rec["border"]
        if name == "f":
            assert value != 1.0 and value == -b["objective"] / ref
        elif name == "c0":
            assert not np.all(value == -1.0) and np.array_equal(value, b["margins"])
        else:
            assert value == b[EXISTENCE] < 0.0
    assert {"f", "c0", "c1"} <= {n for _, n, _, v in seen}
    radius = {}
    for rec in failed:
        b = rec["border"]
        success = by_id[b["nearest"]]
        earlier = [r for r in res.history[:res.history.index(rec)] if r["ok"]]
        assert success is min(earlier, key=lambda r: float(np.sum((u_of[r["id"]] - u_of[rec["id"]]) ** 2)))
        # the border at half the nearest failure's distance so far from this success (the fake failure
        # is no multiplier's border: the margin stays positive along the step)
        e = 1.0 - success["figures"]["max_multiplier"]  # (the margin's scale 1)
        length = float(np.linalg.norm(u_of[rec["id"]] - u_of[success["id"]]))
        radius[success["id"]] = min(radius.get(success["id"], math.inf), length / 2.0)
        assert b["located"] == "radius" and b["radius"] == pytest.approx(radius[success["id"]], rel=1e-14)
        assert b[EXISTENCE] == pytest.approx(e * (1.0 - length / radius[success["id"]]), rel=1e-12)
        assert b[EXISTENCE] <= -e < 0.0
    _against_fresh_differences(res, failed, evaluate)
    assert res.optimum["feasible"] and res.optimum["values"]["valve.switch_out"] <= 0.0215 + 1e-9


def test_the_polish_meeting_the_no_orbit_band_sees_the_border_model_and_its_gradients(monkeypatch):
    """The multistart's polish (SLSQP) on the same problem: at each failed design it meets it is given
    neither the penalty's objective 1 nor margins -1 but the border model's scores, the existence
    constraint negative there (met, at least 0, at each design with an orbit), and as the
    constraints' Jacobian there the model's own: the nearest success's gradients (of the kind the
    model used) and :func:`existence_gradient`'s; the model's scores agree with central differences
    of fresh orbits (a model of order zero fails)."""
    res, seen, evaluate = _failing_search(monkeypatch, method="multistart", sample=8, local_starts=1,
                                          max_evaluations=14, polish=8, seed=3)
    u_of = _u_of(res)
    slsqp = [s for s in seen if s[0] == "SLSQP"]
    met = [(name, value, _record_at(res, u_of, x)) for _, name, x, value in slsqp]
    start = next(m for m in met if m[0] == "f")  # (the polish's objective scaled by its start's)
    ref = abs(start[2]["objectives"][FKEY])
    failed = {rec["id"]: rec for *_, rec in met if not rec["ok"]}
    assert start[1] == -1.0 and failed, "the polish met no design without an orbit: make the problem meet one"
    J = _against_fresh_differences(res, list(failed.values()), evaluate)
    assert {n for n, _, rec in met if not rec["ok"]} == {"f", "c0", "jac"}
    for name, value, rec in met:
        if rec["ok"]:
            assert name != "c0" or value[-1] >= 0.0
            continue
        b = rec["border"]
        if name == "f":
            assert value != 1.0 and value == -b["objective"] / ref
        elif name == "c0":
            assert not np.all(value == -1.0) and np.array_equal(value[:-1], b["margins"])
            assert value[-1] == b[EXISTENCE] < 0.0
        else:  # the Jacobian: the margins' rows the nearest success's, the last the existence's
            assert np.any(value[:-1] != 0.0) and np.any(value[-1] != 0.0)
            assert np.all(np.isfinite(value)) and value.shape == (len(b["margins"]) + 1, 2)
    for name, value, rec in met:  # the Jacobian's margins against the fresh orbits' differences
        if name == "jac" and not rec["ok"]:
            Js = J[rec["border"]["nearest"]][1:]
            assert np.all(np.abs(value[:-1] - Js) <= 5e-3 * np.linalg.norm(Js, axis=1)[:, None] + 1e-9)
