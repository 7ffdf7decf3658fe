"""The tests' one independent reference for the modal equations: scipy ``solve_ivp`` (DOP853).

``q_n'' + d q_n' + w_n^2 q_n = p(t + shift)`` for every mode at once (paper eq. 6), integrated from
``t0`` to ``t1``. A piecewise-constant load is integrated piece by piece with its level fixed on
each piece (restarting at every jump), so no step straddles a jump and no jump time is rounded into
the wrong piece. Optionally stops at the first upward zero of ``c . q`` (an impact event).
"""

import math

import numpy as np
from scipy.integrate import solve_ivp

TWO_PI = 2.0 * math.pi


def _pieces(load, t0, t1, shift):
    """``[(a, b, level or None)]`` covering ``[t0, t1]``, cut at the load's jumps."""
    breaks = getattr(load, "breaks", None)
    if breaks is None:
        return [(t0, t1, None)]
    lo = math.floor((t0 + shift) / TWO_PI) - 1
    hi = math.ceil((t1 + shift) / TWO_PI) + 1
    jumps = sorted(b + TWO_PI * j - shift for j in range(lo, hi + 1) for b in breaks)
    nodes = [t0, *[x for x in jumps if t0 + 1e-12 < x < t1 - 1e-12], t1]
    return [(a, b, float(load(shift + 0.5 * (a + b)))) for a, b in zip(nodes[:-1], nodes[1:], strict=True)]


def solve_modal(w2, d, load, y0, t0, t1, *, shift=0.0, ts=(), end_weights=None, max_step=np.inf,
                rtol=1e-12, atol=1e-14):
    """Integrate the modal state ``y = (q, q')`` from ``t0`` to ``t1``.

    Returns ``(t, y, out, hit)``: the final time and state (the event's, if one was met), the states
    at the sorted times ``ts`` reached (shape (2M, len(ts)), NaN where not reached), and whether
    the integration stopped at an impact event (an upward zero of ``end_weights . q``).
    """
    w2 = np.asarray(w2, dtype=float)
    M = w2.size
    ts = np.asarray(ts, dtype=float)
    out = np.full((2 * M, ts.size), np.nan)
    y = np.asarray(y0, dtype=float).copy()
    events = None
    if end_weights is not None:
        c = np.asarray(end_weights, dtype=float)

        def hit(t, yy):
            return c @ yy[:M]

        hit.terminal = True
        hit.direction = 1
        events = hit
    t = t0
    for a, b, level in _pieces(load, t0, t1, shift):
        if level is None:
            def rhs(tt, yy):
                return np.concatenate((yy[M:], float(load(tt + shift)) - d * yy[M:] - w2 * yy[:M]))
        else:
            def rhs(tt, yy, lv=level):
                return np.concatenate((yy[M:], lv - d * yy[M:] - w2 * yy[:M]))
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=rtol, atol=atol, dense_output=True,
                        events=events, max_step=max_step)
        t_stop = sol.t[-1]
        for i, tt in enumerate(ts):
            if a <= tt <= t_stop:
                out[:, i] = sol.sol(tt)
        if sol.status == 1:
            return sol.t_events[0][-1], sol.y_events[0][-1].copy(), out, True
        t, y = b, sol.y[:, -1]
    return t, y, out, False


def central_difference_jacobian(f, z, h=1e-6, *, relative=False):
    """The tests' finite-difference reference for a Jacobian: column ``j`` is
    ``(f(z + h_j e_j) - f(z - h_j e_j)) / (2 h_j)``, with ``h_j = h`` or, with ``relative``,
    ``h_j = h max(1, |z_j|)``. ``f`` maps an array of shape ``(n,)`` to one of shape ``(k,)``."""
    z = np.asarray(z, dtype=float)
    cols = []
    for j in range(z.size):
        hj = h * max(1.0, abs(z[j])) if relative else h
        e = np.zeros(z.size)
        e[j] = hj
        cols.append((np.asarray(f(z + e)) - np.asarray(f(z - e))) / (2 * hj))
    return np.column_stack(cols)
