"""Integrals of exact pieces (theory §4d): the moments ``int tau^k e^{mu tau}``, a block's value,
``int phi`` and ``int phi^2`` of a block (:mod:`impactbar.laws.rodrock._exactpieces` describes the blocks)."""

from __future__ import annotations

import cmath
import math

import numba
import numpy as np

from ..._shared.literals import plain_literals
from ..._shared.twinops import ipow, quot
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE


@numba.njit(cache=CACHE, nogil=True)
def moments(mu, a, b, K, out):
    """``out[k] = int_a^b tau^k e^{mu tau} dtau`` for ``k < K`` (complex ``mu``, ``0 <= a <= b``):
    upward recursion ``I_k = [tau^k e^{mu tau}/mu]_a^b - k/mu I_{k-1}`` while ``k < |mu| b``, the
    downward one ``I_{k-1} = ([tau^k e^{mu tau}]_a^b - mu I_k)/k`` beyond and for every ``k`` where
    ``|mu| b <= 1`` (each stable where it is used: an error is multiplied by ``|mu| b/k < 1`` a step;
    started from 0 where ``prod |mu| b/k`` has damped its error below 1e-20). (The power series in
    ``mu`` that ``|mu| b <= 1`` used before gave the same values at several times the cost; for
    larger ``|mu| b`` an alternating series loses ``e^{|mu| b}``: a bit with mass, its fast roots.)"""
    if mu.imag == 0.0:  # a real exponent (every massless bit's): real arithmetic, the same values
        m = mu.real  # (the complex ones' imaginary parts are zeros)
        _recursions(m, abs(m), math.exp(m * b) if m != 0.0 else 1.0, math.exp(m * a) if m != 0.0 else 1.0,
                    a, b, K, out)
    else:
        _recursions(mu, abs(mu), cmath.exp(mu * b), cmath.exp(mu * a), a, b, K, out)


@numba.njit(cache=CACHE, nogil=True, inline="always")  # (a call: 5 % of a bit with mass's blow)
def _recursions(mu, amu, eb, ea, a, b, K, out):
    """:func:`moments`' recursions, ``eb = e^{mu b}``, ``ea = e^{mu a}`` (compiled for a real and
    for a complex ``mu``)."""
    x = amu * b
    k0 = min(K, math.ceil(x)) if x > 1.0 else 0
    if k0 < K:
        top = K
        damp = 1.0
        while damp > 1e-20:
            top += 1
            damp *= x / top
        cur = 0.0 * eb
        for kk in range(top, k0, -1):
            pb = 1.0 if b == 1.0 else ipow(b, kk)  # (b = 1: every caller's, the moments in u = tau / b)
            cur = quot(pb * eb - (ipow(a, kk) if a > 0.0 else 0.0) * ea - mu * cur, kk)
            if kk - 1 < K:
                out[kk - 1] = cur
    pb = 1.0
    pa = 1.0
    prev = 0.0 * eb
    for k in range(k0):
        val = quot(eb - ea, mu) if k == 0 else quot(pb * eb - pa * ea, mu) - quot(k, mu) * prev
        out[k] = val
        prev = val
        pb *= b
        pa *= a


@numba.njit(cache=CACHE, nogil=True)
def blk_integral(B, N, lam, a, b):
    """``int_a^b phi``, in the variable ``u = tau / b`` (coefficients ``c_d b^d``): a piece valid
    on a short interval only (a series of a stiff exponent) has huge coefficients ``c_d`` whose
    products would overflow, though its values do not."""
    return blk_integral_exp(B, N, lam, 0.0j, a, b).real


@numba.njit(cache=CACHE, nogil=True)
def _expl(lam_e, tau):
    """``e^{lam_e tau}``: for a real exponent ``cmath.exp``'s value (``(r, r 0)``, ``r = e^{lam_e tau}``)
    without its sine and cosine of 0."""
    if lam_e.imag == 0.0:
        r = math.exp(lam_e.real * tau)
        return complex(r, r * 0.0)
    return cmath.exp(lam_e * tau)


@numba.njit(cache=CACHE, nogil=True)
def blk_value(B, N, lam, tau):
    """The block's value at ``tau`` (the real part of its terms' sum; for a real exponent from the
    coefficients' real parts alone, the same value)."""
    f = 0.0
    for e in range(N.size):
        n = N[e]
        if n == 0:
            continue
        le = lam[e]
        if le.imag == 0.0:
            qr = 0.0
            for d in range(n - 1, -1, -1):
                qr = qr * tau + B[e, d].real
            f += qr if le == 0.0 else math.exp(le.real * tau) * qr
            continue
        q = 0.0j
        for d in range(n - 1, -1, -1):
            q = q * tau + B[e, d]
        f += (_expl(le, tau) * q).real
    return f


#: Gauss-Legendre nodes and weights on [-1, 1] (20 points: exact to degree 39)
_GL_X, _GL_W = np.polynomial.legendre.leggauss(20)
#: the pairwise sum of int phi^2 is kept while its terms are below this many times the result
#: (rounding then costs at most ~1e-12 of it); past it, quadrature
SQ_CANCEL = 1e4
#: the most panels that quadrature takes (a bit ringing on a stiff rock, 1e6 radians over the
#: piece, is left to the pairwise sum)
QUAD_PANELS = 4096


@numba.njit(cache=CACHE, nogil=True)
def blk_integral_sq_quad(B, N, lam, a, b):
    """``int_a^b phi^2`` by Gauss-Legendre quadrature of the block's own values, on panels graded
    geometrically from ``a`` (the first as wide as the fastest term's time scale, each next twice
    as wide, none wider than a quarter of the interval or than 4 over the fastest oscillation):
    a light bit's fast terms decay within a few panels, which resolve them to ~1e-14. NaN where
    that would take more than ``QUAD_PANELS`` panels."""
    if b <= a:
        return 0.0
    rate = 0.0
    osc = 0.0
    for e in range(N.size):
        if N[e] > 0:
            rate = max(rate, abs(lam[e]))
            osc = max(osc, abs(lam[e].imag))
    L = b - a
    cap = 0.25 * L
    if osc > 0.0:
        cap = min(cap, 4.0 / osc)
    w = cap if rate * cap <= 1.0 else 1.0 / rate
    if L / cap + math.log(max(cap / w, 1.0)) / math.log(2.0) > QUAD_PANELS:
        return math.nan  # too fast an oscillation for panels: the caller keeps its sum
    s = 0.0
    x = a
    while x < b:
        hi = min(b, x + w)
        if b - hi < 1e-3 * w:
            hi = b
        half = 0.5 * (hi - x)
        mid = 0.5 * (hi + x)
        part = 0.0
        for i in range(_GL_X.size):
            v = blk_value(B, N, lam, mid + half * _GL_X[i])
            part += _GL_W[i] * v * v
        s += half * part
        x = hi
        w = min(2.0 * w, cap)
    return s


@numba.njit(cache=CACHE, nogil=True)
def blk_integral_sq(B, N, lam, a, b):
    """``int_a^b phi^2`` (``phi`` real: its conjugate terms are in the table): per pair of exponents
    the product polynomial against the moments of ``e^{(lam_1 + lam_2) tau}``; where those terms
    exceed the result ``SQ_CANCEL`` times (a light bit: fast and slow terms of large opposite
    coefficients cancelled to 1e-6 of the piston's energy), by quadrature
    (:func:`blk_integral_sq_quad`)."""
    if b <= 0.0:
        return 0.0
    # in the variable u = tau / b, coefficients c_d b^d (see blk_integral: no overflow of the products
    # of a short-lived series' huge coefficients)
    mom = np.empty(2 * B.shape[1], dtype=np.complex128)
    prod = np.empty(2 * B.shape[1], dtype=np.complex128)
    E = N.size
    C = np.empty((E, B.shape[1]), dtype=np.complex128)
    for e in range(E):
        sc = 1.0
        for d in range(N[e]):
            C[e, d] = B[e, d] * sc
            sc *= b
    s = 0.0j
    mag = 0.0  # the sum of the terms' moduli: the rounding scale of s
    for e1 in range(E):
        n1 = N[e1]
        if n1 == 0:
            continue
        for e2 in range(e1, E):
            n2 = N[e2]
            if n2 == 0:
                continue
            m = n1 + n2 - 1
            for k in range(m):
                prod[k] = 0.0
            for d1 in range(n1):
                c1 = C[e1, d1]
                if c1 == 0.0:
                    continue
                for d2 in range(n2):
                    prod[d1 + d2] += c1 * C[e2, d2]
            moments((lam[e1] + lam[e2]) * b, a / b, 1.0, m, mom)
            t = 0.0j
            for k in range(m):
                t += prod[k] * mom[k]
                pm = prod[k] * mom[k]
                mag += math.sqrt(pm.real * pm.real + pm.imag * pm.imag) if abs(pm.real) < 1e150 and \
                    abs(pm.imag) < 1e150 else abs(pm)  # (a rounding scale: underflow is harmless)
            s += t if e1 == e2 else 2.0 * t
    if mag > SQ_CANCEL * abs(s.real):  # the pairs cancel (a light bit's fast terms): quadrature
        q = blk_integral_sq_quad(B, N, lam, a, b)
        if not math.isnan(q):
            return q
    return s.real * b


@numba.njit(cache=CACHE, nogil=True)
def blk_integral_exp(B, N, lam, shift, a, b):
    """``int_a^b phi(tau) e^{shift tau} dtau`` (complex ``shift``; the complex value, ``phi`` real),
    in the variable ``u = tau / b`` as :func:`blk_integral`: the projections of a wave on the modes."""
    if b <= 0.0:
        return 0.0j
    mom = np.empty(B.shape[1], dtype=np.complex128)
    s = 0.0j
    for e in range(N.size):
        n = N[e]
        if n == 0:
            continue
        moments((lam[e] + shift) * b, a / b, 1.0, n, mom)
        sc = 1.0
        for d in range(n):
            s += B[e, d] * sc * mom[d]
            sc *= b
    return s * b


plain_literals(globals())  # one machine code per kernel for all constant arguments (a shorter compile)
internal_kernels(globals())  # kernels call them all, Python none: link-only (their callers hold their code)
