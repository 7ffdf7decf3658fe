"""The saltation through a flight's end (``_saltation.through``) and the drive's maps' Jacobian
(``map_jacobian``): the central differences in a state moved one component at a time, the same bits
as the same differences taken on fresh copies with numpy's scalars (a reference written here), and an
affine map's matrix to the differences' rounding; a map that keeps or sets each component
(``kept_or_set_jacobian``) exactly, from two calls, the spool drill's maps among them."""

import numpy as np
import pytest

from impactbar.drives import DriveState
from impactbar.drives.circuit import CircuitFlightSettings, _sundials
from impactbar.drives.circuit import flight as F
from impactbar.drives.flight import EVENT, vector_field
from impactbar.orbits import _saltation
from impactbar.orbits._saltation import kept_or_set_jacobian, map_jacobian, through
from impactbar.physical import circuit_preset, load


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


def _keep_or_set(zz):
    out = np.array(zz, dtype=float)
    out[1], out[3] = 0.0, 1.0  # (a stop's velocity and position, as a spool's at its stop)
    return out


def test_a_map_that_keeps_or_sets_is_exact_from_two_calls():
    """The identity's rows and zeros exactly, where the central differences' diagonal is 1 only to
    their rounding (at ``z = 0.3``: some 1e-9 off)."""
    z = np.array([0.3, -2.5e3, 1e-9, 0.97, -0.0, 7.0])
    calls = []

    def fn(zz):
        calls.append(1)
        return _keep_or_set(zz)

    J = kept_or_set_jacobian(fn, z)
    assert len(calls) == 2
    assert np.array_equal(J, np.diag([1.0, 0.0, 1.0, 0.0, 1.0, 1.0]))
    central = map_jacobian(_keep_or_set, z)
    assert np.max(np.abs(central - J)) < 1e-8 and not np.array_equal(central, J)


def test_another_map_takes_the_central_differences():
    rng = np.random.default_rng(5)
    B, c = rng.standard_normal((4, 4)), rng.standard_normal(4)
    z = np.array([0.3, -1.5, 2.0, 1e-3])
    assert np.array_equal(kept_or_set_jacobian(lambda zz: B @ zz + c, z),
                          map_jacobian(lambda zz: B @ zz + c, z))
    swap = kept_or_set_jacobian(lambda zz: np.asarray(zz)[::-1].copy(), z)  # (kept by none: moved)
    assert np.array_equal(swap, map_jacobian(lambda zz: np.asarray(zz)[::-1].copy(), z))


@pytest.mark.skipif(not _sundials.available(), reason="CVODE not bound here")
def test_the_spool_drills_maps_keep_or_set(monkeypatch):
    """Every map at the events of the spool drill's orbit (its variational periods' 58 saltations)
    keeps or sets each component: no central differences taken, each exact Jacobian within 1e-8 of
    them."""
    from pathlib import Path

    from impactbar import find_orbit

    d = load(Path(__file__).resolve().parents[2] / "examples" / "circuit_drill_spool.toml")
    seen, central = [], []
    exact = _saltation.kept_or_set_jacobian

    def recorded(fn, z):
        J = exact(fn, z)
        seen.append(np.max(np.abs(J - map_jacobian(fn, z))))
        return J

    monkeypatch.setattr(_saltation, "kept_or_set_jacobian", recorded)
    monkeypatch.setattr(_saltation, "map_jacobian", lambda fn, z: central.append(1) or map_jacobian(fn, z))
    find_orbit(d.model(), d.drive())
    assert len(seen) >= 29 and not central and max(seen) < 1e-8
