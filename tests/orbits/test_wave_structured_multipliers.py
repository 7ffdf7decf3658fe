"""The wave law's structured Floquet multipliers (rank-2 correction of a block-diagonal map,
Aberth-Ehrlich iteration) against the eigenvalues of the dense Jacobian, which the finite-difference
tests check (the dense eigenvalue problem made periodic_orbits at 1024 modes take minutes)."""

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, SquareWaveLoad, periodic_orbits
from impactbar.laws.wave.periodic import wave_floquet_multipliers, wave_orbit_states, wave_phase_roots

CASES = [
    (50, 0.0, 0.5, CosineLoad(0.6, 1.0)),
    (60, 0.05, 0.8, CosineLoad(0.3, 1.0, 2)),
    (80, 0.1, 0.3, SquareWaveLoad(1.0, 1.3)),
    (45, 0.01, 0.0, CosineLoad(0.3, 1.0)),  # R = 0: the map is rank one
    (41, 0.2, 0.0, CosineLoad(0.2, 1.0)),
    (3, 0.02, 0.5, CosineLoad(0.6, 1.0)),
]


@pytest.mark.parametrize("N, d, R, load", CASES)
def test_structured_equals_dense(N, d, R, load):
    model = BarModel(3.0, d, R, N, impact="wave")
    roots = wave_phase_roots(model, load)
    assert roots
    for phase, _ in roots:
        _, y_end, y_minus, rate = wave_orbit_states(model, load, phase)
        dense = wave_floquet_multipliers(model, load, phase, y_end, y_minus, rate, method="dense")
        fast = wave_floquet_multipliers(model, load, phase, y_end, y_minus, rate, method="structured")
        assert dense.shape == fast.shape == (2 * N + 2,)
        np.testing.assert_allclose(fast, dense, rtol=0, atol=1e-10 * np.max(np.abs(dense)))


def test_orbits_use_it_from_40_modes_and_agree():
    model, load = BarModel(3.0, 0.0, 0.5, 64, impact="wave"), CosineLoad(0.6, 1.0)
    for o in periodic_orbits(model, load):
        _, y_end, y_minus, rate = wave_orbit_states(model, load, o.phase)
        dense = wave_floquet_multipliers(model, load, o.phase, y_end, y_minus, rate, method="dense")
        np.testing.assert_allclose(o.multipliers, dense, rtol=0, atol=1e-10 * np.max(np.abs(dense)))
    with pytest.raises(ValueError, match="method must be"):
        wave_floquet_multipliers(model, load, 0.0, None, None, None, method="qr")
