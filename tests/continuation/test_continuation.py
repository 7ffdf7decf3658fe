"""Continuation of periodic motions: branches against periodic_orbits, located bifurcations against
the chart edges (closed forms and root-finding), the rigid period-doubling cascade against
Feigenbaum's constant, and a flexible doubled orbit against the simulator."""

import math
import subprocess
import sys

import numpy as np
import pytest

from impactbar import (
    BarModel,
    Branch,
    CosineLoad,
    InitialState,
    SquareWaveLoad,
    continue_orbit,
    periodic_orbits,
    simulate,
)
from impactbar.continuation import continue_bifurcation, parameter_value, simulated_diagram, with_parameter
from impactbar.orbits.charts import (
    hydraulic_existence_edge,
    pneumatic_existence_edge,
    pneumatic_stability_edges,
)
from modal_reference import central_difference_jacobian

TWO_PI = 2 * math.pi
FEIGENBAUM = 4.669201609


def _stable_side(model, p0, pk=1.0):
    return next(o for o in periodic_orbits(model, CosineLoad(p0, pk)) if math.cos(o.phase) * pk < 0)


def _nearest(orbits, phase):
    return min(orbits, key=lambda o: abs(math.remainder(o.phase - phase, TWO_PI)))


@pytest.fixture(scope="module")
def flexible_branch():
    model = BarModel(s=10.0, d=0.05, R=0.5, n_modes=4)
    return model, continue_orbit(_stable_side(model, 0.3), "p0", to=1.0)


def test_one_impact_branch_equals_periodic_orbits(flexible_branch):
    model, b = flexible_branch
    assert isinstance(b, Branch) and len(b) > 10
    for v, o in zip(b.values, b.orbits, strict=True):
        ref = _nearest(periodic_orbits(model, CosineLoad(v, 1.0)), o.phase)
        assert o.phase == pytest.approx(ref.phase, abs=1e-9)
        assert o.impact_velocity == pytest.approx(ref.impact_velocity, abs=1e-9)
        np.testing.assert_allclose(np.sort_complex(o.multipliers), np.sort_complex(ref.multipliers),
                                   atol=1e-9)
        assert o.stable == ref.stable and o.admissibility == ref.admissibility


def test_located_fold_and_period_doubling_equal_chart_edges(flexible_branch):
    model, b = flexible_branch
    kinds = [e.kind for e in b.events]
    assert "period-doubling" in kinds and "fold" in kinds
    pd = next(e for e in b.events if e.kind == "period-doubling")
    fold = next(e for e in b.events if e.kind == "fold")
    edges = pneumatic_stability_edges(model)
    assert [k for _, k in edges] == ["period-doubling"]
    assert pd.value == pytest.approx(edges[0][0], abs=1e-8)
    assert pd.multiplier == pytest.approx(-1.0, abs=1e-6)
    assert fold.value == pytest.approx(pneumatic_existence_edge(model.R, model.d), abs=1e-8)
    assert fold.multiplier == pytest.approx(1.0, abs=1e-6)
    # stable between the doubling and the fold, unstable below the doubling
    stable = b.stable
    assert not stable[b.values < pd.value - 1e-3].any()
    mid = (b.values > pd.value + 1e-3) & (b.values < fold.value - 1e-3) & (np.arange(len(b)) < fold.index)
    assert stable[mid].all() and mid.any()
    assert b.status == "turned back"  # past the fold the branch returns below the start


@pytest.mark.parametrize("R", [0.3, 0.8])
def test_rigid_edges_closed_form(R):
    """Rigid bar, d = 0 (theory §6): doubling at kappa_0 = -((1-R)/(1+R))^2, fold at eq. 38."""
    model = BarModel(s=3.0, d=0.0, R=R, n_modes=0)
    lo = (1 + R) ** 2 / math.sqrt(4 * (1 + R * R) ** 2 + math.pi**2 * (1 - R * R) ** 2)
    hi = (1 + R) / (math.pi * (1 - R))
    b = continue_orbit(_stable_side(model, 0.5 * lo), "p0", to=1.01 * hi)
    got = {e.kind: e.value for e in b.events if e.kind in ("fold", "period-doubling")}
    assert got["period-doubling"] == pytest.approx(lo, abs=1e-8)
    assert got["fold"] == pytest.approx(hi, abs=1e-8)


def test_hydraulic_branch_ends_at_the_existence_edge():
    """The hydraulic branch (eq. 34) ends where its impact meets the load's jump: the corner of
    Fig. 8, located by pinning the impact time to the jump."""
    model = BarModel(s=10.0, d=0.0, R=0.5, n_modes=0)
    start = periodic_orbits(model, SquareWaveLoad(1.0, 1.1))[0]
    b = continue_orbit(start, "kappa", to=2.0)
    assert b.status == "impact at a load jump"
    edge = next(e for e in b.events if e.kind == "load-jump")
    assert edge.value == pytest.approx(hydraulic_existence_edge(model), abs=1e-8)
    assert edge.value == pytest.approx((2 * 0.5 + math.sqrt(2 + 2 * 0.25)) / 1.5, abs=1e-8)
    for v, o in zip(b.values[::5], b.orbits[::5], strict=True):
        ref = _nearest(periodic_orbits(model, SquareWaveLoad(1.0, v)), o.phase)
        assert o.phase == pytest.approx(ref.phase, abs=1e-9)


def test_grazing_is_where_admissibility_changes():
    model = BarModel(s=10.0, d=0.0, R=0.5, n_modes=0)
    start = periodic_orbits(model, SquareWaveLoad(1.0, 1.1))[0]
    b = continue_orbit(start, "kappa", to=1.6, stop_on=("grazing",))
    assert b.status == "stopped at grazing"
    g = b.events[-1]
    assert abs(g.orbit.clearance) < 1e-8
    before = _nearest(periodic_orbits(model, SquareWaveLoad(1.0, g.value - 1e-6)), g.orbit.phase)
    after = _nearest(periodic_orbits(model, SquareWaveLoad(1.0, g.value + 1e-6)), g.orbit.phase)
    assert before.admissible != after.admissible


def test_neimark_sacker_pair_on_the_unit_circle():
    model = BarModel(s=3.0, d=0.05, R=0.6, n_modes=4)
    b = continue_orbit(_stable_side(model, 1.0), "p0", to=0.62)
    ns = [e for e in b.events if e.kind == "neimark-sacker"]
    assert ns
    ref = _nearest(periodic_orbits(model, CosineLoad(ns[0].value, 1.0)), ns[0].orbit.phase)
    cpx = ref.multipliers[np.abs(ref.multipliers.imag) > 1e-6]
    assert np.min(np.abs(np.abs(cpx) - 1.0)) < 1e-8


def test_feigenbaum_cascade():
    """Undamped rigid bar (the bouncing-ball map of the paper's rigid block): five successive
    period doublings by branch switching; the gap ratios approach Feigenbaum's 4.669."""
    R = 0.6
    model = BarModel(s=3.0, d=0.0, R=R, n_modes=0)
    b = continue_orbit(_stable_side(model, 0.9), "p0", to=0.5, stop_on=("period-doubling",))
    pds = []
    for level in range(6):
        ev = next(e for e in b.events if e.kind == "period-doubling")
        assert ev.orbit.impacts == 2**level
        assert abs(np.prod(ev.orbit.multipliers) - R ** (2 * 2**level)) < 1e-9 * R ** (2 * 2**level) + 1e-14
        pds.append(ev.value)
        if level < 5:
            b = continue_orbit(ev, "p0", to=0.5, stop_on=("period-doubling",))
            assert b.impacts == 2 ** (level + 1)
    gaps = np.diff(pds)
    ratios = gaps[:-1] / gaps[1:]
    assert np.all(np.diff(pds) < 0)
    assert ratios[-1] == pytest.approx(FEIGENBAUM, rel=0.02)
    assert ratios[-2] == pytest.approx(FEIGENBAUM, rel=0.03)


def test_flexible_doubled_orbit_reached_by_simulate_and_multipliers_by_finite_differences():
    """Flexible bar: the period doubling of the one-impact orbit is subcritical; the doubled branch,
    followed through its fold, turns stable. There the simulator, started near the orbit, settles on
    it, and the multipliers equal those of a central-difference Jacobian of the simulated map."""
    model = BarModel(s=10.0, d=0.05, R=0.6, n_modes=4)
    b = continue_orbit(_stable_side(model, 1.0), "p0", to=0.6, stop_on=("period-doubling",))
    pd = b.events[-1]
    assert pd.kind == "period-doubling"
    b2 = continue_orbit(pd, "p0", to=0.7)
    assert any(e.kind == "fold" for e in b2.events)
    stable = np.flatnonzero(b2.stable)
    o = b2.orbits[stable[np.argmin(b2.max_abs_multiplier[stable])]]
    assert o.stable and o.impacts == 2 and o.periods == 2 and np.ptp(o.phases) > 1e-3
    assert o.max_abs_multiplier < 0.9
    model, load = o.model, o.load
    M = model.n_modes + 1
    # nearby start, 300 load periods later: the impacts are the orbit's
    q, v = o.modal_state_after_impact
    tr = simulate(model, load, InitialState(q * (1 + 1e-3), v * (1 - 1e-3)), o.impact_times[0] + 300 * TWO_PI,
                  t0=o.impact_times[0])
    last = np.mod(tr.impact_times[-4:], TWO_PI)
    assert np.max(np.min(np.abs(last[:, None] - o.phases[None, :]), axis=1)) < 1e-7

    def simulated_map(z):
        q = np.empty(M)
        q[1:] = z[1:M]
        q[0] = -model.end_weights[1:] @ q[1:]
        tr = simulate(model, load, InitialState(q, z[M:]), z[0] + 2 * TWO_PI + 3.0, t0=z[0], max_impacts=2)
        te = tr.impact_times[1]
        Q, V = tr.modal_state([te])
        return np.concatenate(([te], Q[1:, 0], V[:, 0]))

    z0 = np.concatenate(([o.impact_times[0]], o.states_after_impact[0][1:]))
    np.testing.assert_allclose(simulated_map(z0) - z0, np.eye(z0.size)[0] * 2 * TWO_PI, atol=1e-10)
    J = central_difference_jacobian(simulated_map, z0)
    mu = np.linalg.eigvals(J)
    np.testing.assert_allclose(np.sort_complex(mu), np.sort_complex(o.multipliers), atol=1e-6)


def test_branch_views(flexible_branch, tmp_path):
    _, b = flexible_branch
    df = b.to_dataframe()
    assert len(df) == len(b) and "phase_0" in df and "stable" in df
    np.testing.assert_array_equal(df["p0"].to_numpy(), b.values)
    ds = b.to_xarray()
    assert ds.sizes["point"] == len(b) and ds.sizes["event"] == len(b.events)
    assert list(ds["event_kind"].values) == [e.kind for e in b.events]
    ds.to_netcdf(tmp_path / "b.nc")
    ev = b.events_dataframe()
    assert list(ev["kind"]) == [e.kind for e in b.events]
    ax = b.plot()
    assert ax.get_xlabel() == "p0"
    styles = {line.get_linestyle() for line in ax.get_lines()}
    assert {"-", "--"} <= styles
    o = b.orbit_at(0.6)
    assert o.load.p0 == 0.6 and o.impacts == 1 and o.stable  # the first pass: the stable side
    with pytest.raises(ValueError, match="range"):
        b.orbit_at(5.0)


def test_continuation_does_not_import_plotting_libraries():
    code = ("import sys, impactbar.continuation; "
            "print(sorted(m for m in ('matplotlib', 'xarray', 'pandas') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_parameters():
    model, load = BarModel(s=10.0, d=0.05, R=0.5, n_modes=2), CosineLoad(0.3, 1.0, 2)
    assert parameter_value(model, load, "pk") == 1.0
    m2, l2 = with_parameter(model, load, "pk", 2.0)
    assert l2.pk == 2.0 and l2.k == 2 and m2 is model
    m3, _ = with_parameter(model, load, "s", 5.0)
    assert m3.s == 5.0
    with pytest.raises(ValueError, match="kappa"):
        parameter_value(model, load, "kappa")
    with pytest.raises(ValueError, match="parameter must be one of"):
        parameter_value(model, load, "n_modes")
    with pytest.raises(ValueError, match="R must be"):
        with_parameter(model, load, "R", 1.5)
    with pytest.raises(ValueError, match=r"\(of the BarModel and the CosineLoad\); got 'kappa'"):
        with_parameter(model, load, "kappa", 1.5)
    with pytest.raises(ValueError, match="kappa must be"):
        with_parameter(model, SquareWaveLoad(1.0, 1.5), "kappa", 2.5)


def test_bad_input():
    model = BarModel(s=10.0, d=0.05, R=0.5, n_modes=1)
    o = _stable_side(model, 0.6)
    with pytest.raises(ValueError, match="to must differ"):
        continue_orbit(o, "p0", to=0.6)
    with pytest.raises(ValueError, match="q"):
        continue_orbit(o, "q", to=0.6)
    with pytest.raises(ValueError, match="orbit must be"):
        continue_orbit("o", "p0", to=0.6)
    with pytest.raises(ValueError, match="stop_on"):
        continue_orbit(o, "p0", to=0.7, stop_on=("bogus",))
    with pytest.raises(ValueError, match="max_points"):
        continue_orbit(o, "p0", to=0.7, max_points=1)
    with pytest.raises(ValueError, match="tol"):
        continue_orbit(o, "p0", to=0.7, tol=-1.0)
    with pytest.raises(ValueError, match="to must be a finite"):
        continue_orbit(o, "p0", to=math.nan)
    b = continue_orbit(o, "R", to=1.2, max_points=400)  # R leaves [0, 1]: the branch stops inside
    assert b.values.max() <= 1.0 and b.status in ("parameter range", "step too small")


def test_simulated_diagram_on_the_stable_branch(flexible_branch):
    model, b = flexible_branch
    values = np.array([0.65, 0.7])
    start = b.orbit_at(0.65)
    diag = simulated_diagram(model, CosineLoad(0.65, 1.0), "p0", values, transient=150, record=5,
                             start=InitialState(*start.modal_state_after_impact), t0=start.impact_times[0])
    for v in values:
        sel = diag["parameter"] == v
        o = b.orbit_at(v)
        assert sel.sum() >= 4
        np.testing.assert_allclose(diag["impact_velocity"][sel], o.impact_velocity, atol=1e-6)
    with pytest.raises(ValueError, match="record"):
        simulated_diagram(model, CosineLoad(0.65, 1.0), "p0", values, record=0)


def test_cli_continue(tmp_path, capsys):
    from impactbar.cli import main

    out = tmp_path / "c"
    rc = main(["continue", "--s", "3", "--d", "0", "--R", "0.6", "--n-modes", "0", "--p0", "0.9",
               "--parameter", "p0", "--to", "0.68", "--doublings", "1", "--brute", "4", "--transient", "30",
               "--record", "4", "--curve", "R", "0.65", "--out", str(out)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "period-doubling at p0 = 0.7568471206" in text and "branch 1: 2 impact(s)" in text
    assert "period-doubling curve in (p0, R)" in text
    assert (out / "curve_0_period-doubling.csv").is_file() and (out / "curves.png").is_file()
    for name in ("branch_0_1per1.csv", "branch_1_2per2.csv", "events.csv", "branch_0_1per1.nc",
                 "diagram.png"):
        assert (out / name).is_file()
    import pandas as pd

    ev = pd.read_csv(out / "events.csv")
    assert list(ev["kind"])[:2] == ["period-doubling", "period-doubling"]
    rc = main(["continue", "--n-modes", "0", "--parameter", "p0", "--to", "0.8", "--brute", "0", "--json",
               "--out", str(out)])
    assert rc == 0
    import json

    doc = json.loads(capsys.readouterr().out)
    assert doc["branches"][0]["impacts"] == 1
    assert main(["continue", "--parameter", "kappa", "--to", "1.5", "--out", str(out)]) == 2  # cosine load
    assert "kappa" in capsys.readouterr().err


# ---------------------------------------------------------------- two-parameter curves ------------
def test_rigid_fold_and_doubling_curves_follow_the_closed_forms():
    """Rigid bar, d = 0: the fold p0 = (1+R)/(pi (1-R)) (eq. 38) and the period doubling
    p0 = (1+R)^2 / sqrt(4 (1+R^2)^2 + pi^2 (1-R^2)^2) (eq. 39), followed in (p0, R)."""
    model = BarModel(s=3.0, d=0.0, R=0.6, n_modes=0)
    b = continue_orbit(_stable_side(model, 0.5), "p0", to=1.3)
    events = {e.kind: e for e in b.events}
    pd = continue_bifurcation(events["period-doubling"], "R", to=0.75)
    assert pd.status == "reached" and pd.values[-1, 1] == pytest.approx(0.75, abs=1e-12)
    R = pd.values[:, 1]
    ref = (1 + R) ** 2 / np.sqrt(4 * (1 + R * R) ** 2 + np.pi**2 * (1 - R * R) ** 2)
    np.testing.assert_allclose(pd.values[:, 0], ref, atol=1e-10)
    assert all(np.min(np.abs(o.multipliers + 1)) < 1e-8 for o in pd.orbits)
    fold = continue_bifurcation(events["fold"], "R", to=0.5, max_step=0.05)
    R = fold.values[:, 1]
    np.testing.assert_allclose(fold.values[:, 0], (1 + R) / (np.pi * (1 - R)), atol=1e-10)
    assert fold.status == "reached"
    df = pd.to_dataframe()
    assert list(df.columns[:2]) == ["p0", "R"] and len(df) == len(pd)
    ax = pd.plot()
    assert ax.get_xlabel() == "R"


def test_flexible_curves_equal_the_chart_edges(flexible_branch):
    """Four flexible modes, d > 0: the doubling curve equals the charts' root-finding of the
    exact multipliers (Fig. 5's lower edge), the fold curve the closed-form existence edge."""
    model, b = flexible_branch
    events = {e.kind: e for e in b.events}
    pd = continue_bifurcation(events["period-doubling"], "R", to=0.65)
    for i in (len(pd) // 2, len(pd) - 1):
        p0, R = pd.values[i]
        edge = pneumatic_stability_edges(model.with_(R=float(R)))
        assert p0 == pytest.approx(edge[0][0], abs=1e-8)
    fold = continue_bifurcation(events["fold"], "R", to=0.65)
    np.testing.assert_allclose(fold.values[:, 0], pneumatic_existence_edge(fold.values[:, 1], model.d),
                               atol=1e-9)


def test_grazing_curve_keeps_zero_clearance(flexible_branch):
    model, b = flexible_branch
    graze = next(e for e in b.events if e.kind == "grazing")
    curve = continue_bifurcation(graze, "R", to=0.6, max_points=5)
    assert len(curve) >= 3
    assert all(abs(o.clearance) < 1e-8 for o in curve.orbits)
    p0, R = curve.values[-1]
    before = _nearest(periodic_orbits(model.with_(R=float(R)), CosineLoad(p0 - 1e-6, 1.0)),
                      curve.orbits[-1].phase)
    after = _nearest(periodic_orbits(model.with_(R=float(R)), CosineLoad(p0 + 1e-6, 1.0)),
                     curve.orbits[-1].phase)
    assert before.admissible != after.admissible


def test_continue_bifurcation_bad_input(flexible_branch):
    _, b = flexible_branch
    pd = next(e for e in b.events if e.kind == "period-doubling")
    with pytest.raises(ValueError, match="must differ from the branch"):
        continue_bifurcation(pd, "p0", to=0.5)
    with pytest.raises(ValueError, match="to must differ"):
        continue_bifurcation(pd, "R", to=0.5)
    with pytest.raises(ValueError, match="BranchEvent"):
        continue_bifurcation(b.orbits[0], "R", to=0.6)


def test_subharmonic_doubling_curve():
    """The period doubling of the rigid 2-per-2 orbit, followed in (p0, R): at every point the
    2-per-2 orbit found afresh at those parameters has a multiplier -1."""
    from impactbar import find_orbit

    model = BarModel(s=3.0, d=0.0, R=0.6, n_modes=0)
    b1 = continue_orbit(_stable_side(model, 0.9), "p0", to=0.66, stop_on=("period-doubling",))
    b2 = continue_orbit(b1.events[-1], "p0", to=0.66, stop_on=("period-doubling",))
    curve = continue_bifurcation(b2.events[-1], "R", to=0.55)
    assert curve.status == "reached" and curve.orbits[0].impacts == 2
    for (p0, R), o in list(zip(curve.values, curve.orbits, strict=True))[::4]:
        fresh = find_orbit(model.with_(R=float(R)), CosineLoad(float(p0), 1.0), 2, 2, guess=o)
        assert np.min(np.abs(fresh.multipliers + 1.0)) < 1e-7
        assert np.prod(fresh.multipliers).real == pytest.approx(R**4, rel=1e-9)


def test_sticking_at_R0_is_located_as_an_admissibility_event():
    """R = 0: the end leaves the stop at rest, and the orbit is inadmissible ('sticks') where the
    load presses it back (theory §5); the change is located by bisection on the flag."""
    model = BarModel(s=10.0, d=0.05, R=0.0, n_modes=2)
    start = next(o for o in periodic_orbits(model, CosineLoad(0.2, 1.0)) if o.admissibility == "sticks")
    b = continue_orbit(start, "p0", to=0.4)
    ev = next(e for e in b.events if e.kind == "admissibility")
    flags = []
    for dv in (-1e-7, 1e-7):
        o = _nearest(periodic_orbits(model, CosineLoad(ev.value + dv, 1.0)), ev.orbit.phase)
        flags.append(o.admissibility)
    assert sorted(flags) == ["admissible", "sticks"]


def test_start_exactly_at_a_fold():
    """At the fold (a double root of eq. 14) Newton at fixed parameter is singular; the branch
    leaves along the null vector and follows one of the two merging orbits."""
    R = 0.6
    model = BarModel(s=3.0, d=0.0, R=R, n_modes=0)
    fold = periodic_orbits(model, CosineLoad((1 + R) / (math.pi * (1 - R)), 1.0))
    assert fold[0].multiplicity == 2
    b = continue_orbit(fold[0], "p0", to=1.0)
    assert b.status == "reached" and b.values[-1] == 1.0
    ref = _nearest(periodic_orbits(model, CosineLoad(1.0, 1.0)), b.orbits[-1].phase)
    assert b.orbits[-1].phase == pytest.approx(ref.phase, abs=1e-10)


def test_cli_continue_si_preset(tmp_path, capsys):
    """A hammer in SI units (a preset): its dimensionless bar and load are continued in R."""
    from impactbar.cli import main

    rc = main(["continue", "--preset", "pneumatic-drill", "--parameter", "R", "--to", "0.2", "--brute", "0",
               "--out", str(tmp_path)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "n_modes=16" in text and "period-doubling at R = 0.17524" in text
