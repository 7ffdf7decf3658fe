"""The least and the greatest value of a circuit's state over its pieces of a flight or a blow: the
samples' and the stationary points' of the cubic Hermite interpolants between the integrator's steps
(theory §11, *Limits of this version*: the least pressure, which the cavitation check reads, and the
supply's, which the border collisions read)."""

from __future__ import annotations

import numpy as np

__all__ = ["HERMITE_REACH", "hermite_extremes"]


def _hermite_extremes(t, x, dxdt) -> tuple[float, float]:
    """The least and the greatest value of a sampled history ``x(t)`` with its rates ``dxdt``
    (shapes ``(T,)``): over the samples and the stationary points of its cubic Hermite interpolant
    (scipy's ``CubicHermiteSpline``)."""
    if t.size < 2:  # (a single sample)
        return float(x.min()), float(x.max())
    from scipy.interpolate import CubicHermiteSpline

    sp = CubicHermiteSpline(t, x, dxdt)
    roots = sp.derivative().roots(extrapolate=False)
    roots = roots[~np.isnan(roots)]  # (scipy's mark of a step where the derivative vanishes: a constant)
    vals = np.concatenate((x, sp(roots))) if roots.size else x
    return float(np.min(vals)), float(np.max(vals))


#: How far a cubic Hermite interpolant reaches past the greater (the lesser) of its ends' values over
#: a step ``h``, per unit of ``h`` times its ends' slopes away from them: the basis functions
#: ``s (1 - s)^2`` and ``s^2 (1 - s)`` of the slopes peak at ``4/27`` on ``[0, 1]``
HERMITE_REACH = 4.0 / 27.0
#: The bound's slack, relative to the step's values and rates: some thousand times the rounding of
#: the bound and of scipy's values at the stationary points
_REACH_SLACK = 1e-12


def hermite_extremes(histories, columns: int) -> tuple[np.ndarray, np.ndarray]:
    r"""The least and the greatest value of each of ``columns`` sampled histories over several
    pieces: those of :func:`_hermite_extremes` over each piece's samples and its interpolant's
    stationary points, the same numbers, its cubics solved only on the steps whose interpolant can
    pass the samples' extremes (theory §11, *Limits of this version*: the least pressure).

    On a step of length :math:`h` from the value :math:`a` to :math:`b` with the rates :math:`a'` and
    :math:`b'`, the interpolant :math:`a H_{00} + b H_{01} + h a' H_{10} + h b' H_{11}`
    (:math:`H_{00} + H_{01} = 1`, both in :math:`[0, 1]`, :math:`0 \le H_{10} = s (1 - s)^2 \le 4/27`,
    :math:`-4/27 \le H_{11} \le 0`) lies above :math:`\min(a, b) - \tfrac{4}{27} h (\max(-a', 0) +
    \max(b', 0))` and below the like bound: a step whose bound stays within the least (the greatest)
    sample holds no stationary value below (above) it, and is skipped.

    Parameters
    ----------
    histories : iterable of tuple
        Per piece ``(t, x, dxdt)``: its times, shape ``(S,)`` (increasing), and its values and their
        rates, shape ``(S, columns)``, in any consistent units.
    columns : int
        The histories per piece, at least 1.

    Returns
    -------
    lows, highs : numpy.ndarray, shape (columns,)
        In the values' units.

    Raises
    ------
    ValueError
        No piece.
    """
    histories = list(histories)
    if not histories:
        raise ValueError("hermite_extremes: histories must hold at least one piece; got none")
    # the pieces end to end: the steps between two pieces' samples are no steps
    ts, xs, rates = zip(*histories, strict=True)
    t = np.concatenate(ts)
    x, dxdt = np.concatenate(xs).reshape(t.size, columns), np.concatenate(rates).reshape(t.size, columns)
    starts = np.cumsum([0, *(s.size for s in ts)])
    lows, highs = x.min(axis=0), x.max(axis=0)
    h = np.diff(t)[:, None]
    a, b, da, db = x[:-1], x[1:], h * dxdt[:-1], h * dxdt[1:]
    slack = _REACH_SLACK * (np.abs(a) + np.abs(b) + np.abs(da) + np.abs(db))
    below = np.minimum(a, b) - HERMITE_REACH * (np.maximum(-da, 0.0) + np.maximum(db, 0.0)) - slack < lows
    above = np.maximum(a, b) + HERMITE_REACH * (np.maximum(da, 0.0) + np.maximum(-db, 0.0)) + slack > highs
    # (a constant step, as the valve's opening held at an end, is exactly its value)
    reach = (below | above) & ~((a == b) & (da == 0.0) & (db == 0.0))
    reach[starts[1:-1] - 1] = False
    for c in np.flatnonzero(reach.any(axis=0)):
        steps = np.flatnonzero(reach[:, c])
        piece = np.searchsorted(starts, steps, side="right") - 1
        for k in np.unique(piece):
            mine = steps[piece == k]
            # (from the first such step to the step after the last, within the piece: a stationary
            # point on a step's end is evaluated on the step after it, as on the whole piece)
            span = slice(mine.min(), min(mine.max() + 2, starts[k + 1] - 1) + 1)
            lo, hi = _hermite_extremes(t[span], x[span, c], dxdt[span, c])
            lows[c], highs[c] = min(lows[c], lo), max(highs[c], hi)
    return lows, highs
