"""The circuit's orbit on the rod and rock (``examples/circuit_drifter_rock.toml``): the Jacobians that
only steer Newton's method take the coupled blow's forward differences (the chord's first, the chord's
again) or none at all (the closing step takes the chord's), the multipliers' Jacobian the central
differences at the found orbit. Checked against Newton's method with the multipliers' Jacobian at
every step (``newton="full"``) and against the central differences themselves."""

import numpy as np
import pytest
from circuit_parts_reference import ROCK_EXAMPLE

from impactbar import find_orbit
from impactbar.orbits import find_driven_orbit
from impactbar.orbits.coupled import blow_jacobian, blow_state
from impactbar.orbits.driven import ShootingProblem, orbit_of


@pytest.fixture(scope="module")
def both(rock_drifter):
    """Newton's method with the multipliers' Jacobian at every step, and ``find_orbit``'s chord."""
    model, drive = rock_drifter
    return find_driven_orbit(model, drive, newton="full"), find_orbit(model, drive)


def test_the_rock_orbit_is_full_newtons_to_the_multipliers_own_noise(both):
    """The unknowns, the period and the impact velocity to 1e-9 (measured 1.2e-10, 1.4e-11, 1.1e-10: the
    variational flights' root is itself no finer, Newton's steps there stay near 1e-10). The
    multipliers are central differences of blows integrated by CVODE at the unknowns, whose steps
    move with them: a change of 1e-11 in one pressure moves them by 6e-9 (shown here; the gap
    measured 6.7e-9), so the two ways agree to that noise, not to rounding."""
    full, fast = both
    assert full.problem.newton == "full" and fast.problem.newton == "chord" and fast.problem.coupled
    X, Xr = np.asarray(fast._unknowns), np.asarray(full._unknowns)
    assert np.max(np.abs(X - Xr)) <= 1e-9 * np.max(np.abs(Xr))
    assert fast.period == pytest.approx(full.period, rel=1e-9)
    np.testing.assert_allclose(fast.impact_velocities, full.impact_velocities, rtol=1e-9)
    problem = full.problem
    problem._last = None
    nudged = Xr.copy()
    nudged[2] *= 1.0 + 1e-11
    noise = np.max(np.abs(orbit_of(problem, nudged).multipliers - full.multipliers))
    gap = np.max(np.abs(fast.multipliers - full.multipliers))
    assert noise < 1e-6
    assert gap <= max(10.0 * noise, 3e-8), (gap, noise)
    assert fast.stable == full.stable and fast.admissible == full.admissible


def test_the_multipliers_are_the_central_differences_at_the_orbit(both):
    """The orbit's multipliers are those of the central differences of the blow at its unknowns (the
    Jacobian asked again, with no flight remembered), to the bit."""
    _, fast = both
    problem = fast.problem
    problem._last = None
    np.testing.assert_array_equal(problem.orbit(np.asarray(fast._unknowns)).multipliers, fast.multipliers)


def test_find_orbit_takes_one_central_blow_jacobian(rock_drifter, monkeypatch):
    """The Jacobians that only steer take the forward differences; the closing step takes none (the
    variational flights' state only); the multipliers' alone the central differences, once."""
    model, drive = rock_drifter
    seen = []
    fly = ShootingProblem._fly

    def spy(self, tau, mode, y, keep, variational, settings):
        if variational:
            seen.append(variational)
        return fly(self, tau, mode, y, keep, variational, settings)

    monkeypatch.setattr(ShootingProblem, "_fly", spy)
    find_orbit(model, drive)
    assert seen[-2:] == ["state", True], seen
    assert seen[:-2] and set(seen[:-2]) == {"steer"}, seen


def test_forward_differences_of_the_blow_are_the_central_ones_to_their_step(both):
    """At the orbit's arrival: the forward differences (from the blow itself) within 1e-4 of the
    largest entry of the central ones (measured 8.6e-6: their error ``O(h)``, ``h = 1e-5``), and not the
    same."""
    _, fast = both
    model, drive, problem = fast.model, fast.drive, fast.problem
    tau, mode = problem.blocks[0]
    _, _, _, (t, q, v, state), _, _ = problem._flight(tau, mode, np.asarray(fast._unknowns))
    y = blow_state(model, drive, t, q, v, state)[0]
    central = blow_jacobian(model, drive, t, q, v, state)
    forward = blow_jacobian(model, drive, t, q, v, state, forward=y)
    err = np.max(np.abs(forward - central)) / np.max(np.abs(central))
    assert 0.0 < err <= 1e-4, err
    with pytest.raises(ValueError, match="forward"):
        blow_jacobian(model, drive, t, q, v, state, forward=y[:-1])


def _counted_exact_blows(monkeypatch):
    """A list whose entries count the exact coupled blows solved from here on, the exact solver's
    runs (``ExactBlowMap.solve``: the blows' rounds of the drive's force, and any other), and those
    of them outside a coupled blow (a tangent's primal solved again)."""
    import impactbar.laws.rodrock.coupled_exact as CE
    from impactbar.laws.rodrock.exactmap import ExactBlowMap

    count = [0, 0, 0]
    real, solve = CE.driven_exact_contact, ExactBlowMap.solve
    inside = [False]

    def counted(*args, **kwargs):
        count[0] += 1
        inside[0] = True
        try:
            return real(*args, **kwargs)
        finally:
            inside[0] = False

    def solved(self, *args, **kwargs):
        count[1] += 1
        count[2] += not inside[0]
        return solve(self, *args, **kwargs)

    monkeypatch.setattr(CE, "driven_exact_contact", counted)
    monkeypatch.setattr(ExactBlowMap, "solve", solved)
    return count


@pytest.mark.slow
def test_the_exact_blows_orbit_starts_on_the_lattice(rock_drifter, monkeypatch):
    """With exact blows (``RodRock(method="exact")``, the rod as given) ``find_orbit`` finds the orbit
    on the lattice and polishes it on the exact blows with the lattice's Jacobian as the chord's
    (``ShootingProblem.polish``): 4 exact blows where the default chain on the exact blows took 21
    (measured, 6.5 s of CPU against 9.1 s; 6 while the lattice's blows ended at the law's window, 16
    and 31 while the multipliers' Jacobian took ten blows of central differences, not the blow's
    tangent). Its root is the exact problem's: a full Newton step from it (the tangent of the exact
    blow) moves the unknowns by 6.5e-10 of their size (measured; 4.9e-10 from the window's start),
    and the default chain's orbit is the same to the chord's tolerance (the periods measured 7.8e-11
    apart, 1.2e-10 and 1.9e-10 from the full step's; from the window's start 3.1e-10, 3.6e-10 and
    5.4e-11; with the multipliers' and the full step's Jacobian by central differences 3.7e-9 apart,
    1.8e-10 and 3.9e-9)."""
    import dataclasses

    import impactbar.orbits.driven_search as S
    from impactbar.physical import build, read_config

    cfg, _ = read_config(str(ROCK_EXAMPLE))
    del cfg["rock"]["cells_per_piston"]
    cfg["rock"].pop("contact_events", None)  # (the lattice's plain events: the arrival as measured)
    model = build(cfg).model()
    drive = rock_drifter[1]
    exact = model.with_(impact=dataclasses.replace(model.law, method="exact"))
    assert exact.law.coarse_model(exact) is not None
    count = _counted_exact_blows(monkeypatch)
    polished = find_orbit(exact, drive)
    assert count[0] <= 8
    problem = polished.problem
    X = np.asarray(polished._unknowns, dtype=float)
    r, J = problem.residual(X)
    step = np.linalg.solve(J, -r)
    assert np.max(np.abs(step) / np.maximum(np.abs(X), 1e-300)) < 2e-9
    monkeypatch.setattr(S, "_from_coarse", lambda *args: None)  # the default chain on the exact blows
    count[0] = 0
    direct = find_orbit(exact, drive)
    assert count[0] > 15
    assert polished.period == pytest.approx(direct.period, rel=1e-8)
    np.testing.assert_allclose(polished.impact_velocities, direct.impact_velocities, rtol=1e-8)
    full = orbit_of(problem, X + step)
    assert abs(polished.period - full.period) < 1e-9 * full.period
    assert abs(direct.period - full.period) < 1e-9 * full.period


@pytest.mark.slow
def test_the_exact_blows_multipliers_do_not_depend_on_the_step(rock_drifter, monkeypatch):
    """The exact blows' multipliers come from the coupled blow's tangent
    (:meth:`~impactbar.RodRock.driven_tangent`); the central differences they replace agree with them
    to their own noise. The exact coupled blow's noise (some 1e-11 of the state) over the central
    differences' step: at the exact blows' step (``FD_STEP_EXACT_BLOW``, 1e-3) the multipliers are the
    tangent's to 2e-7 (measured 4.7e-9), and those at a step 3.3 times smaller too (measured 9e-8
    from the step 1e-3: the smaller step's noise); at a hundredth of the lattice's step (1e-7) the
    noise over the step moves them by 4.0e-7 from the tangent's (measured; at a tenth, 1e-6, by
    2.9e-7 and, from the lattice orbit started at 8 cells, by 3.7e-8: at one step the noise's size is
    chance; this test once required above 1e-6 at 1e-5, 5e-7 to 1.1e-6 before the drive's spurious
    steps were removed)."""
    import dataclasses

    import impactbar as ib
    import impactbar.orbits.coupled as OC
    from impactbar.physical import build, read_config

    cfg, _ = read_config(str(ROCK_EXAMPLE))
    del cfg["rock"]["cells_per_piston"]
    cfg["rock"].pop("contact_events", None)  # (the lattice's plain events: the arrival as measured)
    model = build(cfg).model()
    exact = model.with_(impact=dataclasses.replace(model.law, method="exact"))

    def largest():
        mu = np.asarray(find_orbit(exact, rock_drifter[1]).multipliers)
        return np.sort(np.abs(mu))[::-1][:2]

    tangent = largest()
    monkeypatch.setattr(ib.RodRock, "driven_tangent", lambda self, *args: None)  # central differences
    default = largest()
    np.testing.assert_allclose(default, tangent, rtol=0, atol=2e-7)
    monkeypatch.setattr(OC, "FD_STEP_EXACT_BLOW", 3e-4)
    np.testing.assert_allclose(largest(), tangent, rtol=0, atol=2e-7)
    monkeypatch.setattr(OC, "FD_STEP_EXACT_BLOW", OC.FD_STEP_BLOW / 100)  # noise over the step
    assert np.max(np.abs(largest() - tangent)) > 5e-8


#: The exact blows' orbit of ``examples/circuit_drifter_rock.toml`` as the polish from the lattice's
#: orbit at the law's window found it (blow frequency Hz, impact velocity m/s, work on rock J,
#: penetration mm, mean supply pressure Pa; the two largest multipliers): 6 exact blows.
EXACT_ORBIT = (45.66071548948399, 10.385623363299239, 218.37092601557174, 0.9145101705343387,
               22615477.619608734, 0.9163043129185183, 0.08601934993829452)


@pytest.mark.slow
def test_the_exact_blows_polish_starts_where_their_blows_end(monkeypatch):
    """The exact blows' coarse model ends its lattice blows where the exact ones end
    (``driven_end="free"``): the polish starts 2.6e-4 from the exact orbit (8.8e-3 at the law's
    window), its chord two steps (four from the window), 4 exact blows an orbit, not 6, its Jacobian
    the lattice orbit's monodromy (no steering Jacobian of the lattice's blow again). The orbit is
    the window-started polish's to the order of that polish's own spread: started 1e-6 or 1e-4 away,
    the window-started polish moves the figures by up to 4.9e-10 and the two largest multipliers by
    up to 9.7e-10 (measured; the chord stops at 1e-9); the new start moves them 5.6e-10 and 1.8e-10
    (measured). The lattice orbit is found from the orbit at 8 cells (``RodRock.coarse_start``: a
    chord of 3 steps, not the settling at the lattice's own grid) and its monodromy takes the blows'
    forward differences: the same 4 exact blows, the figures 1.3e-10 to 3.0e-10 and the largest
    multiplier 8.1e-10 from the orbit found without them (measured). The blows' exact solver runs
    only in their rounds of the drive's force (the tangent takes the last round's switch log). And
    its root is the exact problem's: a full Newton step from it moves the unknowns by less than 2e-9
    of their size."""
    import dataclasses
    import tomllib

    import impactbar.orbits.coupled as OC
    from impactbar.physical import CircuitDrifter
    from impactbar.physical.circuit import CircuitDrifterOrbit

    with open(ROCK_EXAMPLE, "rb") as f:
        drifter = CircuitDrifter.from_config(tomllib.load(f))
    model = drifter.model()
    exact = model.with_(impact=dataclasses.replace(model.law, method="exact"))
    assert exact.law.coarse_model(exact).law.driven_end == "free"
    first = exact.law.coarse_start(exact).law  # (the lattice orbit's start: 8 cells, ending free)
    assert (first.method, first.cells_per_piston, first.driven_end) == ("lattice", 8, "free")
    assert model.law.coarse_start(model) is None  # (lattice blows: no coarse model, no start)
    auto = model.with_(impact=dataclasses.replace(model.law, method="auto", cells_per_piston=None))
    assert auto.law.coarse_model(auto).law.driven_end == auto.law.driven_end  # (its own blows' end)
    count = _counted_exact_blows(monkeypatch)
    lattice = []  # (the lattice's blow Jacobians: whether by forward differences)
    real = OC.blow_jacobian

    def jacobian(model, *args, forward=None, **kwargs):
        if model.law.method == "lattice":
            lattice.append(forward is not None)
        return real(model, *args, forward=forward, **kwargs)

    monkeypatch.setattr(OC, "blow_jacobian", jacobian)
    orbit = find_orbit(exact, drifter.drive())
    assert count[0] <= 4
    # their runs: 7 rounds of the drive's force a blow, 28 (measured), and none outside a blow (the
    # tangent takes the last round's switch log: 29 while it solved its primal again)
    assert count[1] <= 28 and count[2] == 0, count
    # the lattice's Jacobians all by forward differences (five blows each, not ten): the 8 cells'
    # chord's and monodromy's, then the lattice orbit's monodromy (its chord from the 8 cells' orbit
    # takes that one), which only starts the polish's chord; the polish's Jacobian is it (not again)
    assert lattice == [True, True, True]
    point = CircuitDrifterOrbit(drifter, orbit)
    rock = point.rock()
    mu = np.sort(np.abs(np.asarray(orbit.multipliers)))[::-1][:2]
    got = (point.blow_frequency_Hz, point.impact_velocity_m_s, rock["work_on_rock_J"], rock["penetration_mm"],
           point.mean_supply_pressure_Pa, *mu)
    np.testing.assert_allclose(got[:5], EXACT_ORBIT[:5], rtol=1e-9, atol=0)
    np.testing.assert_allclose(got[5:], EXACT_ORBIT[5:], rtol=0, atol=2e-9)
    problem = orbit.problem
    X = np.asarray(orbit._unknowns, dtype=float)
    r, J = problem.residual(X)
    step = np.linalg.solve(J, -r)
    assert np.max(np.abs(step) / np.maximum(np.abs(X), 1e-300)) < 2e-9
