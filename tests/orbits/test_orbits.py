"""One-impact orbits against closed forms (paper eqs. 35, 38, 39, 40), scipy integration,
finite-difference Jacobians and the paper's own integration constants (eqs. 12, 13)."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from impactbar import BarModel, CosineLoad, FourierLoad, SquareWaveLoad, periodic_orbits
from impactbar.orbits.phase import phase_G, phase_residual, phase_roots
from modal_reference import central_difference_jacobian, solve_modal

TWO_PI = 2 * math.pi


# ---------------------------------------------------------------- closed forms, d = 0 ------------
@pytest.mark.parametrize("k", [1, 2, 3])
@pytest.mark.parametrize("R", [0.0, 0.3, 0.8])
def test_eq35_pneumatic_phase(k, R):
    pk = 1.0
    p0 = 0.2 / k  # load factor k p0 / pk = 0.2, inside eq. 38 for every R
    orbits = periodic_orbits(BarModel(s=50.0, d=0.0, R=R, n_modes=0), CosineLoad(p0, pk, k))
    rhs = math.pi * k * (p0 / pk) * (1 - R) / (1 + R)
    assert len(orbits) == 2 * k
    for o in orbits:
        assert math.sin(k * o.phase) == pytest.approx(rhs, abs=1e-12)
    assert all(0 <= o.phase < TWO_PI for o in orbits)
    assert [o.phase for o in orbits] == sorted(o.phase for o in orbits)


@pytest.mark.parametrize("R", [0.0, 0.5, 0.9])
def test_eq38_existence_threshold(R):
    edge = (1 / math.pi) * (1 + R) / (1 - R)  # k p0 / pk at the fold
    model = BarModel(s=50.0, d=0.0, R=R, n_modes=0)
    assert len(periodic_orbits(model, CosineLoad(edge * (1 - 1e-6), 1.0))) == 2
    assert periodic_orbits(model, CosineLoad(edge * (1 + 1e-6), 1.0)) == []
    at = periodic_orbits(model, CosineLoad(edge, 1.0))  # the fold: one double root at pi/2
    assert len(at) in (1, 2)
    assert all(o.phase == pytest.approx(math.pi / 2, abs=1e-6) for o in at)


def _rigid_band(R, k=1):
    lo = (1 + R) ** 2 / math.sqrt(4 * (1 + R * R) ** 2 / k**2 + math.pi**2 * (1 - R * R) ** 2)
    hi = (1 / math.pi) * (1 + R) / (1 - R)
    return lo, hi


def test_eq39_band_R0_numbers_from_model_md():
    """The R = 0 stable band: the closed form gives 1/sqrt(4 + pi^2) = 0.268515 for the lower edge
    (0.26854 was once printed: its fifth digit is off), and the exact multipliers agree."""
    lo, hi = _rigid_band(0.0)
    assert lo == pytest.approx(1 / math.sqrt(4 + math.pi**2), rel=1e-15)
    assert lo == pytest.approx(0.26854, abs=3e-5)
    model = BarModel(s=50.0, d=0.0, R=0.0, n_modes=0)
    for p0, stable in ((lo * (1 - 1e-7), False), (lo * (1 + 1e-7), True)):
        branch = [o for o in periodic_orbits(model, CosineLoad(p0, 1.0)) if math.cos(o.phase) < 0]
        assert (branch[0].max_abs_multiplier < 1) is stable
    assert hi == pytest.approx(0.31831, abs=1e-5)


@pytest.mark.parametrize("R", [0.0, 0.2, 0.6])
@pytest.mark.parametrize("frac", [0.9, 0.99, 1.01, 1.1])
def test_eq39_stability_band_rigid(R, frac):
    """The paper's criterion and the exact multipliers agree for the rigid bar (sigma = 0)."""
    lo, hi = _rigid_band(R)
    p0 = lo * frac
    if p0 >= hi:
        pytest.skip("outside existence")
    orbits = periodic_orbits(BarModel(s=50.0, d=0.0, R=R, n_modes=0), CosineLoad(p0, 1.0))
    stable_branch = [o for o in orbits if math.cos(o.phase) < 0]
    other = [o for o in orbits if math.cos(o.phase) > 0]
    assert len(stable_branch) == 1 and len(other) == 1
    expect = frac > 1
    assert stable_branch[0].schur_stable is expect
    assert (stable_branch[0].max_abs_multiplier < 1) is expect
    assert not other[0].schur_stable and other[0].max_abs_multiplier > 1


def _g(y):
    y = np.mod(y, TWO_PI)
    return math.pi**2 / 6 - math.pi * y / 2 + y * y / 4


@pytest.mark.parametrize("R", [0.0, 0.4, 0.8])
@pytest.mark.parametrize("kappa", [1.05, 1.2, 1.5])
def test_eq40_hydraulic_closed_form(R, kappa):
    orbits = periodic_orbits(BarModel(s=50.0, d=0.0, R=R, n_modes=0), SquareWaveLoad(1.0, kappa))
    for o in orbits:
        lhs = (2 / math.pi) * (_g(kappa * math.pi - o.phase) - _g(o.phase))
        assert lhs == pytest.approx((kappa - 1) * math.pi * (1 - R) / (1 + R), abs=1e-12)
    # every root of the closed form is found: scan it independently
    f = lambda ph: (2 / math.pi) * (_g(kappa * math.pi - ph) - _g(ph)) - (  # noqa: E731
        kappa - 1) * math.pi * (1 - R) / (1 + R)
    grid = np.linspace(0, TWO_PI, 20001)
    vals = np.array([f(x) for x in grid])
    n_sign = int(np.sum(np.sign(vals[1:]) != np.sign(vals[:-1])))
    assert len(orbits) == n_sign


def test_square_wave_matches_long_fourier_series():
    """The exact square wave against 4000 of its harmonics (eq. 34)."""
    sq = SquareWaveLoad(1.0, 1.3)
    fl = FourierLoad(sq.p0, sq.harmonics(4000))
    model = BarModel(s=50.0, d=0.02, R=0.3, n_modes=0)
    a = [o.phase for o in periodic_orbits(model, sq)]
    b = [o.phase for o in periodic_orbits(model, fl)]
    assert len(a) == len(b) == 2
    assert np.allclose(a, b, atol=2e-3)


# ---------------------------------------------------------------- invariants ----------------------
loads = st.one_of(
    st.builds(CosineLoad, st.floats(0.05, 0.6), st.floats(0.5, 2.0), st.integers(1, 3)),
    st.builds(SquareWaveLoad, st.floats(0.5, 2.0), st.floats(1.02, 1.6)),
    st.builds(
        lambda p0, a, b: FourierLoad(p0, [a, b * 1j, 0.1 * a]),
        st.floats(0.05, 0.3),
        st.floats(0.5, 1.5),
        st.floats(-0.5, 0.5),
    ),
)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(load=loads, d=st.floats(0.0, 0.5), R=st.floats(0.0, 1.0))
def test_rigid_mode_strikes_at_2pi_p0_over_1_plus_R(load, d, R):
    for o in periodic_orbits(BarModel(s=10.0, d=d, R=R, n_modes=0), load):
        assert o.impact_velocity == pytest.approx(TWO_PI * load.p0 / (1 + R), rel=1e-10, abs=1e-12)
        assert phase_residual(o.model, load, o.phase) == pytest.approx(0, abs=1e-11)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(load=loads, d=st.floats(0.0, 0.3), R=st.floats(0.0, 0.95))
def test_no_root_missed_against_dense_scan(load, d, R):
    model = BarModel(s=10.0, d=d, R=R, n_modes=0)
    grid = np.linspace(0, TWO_PI, 40001)
    F = phase_residual(model, load, grid)
    sg = np.sign(F)
    sg = sg[sg != 0]  # a root exactly on a grid node (the square wave's jumps) is one crossing, not two
    n_sign = int(np.sum(sg[1:] != sg[:-1]))
    found = phase_roots(model, load)
    assert sum(m if m == 1 else 0 for _, m in found) >= n_sign - 0  # every crossing is found
    assert len([r for r, m in found if m == 1]) == n_sign


def test_G_series_is_continuous_at_zero_damping():
    for R in (0.0, 0.5, 1.0):
        assert phase_G(0.0, R) == pytest.approx(math.pi * (1 - R), rel=1e-15)
        for d in (1e-12, 1e-8, 1e-4, 1e-3, 0.0015, 0.002, 0.1):
            two = TWO_PI * (1 + R * math.exp(-TWO_PI * d)) / (-math.expm1(-TWO_PI * d)) - (1 + R) / d
            tol = 1e-14 / d + 1e-12  # the two-term form's own cancellation error
            assert phase_G(d, R) == pytest.approx(two, abs=tol)


@pytest.mark.parametrize("load", [CosineLoad(0.25, 1.0), SquareWaveLoad(1.0, 1.1)])
def test_continuity_as_damping_vanishes(load):
    """Orbits at d -> 0 converge linearly to those at d = 0 (no jump from the 1/d terms)."""
    model = BarModel(s=7.3, d=0.0, R=0.4, n_modes=6)
    o0 = periodic_orbits(model, load)
    o6 = periodic_orbits(model.with_(d=1e-6), load)
    o9 = periodic_orbits(model.with_(d=1e-9), load)
    assert len(o0) == len(o6) == len(o9) == 2
    for a, b, c in zip(o0, o6, o9, strict=True):
        for attr in ("phase", "impact_velocity"):
            e6 = abs(getattr(b, attr) - getattr(a, attr))
            e9 = abs(getattr(c, attr) - getattr(a, attr))
            assert e6 < 1e-3
            assert e9 <= 2e-3 * e6 + 1e-12  # linear in d
        assert np.allclose(np.sort(np.abs(c.multipliers)), np.sort(np.abs(a.multipliers)),
                           atol=1e-6)


# ---------------------------------------------------------------- against time integration -------
def _integrate_period(orbit):
    model = orbit.model
    _, y, _, _ = solve_modal(model.frequencies**2, model.d, orbit.load, orbit.state_after_impact, 0.0,
                             TWO_PI, shift=orbit.phase, rtol=1e-13)
    return y


@pytest.mark.parametrize(
    ("model", "load"),
    [
        (BarModel(s=3.0, d=0.0, R=0.5, n_modes=4), CosineLoad(0.3, 1.0)),
        (BarModel(s=2.0, d=0.1, R=0.0, n_modes=3), CosineLoad(0.1, 1.0, 2)),
        (BarModel(s=2.5, d=0.05, R=0.8, n_modes=3), SquareWaveLoad(1.0, 1.15)),
        (BarModel(s=1.3, d=0.02, R=0.6, n_modes=2), FourierLoad(0.1, [1.0, 0.3j, -0.2])),
    ],
)
def test_orbit_is_periodic_under_scipy_integration(model, load):
    orbits = periodic_orbits(model, load)
    assert orbits
    M = model.n_modes + 1
    JR = np.concatenate([np.ones(M), -model.R * np.ones(M)])
    for o in orbits:
        y_end = _integrate_period(o)
        scale = np.max(np.abs(o.state_after_impact)) + 1
        assert np.allclose(JR * y_end, o.state_after_impact, atol=1e-9 * scale)
        assert model.end_weights @ y_end[:M] == pytest.approx(0, abs=1e-9 * scale)
        assert model.end_weights @ y_end[M:] == pytest.approx(o.impact_velocity, abs=1e-9 * scale)
        assert o.end_displacement(0.0) == pytest.approx(0, abs=1e-12 * scale)


def test_paper_integration_constants_eq12_13():
    """Flexible modes: the state built here equals the paper's A_n, B_n (eqs. 8, 9, 12, 13)."""
    s, d, R, N = 1.7, 0.07, 0.35, 5
    load = FourierLoad(0.15, [1.0, 0.4 - 0.2j])
    model = BarModel(s=s, d=d, R=R, n_modes=N)
    for o in periodic_orbits(model, load):
        ph = o.phase
        ks = np.arange(0, 3)
        pk = np.array([load.p0, *load.harmonics()])
        for n in range(1, N + 1):
            lam = math.sqrt((s * n * math.pi) ** 2 - d * d / 4)
            H = 1 / ((s * n * math.pi) ** 2 + 1j * ks * d - ks**2)
            Em = np.exp(-math.pi * d - 2j * math.pi * lam)
            Ep = np.exp(-math.pi * d + 2j * math.pi * lam)
            Q = (1 + R) * np.sum(H * pk * 1j * ks * np.exp(1j * ks * ph)) / (
                (d / 2 + 1j * lam) * (1 + R * Em) * (1 - Ep)
                - (d / 2 - 1j * lam) * (1 + R * Ep) * (1 - Em)
            )
            A, B = (1 - Ep) * Q, -(1 - Em) * Q
            q0 = (A + B + np.sum(H * pk * np.exp(1j * ks * ph))).real
            v0 = ((-d / 2 - 1j * lam) * A + (-d / 2 + 1j * lam) * B
                  + np.sum(1j * ks * H * pk * np.exp(1j * ks * ph))).real
            assert o.state_after_impact[n] == pytest.approx(q0, abs=1e-12)
            assert o.state_after_impact[N + 1 + n] == pytest.approx(v0, abs=1e-12)


# ---------------------------------------------------------------- exact multipliers ---------------
def _impact_map(orbit, z):
    """Numerical impact map: from z = (tau, q_1..q_N, v_0..v_N) to the next, by closed-form
    flight and Brent's method for the impact time (independent of the analytic Jacobian)."""
    model, load = orbit.model, orbit.load
    M = model.n_modes + 1
    w2 = model.frequencies**2
    c = model.end_weights
    tau = z[0]
    q = np.concatenate([[-c[1:] @ z[1:M]], z[1:M]])
    v = z[M:]
    t0 = orbit.phase + tau

    def end(t):
        qq, _ = load.propagate(w2, model.d, t0, q, v, [t])
        return float(c @ qq[:, 0])

    tn = brentq(end, t0 + TWO_PI - 0.3, t0 + TWO_PI + 0.3, xtol=1e-15, rtol=1e-15)
    qq, vv = load.propagate(w2, model.d, t0, q, v, [tn])
    return np.concatenate([[tn - orbit.phase - TWO_PI], qq[1:, 0], -model.R * vv[:, 0]])


@pytest.mark.parametrize(
    ("model", "load"),
    [
        (BarModel(s=2.0, d=0.0, R=0.5, n_modes=0), CosineLoad(0.2, 1.0)),
        (BarModel(s=2.0, d=0.05, R=0.5, n_modes=3), CosineLoad(0.2, 1.0)),
        (BarModel(s=1.1, d=0.02, R=0.7, n_modes=4), FourierLoad(0.1, [1.0, 0.2j])),
        (BarModel(s=3.0, d=0.1, R=0.3, n_modes=2), SquareWaveLoad(1.0, 1.1)),
    ],
)
def test_multipliers_against_finite_difference_jacobian(model, load):
    from impactbar.orbits.stability import impact_map_jacobian

    for o in periodic_orbits(model, load):
        if o.impact_velocity <= 0:
            continue
        M = model.n_modes + 1
        z0 = np.concatenate([[0.0], o.state_after_impact[1:M], o.state_after_impact[M:]])
        assert np.allclose(_impact_map(o, z0), z0, atol=1e-10)
        J = central_difference_jacobian(lambda z, o=o: _impact_map(o, z), z0, relative=True)
        DP = impact_map_jacobian(model, load, o.phase, o.state_after_impact, o.state_before_impact)
        assert np.allclose(DP, J, atol=2e-6 * max(1.0, np.abs(J).max()))
        mu_fd = np.sort_complex(np.linalg.eigvals(J))
        assert np.allclose(np.sort(np.abs(mu_fd)), np.sort(np.abs(o.multipliers)), atol=1e-5)


@pytest.mark.parametrize("R", [0.0, 0.3, 0.9])
@pytest.mark.parametrize("p0", [0.1, 0.3, 0.45])
def test_rigid_limit_trace_and_determinant(R, p0):
    """theory §6: rigid bar, d = 0: xi^2 - (-2R + (1+R)^2 kappa_0) xi + R^2."""
    for o in periodic_orbits(BarModel(s=5.0, d=0.0, R=R, n_modes=0), CosineLoad(p0, 1.0)):
        kappa0 = float(o.load(o.phase)) / p0
        mu = o.multipliers
        assert np.sum(mu).real == pytest.approx(-2 * R + (1 + R) ** 2 * kappa0, abs=1e-10)
        assert np.prod(mu).real == pytest.approx(R * R, abs=1e-10)
        assert np.allclose(np.sort_complex(mu), np.sort_complex(o.schur_roots), atol=1e-9)


def test_exact_and_paper_agree_for_stiff_bar():
    """theory §7: for s pi >> k the exact rigid multiplier is within about 1 % of eq. 30."""
    model = BarModel(s=30.0, d=0.0, R=0.5, n_modes=8)
    for o in periodic_orbits(model, CosineLoad(0.5, 1.0)):
        rigid = o.schur_roots[:2]
        big = max(abs(rigid))
        assert o.max_abs_multiplier == pytest.approx(big, rel=0.02)


# ---------------------------------------------------------------- admissibility -------------------
@pytest.mark.parametrize(
    ("model", "load"),
    [
        (BarModel(s=0.33, d=0.0, R=0.5, n_modes=4), CosineLoad(0.2, 1.0)),  # near resonance s=1/pi
        (BarModel(s=10.0, d=0.01, R=0.3, n_modes=8), SquareWaveLoad(1.0, 1.2)),
        (BarModel(s=10.0, d=0.0, R=0.0, n_modes=0), CosineLoad(0.3, 1.0)),
        (BarModel(s=0.7, d=0.02, R=0.2, n_modes=6), CosineLoad(0.2, 1.0, 2)),
    ],
)
def test_admissibility_against_dense_sampling(model, load):
    t = np.linspace(1e-4, TWO_PI - 1e-4, 200001)
    for o in periodic_orbits(model, load):
        u = o.end_displacement(t)
        if o.admissibility == "admissible":
            assert np.all(u < 0)
            assert o.clearance < 0
        elif o.admissibility == "penetrates":
            assert u.max() > 0
            assert o.clearance == pytest.approx(u.max(), abs=1e-6 * max(1, abs(u).max()))
        elif o.admissibility == "sticks":
            assert model.R == 0
        assert o.stable <= o.admissible


def test_near_resonance_orbit_penetrates():
    """Near s = k/(n pi) (eq. 16) the flexible modes swing the end through the stop."""
    orbits = periodic_orbits(BarModel(s=1 / math.pi * 1.02, d=0.0, R=0.5, n_modes=3),
                             CosineLoad(0.2, 1.0))
    assert any(o.admissibility == "penetrates" for o in orbits)
    assert all(not o.stable for o in orbits if not o.admissible)


# ---------------------------------------------------------------- field evaluation ----------------
def test_field_broadcasting_and_end_consistency():
    o = periodic_orbits(BarModel(s=2.0, d=0.05, R=0.5, n_modes=5), CosineLoad(0.2, 1.0))[0]
    x = np.linspace(0, 1, 7)[:, None]
    t = np.linspace(0, TWO_PI, 11)[None, :]
    u = o.displacement(x, t)
    assert u.shape == (7, 11)
    assert np.allclose(u[-1], o.end_displacement(t[0]))
    v = o.velocity(1.0, np.array([1.0, 2.0]))
    h = 1e-6
    fd = (o.end_displacement(np.array([1.0, 2.0]) + h) - o.end_displacement(np.array([1.0, 2.0]) - h))
    assert np.allclose(v, fd / (2 * h), atol=1e-6)
    with pytest.raises(ValueError, match="x"):
        o.displacement(1.5, 0.0)


# ---------------------------------------------------------------- bad input -----------------------
def test_bad_inputs():
    with pytest.raises(ValueError, match="model"):
        periodic_orbits("bar", CosineLoad(0.2, 1.0))
    with pytest.raises(ValueError, match="load"):
        periodic_orbits(BarModel(1, 0, 0.5, 0), lambda t: t)
    with pytest.raises(ValueError, match="resonance"):
        periodic_orbits(BarModel(1 / math.pi, 0.0, 0.5, 2), CosineLoad(0.2, 1.0))


@settings(max_examples=30, deadline=None)
@given(p0=st.floats(-0.5, 0.5), pk=st.floats(0.2, 2.0), k=st.integers(1, 4), d=st.floats(0.0, 0.5),
       R=st.floats(0.0, 0.95))
def test_certified_search_agrees_with_closed_form(p0, pk, k, d, R):
    model = BarModel(s=10.0, d=d, R=R, n_modes=0)
    load = CosineLoad(p0, pk, k)
    a = phase_roots(model, load)
    b = phase_roots(model, load, closed_form=False)
    if any(m == 2 for _, m in a + b):
        return  # at a fold either side may see one double or two close roots
    assert len(a) == len(b)
    assert np.allclose([x for x, _ in a], [x for x, _ in b], atol=1e-10)


def test_elastic_undamped_edge_cases():
    """R = 1, d = 0: the rigid bar's phase-0 orbit has u_t(1, t) with a triple zero at t = pi (an
    inflection), found despite rounding; with flexible modes the orbits form a continuum."""
    orbits = periodic_orbits(BarModel(10.0, 0.0, 1.0, 0), CosineLoad(0.5, 0.5, 1))
    assert [round(o.phase, 12) for o in orbits] == [0.0, round(math.pi, 12)]
    t = np.linspace(1e-3, TWO_PI - 1e-3, 20001)
    for o in orbits:
        assert o.admissible
        u = o.end_displacement(t)
        # the largest stationary value: the inflection at t = pi for phase 0, the minimum for phase pi
        assert abs(o.clearance - float(o.end_displacement(math.pi))) <= o.clearance_error + 1e-9
        assert o.clearance_error < 1e-5
        assert u.max() < 0
    with pytest.raises(ValueError, match="continuum"):
        periodic_orbits(BarModel(10.0, 0.0, 1.0, 4), CosineLoad(0.5, 0.5, 1))
