"""Periodic orbits under a position-switched drive when the contact takes time (the
wave law and the rod-rock law): checked against simulate (an independent time integration), the
paper law's monodromy, finite differences of simulated runs and the laws' limits."""

import numpy as np
import pytest

import impactbar as ib
from impactbar.orbits.valve_segment import ValveProblem

DRIVE = ib.PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
ROCK = ib.RodRock(segments=[ib.RodSegment(length=10.0, impedance=1.0)],
                  rock=ib.BilinearRock(k=60.0, k_u=600.0))


def bar(law, n_modes=0, s=10.0):
    return ib.BarModel(s=s, d=0.05, R=0.5, n_modes=n_modes, impact=law)


def test_return_map_multipliers_equal_the_monodromy_under_the_paper_law():
    """The contact laws' multipliers (return map on the arrival surface, implicit switch and arrival
    times) against the paper law's monodromy with its saltation matrices: two constructions."""
    drive = ib.PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0, delay=0.3)
    for n in (0, 3):
        o = ib.find_orbit(bar("paper", n), drive)
        X = np.concatenate((o.state, o.durations[[1, 3]]))
        generic = ValveProblem(o.model, drive, 1, lambda p: ib.FourierLoad(p, [])).return_map_orbit(X)
        np.testing.assert_allclose(generic.multipliers, o.multipliers, rtol=0, atol=1e-10)
        assert generic.period == pytest.approx(o.period, abs=1e-14)


@pytest.mark.parametrize("law, n_modes", [("wave", 0), ("wave", 3), (ROCK, 0)],
                         ids=["wave-rigid", "wave-3modes", "rodrock-rigid"])
def test_orbit_is_the_motion_simulate_settles_on(law, n_modes):
    model = bar(law, n_modes)
    o = ib.find_orbit(model, DRIVE)
    assert o.stable and o.contact_time > 0.0
    tr = ib.simulate(model, DRIVE, ib.InitialState.rigid(-0.5, 0.0, n_modes), 60 * o.period)
    ti = np.asarray(tr.impact_times)
    assert np.diff(ti[-3:]) == pytest.approx([o.period] * 2, abs=1e-9)
    assert tr.impact_velocities[-1] == pytest.approx(o.impact_velocity, abs=1e-9)
    # the switches after the last complete cycle, measured from its impact
    sw = np.asarray(tr.switch_times)
    after = sw[(sw > ti[-2]) & (sw < ti[-1])] - ti[-2]
    np.testing.assert_allclose(after, o.switch_times, atol=1e-9)
    assert o.period == pytest.approx(float(np.sum(o.durations)) + o.contact_time, abs=1e-14)


@pytest.mark.parametrize("law, atol", [("wave", 1e-9), (ROCK, 3e-8)], ids=["wave", "rodrock"])
def test_multiplier_equals_finite_differences_of_simulated_blows(law, atol):
    """Rigid piston: the one multiplier is d v_(k+1) / d v_k of the arrival velocities, measured
    by simulate from the orbit's state where the contact ends, perturbed by +-1e-5. The wave law's
    contact Jacobian is exact (agreement 1e-9); the rod-rock law's is by central differences on the
    cell grid (measured: 1.0e-8 on a multiplier of 7.6e-4)."""
    model = bar(law)
    o = ib.find_orbit(model, DRIVE)
    q0, v0 = o.state
    v = {}
    for sign in (1, -1):
        tr = ib.simulate(model, DRIVE, ib.InitialState.rigid(q0, v0 + sign * 1e-5, 0), 2.5 * o.period)
        v[sign] = tr.impact_velocities[:2]
    mu = (v[1][1] - v[-1][1]) / (v[1][0] - v[-1][0])
    assert float(o.multipliers[0]) == pytest.approx(mu, rel=0, abs=atol)
    assert o.trivial_multiplier == 1.0


def test_wave_law_tends_to_the_paper_law_as_s_grows():
    """The window 2/s closes: the period, impact velocity and multiplier differ from the paper
    law's by O(1/s) (measured: the differences fall tenfold per decade of s)."""
    paper = ib.find_orbit(bar("paper"), DRIVE)
    diffs = []
    for s in (10.0, 100.0, 1000.0):
        o = ib.find_orbit(bar("wave", s=s), DRIVE)
        diffs.append([o.period - paper.period, o.impact_velocity - paper.impact_velocity,
                      float(o.multipliers[0] - paper.multipliers[0])])
    diffs = np.abs(np.array(diffs))
    np.testing.assert_allclose(diffs[:-1] / diffs[1:], 10.0, rtol=0.05)
    assert diffs[-1, 0] < 2e-3


def test_a_long_rod_on_stiff_rock_is_the_wave_law():
    """A rod of three times the piston's impedance, too long for its reflection to return within
    the window ``2/s``: the wave law with ``R = (3 - 1)/(3 + 1) = 0.5``."""
    law = ib.RodRock(segments=[ib.RodSegment(length=1000.0, impedance=3.0)],
                     rock=ib.BilinearRock(k=1e3, k_u=1e4), blow_time=0.2)
    r = ib.find_orbit(bar(law), DRIVE)
    w = ib.find_orbit(bar("wave"), DRIVE)
    assert r.period == pytest.approx(w.period, abs=1e-10)
    assert r.impact_velocity == pytest.approx(w.impact_velocity, abs=1e-10)
    np.testing.assert_allclose(r.multipliers, w.multipliers, atol=1e-8)


def test_two_impact_orbit_and_continuation_under_the_wave_law():
    model = bar("wave", 2)
    o = ib.find_orbit(model, DRIVE)
    o2 = ib.find_orbit(model, DRIVE, impacts=2, guess=o)
    assert o2.period == pytest.approx(2 * o.period, rel=1e-12)
    np.testing.assert_allclose(o2.switch_times[2:] - o.period, o.switch_times, atol=1e-12)
    b = ib.continue_orbit(o, "switch_out", to=1.3)
    end = b.orbits[-1]
    assert end.drive.switch_out == pytest.approx(1.3)
    again = ib.find_orbit(model, end.drive)
    assert end.period == pytest.approx(again.period, abs=1e-10)
    assert end.impact_velocity == pytest.approx(again.impact_velocity, abs=1e-10)


def test_contacts_of_the_rock_orbit_are_its_blows():
    o = ib.find_orbit(bar(ROCK), DRIVE)
    (blow,) = o.contacts
    assert 0.0 < blow.efficiency <= blow.efficiency_with_rebound <= 1.0
    assert blow.work_on_rock > 0.0 and blow.permanent_penetration > 0.0
    assert ib.find_orbit(bar("paper"), DRIVE).contacts == ()


def test_bad_guesses_under_a_contact_law_are_refused():
    model = bar("wave")
    with pytest.raises(ValueError, match="impacts=2 needs a guess"):
        ib.find_orbit(model, DRIVE, impacts=2)
    run = ib.simulate(model, DRIVE, ib.InitialState.rigid(-0.5, 0.0, 0), 20.0)
    with pytest.raises(ValueError, match="a simulated run as a guess is read under the paper's law only"):
        ib.find_orbit(model, DRIVE, guess=run)


def test_wave_law_orbit_converges_in_the_modes_kept():
    """The period of the wave law's driven orbit converges as N grows, about as 1/N (measured:
    4.78436, 4.78464, 4.78479 at N = 8, 16, 32, the differences halving)."""
    T = [ib.find_orbit(bar("wave", n), DRIVE).period for n in (8, 16, 32)]
    d1, d2 = T[1] - T[0], T[2] - T[1]
    assert 0.0 < d2 < 0.75 * d1
    assert T[2] == pytest.approx(4.78479, abs=1e-5)


@pytest.mark.parametrize("n_modes", [0, 2])
@pytest.mark.parametrize("parameter, to", [("rock.k", 120.0), ("feed", 0.1), ("bit_mass", 0.05),
                                           ("segment0.length", 12.0)])
def test_a_drive_orbit_on_rock_is_continued_in_the_laws_parameters(n_modes, parameter, to):
    """``continue_orbit`` of a valve's orbit in the rod-rock law's own parameters: the parameter moves
    and each point is the orbit ``find_orbit`` finds afresh at its value (period and impact velocity
    1e-9; measured 1e-14), with its multipliers (1e-7; measured 7e-9)."""
    o = ib.find_orbit(bar(ROCK, n_modes), DRIVE)
    branch = ib.continue_orbit(o, parameter, to=to, max_points=3)
    values = [b.model.law.parameter_value(parameter) for b in branch.orbits]
    assert len(values) == 3 and values[-1] > values[0] == pytest.approx(ROCK.parameter_value(parameter))
    end = branch.orbits[-1]
    again = ib.find_orbit(end.model, DRIVE)
    assert end.period == pytest.approx(again.period, rel=1e-9)
    assert end.impact_velocity == pytest.approx(again.impact_velocity, rel=1e-9)
    np.testing.assert_allclose(np.sort_complex(end.multipliers), np.sort_complex(again.multipliers),
                               atol=1e-7)


def test_a_law_parameter_of_another_law_is_refused():
    """Under the wave law the rod-rock law's names are not parameters: a ValueError that lists the
    ones there are."""
    o = ib.find_orbit(bar("wave", 2), DRIVE)
    with pytest.raises(ValueError, match=r"parameter must be one of .*'switch_out'"):
        ib.continue_orbit(o, "rock.k", to=2.0)


def test_every_orbit_of_a_drive_on_rock_is_the_default_chains():
    """``periodic_orbits(model, drive)`` under the rod-rock law has no certified search of its own:
    it gives the default chain's orbit (it raised a ValueError about ``R = -1``, the law's marker for
    a contact that takes time)."""
    model = bar(ROCK, 2)
    orbits = ib.periodic_orbits(model, DRIVE)
    assert len(orbits) == 1 and orbits.window is None and not any(orbits.certified)
    assert orbits[0].period == pytest.approx(ib.find_orbit(model, DRIVE).period, rel=1e-12)
