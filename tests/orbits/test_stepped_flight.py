"""A stepped piston's modes in the flight solvers (theory §12).

Independent references: the uniform bar's own code paths (a piston of two segments of equal
impedance goes through every stepped path and must give the uniform bar's numbers), scipy's
quadrature of the overlaps, and a scipy time integration of the stepped bar's modal equations in
their physical coordinates with a finite-difference Poincare map (the orbit and its multipliers).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from impactbar import (
    BarModel,
    CosineLoad,
    InitialState,
    PositionSwitchedDrive,
    SquareWaveLoad,
    SteppedPiston,
    find_orbit,
    periodic_orbits,
    simulate,
)

EQUAL = SteppedPiston([0.4, 0.6], [1.0, 1.0])  # stepped paths, uniform bar
HEAD_NECK = SteppedPiston([0.3, 0.7], [2.0, 1.0])


def test_one_segment_piston_is_the_uniform_bar():
    m = BarModel(3.0, 0.1, 0.6, 4, piston=SteppedPiston([2.0], [5.0]))
    assert m.piston is None and m == BarModel(3.0, 0.1, 0.6, 4)
    assert repr(m) == "BarModel(s=3.0, d=0.1, R=0.6, n_modes=4, impact='paper')"


def test_equal_segments_give_the_uniform_bars_modal_data():
    uni, eq = BarModel(3.0, 0.1, 0.6, 8), BarModel(3.0, 0.1, 0.6, 8, piston=EQUAL)
    assert eq.piston is EQUAL
    np.testing.assert_allclose(eq.frequencies, uni.frequencies, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(eq.end_weights, uni.end_weights, rtol=1e-12)
    np.testing.assert_allclose(eq.drive_weights, uni.drive_weights, rtol=1e-12)
    x = np.linspace(0.0, 1.0, 7)
    np.testing.assert_allclose(eq.shape_functions(x), uni.shape_functions(x), atol=1e-12)
    st = eq.sticking
    np.testing.assert_allclose(st.wavenumbers, (np.arange(1, 9) - 0.5) * np.pi, rtol=1e-13)


@pytest.mark.parametrize("piston", [EQUAL, HEAD_NECK, SteppedPiston([0.2, 0.5, 0.3], [1.0, 0.4, 1.5])])
def test_sticking_overlaps_against_quadrature(piston):
    """Green's identity's overlaps and reaction weights against scipy's quadrature."""
    N = 5
    st = piston.sticking_basis(N)
    free, fixed = piston.modes(N), piston.fixed_modes(N)
    mu, starts, lengths = piston.mass_per_length, piston.starts, piston.lengths

    def integral(f):
        return sum(mu[j] * quad(f, starts[j], starts[j] + lengths[j], epsabs=1e-13, epsrel=1e-13,
                                limit=200)[0] for j in range(piston.n_segments))

    def phi(n, x):
        return float(free.shapes(np.array([min(max(x, 0.0), 1.0)]))[0, n])

    def psi(m, x):
        return float(fixed.shapes(np.array([min(max(x, 0.0), 1.0)]))[0, m])

    phi0, psi0 = free.shapes(np.zeros(1))[0], fixed.shapes(np.zeros(1))[0]
    assert np.all(np.abs(fixed.shapes(np.ones(1))[0]) < 1e-12)  # held at the struck end
    for n in range(N + 1):
        for m in range(N):
            o = integral(lambda x, n=n, m=m: phi(n, x) * psi(m, x))
            assert st.to_free[n, m] == pytest.approx(o * psi0[m] / phi0[n], abs=1e-11)
            assert st.to_contact[m, n] == pytest.approx(o * phi0[n] / psi0[m], abs=1e-11)
    for m in range(N):
        weight = psi0[m] * integral(lambda x, m=m: psi(m, x))
        assert st.reaction_weights[m] == pytest.approx(weight, abs=1e-11)
        assert integral(lambda x, m=m: psi(m, x) ** 2) == pytest.approx(1.0, abs=1e-11)


def test_equal_segments_orbit_and_multipliers_are_the_uniform_bars():
    load = CosineLoad(0.3, 1.0)
    a = find_orbit(BarModel(3.0, 0.1, 0.6, 6), load)
    b = find_orbit(BarModel(3.0, 0.1, 0.6, 6, piston=EQUAL), load)
    assert b.phase == pytest.approx(a.phase, abs=1e-11)
    assert b.impact_velocity == pytest.approx(a.impact_velocity, rel=1e-11)
    np.testing.assert_allclose(np.sort_complex(b.multipliers), np.sort_complex(a.multipliers), atol=1e-9)
    assert (a.admissible, a.stable) == (b.admissible, b.stable)


def test_equal_segments_every_orbit_is_the_uniform_bars():
    load = CosineLoad(0.6, 1.0)
    a = periodic_orbits(BarModel(5.0, 0.1, 0.5, 8), load)
    b = periodic_orbits(BarModel(5.0, 0.1, 0.5, 8, piston=EQUAL), load)
    assert len(a) == len(b) > 0
    np.testing.assert_allclose([o.phase for o in b], [o.phase for o in a], atol=1e-10)
    assert [o.admissibility for o in a] == [o.admissibility for o in b]


def test_stepped_orbit_against_a_scipy_integration():
    """The orbit of a head-neck piston is periodic under an independent integration of the
    stepped bar's modal equations in physical coordinates, and its multipliers are the
    eigenvalues of a finite-difference Poincare map of that integration."""
    s, d, R = 3.0, 0.1, 0.6
    model = BarModel(s, d, R, 6, piston=HEAD_NECK)
    load = CosineLoad(0.3, 1.0)
    orbit = find_orbit(model, load)
    assert orbit.admissible
    modes = HEAD_NECK.modes(6)
    k2 = (s * modes.wavenumbers) ** 2
    phi0, phi1 = modes.shapes(np.array([0.0, 1.0]))
    M = k2.size

    def rhs(t, y):
        return np.concatenate((y[M:], phi0 * float(load(t)) - d * y[M:] - k2 * y[:M]))

    def arrive(t, y):
        return phi1 @ y[:M]

    arrive.terminal, arrive.direction = True, 1

    def poincare(x):
        y0, t0 = x[:-1], x[-1]
        leave = solve_ivp(rhs, (t0, t0 + 1e-3), y0, method="DOP853", rtol=1e-13, atol=1e-15)
        sol = solve_ivp(rhs, (leave.t[-1], t0 + 3.0 * math.pi), leave.y[:, -1], method="DOP853",
                        rtol=1e-13, atol=1e-15, events=arrive)
        ye = sol.y_events[0][0].copy()
        ye[M:] *= -R
        return np.concatenate((ye, [sol.t_events[0][0]]))

    q, v = orbit.modal_state_after_impact
    x0 = np.concatenate((phi0 * q, phi0 * v, [orbit.phase]))  # eta_n = phi_n(0) q_n
    x1 = poincare(x0)
    x1[-1] -= 2.0 * math.pi
    np.testing.assert_allclose(x1, x0, atol=1e-10)
    assert -phi1 @ (phi0 * v) / R == pytest.approx(orbit.impact_velocity, rel=1e-12)
    h = 1e-6
    J = np.column_stack([(poincare(x0 + h * e) - poincare(x0 - h * e)) / (2 * h) for e in np.eye(x0.size)])
    fd = np.sort(np.abs(np.linalg.eigvals(J)))[::-1][:orbit.multipliers.size]
    np.testing.assert_allclose(fd, np.sort(np.abs(orbit.multipliers))[::-1], atol=1e-6)


def test_sticking_run_of_equal_segments_is_the_uniform_bars():
    """R = 0 under the hydraulic load: flights, sticking on the stop (the fixed-free basis), releases."""
    load = SquareWaveLoad(1.0, 1.5)
    runs = []
    for piston in (None, EQUAL):
        m = BarModel(10.0, 0.05, 0.0, 6, piston=piston)
        start = InitialState(np.r_[-0.5, np.zeros(6)], np.zeros(7))
        runs.append(simulate(m, load, start, 40.0))
    a, b = runs
    assert len(a.contact_intervals) > 0
    np.testing.assert_allclose(b.impact_times, a.impact_times, rtol=1e-10)
    np.testing.assert_allclose(b.impact_velocities, a.impact_velocities, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(b.contact_intervals, a.contact_intervals, rtol=1e-10)
    for name in ("work", "final", "damping_loss", "impact_loss", "projection"):
        assert getattr(b.energy, name) == pytest.approx(getattr(a.energy, name), rel=1e-8, abs=1e-12)
    x = np.linspace(0.0, 1.0, 5)
    t = np.linspace(2.0, 12.0, 9)  # through a sticking phase
    np.testing.assert_allclose(b.displacement(x, t), a.displacement(x, t), atol=1e-10)


def test_sticking_run_of_a_stepped_piston_keeps_its_energy_account():
    m = BarModel(10.0, 0.05, 0.0, 6, piston=HEAD_NECK)
    run = simulate(m, SquareWaveLoad(1.0, 1.5), InitialState(np.r_[-0.5, np.zeros(6)], np.zeros(7)), 40.0)
    assert len(run.contact_intervals) > 0 and len(run.impact_times) > 5
    assert run.energy.relative_residual < 1e-8
    # on the stop while held: the struck end's displacement is zero (the fixed-free shapes)
    lo, hi = run.contact_intervals[0]
    t = np.linspace(lo, hi, 7)[1:-1]
    assert np.max(np.abs(run.displacement([1.0], t))) < 1e-12


def test_equal_segments_drive_orbits_are_the_uniform_bars():
    drive = PositionSwitchedDrive(1, 0.5, 0.15)
    a = periodic_orbits(BarModel(3, 0.1, 0.6, 6), drive)
    b = periodic_orbits(BarModel(3, 0.1, 0.6, 6, piston=EQUAL), drive)
    assert len(a) == len(b) == 7
    np.testing.assert_allclose([o.period for o in b], [o.period for o in a], rtol=1e-10)
    assert [o.stable for o in a] == [o.stable for o in b]


def test_a_stepped_piston_under_every_law_and_checked():
    """The wave law takes a stepped piston as its long rod's exact blow (theory §12), the other laws
    as they are; a piston that is not a SteppedPiston is refused by name."""
    assert type(BarModel(3.0, 0.1, 0.6, 4, impact="wave", piston=HEAD_NECK).law).__name__ == "SteppedLongRod"
    assert type(BarModel(3.0, 0.1, 0.6, 4, piston=HEAD_NECK).law).__name__ == "PaperLaw"
    with pytest.raises(ValueError, match="piston must be a SteppedPiston"):
        BarModel(3.0, 0.1, 0.6, 4, piston=[0.5, 0.5])
