"""Multi-impact orbits and continuation under the wave impact law (theory §4b): one-impact results
against periodic_orbits, the rigid identity, the segment problem's Jacobian against finite
differences, and a doubled orbit against the event-driven simulator and its finite-difference map."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from impactbar import (
    BarModel,
    CosineLoad,
    InitialState,
    SquareWaveLoad,
    continue_orbit,
    find_orbit,
    periodic_orbits,
    simulate,
)
from impactbar.orbits.multi_impact import _Segments, _unknowns_from
from modal_reference import central_difference_jacobian

TWO_PI = 2 * math.pi


def _same_multipliers(a, b):
    return float(np.max(np.abs(np.sort_complex(np.asarray(a)) - np.sort_complex(np.asarray(b)))))


@pytest.fixture(scope="module")
def doubling():
    """The wave-law one-impact branch of a flexible bar in p0, stopped at its period doubling."""
    model = BarModel(s=10.0, d=0.05, R=0.6, n_modes=4, impact="wave")
    start = next(o for o in periodic_orbits(model, CosineLoad(0.3, 1.0)) if o.admissible)
    branch = continue_orbit(start, "p0", to=1.0, stop_on=("period-doubling",))
    return model, branch


@pytest.mark.parametrize("model, load", [
    (BarModel(s=10.0, d=0.01, R=0.5, n_modes=4, impact="wave"), CosineLoad(0.1, 1.0)),
    (BarModel(s=3.0, d=0.02, R=0.3, n_modes=3, impact="wave"), CosineLoad(0.2, 1.0, 2)),
    (BarModel(s=8.0, d=0.02, R=0.5, n_modes=3, impact="wave"), SquareWaveLoad(1.0, 1.3)),
    (BarModel(s=6.0, d=0.0, R=0.4, n_modes=0, impact="wave"), CosineLoad(0.5, 1.0)),
])
def test_wave_one_impact_equals_periodic_orbits(model, load):
    orbits = [o for o in periodic_orbits(model, load) if np.isfinite(o.phase)]
    assert orbits
    M = model.n_modes + 1
    for o in orbits:
        f = find_orbit(model, load, guess=o)
        assert f.window == pytest.approx(2 / model.s, rel=1e-15)
        assert f.phase == pytest.approx(o.phase, abs=1e-9)
        assert f.impact_velocity == pytest.approx(o.impact_velocity, abs=1e-9)
        assert _same_multipliers(f.multipliers, o.multipliers) < 1e-9 * max(1.0, o.max_abs_multiplier)
        assert f.admissibility == o.admissibility
        np.testing.assert_allclose(f.states_after_impact[0], o.state_after_impact, atol=1e-9)
        np.testing.assert_allclose(f.states_before_impact[0], o.state_before_impact, atol=1e-9)
        if o.impact is not None:
            assert f.contacts[0].rod_energy == pytest.approx(o.impact.rod_energy, rel=1e-9)
        # the end touches the rod end on arrival and when the window closes
        assert f.end_displacement(0.0) == pytest.approx(0.0, abs=1e-12)
        assert float(model.end_weights @ f.states_after_impact[0, :M]) == pytest.approx(0.0, abs=1e-12)
        # inside the window, the characteristics solution; after it, the flight
        t = np.array([0.5 / model.s, 3.0])
        np.testing.assert_allclose(f.modal_state(t)[0], o.modal_state(t)[0], atol=1e-9)


@pytest.mark.parametrize("model", [BarModel(s=10.0, d=0.0, R=0.5, n_modes=4, impact="wave"),
                                   BarModel(s=3.0, d=0.05, R=0.2, n_modes=0, impact="wave")])
@pytest.mark.parametrize("load", [CosineLoad(0.3, 1.0), SquareWaveLoad(1.0, 1.3)])
def test_wave_rigid_identity_on_find_orbit(model, load):
    """One impact per period: the rigid mode's impact velocity is
    ``2 pi p0/(1 + R) - int_0^{1/s} p(phase + t) dt`` (theory §4b), whatever the guess."""
    M = model.n_modes + 1
    found = [find_orbit(model, load, guess=o) for o in periodic_orbits(model, load)]
    found.append(find_orbit(model, load))
    for o in found:
        brk = [] if isinstance(load, CosineLoad) else [TWO_PI * math.ceil(o.phase / TWO_PI)]
        pts = [b - o.phase for b in brk if 0 < b - o.phase < 1 / model.s] or None
        half = quad(lambda t, o=o: float(load(o.phase + t)), 0, 1 / model.s, points=pts,
                    epsabs=1e-14, epsrel=1e-13)[0]
        rigid = o.states_before_impact[0, M]
        assert rigid == pytest.approx(TWO_PI * load.p0 / (1 + model.R) - half, abs=1e-12)


def test_wave_jacobian_matches_finite_differences(rng):
    model = BarModel(s=10.0, d=0.05, R=0.6, n_modes=3, impact="wave")
    load = CosineLoad(0.66, 1.0)
    o = next(o for o in periodic_orbits(model, load) if o.admissible)
    p = _Segments(model, load, 2, 2)
    times = o.phase + np.array([0.0, TWO_PI + 0.3])
    u = _unknowns_from(p, times, np.stack([o.state_after_impact] * 2)) + 1e-3 * rng.standard_normal(p.size)
    _, DF, _ = p.evaluate(u)
    fd = central_difference_jacobian(lambda x: p.evaluate(x, jacobian=False)[0], u)
    np.testing.assert_allclose(DF, fd, atol=2e-7 * max(1.0, np.max(np.abs(DF))))


def test_wave_branch_equals_periodic_orbits(doubling):
    model, branch = doubling
    assert branch.orbits[0].window == pytest.approx(0.2)
    assert len(branch.values) >= 5
    for value, o in zip(branch.values, branch.orbits, strict=True):
        ref = min(periodic_orbits(model, CosineLoad(value, 1.0)),
                  key=lambda r: abs(math.remainder(r.phase - o.phase, TWO_PI)))
        assert o.phase == pytest.approx(ref.phase, abs=1e-9)
        assert o.impact_velocity == pytest.approx(ref.impact_velocity, abs=1e-9)
        assert _same_multipliers(o.multipliers, ref.multipliers) < 1e-9 * max(1.0, ref.max_abs_multiplier)
        assert o.admissibility == ref.admissibility
    pd = branch.events[-1]
    assert pd.kind == "period-doubling" and pd.multiplier == pytest.approx(-1.0, abs=1e-8)
    # located: the one-impact orbit there has a multiplier -1
    ref = min(periodic_orbits(model, CosineLoad(pd.value, 1.0)),
              key=lambda r: abs(math.remainder(r.phase - pd.orbit.phase, TWO_PI)))
    assert np.min(np.abs(ref.multipliers + 1.0)) < 1e-7


def test_wave_doubled_orbit_reproduced_by_simulate_and_finite_differences(doubling):
    """Below the period doubling the 2-per-2 orbit, started from the located event, is stable; the
    simulator started at the end of its first contact window strikes at its impact times, and the
    multipliers equal those of a central-difference Jacobian of the simulated map."""
    model, branch = doubling
    pd = branch.events[-1]
    load = CosineLoad(0.66, 1.0)
    o = find_orbit(model, load, impacts=2, periods=2, guess=pd)
    assert o.impacts == 2 and np.ptp(o.phases) > 0.1  # genuinely doubled
    assert o.admissible and o.stable and all(c.separations == 0 for c in o.contacts)
    M = model.n_modes + 1
    T = o.window
    y = o.states_after_impact[0]
    t0 = o.impact_times[0] + T
    tr = simulate(model, load, InitialState(y[:M], y[M:]), t0 + 3 * o.period + 0.1, t0=t0)
    expected = (o.impact_times[None, :] + o.period * np.arange(4)[:, None]).ravel()[1:]
    expected = expected[expected < tr.t_end]
    assert tr.impact_times.size == expected.size
    np.testing.assert_allclose(tr.impact_times, expected, rtol=0, atol=1e-9)
    np.testing.assert_allclose(tr.impact_velocities[:2], np.roll(o.impact_velocities, -1), atol=1e-9)
    again = find_orbit(model, load, impacts=2, periods=2, guess=tr)  # from the run's last impacts
    assert sorted(again.phases) == pytest.approx(sorted(o.phases), abs=1e-10)

    def simulated_map(z):
        """(arrival time, reduced state at the window's end) -> the same two impacts later."""
        q = np.empty(M)
        q[1:] = z[1:M]
        q[0] = -model.end_weights[1:] @ q[1:]
        tr = simulate(model, load, InitialState(q, z[M:]), z[0] + 2 * T + 2 * TWO_PI + 0.3, t0=z[0] + T)
        te = tr.impact_times[1]
        Q, V = tr.modal_state([te + T])
        return np.concatenate(([te], Q[1:, 0], V[:, 0]))

    z0 = np.concatenate(([o.impact_times[0]], y[1:]))
    np.testing.assert_allclose(simulated_map(z0) - z0, np.eye(z0.size)[0] * 2 * TWO_PI, atol=1e-10)
    J = central_difference_jacobian(simulated_map, z0)
    assert _same_multipliers(np.linalg.eigvals(J), o.multipliers) < 1e-6


def test_wave_doubling_curve(doubling):
    """The wave law's period doubling followed in (p0, R): at every point the one-impact orbit of
    periodic_orbits at those parameters has a multiplier -1."""
    from impactbar.continuation import continue_bifurcation

    model, branch = doubling
    curve = continue_bifurcation(branch.events[-1], "R", to=0.5)
    assert curve.status == "reached" and len(curve.values) > 4
    for (p0, R), o in list(zip(curve.values, curve.orbits, strict=True))[::4]:
        ref = min(periodic_orbits(model.with_(R=float(R)), CosineLoad(float(p0), 1.0)),
                  key=lambda r: abs(math.remainder(r.phase - o.phase, TWO_PI)))
        assert abs(math.remainder(ref.phase - o.phase, TWO_PI)) < 1e-9
        assert np.min(np.abs(ref.multipliers + 1.0)) < 1e-8


def test_wave_bad_input():
    model = BarModel(s=0.3, d=0.0, R=0.5, n_modes=1, impact="wave")
    with pytest.raises(ValueError, match="do not fit"):
        find_orbit(model, CosineLoad(0.3, 1.0))
    model = BarModel(s=1.0, d=0.0, R=0.5, n_modes=1, impact="wave")
    with pytest.raises(ValueError, match="do not fit"):
        find_orbit(model, CosineLoad(0.3, 1.0), impacts=4, periods=1, guess=([0, 1, 2, 3], np.zeros((4, 4))))


def test_cli_continue_wave_and_refused_options(tmp_path, capsys):
    import json

    from impactbar.cli import main

    out = tmp_path / "w"
    rc = main(["continue", "--impact", "wave", "--s", "10", "--d", "0.05", "--R", "0.6", "--n-modes", "2",
               "--p0", "0.3", "--parameter", "p0", "--to", "0.75", "--doublings", "1", "--brute", "2",
               "--transient", "5", "--record", "2", "--json", "--out", str(out)])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    first, doubled = doc["branches"]
    pd = next(e for e in first["events"] if e["kind"] == "period-doubling")
    model = BarModel(s=10.0, d=0.05, R=0.6, n_modes=2, impact="wave")
    ref = min(periodic_orbits(model, CosineLoad(pd["value"], 1.0)),
              key=lambda r: abs(math.remainder(r.phase - pd["phase"], TWO_PI)))
    assert np.min(np.abs(ref.multipliers + 1.0)) < 1e-7
    assert doubled["impacts"] == 2 and doubled["periods"] == 2
    for argv, flag in [(["--kappa", "1.5"], "--kappa"),
                       (["--impacts", "2", "--periods", "2", "--orbit", "0"], "--orbit"),
                       (["--brute", "0", "--transient", "5"], "--transient"),
                       (["--preset", "pneumatic-drill", "--R", "0.3"], "--R")]:
        rc = main(["continue", "--parameter", "p0", "--to", "0.8", "--out", str(out), *argv])
        assert rc == 2
        err = capsys.readouterr().err
        assert flag in err and "ignored" in err
