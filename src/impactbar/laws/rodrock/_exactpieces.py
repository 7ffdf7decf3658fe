"""Exact pieces of the exact blow (theory §4d): the block algebra of exponential polynomials, the exact
solution of ``y' - r y = g``, the certified first crossing of zero, the pool of pieces and the channels
(delay lines) that carry them. The driver is :mod:`impactbar.laws.rodrock._exactloop`, whose text
describes the representation."""

from __future__ import annotations

import math

import numba

from ..._shared.literals import plain_literals
from ..._shared.twinops import ipow
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from ._exactintegrals import _expl, blk_integral, blk_integral_sq, blk_value, moments  # noqa: F401 (the kernel's)
from ._records import (  # the records' slots and the pool's columns
    CHI_HEAD,
    CHI_TAIL,
    CNT_FULL,
    CNT_PIECES,
    CNT_TERMS,
    E_CONST,
    PF_INT,
    PF_INT2,
    PF_REF,
    PF_START,
    PF_VALID,
    PI_COUNT,
    PI_FLAG,
    PI_NEXT,
    PI_TERMS,
    STK_A,
    STK_B,
    STK_FA,
    STK_FB,
)

DC = 64  # coefficients per exponent: polynomial degree up to DC - 1
NEAR = 4.0  # |lam_e - r| L below which y' = r y + g is solved by its Taylor recursion (~30 terms)
EPS = 2.220446049250313e-16
SERIES_TOL = 1e-18
#: the largest coefficient a series of ``e^{delta tau}`` may reach (:func:`series_fits`): a piece's
#: derivatives (three in :func:`first_negative`), the waves it reflects and the series solved on
#: them again multiply it by the exponents, and those must stay within the float range (1e240
#: still overflowed at ``k_u/Z = 2e11``, a spike's second pass through the bit)
SERIES_MAX = 1e150
#: arrivals closer than this (relative to the time) are one break point (rounding's slivers)
SNAP = 64.0 * EPS
#: a piece is the open one continued where each coefficient agrees to this fraction of its own size
#: (or of its rounding in the shift), besides 1e-13 of the largest of them
SLOT_REL = 1e-10

# ------------------------------------------------------------------------------------------------
# blocks
# ------------------------------------------------------------------------------------------------


@numba.njit(cache=CACHE, nogil=True)
def blk_clear(B, N):
    for e in range(N.size):
        for d in range(N[e]):
            B[e, d] = 0.0
        N[e] = 0


@numba.njit(cache=CACHE, nogil=True)
def blk_is_zero(N):
    for e in range(N.size):
        if N[e] > 0:
            return False
    return True


@numba.njit(cache=CACHE, nogil=True)
def blk_axpy(B, N, s, A, NA):
    """``B += s A``."""
    for e in range(NA.size):
        n = NA[e]
        if n == 0:
            continue
        for d in range(n):
            B[e, d] += s * A[e, d]
        if n > N[e]:
            N[e] = n


@numba.njit(cache=CACHE, nogil=True)
def blk_set_comb(B, N, s1, A1, N1, s2, A2, N2):
    """``B = s1 A1 + s2 A2``."""
    blk_clear(B, N)
    if s1 != 0.0:
        blk_axpy(B, N, s1, A1, N1)
    if s2 != 0.0:
        blk_axpy(B, N, s2, A2, N2)


@numba.njit(cache=CACHE, nogil=True)
def blk_add_const(B, N, c):
    """Add the constant ``c`` (exponent 0 is entry 0 of the table)."""
    if c == 0.0:
        return
    B[E_CONST, 0] += c
    if N[E_CONST] == 0:
        N[E_CONST] = 1


@numba.njit(cache=CACHE, nogil=True)
def blk_trim(B, N):
    """Drop trailing zero coefficients."""
    for e in range(N.size):
        n = N[e]
        while n > 0 and B[e, n - 1] == 0.0:
            n -= 1
        N[e] = n


@numba.njit(cache=CACHE, nogil=True)
def blk_eval(B, N, lam, tau):
    """Value, first and second derivative (real parts) at ``tau``."""
    f0 = f1 = f2 = 0.0
    for e in range(N.size):
        n = N[e]
        if n == 0:
            continue
        q0 = 0.0j
        q1 = 0.0j
        q2 = 0.0j
        for d in range(n - 1, -1, -1):  # Horner for Q, Q', Q''
            q2 = q2 * tau + 2.0 * q1
            q1 = q1 * tau + q0
            q0 = q0 * tau + B[e, d]
        le = lam[e]
        if le == 0.0:
            f0 += q0.real
            f1 += q1.real
            f2 += q2.real
        else:
            ex = _expl(le, tau)
            f0 += (ex * q0).real
            f1 += (ex * (q1 + le * q0)).real
            f2 += (ex * (q2 + 2.0 * le * q1 + le * le * q0)).real
    return f0, f1, f2


@numba.njit(cache=CACHE, nogil=True)
def cabs(z):
    """``|z|`` of a complex number: ``sqrt(x^2 + y^2)`` where neither square can overflow or
    underflow, ``hypot`` (several times slower) elsewhere."""
    x = abs(z.real)
    y = abs(z.imag)
    m = max(x, y)
    if 1e-150 < m < 1e150:
        return math.sqrt(x * x + y * y)
    return math.hypot(x, y)


@numba.njit(cache=CACHE, nogil=True)
def blk_abs(B, N, lam, tau):
    """Sums of the absolute values of the terms of the value and of its first two derivatives at
    ``tau`` (their rounding scales)."""
    a0 = a1 = a2 = 0.0
    for e in range(N.size):
        n = N[e]
        if n == 0:
            continue
        g = math.exp(lam[e].real * tau)
        al = cabs(lam[e])
        pw0 = 1.0  # tau^d
        pw1 = 0.0  # tau^(d - 1)
        pw2 = 0.0  # tau^(d - 2)
        for d in range(n):
            if d >= 1:
                pw2 = pw1 if d >= 2 else 0.0
                pw1 = pw0
                pw0 = pw0 * tau
            c = cabs(B[e, d]) * g
            if c == 0.0:
                continue
            p0 = pw0
            p1 = d * pw1
            p2 = d * (d - 1) * pw2
            a0 += c * p0
            a1 += c * (al * p0 + p1)
            a2 += c * (al * al * p0 + 2.0 * al * p1 + p2)
    return a0, a1, a2


@numba.njit(cache=CACHE, nogil=True)
def blk_bound(B, N, lam, BIN, a, b, k):
    """An upper bound of ``|phi^(k)|`` on ``[a, b]`` (``0 <= a <= b``), from the terms."""
    tot = 0.0
    for e in range(N.size):
        n = N[e]
        if n == 0:
            continue
        re = lam[e].real
        g = math.exp(re * (a if re <= 0.0 else b))
        if k == 0:  # (every caller's) sum |c_d| g b^d, the powers by products
            pb = 1.0
            acc = 0.0
            for d in range(n):
                acc += cabs(B[e, d]) * pb
                pb *= b
            tot += acc * g
            continue
        al = cabs(lam[e])
        for d in range(n):
            c = cabs(B[e, d])
            if c == 0.0:
                continue
            s = 0.0
            ff = 1.0  # d! / (d - i)!
            for i in range(min(k, d) + 1):
                s += BIN[k, i] * ipow(al, k - i) * ff * ipow(b, d - i)
                ff *= d - i
            tot += c * g * s
    return tot


@numba.njit(cache=CACHE, nogil=True)
def blk_deriv(D, ND, B, N, lam):
    """``D = d/dtau B``."""
    blk_clear(D, ND)
    for e in range(N.size):
        n = N[e]
        if n == 0:
            continue
        le = lam[e]
        for d in range(n):
            c = B[e, d]
            if c == 0.0:
                continue
            if le != 0.0:
                D[e, d] += le * c
            if d > 0:
                D[e, d - 1] += d * c
        m = n if le != 0.0 else n - 1
        ND[e] = m if m > 0 else 0
    blk_trim(D, ND)


@numba.njit(cache=CACHE, nogil=True)
def blk_shift(B, N, delta, lam, BIN):
    """Re-express ``B`` from the origin ``delta`` (in place): ``c (delta + s)^d e^{lam (delta + s)}``
    expanded in ``s``."""
    if delta == 0.0:
        return
    for e in range(N.size):
        n = N[e]
        if n == 0:
            continue
        ex = _expl(lam[e], delta) if lam[e] != 0.0 else 1.0 + 0.0j
        # new_k = ex * sum_{d >= k} c_d binom(d, k) delta^(d - k)
        for k in range(n):
            s = 0.0j
            p = 1.0
            for d in range(k, n):
                s += B[e, d] * BIN[d, k] * p
                p *= delta
            B[e, k] = s * ex
        # (k-order loop reads B[e, d] for d >= k, written only after: safe)


# ------------------------------------------------------------------------------------------------
# the first crossing of zero
# ------------------------------------------------------------------------------------------------


@numba.njit(cache=CACHE, nogil=True)
def _refine(B, N, lam, a, b):
    """The root in ``[a, b]`` of a piece decreasing through it (``phi(a) >= 0 > phi(b)``): Newton's
    steps kept inside the bracket, bisection where they leave it; the point with ``phi <= 0``."""
    x = 0.5 * (a + b)
    for _ in range(200):
        f, f1, _f2 = blk_eval(B, N, lam, x)
        if f >= 0.0:
            a = x
        else:
            b = x
        if b - a <= 2.0 * EPS * max(abs(a), abs(b)) or b - a <= 1e-300:
            break
        xn = x - f / f1 if f1 != 0.0 else 0.5 * (a + b)
        if not (a < xn < b):
            xn = 0.5 * (a + b)
        if xn == x:
            xn = 0.5 * (a + b)
            if xn == a or xn == b:
                break
        x = xn
    return b


@numba.njit(cache=CACHE, nogil=True)
def first_negative(B, N, lam, BIN, L, stack, D, t0):
    """The first ``tau`` in ``[0, L]`` where the piece is negative beyond rounding (it is ``>= 0`` at 0
    up to rounding; one that starts at zero is left by its first non-vanishing derivative), ``-1``
    if none, ``-2`` if the search gave up (its work bounded). A subinterval is excluded by the
    Lipschitz bound or by the cubic Taylor bound from its left end (a piece rising from ~0 whose
    fast terms cancel, a bit with mass). ``stack``: work array, shape (>= 256, 4); ``D``: three
    scratch blocks ``(D1, N1, D2, N2, D3, N3)`` for the derivatives, bounded by their own terms.

    ``t0`` is the piece's start on the blow's clock: a switch located there is known to its
    resolution ``dt = 8 eps |t0|`` only, so a value (a slope) at the start within ``dt`` times the
    slope (the curvature) of zero counts as zero. (A fast piece, a bit of small mass, crosses zero
    with a slope of 1e6: its value at the located root is then 1e-10, and read as a sign it switched
    the contact back at once; the chatter guard then kept a tensile contact to the window's end.)"""
    if L <= 0.0 or blk_is_zero(N):
        return -1.0
    D1, N1, D2, N2, D3, N3 = D
    blk_deriv(D1, N1, B, N, lam)
    blk_deriv(D2, N2, D1, N1, lam)
    blk_deriv(D3, N3, D2, N2, lam)
    f0, f1, f2 = blk_eval(B, N, lam, 0.0)
    a0, a1, a2 = blk_abs(B, N, lam, 0.0)
    dt = 8.0 * EPS * abs(t0)
    e0 = 16.0 * EPS * a0 + dt * abs(f1)
    e1 = 16.0 * EPS * a1 + dt * abs(f2)
    e2 = 16.0 * EPS * a2
    if f0 < -e0:
        return 0.0
    s = 0.0
    if f0 <= e0:  # starts at zero
        if f1 < -e1:
            return 0.0
        if f1 <= e1 and f2 < -e2:
            return 0.0
        # the signed curvature: a piece rising from zero and bending down crosses it again near
        # -2 f1/f2 (a curvature of rounding's size counts as 0; the slope is >= -e1 here)
        g1 = f1 if f1 > e1 else 0.0
        g2 = f2 if abs(f2) > e2 else 0.0
        M3 = blk_bound(D3, N3, lam, BIN, 0.0, L, 0)
        if g1 == 0.0 and g2 <= 0.0:
            s = 0.0  # flat to rounding at the start: the search below decides
        elif M3 <= 0.0:
            # phi(s) - phi(0) = g1 s + g2 s^2/2 > 0 below -2 g1/g2 (half of it kept)
            s = L if g2 >= 0.0 else min(L, -g1 / g2)
        else:
            # phi(s) - phi(0) >= g1 s + g2 s^2/2 - M3 s^3/6 > 0 below the positive root of
            # aa s^2 - b s - g1 (half of it kept), in the form free of cancellation for b < 0
            aa = M3 / 6.0
            b = 0.5 * g2
            disc = math.sqrt(b * b + 4.0 * aa * g1)
            s = 0.5 * ((b + disc) / (2.0 * aa) if b >= 0.0 else 2.0 * g1 / (disc - b))
        if s >= L:
            return -1.0
    aL, _b1, _b2 = blk_abs(B, N, lam, L)
    err = 16.0 * EPS * max(a0, aL)
    fs = blk_value(B, N, lam, s) if s > 0.0 else max(f0, 0.0)
    if fs < -err:
        return _refine(B, N, lam, 0.0, s)
    fL = blk_value(B, N, lam, L)
    stack[0, STK_A] = s
    stack[0, STK_B] = L
    stack[0, STK_FA] = max(fs, 0.0)
    stack[0, STK_FB] = fL
    sp = 1
    wmin = 4.0 * EPS * L
    it = 0
    while sp > 0:
        sp -= 1
        a = stack[sp, STK_A]
        b = stack[sp, STK_B]
        fa = stack[sp, STK_FA]
        fb = stack[sp, STK_FB]
        w = b - a
        it += 1
        if it > 4000:
            return -2.0
        M1 = blk_bound(D1, N1, lam, BIN, a, b, 0)
        if fa + fb - M1 * w > -2.0 * err:
            continue
        g0, g1, g2 = blk_eval(B, N, lam, a)
        M3 = blk_bound(D3, N3, lam, BIN, a, b, 0)
        if g0 + min(g1, 0.0) * w + min(0.0, w * w * (0.5 * g2 - M3 * w / 6.0)) > -err:
            continue
        if fb < -err:
            gm = blk_value(D1, N1, lam, 0.5 * (a + b))
            M2 = blk_bound(D2, N2, lam, BIN, a, b, 0)
            if gm + 0.5 * M2 * w < 0.0:
                return _refine(B, N, lam, a, b)
        if w <= wmin:
            if fb < -err:
                return _refine(B, N, lam, a, b)
            continue  # a tangency to rounding: no crossing
        m = 0.5 * (a + b)
        fm = blk_value(B, N, lam, m)
        if fm < -err:
            stack[sp, STK_A] = a
            stack[sp, STK_B] = m
            stack[sp, STK_FA] = fa
            stack[sp, STK_FB] = fm
            sp += 1
        else:
            if sp + 2 > stack.shape[0]:
                return -2.0
            stack[sp, STK_A] = m
            stack[sp, STK_B] = b
            stack[sp, STK_FA] = max(fm, 0.0)
            stack[sp, STK_FB] = fb
            stack[sp + 1, STK_A] = a
            stack[sp + 1, STK_B] = m
            stack[sp + 1, STK_FA] = fa
            stack[sp + 1, STK_FB] = max(fm, 0.0)
            sp += 2
    return -1.0


# ------------------------------------------------------------------------------------------------
# the pool of pieces and the channels
# ------------------------------------------------------------------------------------------------
# PF (cap, 5) float: t0 (emission start), valid_until (inf: exact), ref (bit history: p - x), and
#    int f, int f^2 over the piece's whole span once its successor is emitted (NaN until computed:
#    the energy account sums them instead of integrating every piece in flight again)
# PI (cap, 4) int: next, term start, term count, flag (bit history: the branch)
# TK (tcap,) int: e * DC + d;  TC (tcap,) complex: coefficient
# CNT int: pieces, terms, (unused), overflow
# CH_T (nch,) float delay; CHI (nch, 2) int: tail (last emitted), cursor (the receiver's piece)

INF = math.inf
LOAD, ELASTIC, FREE = 0, 1, 2
# end codes
GOING, SEPARATED, LIFTED, SPENT, TMAX, BUDGET, RINGS, FAILED, MAY_YIELD = 0, 1, 2, 3, 4, 5, 6, 7, 8


@numba.njit(cache=CACHE, nogil=True)
def _term_bound(re, d, Lb):
    """``max |tau^d e^{re tau}|`` over ``[0, Lb]``."""
    if d == 0:
        return 1.0
    if re < 0.0:
        tm = d / (-re)
        if tm < Lb:
            return math.exp(d * (math.log(tm) - 1.0))
        return math.exp(d * math.log(Lb) + re * Lb)
    return ipow(Lb, d)


@numba.njit(cache=CACHE, nogil=True)
def blk_prune(B, N, lam, tol, Lb):
    """Zero the terms below ``tol`` on ``[0, Lb]``: ``|c| _term_bound < tol``, decided without the
    bound's logarithm and exponential where bounds of it by products decide it with a margin far
    beyond their rounding (the same decisions): ``Lb^d`` above it, ``Lb^d / e`` (a decay ``|re| Lb <=
    1``) or ``|re|^-d / e`` (its value at ``1 / |re|``, a faster decay) below it."""
    for e in range(N.size):
        re = lam[e].real
        fast = re * Lb < -1.0
        p = 1.0  # Lb^d
        q = 1.0  # |re|^-d
        for d in range(N[e]):
            if d > 0:
                p *= Lb
                if fast:
                    q /= -re
            c = B[e, d]
            if c == 0.0:
                continue
            a = cabs(c)
            if d > 0:
                if 2.0 * a * p < tol:
                    B[e, d] = 0.0
                    continue
                if 0.3 * a * (q if fast else p) >= tol:
                    continue
            if a * _term_bound(re, d, Lb) < tol:
                B[e, d] = 0.0
    blk_trim(B, N)


@numba.njit(cache=CACHE, nogil=True)
def pool_unpack(B, N, piece, PI, TK, TC):
    """The pool's piece ``piece`` into the block ``B, N``, from its own origin."""
    blk_clear(B, N)
    ts = PI[piece, PI_TERMS]
    for k in range(ts, ts + PI[piece, PI_COUNT]):
        e = TK[k] // DC
        d = TK[k] - e * DC
        B[e, d] += TC[k]
        if d + 1 > N[e]:
            N[e] = d + 1


@numba.njit(cache=CACHE, nogil=True)
def piece_span(PF, PI, p, lo, t):
    """Piece ``p`` of a channel's list read up to ``t``: ``(t0, nx, tend, a, b)``, its start ``t0``,
    the next piece ``nx`` (-1: none), its end ``tend`` (``t`` while it is the last) and its part
    ``[a, b]`` within ``[lo, t]`` (none where ``b <= a``)."""
    t0 = PF[p, PF_START]
    nx = PI[p, PI_NEXT]
    tend = PF[nx, PF_START] if nx >= 0 else t
    return t0, nx, tend, max(t0, lo), min(tend, t)


@numba.njit(cache=CACHE, nogil=True)
def pool_load(B, N, piece, delta, lam, BIN, PI, TK, TC):
    pool_unpack(B, N, piece, PI, TK, TC)
    blk_shift(B, N, delta, lam, BIN)


@numba.njit(cache=CACHE, nogil=True)
def _write_terms(B, N, TK, TC, CNT):
    """Append the nonzero terms; ``(start, count)`` or ``(-1, 0)`` when the term pool is full."""
    start = CNT[CNT_TERMS]
    nt = start
    for e in range(N.size):
        for d in range(N[e]):
            c = B[e, d]
            if c != 0.0:
                if nt >= TK.size:
                    CNT[CNT_FULL] = 1
                    return -1, 0
                TK[nt] = e * DC + d
                TC[nt] = c
                nt += 1
    CNT[CNT_TERMS] = nt
    return start, nt - start


@numba.njit(cache=CACHE, nogil=True)
def _shift_scale(e, k, tail, delta, dt, lam, BIN, PI, TK, TC):
    """The rounding scale of coefficient ``(e, k)`` of piece ``tail`` shifted by ``delta``
    (:func:`blk_shift`), ``delta`` known to ``dt`` (the clock's rounding): ``|e^{lam_e delta}|
    sum_{d >= k} |c_ed| binom(d, k) (|delta|^(d - k) + (d - k) |delta|^(d - k - 1) dt)``."""
    ad = abs(delta)
    r = 0.0
    ts = PI[tail, PI_TERMS]
    for i in range(ts, ts + PI[tail, PI_COUNT]):
        ei = TK[i] // DC
        d = TK[i] - ei * DC
        if ei == e and d >= k:
            slope = (d - k) * ipow(ad, d - k - 1) * dt if d > k else 0.0
            r += cabs(TC[i]) * BIN[d, k] * (ipow(ad, d - k) + slope)
    return r * math.exp(lam[e].real * delta)


@numba.njit(cache=CACHE, nogil=True)
def _same(B, N, S, NS, tol, tail, t0, delta, pool):
    """Whether block ``B`` is the open piece ``tail`` continued (``S``, ``NS``: it shifted by
    ``delta`` from its start ``t0``; ``pool`` as :func:`emit`'s) to rounding: each coefficient
    within ``tol`` (absolute) besides a relative 1e-13 of the largest, and within ``SLOT_REL`` of its
    own size or of its rounding scale in the shift (:func:`_shift_scale`, the clock's rounding
    ``8 eps |t0 + delta|``). (The largest alone hid a jump: a drive's cubic over a step of 1e-6 of a
    travel time, its cubic coefficient 1e20, let a change of the value by its whole size pass.)"""
    _, PI, TK, TC, _, _, lam, BIN = pool
    top = 0.0
    for e in range(N.size):
        for d in range(max(N[e], NS[e])):
            x = cabs(B[e, d]) if d < N[e] else 0.0
            y = cabs(S[e, d]) if d < NS[e] else 0.0
            top = max(top, x, y)
    lim = 1e-13 * top + tol
    for e in range(N.size):
        for d in range(max(N[e], NS[e])):
            x = B[e, d] if d < N[e] else 0.0j
            y = S[e, d] if d < NS[e] else 0.0j
            diff = cabs(x - y)
            if diff > lim:
                return False
            if diff > SLOT_REL * max(cabs(x), cabs(y)) + tol:  # (rare: the slot's scale decides)
                dt = 8.0 * EPS * (abs(t0) + abs(delta))
                if diff > SLOT_REL * _shift_scale(e, d, tail, delta, dt, lam, BIN, PI, TK, TC) + tol:
                    return False
    return True


@numba.njit(cache=CACHE, nogil=True)
def _fill_piece(B, N, TK, TC, CNT, PF, PI, k, valid, ref, flag):
    """Write the terms of ``B`` into the pool and piece ``k``'s fields but its start and its
    successor (``valid``, ``ref``, ``flag``, its integrals NaN until computed); False (nothing
    written to the piece) where the pool of terms is full."""
    st, nt = _write_terms(B, N, TK, TC, CNT)
    if st < 0:
        return False
    PI[k, PI_TERMS] = st
    PI[k, PI_COUNT] = nt
    PI[k, PI_FLAG] = flag
    PF[k, PF_VALID] = valid
    PF[k, PF_REF] = ref
    PF[k, PF_INT] = math.nan
    PF[k, PF_INT2] = math.nan
    return True


@numba.njit(cache=CACHE, nogil=True)
def emit(c, a, B, N, valid, flag, ref, pool, S, NS, tol, Lb):
    """Emit on channel ``c`` the piece ``B`` from emission time ``a`` (``B`` is pruned in place). A
    piece equal to the continuation of the open one (exact, the same flag) is not emitted; one
    emitted at the open piece's own start replaces it. Returns False when the pool is full. Terms
    are pruned on the piece's life: ``Lb``, or up to ``valid`` for a piece holding series.
    ``pool`` is the tuple ``(PF, PI, TK, TC, CNT, CHI, lam, BIN)``; ``S, NS`` a scratch block."""
    PF, PI, TK, TC, CNT, CHI, lam, BIN = pool
    blk_prune(B, N, lam, tol, min(Lb, max(valid - a, 0.0)))
    tail = CHI[c, CHI_TAIL]
    if tail >= 0:
        t0 = PF[tail, PF_START]
        if t0 == a:  # replace (nobody has received it yet)
            return _fill_piece(B, N, TK, TC, CNT, PF, PI, tail, valid, ref, flag)
        if PF[tail, PF_VALID] == INF and PI[tail, PI_FLAG] == flag and valid == INF and \
                PF[tail, PF_REF] == ref:
            if PI[tail, PI_COUNT] == 0:
                if blk_is_zero(N):
                    return True
            else:
                pool_load(S, NS, tail, a - t0, lam, BIN, PI, TK, TC)
                if _same(B, N, S, NS, tol, tail, t0, a - t0, pool):
                    return True
    npc = CNT[CNT_PIECES]
    if npc >= PF.shape[0]:
        CNT[CNT_FULL] = 1
        return False
    if not _fill_piece(B, N, TK, TC, CNT, PF, PI, npc, valid, ref, flag):
        return False
    PF[npc, PF_START] = a
    PI[npc, PI_NEXT] = -1
    CNT[CNT_PIECES] = npc + 1
    if tail >= 0:
        PI[tail, PI_NEXT] = npc
    else:
        CHI[c, CHI_HEAD] = npc  # a history: its first piece
    CHI[c, CHI_TAIL] = npc
    return True


@numba.njit(cache=CACHE, nogil=True)
def advance(c, a, CHI, CH_T, PF, PI):
    """Move the receiver's cursor on channel ``c`` to the piece arriving at ``a``; returns it and the
    next piece's arrival (inf if not emitted yet). An arrival within ``SNAP`` of ``a`` (relative) has
    arrived: break points equal but for the rounding of sums of travel times, summed in different
    orders (a stepped piston's and rod's paths), are one."""
    cur = CHI[c, CHI_HEAD]
    T = CH_T[c]
    lim = a + SNAP * abs(a)
    while True:
        nx = PI[cur, PI_NEXT]
        if nx < 0:
            CHI[c, CHI_HEAD] = cur
            return cur, INF
        arr = PF[nx, PF_START] + T
        if arr <= lim:
            cur = nx
        else:
            CHI[c, CHI_HEAD] = cur
            return cur, arr


@numba.njit(cache=CACHE, nogil=True)
def window_break(b, t1):
    """A node's next break point: its next arrival ``b`` within the window that ends at ``t1``, or
    ``t1``. An arrival within ``SNAP`` before ``t1`` is taken at ``t1`` (:func:`load_input` reads it
    from its start there): one break point but for rounding (an arrival summed from travel times,
    ``2.5999999999999996``, and the window's end ``26 h = 2.6``), where it was a sliver of an ulp,
    the sliver's piece holding a stiff unloading's spike from its start and the next piece the
    spike an ulp later: downstream the two arrive as one, read from the later (the spike's top
    decayed by ``e^{-k_u/Z * 1 ulp}``, 9e-4 for ``k_u/Z = 2e12``)."""
    if b >= t1 - SNAP * abs(t1):
        return t1
    return b


@numba.njit(cache=CACHE, nogil=True)
def load_input(B, N, c, piece, a, CH_T, PF, PI, TK, TC, lam, BIN):
    """The piece of channel ``c`` arriving at ``a``, from origin ``a``; returns its validity (arrival
    time). A piece arriving within ``SNAP`` of ``a`` (:func:`advance`, :func:`window_break`: the same
    break point but for rounding) starts at ``a``, and is never read before its own start. (Shifted
    back to ``a``, a stiff unloading's term ``e^{-k_u tau/Z}``, ``k_u/Z = 1.5e12``, grew by
    ``e^{1.5e12 * 1.35e-13}``: the spike it reflects from the bit reached the shank 22 % too high, its
    peak force 17 % high. Shifted on by the ulp between an arrival and the window's end it was taken
    at, ``k_u/Z = 2e12``, the spike's top decayed by ``e^{-2e12 * 4.4e-16}``: 9e-4 low.)"""
    arr = PF[piece, PF_START] + CH_T[c]
    delta = a - arr
    if delta <= SNAP * abs(a):
        delta = 0.0
    pool_load(B, N, piece, delta, lam, BIN, PI, TK, TC)
    v = PF[piece, PF_VALID]
    return v + CH_T[c] if v < INF else INF


plain_literals(globals())  # one machine code per kernel for all constant arguments (a shorter compile)
internal_kernels(globals())  # kernels call them all, Python none: link-only (their callers hold their code)
