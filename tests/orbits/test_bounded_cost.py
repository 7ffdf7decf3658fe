"""Bounded cost of find_orbit: a problem too large for the dense Newton Jacobian is
refused before anything is allocated, absurd iteration counts are refused, and a wandering Newton
stops on stagnation."""


import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, find_orbit, periodic_orbits
from impactbar.orbits import multi_impact
from impactbar.orbits.multi_impact import MAX_UNKNOWNS, _Segments


def test_problem_size_refused_before_allocating():
    model, load = BarModel(3.0, 0.1, 0.5, 4), CosineLoad(0.6, 1.0)
    with pytest.raises(ValueError, match=r"40960 unknowns.*limited to 6000.*12\.5 GiB"):
        find_orbit(model, load, impacts=4096, periods=4096)  # tried to allocate 12.5 GiB
    # the bound is 2 (n_modes + 1) impacts: just inside it the problem is set up
    m = MAX_UNKNOWNS // (2 * 5)
    assert _Segments(model, load, m, m).size == 2 * 5 * m <= MAX_UNKNOWNS
    with pytest.raises(ValueError, match="fewer impacts or modes"):
        _Segments(model, load, m + 1, m + 1)


def test_absurd_max_iter_refused():
    model, load = BarModel(3.0, 0.1, 0.5, 1), CosineLoad(0.6, 1.0)
    with pytest.raises(ValueError, match=r"max_iter must be an integer in \[1, 1000\]; got 10000000"):
        find_orbit(model, load, guess=([1.0], np.full((1, 4), 50.0)), max_iter=10**7)


def test_newton_stops_on_stagnation():
    """From a bad start Newton wanders without converging nor overflowing: without the stall
    test these starts run all 1000 iterations (checked by switching it off)."""
    model, load = BarModel(3.0, 0.0, 0.5, 4), CosineLoad(0.6, 1.0)
    p = _Segments(model, load, 3, 2)
    u0 = np.full((3, 10), 5.0)
    u0[:, 0] = [1.0, 4.0, 9.0]
    u, it = p.newton(u0.ravel(), max_iter=1000)
    assert u is None and it < 200
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(multi_impact, "STALL_ITERATIONS", 10**9)
        u, it = p.newton(u0.ravel(), max_iter=300)
        assert u is None and it == 300
    with pytest.raises(ValueError, match="did not converge"):
        find_orbit(model, load, impacts=3, periods=2, guess=(u0[:, 0], np.hstack(
            (np.zeros((3, 1)), u0[:, 1:]))), max_iter=1000)


def test_stiff_one_mode_bar_under_the_wave_law_finishes():
    """``BarModel(1e4, 0.01, 0.5, 1, impact="wave")`` under ``CosineLoad(0.6, 1)`` ran past 120 s
    (a reported case; not reproduced on db27a24, kept as a regression test): its orbits, Newton from one
    of them (the same phase) and a run of 20 periods take seconds."""
    from impactbar import InitialState, simulate

    model, load = BarModel(1e4, 0.01, 0.5, 1, impact="wave"), CosineLoad(0.6, 1.0)
    orbits = periodic_orbits(model, load)
    assert len(orbits) == 2 and all(o.admissible for o in orbits)
    again = find_orbit(model, load, guess=orbits[0])
    assert again.phase == pytest.approx(orbits[0].phase, abs=1e-9)
    tr = simulate(model, load, InitialState.rigid(-0.1, 0.0, 1), 2 * np.pi * 20)
    assert tr.impact_times.size > 20 and np.all(np.isfinite(tr.impact_velocities))
