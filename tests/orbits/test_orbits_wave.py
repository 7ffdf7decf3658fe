"""One-impact orbits under the wave impact law (theory §4b): the exact rigid identity, the rigid
limit, periodicity against an independent flight + contact, the analytic Jacobian against finite
differences of that map, and the flexible multipliers."""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from impactbar import BarModel, CosineLoad, SquareWaveLoad, periodic_orbits
from impactbar.dynamics.implementations import use_reference
from impactbar.laws.wave.impact import wave_impact
from modal_reference import central_difference_jacobian

TWO_PI = 2 * math.pi


def wave(model):
    return model.with_(impact="wave")


def flight_and_contact(model, load, z):
    """The impact map built independently: ``z = (t_e, q_1..q_N, q_0'..q_N')`` at the end of a
    contact window -> the same at the end of the next, by the load's exact flow, a bracketed root
    of ``u(1, t)`` and :func:`wave_impact`."""
    M = model.n_modes + 1
    c = model.end_weights
    te = z[0]
    q = np.concatenate(([-(c[1:] @ z[1:M])], z[1:M]))
    flow = load.flow(model.frequencies**2, model.d, te, q, z[M:])

    def end(t):
        return float(c @ flow([t])[0][:, 0])

    guess = te + TWO_PI - 2 / model.s
    tp = brentq(end, guess - 0.05, guess + 0.05, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    qm, vm = (a[:, 0] for a in flow([tp]))
    qm[0] -= c @ qm
    imp = wave_impact(model, load, tp, qm, vm)
    return np.concatenate(([tp + 2 / model.s], imp.q_after[1:], imp.v_after))


def window_end_state(orbit):
    M = orbit.model.n_modes + 1
    y = orbit.state_after_impact
    return np.concatenate(([orbit.phase + 2 / orbit.model.s], y[1:M], y[M:]))


# ---------------------------------------------------------------- rigid bar: exact identity -------
@pytest.mark.parametrize("load", [CosineLoad(0.3, 1.0), CosineLoad(0.05, 1.0, k=3),
                                  SquareWaveLoad(1.0, 1.3)])
@pytest.mark.parametrize("s, d, R", [(10.0, 0.0, 0.5), (3.0, 0.02, 0.2), (40.0, 0.01, 0.0)])
def test_rigid_identity(load, s, d, R):
    """Integrating ``q_0'' + d q_0' = p`` over the flight and adding the contact's momentum balance:
    the impact velocity is ``2 pi p0/(1 + R) - int_0^{1/s} p(phase + t) dt`` (the contact time
    shifts eq. 14's ``2 pi p0 / (1 + R)`` by the drive impulse of the window's first half)."""
    model = BarModel(s=s, d=d, R=R, n_modes=0, impact="wave")
    orbits = periodic_orbits(model, load)
    assert orbits
    for o in orbits:
        brk = [] if isinstance(load, CosineLoad) else [TWO_PI * math.ceil(o.phase / TWO_PI)]
        half = quad(lambda t, o=o: float(load(o.phase + t)), 0, 1 / s, points=[b - o.phase for b in brk
                    if 0 < b - o.phase < 1 / s] or None, epsabs=1e-14, epsrel=1e-13)[0]
        assert o.impact_velocity == pytest.approx(TWO_PI * load.p0 / (1 + R) - half, abs=1e-12)


@pytest.mark.parametrize("load", [CosineLoad(0.3, 1.0), CosineLoad(0.05, 1.0, k=2),
                                  SquareWaveLoad(1.0, 1.3)])
def test_rigid_limit_same_for_both_laws(load):
    """As ``s -> inf`` the window vanishes and the wave law's orbits tend to the paper's (O(1/s))."""
    for s in (1e3, 1e5):
        paper = periodic_orbits(BarModel(s=s, d=0.01, R=0.4, n_modes=0), load)
        waves = periodic_orbits(BarModel(s=s, d=0.01, R=0.4, n_modes=0, impact="wave"), load)
        assert len(paper) == len(waves)
        for a, b in zip(paper, waves, strict=True):
            assert b.phase == pytest.approx(a.phase, abs=20 / s)
            assert b.impact_velocity == pytest.approx(a.impact_velocity, abs=20 / s)
            np.testing.assert_allclose(np.sort_complex(b.multipliers), np.sort_complex(a.multipliers),
                                       rtol=50 / s, atol=50 / s)


# ---------------------------------------------------------------- flexible bar ---------------------
@pytest.mark.parametrize("load", [CosineLoad(0.3, 1.0), SquareWaveLoad(1.0, 1.3)])
def test_orbit_is_a_fixed_point_of_the_independent_map(load):
    model = BarModel(s=10.0, d=0.005, R=0.5, n_modes=5, impact="wave")
    orbits = periodic_orbits(model, load)
    assert orbits
    for o in orbits:
        z = window_end_state(o)
        z1 = flight_and_contact(model, load, z)
        z1[0] -= TWO_PI
        np.testing.assert_allclose(z1, z, rtol=0, atol=1e-10 * np.abs(z).max())


@pytest.mark.parametrize("load", [CosineLoad(0.3, 1.0), SquareWaveLoad(1.0, 1.3)])
def test_jacobian_against_finite_differences(load):
    model = BarModel(s=10.0, d=0.005, R=0.5, n_modes=4, impact="wave")
    from impactbar.laws.wave.periodic import wave_impact_map_jacobian, wave_orbit_states

    for o in periodic_orbits(model, load):
        _, ye, ym, rate = wave_orbit_states(model, load, o.phase)
        DP = wave_impact_map_jacobian(model, load, o.phase, ye, ym, rate)
        z = window_end_state(o)
        J = central_difference_jacobian(lambda x: flight_and_contact(model, load, x), z, relative=True)
        np.testing.assert_allclose(DP, J, rtol=0, atol=2e-5 * np.abs(DP).max())
        np.testing.assert_allclose(np.sort(np.abs(o.multipliers)), np.sort(np.abs(np.linalg.eigvals(J))),
                                   rtol=0, atol=1e-5 * o.max_abs_multiplier)


def test_flexible_multipliers_near_R():
    """Each flexible mode is multiplied by ``-R`` at the contact and decays over the flight
    ``2 pi - 2/s``: its multipliers lie near ``R exp(-d (pi - 1/s))`` (paper law: near the unit
    circle)."""
    d, R, s = 0.03 / TWO_PI, 0.5, 30.0
    load = CosineLoad(0.3, 1.0)
    target = R * math.exp(-d * (math.pi - 1 / s))
    for o in periodic_orbits(BarModel(s=s, d=d, R=R, n_modes=6, impact="wave"), load):
        assert np.sum(np.isclose(np.abs(o.multipliers), target, rtol=2e-3)) == 12  # 2 N of 2 N + 2
    paper = periodic_orbits(BarModel(s=s, d=d, R=R, n_modes=6), load)
    assert all(np.sort(np.abs(o.multipliers))[-3] > 0.9 for o in paper)


def test_window_longer_than_period_has_no_orbit():
    model = BarModel(s=0.3, d=0.0, R=0.5, n_modes=2, impact="wave")  # 2/s > 2 pi
    assert periodic_orbits(model, CosineLoad(0.3, 1.0)) == []


def test_impact_parameter_is_validated():
    with pytest.raises(ValueError, match="impact"):
        BarModel(s=1.0, d=0.0, R=0.5, n_modes=1, impact="rigid")
    assert BarModel(s=1.0, d=0.0, R=0.5, n_modes=1).impact == "paper"


def test_wave_existence_edge_matches_the_orbits():
    """Just below the edge there are orbits, just above none (pneumatic load, wave law)."""
    from impactbar.laws.wave.periodic import wave_existence_edge

    for k, s in ((1, 5.0), (3, 12.0)):
        model = BarModel(s=s, d=0.004, R=0.3, n_modes=3, impact="wave")
        edge = wave_existence_edge(model, k)
        assert len(periodic_orbits(model, CosineLoad(edge * (1 - 1e-7) / k, 1.0, k))) == 2 * k
        assert periodic_orbits(model, CosineLoad(edge * (1 + 1e-7) / k, 1.0, k)) == []


def test_wave_existence_edge_kept_per_model_is_the_computed_one():
    """The edge is kept per model and order (a chart asks for it in every search): an equal model
    built again gets the computed float to the bit, another restitution or order its own."""
    from impactbar.laws.wave.periodic import _existence_edge, wave_existence_edge

    model = BarModel(s=5.0, d=0.004, R=0.3, n_modes=3, impact="wave")
    edge = wave_existence_edge(model, 3)
    assert wave_existence_edge(BarModel(s=5.0, d=0.004, R=0.3, n_modes=3, impact="wave"), 3) == edge
    assert _existence_edge.__wrapped__(model, 3) == edge
    other = model.with_(R=0.4)
    assert wave_existence_edge(other, 3) == _existence_edge.__wrapped__(other, 3) != edge
    assert wave_existence_edge(model, 1) == _existence_edge.__wrapped__(model, 1) != edge


def test_stability_edges_under_the_wave_law():
    """The rigid-limit band of the wave law tends to the paper's ``1/sqrt(4 + pi^2) .. 1/pi`` at
    ``R = 0`` (theory §6); the paper's Schur criterion is refused under the wave law."""
    from impactbar.laws.wave.periodic import wave_existence_edge
    from impactbar.orbits.charts import pneumatic_stability_edges

    model = BarModel(s=2e4, d=0.0, R=0.0, n_modes=0, impact="wave")
    edges = pneumatic_stability_edges(model, 1)
    assert len(edges) == 1 and edges[0][1] == "period-doubling"
    assert edges[0][0] == pytest.approx(1 / math.sqrt(4 + math.pi**2), abs=1e-3)
    assert wave_existence_edge(model, 1) == pytest.approx(1 / math.pi, abs=1e-3)  # the fold
    with pytest.raises(ValueError, match="criterion"):
        pneumatic_stability_edges(model, 1, criterion="paper")


@pytest.mark.parametrize("load", [CosineLoad(0.3, 1.0), SquareWaveLoad(1.0, 1.3)])
def test_blow_impulse_is_the_drive_impulse_per_period(load):
    """Undamped, the momentum of a periodic motion returns each period: the rod receives per blow
    the drive's impulse ``2 pi p0``, and advances by ``2 pi p0 / Z_s``, ``Z_s = s (1 + R)/(1 - R)``
    (flexible piston, any phase of the contact)."""
    R, s = 0.4, 7.0
    for o in periodic_orbits(BarModel(s=s, d=0.0, R=R, n_modes=4, impact="wave"), load):
        assert o.impact.impulse == pytest.approx(TWO_PI * load.p0, rel=1e-12)
        assert o.impact.advance == pytest.approx(TWO_PI * load.p0 / (s * (1 + R) / (1 - R)), rel=1e-12)


def test_paper_law_charts_refuse_the_wave_law():
    """eq. 14's edges are not the wave law's: asking for them under impact='wave' is an error,
    not the paper law's answer in disguise."""
    from impactbar import SquareWaveLoad
    from impactbar.orbits.charts import hydraulic_existence_edge, max_phase_residual

    wave = BarModel(s=50.0, d=0.0, R=0.5, n_modes=0, impact="wave")
    with pytest.raises(ValueError, match="impact"):
        hydraulic_existence_edge(wave)
    with pytest.raises(ValueError, match="impact"):
        max_phase_residual(wave, SquareWaveLoad(1.0, 1.3))
    paper = BarModel(s=50.0, d=0.0, R=0.5, n_modes=0)
    assert hydraulic_existence_edge(paper) == pytest.approx((1.0 + math.sqrt(2.5)) / 1.5, abs=1e-9)


def test_phase_scan_reuses_its_samples_and_the_cached_flight_matrix():
    """The square wave's refined phase grid: the residual values it returns are those of
    ``wave_phase_residual`` at every returned phase (each phase evaluated once), the grid is the
    equispaced one plus 31 points around each sampled minimum of ``|r|``, and the cached flight
    matrix is the fundamental matrix over ``2 pi - 2/s``."""
    from impactbar.dynamics.modal import fundamental
    from impactbar.laws.wave.periodic import _flight_fundamental, _refined_grid, wave_phase_residual

    model = wave(BarModel(s=12.0, d=0.01, R=0.3, n_modes=5))
    load = SquareWaveLoad(0.08, 1.2)
    calls = []

    def resid(p):
        calls.append(np.size(p))
        return wave_phase_residual(model, load, p)

    grid, r = _refined_grid(resid, 129)
    np.testing.assert_array_equal(r, wave_phase_residual(model, load, grid))
    assert sum(calls) == grid.size  # no phase evaluated twice
    base = np.linspace(0.0, TWO_PI, 129)
    rb = np.abs(wave_phase_residual(model, load, base))
    minima = [i for i in range(1, 128) if rb[i] <= rb[i - 1] and rb[i] <= rb[i + 1]]
    assert minima
    expected = np.unique(np.concatenate([base] + [np.linspace(base[i - 1], base[i + 1], 33)[1:-1]
                                                  for i in minima]))
    np.testing.assert_array_equal(grid, expected)
    for a, b in zip(_flight_fundamental(model), fundamental(model.frequencies**2, model.d,
                                                             TWO_PI - 2.0 / model.s), strict=True):
        np.testing.assert_array_equal(a, b)


def test_square_wave_residual_compiled_as_wave_orbit_states(rng):
    """The phase residual of a piecewise-constant load in one compiled call against
    :func:`wave_orbit_states` phase by phase (the reference of ``"wave.residual"``), on
    random models and loads; and the same orbits from :func:`periodic_orbits` with either."""
    import importlib

    from impactbar import PiecewiseConstantLoad

    W = importlib.import_module("impactbar.laws.wave.periodic")
    for trial in range(16):
        model = BarModel(s=float(rng.choice([0.5, 1.0, 3.0, 10.0, 60.0])), d=float(rng.choice([0.0, 0.02])),
                         R=float(rng.uniform(0.0, 0.95)), n_modes=int(rng.integers(0, 9)), impact="wave")
        load = (SquareWaveLoad(rng.uniform(0.1, 3.0), rng.uniform(1.0, 2.0)) if trial % 2 else
                PiecewiseConstantLoad([0.0, 1.0, 3.0], [rng.uniform(-1.0, 2.0), 2.0, 0.5]))
        phases = rng.uniform(0.0, 2 * np.pi, 12)
        ref = np.array([W.wave_orbit_states(model, load, p, rates=False)[0] for p in phases])
        np.testing.assert_allclose(W.wave_phase_residual(model, load, phases), ref, rtol=1e-12,
                                   atol=1e-13 * np.abs(ref).max())
    model = BarModel(s=10.0, d=0.01, R=0.5, n_modes=4, impact="wave")
    load = SquareWaveLoad(1.0, 1.3)
    fast = periodic_orbits(model, load)
    with use_reference("wave.residual"):
        slow = periodic_orbits(model, load)
    assert len(fast) == len(slow) > 0
    for a, b in zip(fast, slow, strict=True):
        assert a.phase == pytest.approx(b.phase, abs=1e-12)
        assert a.admissibility == b.admissibility
        np.testing.assert_allclose(a.multipliers, b.multipliers, rtol=1e-10, atol=1e-12)


def test_states_from_the_phase_series_are_the_direct_ones(rng):
    """Under a load of finitely many harmonics the wave law's orbit states are evaluated from
    their trigonometric series in the phase (one set of ``2 K + 1`` samples per model and load,
    whose flights share one forced trajectory): against the flight from rest and the window's drive
    computed at each phase, on random models (the rigid bar, damped or not), loads and
    phases; the rates against ``window_drive``'s and against central differences of the states;
    every phase root a zero of the direct residual; a load with its own evaluation is computed
    phase by phase."""
    from impactbar import FourierLoad
    from impactbar.laws.wave import periodic as W
    from impactbar.laws.wave.impact import window_drive

    for trial in range(12):
        model = BarModel(s=float(rng.choice([1.0, 3.0, 10.0])), d=float(rng.choice([0.0, 0.03])),
                         R=float(rng.uniform(0.0, 0.9)), n_modes=int(rng.choice([0, 3, 8, 50])),
                         impact="wave")
        harmonics = rng.normal(size=3) + 1j * rng.normal(size=3)
        harmonics[1] *= trial % 2  # orders (1, 3) or (1, 2, 3)
        load = FourierLoad(float(rng.uniform(0.0, 1.0)), list(harmonics))
        assert W._has_series(model, load)
        for phase in rng.uniform(0.0, TWO_PI, 4):
            r, y_end, y_minus, (dg, dh), (g, h) = W._orbit_states(model, load, phase)
            r0, y_end0, y_minus0, _, (g0, h0) = W._direct_states(model, load, phase, rates=False)
            scale = np.abs(y_minus0).max()
            assert abs(r - r0) <= 1e-12 * scale
            for a, b in ((y_end, y_end0), (y_minus, y_minus0), (g, g0), (h, h0)):
                np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * max(scale, np.abs(b).max()))
            _, _, dg0, dh0 = window_drive(model.s, model.R, model.n_modes, load, phase, derivative=True)
            np.testing.assert_allclose(dg, dg0, rtol=0, atol=1e-11 * np.abs(dg0).max())
            np.testing.assert_allclose(dh, dh0, rtol=0, atol=1e-11 * np.abs(dh0).max())
            eps = 1e-5
            hp, hm = (W._direct_states(model, load, phase + e, rates=False)[4][1] for e in (eps, -eps))
            np.testing.assert_allclose(dh, (hp - hm) / (2 * eps), rtol=0, atol=1e-7 * np.abs(dh0).max())
        for phase, _ in W.wave_phase_roots(model, load):
            r0, _, y_minus0, _, _ = W._direct_states(model, load, phase, rates=False)
            assert abs(r0) <= 1e-11 * np.abs(y_minus0).max()

    class Shifted(FourierLoad):
        def __call__(self, t):
            return super().__call__(np.asarray(t) + 0.1)

    assert not W._has_series(BarModel(3.0, 0.0, 0.5, 4, impact="wave"), Shifted(0.3, [1.0]))
    assert not W._has_series(BarModel(0.3, 0.0, 0.5, 4, impact="wave"), CosineLoad(0.6, 1.0))  # 2/s > 2 pi
