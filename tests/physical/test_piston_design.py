"""optimize_piston (issue 44, theory §12): one segment recovers Lundberg's uniform optimum, more
segments never do worse than the uniform piston and respect the stress limit, the SI result is the
blow of the piston it reports, the arguments are checked, the figure draws."""

import math

import numpy as np
import pytest

from impactbar.laws.rodrock.law import lundberg_efficiency
from impactbar.physical.piston import optimize_piston
from impactbar.physical.rock import RodPiece

E, RHO = 2.1e11, 7850.0
C = math.sqrt(E / RHO)
MASS, LENGTH, V = 2.355, 0.3, 10.0
AREA = MASS / (RHO * LENGTH)  # the rod matched to the uniform piston
ROD = [RodPiece(length_m=20 * LENGTH, area_m2=AREA, E_Pa=E, density_kg_m3=RHO)]


def _rock(alpha, gamma=1e12):
    """Lundberg's ``alpha = K (2 L/c)/Z`` of the uniform piston, ``Z = m c/L``."""
    K = alpha * (MASS * C / LENGTH) / (2 * LENGTH / C)
    return K, gamma * K


def test_one_segment_recovers_the_uniform_optimum():
    """On a rod so long that nothing returns to the bit within the blow's default window, the
    uniform piston is Lundberg's rectangular wave: 0.8145288 at alpha = 1.2564312 (gamma -> inf)."""
    best = optimize_piston(ROD, _rock(1.2564312), mass=MASS, length=LENGTH, max_stress=math.inf,
                           impact_velocity=V, segments=1)
    assert abs(best.efficiency - 0.8145288) < 1e-7
    assert abs(best.efficiency - lundberg_efficiency(1.2564312, 1e12)) < 1e-10
    assert best.work_on_rock_J == pytest.approx(best.efficiency * 0.5 * MASS * V * V, rel=1e-14)
    assert best.evaluations == 0 and best.feasible
    np.testing.assert_allclose(best.areas_m2, [AREA], rtol=1e-14)
    assert best.bar.piston is None and best.bar.mass_kg == pytest.approx(MASS, rel=1e-14)
    # the incident wave Z V/2 for 2 L/c, Z = rho c A: the peak stress rho c V/2
    assert best.peak_stress_Pa == pytest.approx(RHO * C * V / 2, rel=1e-13)


def _check_design(best, limit, K):
    assert best.feasible and best.peak_stress_Pa <= limit * (1 + 1e-12)
    assert best.work_on_rock_J >= best.uniform_work_on_rock_J
    assert best.lengths_m.sum() == pytest.approx(LENGTH, rel=1e-14)
    assert float(RHO * best.areas_m2 @ best.lengths_m) == pytest.approx(MASS, rel=1e-13)
    # the SI work is that of the reported shape's blow, solved again from its lengths and areas
    import impactbar as ib

    mu = best.areas_m2 * RHO * LENGTH / MASS
    k = K * LENGTH ** 2 / (MASS * C * C)  # in units of m c^2 / L^2
    law = ib.RodRock(segments=[ib.RodSegment(20.0, 1.0)], rock=ib.BilinearRock(k=k, k_u=k * 1e12))
    model = ib.BarModel(s=1.0, d=0.0, R=0.0, n_modes=0, impact=law)
    piston = ib.SteppedPiston(best.lengths_m, mu)
    if best.blow.method == "exact":  # the boundaries where the search put them
        again = ib.single_blow(model, V / C, piston=piston, t_max=44.0, method="exact")
    else:  # (the exact blow past its bound of pieces) on whole cells of the lattice
        assert np.allclose(best.lengths_m / LENGTH * 48, np.round(best.lengths_m / LENGTH * 48), atol=1e-9)
        again = ib.single_blow(model, V / C, piston=piston, t_max=44.0, cells_per_piston=48)
    expect = best.work_on_rock_J / (0.5 * MASS * V * V)
    assert again.work_on_rock / again.energy_at_impact == pytest.approx(expect, rel=1e-12)
    # the peak stress: the exact maximum of the piston-shank force over the rod's area
    assert best.peak_stress_Pa == pytest.approx(again.peak_forces()[0][0] * MASS * C * C / LENGTH / AREA,
                                                rel=1e-12)
    # the design as an SI piston: its mass and length, and the impedances it was solved with
    bar = best.bar
    assert bar.mass_kg == pytest.approx(MASS, rel=1e-13) and bar.length_m == pytest.approx(LENGTH, rel=1e-14)
    np.testing.assert_allclose(bar.piston.impedances, mu / mu[0], rtol=1e-13)


@pytest.mark.parametrize("alpha, gain", [(0.5, 1.0066), (1.2564312, 1.0376), (3.0, 1.1577)])
def test_two_segments_at_least_as_good_as_the_uniform_piston(alpha, gain):
    """Better than the rectangular wave by the gains quoted in theory §12, with a rising incident
    wave (its first step below its peak); the design's blow and the uniform piston's exact."""
    K, K_u = _rock(alpha)
    limit = 1.3 * RHO * C * V / 2
    best = optimize_piston(ROD, (K, K_u), mass=MASS, length=LENGTH, max_stress=limit, impact_velocity=V,
                           segments=2)
    assert best.blow.method == best.uniform_blow.method == "exact"
    assert abs(best.uniform_efficiency - lundberg_efficiency(alpha, 1e12)) < 1e-10
    _check_design(best, limit, K)
    assert best.gain == pytest.approx(gain, abs=2e-3)
    assert best.incident_force_N[0] < 0.9 * best.incident_force_N.max()


@pytest.mark.parametrize("alpha", [pytest.param(0.5, marks=pytest.mark.slow), 1.2564312,
                                   pytest.param(3.0, marks=pytest.mark.slow)])
def test_three_segments_at_least_as_good_as_two(alpha):
    K, K_u = _rock(alpha)
    limit = 1.3 * RHO * C * V / 2
    kw = dict(mass=MASS, length=LENGTH, max_stress=limit, impact_velocity=V)
    three = optimize_piston(ROD, (K, K_u), segments=3, **kw)
    _check_design(three, limit, K)
    two = optimize_piston(ROD, (K, K_u), segments=2, **kw)
    assert three.work_on_rock_J >= two.work_on_rock_J * (1 - 2e-3)


def test_an_unreachable_stress_limit_is_reported():
    """A stress limit that neither the search nor the uniform piston meets: not feasible, the
    closest design returned, never a shape worse in stress than the uniform piston."""
    best = optimize_piston(ROD, _rock(1.0), mass=MASS, length=LENGTH, max_stress=0.5 * RHO * C * V / 2,
                           impact_velocity=V, segments=2, max_evaluations=40)
    assert not best.feasible
    assert best.peak_stress_Pa <= best.uniform_peak_stress_Pa


@pytest.mark.parametrize("kwargs, match", [
    (dict(rod=[]), "rod must be"),
    (dict(rock=(2.0, 1.0)), "rock K_u"),
    (dict(rock=3.0), "rock must be a pair"),
    (dict(mass=0.0), "mass"),
    (dict(segments=0), "segments"),
    (dict(segments=9), "segments"),
    (dict(cells=4), "cells"),
    (dict(max_stress=-1.0), "max_stress"),
    (dict(impact_velocity=math.nan), "impact_velocity"),
])
def test_arguments_checked(kwargs, match):
    args = dict(rod=ROD, rock=_rock(1.0), mass=MASS, length=LENGTH, max_stress=1e9, impact_velocity=V,
                segments=1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        optimize_piston(args.pop("rod"), args.pop("rock"), **args)


def test_the_figure_draws():
    pytest.importorskip("matplotlib")
    best = optimize_piston(ROD, _rock(1.2564312), mass=MASS, length=LENGTH, max_stress=math.inf,
                           impact_velocity=V, segments=2, max_evaluations=20)
    axes = best.plot()
    assert axes.shape == (2,)
    assert len(axes[1].patches) == 2  # the two incident waves
    import matplotlib.pyplot as plt

    plt.close("all")


def test_a_design_under_a_feed_is_solved_exactly():
    """With a feed (a massless bit) the design and the uniform piston are solved by the exact blow
    over the window too (they were the lattice's on whole cells): the SI work is that of the
    reported shape's exact blow solved again, and the lattice refined on that shape converges to it
    at first order (measured 2.4e-5 at 32 cells, 1.4e-6 at 128, 3.5e-7 at 512, 5e-8 at 2048)."""
    import impactbar as ib

    K, K_u = _rock(1.2564312)
    limit = 1.3 * RHO * C * V / 2
    force = MASS * C * C / LENGTH  # the model's force unit
    feed = 0.1 * (MASS * C / LENGTH) * V / 2
    best = optimize_piston(ROD, (K, K_u), mass=MASS, length=LENGTH, max_stress=limit, impact_velocity=V,
                           segments=2, feed=feed)
    assert best.blow.method == best.uniform_blow.method == "exact"
    assert best.feasible and best.work_on_rock_J >= best.uniform_work_on_rock_J
    k = K * LENGTH ** 2 / (MASS * C * C)
    law = ib.RodRock(segments=[ib.RodSegment(20.0, 1.0)], rock=ib.BilinearRock(k=k, k_u=k * 1e12),
                     feed=feed / force)
    model = ib.BarModel(s=1.0, d=0.0, R=0.0, n_modes=0, impact=law)
    piston = ib.SteppedPiston(best.lengths_m, best.areas_m2 * RHO * LENGTH / MASS)
    again = ib.single_blow(model, V / C, piston=piston, t_max=44.0, method="exact")
    expect = best.work_on_rock_J / (0.5 * MASS * V * V)
    assert again.work_on_rock / again.energy_at_impact == pytest.approx(expect, rel=1e-12)
    errs = [abs(ib.single_blow(model, V / C, piston=piston, t_max=44.0, method="lattice",
                               cells_per_piston=n).work_on_rock / again.work_on_rock - 1.0)
            for n in (32, 512)]
    assert errs[1] < 1e-6 and errs[1] < errs[0] / 16
