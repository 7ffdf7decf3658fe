"""Certified zero search: every zero of a function with a known local Lipschitz bound is enclosed.

An interval ``[m - h, m + h]`` can hold a zero of ``f`` only if ``|f(m)| <= L h`` with ``L`` a bound
of ``|f'|`` on it; every other interval is excluded for certain. The survivors are bisected until
they are narrow, then grouped into clusters; each zero lies in a cluster. Callers refine inside the
clusters (Brent on a sign change, a bounded minimisation for a double zero at a fold or tangency).
A single harmonic needs no search: :func:`cosine_roots` gives its zeros in closed form.
"""

from __future__ import annotations

import math

import numpy as np

from .._shared.columns import IV_HI, IV_LO

TWO_PI = 2.0 * math.pi

__all__ = ["enclose_zeros", "zeros_in_clusters", "cosine_roots"]


def enclose_zeros(f, lipschitz, a: float, b: float, *, n0: int = 64, min_width: float = 1e-7,
                  max_intervals: int = 400_000, joint=None, intervals=None, merge: bool = True,
                  atol: float = 0.0, prune=None):
    """Clusters ``(lo, hi)`` that together contain every zero of ``f`` in ``[a, b]``.

    Parameters
    ----------
    f : callable
        ``f(t)`` for an array ``t``, vectorised.
    lipschitz : callable
        ``lipschitz(mid, half)`` -> array, an upper bound of ``|f'|`` on each ``[mid-half, mid+half]``.
    a, b : float
        The search interval.
    n0 : int
        Initial number of intervals.
    min_width : float
        Width at which bisection stops.
    max_intervals : int
        Guard against runaway subdivision (raises ``RuntimeError``).
    joint : callable, optional
        ``joint(mid, half) -> (f(mid), bound)`` in one call, when both share work; replaces ``f``
        and ``lipschitz`` in the search.
    intervals : array_like, shape (m, 2), optional
        Search these intervals (clusters from an earlier call) instead of ``[a, b]``.
    merge : bool
        Merge adjacent survivors into clusters (default); if false, return the narrow survivors.
    atol : float
        Rounding floor: an interval is kept while ``|f(mid)| <= L h + atol``, so that a zero whose
        computed value is a rounding error away from 0 is not excluded.
    prune : callable, optional
        ``prune(mids, half, f(mids), bound) -> mask``: at each level, only the intervals it keeps
        (and that may hold a zero) go on; for a branch and bound whose zeros are not all wanted.

    Returns
    -------
    list of tuple
        Disjoint ``(lo, hi)`` in increasing order.
    """
    if intervals is not None:  # continue from given clusters, each split into n0 pieces
        lo_hi = np.asarray(intervals, dtype=float).reshape(-1, 2)
        width = float(np.max(lo_hi[:, IV_HI] - lo_hi[:, IV_LO])) if lo_hi.size else 0.0
        if not width > 4.0 * np.spacing(max(abs(a), abs(b), 1.0)) * n0:
            return [tuple(x) for x in lo_hi.tolist()]  # too narrow to split in floating point
        half = 0.5 * width / n0
        mids = (lo_hi[:, :IV_HI] + half * (2.0 * np.arange(n0) + 1.0)).ravel()
        mids = mids[mids < np.repeat(lo_hi[:, IV_HI], n0) + half]
    else:
        half = 0.5 * (b - a) / n0
        mids = a + half * (2.0 * np.arange(n0) + 1.0)
    while True:
        if joint is not None:
            fm, lip = joint(mids, half)
        else:
            fm, lip = f(mids), lipschitz(mids, half)
        bound = lip * half
        keep = np.abs(fm) <= bound * (1.0 + 1e-9) + atol + 1e-300
        if prune is not None:
            keep &= prune(mids, half, fm, lip)
        mids = mids[keep]
        if mids.size == 0 or 2.0 * half <= min_width:
            break
        if mids.size > max_intervals:
            raise RuntimeError("zero search did not converge (Lipschitz bound too loose)")
        half *= 0.5
        mids = np.sort(np.concatenate((mids - half, mids + half)))
    if mids.size == 0:
        return []
    lo = np.maximum(mids - half, a)
    hi = np.minimum(mids + half, b)
    if not merge:
        return list(zip(lo.tolist(), hi.tolist(), strict=True))
    clusters = []
    start, end = lo[0], hi[0]
    for l_, h_ in zip(lo[1:], hi[1:], strict=True):
        if l_ <= end + 1e-12 * max(1.0, abs(end)):
            end = h_
        else:
            clusters.append((start, end))
            start, end = l_, h_
    clusters.append((start, end))
    return clusters


def zeros_in_clusters(f, clusters, *, atol: float):
    """Zeros of a scalar function inside each cluster from :func:`enclose_zeros`.

    A sign change is refined by Brent's method to full precision; a cluster without one is searched
    for an extremum of ``f`` that touches zero within ``atol`` (a double zero) or crosses it (two
    close zeros).

    Returns
    -------
    list of tuple
        ``(t, multiplicity)`` with multiplicity 1 or 2, in increasing ``t``.
    """
    from scipy.optimize import brentq, minimize_scalar  # here, not at the top: a slow import

    out = []

    def f1(t):
        return float(f(np.array([t]))[0])

    for lo, hi in clusters:
        flo, fhi = f1(lo), f1(hi)
        if flo == 0.0:
            out.append((lo, 1))
            continue
        if np.sign(flo) * np.sign(fhi) < 0.0:  # signs, not the product: it underflows for denormals
            out.append((brentq(f1, lo, hi, xtol=1e-15, rtol=8.9e-16, maxiter=200), 1))
            continue
        sgn = 1.0 if flo > 0 else -1.0
        res = minimize_scalar(lambda t, s=sgn: s * f1(t), bounds=(lo, hi), method="bounded",
                              options={"xatol": 1e-13})
        tm, fm = float(res.x), sgn * float(res.fun)
        if abs(fm) <= atol:
            out.append((tm, 2))
        elif np.sign(fm) * np.sign(flo) < 0.0:
            out.append((brentq(f1, lo, tm, xtol=1e-15, rtol=8.9e-16), 1))
            out.append((brentq(f1, tm, hi, xtol=1e-15, rtol=8.9e-16), 1))
    return out


def cosine_roots(A, theta, B, k, tol=1e-15):
    """The zeros of one harmonic in closed form, where no search is needed (the phase equations of a
    load with one harmonic, eq. 14 and theory §4b).

    The roots in ``[0, 2 pi)`` of ``A cos(k phase + theta) = B`` are ``k phase = -theta +-
    arccos(B / A) (mod 2 pi)``: ``2k`` of them, or ``k`` double ones at ``|B| = A``.

    Parameters
    ----------
    A : float
        Amplitude, ``> 0``.
    theta : float
        Phase offset (rad).
    B : float
        Right-hand side.
    k : int
        Order of the harmonic, ``>= 1``.
    tol : float
        Relative tolerance of ``|B| = A`` (a double root) and of ``|B| > A`` (no root).

    Returns
    -------
    list of (float, int)
        ``(phase, multiplicity)`` sorted by phase; empty when ``|B| > A (1 + tol)``.
    """
    ratio = B / A
    if abs(ratio) > 1.0 + tol:
        return []
    if abs(ratio) >= 1.0 - tol:
        base, mult = [math.acos(max(-1.0, min(1.0, ratio)))], 2
    else:
        a = math.acos(ratio)
        base, mult = [a, -a], 1
    out = []
    for b in base:
        for j in range(k):
            out.append(((b - theta + TWO_PI * j) / k) % TWO_PI)
    return [(t, mult) for t in sorted(out)]
