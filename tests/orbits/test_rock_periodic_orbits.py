"""periodic_orbits under the rod-rock law (theory §4d): the one-impact orbits found by Newton's
method from the paper law's orbits and a settled simulation (impactbar.orbits.rock)."""

import math

import numpy as np
import pytest

import impactbar as ib


@pytest.fixture(scope="module")
def case():
    """A rigid piston on a stiffer rod (impedance 2, travel time 1) over a rock (alpha_r = 0.6),
    driven by a force that pulls back, pushes, and rests: two one-impact orbits."""
    law = ib.RodRock(segments=[ib.RodSegment(length=10.0, impedance=2.0)],
                     rock=ib.BilinearRock(k=60.0, k_u=1e6), blow_time=2.0)
    model = ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=0, impact=law)
    load = ib.PiecewiseConstantLoad([0.0, 1.0, 3.0], [-1.0, 2.0, 0.0])
    return model, load, ib.periodic_orbits(model, load)


def test_orbits_are_fixed_points_of_the_simulator(case):
    """Each orbit, started in the simulator at its flight's start, strikes again at its phase with
    its impact velocity (to 1e-9) for the next period: a fixed point of the simulator's map."""
    model, load, orbits = case
    assert len(orbits) == 2 and [o.stable for o in orbits] == [False, True]
    assert all(o.admissible for o in orbits) and orbits[0].phase < orbits[1].phase
    T = model.law.window(model)
    for o in orbits:
        y = o.states_after_impact[0]
        t0 = o.impact_times[0] + T
        run = ib.simulate(model, load, ib.InitialState(modal_displacement=y[:1], modal_velocity=y[1:]),
                          t0 + 2 * math.pi, t0=t0)
        assert math.remainder(run.impact_times[0] - o.phase, 2 * math.pi) == pytest.approx(0, abs=1e-9)
        assert run.impact_velocities[0] == pytest.approx(o.impact_velocity, rel=1e-9)


def test_stable_orbit_is_the_settled_motion_and_its_multiplier(case):
    """The stable orbit is where a simulation from rest settles, and a small perturbation of it
    decays per period by the orbit's leading multiplier (its impact velocity's deviation, the ratio
    of successive periods against ``max |mu|``, to 2 %); the unstable orbit has a multiplier
    outside the unit circle."""
    model, load, orbits = case
    unstable, stable = orbits
    assert unstable.max_abs_multiplier > 1.0 > stable.max_abs_multiplier
    tr = ib.simulate(model, load, ib.InitialState.rigid(-0.1, 0.0, n_modes=0), 2 * math.pi * 40)
    assert np.mod(tr.impact_times[-1], 2 * math.pi) == pytest.approx(stable.phase, abs=1e-8)
    T = model.law.window(model)
    y = stable.states_after_impact[0] + np.array([0.0, 1e-4])
    t0 = stable.impact_times[0] + T
    run = ib.simulate(model, load, ib.InitialState(modal_displacement=y[:1], modal_velocity=y[1:]),
                      t0 + 2 * math.pi * 8, t0=t0)
    dev = run.impact_velocities[:8] - stable.impact_velocity
    mu = stable.multipliers[np.argmax(np.abs(stable.multipliers))]
    assert abs(mu.imag) < 1e-12
    ratios = dev[3:7] / dev[2:6]
    np.testing.assert_allclose(ratios, mu.real, rtol=0.02)


def test_efficiency_of_each_orbit_is_a_single_blow(case):
    """The stable orbit's blow happens while the drive rests: its efficiency is the closed form
    ``4 r/(1+r)^2 eta(alpha_r, gamma)`` (Lundberg, alpha_r = 0.6) to 1e-10, and each orbit's
    efficiency lies in [0, 1]."""
    from impactbar.laws.rodrock import lundberg_efficiency

    _, _, orbits = case
    for o in orbits:
        assert 0.0 <= o.contacts[0].efficiency <= 1.0
    closed = 8 / 9 * lundberg_efficiency(0.6, 1e6 / 60.0)
    assert abs(orbits[1].contacts[0].efficiency - closed) < 1e-10


def test_no_orbit_gives_an_empty_list():
    """Where the motion chatters and no guess converges to a one-impact orbit, the list is empty
    (not an error)."""
    law = ib.RodRock(segments=[ib.RodSegment(length=2.0, impedance=2.0)],
                     rock=ib.BilinearRock(k=20.0, k_u=200.0))
    model = ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law)
    assert list(ib.periodic_orbits(model, ib.CosineLoad(1.0, 1.0))) == []


def test_find_orbit_without_a_guess_starts_from_periodic_orbits(case):
    """``find_orbit`` with no guess starts from ``periodic_orbits`` (stable first), now under this
    law too: the stable orbit, to the digits Newton gives."""
    model, load, orbits = case
    o = ib.find_orbit(model, load)
    assert o.phase == pytest.approx(orbits[1].phase, abs=1e-10) and o.stable


def _scaled(load, c):
    return ib.PiecewiseConstantLoad(load.breaks, c * load.levels)


def test_orbits_do_not_depend_on_the_scale_of_the_load(case):
    """The problem is homogeneous of degree one in the load (no feed, a bilinear rock): scaled by
    ``c`` from 1e-9 to 1e9 it has the same orbits, phases and multipliers, with states times ``c``.
    The impact map's finite-difference step was ``1e-6 max(1, |y|)``, a thousand times the state at
    ``c = 1e-9``: there the stable orbit (3.5461) was lost and an unstable one (2.4454) came with the
    multiplier -2.437 instead of -1.562 on the lattice; on the exact blows (the default)
    that orbit's phase is 2.4454631 and its flip multiplier -1.5991074 at every scale."""
    model, load, orbits = case
    ref = [(o.phase, o.stable, o.impact_velocity) for o in orbits]
    assert [(round(p, 4), st) for p, st, _ in ref] == [(2.6008, False), (3.5461, True)]
    for c in (1e-9, 1e-7, 1e-3, 1e3, 1e9):
        got = ib.periodic_orbits(model, _scaled(load, c))
        assert [o.stable for o in got] == [st for _, st, _ in ref]
        for o, (phase, _, v) in zip(got, ref, strict=True):
            assert o.phase == pytest.approx(phase, abs=1e-8)
            assert o.impact_velocity == pytest.approx(c * v, rel=1e-7)
    # the third orbit (phase 2.4454, a flip multiplier) from the same relative guess at every scale
    guess = (np.array([2.4454]), np.array([[-0.14544947, -0.08505581]]))
    mults = []
    for c in (1e-9, 1.0, 1e9):
        o = ib.find_orbit(model, _scaled(load, c), guess=(guess[0], c * guess[1]))
        assert o.phase == pytest.approx(2.4454630693, abs=1e-8) and not o.stable
        mults.append(np.sort(o.multipliers.real)[0])
    np.testing.assert_allclose(mults, -1.5991073884, rtol=1e-8)
