"""The bit and the rock's node of the exact blow (theory §4d): the bit's exact piecewise-linear ODE
on the branches of the bilinear rock law, its switches located as roots of exact pieces, its
loading episodes recorded, and the wave it reflects into the rod (the driver:
:mod:`impactbar.laws.rodrock._exactloop`)."""

from __future__ import annotations

import numba

from ..._shared.literals import plain_literals
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from ._exactnode import LOG_BIT, _crossing, _emit, _load, _log
from ._exactode import blk_ode1
from ._exactpieces import (  # the pieces' algebra, the crossings, the pool and the channels
    ELASTIC,
    EPS,
    FREE,
    LOAD,
    advance,
    blk_add_const,
    blk_axpy,
    blk_clear,
    blk_deriv,
    blk_eval,
    blk_integral_sq,
    blk_set_comb,
    blk_shift,
    window_break,
)
from ._records import (  # the records' slots
    B_E,
    B_IN,
    B_N,
    B_ODE,
    B_OUT,
    B_OUT2,
    B_RATE,
    B_X,
    B_XD,
    B_ZERO,
    BI_BRANCH,
    BI_NEP,
    BS_ABS,
    BS_DISS,
    BS_EPP,
    BS_EPT,
    BS_P,
    BS_PMAX,
    BS_PPERM,
    BS_RDP,
    BS_RMAX,
    BS_TPMAX,
    BS_W,
    BS_X,
    CI_DEG,
    CI_GIVEUP,
    CNT_FULL,
    CT_TLOAD,
    EP_DISS,
    EP_PEND,
    EP_PSTART,
    EP_TEND,
    EP_TSTART,
    NSI_IN,
    PR_FEED,
    PR_K,
    PR_KU,
    PR_LB,
    PR_MASS,
    PR_RECORD,
    PR_SEMI,
    PR_ZBIT,
    RC_FIRST,
    RC_SECOND,
    RT_FIRST,
    RT_SECOND,
)

#: Most switches of the bit's branches between two arrivals at the bit (each a located root); a bit
#: ringing on a stiff rock bounces on it (2 switches a bounce: 64 gave up there, its energy account
#: off by 7e-2, rod 4 long, k_u 4e5, bit mass 0.3); past it the search is given up (`uncertainty`)
MAX_BIT_SWITCHES = 1_000_000


@numba.njit(cache=CACHE, nogil=True)
def bit_solve(WB, WN, lam, PR, RT, RC, CI, br, x0, w0, L):
    """The bit's motion on branch ``br`` over ``[0, L]`` under the forcing ``E`` (block 6), from
    ``(x0, w0)``: ``x`` in block 7 and ``x'`` in block 8 (``Z x' + b x = E`` for a massless bit,
    ``m x'' + Z x' + b x = E`` else, ``b`` the branch's stiffness); returns whether a series was cut
    (the pieces then hold only on ``[0, L]``)."""
    m = PR[PR_MASS]
    if m == 0.0:
        blk_clear(WB[B_RATE], WN[B_RATE])
        blk_axpy(WB[B_RATE], WN[B_RATE], 1.0 / PR[PR_ZBIT], WB[B_E], WN[B_E])
        st, series = blk_ode1(WB[B_X], WN[B_X], WB[B_RATE], WN[B_RATE], lam, RC[br, RC_FIRST],
                              RT[br, RT_FIRST], x0 + 0.0j, L)
    else:
        r2 = RT[br, RT_SECOND]
        blk_clear(WB[B_RATE], WN[B_RATE])
        blk_axpy(WB[B_RATE], WN[B_RATE], 1.0 / m, WB[B_E], WN[B_E])
        st, s1 = blk_ode1(WB[B_ODE], WN[B_ODE], WB[B_RATE], WN[B_RATE], lam, RC[br, RC_FIRST],
                          RT[br, RT_FIRST], w0 - r2 * x0, L)
        st2, s2 = blk_ode1(WB[B_X], WN[B_X], WB[B_ODE], WN[B_ODE], lam, RC[br, RC_SECOND], r2, x0 + 0.0j, L)
        st += st2
        series = s1 or s2
    if st != 0:
        CI[CI_DEG] += 1
    blk_deriv(WB[B_XD], WN[B_XD], WB[B_X], WN[B_X], lam)
    return series


@numba.njit(cache=CACHE, nogil=True)
def _episode_end(EP, BS, BI, PR, CNT, CT, t, p):
    """The loading episode ending at ``t`` at the penetration ``p`` into ``EP`` (``CNT[CNT_FULL]``
    set where it has no room), counted in ``BI[BI_NEP]``."""
    n = BI[BI_NEP]
    if n < EP.shape[0]:
        EP[n, EP_TSTART] = BS[BS_EPT]
        EP[n, EP_TEND] = t
        EP[n, EP_PSTART] = BS[BS_EPP]
        EP[n, EP_PEND] = p
        k = PR[PR_K]
        EP[n, EP_DISS] = (1.0 - k / PR[PR_KU]) * k * (p - BS[BS_EPP]) * (p + BS[BS_EPP]) * 0.5
    else:
        CNT[CNT_FULL] = 1
    BI[BI_NEP] = n + 1
    CT[CT_TLOAD] = t


@numba.njit(cache=CACHE, nogil=True)
def bit_input(pool, CH_T, WB, WN, PR, NSI, J, a, t1):
    """The wave ``F`` arriving at the bit from ``a`` (block 0) and its forcing ``E = 2 F + f`` (block
    6): the end of that piece (at most ``t1``) and its validity."""
    PF, PI, TK, TC, CNT, CHI, lam, BIN = pool
    fch = 2 * (J - 1)
    cf, nb = advance(fch, a, CHI, CH_T, PF, PI)
    vf = _load(pool, CH_T, WB, WN, B_IN, fch, cf, a)
    NSI[J, NSI_IN] = cf
    blk_clear(WB[B_E], WN[B_E])
    blk_axpy(WB[B_E], WN[B_E], 2.0, WB[B_IN], WN[B_IN])
    blk_add_const(WB[B_E], WN[B_E], PR[PR_FEED])
    return window_break(nb, t1), vf


@numba.njit(cache=CACHE, nogil=True)
def node_bit(ws, t, t1):
    """The bit and the rock: ``m p'' + Z p' + R(p) = 2 F + f`` on the branches of the bilinear law,
    the reflected wave ``G = F - Z p'`` (absorbed on a semi-infinite rod)."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    pool = (PF, PI, TK, TC, CNT, CHI, lam, BIN)
    Lb = PR[PR_LB]
    J = SZ.size
    goch = 2 * J - 1
    hch = 3 * J + 1
    k = PR[PR_K]
    ku = PR[PR_KU]
    Z = PR[PR_ZBIT]
    semi = PR[PR_SEMI] != 0.0
    record = PR[PR_RECORD] != 0.0
    a = t
    while True:
        b, vf = bit_input(pool, CH_T, WB, WN, PR, NSI, J, a, t1)
        stall = 0  # switches at one instant (a chatter of the branches: given up past 64)
        switches = 0  # switches in this arrival interval: a bit ringing on a stiff rock bounces
        # thousands of times (2 switches a bounce; the bound only keeps a call's cost finite)
        turned = False  # unloaded at this very instant (a turning point)
        while True:
            br = BI[BI_BRANCH]
            x0 = BS[BS_X]
            w0 = BS[BS_W]
            L = b - a
            series = bit_solve(WB, WN, lam, PR, RT, RC, CI, br, x0, w0, L)
            valid = min(vf, a + L) if series else vf
            ref = 0.0 if br == LOAD else BS[BS_PPERM]
            # the first switch
            te = -1.0
            if br == LOAD:
                # unloading where the velocity turns negative beyond the rounding of the force
                # balance: at rest under the feed (E = k x) it is zero to rounding, and its sign
                # there (from x0 - E/k, an ulp of x0, times the branch's rates) unloaded and
                # reloaded the rock at once, each a spurious loading episode
                e0, _e1, _e2 = blk_eval(WB[B_E], WN[B_E], lam, 0.0)
                rmax = max(abs(RT[br, RT_FIRST]), abs(RT[br, RT_SECOND]))  # (RT_SECOND 0: a massless bit)
                tolv = 64.0 * EPS * (abs(x0) * rmax + abs(e0) / Z)
                blk_clear(WB[B_ZERO], WN[B_ZERO])
                blk_axpy(WB[B_ZERO], WN[B_ZERO], 1.0, WB[B_XD], WN[B_XD])
                blk_add_const(WB[B_ZERO], WN[B_ZERO], tolv)
                te = _crossing(WB, WN, lam, BIN, STK, CI, B_ZERO, L, a)
            elif br == ELASTIC:
                blk_clear(WB[B_ZERO], WN[B_ZERO])
                blk_axpy(WB[B_ZERO], WN[B_ZERO], -1.0, WB[B_X], WN[B_X])
                xtop = BS[BS_RMAX] / ku
                if turned:  # a reload within rounding of the turning point is none: the velocity,
                    # zero there, has rounding-level signs on the two branches (they chattered)
                    xtop += 4096.0 * EPS * abs(xtop)
                blk_add_const(WB[B_ZERO], WN[B_ZERO], xtop)
                t1a = _crossing(WB, WN, lam, BIN, STK, CI, B_ZERO, L, a)
                t2a = _crossing(WB, WN, lam, BIN, STK, CI, B_X, t1a if t1a >= 0.0 else L, a)
                nxt = -1
                if t2a >= 0.0 and (t1a < 0.0 or t2a <= t1a):
                    te = t2a
                    nxt = FREE
                elif t1a >= 0.0:
                    te = t1a
                    nxt = LOAD
            else:
                blk_clear(WB[B_ZERO], WN[B_ZERO])
                blk_axpy(WB[B_ZERO], WN[B_ZERO], -1.0, WB[B_X], WN[B_X])
                te = _crossing(WB, WN, lam, BIN, STK, CI, B_ZERO, L, a)
            # the reflected wave and the history
            if semi:
                blk_set_comb(WB[B_OUT2], WN[B_OUT2], 1.0, WB[B_IN], WN[B_IN], -Z, WB[B_XD], WN[B_XD])
                BS[BS_ABS] += blk_integral_sq(WB[B_OUT2], WN[B_OUT2], lam, 0.0, te if te >= 0.0 else L) / Z
                blk_clear(WB[B_OUT], WN[B_OUT])
            else:
                blk_set_comb(WB[B_OUT], WN[B_OUT], 1.0, WB[B_IN], WN[B_IN], -Z, WB[B_XD], WN[B_XD])
            if te != 0.0:
                if not _emit(pool, CH_TOL, WB, WN, Lb, goch, a, B_OUT, valid, 0, 0.0):
                    return False
                if record:
                    blk_clear(WB[B_N], WN[B_N])
                    blk_axpy(WB[B_N], WN[B_N], 1.0, WB[B_X], WN[B_X])
                    if not _emit(pool, CH_TOL, WB, WN, Lb, hch, a, B_N, valid, br, ref):
                        return False
            tt = L if te < 0.0 else te
            x1, w1, _ = blk_eval(WB[B_X], WN[B_X], lam, tt)
            # work on the rock over the piece
            if br == LOAD:
                x1 = max(x1, x0)
                if x1 > x0:  # (p_max, R_max and when first reached: as they were at rest)
                    BS[BS_RDP] += 0.5 * k * (x1 - x0) * (x1 + x0)
                    BS[BS_DISS] += 0.5 * (1.0 - k / ku) * k * (x1 - x0) * (x1 + x0)
                    BS[BS_PMAX] = x1
                    BS[BS_RMAX] = k * x1
                    BS[BS_PPERM] = x1 - BS[BS_RMAX] / ku
                    BS[BS_TPMAX] = a + tt
            elif br == ELASTIC:
                BS[BS_RDP] += 0.5 * ku * (x1 - x0) * (x1 + x0)
            if te < 0.0:
                BS[BS_X] = x1
                BS[BS_W] = w1
                BS[BS_P] = ref + x1
                break
            # a switch at a + te
            stall = stall + 1 if a + te == a else 0
            a += te
            switches += 1
            if stall > 64 or switches > MAX_BIT_SWITCHES:
                CI[CI_GIVEUP] += 1
                return True
            blk_shift(WB[B_IN], WN[B_IN], te, lam, BIN)
            blk_shift(WB[B_E], WN[B_E], te, lam, BIN)
            turned = br == LOAD
            pm = BS[BS_W]  # (a massless bit's: p' at the end of the last piece, logged)
            if br == LOAD:  # unloading from p_max (an episode that did not advance is none)
                if x1 > BS[BS_EPP]:
                    _episode_end(EP, BS, BI, PR, CNT, CT, a, x1)
                BI[BI_BRANCH] = ELASTIC
                BS[BS_X] = BS[BS_RMAX] / ku
                BS[BS_W] = 0.0  # the turning point (w1 is zero to rounding)
                BS[BS_P] = x1
            elif br == ELASTIC:
                if nxt == FREE:
                    BI[BI_BRANCH] = FREE
                    BS[BS_X] = 0.0
                    BS[BS_W] = w1
                    BS[BS_P] = BS[BS_PPERM]
                else:  # reloading at p_max
                    BI[BI_BRANCH] = LOAD
                    BS[BS_X] = BS[BS_PMAX]
                    BS[BS_W] = w1
                    BS[BS_P] = BS[BS_PMAX]
                    BS[BS_EPT] = a
                    BS[BS_EPP] = BS[BS_PMAX]
            else:  # touching the rock again
                BI[BI_BRANCH] = ELASTIC
                BS[BS_X] = 0.0
                BS[BS_W] = w1
                BS[BS_P] = BS[BS_PPERM]
            _log(RD, a, LOG_BIT + BI[BI_BRANCH], pm, 0.0, 0.0)
        if b >= t1:
            return True
        a = b

plain_literals(globals())  # one machine code per kernel for all constant arguments (a shorter compile)
internal_kernels(globals())  # only kernels call them: link-only
