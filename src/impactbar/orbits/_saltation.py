"""The Jacobian of a drive's flight through its end and the drive's maps (Hiskens & Pai, "Trajectory
sensitivity analysis of hybrid systems", IEEE Trans. Circuits Syst. I 47 (2000) 204-220): the
saltation of the fundamental matrix at an event, for the shooting problem of
:mod:`impactbar.orbits.driven` (theory §10)."""

from __future__ import annotations

import numpy as np

from ..drives.base import DriveState
from ..drives.flight import vector_field

__all__ = ["through", "map_jacobian", "kept_or_set_jacobian"]


def through(model, drive, k: int, mode, fl, fired, D, exact_maps: bool = False):
    """The Jacobian through the end of a flight: the flight's fundamental matrix ``Phi``
    (``fl.sensitivity``), the event's time moved by the perturbation,
    ``Phi - f^- (grad h . Phi) / (grad h . f^-)`` (``h`` the arrival ``c . q`` or the fired event's
    function, ``f^-`` the vector field in the mode before), then the drive's map at the event (its
    Jacobian by central differences: the maps are affine or constant in the state); composed with
    ``D``, the Jacobian so far.

    Parameters
    ----------
    model : BarModel
    drive : Drive
    k : int
        The drive's state size.
    mode : hashable
        The drive's mode during the flight.
    fl : Flight
        The flight (with its ``sensitivity``).
    fired : sequence of events or None
        The drive's events that ended it, ``None`` for the arrival at the stop.
    D : numpy.ndarray, shape (n, n), or None
        The Jacobian so far, ``n = 2 (N + 1) + k``; ``None`` where the flight's ``sensitivity``
        already carries it (its variational equations started from it, ``OwnFlight.carried``).
    exact_maps : bool, optional
        The map's Jacobian by :func:`kept_or_set_jacobian` (exact where the map keeps or sets each
        component, two calls of it), else by :func:`map_jacobian`'s central differences (``2 k``).

    Returns
    -------
    numpy.ndarray, shape (n, n)
    """
    M = model.n_modes + 1
    n = 2 * M + k
    y = np.concatenate((fl.q, fl.v, fl.z))
    f = vector_field(model, drive, mode)(fl.t, y)
    if fired is None:
        grad = np.concatenate((model.end_weights, np.zeros(M + k)))
    else:
        value, t = fired[0].value, fl.t
        yy = y.copy()  # (one state, each component moved and put back: the event functions only read it)
        q, v, z = yy[:M], yy[M:2 * M], yy[2 * M:]
        grad = np.empty(n)
        for j, yj in enumerate(y.tolist()):  # (as floats: the same roundings as numpy's scalars')
            step = 1e-7 * max(1.0, abs(yj))
            yy[j] = yj + step
            up = value(t, q, v, z)
            yy[j] = yj - step
            down = value(t, q, v, z)
            yy[j] = yj
            grad[j] = (up - down) / (2.0 * step)
    Phi = fl.sensitivity
    rate = float(grad @ f)
    Dt = Phi - np.outer(f, grad @ Phi) / rate
    if fired:
        def z_after(zz):
            st = DriveState(mode, zz)
            for e in fired:
                st = drive.jump(st.mode, st.z, e, fl.t, fl.q, fl.v)
            return st.z

        G = np.eye(n)
        G[2 * M:, 2 * M:] = (kept_or_set_jacobian if exact_maps else map_jacobian)(z_after, fl.z)
        Dt = G @ Dt
    return Dt if D is None else Dt @ D


def map_jacobian(fn, z):
    """The Jacobian of a drive's map ``z -> fn(z)`` by central differences.

    Parameters
    ----------
    fn : callable
        ``z -> z'``, arrays of shape ``(k,)``.
    z : array_like, shape (k,)

    Returns
    -------
    numpy.ndarray, shape (k, k)
    """
    z = np.asarray(z, dtype=float)
    k = z.size
    out = np.empty((k, k))
    for j, zj in enumerate(z.tolist()):  # (as floats: the same roundings as numpy's scalars')
        step = 1e-7 * max(1.0, abs(zj))
        zp, zm = z.copy(), z.copy()
        zp[j] = zj + step
        zm[j] = zj - step
        out[:, j] = (np.asarray(fn(zp), dtype=float) - np.asarray(fn(zm), dtype=float)) / (2.0 * step)
    return out


def kept_or_set_jacobian(fn, z):
    """The Jacobian of a drive's map ``z -> fn(z)`` that keeps each component or sets it to a value of
    its own (the oil circuit's: a flag's event keeps the state, a spool's stop sets its position and
    velocity, a held supply its pressure), exact: the identity's rows where ``fn`` keeps the
    component, zero where it sets it, told apart by ``fn`` at ``z`` and at ``z`` moved by
    :func:`map_jacobian`'s steps (a kept component returned as given, a set one the same at both);
    :func:`map_jacobian`'s central differences (``2 k`` calls, each entry within some ``1e-9`` of
    the exact one by their rounding) where a component is neither.

    Parameters
    ----------
    fn : callable
        The drive's map, an array of shape ``(k,)`` to another.
    z : array_like, shape (k,)
        Where its Jacobian is taken.

    Returns
    -------
    numpy.ndarray, shape (k, k)
        ``d fn / d z`` there.
    """
    z = np.asarray(z, dtype=float)
    moved = z + 1e-7 * np.maximum(1.0, np.abs(z))
    at, there = np.asarray(fn(z.copy()), dtype=float), np.asarray(fn(moved.copy()), dtype=float)
    kept = (at == z) & (there == moved)
    if not np.all(kept | (there == at)):
        return map_jacobian(fn, z)
    return np.diag(kept.astype(float))
