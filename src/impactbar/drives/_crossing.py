"""Closed forms of the rigid coordinate under a constant force, compiled (theory §10).

Between events a drive whose force is piecewise constant (a :class:`~impactbar.Drive` without state
of its own, such as the valve of :class:`~impactbar.PositionSwitchedDrive`) pushes the bar with a
constant ``p``. The rigid coordinate then obeys ``q_0'' + d q_0' = p`` alone (the flexible modes do
not enter it), so the gap ``y = -q_0`` and its rate are known in closed form, the rate is monotone,
and the first crossing of a level by the gap or by its rate is found without a search that could
miss one: :func:`first_rising_crossing`, :func:`first_rate_crossing`. The drives' event times
(:meth:`impactbar.drives.DriveEvent.first_time`) and the valve's compiled loop call these.
"""

from __future__ import annotations

import math

import numba

from ..dynamics.compiled import CACHE

__all__ = ["gap", "rate_zero", "first_rising_crossing", "first_rate_crossing", "rigid_flight"]


@numba.njit(cache=CACHE, nogil=True)
def gap(d, y0, w0, a, t):
    """Gap and its rate after ``t`` under ``y'' + d y' = a`` from ``(y0, w0)`` (closed form)."""
    if d == 0.0:
        return y0 + t * (w0 + 0.5 * a * t), w0 + a * t
    e = math.exp(-d * t)
    b = -math.expm1(-d * t) / d  # int_0^t e^{-d s} ds
    y = d * t
    c = t * t * (0.5 - y / 6.0 + y * y / 24.0 - y**3 / 120.0) if abs(y) < 1e-3 else (t - b) / d
    return y0 + w0 * b + a * c, w0 * e + a * b


@numba.njit(cache=CACHE, nogil=True)
def rate_zero(d, w0, a):
    """The time ``y' = 0`` under ``y'' + d y' = a`` from the rate ``w0`` (``inf`` if never)."""
    if d == 0.0:
        t = -w0 / a if a != 0.0 else math.inf
        return t if t > 0.0 else math.inf
    # w0 e^{-dt} + (a/d)(1 - e^{-dt}) = 0  ->  e^{-dt} = (a/d) / (a/d - w0)
    r = a / d
    den = r - w0
    if den == 0.0:
        return math.inf
    x = r / den
    if not 0.0 < x < 1.0:
        return math.inf
    return -math.log(x) / d


@numba.njit(cache=CACHE, nogil=True)
def first_rising_crossing(d, y0, w0, a, level):
    """First ``t > 0`` at which the gap ``y`` rises through ``level`` under ``y'' + d y' = a``.

    The rate ``y' = w0 e^{-d t} + a b(t)`` is monotone in ``t`` (its derivative ``(a - d w0)
    e^{-d t}`` keeps its sign), so ``y`` has at most one turning point and at most one rising
    crossing of any level: no crossing can be missed. It is bracketed on the rising piece and
    refined to rounding by Newton's method, which converges monotonically there (``y`` is convex
    or concave throughout) (theory §10).

    Parameters
    ----------
    d : float
        Damping, ``>= 0``.
    y0, w0 : float
        Gap and its rate at ``t = 0``.
    a : float
        Constant acceleration of the gap (``-p``).
    level : float
        The switch position.

    Returns
    -------
    float
        The crossing time, ``inf`` if there is none.
    """
    if d == 0.0 and a == 0.0:
        if w0 <= 0.0 or y0 >= level:
            return math.inf
        return (level - y0) / w0
    # the rising piece [t_lo, t_hi] of y (t_hi may be infinite)
    slope = a - d * w0  # sign of y''
    if w0 > 0.0:
        t_lo = 0.0
        if slope >= 0.0:
            t_hi = math.inf
        else:  # y' falls to 0 at t* (if ever)
            t_hi = rate_zero(d, w0, a)
    else:
        if slope <= 0.0:
            return math.inf  # y' <= 0 for ever
        t_lo = rate_zero(d, w0, a) if w0 < 0.0 else 0.0
        if not math.isfinite(t_lo):
            return math.inf
        t_hi = math.inf
    y_lo, _ = gap(d, y0, w0, a, t_lo)
    if y_lo >= level:  # starts at or above the level moving up: no rising crossing ahead
        return math.inf
    if not math.isfinite(t_hi):
        h = max(1.0, t_lo)
        t_hi = t_lo + h
        y_hi, _ = gap(d, y0, w0, a, t_hi)
        while y_hi < level:
            h *= 2.0
            t_hi = t_lo + h
            if h > 1e300:  # the gap tends to a finite limit below the level
                return math.inf
            y_hi, _ = gap(d, y0, w0, a, t_hi)
    else:
        y_hi, _ = gap(d, y0, w0, a, t_hi)
        if y_hi < level:
            return math.inf
    if d == 0.0:  # the rising root of a t^2/2 + w0 t + y0 - level = 0, in its stable form
        r = math.sqrt(max(w0 * w0 + 2.0 * a * (level - y0), 0.0))  # the rate at the crossing
        return 2.0 * (level - y0) / (w0 + r) if w0 >= 0.0 else (r - w0) / a
    # y'' = (a - d w0) e^{-d t} keeps its sign: y is convex or concave. Newton from the end of the
    # bracket on the level's far side converges monotonically to the one root (no overshoot): from
    # the upper end where y is convex, from the lower end where it is concave.
    t = t_hi if slope > 0.0 else t_lo
    sign = 0.0
    for _ in range(200):
        y, w = gap(d, y0, w0, a, t)
        if w <= 0.0:
            break
        step = (y - level) / w
        if step == 0.0 or step * sign < 0.0:  # an overshoot can only be rounding: done
            break
        sign = step
        t_new = min(max(t - step, t_lo), t_hi)
        if t_new == t:
            break
        t = t_new
    return t


@numba.njit(cache=CACHE, nogil=True)
def rigid_flight(d, q, v, level, h):
    """The rigid mode ``q_0'' + d q_0' = level`` after ``h`` from ``(q, v)``: ``(q_0, q_0')``."""
    e = -math.expm1(-d * h) / d if d else h
    c = (h - e) / d if d else 0.5 * h * h
    return q + v * e + level * c, v * (1.0 - d * e) + level * e


@numba.njit(cache=CACHE, nogil=True)
def first_rate_crossing(d, w0, a, level):
    """First ``t > 0`` at which the rate ``w = y'`` of ``y'' + d y' = a`` crosses ``level`` (either way),
    ``inf`` if never.

    ``w(t) = a/d + (w0 - a/d) e^{-d t}`` (``w0 + a t`` without damping) is monotone, so it crosses a
    level at most once, in the direction of ``a - d w0`` (theory §10).
    """
    if w0 == level:
        return math.inf
    if d == 0.0:
        if a == 0.0:
            return math.inf
        t = (level - w0) / a
        return t if t > 0.0 else math.inf
    r = a / d  # the rate's limit
    den = w0 - r
    if den == 0.0:
        return math.inf
    x = (level - r) / den  # e^{-d t}
    if not 0.0 < x < 1.0:
        return math.inf
    return -math.log(x) / d
