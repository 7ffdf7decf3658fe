"""Continuation under the rod-rock law (theory §4d) in the rock's and the rod's parameters
(``"rock.k"``, ``"rock.k_u"``, ``"bit_mass"``, ``"feed"``, ``"segment<i>.length"``)."""

import dataclasses

import numpy as np
import pytest

import impactbar as ib
from impactbar.continuation.parameters import parameter_value, with_parameter
from impactbar.laws.rodrock import lundberg_efficiency

S, R_IMP, K_U = 10.0, 2.0, 1e6


@pytest.fixture(scope="module")
def lundberg_branch():
    """A rigid piston (impedance ``s = 10``) on a rod twice as stiff (``r = 2``, 10 piston lengths,
    travel time 1) over a rock with ``k_u = 1e6``, driven by a force that pulls back, pushes, and is
    zero over the whole blow (``blow_time = 2``, ending before the rock's reflection comes back to
    the bit): each blow is a single rectangular incident wave on a massless bit, so the work on rock
    over the piston's energy is ``4 r/(1+r)^2`` times Lundberg's ``eta(alpha_r, gamma)`` with
    ``alpha_r = k (2/s)/(r s)``. The branch of one-impact orbits in ``k`` from 20 to 300."""
    law = ib.RodRock(segments=[ib.RodSegment(length=10.0, impedance=R_IMP)],
                     rock=ib.BilinearRock(k=20.0, k_u=K_U), blow_time=2.0)
    model = ib.BarModel(s=S, d=0.3, R=0.0, n_modes=0, impact=law)
    load = ib.PiecewiseConstantLoad([0.0, 1.0, 3.0], [-1.0, 2.0, 0.0])
    tr = ib.simulate(model, load, ib.InitialState.rigid(-0.1, 0.0, n_modes=0), 60.0)
    orbit = ib.find_orbit(model, load, guess=tr)
    return ib.continue_orbit(orbit, "rock.k", 300.0)


def test_efficiency_against_stiffness_is_lundbergs_curve(lundberg_branch):
    """Each branch point's efficiency against the closed form at its ``k`` (to 1e-10) and against an
    independent :func:`single_blow` of a rigid piston at the point's impact velocity (no drive,
    the same duration): the drive is zero during the blow. The efficiency stays in ``[0, 1]`` and
    its largest value on the branch is near the curve's maximum ``(8/9) 0.8145288``, reached at
    ``alpha_r = 1.2564312`` (``k = 125.6``)."""
    branch = lundberg_branch
    assert branch.status == "reached" and len(branch.orbits) >= 8
    np.testing.assert_allclose(branch.values[[0, -1]], [20.0, 300.0], rtol=1e-12)
    effs = []
    for orbit in branch.orbits:
        assert orbit.admissible and orbit.stable
        k = orbit.model.law.rock.k
        (blow,) = orbit.contacts
        assert blow.drive_work == 0.0
        closed = 4 * R_IMP / (1 + R_IMP) ** 2 * lundberg_efficiency(2 * k / (R_IMP * S * S), K_U / k)
        assert abs(blow.efficiency - closed) < 1e-10
        alone = ib.single_blow(orbit.model, orbit.impact_velocities[0], t_max=blow.duration,
                               energy_fraction=0.0)
        assert blow.work_on_rock == pytest.approx(alone.work_on_rock, rel=1e-10)
        assert 0.0 <= blow.efficiency <= 1.0
        effs.append(blow.efficiency)
    best = int(np.argmax(effs))
    assert 0 < best < len(effs) - 1  # an interior maximum
    peak = 8 / 9 * 0.8145288
    assert peak - 0.01 < effs[best] <= peak * (1 - 20.0 / K_U) + 1e-7
    assert branch.values[best - 1] < 125.6 < branch.values[best + 1]


@pytest.fixture(scope="module")
def case():
    """The stable two-blow motion of tests/orbits/test_rock_orbit.py (flexible piston, cosine drive)."""
    law = ib.RodRock(segments=[ib.RodSegment(length=2.0, impedance=2.0)],
                     rock=ib.BilinearRock(k=20.0, k_u=200.0), feed=0.0)
    model = ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law)
    load = ib.CosineLoad(0.3, 1.0)
    tr = ib.simulate(model, load, ib.InitialState.rigid(-0.1, 0.0, n_modes=4), 200.0)
    return ib.find_orbit(model, load, impacts=2, periods=2, guess=tr)


@pytest.mark.parametrize("name, to", [("rock.k_u", 150.0), ("bit_mass", 0.05), ("feed", 0.05),
                                      ("rock.k", 24.0)])
def test_continuation_in_rock_and_rod_parameters(case, name, to):
    """Each point of a branch in a rock or rod parameter is an orbit of the segment problem at its
    value (residual zero), with the law changed as named and the rest kept."""
    from impactbar.orbits.multi_impact import _Segments, _unknowns_from

    branch = ib.continue_orbit(case, name, to, max_points=3)
    assert len(branch.orbits) == 3
    o = branch.orbits[-1]
    assert parameter_value(o.model, o.load, name) == pytest.approx(branch.values[-1], rel=1e-15)
    assert branch.values[-1] != parameter_value(case.model, case.load, name)
    law0, law = case.model.law, o.model.law
    assert law.segments == law0.segments
    assert sum(getattr(law, f) != getattr(law0, f) for f in ("rock", "bit_mass", "feed")) == 1
    problem = _Segments(o.model, o.load, 2, 2)
    F, _, _ = problem.evaluate(_unknowns_from(problem, o.impact_times, o.states_after_impact),
                               jacobian=False)
    assert np.max(np.abs(F)) < 1e-9


def test_rock_parameter_names_are_checked(case):
    """Rock parameters need the rod-rock law and an existing segment; ``rock.k`` above ``k_u`` and a
    negative bit mass are refused by the law's own checks, naming the field."""
    model, load = case.model, case.load
    assert parameter_value(model, load, "rock.k_u") == 200.0
    assert with_parameter(model, load, "feed", 0.1)[0].law.feed == 0.1
    assert with_parameter(model, load, "segment0.length", 3.0)[0].law.window(model) == pytest.approx(
        4 / 10 + 2 * 3.0 / 10)
    with pytest.raises(ValueError, match=r"parameter must be one of .*'segment0.length'.*got 'segment1"):
        parameter_value(model, load, "segment1.length")
    with pytest.raises(ValueError, match=r"parameter must be one of \('s', 'd', 'R', 'p0', 'pk'\)"):
        parameter_value(model.with_(impact="paper"), load, "rock.k")
    with pytest.raises(ValueError, match="k_u"):
        with_parameter(model, load, "rock.k", 300.0)
    with pytest.raises(ValueError, match="bit_mass"):
        with_parameter(model, load, "bit_mass", -1.0)
    lattice = dataclasses.replace(model.law, method="lattice")
    on_grid = ib.find_orbit(model.with_(impact=lattice), load, impacts=2, periods=2, guess=case)
    with pytest.raises(ValueError, match="whole cells"):  # the lattice's blow is piecewise constant
        ib.continue_orbit(on_grid, "segment0.length", 2.5)  # in a length


def test_continuation_in_a_segments_length_on_the_exact_blows(case):
    """The exact blows carry each segment as a delay line of its own travel time, so an orbit is
    followed in a segment's length; the branch's end is the orbit found afresh at that
    length (1e-8), the rod's length changed alone."""
    branch = ib.continue_orbit(case, "segment0.length", 2.37, max_points=40)
    assert branch.status == "reached"
    o = branch.orbits[-1]
    assert o.model.law.segments[0].length == pytest.approx(2.37, rel=1e-12)
    again = ib.find_orbit(o.model, o.load, impacts=2, periods=2, guess=case)
    np.testing.assert_allclose(o.impact_velocities, again.impact_velocities, rtol=1e-8)
    np.testing.assert_allclose(o.impact_times, again.impact_times, atol=1e-8)


def test_a_target_beyond_the_end_the_start_sits_on_is_refused(case):
    """The start has no feed (``feed = 0``, the end of its range ``[0, inf)``): a target ``feed = -1``
    is refused at the call, naming the parameter, instead of a one-point branch "step too small";
    a target beyond a range the branch can enter (``R`` to 1.2 in tests/continuation) is kept."""
    with pytest.raises(ValueError, match=r"to = -1 is outside the allowed range of feed.*feed = 0"):
        ib.continue_orbit(case, "feed", to=-1.0)
    with pytest.raises(ValueError, match="bit_mass"):
        ib.continue_orbit(case, "bit_mass", to=-0.5)
