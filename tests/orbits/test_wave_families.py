"""Under the wave law a phase residual that vanishes on a whole interval is one
degenerate family of orbits, not its rounding noise's sign changes (143, 166 and 197 "orbits" at
q = 1e-12, 1 and 1e12 before), and identically so at every load scale (the model is linear in
the load)."""

import math

import numpy as np
import pytest

from impactbar import BarModel, SquareWaveLoad, periodic_orbits
from impactbar.laws.wave.periodic import wave_phase_families, wave_phase_residual, wave_phase_roots

RIGID = BarModel(1, 0, 0.9, 0, impact="wave")


def test_degenerate_family_is_one_interval_at_every_load_scale():
    # s = 1: the window is [phase, phase + 2]; the load's short negative part [6.1261, 2 pi) lies in
    # the window's second half, [phase + 1, phase + 2], for phase in [2 pi - 2, 6.1261 - 1]
    load1 = SquareWaveLoad(1.0, 1.95)
    lo_exact, hi_exact = 2 * math.pi - 2.0, float(load1.breaks[1]) - 1.0
    found = []
    for q in (1e-12, 1.0, 1e12):
        load = SquareWaveLoad(q, 1.95)
        orbits = periodic_orbits(RIGID, load)
        assert orbits.degenerate and len(orbits.families) == 1
        lo, hi = orbits.families[0]
        assert lo == pytest.approx(lo_exact, abs=1e-4)  # the residual leaves it quadratically
        assert hi == pytest.approx(hi_exact, abs=1e-9)
        assert wave_phase_roots(RIGID, load) == []  # no noise reported as roots
        assert len(orbits) == 1 and orbits[0].multiplicity == 0
        assert lo < orbits[0].phase < hi
        found.append((lo, hi, orbits[0].phase, orbits[0].impact_velocity / q))
        # the family: the residual vanishes (to rounding) inside, not outside
        inside = np.linspace(lo + 1e-3, hi - 1e-3, 50)
        outside = np.array([lo - 0.05, hi + 0.05, 1.0, 3.0])
        scale = np.max(np.abs(wave_phase_residual(RIGID, load, np.linspace(0, 2 * np.pi, 64))))
        assert np.max(np.abs(wave_phase_residual(RIGID, load, inside))) <= 1e-12 * scale
        assert np.min(np.abs(wave_phase_residual(RIGID, load, outside))) > 1e-6 * scale
    found = np.array(found)
    same = np.broadcast_to(found[1], found.shape)  # the same at every scale
    np.testing.assert_allclose(found, same, rtol=1e-9, atol=1e-9)
    # the rigid identity of the wave law: 2 pi p0 / (1 + R) - int_0^{1/s} p = the impact velocity
    assert found[1, 3] == pytest.approx(2 * math.pi * load1.p0 / 1.9 - 1.0 * 1.0, abs=1e-9)


def test_family_orbit_has_the_neutral_multiplier():
    """Along a family the phase is free: the one-impact map has a multiplier exactly 1."""
    o = periodic_orbits(RIGID, SquareWaveLoad(1.0, 1.95))[0]
    assert np.min(np.abs(o.multipliers - 1.0)) < 1e-9


@pytest.mark.parametrize("model, load", [
    (BarModel(10, 0.05, 0.5, 2, impact="wave"), SquareWaveLoad(0.5, 1.2)),
    (BarModel(1, 0, 0.9, 0, impact="wave"), SquareWaveLoad(1.0, 1.0)),
])
def test_isolated_roots_have_no_family(model, load):
    orbits = periodic_orbits(model, load)
    assert wave_phase_families(model, load) == [] and not orbits.degenerate
    assert len(orbits) >= 1 and all(o.multiplicity == 1 for o in orbits)
    r = wave_phase_residual(model, load, np.array([o.phase for o in orbits]))
    scale = np.max(np.abs(wave_phase_residual(model, load, np.linspace(0, 2 * np.pi, 64))))
    assert np.max(np.abs(r)) <= 1e-10 * scale
