"""The one view of a load that compiled code reads (theory §2, paper eq. 7).

Every compiled kernel (:mod:`impactbar.dynamics._event_loop`, ``_load_flow``, ``_separation``,
:mod:`impactbar.orbits._admissibility_search`) gets a load as one :class:`LoadKernelView`, built once by the
frozen load itself (its abilities' ``kernel``). The dtypes of its fields never change, so
numba compiles each kernel once for every load of both kinds.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["LoadKernelView", "ModalBasisView", "FOURIER", "PIECEWISE"]

#: ``kind`` of a load of finitely many harmonics (eq. 7)
FOURIER = 0
#: ``kind`` of a piecewise-constant load (eq. 34)
PIECEWISE = 1


class LoadKernelView(NamedTuple):
    """A load as the compiled kernels read it: plain scalars and contiguous float arrays.

    Fields that do not apply to the load's kind hold zeros (``ks, pr, pim`` of length 0 for a
    piecewise-constant load; ``breaks, levels`` of length 1 for a Fourier load), so that the
    argument has one numba type for both kinds.

    Attributes
    ----------
    kind : int
        :data:`FOURIER` (0) or :data:`PIECEWISE` (1).
    p0 : float
        Mean load (dimensionless, eq. 2).
    ks : numpy.ndarray of float, shape (K,)
        Orders ``k`` of the non-zero harmonics (kind 0).
    pr, pim : numpy.ndarray of float, shape (K,)
        Real and imaginary parts of the harmonics ``p_k`` (eq. 7).
    breaks, levels : numpy.ndarray of float, shape (J,)
        Start times of the pieces in ``[0, 2 pi)`` and the load on each (kind 1).
    psup : float
        ``sup |p(t)|``.
    p1, p2, p3 : float
        ``sum k^j |p_k|`` for ``j = 1, 2, 3``: bounds of ``|p'|, |p''|, |p'''|`` (0 for kind 1).
    posc : float
        ``sup |p(t) - p0|``.
    spread : float
        ``max p - min p`` of a piecewise-constant load (its largest jump; 0 for kind 0).
    """

    kind: int
    p0: float
    ks: np.ndarray
    pr: np.ndarray
    pim: np.ndarray
    breaks: np.ndarray
    levels: np.ndarray
    psup: float
    p1: float
    p2: float
    p3: float
    posc: float
    spread: float

    @classmethod
    def fourier(cls, p0: float, ks, pk) -> LoadKernelView:
        """The view of ``p0 + Re sum p_k exp(i k t)`` (orders ``ks``, complex ``pk``)."""
        ks = np.array(ks, dtype=float)
        pk = np.asarray(pk, dtype=complex)
        if ks.size == 1:  # one harmonic (the pneumatic load, eq. 33): the sums below of one term
            (k,), (p,) = ks.tolist(), pk.tolist()
            a1 = float(np.abs(p))
            return cls(0, float(p0), ks, np.array([p.real]), np.array([p.imag]), np.zeros(1), np.zeros(1),
                       abs(float(p0)) + a1, k * a1, k * k * a1, k**3 * a1, a1, 0.0)
        a = np.abs(pk)
        # private writable copies: a read-only array would be another numba type (and compilation)
        return cls(0, float(p0), ks, np.array(pk.real, dtype=float), np.array(pk.imag, dtype=float),
                   np.zeros(1), np.zeros(1),
                   abs(float(p0)) + float(np.sum(a)), float(np.sum(ks * a)), float(np.sum(ks**2 * a)),
                   float(np.sum(ks**3 * a)), float(np.sum(a)), 0.0)

    @classmethod
    def piecewise(cls, p0: float, breaks, levels) -> LoadKernelView:
        """The view of a load equal to ``levels[j]`` from ``breaks[j]`` to the next break."""
        lv = np.array(levels, dtype=float)
        return cls(1, float(p0), np.zeros(0), np.zeros(0), np.zeros(0), np.array(breaks, dtype=float),
                   lv, float(np.max(np.abs(lv))), 0.0, 0.0, 0.0, float(np.max(np.abs(lv - p0))),
                   float(np.max(lv) - np.min(lv)))


class ModalBasisView(NamedTuple):
    """A modal basis under one load as the compiled kernels read it (theory §2, eq. 8).

    Attributes
    ----------
    w2 : numpy.ndarray of float, shape (M,)
        Squared frequencies (0 for the rigid mode).
    d : float
        Damping.
    hpr, hpi : numpy.ndarray of float, shape (M, K)
        Real and imaginary parts of ``H_nk p_k``, the periodic particular response (eq. 8).
    vpb, apb, jpb : numpy.ndarray of float, shape (M,)
        ``sum_k k^j |H_nk p_k|`` for ``j = 1, 2, 3``: bounds of the particular velocity,
        acceleration and jerk of each mode.
    """

    w2: np.ndarray
    d: float
    hpr: np.ndarray
    hpi: np.ndarray
    vpb: np.ndarray
    apb: np.ndarray
    jpb: np.ndarray

    @classmethod
    def unforced(cls, w2, d: float) -> ModalBasisView:
        """A basis without a harmonic response (all a piecewise-constant load needs), shape
        ``(M, 0)`` for ``hpr, hpi``."""
        w2 = np.array(w2, dtype=float)
        M = w2.size
        empty = np.zeros((M, 0))
        return cls(w2, float(d), empty, empty.copy(), np.zeros(M), np.zeros(M), np.zeros(M))
