"""The wave law's sustained contact (theory §4b): after a window that ends with
the struck end still moving into the rod, the piston pushes a rod that acts on it as a dashpot of
impedance ``Z = s (1 + R)/(1 - R)`` until the interface force would turn tensile."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from impactbar import BarModel, CosineLoad, InitialState, SquareWaveLoad, simulate
from impactbar.laws import PressedContact
from impactbar.laws.wave.impact import wave_impact
from impactbar.laws.wave.sustained import rod_impedance, sustained_contact

TWO_PI = 2 * math.pi
PRESS = SquareWaveLoad(1.0, 1.2)  # presses over [0, 1.2 pi), pulls over the rest


def test_impedance_is_the_window_advance():
    """``Z`` is the coefficient the window's own advance uses: ``advance = impulse / Z``."""
    model = BarModel(7.0, 0.0, 0.4, 3, impact="wave")
    imp = wave_impact(model, CosineLoad(0.3, 1.0), 1.0, np.zeros(4), np.r_[0.8, 0.0, 0.0, 0.0])
    assert imp.advance == pytest.approx(imp.impulse / rod_impedance(model), rel=1e-14)
    assert rod_impedance(BarModel(7.0, 0.0, 0.0, 0, impact="wave")) == 7.0  # R = 0: matched


@pytest.mark.parametrize("load", [CosineLoad(0.6, 1.0), PRESS])
@pytest.mark.parametrize("n_modes, R", [(0, 0.0), (3, 0.6)])
def test_solution_against_an_ode_solver(load, n_modes, R):
    """The exact (eigenvector) solution against Radau on the same dashpot-loaded modal system,
    built here from the field equation (the force ``Z u_t(1)`` at ``x = 1`` enters mode ``n`` with
    ``(-1)^n``), and the energy balance of the record."""
    model = BarModel(10.0, 0.1, R, n_modes, impact="wave")
    M = n_modes + 1
    q, v = np.zeros(M), np.zeros(M)
    v[0] = 0.01
    sc = sustained_contact(model, load, 0.3, q, v, 20.0)
    assert sc.released
    Z = model.s * (1 + R) / (1 - R)
    c = model.end_weights
    sign = (-1.0) ** np.arange(M)
    w2 = (model.s * np.pi * np.arange(M)) ** 2

    jac = np.block([[np.zeros((M, M)), np.eye(M)],
                    [-np.diag(w2), -model.d * np.eye(M) - Z * np.outer(sign, c)]])
    ones = np.r_[np.zeros(M), np.ones(M)]
    sol = solve_ivp(lambda t, y: jac @ y + ones * load(t), (0.3, 0.3 + sc.duration),
                    np.concatenate((q, v)), method="Radau", jac=jac, rtol=1e-11, atol=1e-14,
                    max_step=0.05)
    # free-free state with positions from the moving rod end: the ODE's q less the rod's advance
    yq, yv = sol.y[:M, -1], sol.y[M:, -1]
    yq = yq - np.r_[c @ yq, np.zeros(n_modes)]
    np.testing.assert_allclose(sc.q_after, yq, atol=1e-10)
    np.testing.assert_allclose(sc.v_after, yv, atol=1e-10)
    assert sc.advance == pytest.approx(c @ sol.y[:M, -1], rel=1e-8)
    work, rod, damp, field = sc.account(sc.duration)
    e0 = 0.5 * v[0] ** 2
    assert e0 + work == pytest.approx(field + rod + damp, abs=1e-14 * (e0 + abs(work)))


def test_release_where_the_force_turns_tensile():
    """Exit: the interface force is positive through the sustained phase and 0 at the release,
    and the end then leaves the rod end (its flight starts away from it)."""
    model = BarModel(100.0, 0.05, 0.3, 2, impact="wave")
    tr = simulate(model, PRESS, InitialState.rigid(-0.2, 0.0, 2), TWO_PI)
    pressed = [w for w in tr.impacts if isinstance(w, PressedContact)]
    assert pressed
    rec = pressed[0]
    sc = rec.sustained
    assert sc.released
    tau = np.linspace(0.0, sc.duration, 400)[1:-1]
    force = sc.force(tau)
    peak = float(np.max(force))
    assert np.all(force > 0.0)
    assert abs(sc.force(sc.duration)[0]) <= 1e-10 * peak
    assert sc.force(sc.duration * (1 - 1e-6))[0] > 0.0
    # the release comes after the drive turned tensile (t = 1.2 pi), within a few 1/Z
    t_rel = sc.t0 + sc.duration
    assert 1.2 * np.pi < t_rel < 1.2 * np.pi + 10.0 / sc.impedance
    # the flight after the release moves away: the end off the rod end just after
    assert tr.contact_intervals[0, 1] == pytest.approx(t_rel, abs=1e-14)
    later = tr.end_displacement(np.array([t_rel + 1e-3, t_rel + 0.1]))
    assert np.all(later < 0.0)


def test_entry_only_when_the_window_ends_driven_into_the_rod():
    """Entry: a free arrival under a pulling drive leaves after its window (no sustained phase);
    under a pressing one the window's end still moves into the rod and the contact goes on."""
    model = BarModel(100.0, 0.0, 0.0, 0, impact="wave")
    law = model.law
    q, v = np.zeros(1), np.array([1.0])
    _, v_free, t_free, rec_free = law.contact(model, CosineLoad(-0.5, 0.1), 1.0, q, v, t_end=10.0)
    assert not isinstance(rec_free, PressedContact) and t_free == pytest.approx(1.02)
    assert v_free[0] <= 0.0
    _, _, t_pressed, rec = law.contact(model, CosineLoad(0.5, 0.1), 1.0, q, v, t_end=10.0)
    assert isinstance(rec, PressedContact)
    assert rec.window.v_after[0] > 0.0  # the window ended with the end moving into the rod
    assert t_pressed == pytest.approx(10.0)  # pressed for the whole run: stops at t_end
    assert not rec.sustained.released


@pytest.mark.parametrize("n_modes, R, d", [(0, 0.0, 0.1), (3, 0.4, 0.05)])
def test_energy_account_closes(n_modes, R, d):
    model = BarModel(300.0, d, R, n_modes, impact="wave")
    tr = simulate(model, PRESS, InitialState.rigid(-0.3, 0.0, n_modes), 3 * TWO_PI + 0.5)
    assert any(isinstance(w, PressedContact) for w in tr.impacts)
    acc = tr.energy
    assert abs(acc.relative_residual) < 1e-9
    # the rod's energy is the whole contacts' (windows and sustained phases)
    rod = sum(w.rod_energy for w in tr.impacts[:-1])
    last = tr.impacts[-1]
    rod += last.account(min(tr.t_end - tr.impact_times[-1], last.duration))[1]
    assert acc.impact_loss == pytest.approx(rod, rel=1e-12)


def test_cost_does_not_grow_with_s():
    """A reported case: s = 1e6 over one load period, 850,000 windows before; now the same
    few pieces at every s."""
    counts = []
    for s in (1e2, 1e4, 1e6):
        model = BarModel(s, 0.1, 0.0, 0, impact="wave")
        tr = simulate(model, PRESS, InitialState.rigid(-0.5, 0.0), TWO_PI)
        counts.append((len(tr._segments), tr.n_impacts))
        assert tr.contact_intervals.shape == (1, 2)
    assert counts[0] == counts[1] == counts[2] == (3, 1)


def _chained(model, load, t, q, v, t_stop):
    """The former behaviour: window after window while the end is still driven into the rod
    (each window by the Python characteristics solver); the release time and state, and the rod
    end's advance."""
    c = model.end_weights
    advance = 0.0
    while t < t_stop:
        imp = wave_impact(model, load, t, q, v)
        advance += imp.advance
        q, v, t = imp.q_after.copy(), imp.v_after.copy(), t + imp.duration
        if not c @ v > 0.0 or imp.separations:
            break
        q[0] -= c @ q
    return t, q, v, advance


@pytest.mark.parametrize("s", [200.0, 800.0])
def test_continuity_with_chained_windows(s):
    """Where windows chain, they are the same physics (nothing returns from the rod): the rigid
    piston's sustained contact matches the chained windows' release time to ``4/s`` and the state
    there to ``2 sup|p| / s`` (the chained windows of a rigid piston drop the strain each window
    leaves, an ``O(1/s)`` difference; the bound is not a fit: it halves as s doubles)."""
    model = BarModel(s, 0.0, 0.0, 0, impact="wave")
    load = CosineLoad(0.5, 0.8)
    t0, q, v = 0.5, np.zeros(1), np.array([0.3])
    tc, qc, vc, advance = _chained(model, load, t0, q, v, 10.0)
    qs, vs, ts, rec = model.law.contact(model, load, t0, q, v, t_end=10.0)
    assert isinstance(rec, PressedContact)
    assert tc > t0 + 1.0  # a long pressed phase: many windows chained
    assert abs(ts - tc) < 4.0 / s
    assert abs(vs[0] - vc[0]) < 2 * load.sup_abs / s
    assert rec.advance == pytest.approx(advance, rel=10.0 / s)
