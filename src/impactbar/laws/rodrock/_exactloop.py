"""Compiled core of the exact blow (theory §4d): waves on a chain of uniform segments carried as exact
pieces, the junctions algebraic, the piston-shank contact unilateral, the bit and the rock an exact
piecewise-linear ODE; every switch a root of an exact piece (:mod:`impactbar.laws.rodrock.exact`).

**Pieces.** Every signal (a travelling force wave at the end of a segment, as a function of the time
it leaves that end; a node's force; the bit's penetration) is a chain of pieces; a piece starting at
``t0`` is

    phi(t0 + tau) = Re sum_e exp(lam_e tau) sum_d c_ed tau^d,      0 <= tau < length,

with ``lam_e`` from a short table of exponents (0, the bit's characteristic roots on each branch of
the rock, the exponents of the data) and complex ``c``; conjugate exponents are separate entries,
so the sum is real.

**The bit's equation without cancellation.** ``y' - r y = g`` is solved on each sub-interval
``[0, L]`` (``L`` known when it is solved: up to the next arrival, event or window end): a forcing
exponent ``lam_e`` farther than ``NEAR / L`` from ``r`` by back-substitution of the particular
solution (its chain contracts there); a nearer one, and ``r`` itself, by the Taylor recursion of the
initial-value problem, which divides by nothing: the particular solution's
``(e^{lam tau} - e^{r tau}) / (lam - r)`` never appears as two large cancelling terms. (Written that
way, a transient reflected at the bit again and again grows in its coefficients though not in its
value, and rounding grows with it: measured, the energy account of a ringing rod lost 1e-2 in 20
time units.) A pair whose series would pass ``SERIES_MAX`` (a stiff rock's exponent on a
piece of a few ``Z/k_u``) is solved by back-substitution: its coefficients, divided by
``|lam_e - r|``, are small (:func:`series_fits`). A series cut below rounding holds on ``[0, L]``
only: such pieces are marked valid up to ``L`` and are never extended.

**Blocks.** Pieces are computed in dense scratch blocks ``B[e, d]`` with ``N[e]`` the used count
of coefficients of exponent ``e`` (entries past ``N[e]`` are zero) and stored, pruned of terms below
``tol_abs`` on the blow's time scale, in a pool (``PF``, ``PI``, ``TK``, ``TC``).

**Crossings.** The first ``tau`` in ``(0, L]`` at which a piece turns negative is found by branch and
bound: a Lipschitz bound of the piece's derivative, from its terms, excludes a subinterval where
the piece cannot reach zero; a bound of the second derivative proves a bracket monotone, and
safeguarded Newton steps (the exact derivative) refine the root to rounding. A piece that starts at
zero (a separation, an unloading) is left by its first non-vanishing derivative, and a cubic
Taylor bound excludes its start.
"""

from __future__ import annotations

import math

import numba

from ..._shared.literals import plain_literals
from ..._shared.twinops import checkpoint
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from ._exactbit import node_bit
from ._exactend import account, certify
from ._exactnode import LOG_SEP, _crossing, _emit, _load, _log, _log_recontact
from ._exactode import blk_ode1
from ._exactpieces import (  # the pieces' algebra, the crossings, the pool and the channels
    BUDGET,
    FAILED,
    GOING,
    INF,
    LOAD,
    RINGS,
    TMAX,
    advance,
    blk_axpy,
    blk_clear,
    blk_integral,
    blk_integral_sq,
    blk_set_comb,
    blk_value,
    window_break,
)
from ._records import (  # the records' slots
    B_AUX,
    B_IN,
    B_IN2,
    B_N,
    B_OUT,
    B_OUT2,
    B_RATE,
    B_ZERO,
    BI_BRANCH,
    BS_DRIVEW,
    BS_P,
    CH_FAR_IN,
    CH_FAR_OUT,
    CI_DEG,
    CI_END,
    CI_RECON,
    CI_SEP,
    CI_STATUS,
    CI_WIN,
    CNT_FULL,
    CNT_PIECES,
    CT_PSI,
    CT_T,
    CT_THR,
    CT_TSEP,
    E_CONST,
    NSF_GAP,
    NSF_SHANK,
    NSI_CONTACT,
    NSI_DRIVE,
    NSI_IN,
    NSI_IN2,
    PR_DRIVEN,
    PR_FIXED,
    PR_LB,
    PR_MAXP,
    PR_MAXWIN,
    PR_NODW,
    PR_NP,
    PR_RECORD,
    PR_TMAX,
    PR_WINDOW,
    SEG_FAR,
)

# ------------------------------------------------------------------------------------------------
# the workspace
# ------------------------------------------------------------------------------------------------
# ws = (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
#       RT, RC, RD, EP, CI, CT), its positions WS_* in :mod:`._records`
# the records PR, BS, BI, CI, CT, CNT, the blocks WB, WN and the tables NSF, NSI (the nodes), EP (the
#     loading episodes), RT, RC (the roots), STK and RD: their slots and columns are named, and said,
#     in :mod:`._records`; RD, the switch log (the tangent run's schedule, :mod:`._exacttangent`), is
#     kept only when it has more than its header row, a switch a row (codes LOG_SEP, LOG_RECON,
#     LOG_BIT + the new branch)


@numba.njit(cache=CACHE, nogil=True)
def node_end(ws, t, t1):
    """The piston's far end: ``N = p(t)`` (the drive, or 0): ``f_out = p - g_in``."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    pool = (PF, PI, TK, TC, CNT, CHI, lam, BIN)
    Lb = PR[PR_LB]
    J = SZ.size
    driven = PR[PR_DRIVEN] != 0.0
    a = t
    while True:
        cg, nb = advance(CH_FAR_IN, a, CHI, CH_T, PF, PI)
        cd = -1
        nbd = INF
        if driven:
            cd, nbd = advance(2 * J, a, CHI, CH_T, PF, PI)
        if cg != NSI[0, NSI_IN] or cd != NSI[0, NSI_DRIVE]:
            valid = _load(pool, CH_T, WB, WN, B_IN2, CH_FAR_IN, cg, a)
            blk_clear(WB[B_OUT], WN[B_OUT])
            blk_axpy(WB[B_OUT], WN[B_OUT], -1.0, WB[B_IN2], WN[B_IN2])
            if driven:
                valid = min(valid, _load(pool, CH_T, WB, WN, B_IN, 2 * J, cd, a))
                blk_axpy(WB[B_OUT], WN[B_OUT], 1.0, WB[B_IN], WN[B_IN])
            if not _emit(pool, CH_TOL, WB, WN, Lb, CH_FAR_OUT, a, B_OUT, valid, 0, 0.0):
                return False
            NSI[0, NSI_IN] = cg
            NSI[0, NSI_DRIVE] = cd
        b = window_break(min(nb, nbd), t1)
        if driven and PR[PR_NODW] == 0.0:  # the drive's work int p v dt, v = (p - 2 g_in)/Z at the far end
            L = min(b, t1) - a
            if L > 0.0:
                _load(pool, CH_T, WB, WN, B_IN, 2 * J, cd, a)
                _load(pool, CH_T, WB, WN, B_IN2, CH_FAR_IN, cg, a)
                pp = blk_integral_sq(WB[B_IN], WN[B_IN], lam, 0.0, L)
                blk_set_comb(WB[B_OUT2], WN[B_OUT2], 1.0, WB[B_IN], WN[B_IN], 1.0, WB[B_IN2], WN[B_IN2])
                sp = blk_integral_sq(WB[B_OUT2], WN[B_OUT2], lam, 0.0, L)
                blk_set_comb(WB[B_OUT2], WN[B_OUT2], 1.0, WB[B_IN], WN[B_IN], -1.0, WB[B_IN2], WN[B_IN2])
                sm = blk_integral_sq(WB[B_OUT2], WN[B_OUT2], lam, 0.0, L)
                BS[BS_DRIVEW] += (pp - 0.5 * (sp - sm)) / SZ[SEG_FAR]
        if b >= t1:
            return True
        a = b


@numba.njit(cache=CACHE, nogil=True)
def node_junction(ws, j, t, t1):
    """A welded junction between segments ``j`` and ``j + 1``: ``N = 2 (Z_R f_in + Z_L g_in)/(Z_L + Z_R)``,
    ``f_out = N - g_in``, ``g_out = N - f_in``."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    pool = (PF, PI, TK, TC, CNT, CHI, lam, BIN)
    Lb = PR[PR_LB]
    J = SZ.size
    fch = 2 * (j - 1)
    gch = 2 * j + 1
    ZL = SZ[j - 1]
    ZR = SZ[j]
    s = ZL + ZR
    record = PR[PR_RECORD] != 0.0
    a = t
    while True:
        cf, nbf = advance(fch, a, CHI, CH_T, PF, PI)
        cg, nbg = advance(gch, a, CHI, CH_T, PF, PI)
        if cf != NSI[j, NSI_IN] or cg != NSI[j, NSI_IN2]:
            valid = min(_load(pool, CH_T, WB, WN, B_IN, fch, cf, a),
                        _load(pool, CH_T, WB, WN, B_IN2, gch, cg, a))
            blk_set_comb(WB[B_OUT], WN[B_OUT], 2.0 * ZR / s, WB[B_IN], WN[B_IN], (ZL - ZR) / s, WB[B_IN2],
                         WN[B_IN2])
            blk_set_comb(WB[B_OUT2], WN[B_OUT2], (ZR - ZL) / s, WB[B_IN], WN[B_IN], 2.0 * ZL / s, WB[B_IN2],
                         WN[B_IN2])
            if record:
                blk_set_comb(WB[B_N], WN[B_N], 1.0, WB[B_IN], WN[B_IN], 1.0, WB[B_OUT2], WN[B_OUT2])
                if not _emit(pool, CH_TOL, WB, WN, Lb, 2 * J + 1 + j, a, B_N, valid, 0, 0.0):
                    return False
            if not _emit(pool, CH_TOL, WB, WN, Lb, 2 * j, a, B_OUT, valid, 0, 0.0):
                return False
            if not _emit(pool, CH_TOL, WB, WN, Lb, 2 * j - 1, a, B_OUT2, valid, 0, 0.0):
                return False
            NSI[j, NSI_IN] = cf
            NSI[j, NSI_IN2] = cg
        b = window_break(min(nbf, nbg), t1)
        if b >= t1:
            return True
        a = b


@numba.njit(cache=CACHE, nogil=True)
def _contact_switch(WB, WN, lam, BIN, STK, CI, blk, L, a, flips):
    """The contact's next switch: :func:`_crossing` of block ``blk`` (the weld's force, or the gap),
    at once (0) where below the clock's resolution (else no progress), none (-1) where it would be
    the third switch at once in a row (a chatter)."""
    tc = _crossing(WB, WN, lam, BIN, STK, CI, blk, L, a)
    if tc > 0.0 and a + tc == a:  # below the clock's resolution: at once (else no progress)
        tc = 0.0
    if tc == 0.0 and flips >= 2:
        tc = -1.0
    return tc


@numba.njit(cache=CACHE, nogil=True)
def contact_node(PR, SZ):
    """The piston-shank node: ``(j, fch, gch, ZL, ZR, s)``, its segment boundary ``j`` (the piston's
    segments), the channels of the wave arriving from the piston and from the shank, their
    impedances and ``ZL + ZR``."""
    j = int(PR[PR_NP])
    ZL = SZ[j - 1]
    ZR = SZ[j]
    return j, 2 * (j - 1), 2 * j + 1, ZL, ZR, ZL + ZR


@numba.njit(cache=CACHE, nogil=True)
def contact_emit(pool, CH_TOL, WB, WN, Lb, j, hch, a, valid, welded, record, valid_n):
    """The waves the piston-shank node ``j`` sends from ``a`` on, from those arriving (``B_IN`` from
    the piston, ``B_IN2`` from the shank): welded, ``N - g_in`` into the shank and ``N - f_in`` into
    the piston with the force ``N`` in ``B_N``; apart, ``-g_in`` and ``-f_in``. With ``record`` the
    force ``B_N`` first into the node's history channel (valid to ``valid_n``). Returns whether
    every emission found room (:func:`_emit`)."""
    if welded:
        blk_set_comb(WB[B_OUT], WN[B_OUT], 1.0, WB[B_N], WN[B_N], -1.0, WB[B_IN2], WN[B_IN2])
        blk_set_comb(WB[B_OUT2], WN[B_OUT2], 1.0, WB[B_N], WN[B_N], -1.0, WB[B_IN], WN[B_IN])
    else:
        blk_clear(WB[B_OUT], WN[B_OUT])
        blk_axpy(WB[B_OUT], WN[B_OUT], -1.0, WB[B_IN2], WN[B_IN2])
        blk_clear(WB[B_OUT2], WN[B_OUT2])
        blk_axpy(WB[B_OUT2], WN[B_OUT2], -1.0, WB[B_IN], WN[B_IN])
    if record and not _emit(pool, CH_TOL, WB, WN, Lb, hch, a, B_N, valid_n, 0, 0.0):
        return False
    return (_emit(pool, CH_TOL, WB, WN, Lb, 2 * j, a, B_OUT, valid, 0, 0.0)
            and _emit(pool, CH_TOL, WB, WN, Lb, 2 * j - 1, a, B_OUT2, valid, 0, 0.0))


@numba.njit(cache=CACHE, nogil=True)
def _contact_flip(NSF, NSI, CI, CT, j, a, welded):
    """The piston-shank node ``j`` switching at ``a``: welded again (a re-contact, counted in
    ``CI[CI_RECON]``) or apart (a separation, counted in ``CI[CI_SEP]``, its time in
    ``CT[CT_TSEP]``), the gap set to 0."""
    NSI[j, NSI_CONTACT] = 1 if welded else 0
    NSF[j, NSF_GAP] = 0.0
    if welded:
        CI[CI_RECON] += 1
    else:
        CI[CI_SEP] += 1
        CT[CT_TSEP] = a


@numba.njit(cache=CACHE, nogil=True)
def node_contact(ws, t, t1):
    """The piston's struck end and the shank: welded while the force is compressive; free ends
    (``f_out = -g_in``, ``g_out = -f_in``) while apart, the gap the integral of ``v_s - v_p``; contact
    resumes where the gap closes."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    pool = (PF, PI, TK, TC, CNT, CHI, lam, BIN)
    Lb = PR[PR_LB]
    j, fch, gch, ZL, ZR, s = contact_node(PR, SZ)
    hch = 2 * SZ.size + 1 + j  # the node's force history
    record = PR[PR_RECORD] != 0.0
    a = t
    dirty = False
    flips = 0
    while True:
        cf, nbf = advance(fch, a, CHI, CH_T, PF, PI)
        cg, nbg = advance(gch, a, CHI, CH_T, PF, PI)
        if cf != NSI[j, NSI_IN] or cg != NSI[j, NSI_IN2]:
            dirty = True
            flips = 0
        b = window_break(min(nbf, nbg), t1)
        valid = min(_load(pool, CH_T, WB, WN, B_IN, fch, cf, a),
                    _load(pool, CH_T, WB, WN, B_IN2, gch, cg, a))
        L = b - a
        welded = NSI[j, NSI_CONTACT] == 1
        if welded:  # in contact
            blk_set_comb(WB[B_N], WN[B_N], 2.0 * ZR / s, WB[B_IN], WN[B_IN], 2.0 * ZL / s, WB[B_IN2],
                         WN[B_IN2])
            ts = _contact_switch(WB, WN, lam, BIN, STK, CI, B_N, L, a, flips)
            if ts == 0.0:
                _contact_flip(NSF, NSI, CI, CT, j, a, False)
                dirty = True
                flips += 1
                if RD.shape[0] > 1:  # the waves arriving just before (the pieces before a, if new)
                    fm = blk_value(WB[B_IN], WN[B_IN], lam, 0.0)
                    gm = blk_value(WB[B_IN2], WN[B_IN2], lam, 0.0)
                    if cf != NSI[j, NSI_IN] and NSI[j, NSI_IN] >= 0:
                        _load(pool, CH_T, WB, WN, B_AUX, fch, NSI[j, NSI_IN], a)
                        fm = blk_value(WB[B_AUX], WN[B_AUX], lam, 0.0)
                    if cg != NSI[j, NSI_IN2] and NSI[j, NSI_IN2] >= 0:
                        _load(pool, CH_T, WB, WN, B_AUX, gch, NSI[j, NSI_IN2], a)
                        gm = blk_value(WB[B_AUX], WN[B_AUX], lam, 0.0)
                    _log(RD, a, LOG_SEP, fm, gm, 0.0)
                continue
            if dirty:
                if not contact_emit(pool, CH_TOL, WB, WN, Lb, j, hch, a, valid, True, record, valid):
                    return False
                dirty = False
            te = L if ts < 0.0 else ts
            # the common velocity (2 f_in - N)/Z_L
            blk_set_comb(WB[B_RATE], WN[B_RATE], 2.0 / ZL, WB[B_IN], WN[B_IN], -1.0 / ZL, WB[B_N], WN[B_N])
            NSF[j, NSF_SHANK] += blk_integral(WB[B_RATE], WN[B_RATE], lam, 0.0, te)
        else:
            # gap' = v_s - v_p = -2 g_in/Z_R - 2 f_in/Z_L
            blk_set_comb(WB[B_RATE], WN[B_RATE], -2.0 / ZL, WB[B_IN], WN[B_IN], -2.0 / ZR, WB[B_IN2],
                         WN[B_IN2])
            st, gser = blk_ode1(WB[B_ZERO], WN[B_ZERO], WB[B_RATE], WN[B_RATE], lam, E_CONST, 0.0j,
                                NSF[j, NSF_GAP] + 0.0j, L)
            if st != 0:
                CI[CI_DEG] += 1
            ts = _contact_switch(WB, WN, lam, BIN, STK, CI, B_ZERO, L, a, flips)
            if ts == 0.0:
                _contact_flip(NSF, NSI, CI, CT, j, a, True)
                dirty = True
                flips += 1
                if RD.shape[0] > 1:
                    _log_recontact(RD, a, blk_value(WB[B_IN], WN[B_IN], lam, 0.0),
                                   blk_value(WB[B_IN2], WN[B_IN2], lam, 0.0),
                                   blk_value(WB[B_RATE], WN[B_RATE], lam, 0.0),
                                   ZL, ZR)
                continue
            if dirty:
                blk_clear(WB[B_N], WN[B_N])  # (apart: no force; the outputs do not read it)
                if not contact_emit(pool, CH_TOL, WB, WN, Lb, j, hch, a, valid, False, record, INF):
                    return False
                dirty = False
            te = L if ts < 0.0 else ts
            NSF[j, NSF_SHANK] += -2.0 / ZR * blk_integral(WB[B_IN2], WN[B_IN2], lam, 0.0, te)
        if ts > 0.0:  # the switch inside the piece: a separation, or a re-contact
            if RD.shape[0] > 1:
                fv = blk_value(WB[B_IN], WN[B_IN], lam, ts)
                gv = blk_value(WB[B_IN2], WN[B_IN2], lam, ts)
                if welded:
                    _log(RD, a + ts, LOG_SEP, fv, gv, 0.0)
                else:
                    _log_recontact(RD, a + ts, fv, gv, blk_value(WB[B_RATE], WN[B_RATE], lam, ts), ZL, ZR)
            a += ts
            _contact_flip(NSF, NSI, CI, CT, j, a, not welded)
            dirty = True
            flips = 1
            NSI[j, NSI_IN] = cf
            NSI[j, NSI_IN2] = cg
            continue
        if not welded:
            NSF[j, NSF_GAP] = max(blk_value(WB[B_ZERO], WN[B_ZERO], lam, te), 0.0)
        NSI[j, NSI_IN] = cf
        NSI[j, NSI_IN2] = cg
        if b >= t1:
            return True
        a = b


@numba.njit(cache=CACHE, nogil=True)
def run(ws, t_account):
    """Window after window of length ``h`` (every node's inputs over a window left their source
    before it began) until the blow ends, ``t_max``, or the budget. ``CI[CI_STATUS]``: 0 done, 1 the pool is
    full (start again with a larger one). With ``t_account >= 0`` only :func:`account` at that time
    (Python's call of it: its machine code is ``run``'s, its kernel link-only); ``-1`` for the run."""
    if t_account >= 0.0:
        account(ws, t_account)
        return
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    J = SZ.size
    n_p = int(PR[PR_NP])
    h = PR[PR_WINDOW]
    tmax = PR[PR_TMAX]
    maxp = PR[PR_MAXP]
    while True:
        checkpoint()  # (compiled: nothing; its twin: abandoned here once past its budget)
        w = CI[CI_WIN]
        t = w * h
        if t >= tmax:
            CI[CI_END] = TMAX
            account(ws, t)
            CI[CI_STATUS] = 0
            return
        t1 = min((w + 1) * h, tmax)
        ok = node_end(ws, t, t1)
        for j in range(1, J):
            if not ok:
                break
            if j == n_p:
                ok = node_contact(ws, t, t1)
            else:
                ok = node_junction(ws, j, t, t1)
        if ok:
            ok = node_bit(ws, t, t1)
        if not ok or CNT[CNT_FULL] != 0:
            CI[CI_STATUS] = 1
            return
        CI[CI_WIN] = w + 1
        CT[CT_T] = t1
        # a fixed horizon (the simulator's blow under a drive): on to t_max, nothing certified
        code = certify(ws, t1) if PR[PR_FIXED] == 0.0 else GOING
        if not (math.isfinite(BS[BS_P]) and math.isfinite(CT[CT_PSI])):  # overflowed pieces: stop, say so
            code = FAILED
        if code == GOING and t1 >= tmax:
            code = TMAX
        if code == GOING and (CNT[CNT_PIECES] > maxp or CI[CI_WIN] >= PR[PR_MAXWIN]):
            account(ws, t1)
            code = RINGS if (BI[BI_BRANCH] != LOAD and CT[CT_PSI] < CT[CT_THR]) else BUDGET
        if code != GOING:
            CI[CI_END] = code
            CI[CI_STATUS] = 0
            return


plain_literals(globals())  # one machine code per kernel for all constant arguments (a shorter compile)
# the kernels Python calls keep their wrapper and cache entry; the others are link-only (for kernels)
internal_kernels(globals(), python=("run",))
