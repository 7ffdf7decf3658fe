"""Multi-impact periodic motions (find_orbit) against the one-impact closed forms, the rigid bar's
invariants, finite differences and the event-driven simulator."""

import math

import numpy as np
import pytest

from impactbar import (
    BarModel,
    CosineLoad,
    InitialState,
    MultiImpactOrbit,
    SquareWaveLoad,
    find_orbit,
    periodic_orbits,
    simulate,
)
from impactbar.orbits.multi_impact import _Segments, _unknowns_from
from modal_reference import central_difference_jacobian

TWO_PI = 2 * math.pi


def _rigid_pd_edge(R):
    """Load factor of the rigid bar's period doubling, d = 0 (theory §6, kappa_0 = -((1-R)/(1+R))^2)."""
    return (1 + R) ** 2 / math.sqrt(4 * (1 + R * R) ** 2 + math.pi**2 * (1 - R * R) ** 2)


def _same_multipliers(a, b):
    a = np.sort_complex(np.asarray(a))
    b = np.sort_complex(np.asarray(b))
    return float(np.max(np.abs(a - b)))


@pytest.mark.parametrize("model, load", [
    (BarModel(s=3.0, d=0.05, R=0.5, n_modes=4), CosineLoad(0.2, 1.0)),
    (BarModel(s=10.0, d=0.0, R=0.3, n_modes=6), CosineLoad(0.2, 1.0, 2)),
    (BarModel(s=10.0, d=0.02, R=0.5, n_modes=3), SquareWaveLoad(1.0, 1.2)),
    (BarModel(s=1.0, d=0.0, R=0.7, n_modes=0), CosineLoad(0.9, 1.0)),
])
def test_one_impact_equals_periodic_orbits(model, load):
    orbits = periodic_orbits(model, load)
    assert orbits
    for o in orbits:
        f = find_orbit(model, load, guess=o)
        assert f.impacts == f.periods == 1
        assert f.phase == pytest.approx(o.phase, abs=1e-9)
        assert f.impact_velocity == pytest.approx(o.impact_velocity, abs=1e-9)
        assert _same_multipliers(f.multipliers, o.multipliers) < 1e-9
        assert f.admissibility == o.admissibility
        assert f.stable == o.stable
        if np.isfinite(o.clearance):
            assert f.clearance == pytest.approx(o.clearance, abs=1e-9)
        np.testing.assert_allclose(f.state_after_impact, o.state_after_impact, atol=1e-9)
        t = np.linspace(0, TWO_PI, 7)
        np.testing.assert_allclose(f.end_displacement(t), o.end_displacement(t), atol=1e-9)


def test_default_guess_is_the_stable_orbit():
    model, load = BarModel(s=10.0, d=0.05, R=0.5, n_modes=4), CosineLoad(0.7, 1.0)
    stable = [o for o in periodic_orbits(model, load) if o.stable]
    assert len(stable) == 1
    f = find_orbit(model, load)
    assert f.stable and f.phase == pytest.approx(stable[0].phase, abs=1e-10)
    f3 = find_orbit(model, load, impacts=3, periods=3)  # the same orbit, three times round
    np.testing.assert_allclose(f3.impact_times, stable[0].phase + TWO_PI * np.arange(3), atol=1e-9)
    assert f3.max_abs_multiplier == pytest.approx(stable[0].max_abs_multiplier**3, rel=1e-8)


def test_jacobian_matches_finite_differences(rng):
    model, load = BarModel(s=2.0, d=0.03, R=0.6, n_modes=3), CosineLoad(0.6, 1.0)
    o2 = find_orbit(model, load, impacts=2, periods=2)
    p = _Segments(model, load, 2, 2)
    u = _unknowns_from(p, o2.impact_times, o2.states_after_impact) + 1e-3 * rng.standard_normal(p.size)
    _, DF, _ = p.evaluate(u)
    fd = central_difference_jacobian(lambda x: p.evaluate(x, jacobian=False)[0], u)
    np.testing.assert_allclose(DF, fd, atol=2e-7 * max(1.0, np.max(np.abs(DF))))


@pytest.mark.parametrize("R", [0.3, 0.6, 0.8])
def test_rigid_multiplier_product_is_R_power_2m(R):
    """Undamped rigid bar: each flight preserves area and each impact scales it by R^2, so the
    m-impact multipliers multiply to R^(2m) exactly."""
    model = BarModel(s=3.0, d=0.0, R=R, n_modes=0)
    load = CosineLoad(0.97 * _rigid_pd_edge(R), 1.0)
    o1 = next(o for o in periodic_orbits(model, load) if math.cos(o.phase) < 0)
    assert np.prod(o1.multipliers).real == pytest.approx(R**2, rel=1e-12)
    o2 = find_orbit(model, load, impacts=2, periods=2, guess=o1)
    assert np.ptp(o2.phases) > 1e-3  # a genuinely doubled orbit, not the one-impact orbit twice
    assert np.prod(o2.multipliers).real == pytest.approx(R**4, rel=1e-10)
    assert abs(np.prod(o2.multipliers).imag) < 1e-12


def test_doubled_orbit_is_reproduced_by_simulate():
    """Past the period doubling the one-impact orbit is unstable; the 2-per-2 orbit found from it
    is stable, and the simulator started on it strikes at its impact times to 1e-9."""
    R = 0.6
    model = BarModel(s=3.0, d=0.0, R=R, n_modes=0)
    load = CosineLoad(0.98 * _rigid_pd_edge(R), 1.0)
    o1 = next(o for o in periodic_orbits(model, load) if math.cos(o.phase) < 0)
    assert not o1.stable and np.min(o1.multipliers.real) < -1
    o2 = find_orbit(model, load, impacts=2, periods=2, guess=o1)
    assert isinstance(o2, MultiImpactOrbit)
    assert o2.stable and o2.admissible
    periods = 10
    tr = simulate(model, load, InitialState(*o2.modal_state_after_impact),
                  o2.impact_times[0] + periods * o2.period + 0.5, t0=o2.impact_times[0])
    expected = (o2.impact_times[None, :] + o2.period * np.arange(periods + 1)[:, None]).ravel()[1:]
    expected = expected[expected < tr.t_end]
    assert tr.impact_times.size == expected.size
    np.testing.assert_allclose(tr.impact_times, expected, atol=1e-9)
    np.testing.assert_allclose(tr.impact_velocities[:2], np.roll(o2.impact_velocities, -1), atol=1e-9)


def test_guess_from_a_trajectory():
    """A run started near the unstable one-impact orbit settles on the 2-per-2 motion; its last
    impacts start Newton on it."""
    R = 0.6
    model = BarModel(s=3.0, d=0.0, R=R, n_modes=0)
    load = CosineLoad(0.98 * _rigid_pd_edge(R), 1.0)
    o1 = next(p for p in periodic_orbits(model, load) if math.cos(p.phase) < 0)
    q, v = o1.modal_state_after_impact
    tr = simulate(model, load, InitialState(q, 1.01 * v), o1.phase + 100 * TWO_PI, t0=o1.phase)
    gaps = np.diff(tr.impact_times[-3:])
    assert np.sum(gaps) == pytest.approx(2 * TWO_PI, abs=1e-6) and abs(gaps[0] - gaps[1]) > 0.1
    o = find_orbit(model, load, impacts=2, periods=2, guess=tr)
    ref = find_orbit(model, load, impacts=2, periods=2, guess=o1)
    assert sorted(o.phases) == pytest.approx(sorted(ref.phases), abs=1e-10)
    assert np.min(np.abs(np.mod(tr.impact_times[-1], TWO_PI) - o.phases)) < 1e-8


def test_field_and_modal_state_continuity():
    model, load = BarModel(s=2.0, d=0.03, R=0.6, n_modes=3), CosineLoad(0.6, 1.0)
    o2 = find_orbit(model, load, impacts=2, periods=2)
    rel = o2.impact_times - o2.impact_times[0]
    # contact at every impact, displacement periodic over 2 pi n
    np.testing.assert_allclose(o2.end_displacement(rel), 0.0, atol=1e-12)
    t = np.linspace(0.1, 3.0, 5)
    np.testing.assert_allclose(o2.displacement(1.0, t), o2.end_displacement(t), atol=1e-13)
    np.testing.assert_allclose(o2.displacement(0.3, t + o2.period), o2.displacement(0.3, t), atol=1e-12)
    assert o2.velocity(1.0, rel[1]) == pytest.approx(-model.R * o2.impact_velocities[1], abs=1e-12)
    d = o2.to_dict()
    assert d["impacts"] == 2 and len(d["multipliers"]) == 2 * (model.n_modes + 1)


def test_bad_input():
    model, load = BarModel(s=2.0, d=0.03, R=0.6, n_modes=1), CosineLoad(0.6, 1.0)
    with pytest.raises(ValueError, match="impacts"):
        find_orbit(model, load, impacts=0)
    with pytest.raises(ValueError, match="periods"):
        find_orbit(model, load, periods=1.5)
    with pytest.raises(ValueError, match="guess is required"):
        find_orbit(model, load, impacts=2, periods=1)
    o = find_orbit(model, load)
    with pytest.raises(ValueError, match="not impacts=3, periods=2"):
        find_orbit(model, load, impacts=3, periods=2, guess=o)
    with pytest.raises(ValueError, match="guess must give"):
        find_orbit(model, load, guess=([1.0, 2.0], np.zeros((2, 4))))
    with pytest.raises(ValueError, match="guess must be"):
        find_orbit(model, load, guess="x")
    with pytest.raises(ValueError, match="model must be a BarModel"):
        find_orbit("m", load)
    with pytest.raises(ValueError, match="did not converge"):
        find_orbit(model, load, guess=([1.0], np.full((1, 4), 50.0)), max_iter=3)
    other = BarModel(s=2.0, d=0.03, R=0.6, n_modes=1)
    object.__setattr__(other, "impact", "plastic")  # a law neither eq. 10 nor the wave law
    with pytest.raises(ValueError, match="impact='plastic'"):
        find_orbit(other, load)
