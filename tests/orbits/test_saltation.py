"""The saltation through a flight's end (``_saltation.through``) and the drive's maps' Jacobian
(``map_jacobian``): the central differences in a state moved one component at a time, the same bits
as the same differences taken on fresh copies with numpy's scalars (a reference written here), and an
affine map's matrix to the differences' rounding."""

import numpy as np
import pytest

from impactbar.drives import DriveState
from impactbar.drives.circuit import CircuitFlightSettings, _sundials
from impactbar.drives.circuit import flight as F
from impactbar.drives.flight import EVENT, vector_field
from impactbar.orbits._saltation import map_jacobian, through
from impactbar.physical import circuit_preset


def _differences(fn, z):
    z = np.asarray(z, dtype=float)
    out = np.empty((z.size, z.size))
    for j in range(z.size):
        step = 1e-7 * max(1.0, abs(z[j]))
        zp, zm = z.copy(), z.copy()
        zp[j] += step
        zm[j] -= step
        out[:, j] = (np.asarray(fn(zp), dtype=float) - np.asarray(fn(zm), dtype=float)) / (2.0 * step)
    return out


def test_map_jacobian_of_an_affine_map():
    rng = np.random.default_rng(3)
    B, c = rng.standard_normal((5, 5)), rng.standard_normal(5)
    z = np.array([0.3, -2.5e3, 1e-9, 7.0, -0.0])
    J = map_jacobian(lambda zz: B @ zz + c, z)
    assert np.array_equal(J, _differences(lambda zz: B @ zz + c, z))
    assert np.allclose(J, B, rtol=0.0, atol=1e-5)  # (the differences' rounding at |z| = 2.5e3)


@pytest.mark.skipif(not _sundials.available(), reason="CVODE not bound here")
def test_through_an_event_is_the_fresh_copies_differences():
    """A variational flight of the preset from rest to the valve's ramp end: the saltation there, its
    event's gradient taken in place, equal to the bit to the one on fresh copies."""
    d = circuit_preset("circuit-drifter")
    model, drive = d.model(), d.drive()
    q, v = np.array([-0.08]), np.zeros(1)
    state = drive.start(model, q, v)
    fl = F.circuit_flight(drive, model, DriveState(state.mode, state.z), 0.0, q, v, 50.0,
                          CircuitFlightSettings(sensitivity="cvode"), variational=True)
    assert fl.end == EVENT
    k, M = fl.z.size, 1
    n = 2 * M + k
    got = through(model, drive, k, state.mode, fl, fl.events, None)
    y = np.concatenate((fl.q, fl.v, fl.z))
    f = vector_field(model, drive, state.mode)(fl.t, y)
    e = fl.events[0]
    grad = np.empty(n)
    for j in range(n):
        step = 1e-7 * max(1.0, abs(y[j]))
        yp, ym = y.copy(), y.copy()
        yp[j] += step
        ym[j] -= step
        grad[j] = (e.value(fl.t, yp[:M], yp[M:2 * M], yp[2 * M:])
                   - e.value(fl.t, ym[:M], ym[M:2 * M], ym[2 * M:])) / (2.0 * step)
    assert np.any(grad != 0.0)
    Phi = fl.sensitivity
    Dt = Phi - np.outer(f, grad @ Phi) / float(grad @ f)

    def z_after(zz):
        st = DriveState(state.mode, zz)
        for ev in fl.events:
            st = drive.jump(st.mode, st.z, ev, fl.t, fl.q, fl.v)
        return st.z

    G = np.eye(n)
    G[2 * M:, 2 * M:] = _differences(z_after, fl.z)
    assert np.array_equal(got, G @ Dt)
