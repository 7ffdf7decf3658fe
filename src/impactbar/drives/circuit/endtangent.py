r"""The circuit's variational equations over a blow (theory §11, "The coupled blow"): the derivative
of its state along directions of the blow's data, beside the flight of :mod:`.endflight`.

Over a blow the circuit's state ``Y = (w, z)`` follows ``Y' = f(Y, a(t))`` (:mod:`._endgen`), the
wave ``a`` arriving at the driven end given by the law. A direction of the blow's data moves ``Y``
at the start by ``dY_0`` and the wave by ``da(t)``; the derivative follows the linear equations

.. math::

    dY' = J(t)\, dY + f_a(t)\, da(t), \qquad J = \partial f / \partial Y, \quad
    f_a = \partial f / \partial a

along the primal flight (its integrator's cubic Hermite steps), ``f`` affine in ``a``. An impulse of
``da`` (weight ``m``: a jump of ``a`` moved by the direction) is a jump ``f_a m`` of ``dY``. The
equations are stiff (the chambers' oil), so they are integrated by the three-stage Radau IIA
collocation (order 5, L-stable; Hairer & Wanner, *Solving ODEs II*, IV.5) on the primal's own steps
and the extra times given (the law's drive's steps, the impulses), each step one linear system of
``3 (1 + n_z)`` unknowns for all the directions at once, compiled; :math:`J` and :math:`f_a` from the
generated ``end_tangent_at``, on the primal's Hermite interpolant and the law's spline of ``a``.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ...dynamics.compiled import CACHE
from . import _endgen as EK

__all__ = ["EndTangent", "BEFORE", "AFTER"]

#: the sides of a time of the grid in :func:`radau_linear`'s values: as the step before ends, as the
#: step after starts (an impulse between them)
BEFORE, AFTER = 0, 1
#: where a step's matrices are taken, of its four points (its start, Radau's three nodes): the start,
#: the end (the last node)
AT_START, AT_END = 0, 3

_S6 = math.sqrt(6.0)
#: Radau IIA's nodes (three stages) and its matrix (Hairer & Wanner, Table IV.5.6)
RADAU_C = np.array([(4.0 - _S6) / 10.0, (4.0 + _S6) / 10.0, 1.0])
RADAU_A = np.array([[(88.0 - 7.0 * _S6) / 360.0, (296.0 - 169.0 * _S6) / 1800.0, (-2.0 + 3.0 * _S6) / 225.0],
                    [(296.0 + 169.0 * _S6) / 1800.0, (88.0 + 7.0 * _S6) / 360.0, (-2.0 - 3.0 * _S6) / 225.0],
                    [(16.0 - _S6) / 36.0, (16.0 + _S6) / 36.0, 1.0 / 9.0]])
#: where each step's matrices are taken: its start, Radau's nodes (its end the last)
_NODES = np.concatenate(([0.0], RADAU_C))


@nb.njit(cache=CACHE, nogil=True)
def radau_linear(h, J, fa, da, x0, kick, A):
    """The linear equations ``x' = J(t) x + f_a(t) da(t)`` for ``K`` directions over steps ``h`` by
    Radau IIA.

    Parameters
    ----------
    h : numpy.ndarray, shape (S,)
    J : numpy.ndarray, shape (S, 4, n, n)
        At each step's start and its three nodes.
    fa : numpy.ndarray, shape (S, 4, n)
    da : numpy.ndarray, shape (S, 4, K)
    x0 : numpy.ndarray, shape (K, n)
    kick : numpy.ndarray, shape (S + 1, K)
        Impulses of ``da`` at each step's start (``f_a`` there times it added to ``x``).
    A : numpy.ndarray, shape (3, 3)
        Radau's matrix.

    Returns
    -------
    X, R : numpy.ndarray, shape (S + 1, 2, K, n)
        ``x`` and its rate at each time, as the step before ends (0) and as the step after starts (1).
    """
    S, n, K = h.size, x0.shape[1], x0.shape[0]
    X = np.zeros((S + 1, 2, K, n))
    R = np.zeros((S + 1, 2, K, n))
    x = x0.copy()
    X[0, BEFORE] = x
    M = np.empty((3 * n, 3 * n))
    B = np.empty((3 * n, K))
    for s in range(S):
        for d in range(K):
            for i in range(n):
                x[d, i] += fa[s, AT_START, i] * kick[s, d]
        X[s, AFTER] = x
        R[s, AFTER] = x @ J[s, AT_START].T + np.outer(da[s, AT_START], fa[s, AT_START])
        for bi in range(3):
            for bj in range(3):
                c = h[s] * A[bi, bj]
                for i in range(n):
                    for j in range(n):
                        unit = 1.0 if (bi == bj and i == j) else 0.0
                        M[bi * n + i, bj * n + j] = unit - c * J[s, 1 + bj, i, j]
            for i in range(n):
                for d in range(K):
                    acc = x[d, i]
                    for bj in range(3):
                        acc += h[s] * A[bi, bj] * fa[s, 1 + bj, i] * da[s, 1 + bj, d]
                    B[bi * n + i, d] = acc
        Z = np.linalg.solve(M, B)
        for d in range(K):
            for i in range(n):
                x[d, i] = Z[2 * n + i, d]
        X[s + 1, BEFORE] = x
        R[s + 1, BEFORE] = x @ J[s, AT_END].T + np.outer(da[s, AT_END], fa[s, AT_END])
    if S:
        for d in range(K):
            for i in range(n):
                x[d, i] += fa[S - 1, AT_END, i] * kick[S, d]
    X[S, AFTER] = x
    R[S, AFTER] = R[S, BEFORE]
    return X, R


class EndTangent:
    """The variational equations of the circuit along a blow's flight (module docstring).

    Parameters
    ----------
    drive : HydraulicCircuitDrive
    pieces : list of EndPiece
        The primal flight's pieces (:func:`.endflight.circuit_end_flight`).
    events : list
        Its events inside the blow: none (a saltation each, not carried).
    mode : tuple
        The circuit's mode over the blow.
    breaks : numpy.ndarray, shape (m + 1,)
        The flight's breaks (model times).
    splines : list of tuple
        The primal wave ``a`` on each interval, a cubic spline ``(x, c, t0)`` (the coupled exact blow's
        callables' ``spline``: :mod:`._endcvode`).
    impedance : float
        ``Z > 0`` of the piston's driven end (model units).
    t0 : float
        The impact's time: the times below are from it (model units).
    one_mode : object
        The one-mode bar of the compiled kernels' parameters (``drive._rate_model(1)``: what
        :meth:`HydraulicCircuitDrive.end_tangent` passes).

    Raises
    ------
    ValueError
        Where the flight has events inside it (``events`` not empty).
    """

    def __init__(self, drive, pieces, events, mode, breaks, splines, impedance, t0, one_mode):
        from .endflight import _end_code

        if events:
            raise ValueError(f"events must be empty (no event inside the blow); got {len(events)}")
        self.code = _end_code(drive)
        self.par = drive._network_par(one_mode, mode)
        self.iz = 1.0 / float(impedance)
        self.t0 = float(t0)
        self.bt = np.asarray(breaks, dtype=float) - self.t0
        self.splines = splines
        self.pieces = [p for p in pieces if p.t.size >= 2]
        self.starts = np.array([p.t0 for p in self.pieces]) - self.t0
        self.steps = np.unique(np.concatenate([p.t - self.t0 for p in self.pieces]))
        L = drive.layout
        self.n = 1 + L.n_states
        self.front, self.rear = 1 + L["front"], 1 + L["rear"]
        self.alpha = drive.chambers.area_ratio

    def grid(self, extra):
        """The steps: the primal's and the times ``extra`` (from the impact) inside the flight."""
        lo, hi = float(self.steps.min()), float(self.steps.max())
        extra = np.asarray(extra, dtype=float)
        return np.union1d(self.steps, extra[(extra > lo) & (extra < hi)])

    def interval(self, tau):
        """The breaks' interval of each time (from the impact) ``tau``."""
        return np.clip(np.searchsorted(self.bt, tau, side="right") - 1, 0, self.bt.size - 2)

    def solve(self, grid, x0, da, kicks):
        """The derivatives along ``K`` directions over ``grid``.

        Parameters
        ----------
        grid : numpy.ndarray, shape (S + 1,)
            Times from the impact (:meth:`grid`).
        x0 : numpy.ndarray, shape (K, 1 + n_z)
            ``dY`` at the start (``dw``, ``dz``).
        da : list of callables
            Each interval's ``da``: a function of times from the impact returning shape ``(K, T)``.
        kicks : numpy.ndarray, shape (S + 1, K)
            The impulses of ``da`` at the grid's times.

        Returns
        -------
        X, R : numpy.ndarray, shape (S + 1, 2, K, 1 + n_z)
            ``dY`` and its rate at the grid's times, as the step before ends and as the step after
            starts (:func:`radau_linear`).
        """
        h = np.diff(grid)
        S = h.size
        pts = grid[:-1, None] + h[:, None] * _NODES[None, :]  # (S, 4)
        pts[:, AT_END] = grid[1:]
        mid = 0.5 * (grid[:-1] + grid[1:])
        flat = pts.ravel()
        Y = np.empty((flat.size, int(self.code.NE)))
        last = len(self.pieces) - 1
        piece = np.repeat(np.clip(np.searchsorted(self.starts, mid, side="right") - 1, 0, last), 4)
        for j in np.unique(piece):
            sel = piece == j
            Y[sel] = self.pieces[j]._at(self.t0 + flat[sel]).T
        k = np.repeat(self.interval(mid), 4)
        ext = np.zeros((flat.size, EK.EXT_SIZE))
        ext[:, EK.EXT_IZ] = self.iz
        K = x0.shape[0]
        dav = np.empty((flat.size, K))
        for j in np.unique(k):
            sel = k == j
            ext[sel, EK.EXT_A] = _spline_values(self.splines[j], self.t0 + flat[sel])
            dav[sel] = da[j](flat[sel]).T
        J = np.empty((flat.size, self.n, self.n))
        fa = np.empty((flat.size, self.n))
        self.code.end_tangent_at(Y, self.par, ext, J, fa)
        return radau_linear(h, J.reshape(S, 4, self.n, self.n), fa.reshape(S, 4, self.n),
                            dav.reshape(S, 4, K), np.ascontiguousarray(x0, dtype=float), kicks, RADAU_A)

    def start(self, dw, dz):
        """``dY`` at the start from the driven end's ``dw`` (shape ``(K,)``) and the circuit's ``dz``
        (shape ``(K, n_z)``), shape ``(K, 1 + n_z)``."""
        x0 = np.empty((dz.shape[0], self.n))
        x0[:, EK.Y_W] = dw
        x0[:, EK.Y_CIRCUIT:] = dz
        return x0

    @staticmethod
    def state_after(X):
        """The circuit's ``dz`` at the grid's end (after an impulse there), shape ``(K, n_z)``."""
        return X[-1, AFTER, :, EK.Y_CIRCUIT:]

    def force(self, X):
        """The force's derivative ``dp_r - alpha dp_f`` of ``dY`` (any leading shape)."""
        return X[..., self.rear] - self.alpha * X[..., self.front]

    def force_ends(self, grid, X, R, a, b):
        """The force's derivative and its rate at the times ``a`` (as the step after starts) and ``b``
        (as the step before ends), each a time of ``grid`` (or its nearest end), shapes ``(m, K)``:
        a piece ``[a, b]``'s ends from its own side."""
        last = grid.size - 1
        ia = np.clip(np.searchsorted(grid, a), 0, last)
        ib = np.clip(np.searchsorted(grid, b), 0, last)
        P, Q = self.force(X), self.force(R)
        return P[ia, AFTER], Q[ia, AFTER], P[ib, BEFORE], Q[ib, BEFORE]


def _spline_values(spline, t):
    """The spline ``(x, c, t0)`` of a coupled exact blow's wave at the model times ``t`` (its
    callable's arithmetic, :func:`._endcvode.spline_at`, on arrays)."""
    x, c, t0 = spline
    tt = np.asarray(t, dtype=float) - t0
    i = np.clip(np.searchsorted(x, tt, side="right") - 1, 0, x.size - 2)
    s = tt - x[i]
    s2 = s * s
    return ((c[3, i] + c[2, i] * s) + c[1, i] * s2) + c[0, i] * (s2 * s)
