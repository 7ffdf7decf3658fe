"""The variational flights' Newton systems by one LU of the state's block (``blocks=True``, the
default: ``_cvode._block_setup_c``, ``_cvode._block_solve_c`` in place of the band solver's setup and
solve) against SUNDIALS' band solver itself (``blocks=False``, the way before): the same steps, the
same flights and the same orbit and multipliers of the preset drifter with a flexible piston. The
plain flights' Newton systems by the same LU of the state's block (the energies' rows the identity's)
against SUNDIALS' dense solver (``blocks=False``): the same steps and states, to the bit.

The block solver repeats the band LU's operations on each block in their order, so on this machine
the two agree to the bit; the orbits are compared to 1e-8 (a SUNDIALS built with fused multiply-adds
would round its band solve otherwise)."""

from pathlib import Path

import numpy as np
import pytest

from impactbar import find_orbit
from impactbar.drives import DriveState
from impactbar.drives.circuit import CircuitFlightSettings, HydraulicCircuitDrive, _sundials
from impactbar.drives.circuit import flight as F
from impactbar.physical import circuit_preset, load

pytestmark = pytest.mark.skipif(not _sundials.available(), reason="CVODE not bound here")

#: CVODE's variational flights, by the blocks' LU and by the band solver's own
FAST = CircuitFlightSettings(sensitivity="cvode")
BAND = CircuitFlightSettings(blocks=False, sensitivity="cvode")
SPOOL = Path(__file__).resolve().parents[2] / "examples" / "circuit_drill_spool.toml"


@pytest.fixture(scope="module")
def drifter():
    return circuit_preset("circuit-drifter")


def _engaged():
    from impactbar.drives.circuit import _cvode

    ws = _cvode.last_workspace()
    return ws is not None and ws.band > 0 and ws.blocks


def _same_orbits(fast, band):
    assert abs(fast.period - band.period) <= 1e-8 * band.period
    assert np.allclose(fast.impact_velocities, band.impact_velocities, rtol=1e-8, atol=0.0)
    assert np.allclose(fast._unknowns, band._unknowns, rtol=1e-8, atol=1e-12)
    assert np.max(np.abs(fast.multipliers - band.multipliers)) <= 1e-8
    assert fast.stable == band.stable


def test_a_variational_flight_takes_the_band_solvers_steps(drifter):
    """Four modes, a stroke flight from rest with the valve open: the same steps and the same
    fundamental matrix, CVODE's counters equal."""
    from impactbar.drives.circuit import _cvode

    model = drifter.model().with_(n_modes=4)
    drive = drifter.drive()
    M = model.n_modes + 1
    q, v = np.zeros(M), np.zeros(M)
    q[0] = -0.02
    state = drive.start(model, q, v)
    out = {}
    for blocks in (True, False):
        fl = F.circuit_flight(drive, model, DriveState(state.mode, state.z), 0.0, q, v, 50.0,
                              CircuitFlightSettings(blocks=blocks, sensitivity="cvode"), variational=True)
        out[blocks] = (fl, _cvode.last_workspace().statistics(), _cvode.last_workspace().blocks)
    (fast, s_fast, engaged), (band, s_band, off) = out[True], out[False]
    assert engaged and not off  # (SUNDIALS 7's table found here: else the band solver both times)
    assert s_fast["steps"] == s_band["steps"] > 100 and s_fast["setups"] == s_band["setups"]
    assert np.allclose(fast.piece.t, band.piece.t, rtol=1e-12, atol=0.0)
    scale = np.max(np.abs(band.sensitivity))
    assert np.allclose(fast.sensitivity, band.sensitivity, rtol=1e-10, atol=1e-12 * scale)
    assert np.allclose(np.concatenate((fast.q, fast.v, fast.z)), np.concatenate((band.q, band.v, band.z)),
                       rtol=1e-12, atol=1e-14)


def test_the_four_mode_orbit_is_the_band_solvers(drifter):
    model = drifter.model().with_(n_modes=4)
    fast = find_orbit(model, drifter.drive(), settings=FAST)
    assert _engaged()
    band = find_orbit(model, drifter.drive(), settings=BAND)
    _same_orbits(fast, band)


@pytest.mark.slow  # some 40 s of CPU time (80 s of wall time on the shared machine)
def test_the_eight_mode_orbit_is_the_band_solvers(drifter):
    model = drifter.model().with_(n_modes=8)
    fast = find_orbit(model, drifter.drive(), settings=FAST)
    band = find_orbit(model, drifter.drive(), settings=BAND)
    _same_orbits(fast, band)


def test_blocks_must_be_a_bool(drifter):
    with pytest.raises(ValueError, match="blocks must be True or False"):
        CircuitFlightSettings(blocks=1)
    assert isinstance(drifter.drive(), HydraulicCircuitDrive) and drifter.drive().integrator.blocks is True


@pytest.mark.parametrize("spool", [False, True], ids=["preset", "spool drill"])
def test_a_plain_flight_takes_the_dense_solvers_steps(drifter, spool):
    """A rigid stroke from rest of the preset (6 states, 8 energies) and of the spool drill (10 states,
    20 energies): the state's block and the energies' identity, by the blocks' LU, take the dense
    solver's steps and states to the bit (its LU never pivots into the energies' zero rows, and their
    updates are all of zeros), CVODE's counters equal."""
    from impactbar.drives.circuit import _cvode

    d = load(SPOOL) if spool else drifter
    model, drive = d.model(), d.drive()
    q, v = np.array([-0.02]), np.zeros(1)
    state = drive.start(model, q, v)
    out = {}
    for blocks in (True, False):
        fl = F.circuit_flight(drive, model, DriveState(state.mode, state.z), 0.0, q, v, 50.0,
                              CircuitFlightSettings(blocks=blocks))
        ws = _cvode.last_workspace()
        out[blocks] = (fl, ws.statistics(), ws.band > 0 and ws.plain and ws.blocks)
    (fast, s_fast, engaged), (dense, s_dense, off) = out[True], out[False]
    assert engaged and not off
    assert s_fast == s_dense and s_fast["steps"] > 50
    assert fast.piece.y.shape[1] == drive.layout.size(1) + drive.layout.n_energy
    assert np.array_equal(fast.piece.t, dense.piece.t) and np.array_equal(fast.piece.y, dense.piece.y)
    for a, b in ((fast.q, dense.q), (fast.v, dense.v), (fast.z, dense.z)):
        assert np.array_equal(a, b)
