"""Hand-written peers the benchmarks time impactbar against.

:func:`minimal_loop_rigid` is the compiled minimal loop a user would write for a short run of the
rigid bar under ``p(t) = p0 + pk cos t``: the flight in closed form, the impact found by steps of
0.1 and bisection to the last bit, ``v -> -R v``, the impacts returned in fresh arrays. It checks
nothing, certifies no event (a grazing impact inside a step is missed) and logs no motion: the
floor of a 1-impact ``simulate`` call's cost.
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True)
def _flight(x0, v0, t0, t, p0, pk, d):
    """Position and velocity at ``t`` of ``x'' + d x' = p0 + pk cos t`` from ``(t0, x0, v0)``."""
    a = -pk / (1.0 + d * d)  # particular response a cos t + b sin t (+ p0 t / d)
    b = d * pk / (1.0 + d * d)
    c2 = (p0 / d - a * math.sin(t0) + b * math.cos(t0) - v0) / d
    c1 = x0 - c2 - a * math.cos(t0) - b * math.sin(t0)
    e = math.exp(-d * (t - t0))
    x = c1 + c2 * e + p0 / d * (t - t0) + a * math.cos(t) + b * math.sin(t)
    v = -d * c2 * e + p0 / d - a * math.sin(t) + b * math.cos(t)
    return x, v


@numba.njit(cache=True)
def _loop(x, v, t, t_end, max_imp, p0, pk, d, R, out_t, out_v):
    n = 0
    h = 0.1
    while n < max_imp and t < t_end:
        a = t
        b = min(t + h, t_end)
        xb, _ = _flight(x, v, t, b, p0, pk, d)
        while xb < 0.0 and b < t_end:  # step until the end crosses the stop
            a = b
            b = min(b + h, t_end)
            xb, _ = _flight(x, v, t, b, p0, pk, d)
        if xb < 0.0:
            break
        for _ in range(200):  # bisection to the last bit
            m = 0.5 * (a + b)
            if m <= a or m >= b:
                break
            xm, _ = _flight(x, v, t, m, p0, pk, d)
            if xm < 0.0:
                a = m
            else:
                b = m
        _, vb = _flight(x, v, t, b, p0, pk, d)
        out_t[n] = b
        out_v[n] = vb
        n += 1
        x, v, t = 0.0, -R * vb, b
    return n


def minimal_loop_rigid(x0, v0, t0, t_end, max_imp, p0, pk, d, R):
    """Impact times and arrival velocities of the rigid bar from ``(t0, x0, v0)``, at most
    ``max_imp`` of them before ``t_end``."""
    out_t = np.empty(max_imp)
    out_v = np.empty(max_imp)
    n = _loop(float(x0), float(v0), float(t0), float(t_end), int(max_imp), float(p0), float(pk), float(d),
              float(R), out_t, out_v)
    return out_t[:n], out_v[:n]
