"""The rigid bar's multi-impact segment problem in plain floats ("orbits.rigid_segments")
and its flights' clearance under a cosine load from the zeros of the velocity
("admissibility.rigid_cosine"), each against its reference (the general numpy evaluation, the
certified search) and against an independent check (central differences, a dense sampling)."""

import math

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, FourierLoad, SquareWaveLoad, find_orbit, periodic_orbits
from impactbar.dynamics.implementations import use_reference
from impactbar.orbits._rigid_scalar import RigidFlight, cosine_clearance
from impactbar.orbits.admissibility import _admissibility
from impactbar.orbits.multi_impact import _Segments, _unknowns_from
from modal_reference import central_difference_jacobian

TWO_PI = 2.0 * math.pi


def _random_load(rng, kind):
    if kind == "cosine":
        return CosineLoad(rng.uniform(-1, 1), rng.uniform(-2, 2), int(rng.integers(1, 4)))
    if kind == "fourier":
        return FourierLoad(rng.uniform(-1, 1), rng.normal(size=3) + 1j * rng.normal(size=3))
    if kind == "many harmonics":  # summed by numpy in RigidFlight
        return FourierLoad(rng.uniform(-1, 1), (rng.normal(size=20) + 1j * rng.normal(size=20)) / 20)
    return SquareWaveLoad(rng.uniform(0, 1), rng.uniform(1, 2))


@pytest.mark.parametrize("kind", ["cosine", "fourier", "many harmonics", "square"])
def test_float_evaluation_equals_the_general_one(rng, kind):
    """Residual, Jacobian, impact maps and states at random unknowns, d = 0, tiny and moderate,
    m = 1 to 3 impacts in m or m + 1 periods: the same numbers to rounding."""
    for trial in range(40):
        d = (0.0, 1e-9, rng.uniform(0, 0.5))[trial % 3]
        model = BarModel(s=3.0, d=d, R=rng.uniform(0, 1), n_modes=0)
        load = _random_load(rng, kind)
        m = int(rng.integers(1, 4))
        n = m + int(rng.integers(0, 2))
        fast = _Segments(model, load, m, n)
        assert fast.rigid is not None
        with use_reference("orbits.rigid_segments"):
            ref = _Segments(model, load, m, n)
        assert ref.rigid is None
        u = np.column_stack((np.sort(rng.uniform(0, 0.95 * TWO_PI * n, m)), rng.normal(size=m))).ravel()
        F, DF, info = fast.evaluate(u)
        F_ref, DF_ref, info_ref = ref.evaluate(u)
        for got, want in [(F, F_ref), (DF, DF_ref)] + [(info[k], info_ref[k]) for k in info_ref]:
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * max(1.0, np.max(np.abs(want))))


def test_float_jacobian_matches_central_differences(rng):
    model, load = BarModel(s=3.0, d=0.07, R=0.6, n_modes=0), CosineLoad(0.68, 1.0)
    o1 = next(o for o in periodic_orbits(model, load) if math.cos(o.phase) < 0)
    o2 = find_orbit(model, load, impacts=2, periods=2, guess=o1)
    p = _Segments(model, load, 2, 2)
    assert p.rigid is not None
    u = _unknowns_from(p, o2.impact_times, o2.states_after_impact) + 1e-3 * rng.standard_normal(p.size)
    _, DF, _ = p.evaluate(u)
    fd = central_difference_jacobian(lambda x: p.evaluate(x, jacobian=False)[0], u)
    np.testing.assert_allclose(DF, fd, atol=1e-8 * max(1.0, np.max(np.abs(DF))))


def test_rigid_flight_against_scipy_integration():
    """The flight's closed form against an ODE integration of q'' + d q' = p(t)."""
    from scipy.integrate import solve_ivp

    d = 0.13
    for load in (CosineLoad(0.3, 1.2, 2), FourierLoad(-0.2, [0.5, 0.3j, -0.2 + 0.1j])):
        sol = solve_ivp(lambda t, y, p=load: [y[1], float(p(t)) - d * y[1]], (0.4, 7.9), [0.1, -0.7],
                        rtol=1e-12, atol=1e-12)
        q, v, p_start, p_end = RigidFlight(d, load).state(0.4, 0.1, -0.7, 7.9)
        assert (q, v) == pytest.approx(tuple(sol.y[:, -1]), abs=1e-9)
        assert (p_start, p_end) == pytest.approx((float(load(0.4)), float(load(7.9))), abs=1e-14)


def test_multi_impact_orbits_are_the_same_by_either_path():
    """find_orbit's doubled orbit near the period doubling, by the float path and the general one."""
    model, load = BarModel(s=3.0, d=0.02, R=0.6, n_modes=0), CosineLoad(0.7, 1.0)
    o1 = next(o for o in periodic_orbits(model, load) if math.cos(o.phase) < 0)
    fast = find_orbit(model, load, impacts=2, periods=2, guess=o1)
    with use_reference("orbits.rigid_segments"), use_reference("admissibility.rigid_cosine"):
        ref = find_orbit(model, load, impacts=2, periods=2, guess=o1)
    np.testing.assert_allclose(fast.impact_times, ref.impact_times, atol=1e-11)
    np.testing.assert_allclose(fast.multipliers, ref.multipliers, atol=1e-10)
    assert fast.admissibility == ref.admissibility and fast.stable == ref.stable
    assert fast.clearance == pytest.approx(ref.clearance, abs=1e-10)


def test_cosine_clearance_equals_the_certified_search(rng):
    """The flight's clearance and verdict from the velocity's zeros (one per arc of constant load
    sign) against the certified search, over random flights up to two load periods long, R = 0
    (departure at rest) included."""
    seen = set()
    for trial in range(400):
        d = (0.0, rng.uniform(0, 0.5))[trial % 2]
        R = (0.0, rng.uniform(0, 1))[(trial // 2) % 2]
        model = BarModel(s=3.0, d=d, R=R, n_modes=0)
        load = CosineLoad(rng.uniform(-1, 1), rng.uniform(0, 2) if trial % 13 else 0.0,
                          int(rng.integers(1, 4)))
        t0, horizon = rng.uniform(0, TWO_PI), rng.uniform(0.1, 2 * TWO_PI)
        y = np.array([0.0, 0.0 if R == 0 else -abs(rng.normal())])
        v_imp = abs(rng.normal())
        fast = _admissibility(model, load, t0, y, v_imp, horizon=horizon)
        with use_reference("admissibility.rigid_cosine"):
            ref = _admissibility(model, load, t0, y, v_imp, horizon=horizon)
        assert fast[0] == ref[0]
        if math.isfinite(ref[1]):
            assert fast[1] == pytest.approx(ref[1], rel=1e-10, abs=1e-12)
        else:
            assert fast[1] == ref[1]
        seen.add(str(ref[0]))
    assert {"admissible", "penetrates"} <= seen


def test_cosine_clearance_against_a_dense_sampling():
    """The largest stationary value against the largest local maximum of a dense sampling of the
    flight (independent of both searches)."""
    d, p0, pk, k, t0, v0, horizon = 0.05, 0.3, 1.0, 1, 2.0, -1.1, 9.0
    load = CosineLoad(p0, pk, k)
    tau = np.linspace(0.0, horizon, 200001)
    flight = RigidFlight(d, load)
    q = np.array([flight.state(t0, 0.0, v0, t0 + x)[0] for x in tau])
    interior = (q[1:-1] >= q[:-2]) & (q[1:-1] >= q[2:])
    assert interior.sum() >= 1
    got = cosine_clearance(d, p0, pk, k, t0, v0, horizon, False)
    assert got == pytest.approx(float(np.max(q[1:-1][interior])), abs=1e-9)
