"""The bit's equation on a piece (theory §4d): ``y' = r y + g`` solved exactly for a block forcing
``g`` (:func:`blk_ode1`), by back-substitution where an exponent is far from ``r`` and by the Taylor
series of ``e^{delta tau}`` where it is near and the series fits (:func:`series_fits`), the series
folded into the slot of ``r`` (:func:`blk_fold`); :mod:`impactbar.laws.rodrock._exactpieces`
describes the blocks."""

from __future__ import annotations

import math

import numba
import numpy as np

from ..._shared.literals import plain_literals
from ..._shared.twinops import quot
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from ._exactpieces import DC, EPS, NEAR, SERIES_MAX, SERIES_TOL, blk_clear, blk_trim, cabs


@numba.njit(cache=CACHE, nogil=True)
def _ode1_series(Y, NY, row, G, e, n, delta, grows, ex, L):
    """:func:`blk_ode1`'s series for the forcing ``G[e]`` (``n`` coefficients), added into slot
    ``row`` of ``Y`` (``NY[row]`` raised to its length) until its terms fall below ``SERIES_TOL`` of
    the largest on ``[0, L]``: with ``grows``, the integral of ``e^{-delta s} P(s)`` (``ex`` (DC,)
    scratch for the exponential's coefficients), else the Taylor recursion of ``(D - delta) Q = P``.
    Returns whether the degree limit was reached."""
    status = False
    q = 0.0j
    dp = -delta
    if grows:
        ex[0] = 1.0  # dp^m / m!, each as the series reaches it
    top = 0.0
    Lp = 1.0
    last = 0
    for kk in range(DC - 1):
        if grows:
            if kk > 0:
                ex[kk] = quot(ex[kk - 1] * dp, kk)
            R = 0.0j  # the coefficient of s^kk in e^{dp s} P(s)
            for i in range(min(kk, n - 1) + 1):
                R += G[e, i] * ex[kk - i]
            q = quot(R, kk + 1)
        else:
            P = G[e, kk] if kk < n else 0.0j
            q = quot(P + delta * q, kk + 1)
        Y[row, kk + 1] += q
        last = kk + 1
        Lp *= L
        mag = cabs(q) * Lp
        if mag > top:
            top = mag
        if kk + 1 >= n and (q == 0.0 or mag <= SERIES_TOL * top):
            break
        if kk + 2 >= DC:
            status = True
    if last + 1 > NY[row]:
        NY[row] = last + 1
    return status


@numba.njit(cache=CACHE, nogil=True)
def series_fits(delta, L):
    """Whether the exponents ``delta`` apart are solved (:func:`blk_ode1`) and folded
    (:func:`blk_fold`) on ``[0, L]`` as one, by a series: they are within ``NEAR / L`` and the series
    of ``e^{delta tau}``, cut below ``SERIES_TOL`` on ``[0, L]`` as the solver cuts it, keeps its
    coefficients ``|delta|^k / k!`` below ``SERIES_MAX``. Past it (a stiff exponent ``delta`` on a
    piece of a few ``1 / |delta|``: a stiff rock's unloading spike, ``k_u / Z = 2e12``, its series
    reached 7e292 at degree 26 and its derivatives overflowed) the exponents are apart on ``[0, L]``
    in the only sense that matters: the particular solution's back-substitution divides by
    ``|delta|``, each step shrinking the coefficients, so no large terms cancel."""
    ad = abs(delta)
    x = ad * L
    if x > NEAR:
        return False
    lim = math.log(SERIES_MAX)
    if ad <= lim:  # (|delta|^k / k! <= e^|delta| <= SERIES_MAX: no term-by-term check)
        return True
    lg = math.log(ad)
    term = 1.0  # x^k / k!
    top = 1.0
    lf = 0.0  # log k!
    for kk in range(1, DC):
        lf += math.log(kk)
        if kk * lg - lf > lim:
            return False
        term *= x / kk
        top = max(top, term)
        if term <= SERIES_TOL * top:
            return True
    return True


@numba.njit(cache=CACHE, nogil=True)
def blk_ode1(Y, NY, G, NG, lam, rc, r, y0, L):
    """``Y`` = the solution of ``y' - r y = g`` with ``y(0) = y0`` on ``[0, L]`` (``G`` the block of
    ``g``; ``r = lam[rc]``), without cancellation: a forcing exponent ``lam_e`` within ``NEAR / L`` of
    ``r`` by the Taylor recursion of the initial-value problem, around the exponent of the two with
    the smaller real part so that the series grows rather than alternates (``(D - delta) Q = P``,
    ``Q(0) = 0``, ``delta = r - lam_e``, in slot ``e``, or ``e^{r tau}`` times the integral of the
    series of ``e^{(lam_e - r) s} P(s)``, in slot ``rc``; for ``delta = 0`` exact, one degree more;
    else a series cut below ``SERIES_TOL`` on ``[0, L]``), a farther one by back-substitution of
    ``(D + lam_e - r) Q = P`` (contracting there; also a near one whose series would not fit,
    :func:`series_fits`); the homogeneous ``C e^{r tau}`` exact. Returns
    ``(status, series)``: status 1 when the degree limit was reached; ``series`` whether a series
    was cut (the piece then holds only on ``[0, L]``)."""
    blk_clear(Y, NY)
    status = 0
    series = False
    near = False  # a forcing exponent near r: a series, or a fold (their coefficients in ex)
    for e in range(NG.size):
        if NG[e] > 0 and e != rc and series_fits(r - lam[e], L):
            near = True
    ex = np.empty(DC if near else 1, dtype=np.complex128)
    for e in range(NG.size):
        n = NG[e]
        if n == 0:
            continue
        delta = r - lam[e]
        if e != rc and series_fits(delta, L) and lam[e].real > r.real:
            # e^{r tau} int_0^tau e^{(lam_e - r) s} P(s) ds: the series of e^{(lam_e - r) s} grows
            series = True
            if _ode1_series(Y, NY, rc, G, e, n, delta, True, ex, L):
                status = 1
        elif e == rc or series_fits(delta, L):
            if e != rc:
                series = True
            if _ode1_series(Y, NY, e, G, e, n, delta, False, ex, L):
                status = 1
        else:
            a0 = lam[e] - r
            qn = 0.0j
            for jj in range(n - 1, -1, -1):
                qn = quot(G[e, jj] - (jj + 1) * qn, a0)
                Y[e, jj] += qn
            if n > NY[e]:
                NY[e] = n
    at0 = 0.0j
    mag0 = abs(y0)
    for e in range(NY.size):
        if NY[e] > 0:
            at0 += Y[e, 0]
            mag0 += abs(Y[e, 0])
    C = y0 - at0
    if abs(C) <= 4.0 * EPS * mag0:  # rounding: the particular solution starts at y0
        C = 0.0j
    if C != 0.0:
        Y[rc, 0] += C
        if NY[rc] == 0:
            NY[rc] = 1
    blk_trim(Y, NY)
    # the exponents near r folded into the one of them with the smallest real part: one polynomial,
    # whose coefficients cancel where its value does
    c = rc
    for e in range(NY.size):
        if NY[e] > 0 and series_fits(lam[e] - r, L) and lam[e].real < lam[c].real:
            c = e
    for e in range(NY.size):
        if e != c and NY[e] > 0 and series_fits(lam[e] - r, L):
            if blk_fold(Y, NY, e, c, lam, L, ex) != 0:
                status = 1
            series = True
    blk_trim(Y, NY)
    return status, series


@numba.njit(cache=CACHE, nogil=True)
def blk_fold(Y, NY, e, c, lam, L, ex):
    """Move the terms of exponent ``e`` into exponent ``c`` (``Re lam_c <= Re lam_e``): ``P(tau)
    e^{lam_e tau} = e^{lam_c tau} P(tau) e^{d tau}``, ``d = lam_e - lam_c``, the series cut below
    ``SERIES_TOL`` on ``[0, L]`` (``ex``: scratch of ``DC`` for ``d^m / m!``). Returns 1 at the
    degree limit."""
    n = NY[e]
    d = lam[e] - lam[c]
    ex[0] = 1.0  # d^m / m!, each as the series reaches it
    top = 0.0
    Lp = 1.0
    status = 1
    last = 0
    for kk in range(DC):
        if kk > 0:
            ex[kk] = quot(ex[kk - 1] * d, kk)
        R = 0.0j
        for i in range(min(kk, n - 1) + 1):
            R += Y[e, i] * ex[kk - i]
        Y[c, kk] += R
        last = kk
        mag = cabs(R) * Lp
        Lp *= L
        if mag > top:
            top = mag
        if kk >= n - 1 and mag <= SERIES_TOL * top:
            status = 0
            break
    if last + 1 > NY[c]:
        NY[c] = last + 1
    for i in range(n):
        Y[e, i] = 0.0
    NY[e] = 0
    return status

plain_literals(globals())  # one machine code per kernel for all constant arguments (a shorter compile)
internal_kernels(globals())  # kernels call them all, Python none: link-only (their callers hold their code)
