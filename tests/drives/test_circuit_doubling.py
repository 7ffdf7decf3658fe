"""A period doubling of the oil-circuit drifter and branch switching onto its period-2 motions
(theory §11).

The preset ``circuit-drifter``'s circuit unchanged, its piston flexible (two modes), undamped, on a
stop of restitution 0.8, followed in the wave-speed ratio ``s``: the most negative multiplier passes
-1 at ``s = 8.3905204`` (with four modes at 8.4265385: the doubling is the piston's, not the
truncation's). Checked: the crossing by the finite-difference Poincare map of the orbit on either
side (independent of the variational equations that give the multipliers), the period-2 branch
switched onto at the doubling (the two impacts differ, the motion is stable: supercritical), and
past the doubling a run of ``simulate`` started next to the unstable period-1 orbit settles onto the
period-2 orbit Newton's method finds.
"""

import dataclasses

import numpy as np
import pytest

from impactbar import InitialState, continue_orbit, find_orbit, simulate
from impactbar.physical import circuit_preset

#: where the doubling is (two flexible modes, R = 0.8, d = 0; located by continue_orbit)
DOUBLING_S = 8.3905204


@pytest.fixture(scope="module")
def doubling():
    p = circuit_preset("circuit-drifter")
    drive = p.drive()
    model = p.model().with_(n_modes=2, d=0.0, R=0.8, s=8.41)
    start = find_orbit(model, drive)
    branch = continue_orbit(start, "s", to=8.37, events=True, stop_on=("period-doubling",))
    return drive, start, branch


def _fd_multipliers(orbit, h=1e-5):
    """The eigenvalues of the return map on the section by central differences of the shooting
    residual (plain flights, no variational equations), the trivial one along the flow included.

    The step balances the flights' noise (their tolerance, 1e-10, over ``h``) against the truncation
    (``h^2``): the most negative multiplier next to the doubling came 5e-5 to 1e-4 from the
    variational one at ``h = 1e-6`` (as the flights' rounding fell), 4e-6 to 7e-6 at ``1e-5``, 8e-5 at
    ``1e-4`` (measured)."""
    problem, X = orbit._problem, np.asarray(orbit._unknowns, dtype=float)
    n = X.size
    P = np.empty((n, n))
    for j in range(n):
        step = h * max(1.0, abs(X[j]))
        up, down = X.copy(), X.copy()
        up[j] += step
        down[j] -= step
        P[:, j] = (problem.value(up) - problem.value(down)) / (2 * step)
    return np.linalg.eigvals(P + np.eye(n))


def test_the_circuit_doubles_its_period_as_the_piston_softens(doubling):
    _, start, branch = doubling
    assert start.stable
    (pd,) = [e for e in branch.events if e.kind == "period-doubling"]
    assert pd.value == pytest.approx(DOUBLING_S, abs=1e-5)
    assert abs(pd.multiplier + 1.0) < 1e-6
    # either side, by finite differences: the most negative real eigenvalue above, then below -1
    before = [o for o, s in zip(branch.orbits, branch.values, strict=True) if s > pd.value][-1]
    after = [o for o, s in zip(branch.orbits, branch.values, strict=True) if s < pd.value][0]
    for orbit, stable in ((before, True), (after, False)):
        fd = _fd_multipliers(orbit)
        lowest = float(np.min(fd.real))
        assert lowest == pytest.approx(float(np.min(orbit.multipliers.real)), abs=1e-4)
        assert (lowest > -1.0) == stable and orbit.stable == stable


def test_branch_switching_onto_the_period_two_motions(doubling):
    _, _, branch = doubling
    (pd,) = [e for e in branch.events if e.kind == "period-doubling"]
    doubled = continue_orbit(pd, "s", to=8.37, max_points=3)
    assert doubled.impacts == 2
    beyond = [(o, s) for o, s in zip(doubled.orbits, doubled.values, strict=True) if s < pd.value - 1e-5]
    assert len(beyond) == 2
    ratios = []
    for orbit, s in beyond:  # two different blows a period, a stable motion where period 1 is not
        v = orbit.impact_velocities
        assert abs(v[0] - v[1]) > 1e-4 and orbit.stable
        ratios.append((v[0] - v[1]) ** 2 / (pd.value - s))
    # supercritical: the blows part as the square root of the distance from the doubling
    assert ratios[0] == pytest.approx(ratios[1], rel=0.2)


@pytest.mark.slow
def test_past_the_doubling_a_run_settles_on_the_period_two_orbit(doubling):
    drive, start, branch = doubling
    (pd,) = [e for e in branch.events if e.kind == "period-doubling"]
    model = start.model.with_(s=8.33)
    one = find_orbit(model, drive, guess=pd.orbit)
    assert not one.stable
    doubled = continue_orbit(pd, "s", to=8.33, max_points=12)
    two = find_orbit(model, drive, impacts=2, guess=doubled.orbits[-1])
    assert two.stable
    q, v = one.modal_state_after_impact
    run = simulate(model, dataclasses.replace(drive, start_pressures=tuple(one.drive_states[0])),
                   InitialState(np.asarray(q), np.asarray(v) * (1 + 1e-3)), 1e6, max_impacts=400)
    last = np.sort(run.impact_velocities[-2:])
    np.testing.assert_allclose(last, np.sort(two.impact_velocities), rtol=1e-6)


@pytest.mark.slow
def test_with_four_modes_the_doubling_stays():
    """The doubling is the piston's, not the truncation's: with four flexible modes it moves from
    8.3905 to 8.4265385."""
    p = circuit_preset("circuit-drifter")
    model = p.model().with_(n_modes=4, d=0.0, R=0.8, s=8.44)
    branch = continue_orbit(find_orbit(model, p.drive()), "s", to=8.41, events=True,
                            stop_on=("period-doubling",))
    (pd,) = [e for e in branch.events if e.kind == "period-doubling"]
    assert pd.value == pytest.approx(8.4265385, abs=1e-5)
