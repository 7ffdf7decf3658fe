"""Histories of the exact blow (theory §4d): a recorded channel evaluated at given times, its
largest value and its integral (:mod:`impactbar.laws.rodrock._exactloop` records them)."""

from __future__ import annotations

import numba
import numpy as np

from ..._shared.literals import plain_literals
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from ._exactintegrals import blk_integral
from ._exactpieces import (
    DC,
    EPS,
    INF,
    SNAP,
    blk_abs,
    blk_bound,
    blk_eval,
    blk_value,
    pool_load,
    pool_unpack,
)
from ._records import (  # the result's slots  # the pool's columns
    HMAX_T,
    HMAX_V,
    PF_REF,
    PF_START,
    PI_COUNT,
    PI_FLAG,
    PI_NEXT,
    STK_A,
    STK_B,
)

NOBIN = np.zeros((1, 1))

# ------------------------------------------------------------------------------------------------
# histories
# ------------------------------------------------------------------------------------------------


@numba.njit(cache=CACHE, nogil=True)
def eval_history(PF, PI, TK, TC, lam, head, times, out, kind, lamk):
    """A history channel at ``times`` (sorted): ``kind`` 0 the value, 1 the bit's penetration
    (``ref + x``), 2 the rock's force (``b x`` with ``b = lamk[branch]``)."""
    E = lam.size
    B = np.zeros((E, DC), dtype=np.complex128)
    N = np.zeros(E, dtype=np.int64)
    _eval_into(PF, PI, TK, TC, lam, head, times, out, kind, lamk, B, N)


@numba.njit(cache=CACHE, nogil=True)
def eval_histories(PF, PI, TK, TC, lam, heads, times, out, kind, lamk):
    """:func:`eval_history` of the channels whose first pieces are ``heads`` at the same ``times``,
    into the columns of ``out`` (shape ``(times.size, heads.size)``)."""
    E = lam.size
    B = np.zeros((E, DC), dtype=np.complex128)
    N = np.zeros(E, dtype=np.int64)
    col = np.empty(times.size)
    for j in range(heads.size):
        _eval_into(PF, PI, TK, TC, lam, heads[j], times, col, kind, lamk, B, N)
        for i in range(times.size):  # (a loop: numba's slice setitem compiles for seconds)
            out[i, j] = col[i]


@numba.njit(cache=CACHE, nogil=True)
def eval_bit(PF, PI, TK, TC, lam, head, times, pen, force, lamk):
    """The bit's history at ``times`` (sorted): its penetration into ``pen`` and the rock's force into
    ``force`` (:func:`eval_history`'s kinds 1 and 2), each value computed once."""
    E = lam.size
    B = np.zeros((E, DC), dtype=np.complex128)
    N = np.zeros(E, dtype=np.int64)
    _eval_into(PF, PI, TK, TC, lam, head, times, pen, 0, lamk, B, N)
    p = head
    for i in range(times.size):
        if p < 0:
            force[i] = 0.0
            continue
        while PI[p, PI_NEXT] >= 0 and PF[PI[p, PI_NEXT], PF_START] <= times[i]:
            p = PI[p, PI_NEXT]
        v = pen[i]
        force[i] = max(lamk[PI[p, PI_FLAG]] * v, 0.0)
        pen[i] = v + PF[p, PF_REF]


@numba.njit(cache=CACHE, nogil=True)
def _eval_into(PF, PI, TK, TC, lam, head, times, out, kind, lamk, B, N):
    """:func:`eval_history` with a scratch block ``B, N``: each piece loaded once for the times on it
    (0 where the channel holds none)."""
    p = head
    if p < 0:
        out[:] = 0.0
        return
    loaded = -1
    for i in range(times.size):
        t = times[i]
        while PI[p, PI_NEXT] >= 0 and PF[PI[p, PI_NEXT], PF_START] <= t:
            p = PI[p, PI_NEXT]
        tau = t - PF[p, PF_START]
        if tau < 0.0:
            tau = 0.0
        if p != loaded:
            pool_unpack(B, N, p, PI, TK, TC)
            loaded = p
        v = blk_value(B, N, lam, tau)
        if kind == 1:
            v += PF[p, PF_REF]
        elif kind == 2:
            v = max(lamk[PI[p, PI_FLAG]] * v, 0.0)
        out[i] = v


@numba.njit(cache=CACHE, nogil=True)
def piece_max(B, N, lam, BIN, L, stack):
    """The largest value of a piece on ``[0, L]`` and where it is first reached (to rounding):
    branch and bound on ``phi(m) + |phi'(m)| w/2 + M2 w^2/8``, the best point refined by Newton's
    steps on ``phi'``."""
    f0 = blk_value(B, N, lam, 0.0)
    best = f0
    tb = 0.0
    fL = blk_value(B, N, lam, L)
    a0, _x, _y = blk_abs(B, N, lam, 0.0)
    tol = 8.0 * EPS * a0
    if fL > best + tol:
        best = fL
        tb = L
    if L <= 0.0:
        return best, tb
    stack[0, STK_A] = 0.0
    stack[0, STK_B] = L
    sp = 1
    it = 0
    while sp > 0 and it < 4000:
        it += 1
        sp -= 1
        a = stack[sp, STK_A]
        b = stack[sp, STK_B]
        w = b - a
        m = 0.5 * (a + b)
        fm, dm, _ = blk_eval(B, N, lam, m)
        M2 = blk_bound(B, N, lam, BIN, a, b, 2)
        if fm + abs(dm) * 0.5 * w + M2 * w * w * 0.125 <= best + tol:
            continue
        if fm > best + tol:
            best = fm
            tb = m
        if w <= 64.0 * EPS * L or sp + 2 > stack.shape[0]:
            continue
        stack[sp, STK_A] = m
        stack[sp, STK_B] = b
        stack[sp + 1, STK_A] = a
        stack[sp + 1, STK_B] = m
        sp += 2
    if 0.0 < tb < L:  # Newton on phi' = 0 from the best point
        x = tb
        for _ in range(30):
            _f, d1, d2 = blk_eval(B, N, lam, x)
            if d2 >= 0.0:
                break
            xn = x - d1 / d2
            if not (0.0 < xn < L) or abs(xn - x) <= 2.0 * EPS * x:
                break
            x = xn
        fx = blk_value(B, N, lam, x)
        if fx >= best:
            best = fx
            tb = x
    return best, tb


@numba.njit(cache=CACHE, nogil=True)
def history_max(PF, PI, TK, TC, lam, head, t_end, res):
    """The largest value of a history channel up to ``t_end`` and the time it is first reached
    (``res``: value, time, at ``HMAX_V``, ``HMAX_T``)."""
    E = lam.size
    B = np.zeros((E, DC), dtype=np.complex128)
    N = np.zeros(E, dtype=np.int64)
    BIN = np.zeros((DC, DC))
    for a in range(DC):
        BIN[a, 0] = 1.0
        for b in range(1, a + 1):
            BIN[a, b] = BIN[a - 1, b - 1] + (BIN[a - 1, b] if b < a else 0.0)
    stack = np.zeros((256, 2))
    best = -INF
    tb = 0.0
    p = head
    while p >= 0:
        nx = PI[p, PI_NEXT]
        L = min(PF[nx, PF_START] if nx >= 0 else t_end, t_end) - PF[p, PF_START]
        if L < 0.0:  # (the pieces from t_end on)
            break
        if nx >= 0 and L <= SNAP * abs(PF[nx, PF_START]):
            # a sliver between two arrivals that rounding set apart (incommensurate segments): its
            # value mixes the old wave on one input with the new on the other, a force that never acts.
            # Such are the solver's own (:func:`advance`'s ``SNAP``), not anything shorter than 1e-11
            # of the time: a stiff rock's unloading spike lasts ``Z/k_u`` (5e-13 for ``k_u/Z = 2e12``),
            # and its peak, the largest force of the blow at a junction, was skipped
            p = nx
            continue
        if PI[p, PI_COUNT] == 0:
            v = 0.0
            tv = PF[p, PF_START]
        else:
            pool_unpack(B, N, p, PI, TK, TC)
            v, tau = piece_max(B, N, lam, BIN, L, stack)
            tv = PF[p, PF_START] + tau
        if v > best + 8.0 * EPS * abs(v):
            best = v
            tb = tv
        p = nx
    res[HMAX_V] = best
    res[HMAX_T] = tb


@numba.njit(cache=CACHE, nogil=True)
def history_integral(PF, PI, TK, TC, lam, head, t_end):
    """``int_0^{t_end}`` of a history channel (its value), piece by piece in closed form."""
    E = lam.size
    B = np.zeros((E, DC), dtype=np.complex128)
    N = np.zeros(E, dtype=np.int64)
    total = 0.0
    p = head
    while p >= 0:
        nx = PI[p, PI_NEXT]
        t0 = PF[p, PF_START]
        t1 = min(PF[nx, PF_START] if nx >= 0 else t_end, t_end)
        a = max(t0, 0.0)
        if t1 > a and PI[p, PI_COUNT] > 0:
            pool_load(B, N, p, 0.0, lam, NOBIN, PI, TK, TC)  # (no shift: no binomials read)
            total += blk_integral(B, N, lam, a - t0, t1 - t0)
        if t1 >= t_end:
            break
        p = nx
    return total


plain_literals(globals())  # one machine code per kernel for all constant arguments (a shorter compile)
# the kernels Python calls keep their wrapper and cache entry; the others are link-only (for kernels)
internal_kernels(globals(), python=("eval_history", "eval_histories", "eval_bit", "history_max",
                                     "history_integral"))
