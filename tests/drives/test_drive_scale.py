"""The position-switched drive's orbits do not depend on its scale (a fuzz case): every force
and switch position scaled by a power of two (exact in floating point) gives the same period and
admissibility and velocities scaled by it. Newton's stopping test was relative to max(1, |X|), the
states scaling and the flight times not; the admissibility threshold was 1e-12 max(1, |z|); and a
root with flights shrunk to nothing was returned as an orbit, a different one at each scale."""

import pytest

from impactbar import BarModel, PositionSwitchedDrive, find_orbit, periodic_orbits
from impactbar.orbits.driven import orbit_problem
from impactbar.orbits.driven_search import _solve


def _pair(model, stroke, ret, switch_out, lam, delay=0.0):
    return [find_orbit(model, PositionSwitchedDrive(stroke * x, ret * x, switch_out * x, delay))
            for x in (1.0, lam)]


@pytest.mark.parametrize("lam", [2.0, 0.25, 1024.0])
def test_a_poorly_conditioned_orbit_converges_at_every_scale(lam):
    """Multipliers 0.997 and 0.996: Newton's last steps stall at the rounding floor, ~1e-10; it did
    not converge at a scale of 1.9 (50 steps), and now stops there at every scale."""
    model = BarModel(1.0363389262686133, 0.25014941882297387, 0.5480339651072739, 2)
    a, b = _pair(model, 68.69517076378605, 7.713254025856753, 0.00477513851983872, lam)
    assert b.period == pytest.approx(a.period, rel=1e-9)
    assert b.impact_velocities[0] == pytest.approx(lam * a.impact_velocities[0], rel=1e-9)
    assert a.admissible and b.admissible and abs(a.multipliers[0]) > 0.997


@pytest.mark.parametrize("lam", [1.0, 2.0 ** -7])
def test_a_degenerate_root_is_refused(lam):
    """Newton from the rigid orbit reaches flights of total length 3e-9: refused, and the default
    goes on to the search, whose admissible orbit is the same at both scales."""
    model = BarModel(1.254752090566295, 0.2550514112740797, 0.2413567701357589, 2)
    drive = PositionSwitchedDrive(0.07897905817702264 * lam, 0.0754537997215749 * lam,
                                  0.004086703010728663 * lam)
    problem = orbit_problem(model, drive, 1)
    # refused either way: converged onto the degenerate root and refused, or (numpy 1.26's rounding)
    # Newton's steps stall at 7e-9 on the vanishing flights; never returned as an orbit
    with pytest.raises(ValueError, match="degenerate solution|did not converge"):
        _solve(problem, problem.initial(None, 1e-13, 50), 1e-13, 50)
    o = find_orbit(model, drive)
    listed = periodic_orbits(model, drive)
    assert o.admissible and o.period == pytest.approx(0.5556874341845957, rel=1e-10)
    assert [x.admissible for x in listed] == [True, False, False, False, False]
    assert listed[0].period == pytest.approx(o.period, rel=1e-12)
    assert o.impact_velocities[0] == pytest.approx(0.03201894 * lam, rel=1e-6)


def test_admissibility_does_not_depend_on_the_scale():
    """switch_out = 1e12: the end's rounding noise near the stop (1e-4) against a threshold of
    1e-12 max(1, |z after impact|) read "penetrates" at one scale and "admissible" at another."""
    model = BarModel(1.765727433058593, 0.2826123618257868, 0.6562425437977147, 1)
    a, b = _pair(model, 0.0019272743243413952, 0.006711185260085899, 1e12, 16.0, delay=0.18903309452817232)
    assert a.admissibility == b.admissibility == "admissible"
    assert b.period == pytest.approx(a.period, rel=1e-9)
