"""The flexible bar's flow between impacts under a constant force, mode by mode (eq. 8, theory
§10): each mode's 2x2 fundamental block ``(a, b, c, e)`` and the affine part of the flow, in closed
form for the rigid mode and the underdamped flexible ones. The building blocks of the valve's orbit
problem (:mod:`.valve_segment`) and of its search of every orbit (:mod:`.valve_search`)."""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING

import numpy as np

from ..drives.valve import RETURN, STROKE
from ..dynamics.modal import fundamental

if TYPE_CHECKING:
    from ..model import BarModel


def _w2(model: BarModel) -> np.ndarray:
    """``(s n pi)^2``, ``n = 0..N`` (eq. 6), built once per ``(s, N)`` (the flows ask for it at every
    step; callers only read it); a stepped piston's ``(s k_n)^2`` (theory §12)."""
    if model.piston is not None:
        return _w2_stepped(model)
    return _w2_of(model.s, model.n_modes + 1)


@functools.lru_cache(maxsize=64)
def _w2_stepped(model: BarModel) -> np.ndarray:
    w2 = model.frequencies ** 2
    w2.flags.writeable = False
    return w2


@functools.lru_cache(maxsize=64)
def _w2_of(s: float, M: int) -> np.ndarray:
    return (s * np.pi * np.arange(M)) ** 2


def _field(w2, d, p, z):
    M = w2.size
    q, v = z[:M], z[M:]
    return np.concatenate((v, p - d * v - w2 * q))


def _fund(w2, d, h):
    """The flow's Jacobian ``E(h)``, shape ``(2M, 2M)`` (block-diagonal per mode)."""
    return _matrix(_blocks(w2, d, h))


def _blocks(w2, d, h):
    """The flow's Jacobian over ``h`` as its per-mode 2x2 blocks ``(a, b, c, e)``, each ``(M,)``
    (:func:`~impactbar.dynamics.modal.fundamental`, with the rigid mode and underdamped flexible
    modes in direct closed form)."""
    h = float(h)
    lam2 = w2[1:] - 0.25 * d * d
    if lam2.size and not np.all(lam2 > 0.0):  # an overdamped mode: the general forms
        return fundamental(w2, d, np.full(w2.shape, h))
    b0 = -math.expm1(-d * h) / d if d else h
    a = np.empty(w2.size)
    b = np.empty(w2.size)
    c = np.empty(w2.size)
    e = np.empty(w2.size)
    a[0], b[0], c[0], e[0] = 1.0, b0, 0.0, math.exp(-d * h)
    if lam2.size:
        lam = np.sqrt(lam2)
        damp = math.exp(-0.5 * d * h)
        cs = damp * np.cos(lam * h)
        sn = damp * np.sin(lam * h) / lam
        a[1:] = cs + 0.5 * d * sn
        b[1:] = sn
        c[1:] = -w2[1:] * sn
        e[1:] = cs - 0.5 * d * sn
    return a, b, c, e


def _affine(w2, d, p, h, E):
    """The constant part ``g`` of the flow ``z(h) = E z0 + g`` under the force ``p`` (eq. 8)."""
    a, _, c, _ = E
    gq = np.empty(w2.size)
    gv = np.empty(w2.size)
    y = d * h
    if d == 0.0:
        b0, c0 = h, 0.5 * h * h
    else:
        b0 = -math.expm1(-y) / d
        c0 = h * h * (0.5 - y / 6.0 + y * y / 24.0 - y**3 / 120.0 + y**4 / 720.0) if abs(y) < 1e-2 \
            else (h - b0) / d
    gq[0], gv[0] = p * c0, p * b0
    if w2.size > 1:
        qs = p / w2[1:]  # static deflection of the flexible modes
        gq[1:] = qs * (1.0 - a[1:])
        gv[1:] = -c[1:] * qs
    return gq, gv


def _compose(E2, E1):
    a2, b2, c2, e2 = E2
    a1, b1, c1, e1 = E1
    return a2 * a1 + b2 * c1, a2 * b1 + b2 * e1, c2 * a1 + e2 * c1, c2 * b1 + e2 * e1


def _apply(E, g, z):
    M = g[0].size
    a, b, c, e = E
    q, v = z[:M], z[M:]
    return np.concatenate((a * q + b * v + g[0], c * q + e * v + g[1]))


def _matrix(E):
    a, b, c, e = E
    M = a.size
    out = np.zeros((2 * M, 2 * M))
    i = np.arange(M)
    out[i, i], out[i, M + i], out[M + i, i], out[M + i, M + i] = a, b, c, e
    return out


def _legs(model, drive, z0, durations):
    """States at the ends of the four flights from ``z0`` (after the impact)."""
    w2, d = _w2(model), model.d
    ps, pr = drive.level(STROKE), drive.level(RETURN)
    out = []
    z = z0
    for p, h in zip((ps, pr, pr, ps), durations, strict=True):
        if h:
            E = _blocks(w2, d, h)
            z = _apply(E, _affine(w2, d, p, h, E), z)
        out.append(z)
    return tuple(out)
