"""The wave law with a stepped piston (theory §4b, §12; impactbar.laws.rodrock.longrod): each contact the
exact blow on a semi-infinite rod of the struck end's impedance times ``(1 + R)/(1 - R)``, over the
window ``2/s``; against the wave law's own characteristics solver and the staircase's closed form."""

import numpy as np
import pytest
from test_stepped_blow import _closed_form

import impactbar as ib
from impactbar.laws.rodrock.longrod import LongRodContact, SteppedLongRod


def _model(piston, s=10.0, d=0.1, R=0.5, N=4):
    return ib.BarModel(s, d, R, N, impact="wave", piston=piston)


def test_two_equal_segments_give_the_wave_laws_orbit():
    """A piston cut into two segments of one section under ``impact="wave"`` runs the exact blow on
    the long rod (not the wave law's window solver): its orbit is the wave law's, found by the
    wave law's own characteristics and phase equation, to rounding in the impact times and
    velocities, and its multipliers (from the contact map's finite-difference Jacobian) to 1e-7 (its
    flights start off the rod, ``q_0`` among the unknowns: one more multiplier, zero)."""
    load = ib.CosineLoad(0.3, 1.0)
    uniform = ib.find_orbit(_model(None), load)
    model = _model(ib.SteppedPiston([0.4, 0.6], [1.0, 1.0]))
    assert isinstance(model.law, SteppedLongRod) and model.impact == "wave"
    orbit = ib.find_orbit(model, load, guess=uniform)
    np.testing.assert_allclose(orbit.impact_times, uniform.impact_times, rtol=0, atol=1e-12)
    np.testing.assert_allclose(orbit.impact_velocities, uniform.impact_velocities, rtol=1e-12)
    mu, mu0 = np.sort(np.abs(orbit.multipliers)), np.sort(np.abs(uniform.multipliers))
    assert mu.size == mu0.size + 1 and mu[0] < 1e-12
    np.testing.assert_allclose(mu[1:], mu0, rtol=1e-7)
    assert isinstance(orbit.contacts[0], LongRodContact)
    assert orbit.contacts[0].rod_energy == pytest.approx(uniform.contacts[0].rod_energy, rel=1e-10)


@pytest.mark.parametrize("lengths, impedances", [([0.75, 0.25], [1.0, 2.0]), ([0.5, 0.5], [3.0, 1.0]),
                                                 ([0.375, 0.625], [1.0, 1.5])])
def test_a_rigid_arrival_sends_the_staircase(lengths, impedances):
    """``R = 0``: the long rod has the head's impedance, and a rigid piston arriving at ``V`` without
    a drive sends the staircase of the characteristics' closed form (``Z_h V/2``, then the neck's
    transmitted and reflected steps) over the window, to rounding; the rod takes its energy
    ``int N^2 dt / Z_h``, the piston keeps the rest, and the rod end advances by the impulse over
    ``Z_h``."""
    s, V = 2.0, 1.3
    piston = ib.SteppedPiston(lengths, impedances)
    model = _model(piston, s=s, d=0.0, R=0.0, N=3)
    q, v = np.zeros(4), np.zeros(4)
    v[0] = V
    _, _, t_release, rec = model.law.contact(model, ib.FourierLoad(0.0, []), 0.3, q, v)
    assert t_release == pytest.approx(0.3 + 2.0 / s)
    t = np.linspace(0.0, 2.0 / s, 4001)[1:-1]
    t = t[np.abs((t * s / 2.0 - piston.lengths[1]) % 1.0) > 1e-9]  # (off the steps)
    scale = 0.5 * s * piston.mass_per_length[-1] * V
    np.testing.assert_allclose(rec.blow.shank_force(t), _closed_form(piston, s, V, t), rtol=0,
                               atol=1e-13 * scale)
    Zh = s * piston.mass_per_length[-1]
    ex = rec.blow.exact
    ts = np.sort(np.concatenate(([0.0, 2.0 / s], ex.junction_breaks(ex.contact_junction))))
    mid = 0.5 * (ts[:-1] + ts[1:])
    n = _closed_form(piston, s, V, mid)
    into_rod = float(np.sum(n * n * np.diff(ts))) / Zh
    assert rec.rod_energy == pytest.approx(into_rod, rel=1e-12)
    assert rec.efficiency == pytest.approx(into_rod / (0.5 * V * V), rel=1e-12)
    assert rec.advance == pytest.approx(float(np.sum(n * np.diff(ts))) / Zh, rel=1e-12)


def test_simulate_closes_its_energy_account_and_chains_pressed_windows():
    """A piston heavy at its driven end keeps pressing the rod after the window: ``simulate`` chains
    windows (the rod being memoryless, exactly), the run's energy account closes to rounding, and
    each record's efficiency lies in [0, 1]."""
    model = _model(ib.SteppedPiston([0.3, 0.7], [2.0, 1.0]))
    tr = ib.simulate(model, ib.CosineLoad(0.3, 1.0), ib.InitialState.rigid(-0.1, 0.0, n_modes=4), 40.0)
    assert tr.n_impacts > 10 and tr.energy.relative_residual < 1e-12
    gaps = np.diff(tr.impact_times)
    assert np.any(np.abs(gaps - 2.0 / model.s) < 1e-12)  # a contact that went on: the next window at once
    for rec in tr.impacts:
        assert isinstance(rec, LongRodContact) and 0.0 <= rec.efficiency <= 1.0


def test_the_law_follows_the_piston_and_refuses_a_rigid_stop():
    model = _model(ib.SteppedPiston([0.3, 0.7], [2.0, 1.0]))
    assert type(model.with_(piston=None).law).__name__ == "WaveLaw"
    assert isinstance(model.with_(n_modes=2).law, SteppedLongRod)
    assert type(model.with_(impact="paper").law).__name__ == "PaperLaw"
    with pytest.raises(ValueError, match="R must be below 1 under the wave law with a stepped piston"):
        _model(ib.SteppedPiston([0.3, 0.7], [2.0, 1.0]), R=1.0)
