"""Closed-form motion of the modal oscillators between impacts (theory §2, paper eqs. 6, 8).

Every mode obeys ``q'' + d q' + w2 q = p(t)`` with ``w2 = (s n pi)^2`` (``w2 = 0`` for the rigid
mode). This module holds the load-independent pieces: the fundamental matrix of the homogeneous
oscillator and the integrals ``b``, ``c`` of the rigid mode. Plain floats and arrays only.
"""

from __future__ import annotations

import numpy as np

__all__ = ["fundamental", "b_integral", "c_integral", "step_constant"]


def _sinhc(x: np.ndarray) -> np.ndarray:
    """``sinh(x)/x`` with its limit 1 at 0."""
    x = np.asarray(x, dtype=float)
    small = np.abs(x) < 1e-4
    xs = np.where(small, 1.0, x)
    return np.where(small, 1.0 + x * x / 6.0, np.sinh(xs) / xs)


def fundamental(w2, d: float, tau):
    """Fundamental matrix ``Phi(tau)`` of ``q'' + d q' + w2 q = 0`` (homogeneous part of eq. 8).

    ``(q, q')(tau) = Phi(tau) (q, q')(0)`` for every damping regime (under-, critically and
    over-damped) and for the rigid mode ``w2 = 0``.

    Parameters
    ----------
    w2 : array_like, shape (M,) or broadcastable with ``tau``
        Squared undamped frequencies ``(s n pi)^2``, ``>= 0`` (dimensionless).
    d : float
        Damping, ``>= 0``.
    tau : array_like
        Elapsed times (dimensionless), broadcast against ``w2``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(phi11, phi12, phi21, phi22)``, each of the broadcast shape of ``w2`` and ``tau``.
    """
    w2 = np.asarray(w2, dtype=float)
    tau = np.asarray(tau, dtype=float)
    lam2 = w2 - 0.25 * d * d
    rigid = w2 == 0.0
    if np.all((lam2 > 0.0) | rigid):  # fast path: flexible modes underdamped (the rule)
        lam = np.sqrt(np.where(rigid, 1.0, lam2))
        x = lam * tau
        eC = np.cos(x)
        p12 = np.sin(x) / lam
        if d:
            e = np.exp(-0.5 * d * tau)
            eC = e * eC
            p12 = e * p12
        hd = 0.5 * d * p12
        out = [eC + hd, p12, -w2 * p12, eC - hd]
        if np.any(rigid):
            shape = np.broadcast_shapes(w2.shape, tau.shape)
            a11, a12, a21, a22 = (np.broadcast_to(o, shape) for o in out)
            out = [np.where(rigid, 1.0, a11), np.where(rigid, b_integral(d, tau), a12),
                   np.where(rigid, 0.0, a21), np.where(rigid, np.exp(-d * tau), a22)]
        return tuple(out)
    w2, tau = np.broadcast_arrays(w2, tau)
    rigid = w2 == 0.0
    lam2 = w2 - 0.25 * d * d
    lam = np.sqrt(np.abs(lam2))
    x = lam * tau
    under = lam2 >= 0.0
    e = np.exp(-0.5 * d * tau)
    eC = e * np.where(under, np.cos(x), 1.0)
    eS = e * tau * np.where(under, np.sinc(x / np.pi), 1.0)
    over = ~under
    if np.any(over):  # overdamped: e^{-d tau/2} cosh, sinh as decaying exponentials (no inf * 0)
        xo, to, lo = x[over], tau[over], lam[over]
        ep = 0.5 * np.exp((lo - 0.5 * d) * to)
        em = 0.5 * np.exp((-lo - 0.5 * d) * to)
        small = np.abs(xo) < 1e-4
        lo_safe = np.where(small, 1.0, lo)
        eC[over] = ep + em
        eS[over] = np.where(small, np.exp(-0.5 * d * to) * to * _sinhc(np.where(small, xo, 0.0)),
                            (ep - em) / lo_safe)
    phi11 = eC + 0.5 * d * eS
    phi12 = eS
    phi21 = -w2 * eS
    phi22 = eC - 0.5 * d * eS
    if np.any(rigid):  # exact forms for the rigid mode: no cosh/sinh cancellation
        phi11 = np.where(rigid, 1.0, phi11)
        phi12 = np.where(rigid, b_integral(d, tau), phi12)
        phi21 = np.where(rigid, 0.0, phi21)
        phi22 = np.where(rigid, np.exp(-d * tau), phi22)
    return phi11, phi12, phi21, phi22


def b_integral(d: float, tau):
    """``b(tau) = (1 - exp(-d tau)) / d = int_0^tau exp(-d t) dt`` (``tau`` at ``d = 0``)."""
    tau = np.asarray(tau, dtype=float)
    if d == 0.0:
        return tau.copy()
    y = d * tau
    # series where d tau is tiny (it may underflow to 0 for denormal d); the quotient is formed only
    # where it is not tiny, so a denormal d never meets a division that some numpy versions flag
    out = np.array(tau * (1.0 - 0.5 * y), dtype=float)
    big = np.abs(y) >= 1e-8
    if np.any(big):
        if out.ndim == 0:
            return np.asarray(-np.expm1(-y) / d)
        out[big] = -np.expm1(-y[big]) / d
    return out


def c_integral(d: float, tau):
    """``c(tau) = (tau - b(tau)) / d = int_0^tau b(t) dt`` (``tau^2/2`` at ``d = 0``), evaluated
    by its series where the difference would cancel."""
    tau = np.asarray(tau, dtype=float)
    if d == 0.0:
        return 0.5 * tau * tau
    y = d * tau
    small = np.abs(y) < 1e-2
    series = tau * tau * (0.5 - y / 6.0 + y * y / 24.0 - y**3 / 120.0 + y**4 / 720.0)
    out = series
    big = ~small
    if np.any(big):
        out = np.array(series, dtype=float)
        tb = tau[big] if tau.ndim else tau
        out[big] = (tb - (-np.expm1(-d * tb) / d)) / d
    return out


def step_constant(w2, d: float, level, q0, v0, tau):
    """Exact state after ``tau`` under a constant load ``level`` (one piece of a piecewise-constant
    load, e.g. the square wave of eq. 34).

    Parameters
    ----------
    w2 : array_like, shape (M,)
        Squared frequencies, ``>= 0``.
    d : float
        Damping.
    level : float or array_like
        The constant load on the piece, broadcast against ``tau``.
    q0, v0 : array_like, shape (M,)
        Displacement and velocity at the start of the piece.
    tau : array_like, shape (T,) or scalar
        Times since the start of the piece.

    Returns
    -------
    q, v : numpy.ndarray, shape (M, T) (or (M,) for scalar ``tau``)
    """
    w2 = np.asarray(w2, dtype=float)
    q0 = np.asarray(q0, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    if q0.ndim == 2:  # one start state per time column
        return _step_columns(w2, d, level, q0, v0, tau)
    scalar = np.ndim(tau) == 0
    tau = np.atleast_1d(np.asarray(tau, dtype=float))[None, :]
    level = np.atleast_1d(np.asarray(level, dtype=float))[None, :]
    w2c = w2[:, None]
    p11, p12, p21, p22 = fundamental(w2c, d, tau)
    rigid = w2c == 0.0
    qs = np.where(rigid, 0.0, level / np.where(rigid, 1.0, w2c))  # static deflection
    dq = q0[:, None] - qs
    q = p11 * dq + p12 * v0[:, None] + qs
    v = p21 * dq + p22 * v0[:, None]
    if np.any(rigid):
        q = np.where(rigid, q + level * c_integral(d, tau), q)
        v = np.where(rigid, v + level * b_integral(d, tau), v)
    if scalar:
        return q[:, 0], v[:, 0]
    return q, v


def _step_columns(w2, d, level, q0, v0, tau):
    """:func:`step_constant` with a start state and a level per column: ``q0, v0`` shape (M, T),
    ``level`` and ``tau`` shape (T,)."""
    tau = np.asarray(tau, dtype=float)[None, :]
    level = np.broadcast_to(np.asarray(level, dtype=float), tau.shape[1:])[None, :]
    w2c = w2[:, None]
    p11, p12, p21, p22 = fundamental(w2c, d, tau)
    rigid = w2c == 0.0
    qs = np.where(rigid, 0.0, level / np.where(rigid, 1.0, w2c))
    dq = q0 - qs
    q = p11 * dq + p12 * v0 + qs
    v = p21 * dq + p22 * v0
    if np.any(rigid):
        q = np.where(rigid, q + level * c_integral(d, tau), q)
        v = np.where(rigid, v + level * b_integral(d, tau), v)
    return q, v
