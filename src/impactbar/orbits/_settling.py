"""The limit of a map's iterates that converge along one real multiplier (theory §11): how the start
of Newton for a drive with state skips the slow supply mode of the oil circuit."""

from __future__ import annotations

import numpy as np

__all__ = ["dominant_limit"]

#: the dominant-mode extrapolation of :func:`dominant_limit` is taken where each of the last two
#: steps is a multiple ``rho`` of the one before to this fraction of its size, the two multiples
#: agree to ``DOMINANT_AGREE (1 - rho)`` (the map is linear enough there for the limit
#: ``1 / (1 - rho)`` to be right to about 10 %) and ``|rho| < DOMINANT_RHO``
DOMINANT_FIT = 0.02
DOMINANT_AGREE = 0.1
DOMINANT_RHO = 0.995


def _ratio(d1, d2):
    """``rho`` with ``d2 = rho d1`` in least squares, or None where that does not fit."""
    n1 = float(d1 @ d1)
    if not n1 > 0.0:
        return None
    rho = float(d1 @ d2) / n1
    if float(np.linalg.norm(d2 - rho * d1)) > DOMINANT_FIT * float(np.linalg.norm(d2)):
        return None
    return rho


def dominant_limit(y0, y1, y2, y3):
    """The limit of four iterates of a map that converge along one real multiplier (theory §11).

    Parameters
    ----------
    y0, y1, y2, y3 : numpy.ndarray, shape (n,)
        Consecutive iterates (the states after successive impacts; dimensionless).

    Returns
    -------
    numpy.ndarray, shape (n,), or None
        ``y3 + rho / (1 - rho) (y3 - y2)`` (Aitken's delta-squared in vector form, as in
        Steffensen's method) where each of the last two steps is one multiple ``rho`` of the step
        before (:data:`DOMINANT_FIT`, :data:`DOMINANT_AGREE`, ``|rho| <`` :data:`DOMINANT_RHO`);
        ``None`` where they do not fit one multiplier (a complex pair, two modes of one size, a
        map still far from linear).
    """
    d1, d2, d3 = y1 - y0, y2 - y1, y3 - y2
    r1, r2 = _ratio(d1, d2), _ratio(d2, d3)
    if r1 is None or r2 is None or not abs(r2) < DOMINANT_RHO or \
            abs(r2 - r1) > DOMINANT_AGREE * (1.0 - r2):
        return None
    return y3 + r2 / (1.0 - r2) * d3


def surfaces_ahead(drive, mode, y, M: int, tol: float = 0.0) -> bool:
    """Whether the state ``y = (q, q', z)`` (``M`` modes) lies on the near side of each of ``mode``'s
    surface events (``direction * value <= 0``: a crossing in the event's direction is still ahead),
    as a flight in ``mode`` needs: past one (the oil circuit's supply pressure above the relief
    pressure with the relief valve's flag closed) the flight never fires it, and its motion is not the
    drive's.

    Parameters
    ----------
    drive : Drive
    mode : object
        The drive's discrete state.
    y : numpy.ndarray, shape (2 M + k,)
    M : int
    tol : float, optional
        How far past a surface still counts as on it.

    Returns
    -------
    bool
    """
    from ..drives.base import SurfaceEvent

    q, v, z = y[:M], y[M:2 * M], y[2 * M:]
    return all(e.direction * e.value(0.0, q, v, z) <= tol for e in drive.events(mode)
               if isinstance(e, SurfaceEvent))
