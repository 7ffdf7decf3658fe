"""One orbit type, one continuation engine, string enums with messages, the doubling cascade."""

import dataclasses
import io
import json
import math

import numpy as np
import pytest

import impactbar
from impactbar import (
    Admissibility,
    BarModel,
    BranchStatus,
    CosineLoad,
    CurveKind,
    EventKind,
    MultiImpactOrbit,
    PeriodicOrbit,
    RunStatus,
    continue_bifurcation,
    continue_orbit,
    find_orbit,
    periodic_orbits,
)
from impactbar.continuation import EVENT_KINDS, ContinuationSettings, doubling_cascade
from impactbar.continuation import engine as engine_module
from impactbar.orbits.multi_impact import _Segments, _unknowns_from

# ------------------------------------------------------------------------------------------------
# enums
# ------------------------------------------------------------------------------------------------
OLD_STRINGS = {
    Admissibility: {"admissible", "penetrates", "grazing", "backward impact", "sticks", "separates",
                    "unchecked"},
    RunStatus: {"t_end", "max_impacts"},
    EventKind: {"fold", "branch-point", "period-doubling", "neimark-sacker", "grazing",
                "admissibility", "load-jump", "border-collision"},
    CurveKind: {"fold", "period-doubling", "grazing"},
}


@pytest.mark.parametrize("enum", [Admissibility, RunStatus, EventKind, CurveKind, BranchStatus])
def test_enum_members_are_their_strings_with_a_message(enum):
    for member in enum:
        assert isinstance(member, str) and member == member.value
        assert str(member) == f"{member}" == repr(member)[1:-1] == member.value
        assert json.dumps({"k": member}) == json.dumps({"k": member.value})
        assert isinstance(member.message, str) and len(member.message) > 20
        assert enum(member.value) is member
    if enum in OLD_STRINGS:
        assert {m.value for m in enum} == OLD_STRINGS[enum]


def test_enum_specific_members():
    assert BranchStatus.LOAD_JUMP == "impact at a load jump" and "jump" in BranchStatus.LOAD_JUMP.message
    assert {m.value for m in BranchStatus} >= {"reached", "max_points", "step too small",
                                                "parameter range", "turned back"}
    for kind in EventKind:
        assert BranchStatus.stopped_at(kind) == f"stopped at {kind}"
    assert EVENT_KINDS == tuple(EventKind)
    # the order in which a motion's failing flights are reported
    ranked = sorted(Admissibility, key=lambda a: a.rank)
    assert ranked[:6] == ["penetrates", "backward impact", "grazing", "sticks", "separates", "admissible"]
    for name in ("Admissibility", "RunStatus", "BranchStatus", "EventKind", "CurveKind"):
        assert name in impactbar.__all__


def test_results_carry_enums_and_serialise_as_before():
    model = BarModel(s=3, d=0, R=0.0, n_modes=0)
    orbits = periodic_orbits(model, CosineLoad(0.3, 1.0))
    assert all(isinstance(o.admissibility, Admissibility) for o in orbits)
    d = orbits[0].to_dict()
    plain = dict(d, admissibility=str.__str__(d["admissibility"]))
    assert json.dumps(d) == json.dumps(plain)
    buf_enum, buf_plain = io.StringIO(), io.StringIO()
    df = orbits.to_dataframe()
    df.to_csv(buf_enum)
    df.assign(admissibility=[str.__str__(a) for a in df["admissibility"]]).to_csv(buf_plain)
    assert buf_enum.getvalue() == buf_plain.getvalue()
    start = impactbar.InitialState(*orbits[0].modal_state_after_impact)
    tr = impactbar.simulate(model, CosineLoad(0.3, 1.0), start, 20.0)
    assert isinstance(tr.status, RunStatus) and tr.status == "t_end"


# ------------------------------------------------------------------------------------------------
# one orbit type
# ------------------------------------------------------------------------------------------------
def test_one_impact_orbit_is_find_orbit_with_one_impact_in_one_period():
    model, load = BarModel(s=10, d=0.05, R=0.5, n_modes=4), CosineLoad(0.1, 1.0)
    found = find_orbit(model, load, impacts=1, periods=1)
    ref = min(periodic_orbits(model, load), key=lambda o: abs(math.remainder(o.phase - found.phase,
                                                                             2 * math.pi)))
    assert type(found) is type(ref) is PeriodicOrbit is MultiImpactOrbit
    assert isinstance(found, MultiImpactOrbit) and isinstance(ref, MultiImpactOrbit)
    for o in (ref, found):
        assert (o.impacts, o.periods, o.multiplicity) == (1, 1, 1)
        assert isinstance(o.phase, float) and isinstance(o.impact_velocity, float)
        assert o.phase == o.phases[0] == o.impact_times[0]
    for name in ("phase", "impact_velocity", "clearance", "max_abs_multiplier", "window", "period"):
        assert getattr(found, name) == pytest.approx(getattr(ref, name), abs=1e-10), name
    for name in ("impact_times", "phases", "impact_velocities", "multipliers", "states_after_impact",
                 "states_before_impact", "state_after_impact", "state_before_impact"):
        np.testing.assert_allclose(getattr(found, name), getattr(ref, name), rtol=0, atol=1e-10,
                                   err_msg=name)
    for name in ("admissible", "admissibility", "stable", "impact", "contacts"):
        assert getattr(found, name) == getattr(ref, name), name
    t = np.linspace(0.0, 4 * math.pi, 37)
    x = np.linspace(0.0, 1.0, 5)[:, None]
    np.testing.assert_allclose(found.end_displacement(t), ref.end_displacement(t), atol=1e-10)
    np.testing.assert_allclose(found.displacement(x, t), ref.displacement(x, t), atol=1e-10)
    np.testing.assert_allclose(found.velocity(x, t), ref.velocity(x, t), atol=1e-10)
    for a, b in zip(found.modal_state(t), ref.modal_state(t), strict=True):
        np.testing.assert_allclose(a, b, atol=1e-10)
    np.testing.assert_allclose(found.to_dataframe(16).to_numpy(), ref.to_dataframe(16).to_numpy(),
                               atol=1e-10)
    # the one-impact extras are the phase equation's (periodic_orbits), and so is its summary
    assert found.schur_roots is None and found.schur_stable is None
    assert isinstance(ref.schur_stable, bool) and ref.schur_roots.shape == ref.multipliers.shape
    assert list(ref.to_dict()) == ["phase", "multiplicity", "impact_velocity", "admissible",
                                   "admissibility", "clearance", "stable", "max_abs_multiplier",
                                   "multipliers", "schur_stable", "schur_roots", "impact_law"]
    assert list(found.to_dict()) == ["impacts", "periods", "impact_times", "phases",
                                     "impact_velocities", "admissible", "admissibility", "clearance",
                                     "stable", "max_abs_multiplier", "multipliers"]


def test_multi_impact_orbit_tables_span_its_period():
    model, load = BarModel(s=3, d=0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0)
    start = periodic_orbits(model, load)[1]
    ev = continue_orbit(start, "p0", to=0.5, stop_on=("period-doubling",)).events[-1]
    o = find_orbit(model.with_(R=0.6), CosineLoad(ev.value - 0.01, 1.0), 2, 2, guess=ev)
    df = o.to_dataframe(8)
    assert df.index[-1] == pytest.approx(4 * math.pi)
    # the end touches the stop at both impacts, and is off it in between
    u = o.end_displacement(o.impact_times - o.impact_times[0])
    np.testing.assert_allclose(u, 0.0, atol=1e-10)
    assert np.all(df["end_displacement"].to_numpy()[1:-1] < 1e-12)


# ------------------------------------------------------------------------------------------------
# settings and the engine
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, name", [
    ({"step": 0.0}, "step"), ({"step": -1.0}, "step"), ({"max_step": math.inf}, "max_step"),
    ({"min_step": "a"}, "min_step"), ({"max_points": 1}, "max_points"),
    ({"max_points": 2.5}, "max_points"), ({"tol": 0.0}, "tol"), ({"tol": 0.1}, "tol"),
    ({"min_step": 1.0, "max_step": 0.5}, "min_step"),
])
def test_settings_validated_once(kwargs, name):
    with pytest.raises(ValueError, match=name):
        ContinuationSettings(**kwargs)


def test_settings_frozen_and_defaults():
    s = ContinuationSettings()
    assert (s.step, s.max_step, s.min_step, s.max_points, s.tol) == (None, None, None, 2000, 1e-11)
    assert s.steps(1.0) == (1 / 50, 1 / 10, 1e-9)
    assert ContinuationSettings(step=1.0, max_step=0.2).steps(1.0)[0] == 0.2
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.tol = 1e-6


@pytest.fixture(scope="module")
def rigid_doubling():
    start = periodic_orbits(BarModel(s=3, d=0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))[1]
    return continue_orbit(start, "p0", to=0.7).events[0]


def test_both_continuations_run_on_the_one_engine(rigid_doubling, monkeypatch):
    seen = []
    march = engine_module._Engine.march

    def spy(self, *args, **kwargs):
        seen.append((type(self.problem).__name__, self.tol))
        return march(self, *args, **kwargs)

    monkeypatch.setattr(engine_module._Engine, "march", spy)
    settings = ContinuationSettings(max_step=0.02, max_points=40, tol=1e-10)
    b = continue_orbit(rigid_doubling.orbit, "p0", to=0.8, settings=settings)
    c = continue_bifurcation(rigid_doubling, "R", to=0.65, settings=settings)
    assert seen == [("_OrbitProblem", 1e-10), ("_BifurcationProblem", 1e-10)]
    for res in (b, c):
        assert isinstance(res.status, BranchStatus) and res.status == "reached"
        assert 2 < len(res.values) <= 40
    # a point limit from the settings, overridden by the keyword argument
    short = continue_bifurcation(rigid_doubling, "R", to=0.65, settings=settings, max_points=3)
    assert len(short) == 3 and short.status == BranchStatus.MAX_POINTS
    with pytest.raises(ValueError, match="settings"):
        continue_orbit(rigid_doubling.orbit, "p0", to=0.8, settings={"tol": 1e-9})


def test_bifurcation_curve_points_solve_the_augmented_system(rigid_doubling):
    """Every point solves the segment problem and has a multiplier at -1 (the augmented system
    ``(F, g) = 0``), checked independently of the bordering."""
    curve = continue_bifurcation(rigid_doubling, "R", to=0.75)
    assert curve.kind is CurveKind.PERIOD_DOUBLING and curve.status == "reached"
    assert curve.values[-1, 1] == 0.75 and len(curve) > 3
    for (p0, R), o in zip(curve.values, curve.orbits, strict=True):
        assert (o.load.p0, o.model.R) == (p0, R)
        problem = _Segments(o.model, o.load, o.impacts, o.periods)
        u = _unknowns_from(problem, o.impact_times, o.states_after_impact)
        F, _, _ = problem.evaluate(u, jacobian=False)
        assert np.max(np.abs(F)) < 1e-9
        assert np.min(np.abs(o.multipliers + 1.0)) < 1e-6


# ------------------------------------------------------------------------------------------------
# the cascade
# ------------------------------------------------------------------------------------------------
def test_doubling_cascade_gap_ratios_approach_feigenbaum():
    """The rigid bar's cascade that the README quotes: gap ratios 5.79, 4.84, 4.670, 4.668."""
    model = BarModel(s=3.0, d=0.0, R=0.6, n_modes=0)
    start = next(o for o in periodic_orbits(model, CosineLoad(0.9, 1.0)) if math.cos(o.phase) < 0)
    c = doubling_cascade(start, "p0", to=0.5, doublings=5, stop_on=("period-doubling",))
    assert [b.impacts for b in c.branches] == [1, 2, 4, 8, 16, 32]
    assert [b.periods for b in c.branches] == [1, 2, 4, 8, 16, 32]
    assert len(c.doublings) == 6 and all(e.kind == EventKind.PERIOD_DOUBLING for e in c.doublings)
    for k, e in enumerate(c.doublings):
        assert e.orbit.impacts == 2**k
        assert np.min(np.abs(e.orbit.multipliers + 1.0)) < 1e-7
    for b, e in zip(c.branches[1:], c.doublings, strict=False):  # each branch starts at a doubling
        assert b.values[0] == e.value
    ratios = [round(float(r), n) for r, n in zip(c.gap_ratios, (2, 2, 3, 3), strict=True)]
    assert ratios == [5.79, 4.84, 4.670, 4.668]
    one = doubling_cascade(start, "p0", to=0.5, doublings=0, stop_on=("period-doubling",))
    assert len(one.branches) == 1 and len(one.doublings) == 1 and one.gap_ratios.size == 0
    with pytest.raises(ValueError, match="doublings"):
        doubling_cascade(start, "p0", to=0.5, doublings=-1)
