"""No event where no multiplier crosses its critical value (a sign change
of det(I -+ P) through the pole of the saltation term at a grazing impact), and branch switching
at a period doubling that returns a doubled branch, never the one-impact orbit traversed twice."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from impactbar import BarModel, CosineLoad, continue_orbit, periodic_orbits
from impactbar.continuation import doubling_cascade
from impactbar.continuation.one_parameter import _crosses, _real_offset


def _cos_negative(model, p0):
    return next(o for o in periodic_orbits(model, CosineLoad(p0, 1.0)) if math.cos(o.phase) < 0)


def _critical_ok(branch):
    """Every fold, branch point and period doubling has a real multiplier at +1 or -1."""
    for e in branch.events:
        if e.kind in ("fold", "branch-point"):
            assert abs(e.multiplier - 1.0) < 1e-6, (e.kind, e.value, e.multiplier)
        if e.kind == "period-doubling":
            assert abs(e.multiplier + 1.0) < 1e-6, (e.kind, e.value, e.multiplier)


@pytest.mark.parametrize("model, pd, fold", [
    (BarModel(5, 0.1, 0.3, n_modes=4), 0.378648924, 0.492966266),
    (BarModel(10, 0.05, 0.5, 8, impact="wave"), 0.591275553, 0.858000554),
])
def test_no_event_at_the_pole_of_a_grazing_impact(model, pd, fold):
    """The branch runs into a grazing impact near p0 = 0 (impact velocity -> 0, the largest
    multiplier through infinity): grazing is reported there, no period doubling nor branch point
    (before the fix: multipliers -0.677 and 0.622, wave law -0.377+0.206j and 0.429+0.013j)."""
    b = continue_orbit(_cos_negative(model, 0.05), "p0", to=3.0)
    _critical_ok(b)
    kinds = [(e.kind, round(e.value, 9)) for e in b.events if e.kind != "grazing"]
    assert kinds == [("period-doubling", pytest.approx(pd, abs=1e-8)),
                     ("fold", pytest.approx(fold, abs=1e-8))]
    low = [e for e in b.events if e.value < 0.01]
    assert [e.kind for e in low] == ["grazing"]
    assert abs(low[0].orbit.impact_velocity) < 1e-8  # a grazing impact, where the pole sits


def test_doubling_cascade_switches_at_the_true_doubling():
    """``impactbar continue --doublings 1`` aborted (the first branch reported a false period
    doubling at the grazing impact); the doubled branch now starts at the true one."""
    c = doubling_cascade(_cos_negative(BarModel(5, 0.1, 0.3, n_modes=4), 0.05), "p0", 3.0, doublings=1)
    assert len(c.branches) == 2 and c.branches[1].impacts == 2
    assert c.doublings[0].value == pytest.approx(0.378648924, abs=1e-8)
    _critical_ok(c.branches[1])


class _Orbit:
    def __init__(self, mu):
        self.multipliers = np.asarray(mu, dtype=complex)


def test_confirmation_of_a_located_crossing():
    """A located sign change counts where a real multiplier sits at the critical value, or
    crosses it between the two orbits around the located point; not where the nearest real
    multiplier stays away (a pole), nor for a complex pair."""
    def never(d):
        raise AssertionError("not needed")

    assert _real_offset(_Orbit([3e10, -0.677, 0.62]), -1.0) == pytest.approx(0.323)
    assert _crosses(_Orbit([3e10, -1.0 + 1e-9, 0.5]), -1.0, never)
    assert not _crosses(_Orbit([3e10, -0.677, 0.62]), -1.0, never)
    assert not _crosses(_Orbit([-0.377 + 0.206j, -0.377 - 0.206j]), -1.0, never)
    sides = {-1.0: _Orbit([-0.999, 0.2]), 1.0: _Orbit([-1.001, 0.2])}
    assert _crosses(_Orbit([-1.0 + 2e-5, 0.2]), -1.0, sides.get)
    sides = {-1.0: _Orbit([-0.9999, 0.2]), 1.0: _Orbit([-0.9998, 0.2])}
    assert not _crosses(_Orbit([-1.0 + 2e-5, 0.2]), -1.0, sides.get)


def test_switching_returns_a_doubled_branch():
    """BarModel(10, 0, 0.5, 2): two multipliers near -1 at the doubling p0 = 0.64592 (-1.035 and
    -1.0). The driven branch was the one-impact orbit traversed twice (both halves equal to
    1e-14, ending at the one-impact fold 0.95493); now every point past the doubling has distinct
    halves, and the branch has its own fold and period doubling."""
    model = BarModel(10, 0, 0.5, n_modes=2)
    b = continue_orbit(_cos_negative(model, 0.3), "p0", to=1.0)
    pd = next(e for e in b.events if e.kind == "period-doubling")
    assert pd.value == pytest.approx(0.64592114, abs=1e-7)
    near = np.sort(np.abs(pd.orbit.multipliers + 1.0))
    assert near[0] < 1e-8 and near[1] < 0.05  # two multipliers near -1
    d = continue_orbit(pd, "p0", to=0.3)
    assert d.impacts == 2 and d.periods == 2
    ph = d.phases[1:]
    gap = np.abs(np.angle(np.exp(1j * (ph[:, 0] - ph[:, 1]))))
    assert np.all(gap > 1e-3)  # doubled at every point past the doubling
    assert d.status == "reached"
    assert not any(e.kind == "fold" and abs(e.value - 0.95493) < 1e-3 for e in d.events)
    _critical_ok(d)
    # each point is a 2-per-2 orbit: its halves are not one orbit traversed twice
    last = d.orbits[-1]
    assert abs(last.impact_times[1] - last.impact_times[0] - 2 * math.pi) > 1e-2


@settings(max_examples=4, deadline=None, derandomize=True, phases=(Phase.explicit, Phase.generate),
          suppress_health_check=[HealthCheck.too_slow])
@given(s=st.floats(2.0, 12.0), R=st.floats(0.3, 0.9), n_modes=st.sampled_from([0, 1, 2]),
       impact=st.sampled_from(["paper", "wave"]))
def test_events_are_critical_and_scale_free(s, R, n_modes, impact):
    """Property (both laws): every located fold, branch point and period doubling has its multiplier
    at +1 or -1, and the load scaled by 1e3 (parameter and target with it) gives the same events
    at the scaled values (the model is linear in the load), within the range continued (past
    ``to`` or the start, where a branch that turned back stops depends on the steps)."""
    model = BarModel(s, 0.05, R, n_modes, impact=impact)
    try:
        start = _cos_negative(model, 0.05)
    except (StopIteration, ValueError):
        return
    b = continue_orbit(start, "p0", to=1.5, max_points=300)
    _critical_ok(b)
    L = 1e3
    big = next(o for o in periodic_orbits(model, CosineLoad(0.05 * L, L)) if math.cos(o.phase) < 0)
    c = continue_orbit(big, "p0", to=1.5 * L, max_points=300)
    _critical_ok(c)
    inside = [(e.kind, e.value) for e in b.events if 0.05 < e.value < 1.5]
    scaled = [(e.kind, e.value / L) for e in c.events if 0.05 < e.value / L < 1.5]
    assert [k for k, _ in scaled] == [k for k, _ in inside]
    np.testing.assert_allclose([v for _, v in scaled], [v for _, v in inside], rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("path", ["fast", "reference"])
def test_no_branch_point_at_the_start_of_a_doubled_branch(path):
    """The branch born at a period doubling starts on the parent's doubling, where the
    doubled orbit's multiplier is (-1)^2 = +1 and det(I - P) is zero up to rounding; its sign there
    is no crossing. Before the fix, the rigid bar's float path (same orbits to 1e-14) reported a
    branch point at the start, p0 = 0.75684712062, where the general path's corrector failed by
    chance at the first chord position the location tried."""
    from impactbar.dynamics.implementations import implementation

    model = BarModel(s=3.0, d=0.0, R=0.6, n_modes=0)
    with implementation("orbits.rigid_segments", path):
        b1 = continue_orbit(_cos_negative(model, 0.9), "p0", to=0.66, stop_on=("period-doubling",))
        b2 = continue_orbit(b1.events[-1], "p0", to=0.66, stop_on=("period-doubling",))
    assert [e.kind for e in b2.events] == ["period-doubling"]
    assert b2.events[0].value == pytest.approx(0.6859464472726, abs=1e-11)
    _critical_ok(b2)
