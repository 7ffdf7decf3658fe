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
from impactbar.physical.optimize_border import EXISTENCE, border_score, existence_margin
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


VARY = {"valve.switch_out": ("19 mm", "24 mm"), "accumulator.precharge": ("7 MPa", "13 MPa")}
LO, SPAN = np.array([0.019, 7e6]), np.array([0.005, 6e6])


def test_a_search_meeting_the_no_orbit_band_sees_the_nearest_success_s_extrapolation(monkeypatch):
    """COBYLA on the circuit preset where every design with its switch point past the start's (21.5 mm)
    has no orbit: at each such design it meets, it is scored neither 1 nor -1 but by the nearest
    design with an orbit extrapolated, to the gradient's accuracy the same as central differences of
    fresh orbits at that design give (step 1e-4 of the spans), and the existence constraint there is
    negative, falling on with the distance, while it is met at every design with an orbit."""
    module = importlib.import_module("impactbar.physical.optimize_drifter")
    evaluate = module.evaluate_design

    def failing(drifter, *args, **kwargs):
        if drifter.si["switch_out_m"] > 0.0215 + 1e-9:
            raise ValueError(_NO_ORBIT)
        return evaluate(drifter, *args, **kwargs)

    seen, minimize = [], scipy.optimize.minimize

    def logged(fun, x0, *args, constraints=(), **kwargs):  # what COBYLA is given at each design
        def watch(name, fn):
            def call(x):
                value = fn(x)
                seen.append((name, np.array(x, dtype=float), np.array(value, dtype=float)))
                return value
            return call
        watched = [dict(c, fun=watch(f"c{i}", c["fun"])) for i, c in enumerate(constraints)]
        return minimize(watch("f", fun), x0, *args, constraints=watched, **kwargs)

    monkeypatch.setattr(module, "evaluate_design", failing)
    monkeypatch.setattr(scipy.optimize, "minimize", logged)
    res = optimize_drifter("circuit-drifter", VARY, objective="impact_power", max_evaluations=12,
                           progress=False)
    fkey = "impact_power_kW"
    by_id = {r["id"]: r for r in res.history}
    u_of = {r["id"]: (np.array([r["values"][k] for k in VARY]) - LO) / SPAN for r in res.history}
    ref = abs(res.history[0]["objectives"][fkey])
    failed = [r for r in res.history if not r["ok"]]
    assert len(failed) >= 3 and all("border" in r for r in failed)
    for name, x, value in seen:  # COBYLA's view: no penalty at a failed design, the model's scores
        rec = min(res.history, key=lambda r: float(np.sum((u_of[r["id"]] - np.clip(x, 0, 1)) ** 2)))
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
    assert {"f", "c0", "c1"} <= {n for n, _, v in seen}

    cfg, folder = read_config("circuit-drifter")
    limits = _limits(None, build(cfg, folder))

    def fresh(u):
        changes = {k: f"{float(x)!r} {'m' if k == 'valve.switch_out' else 'Pa'}"
                   for k, x in zip(VARY, LO + SPAN * u, strict=True)}
        rec, _ = evaluate(build(with_values(cfg, changes), folder), limits)
        return np.array([rec["objectives"][fkey], *(c["scaled"] for c in rec["constraints"].values())])

    gradients, radius = {}, {}
    for rec in failed:
        b = rec["border"]
        success = by_id[b["nearest"]]
        earlier = [r for r in res.history[:res.history.index(rec)] if r["ok"]]
        assert success is min(earlier, key=lambda r: float(np.sum((u_of[r["id"]] - u_of[rec["id"]]) ** 2)))
        us, d = u_of[success["id"]], u_of[rec["id"]] - u_of[success["id"]]
        if success["id"] not in gradients:  # central differences of fresh orbits, 1e-4 of the spans
            h = 1e-4
            gradients[success["id"]] = np.column_stack([(fresh(us + h * e) - fresh(us - h * e)) / (2 * h)
                                                        for e in np.eye(2)])
        J = gradients[success["id"]]
        at = np.array([success["objectives"][fkey], *(c["scaled"] for c in success["constraints"].values())])
        model, by_differences = np.array([b["objective"], *b["margins"]]), at + J @ d
        # each figure's step to 0.5 % of its gradient's norm times the step's (the multiplier's margin
        # the least accurate, some 0.1 %; the objective's 2e-5), the objective's step itself some 1.5 %
        # of it: not the success's own value
        bound = 5e-3 * np.linalg.norm(J, axis=1) * np.linalg.norm(d) + 1e-9
        assert np.all(np.abs(model - by_differences) <= bound), (model - by_differences) / bound
        assert abs(J[0] @ d) > 1e-3 * abs(at[0])
        # the border at half the nearest failure's distance so far from this success (the fake failure
        # is no multiplier's border: the margin stays positive along the step)
        e = 1.0 - success["figures"]["max_multiplier"]  # (the margin's scale 1)
        length = float(np.linalg.norm(d))
        radius[success["id"]] = min(radius.get(success["id"], math.inf), length / 2.0)
        assert b["located"] == "radius" and b["radius"] == pytest.approx(radius[success["id"]], rel=1e-14)
        assert b[EXISTENCE] == pytest.approx(e * (1.0 - length / radius[success["id"]]), rel=1e-12)
        assert b[EXISTENCE] <= -e < 0.0
    assert res.optimum["feasible"] and res.optimum["values"]["valve.switch_out"] <= 0.0215 + 1e-9
