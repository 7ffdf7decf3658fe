"""Admissibility of an orbit (theory §5): the struck end stays off the stop between impacts
and leaves it after the impact, decided with certified bounds, not by sampling."""

from __future__ import annotations

import math

import numpy as np

from ..dynamics.certified import enclose_zeros

TWO_PI = 2.0 * math.pi

#: the bounds of the certified search by the compiled kernel (``False``: the numpy reference path)
_COMPILED_BOUND = True


def _admissibility(model, load, phase, y_plus, v_imp, horizon=TWO_PI, at_rest=None):
    """Decide admissibility (theory §5) with certified bounds, over the flight
    ``[phase, phase + horizon]`` from ``y_plus``; ``at_rest`` (default ``R == 0``) says the end
    leaves the stop at rest, so that its departure is decided by its acceleration.

    The stationary points of ``g(t) = u(1, t)`` are the zeros of ``g' = c . q'``; they are enclosed
    with a bound of ``|g''|`` on each interval, built from each mode's energy about the static
    deflection under the local load: ``sqrt(v^2 + w^2 (q - P/w^2)^2)`` grows at most by the load's
    variation times the time elapsed (and by ``e^{d h}`` going backwards), and
    ``|q''| <= delta + (d + w) sqrt(E)``.

    ``duration`` is the flight time after the impact at load time ``phase`` (``2 pi`` for a
    one-impact orbit; the flights of a multi-impact motion differ).
    """
    M = model.n_modes + 1
    w2 = model.frequencies**2
    w = np.sqrt(w2)
    d, R = model.d, model.R
    c = model.end_weights
    absc = np.abs(c)
    psup = load.sup_abs
    q0, v0 = y_plus[:M], y_plus[M:]

    flow = load.flow(w2, d, phase, q0, v0)

    def states(t):
        return flow(phase + np.asarray(t, dtype=float))

    def g(t):
        return c @ states(t)[0]

    def gprime_and_bound(mid, half):
        q, v = states(mid)
        center, delta = load.variation(phase + mid, half)
        if _COMPILED_BOUND and q.ndim == 2:
            from ..dynamics._flowkernel import end_velocity_bound

            T = q.shape[1]
            return end_velocity_bound(c, absc, w2, float(d), float(psup), q, v,
                                      *(_column(x, T) for x in (center, delta, half)))
        grow = np.exp(d * np.asarray(half))
        bound = np.empty_like(q)
        flex = w2 > 0
        wc = w[flex, None]
        sqrtE = np.sqrt(v[flex] ** 2 + (wc * q[flex] - center / wc) ** 2)
        Eb = (sqrtE + delta * half) * grow
        bound[flex] = delta + (d + wc) * Eb
        vb = (np.abs(v[~flex]) + psup * half) * grow
        bound[~flex] = psup + d * vb
        return c @ v, absc @ bound

    scale = max(abs(v_imp), psup, 1e-300)
    if at_rest is None:
        at_rest = R == 0.0
    clusters = enclose_zeros(None, None, 0.0, horizon, n0=64, min_width=6e-3,
                             joint=gprime_and_bound, merge=False, atol=1e-13 * scale)
    # the departure: for R = 0 every velocity is zero just after impact, so t = 0 is a stationary
    # point of g; the end leaves the stop iff its acceleration there points away from the stop.
    if at_rest:
        acc0 = float(c @ (float(load(phase)) - d * v0 - w2 * q0))
        clusters = [cl for cl in clusters if cl[0] > 1e-6]
    # the stationary points that can carry the largest value are refined to full precision
    values, err_b = _stationary_values(states, gprime_and_bound, load, phase, c, w2, d, clusters,
                                       atol=1e-13 * scale, horizon=horizon)
    # rounding of the values themselves: relative to the problem's scale (linear in the load), so
    # that every verdict is invariant under load -> L load
    err = err_b + 1e-12 * (scale + max((abs(v) for v in values), default=0.0))
    clearance = max(values) if values else -math.inf
    tol = max(err, 1e-11 * scale)
    if not v_imp > 1e-12 * scale:
        status = "grazing" if abs(v_imp) <= 1e-12 * scale else "backward impact"
    elif at_rest and not acc0 < 0.0:
        status = "sticks"
    elif clearance > tol:
        status = "penetrates"
    elif clearance >= -tol:
        status = "grazing"
    else:
        status = "admissible"
    return status, clearance, err


def _column(x, T):
    """``x`` as a contiguous float array of shape ``(T,)`` (broadcast only where it must be)."""
    x = np.asarray(x, dtype=float)
    if x.shape == (T,) and x.flags.c_contiguous:
        return x
    return np.ascontiguousarray(np.broadcast_to(x, (T,)))


def _newton_stationary(states, load, phase, c, w2, d, lo, hi):
    """Vectorised Newton for zeros of ``g' = c . q'`` on intervals ``[lo, hi]``, with
    ``g'' = c . (p - d q' - w2 q)``. Returns the final points and which converged inside."""
    t = 0.5 * (lo + hi)
    ok = np.zeros(t.size, dtype=bool)
    for _ in range(8):
        q, v = states(t)
        g1 = c @ v
        g2 = c @ (load(phase + t)[None, :] - d * v - w2[:, None] * q)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(g2 != 0.0, g1 / g2, np.inf)
        step = np.nan_to_num(step, nan=np.inf)
        t_new = t - np.where(np.isfinite(step), step, 0.0)
        inside = (t_new >= lo) & (t_new <= hi) & np.isfinite(step)
        t = np.clip(t_new, lo, hi)
        ok = inside & (np.abs(step) < 1e-12)
        if np.all(ok | ~inside):
            break
    return t, ok


def _stationary_values(states, bound, load, phase, c, w2, d, intervals, rounds=8, atol=0.0,
                       horizon=TWO_PI):
    """Largest values of ``g = c . q`` at its stationary points, by branch and bound.

    All narrow intervals that may hold a zero of ``g'`` get a vectorised Newton step; converged
    points give stationary values. An interval where Newton fails is kept only if an upper bound of
    ``g`` on it, ``g(mid) + (|g'(mid)| + L h) h``, can still beat the best value found; those are
    split 64-fold by the certified exclusion and tried again. Where that cannot go on (a zero of
    ``g'`` of high order, whose enclosure does not shrink), the upper bounds themselves are used.

    Returns
    -------
    values : list of float
    err : float
        Bound on the error of the largest value (0 up to rounding when every stationary point
        that matters was located; otherwise the spread of the bounds on the unresolved intervals,
        whose upper end is reported).
    """
    def value_bounds(iv):
        """``g`` at the midpoints and its upper bound on each interval."""
        mid = 0.5 * (iv[:, 0] + iv[:, 1])
        half = 0.5 * (iv[:, 1] - iv[:, 0])
        gm = c @ states(mid)[0]
        g1, L2 = bound(mid, half)
        return gm, gm + (np.abs(g1) + L2 * half) * half

    values: list[float] = []
    err = 0.0
    best = -math.inf
    cur = np.array(intervals, dtype=float).reshape(-1, 2)
    for _ in range(rounds):
        if cur.size == 0:
            break
        lo, hi = cur[:, 0], cur[:, 1]
        t, ok = _newton_stationary(states, load, phase, c, w2, d, lo, hi)
        if np.any(ok):
            vals = c @ states(t[ok])[0]
            values.extend(float(x) for x in vals)
            best = max(best, float(np.max(vals)))
        rest = cur[~ok]
        if rest.size == 0:
            cur = rest
            break
        gm, upper = value_bounds(rest)
        keep = upper >= best
        rest, gm, upper = rest[keep], gm[keep], upper[keep]
        cur = rest
        if rest.size == 0:
            break
        width = float(np.max(rest[:, 1] - rest[:, 0]))
        try:
            cur = np.array(enclose_zeros(None, None, 0.0, horizon, n0=8, min_width=width / 64.0,
                                         joint=bound, intervals=rest, merge=False,
                                         max_intervals=20_000, atol=atol)).reshape(-1, 2)
        except RuntimeError:  # a zero of high order: the enclosure no longer shrinks
            lower = 2.0 * gm - upper  # gm - slack
            values.append(float(np.max(upper)))  # conservative: never below the true value
            err = max(err, float(np.max(upper) - np.min(lower)))
            cur = np.empty((0, 2))
            break
    if cur.size:  # rounds exhausted: bound what is left
        gm, upper = value_bounds(cur)
        if float(np.max(upper)) >= best:
            values.append(float(np.max(upper)))  # conservative: never below the true value
            err = max(err, float(np.max(upper) - np.min(2.0 * gm - upper)))
    return values, err
