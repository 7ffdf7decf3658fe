"""The fast paths against the general paths they replace (same orbits, flags and
multipliers to 1e-10 on random parameters): the rigid bar's closed forms, the structured eigenvalue
method for the multipliers, the vectorised sweep chunk."""

import math

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, FourierLoad, SquareWaveLoad, periodic_orbits
from impactbar.dynamics.implementations import implementation, use_reference
from impactbar.dynamics.modal import fundamental
from impactbar.laws.paper.periodic import _impact_states
from impactbar.loads.abilities import left_limit
from impactbar.orbits import impact_map_jacobian
from impactbar.orbits.one_impact import _periodic_orbits_general, orbit_multipliers
from impactbar.orbits.rigid import STATUS, rigid_cosine_orbits, rigid_multipliers
from impactbar.orbits.stability import floquet_multipliers, period_fundamental, sort_multipliers

TWO_PI = 2.0 * math.pi


def _set_distance(a, b):
    """Largest distance from a multiplier of one set to the nearest of the other, relative."""
    a, b = np.asarray(a), np.asarray(b)
    return max(max(np.min(np.abs(x - b)) / max(1.0, abs(x)) for x in a),
               max(np.min(np.abs(x - a)) / max(1.0, abs(x)) for x in b))


def _assert_same_orbits(fast, ref):
    assert len(fast) == len(ref)
    for o, g in zip(fast, ref, strict=True):
        assert o.phase == pytest.approx(g.phase, abs=1e-10)
        assert o.multiplicity == g.multiplicity
        assert o.admissibility == g.admissibility
        assert o.admissible == g.admissible
        assert o.stable == g.stable
        assert o.schur_stable == g.schur_stable
        assert o.impact_velocity == pytest.approx(g.impact_velocity, rel=1e-10, abs=1e-12)
        if math.isfinite(g.clearance):
            assert o.clearance == pytest.approx(g.clearance, rel=1e-10, abs=1e-12)
        else:
            assert o.clearance == g.clearance
        if np.all(np.isfinite(g.multipliers)):
            # to 1e-10 of the spectral radius: a dense eigensolver's error is relative to the norm
            scale = max(1.0, float(np.max(np.abs(g.multipliers))))
            assert _set_distance(o.multipliers, g.multipliers) < 1e-10 * scale
            assert np.allclose(np.abs(o.multipliers), np.abs(g.multipliers), rtol=1e-10, atol=1e-10 * scale)
        else:
            assert not np.all(np.isfinite(o.multipliers))
        fin = np.isfinite(g.schur_roots)
        assert np.array_equal(fin, np.isfinite(o.schur_roots))
        assert _set_distance(o.schur_roots[fin], g.schur_roots[fin]) < 1e-10 if fin.any() else True
        assert np.allclose(o.state_after_impact, g.state_after_impact, rtol=1e-10, atol=1e-12)
        assert np.allclose(o.state_before_impact, g.state_before_impact, rtol=1e-10, atol=1e-12)


def _random_rigid_case(rng, k):
    d = 0.0 if rng.random() < 0.3 else 0.3 * rng.random()
    R = 0.0 if rng.random() < 0.15 else (1.0 if rng.random() < 0.05 else rng.random())
    p0 = k * rng.uniform(-0.1, 0.6)
    pk = rng.uniform(-1.5, 1.5)
    return d, R, p0, pk


@pytest.mark.parametrize("k", [1, 2, 3])
def test_rigid_closed_form_equals_general_path(rng, k):
    """periodic_orbits on a rigid bar under one cosine harmonic (closed forms) against the general
    path (certified searches, dense Jacobian): phases, flags, clearance, multipliers."""
    seen = set()
    for _ in range(60):
        d, R, p0, pk = _random_rigid_case(rng, k)
        model, load = BarModel(1.0, d, R, 0), CosineLoad(p0, pk, k)
        fast = periodic_orbits(model, load)
        _assert_same_orbits(fast, _periodic_orbits_general(model, load))
        seen.update(o.admissibility for o in fast)
    assert {"admissible", "penetrates"} <= seen  # the random cases reach both sides


def test_rigid_square_wave_closed_form_equals_general_path(rng):
    """The square wave (eq. 34) on a rigid bar in closed form against the general path."""
    seen = set()
    for _ in range(120):
        d = 0.0 if rng.random() < 0.3 else 0.3 * rng.random()
        R = 0.0 if rng.random() < 0.15 else rng.random()
        model, load = BarModel(1.0, d, R, 0), SquareWaveLoad(rng.uniform(0.2, 2.0), rng.uniform(1.0, 1.9))
        fast = periodic_orbits(model, load)
        _assert_same_orbits(fast, _periodic_orbits_general(model, load))
        seen.update(o.admissibility for o in fast)
    assert {"admissible", "penetrates", "sticks"} <= seen


def test_square_wave_flight_keeps_the_rigid_invariant():
    """Regression: PiecewiseConstantLoad.propagate read the last piece's level past the next jump
    when that jump fell within 1 of the end time. The rigid mode must arrive at 2 pi p0/(1 + R)
    (theory §4) from every phase of the orbit equation, including phases after the jump."""
    d, R, q, kappa = 0.006055935902915799, 0.8705533043101933, 0.8301889996603169, 1.8392315437529074
    load = SquareWaveLoad(q, kappa)
    orbits = _periodic_orbits_general(BarModel(1.0, d, R, 0), load)
    assert any(o.phase > kappa * math.pi for o in orbits)
    for o in orbits:
        assert o.impact_velocity == pytest.approx(TWO_PI * load.p0 / (1.0 + R), rel=1e-12)


def test_rigid_vectorised_equals_pointwise(rng):
    """One call over a parameter array gives each point's orbits, padded with NaN / -1."""
    n = 50
    d = np.where(rng.random(n) < 0.3, 0.0, 0.2 * rng.random(n))
    R = rng.random(n)
    p0 = rng.uniform(0.0, 0.5, n)
    pk = rng.uniform(0.2, 1.5, n)
    res = rigid_cosine_orbits(d, R, p0, pk, 2)
    assert res.phase.shape == (n, 4) and res.multipliers.shape == (n, 4, 2)
    for i in range(n):
        orbits = periodic_orbits(BarModel(3.0, d[i], R[i], 0), CosineLoad(p0[i], pk[i], 2))
        assert res.n_orbits[i] == len(orbits)
        assert np.all(np.isnan(res.phase[i, len(orbits):]))
        assert np.all(res.status[i, len(orbits):] == -1)
        for j, o in enumerate(orbits):
            assert res.phase[i, j] == pytest.approx(o.phase, abs=1e-12)
            assert STATUS[res.status[i, j]] == o.admissibility
            assert res.max_abs_multiplier[i, j] == pytest.approx(o.max_abs_multiplier, rel=1e-12)


def _assert_scalar_equals_vectorised(found, res, i):
    """The plain-float orbits of one point against row ``i`` of the vectorised closed form."""
    if found is None:
        assert res.fallback[i]
        return
    assert not res.fallback[i]
    assert res.n_orbits[i] == len(found)
    for j, o in enumerate(found):
        assert o.phase == pytest.approx(res.phase[i, j], abs=1e-12)
        assert o.multiplicity == res.multiplicity[i, j]
        assert o.status == res.status[i, j]
        assert o.stable == res.stable[i, j] and o.schur_stable == res.schur_stable[i, j]
        for name in ("impact_velocity", "v_plus", "q_minus", "clearance", "clearance_error"):
            a, b = getattr(o, name), getattr(res, name)[i, j]
            assert a == b or a == pytest.approx(b, rel=1e-10, abs=1e-12), name
        scale = max(1.0, abs(res.multipliers[i, j, 0]))
        assert np.allclose(o.multipliers, res.multipliers[i, j], rtol=1e-10, atol=1e-12 * scale)
        assert _set_distance(o.schur_roots, res.schur_roots[i, j]) < 1e-10


@pytest.mark.parametrize("k", [1, 2, 3])
def test_rigid_scalar_path_equals_vectorised_closed_form(rng, k):
    """One point in plain floats (orbits/_rigid_scalar.py, what periodic_orbits uses) against the
    vectorised numpy closed form (what sweeps and charts use), on random parameters with the
    edge values d = 0, R = 0, R = 1: same orbits, flags, clearance, multipliers, fallbacks."""
    from impactbar.orbits import _rigid_scalar
    from impactbar.orbits.rigid import rigid_square_orbits

    cases = [_random_rigid_case(rng, k) for _ in range(400)] + [(0.1, 0.5, 0.0, 1.0)]
    d, R, p0, pk = (np.array(c) for c in zip(*cases, strict=True))
    res = rigid_cosine_orbits(d, R, p0, pk, k)
    for i, c in enumerate(cases):
        _assert_scalar_equals_vectorised(_rigid_scalar.cosine_orbits(*c, k), res, i)
    assert res.fallback.any() and (res.n_orbits == 0).any() and (res.status == 1).any()
    d = np.where(rng.random(400) < 0.3, 0.0, 0.3 * rng.random(400))
    R = np.where(rng.random(400) < 0.15, 0.0, rng.random(400))
    q, kappa = rng.uniform(0.2, 2.0, 400), rng.uniform(1.0, 1.95, 400)
    res = rigid_square_orbits(d, R, q, kappa)
    for i in range(400):
        _assert_scalar_equals_vectorised(_rigid_scalar.square_orbits(d[i], R[i], q[i], kappa[i]), res, i)
    assert (res.status == 4).any() and (res.status == 0).any()


def _assert_rigid_arrays_equal(fast, ref):
    """Two ``RigidOrbits`` of the same points: the same orbits, flags and fallbacks, the numbers to
    rounding (the points left to the general path are compared by their flag only)."""
    assert np.array_equal(fast.fallback, ref.fallback)
    ok = ~ref.fallback
    for name in ("n_orbits", "multiplicity", "status", "stable", "schur_stable"):
        assert np.array_equal(getattr(fast, name)[ok], getattr(ref, name)[ok]), name
    assert np.allclose(fast.phase[ok], ref.phase[ok], rtol=0.0, atol=1e-12, equal_nan=True)
    for name in ("impact_velocity", "v_plus", "q_minus", "clearance", "clearance_error"):
        a, b = getattr(fast, name)[ok], getattr(ref, name)[ok]
        assert np.array_equal(np.isinf(a), np.isinf(b)), name
        fin = np.isfinite(b) | np.isnan(b)
        assert np.allclose(a[fin], b[fin], rtol=1e-10, atol=1e-12, equal_nan=True), name
    used = ref.status[ok] >= 0
    mu_f, mu_r = fast.multipliers[ok][used], ref.multipliers[ok][used]
    scale = np.maximum(1.0, np.abs(mu_r[:, :1]))
    fin = np.isfinite(mu_r)
    assert np.array_equal(fin, np.isfinite(mu_f))
    assert np.all(np.abs(mu_f - mu_r)[fin] <= (1e-10 * scale * np.ones_like(mu_r.real))[fin])
    for a, b in zip(fast.schur_roots[ok][used], ref.schur_roots[ok][used], strict=True):
        assert _set_distance(a, b) < 1e-10  # a complex pair in either order


@pytest.mark.parametrize("k", [1, 2, 3])
def test_compiled_rigid_arrays_equal_numpy_closed_forms(rng, k):
    """The closed forms compiled point by point (orbits/_rigid_arrays.py, what sweeps use) against
    the vectorised numpy closed forms (the reference of "orbits.rigid_arrays"), which seek every
    zero of the flight's velocity where the kernel seeks only the maxima's (theory §5): the same
    orbits, flags, clearances, multipliers and fallbacks, on random parameters with the edge values
    d = 0, R = 0, R = 1 and a degenerate point."""
    cases = [_random_rigid_case(rng, k) for _ in range(600)] + [(0.1, 0.5, 0.0, 1.0)]
    d, R, p0, pk = (np.array(c) for c in zip(*cases, strict=True))
    fast = rigid_cosine_orbits(d, R, p0, pk, k)
    with use_reference("orbits.rigid_arrays"):
        ref = rigid_cosine_orbits(d, R, p0, pk, k)
    _assert_rigid_arrays_equal(fast, ref)
    assert fast.fallback.any() and (fast.n_orbits == 0).any()
    assert (fast.status == 1).any() and (fast.status == 0).any() and fast.stable.any()


def test_compiled_rigid_square_wave_equals_numpy_closed_forms(rng):
    """The same for the square wave (eq. 34), with kappa = 2 (a constant load: no orbit here)."""
    from impactbar.orbits.rigid import rigid_square_orbits

    n = 800
    d = np.where(rng.random(n) < 0.3, 0.0, 0.3 * rng.random(n))
    R = np.where(rng.random(n) < 0.15, 0.0, rng.random(n))
    q = rng.uniform(0.2, 2.0, n)
    kappa = np.where(rng.random(n) < 0.05, 2.0, rng.uniform(1.0, 1.95, n))
    fast = rigid_square_orbits(d, R, q, kappa)
    with use_reference("orbits.rigid_arrays"):
        ref = rigid_square_orbits(d, R, q, kappa)
    _assert_rigid_arrays_equal(fast, ref)
    assert np.all(fast.n_orbits[kappa == 2.0] == 0)
    assert (fast.status == 4).any() and (fast.status == 0).any() and (fast.status == 1).any()


def test_periodic_orbits_rigid_scalar_switch(rng, monkeypatch):
    """periodic_orbits on a rigid bar returns the same orbits with the plain-float path and with the
    vectorised closed form (the reference of "orbits.rigid_scalar"), fallbacks included."""

    cases = [(BarModel(1.0, *_random_rigid_case(rng, 1)[:2], 0), CosineLoad(*_random_rigid_case(rng, 1)[2:]))
             for _ in range(30)]
    cases += [(BarModel(1.0, 0.1 * rng.random(), rng.random(), 0),
               SquareWaveLoad(rng.uniform(0.2, 2.0), rng.uniform(1.0, 1.9))) for _ in range(30)]
    cases.append((BarModel(1.0, 0.1, 0.5, 0), CosineLoad(0.0, 1.0)))  # degenerate: the general path
    for model, load in cases:
        fast = periodic_orbits(model, load)
        with use_reference("orbits.rigid_scalar"):
            ref = periodic_orbits(model, load)
        _assert_same_orbits(fast, ref)
        assert all(o.multipliers.dtype == complex and o.state_after_impact.shape == (2,) for o in fast)


def test_rigid_closed_form_invariants():
    """Independent checks: the rigid mode strikes at 2 pi p0 / (1 + R) (theory §4), and at d = 0
    the rigid block is xi^2 - (-2R + (1+R)^2 kappa_0) xi + R^2 with kappa_0 = p(phase)/p0 (theory §6)."""
    R, p0 = 0.4, 0.3
    res = rigid_cosine_orbits(0.0, R, p0, 1.0, 1)
    assert res.n_orbits[0] == 2
    for j in range(2):
        assert res.impact_velocity[0, j] == pytest.approx(TWO_PI * p0 / (1 + R), rel=1e-13)
        kappa0 = (p0 + math.cos(res.phase[0, j])) / p0
        expected = np.roots([1.0, -(-2 * R + (1 + R) ** 2 * kappa0), R * R])
        assert _set_distance(res.multipliers[0, j], expected) < 1e-12


def test_rigid_degenerate_orbit_falls_back_to_general_path():
    """p0 = 0: the end arrives at rest (grazing); the closed form declines and periodic_orbits
    returns the general path's answer."""
    res = rigid_cosine_orbits(0.1, 0.5, 0.0, 1.0, 1)
    assert res.fallback[0]
    model, load = BarModel(1.0, 0.1, 0.5, 0), CosineLoad(0.0, 1.0)
    _assert_same_orbits(periodic_orbits(model, load), _periodic_orbits_general(model, load))


@pytest.mark.parametrize("d, R, load", [
    (1e-6, 1e-9, CosineLoad(1.0568994031282851e-07, -0.1962943504503838, 5)),  # leaves nearly at rest
    (5.0, 1e-9, SquareWaveLoad(1.287036878130578e-06, 1.000000001)),  # arrives nearly at rest
    (50.0, 0.5, CosineLoad(3.0, 0.5, 2)),  # heavy damping, the load never pulls
    (1e-12, 0.999999, SquareWaveLoad(5.0, 1.9)),
])
def test_rigid_extreme_parameters_equal_general_path(d, R, load):
    """Cases found by fuzzing: nearly-at-rest departures and arrivals go to the general path,
    extreme damping and restitution stay in the closed form, and both agree."""
    model = BarModel(1.0, d, R, 0)
    _assert_same_orbits(periodic_orbits(model, load), _periodic_orbits_general(model, load))


def test_rigid_multipliers_equal_jacobian_eigenvalues(rng):
    """The 2 x 2 closed form against the eigenvalues of the analytic Jacobian, for a load with
    several harmonics and the square wave (the general path's orbits)."""
    loads = [FourierLoad(0.3, [1.0, 0.3 - 0.2j, 0.1]), SquareWaveLoad(1.0, 1.15)]
    for load in loads:
        for R in (0.2, 0.7):
            model = BarModel(1.0, 0.05, R, 0)
            for o in periodic_orbits(model, load):
                yp, ym = _impact_states(model, load, o.phase)
                dense = np.linalg.eigvals(impact_map_jacobian(model, load, o.phase, yp, ym))
                mu = rigid_multipliers(0.05, R, float(load(o.phase)), float(left_limit(load, o.phase)),
                                       yp[1], ym[1])
                assert _set_distance(mu, dense) < 1e-10
                assert _set_distance(orbit_multipliers(model, load, o.phase), dense) < 1e-10


@pytest.mark.parametrize("n_modes", [40, 72, 200])
def test_structured_multipliers_equal_dense_eigvals(rng, n_modes):
    """The block-diagonal-plus-rank-2 method (Aberth iteration) against numpy's dense eigvals of
    the impact map's Jacobian, on random bars and loads."""
    cases = [(CosineLoad(0.3, 1.0), 0.5), (CosineLoad(0.25, 1.0, 2), 0.8),
             (SquareWaveLoad(1.0, 1.2), 0.5), (FourierLoad(0.3, [1.0, 0.2j]), 0.3),
             (CosineLoad(0.3, 1.0), 0.0), (CosineLoad(0.3, 1.0), 0.02)]
    heavy = (CosineLoad(0.05, 1.0), 0.6)  # and one with d = 0.95, near the structured method's limit
    checked = 0
    for load, R in [*cases, heavy]:
        s = rng.uniform(1.5, 6.0)
        d = 0.95 if (load, R) == heavy else rng.uniform(0.0, 0.2)
        model = BarModel(s, d, R, n_modes)
        for ph, _ in _phases(model, load):
            yp, ym = _impact_states(model, load, ph)
            dense = np.linalg.eigvals(impact_map_jacobian(model, load, ph, yp, ym))
            fast = floquet_multipliers(model, load, ph, yp, ym, method="structured")
            assert fast.shape == dense.shape
            assert _set_distance(fast, dense) < 1e-10
            checked += 1
    assert checked >= 8


def test_compiled_aberth_gives_up_cleanly():
    """The compiled Aberth sweeps: the same zeros as dense eigvals when they settle, ``None`` (so the
    dense method takes over) when the sweeps run out or a start sits on a pole, never an error."""
    from impactbar.dynamics._aberth import aberth_iterate
    from impactbar.dynamics.monodromy import aberth
    from impactbar.laws.paper.stability import _structured_parts

    model, load = BarModel(5.0, 0.1, 0.5, 48), CosineLoad(0.6, 1.0)
    ph = _phases(model, load)[0][0]
    yp, ym = _impact_states(model, load, ph)
    parts = _structured_parts(model, load, ph, yp, ym)
    dense = np.linalg.eigvals(impact_map_jacobian(model, load, ph, yp, ym))
    mu = aberth(*parts)
    assert mu is not None and mu.shape == (2 * 49,)
    assert _set_distance(mu, dense) < 1e-10
    assert aberth(*parts, iters=1) is None
    x = np.full(4, 1.0 + 0.0j)  # on the pole of a block with trace 1, determinant 0
    assert not aberth_iterate(x, np.ones(2), np.zeros(2), np.zeros((4, 2)), np.zeros(2, complex), 5, 1e-12)
    a, b, c, e, U, V, ut, vt = parts  # factors that are not the extended state's: refused
    V = V.copy()
    V[3, 0, 0] = 1.0
    with pytest.raises(ValueError, match="extended state"):
        aberth(a, b, c, e, U, V, ut, vt)


def test_heavy_damping_keeps_the_dense_method():
    """With d > 1 the automatic choice is the dense method (see floquet_multipliers)."""
    model, load = BarModel(2.0, 3.0, 0.5, 40), CosineLoad(0.02, 1.0)
    ph = _phases(model, load)[0][0]
    yp, ym = _impact_states(model, load, ph)
    auto = floquet_multipliers(model, load, ph, yp, ym)
    assert np.array_equal(auto, floquet_multipliers(model, load, ph, yp, ym, method="dense"))


def _phases(model, load):
    from impactbar.orbits import phase_roots

    return phase_roots(model, load)


def test_floquet_multipliers_method_is_checked():
    model, load = BarModel(2.0, 0.1, 0.5, 2), CosineLoad(0.3, 1.0)
    o = periodic_orbits(model, load)[0]
    with pytest.raises(ValueError, match="method"):
        floquet_multipliers(model, load, o.phase, o.state_after_impact, o.state_before_impact,
                            method="qr")


def test_periodic_orbits_with_many_modes_equal_dense_reference():
    """periodic_orbits at 48 modes (structured multipliers) against the dense method."""
    model, load = BarModel(2.5, 0.08, 0.6, 48), CosineLoad(0.3, 1.0)
    for o in periodic_orbits(model, load):
        yp, ym = o.state_after_impact, o.state_before_impact
        dense = floquet_multipliers(model, load, o.phase, yp, ym, method="dense")
        assert np.allclose(np.abs(o.multipliers), np.abs(dense), rtol=1e-10, atol=1e-12)
        assert _set_distance(o.multipliers, dense) < 1e-10


def test_sort_multipliers_orders_by_modulus_then_imaginary_part():
    mu = np.array([0.5 - 0.5j, 2.0, 0.5 + 0.5j, -0.1, np.inf])
    out = sort_multipliers(mu)
    assert out[0] == np.inf and out[1] == 2.0
    assert out[2] == 0.5 + 0.5j and out[3] == 0.5 - 0.5j and out[4] == -0.1


def test_period_fundamental_is_cached_and_exact():
    model = BarModel(3.0, 0.2, 0.5, 5)
    a = period_fundamental(model)
    assert period_fundamental(BarModel(3.0, 0.2, 0.5, 5)) is a
    ref = fundamental(model.frequencies**2, 0.2, TWO_PI)
    for x, y in zip(a, ref, strict=True):
        assert np.array_equal(x, y)
        assert not x.flags.writeable


def test_sweep_chunk_closed_form_equals_point_by_point(monkeypatch):
    """compute_chunk's vectorised rigid path against the point-by-point path, over axes of k, p0,
    d and R (R = 0 and R = 1 included)."""
    from impactbar.sweeps.spec import parse_spec

    spec = parse_spec({
        "task": "orbits",
        "model": {"s": 10.0, "d": 0.05, "R": 0.5, "n_modes": 0},
        "load": {"kind": "cosine", "p0": 0.3, "pk": 1.0, "k": 1},
        "axes": {"k": {"values": [1, 3]}, "p0": {"start": -0.2, "stop": 1.2, "num": 8},
                 "d": {"values": [0.0, 0.1]}, "R": {"values": [0.0, 0.35, 1.0]}},
        "chunk_points": 20,
    })
    fast = _assert_chunks_equal_point_by_point(spec, monkeypatch)
    assert sum(int(np.sum(c["n_orbits"])) for c in fast) > 20


def _assert_chunks_equal_point_by_point(spec, monkeypatch):
    """Every chunk by compute_chunk's closed forms, numpy's (a small sweep's) and the compiled ones
    (a sweep of 100,000 points or more), and point by point; returns the compiled ones' chunks."""
    from impactbar.sweeps import tasks

    numpy_ = [tasks.compute_chunk(spec, c) for c in range(spec.n_chunks)]
    monkeypatch.setattr(tasks, "COMPILED_CLOSED_FORMS_FROM", 0)
    fast = [tasks.compute_chunk(spec, c) for c in range(spec.n_chunks)]
    monkeypatch.setattr(tasks, "_rigid_chunk", lambda *a: None)
    slow = [tasks.compute_chunk(spec, c) for c in range(spec.n_chunks)]
    for a, b, c in zip(fast, slow, numpy_, strict=True):
        assert a.keys() == b.keys() == c.keys()
        for name in a:
            if a[name].dtype.kind == "f":
                assert np.allclose(a[name], b[name], rtol=1e-10, atol=1e-12, equal_nan=True), name
                assert np.allclose(c[name], b[name], rtol=1e-10, atol=1e-12, equal_nan=True), name
            else:
                assert np.array_equal(a[name], b[name]), name
                assert np.array_equal(c[name], b[name]), name
    return fast


def test_small_rigid_sweep_loads_no_numba():
    """A rigid closed-form sweep below 100,000 points takes the numpy closed forms and imports no
    numba; a larger one takes the compiled loop (the same numbers: the tests above)."""
    _run_python(
        "import sys\n"
        "from impactbar.sweeps.spec import parse_spec\n"
        "from impactbar.sweeps import tasks\n"
        "def spec(n):\n"
        "    return parse_spec({'task': 'orbits', 'model': {'s': 10.0, 'd': 0.0, 'R': 0.5, 'n_modes': 0},\n"
        "                       'load': {'kind': 'cosine', 'p0': 0.3, 'pk': 1.0, 'k': 1},\n"
        "                       'axes': {'R': {'start': 0.0, 'stop': 0.9, 'num': n},\n"
        "                                'p0': {'start': 0.2, 'stop': 0.45, 'num': n}}})\n"
        "assert tasks.compute_chunk(spec(300), 0)['n_orbits'].sum() > 0\n"
        "assert 'numba' not in sys.modules\n"
        "assert tasks.compute_chunk(spec(320), 0)['n_orbits'].sum() > 0\n"
        "assert 'numba' in sys.modules\n"
    )


def test_sweep_chunk_square_wave_closed_form_equals_point_by_point(monkeypatch):
    """The same for the square wave, kappa = 2 (a constant load, left to the general path) included."""
    from impactbar.sweeps.spec import parse_spec

    spec = parse_spec({
        "task": "orbits",
        "model": {"s": 10.0, "d": 0.05, "R": 0.5, "n_modes": 0},
        "load": {"kind": "square", "q": 1.0, "kappa": 1.2},
        "axes": {"kappa": {"values": [1.0, 1.1, 1.3, 1.45, 2.0]}, "R": {"values": [0.0, 0.35, 0.9]},
                 "d": {"values": [0.0, 0.1]}},
        "chunk_points": 7,
    })
    fast = _assert_chunks_equal_point_by_point(spec, monkeypatch)
    assert sum(int(np.sum(c["n_orbits"])) for c in fast) > 10


def _run_python(code):
    """Run ``code`` in a fresh interpreter; fail with its stderr if it fails."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr


def test_import_is_light_and_every_public_name_resolves():
    """``import impactbar`` and building the CLI parser load none of scipy.optimize, numba, pint,
    dask, xarray, zarr, matplotlib (they come on first use); every name of ``__all__`` (package and
    ``impactbar.physical``) still resolves."""
    _run_python(
        "import sys, impactbar, impactbar.cli\n"
        "impactbar.cli.build_parser()\n"
        "heavy = [m for m in ('scipy.optimize', 'numba', 'pint', 'dask', 'distributed', 'xarray', "
        "'zarr', 'matplotlib') if m in sys.modules]\n"
        "assert not heavy, heavy\n"
        "for name in impactbar.__all__: getattr(impactbar, name)\n"
        "for name in impactbar.physical.__all__: getattr(impactbar.physical, name)\n"
        "from impactbar import simulate, periodic_orbits, PeriodicOrbit, run_sweep, plot_sweep\n"
        "assert 'numba' in sys.modules\n"
        "assert 'periodic_orbits' in dir(impactbar) and callable(impactbar.simulate)\n"
    )
    with pytest.raises(AttributeError):
        import impactbar

        impactbar.no_such_name  # noqa: B018


def test_rigid_orbits_load_neither_numba_nor_scipy_optimize():
    """A first rigid-bar ``periodic_orbits`` call in a fresh process takes the closed forms without
    loading the wave law's or the kernel's heavy imports; a wave-law call then loads them."""
    _run_python(
        "import sys\n"
        "from impactbar import BarModel, CosineLoad, SquareWaveLoad, periodic_orbits\n"
        "assert periodic_orbits(BarModel(5, 0.1, 0.5, 0), CosineLoad(0.6, 1))\n"
        "assert periodic_orbits(BarModel(5, 0.1, 0.5, 0), SquareWaveLoad(1, 1.2))\n"
        "heavy = [m for m in ('scipy.optimize', 'numba') if m in sys.modules]\n"
        "assert not heavy, heavy\n"
        "periodic_orbits(BarModel(5, 0.1, 0.5, 0, impact='wave'), CosineLoad(0.6, 1))\n"
        "assert 'scipy.optimize' in sys.modules\n"
    )


def test_simulation_core_is_built_once_and_runs_are_unchanged():
    """simulate reuses the kernel data of a (model, load) pair; a run with the cached core equals
    one with a freshly built core, impact for impact."""
    import importlib

    from impactbar import InitialState, simulate

    sim_module = importlib.import_module("impactbar.simulation._core")

    model, load = BarModel(1.37, 0.02, 0.8, 3), CosineLoad(1.2, 1.0)
    start = InitialState.rigid(-0.05, 0.0, 3)
    first = simulate(model, load, start, 60.0)
    core = sim_module._core_for(model, load)
    assert sim_module._core_for(BarModel(1.37, 0.02, 0.8, 3), load) is core
    assert sim_module._core_for(model, CosineLoad(1.2, 1.0)) is core  # keyed by the load's value
    assert sim_module._core_for(model, CosineLoad(1.2, 3.0)) is not core
    again = simulate(model, load, start, 60.0)
    sim_module._CORES.clear()
    fresh = simulate(model, load, start, 60.0)
    assert first.n_impacts > 5
    assert np.array_equal(again.impact_times, first.impact_times)
    assert np.array_equal(fresh.impact_times, first.impact_times)


def test_kernel_compiles_in_memory_without_a_cache_folder():
    """With no writable cache folder (a read-only install) the kernel still imports and compiles,
    in memory; normally it caches on disk."""
    _run_python(
        "import numba.core.caching as c\n"
        "(getattr(c, 'CacheImpl', None) or c._CacheImpl)._locator_classes = []\n"
        "from impactbar.dynamics import _crossing as K\n"
        "assert K.CACHE is False\n"
        "b, cc = K._bc(0.0, 2.0)\n"
        "assert (b, cc) == (2.0, 2.0)\n"
    )
    from impactbar.dynamics import _event_loop

    assert _event_loop.CACHE is True


def test_long_run_holds_its_trajectory_about_once():
    """Peak memory of a 30,000-impact run is close to what the trajectory stores (the kernel
    writes into the log's rows, grown in place), not twice it."""
    import tracemalloc

    from impactbar import InitialState, simulate

    model, load = BarModel(1.37, 0.02, 0.8, 8), CosineLoad(1.2, 1.0)
    o = next(o for o in periodic_orbits(model, load) if o.stable)
    q, v = o.modal_state_after_impact
    q[0] -= 1e-3
    start = InitialState(q, v)
    simulate(model, load, start, o.phase + 1e6, t0=o.phase, max_impacts=5)
    tracemalloc.start()
    try:
        tr = simulate(model, load, start, o.phase + 1e6, t0=o.phase, max_impacts=30_000)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    seg = tr._segments
    stored = sum(a.nbytes for a in (seg.t, seg.basis, seg.entry, seg.q, seg.v, tr.impact_times,
                                    tr.impact_velocities))
    assert tr.n_impacts == 30_000 and len(seg) == 30_001
    assert peak < 1.3 * stored
    # the stored pieces are the impacts themselves: the end is on the stop after each
    assert np.allclose(seg.q[1:] @ model.end_weights, 0.0, atol=1e-12)


def test_certified_phase_roots_see_a_sign_change_below_the_smallest_normal():
    """Regression (found by the hypothesis test of test_orbits): with p0 = 5e-324 the residual at
    the bracket's ends is denormal and their product underflows to 0; the sign change must still
    be seen, so the certified search finds both roots of sin(phase) = p0 G / p1, near 0 and pi."""
    from impactbar.orbits import phase_roots

    model, load = BarModel(10.0, 0.0, 0.0, 0), CosineLoad(5e-324, 1.0)
    a = phase_roots(model, load)
    b = phase_roots(model, load, closed_form=False)
    assert len(a) == len(b) == 2
    assert np.allclose([x for x, _ in a], [x for x, _ in b], atol=1e-10)
    assert np.allclose([x for x, _ in b], [0.0, math.pi], atol=1e-10)


def _random_rigid_run(rng):
    """A random rigid bar under one harmonic and a start, with the general search's run."""
    import importlib

    from impactbar import InitialState, simulate

    sim_module = importlib.import_module("impactbar.simulation._core")
    k = int(rng.integers(1, 4))
    d, R, p0, pk = _random_rigid_case(rng, k)
    model, load = BarModel(2.0, d, R, 0), CosineLoad(p0, pk, k)
    start = InitialState.rigid(-rng.uniform(0.0, 1.0), rng.uniform(-2.0, 2.0))
    t0 = rng.uniform(0.0, TWO_PI)
    with use_reference("simulate.impact_search"):
        ref = simulate(model, load, start, t0 + 60.0, t0=t0)
    return sim_module._core_for(model, load), ref


def test_rigid_one_harmonic_impact_search_equals_general_search(rng):
    """The rigid bar's scalar impact search (kernel ``rigid1_crossing``) finds the same next event
    as the general certified search (``find_crossing``) from the start of every flight between two
    impacts of random runs (random d, R, p0, pk, k, starts; chatter and sticking included): the
    same status, the impact time to 1e-12 (relative to 1 + |t|) wherever the arrival is not grazing
    (``|u_t| >= 1e-3``), and below that to the rounding of the end's displacement (the time of
    a grazing arrival is only defined to ``noise / |u_t|``)."""
    from impactbar.dynamics import _crossing as K

    n_flights = n_slow = 0
    for _ in range(40):
        core, ref = _random_rigid_run(rng)
        D, B = core.data, core.free
        seg = ref._segments
        for i in np.nonzero((seg.entry[:-1] == 1) & (seg.entry[1:] == 1))[0]:  # the flights taken
            t, qa, va = float(seg.t[i]), seg.q[i].copy(), seg.v[i].copy()
            htol = 1e-14 * abs(qa[0])
            q, v = np.empty(1), np.empty(1)
            st, tc = K.find_crossing(D, B.view, core.c, 0.0, np.array([t]), qa.copy(), va.copy(),
                                     ref.t_end, htol, (q, v, *(np.empty(1) for _ in range(4))))
            h1 = (D.ks[0], D.pr[0], D.pim[0], B.hpr[0, 0], B.hpi[0, 0], math.hypot(B.hpr[0, 0], B.hpi[0, 0]))
            st2, tc2, q2, v2, _, _ = K.rigid1_crossing(core.d, 1.0, D.p0, h1, t, qa[0], va[0], ref.t_end,
                                                       htol)
            assert st2 == st
            n_flights += 1
            if st != K.CROSS:
                continue
            scale = 1.0 + abs(tc)
            if abs(v[0]) >= 1e-3:
                assert abs(tc2 - tc) <= 1e-12 * scale
                assert v2 == pytest.approx(v[0], rel=1e-10, abs=1e-9)
            else:
                n_slow += 1
                assert abs(tc2 - tc) * abs(v[0]) <= 1e-14 * scale
    assert n_flights > 200 and n_slow > 10


@pytest.mark.parametrize("case", ["settles", "chatter", "sticks"])
def test_rigid_one_harmonic_simulate_equals_general_search(case):
    """simulate with the rigid bar's scalar search gives the run of the general search: the same
    impacts (count, times to 1e-12 relative, velocities), contact intervals, status and final
    state; on a run that settles on a stable orbit, one that chatters into permanent contact,
    and one that sticks and releases every period (to 1e-9 where chatter's grazing bounces
    carry rounding from one bounce to the next)."""
    from impactbar import InitialState, simulate

    model, load = BarModel(1.37, 0.02, 0.8, 0), CosineLoad(1.2, 1.0)
    orbit = next(o for o in periodic_orbits(model, load) if o.stable)
    q, v = orbit.modal_state_after_impact
    model, load, start, t0 = {
        "settles": (model, load, InitialState(q - [0.05], v), orbit.phase),
        "chatter": (BarModel(1.37, 0.1, 0.5, 0), CosineLoad(0.3, 1.0), InitialState.rigid(-0.1, 0.0), 0.0),
        "sticks": (BarModel(2.0, 0.05, 0.0, 0), CosineLoad(0.2, 1.0, 2), InitialState.rigid(-0.2, 0.5), 0.0),
    }[case]
    runs = {}
    for fast in (False, True):
        with implementation("simulate.impact_search", "fast" if fast else "reference"):
            runs[fast] = simulate(model, load, start, t0 + 400.0, t0=t0)
    ref, new = runs[False], runs[True]
    assert ref.n_impacts > 20
    assert new.n_impacts == ref.n_impacts and new.status == ref.status
    if case != "chatter":
        assert np.all(np.abs(new.impact_times - ref.impact_times) <= 1e-12 * (1.0 + np.abs(ref.impact_times)))
    # a chatter sequence ends in bounces of speed ~1e-6, timed to rounding / speed, and the next
    # bounces start from there: its times agree to that conditioning
    np.testing.assert_allclose(new.impact_times, ref.impact_times, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(new.impact_velocities, ref.impact_velocities, rtol=1e-6, atol=1e-9)
    assert new.contact_intervals.shape == ref.contact_intervals.shape
    np.testing.assert_allclose(new.contact_intervals, ref.contact_intervals, rtol=1e-9, atol=1e-9)
    if case == "chatter":
        assert ref.contact_intervals.shape[0] >= 2
    if case == "sticks":
        assert ref.contact_intervals.shape[0] >= 5


def _modal_search_constants(core):
    """The per-model inputs of the kernel's ``modal_crossing``, formed as ``run_free`` forms them."""
    B, D, c, d = core.free, core.data, core.c, core.d
    lam = np.sqrt(np.abs(B.w2 - 0.25 * d * d))
    hs = np.hypot(B.hpr, B.hpi).sum(axis=1)
    static = np.where(B.w2 > 0, abs(D.p0) / np.where(B.w2 > 0, B.w2, 1.0), 0.0)
    return (lam, np.sqrt(B.w2), c @ B.hpr, c @ B.hpi, (c * B.w2) @ B.hpr, (c * B.w2) @ B.hpi,
            float(np.sum(2 * np.abs(c) * (hs + static))), float(np.sum(2 * np.abs(c) * B.vpb)))


@pytest.mark.parametrize("n_modes", [1, 4, 12, 40])
def test_modal_impact_search_equals_general_search(rng, n_modes):
    """The flexible bar's impact search in folded form (kernel ``modal_crossing``: one sine and
    cosine per mode, coarse steps on a bound free of the modes) finds the same next event as the
    general certified search (``find_crossing``) from the start of every flight between two impacts
    of random runs
    (random s, d, R, Fourier loads with one to three harmonics, random modal starts): the same
    status, the impact time to 1e-12 relative to 1 + |t| where the arrival is fast (``|u_t| >= 0.1``),
    and for every arrival to the rounding of the end's displacement (a slow arrival's time is only
    defined to ``noise / |u_t|``)."""
    import importlib

    from impactbar import InitialState, simulate
    from impactbar.dynamics import _crossing as K

    sim_module = importlib.import_module("impactbar.simulation._core")
    n_flights = n_slow = 0
    for _ in range(12 if n_modes < 40 else 4):
        s = rng.uniform(0.5, 3.0)
        d = 0.0 if rng.random() < 0.25 else 0.2 * rng.random()
        R = rng.uniform(0.0, 0.95)
        harmonics = rng.normal(size=int(rng.integers(1, 4))) * (rng.random() < 0.5 or 1j)
        load = FourierLoad(rng.uniform(-0.1, 1.0), harmonics)
        model = BarModel(s, d, R, n_modes)
        q = np.concatenate(([-rng.uniform(0.05, 0.5)], 0.01 * rng.normal(size=n_modes)))
        v = np.concatenate(([rng.uniform(-1.0, 1.0)], 0.05 * rng.normal(size=n_modes)))
        q[0] -= max(0.0, float(model.end_weights @ q))
        try:
            with use_reference("simulate.impact_search"):
                ref = simulate(model, load, InitialState(q, v), 40.0, max_impacts=60)
        except ValueError:  # an undamped resonance of a mode with a harmonic
            continue
        core = sim_module._core_for(model, load)
        D, B, M = core.data, core.free, n_modes + 1
        consts = _modal_search_constants(core)
        seg = ref._segments
        t_lim = ref.t_end + 10.0  # past the run's last impact (max_impacts)
        # the flights the run took: from an impact to the next (not those a chatter jump skipped,
        # whose start sits on the stop to rounding)
        for i in np.nonzero((seg.entry[:-1] == 1) & (seg.entry[1:] == 1))[0]:
            t, qa, va = float(seg.t[i]), seg.q[i].copy(), seg.v[i].copy()
            htol = 1e-14 * float(np.sum(np.abs(core.c * qa)))
            qq, vv = np.empty(M), np.empty(M)
            st, tc = K.find_crossing(D, B.view, core.c, 0.0, np.array([t]), qa.copy(), va.copy(), t_lim,
                                     htol, (qq, vv, *(np.empty(M) for _ in range(4))))
            st2, tc2 = K.modal_crossing(D, B.view, core.c, consts, t, qa, va, t_lim, htol,
                                        tuple(np.empty(M) for _ in range(6)))
            assert st2 == st
            n_flights += 1
            if st != K.CROSS:
                continue
            speed = abs(float(core.c @ vv))
            scale = 1.0 + abs(tc)
            if speed >= 0.1:
                assert abs(tc2 - tc) <= 1e-12 * scale
            else:
                n_slow += 1
            # the end's displacement at the two times agrees to its rounding
            assert abs(tc2 - tc) * speed <= 1e-13 * scale * (1.0 + float(np.sum(np.abs(core.c * qq))))
    assert n_flights > 50


@pytest.mark.parametrize("n_modes", [8, 64])
def test_modal_simulate_equals_general_search(n_modes):
    """simulate with the folded modal search gives the run of the general search, near a stable
    orbit (the benchmark's case, 8 and 64 modes): the same impacts to 1e-12, the same final
    state to 1e-10."""
    from impactbar import InitialState, simulate

    model, load = BarModel(1.37, 0.02, 0.8, n_modes), CosineLoad(1.2, 1.0)
    orbit = next(o for o in periodic_orbits(model, load) if o.stable)
    q, v = orbit.modal_state_after_impact
    start = InitialState(q - np.eye(n_modes + 1)[0] * 0.01, v)
    runs = {}
    for fast in (False, True):
        with implementation("simulate.impact_search", "fast" if fast else "reference"):
            runs[fast] = simulate(model, load, start, orbit.phase + 200.0, t0=orbit.phase)
    ref, new = runs[False], runs[True]
    assert ref.n_impacts > 25 and new.n_impacts == ref.n_impacts and new.status == ref.status
    assert np.all(np.abs(new.impact_times - ref.impact_times) <= 1e-12 * (1.0 + np.abs(ref.impact_times)))
    np.testing.assert_allclose(new.impact_velocities, ref.impact_velocities, rtol=1e-10)
    for a, b in ((new.final_state.modal_displacement, ref.final_state.modal_displacement),
                 (new.final_state.modal_velocity, ref.final_state.modal_velocity)):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10 * float(np.max(np.abs(b))))


_ABERTH_BITS = r"""
import sys
import numpy as np

if sys.argv[1] == "primed":  # the rigid sweep chunk compiled first (plain kernels, numba's max() in them)
    from impactbar.orbits.rigid import rigid_cosine_orbits

    n = 4  # (rigid_cosine_orbits runs the compiled loop at any size)
    rigid_cosine_orbits(np.full(n, 0.1), np.full(n, 0.5), np.full(n, 0.6), np.ones(n), 1)
from impactbar.dynamics._aberth import aberth_iterate

rng = np.random.default_rng(7)
M = 48
tr = rng.uniform(-1.5, 1.5, M)
dt = rng.uniform(0.3, 0.9, M)
X = rng.normal(size=(4, M)) * 1e-2
ut = np.array([0.1 + 0.05j, -0.2 + 0.1j])
disc = np.sqrt((0.25 * tr * tr - dt).astype(complex))
x = np.concatenate((0.5 * tr + disc, 0.5 * tr - disc))
x = x * (1.0 + 1e-3 * np.exp(2j * np.pi * 0.618 * np.arange(2 * M)))
aberth_iterate(x, tr, dt, X, ut, 3, 1e-300)  # three sweeps, every zero corrected in each
print(x.tobytes().hex())
"""


@pytest.mark.slow  # about 20 s (two new processes compile the sweeps): run by .ci/run
def test_compiled_aberth_does_not_depend_on_the_process_history(tmp_path):
    """The fast-math Aberth sweeps compile to the same machine code whatever the process compiled
    before: after the rigid sweep chunk, the multipliers' iterates came out different in their last
    bits (the kernel took numba's implementations with the flags of their first caller; see the
    comment in ``_aberth``)."""
    import os
    import subprocess
    import sys

    bits = []
    for mode in ("fresh", "primed"):
        env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / mode))
        out = subprocess.run([sys.executable, "-c", _ABERTH_BITS, mode], capture_output=True, text=True,
                             check=True, env=env)
        bits.append(out.stdout.strip())
    assert bits[0] == bits[1]
