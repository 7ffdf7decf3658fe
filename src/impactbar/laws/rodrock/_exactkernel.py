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
time units.) A series cut below rounding holds on ``[0, L]`` only: such pieces are marked valid up
to ``L`` and are never extended.

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

from ...dynamics.kernels import CACHE
from ._exactend import account, certify
from ._exactpieces import (  # the pieces' algebra, the crossings, the pool and the channels
    BUDGET,
    ELASTIC,
    EPS,
    FAILED,
    FREE,
    GOING,
    INF,
    LOAD,
    RINGS,
    TMAX,
    advance,
    blk_add_const,
    blk_axpy,
    blk_clear,
    blk_deriv,
    blk_eval,
    blk_integral,
    blk_integral_sq,
    blk_ode1,
    blk_set_comb,
    blk_shift,
    blk_value,
    emit,
    first_negative,
    load_input,
)

# ------------------------------------------------------------------------------------------------
# the workspace
# ------------------------------------------------------------------------------------------------
# ws = (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
#       RT, RC, RD, EP, CI, CT)
# PR: 0 k, 1 k_u, 2 m (0: massless), 3 feed, 4 Z at the bit, 5 H, 6 fixed horizon (run to t_max,
#     certify nothing), 7 semi-infinite rod,
#     8 Lb (time scale of pruning), 9 spent fraction, 10 E0, 11 rod's static compliance,
#     12 piston's compliance about its struck end, 13 rod's about the shank, 14 rod's about the bit,
#     15 piston's mass, 16 rod's mass with the bit's, 17 h (window), 18 t_max, 19 max windows,
#     20 p at the start, 21 contact node index, 22 driven, 23 record, 24 max pieces, 25 no drive
#     work (a tangent run)
# NSF (J + 1, 4): contact node: gap, shank displacement; NSI (J + 1, 4): used cursors (2), drive
#     cursor, contact flag
# BS: 0 p, 1 x (= p - ref), 2 w, 3 p_max, 4 R_max, 5 p_perm, 6 dissipated, 7 int R dp, 8 absorbed
#     (semi-infinite rod), 9 p at the start, 10 time of p_max, 11 episode start time, 12 episode
#     start p, 13 int G^2/Z spare, 14 the drive's work on the piston; BI: 0 branch, 1 episodes
# EP (cap, 5): episodes t_start, t_end, p_start, p_end, dissipated
# RD (1 + n, 6) complex: the switch log (the tangent run's schedule, :mod:`._exacttangent`), kept
#     only when it has more than its header row: RD[0, 0] the count, RD[0, 1] 1 once full; row i + 1:
#     time, code (LOG_SEP, LOG_RECON, LOG_BIT + the new branch) and, for a re-contact, the contact
#     force just after it, the jump of the shank's velocity and the gap's rate just before it; for
#     a separation the waves arriving just before it; for the bit, p' just before (a massless bit)
# CI: 0 status, 1 ended_by, 2 windows done, 3 (unused), 4 crossing searches given up, 5 separations,
#     6 re-contacts, 7 degree limit reached; CT: 0 time reached, 1 last separation, 2 last loading end,
#     3 piston momentum, 4 piston energy, 5 rod momentum, 6 rod wave energy, 7 Psi, 8 yield
#     threshold (3 to 8 by account), 9 the time of account's last pass


#: Most switches of the bit's branches between two arrivals at the bit (each a located root); a bit
#: ringing on a stiff rock bounces on it (2 switches a bounce: 64 gave up there, its energy account
#: off by 7e-2, rod 4 long, k_u 4e5, bit mass 0.3); past it the search is given up (`uncertainty`)
MAX_BIT_SWITCHES = 1_000_000

#: the switch log's codes (RD): the piston leaves the shank, touches it again, the bit's new branch
LOG_SEP, LOG_RECON, LOG_BIT = 1, 2, 10


@numba.njit(cache=CACHE, nogil=True)
def _log(RD, t, code, x1, x2, x3):
    """Append a switch at ``t`` to the log ``RD`` (nothing where it has only its header row)."""
    if RD.shape[0] <= 1:
        return
    n = int(RD[0, 0].real)
    if n + 1 >= RD.shape[0]:
        RD[0, 1] = 1.0
        return
    RD[n + 1, 0] = t
    RD[n + 1, 1] = code
    RD[n + 1, 2] = x1
    RD[n + 1, 3] = x2
    RD[n + 1, 4] = x3
    RD[0, 0] = n + 1


@numba.njit(cache=CACHE, nogil=True)
def _log_recontact(RD, t, f, g, gd, ZL, ZR):
    """Log a re-contact at ``t`` from the arriving waves ``f``, ``g`` and the gap's rate ``gd`` there:
    the contact force ``N`` just after, the jump of the shank's velocity (free ``-2 g/Z_R`` to welded
    ``(2 f - N)/Z_L``)."""
    if RD.shape[0] <= 1:
        return
    N = 2.0 * (ZR * f + ZL * g) / (ZL + ZR)
    _log(RD, t, LOG_RECON, N, (2.0 * f - N) / ZL + 2.0 * g / ZR, gd)


@numba.njit(cache=CACHE, nogil=True)
def _emit(ws, c, a, blk, valid, flag, ref):
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    return emit(c, a, WB[blk], WN[blk], valid, flag, ref, (PF, PI, TK, TC, CNT, CHI, lam, BIN), WB[10],
                WN[10], CH_TOL[c], PR[8])


@numba.njit(cache=CACHE, nogil=True)
def _load(ws, blk, c, piece, a):
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    return load_input(WB[blk], WN[blk], c, piece, a, CH_T, PF, PI, TK, TC, lam, BIN)


@numba.njit(cache=CACHE, nogil=True)
def _advance(ws, c, a):
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    return advance(c, a, CHI, CH_T, PF, PI)


@numba.njit(cache=CACHE, nogil=True)
def node_end(ws, t, t1):
    """The piston's far end: ``N = p(t)`` (the drive, or 0): ``f_out = p - g_in``."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    J = SZ.size
    driven = PR[22] != 0.0
    a = t
    while True:
        cg, nb = _advance(ws, 1, a)
        cd = -1
        nbd = INF
        if driven:
            cd, nbd = _advance(ws, 2 * J, a)
        if cg != NSI[0, 0] or cd != NSI[0, 2]:
            valid = _load(ws, 1, 1, cg, a)
            blk_clear(WB[2], WN[2])
            blk_axpy(WB[2], WN[2], -1.0, WB[1], WN[1])
            if driven:
                valid = min(valid, _load(ws, 0, 2 * J, cd, a))
                blk_axpy(WB[2], WN[2], 1.0, WB[0], WN[0])
            if not _emit(ws, 0, a, 2, valid, 0, 0.0):
                return False
            NSI[0, 0] = cg
            NSI[0, 2] = cd
        b = min(nb, nbd)
        if driven and PR[25] == 0.0:  # the drive's work int p v dt, v = (p - 2 g_in)/Z at the far end
            L = min(b, t1) - a
            if L > 0.0:
                _load(ws, 0, 2 * J, cd, a)
                _load(ws, 1, 1, cg, a)
                pp = blk_integral_sq(WB[0], WN[0], lam, 0.0, L)
                blk_set_comb(WB[3], WN[3], 1.0, WB[0], WN[0], 1.0, WB[1], WN[1])
                sp = blk_integral_sq(WB[3], WN[3], lam, 0.0, L)
                blk_set_comb(WB[3], WN[3], 1.0, WB[0], WN[0], -1.0, WB[1], WN[1])
                sm = blk_integral_sq(WB[3], WN[3], lam, 0.0, L)
                BS[14] += (pp - 0.5 * (sp - sm)) / SZ[0]
        if b >= t1:
            return True
        a = b


@numba.njit(cache=CACHE, nogil=True)
def node_junction(ws, j, t, t1):
    """A welded junction between segments ``j`` and ``j + 1``: ``N = 2 (Z_R f_in + Z_L g_in)/(Z_L + Z_R)``,
    ``f_out = N - g_in``, ``g_out = N - f_in``."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    J = SZ.size
    fch = 2 * (j - 1)
    gch = 2 * j + 1
    ZL = SZ[j - 1]
    ZR = SZ[j]
    s = ZL + ZR
    record = PR[23] != 0.0
    a = t
    while True:
        cf, nbf = _advance(ws, fch, a)
        cg, nbg = _advance(ws, gch, a)
        if cf != NSI[j, 0] or cg != NSI[j, 1]:
            valid = min(_load(ws, 0, fch, cf, a), _load(ws, 1, gch, cg, a))
            blk_set_comb(WB[2], WN[2], 2.0 * ZR / s, WB[0], WN[0], (ZL - ZR) / s, WB[1], WN[1])
            blk_set_comb(WB[3], WN[3], (ZR - ZL) / s, WB[0], WN[0], 2.0 * ZL / s, WB[1], WN[1])
            if record:
                blk_set_comb(WB[4], WN[4], 1.0, WB[0], WN[0], 1.0, WB[3], WN[3])
                if not _emit(ws, 2 * J + 1 + j, a, 4, valid, 0, 0.0):
                    return False
            if not _emit(ws, 2 * j, a, 2, valid, 0, 0.0):
                return False
            if not _emit(ws, 2 * j - 1, a, 3, valid, 0, 0.0):
                return False
            NSI[j, 0] = cf
            NSI[j, 1] = cg
        b = min(nbf, nbg)
        if b >= t1:
            return True
        a = b


@numba.njit(cache=CACHE, nogil=True)
def node_contact(ws, t, t1):
    """The piston's struck end and the shank: welded while the force is compressive; free ends
    (``f_out = -g_in``, ``g_out = -f_in``) while apart, the gap the integral of ``v_s - v_p``; contact
    resumes where the gap closes."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    SCR = (WB[13], WN[13], WB[14], WN[14], WB[15], WN[15])
    J = SZ.size
    j = int(PR[21])
    fch = 2 * (j - 1)
    gch = 2 * j + 1
    ZL = SZ[j - 1]
    ZR = SZ[j]
    s = ZL + ZR
    record = PR[23] != 0.0
    a = t
    dirty = False
    flips = 0
    while True:
        cf, nbf = _advance(ws, fch, a)
        cg, nbg = _advance(ws, gch, a)
        if cf != NSI[j, 0] or cg != NSI[j, 1]:
            dirty = True
            flips = 0
        b = min(nbf, nbg, t1)
        valid = min(_load(ws, 0, fch, cf, a), _load(ws, 1, gch, cg, a))
        L = b - a
        if NSI[j, 3] == 1:  # in contact
            blk_set_comb(WB[4], WN[4], 2.0 * ZR / s, WB[0], WN[0], 2.0 * ZL / s, WB[1], WN[1])
            ts = first_negative(WB[4], WN[4], lam, BIN, L, STK, SCR, a)
            if ts == -2.0:
                CI[4] += 1
                ts = -1.0
            if ts > 0.0 and a + ts == a:  # below the clock's resolution: at once (else no progress)
                ts = 0.0
            if ts == 0.0 and flips >= 2:
                ts = -1.0
            if ts == 0.0:
                NSI[j, 3] = 0
                NSF[j, 0] = 0.0
                dirty = True
                flips += 1
                CI[5] += 1
                CT[1] = a
                if RD.shape[0] > 1:  # the waves arriving just before (the pieces before a, if new)
                    fm = blk_value(WB[0], WN[0], lam, 0.0)
                    gm = blk_value(WB[1], WN[1], lam, 0.0)
                    if cf != NSI[j, 0] and NSI[j, 0] >= 0:
                        _load(ws, 12, fch, NSI[j, 0], a)
                        fm = blk_value(WB[12], WN[12], lam, 0.0)
                    if cg != NSI[j, 1] and NSI[j, 1] >= 0:
                        _load(ws, 12, gch, NSI[j, 1], a)
                        gm = blk_value(WB[12], WN[12], lam, 0.0)
                    _log(RD, a, LOG_SEP, fm, gm, 0.0)
                continue
            if dirty:
                blk_set_comb(WB[2], WN[2], 1.0, WB[4], WN[4], -1.0, WB[1], WN[1])
                blk_set_comb(WB[3], WN[3], 1.0, WB[4], WN[4], -1.0, WB[0], WN[0])
                if record and not _emit(ws, 2 * J + 1 + j, a, 4, valid, 0, 0.0):
                    return False
                if not _emit(ws, 2 * j, a, 2, valid, 0, 0.0):
                    return False
                if not _emit(ws, 2 * j - 1, a, 3, valid, 0, 0.0):
                    return False
                dirty = False
            te = L if ts < 0.0 else ts
            # the common velocity (2 f_in - N)/Z_L
            blk_set_comb(WB[5], WN[5], 2.0 / ZL, WB[0], WN[0], -1.0 / ZL, WB[4], WN[4])
            NSF[j, 1] += blk_integral(WB[5], WN[5], lam, 0.0, te)
            if ts > 0.0:
                if RD.shape[0] > 1:
                    _log(RD, a + ts, LOG_SEP, blk_value(WB[0], WN[0], lam, ts),
                         blk_value(WB[1], WN[1], lam, ts), 0.0)
                a += ts
                NSI[j, 3] = 0
                NSF[j, 0] = 0.0
                dirty = True
                flips = 1
                CI[5] += 1
                CT[1] = a
                NSI[j, 0] = cf
                NSI[j, 1] = cg
                continue
        else:
            # gap' = v_s - v_p = -2 g_in/Z_R - 2 f_in/Z_L
            blk_set_comb(WB[5], WN[5], -2.0 / ZL, WB[0], WN[0], -2.0 / ZR, WB[1], WN[1])
            st, gser = blk_ode1(WB[9], WN[9], WB[5], WN[5], lam, 0, 0.0j, NSF[j, 0] + 0.0j, L)
            if st != 0:
                CI[7] += 1
            tc = first_negative(WB[9], WN[9], lam, BIN, L, STK, SCR, a)
            if tc == -2.0:
                CI[4] += 1
                tc = -1.0
            if tc > 0.0 and a + tc == a:
                tc = 0.0
            if tc == 0.0 and flips >= 2:
                tc = -1.0
            if tc == 0.0:
                NSI[j, 3] = 1
                NSF[j, 0] = 0.0
                dirty = True
                flips += 1
                CI[6] += 1
                if RD.shape[0] > 1:
                    _log_recontact(RD, a, blk_value(WB[0], WN[0], lam, 0.0),
                                   blk_value(WB[1], WN[1], lam, 0.0), blk_value(WB[5], WN[5], lam, 0.0),
                                   ZL, ZR)
                continue
            if dirty:
                blk_clear(WB[2], WN[2])
                blk_axpy(WB[2], WN[2], -1.0, WB[1], WN[1])
                blk_clear(WB[3], WN[3])
                blk_axpy(WB[3], WN[3], -1.0, WB[0], WN[0])
                blk_clear(WB[4], WN[4])
                if record and not _emit(ws, 2 * J + 1 + j, a, 4, INF, 0, 0.0):
                    return False
                if not _emit(ws, 2 * j, a, 2, valid, 0, 0.0):
                    return False
                if not _emit(ws, 2 * j - 1, a, 3, valid, 0, 0.0):
                    return False
                dirty = False
            te = L if tc < 0.0 else tc
            NSF[j, 1] += -2.0 / ZR * blk_integral(WB[1], WN[1], lam, 0.0, te)
            if tc > 0.0:
                if RD.shape[0] > 1:
                    _log_recontact(RD, a + tc, blk_value(WB[0], WN[0], lam, tc),
                                   blk_value(WB[1], WN[1], lam, tc), blk_value(WB[5], WN[5], lam, tc),
                                   ZL, ZR)
                a += tc
                NSF[j, 0] = 0.0
                NSI[j, 3] = 1
                dirty = True
                flips = 1
                CI[6] += 1
                NSI[j, 0] = cf
                NSI[j, 1] = cg
                continue
            NSF[j, 0] = max(blk_value(WB[9], WN[9], lam, te), 0.0)
        NSI[j, 0] = cf
        NSI[j, 1] = cg
        if b >= t1:
            return True
        a = b


@numba.njit(cache=CACHE, nogil=True)
def bit_solve(ws, br, x0, w0, L):
    """The bit's motion on branch ``br`` over ``[0, L]`` under the forcing ``E`` (block 6), from
    ``(x0, w0)``: ``x`` in block 7 and ``x'`` in block 8 (``Z x' + b x = E`` for a massless bit,
    ``m x'' + Z x' + b x = E`` else, ``b`` the branch's stiffness); returns whether a series was cut
    (the pieces then hold only on ``[0, L]``)."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    m = PR[2]
    if m == 0.0:
        blk_clear(WB[5], WN[5])
        blk_axpy(WB[5], WN[5], 1.0 / PR[4], WB[6], WN[6])
        st, series = blk_ode1(WB[7], WN[7], WB[5], WN[5], lam, RC[br, 0], RT[br, 0], x0 + 0.0j, L)
    else:
        r2 = RT[br, 1]
        blk_clear(WB[5], WN[5])
        blk_axpy(WB[5], WN[5], 1.0 / m, WB[6], WN[6])
        st, s1 = blk_ode1(WB[11], WN[11], WB[5], WN[5], lam, RC[br, 0], RT[br, 0], w0 - r2 * x0, L)
        st2, s2 = blk_ode1(WB[7], WN[7], WB[11], WN[11], lam, RC[br, 1], r2, x0 + 0.0j, L)
        st += st2
        series = s1 or s2
    if st != 0:
        CI[7] += 1
    blk_deriv(WB[8], WN[8], WB[7], WN[7], lam)
    return series


@numba.njit(cache=CACHE, nogil=True)
def _episode_end(ws, t, p):
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    n = BI[1]
    if n < EP.shape[0]:
        EP[n, 0] = BS[11]
        EP[n, 1] = t
        EP[n, 2] = BS[12]
        EP[n, 3] = p
        k = PR[0]
        EP[n, 4] = (1.0 - k / PR[1]) * k * (p - BS[12]) * (p + BS[12]) * 0.5
    else:
        CNT[3] = 1
    BI[1] = n + 1
    CT[2] = t


@numba.njit(cache=CACHE, nogil=True)
def bit_input(ws, a, t1):
    """The wave ``F`` arriving at the bit from ``a`` (block 0) and its forcing ``E = 2 F + f`` (block
    6): the end of that piece (at most ``t1``) and its validity."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    J = SZ.size
    fch = 2 * (J - 1)
    cf, nb = _advance(ws, fch, a)
    vf = _load(ws, 0, fch, cf, a)
    NSI[J, 0] = cf
    blk_clear(WB[6], WN[6])
    blk_axpy(WB[6], WN[6], 2.0, WB[0], WN[0])
    blk_add_const(WB[6], WN[6], PR[3])
    return min(nb, t1), vf


@numba.njit(cache=CACHE, nogil=True)
def node_bit(ws, t, t1):
    """The bit and the rock: ``m p'' + Z p' + R(p) = 2 F + f`` on the branches of the bilinear law,
    the reflected wave ``G = F - Z p'`` (absorbed on a semi-infinite rod)."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    SCR = (WB[13], WN[13], WB[14], WN[14], WB[15], WN[15])
    J = SZ.size
    goch = 2 * J - 1
    hch = 3 * J + 1
    k = PR[0]
    ku = PR[1]
    Z = PR[4]
    semi = PR[7] != 0.0
    record = PR[23] != 0.0
    a = t
    while True:
        b, vf = bit_input(ws, a, t1)
        stall = 0  # switches at one instant (a chatter of the branches: given up past 64)
        switches = 0  # switches in this arrival interval: a bit ringing on a stiff rock bounces
        # thousands of times (2 switches a bounce; the bound only keeps a call's cost finite)
        turned = False  # unloaded at this very instant (a turning point)
        while True:
            br = BI[0]
            x0 = BS[1]
            w0 = BS[2]
            L = b - a
            series = bit_solve(ws, br, x0, w0, L)
            valid = min(vf, a + L) if series else vf
            ref = 0.0 if br == LOAD else BS[5]
            # the first switch
            te = -1.0
            if br == LOAD:
                # unloading where the velocity turns negative beyond the rounding of the force
                # balance: at rest under the feed (E = k x) it is zero to rounding, and its sign
                # there (from x0 - E/k, an ulp of x0, times the branch's rates) unloaded and
                # reloaded the rock at once, each a spurious loading episode
                e0, _e1, _e2 = blk_eval(WB[6], WN[6], lam, 0.0)
                rmax = max(abs(RT[br, 0]), abs(RT[br, 1]))  # (RT[br, 1] = 0: a massless bit)
                tolv = 64.0 * EPS * (abs(x0) * rmax + abs(e0) / Z)
                blk_clear(WB[9], WN[9])
                blk_axpy(WB[9], WN[9], 1.0, WB[8], WN[8])
                blk_add_const(WB[9], WN[9], tolv)
                te = first_negative(WB[9], WN[9], lam, BIN, L, STK, SCR, a)
            elif br == ELASTIC:
                blk_clear(WB[9], WN[9])
                blk_axpy(WB[9], WN[9], -1.0, WB[7], WN[7])
                xtop = BS[4] / ku
                if turned:  # a reload within rounding of the turning point is none: the velocity,
                    # zero there, has rounding-level signs on the two branches (they chattered)
                    xtop += 4096.0 * EPS * abs(xtop)
                blk_add_const(WB[9], WN[9], xtop)
                t1a = first_negative(WB[9], WN[9], lam, BIN, L, STK, SCR, a)
                if t1a == -2.0:
                    CI[4] += 1
                    t1a = -1.0
                t2a = first_negative(WB[7], WN[7], lam, BIN, t1a if t1a >= 0.0 else L, STK, SCR, a)
                if t2a == -2.0:
                    CI[4] += 1
                    t2a = -1.0
                nxt = -1
                if t2a >= 0.0 and (t1a < 0.0 or t2a <= t1a):
                    te = t2a
                    nxt = FREE
                elif t1a >= 0.0:
                    te = t1a
                    nxt = LOAD
            else:
                blk_clear(WB[9], WN[9])
                blk_axpy(WB[9], WN[9], -1.0, WB[7], WN[7])
                te = first_negative(WB[9], WN[9], lam, BIN, L, STK, SCR, a)
            if te == -2.0:
                CI[4] += 1
                te = -1.0
            # the reflected wave and the history
            if semi:
                blk_set_comb(WB[3], WN[3], 1.0, WB[0], WN[0], -Z, WB[8], WN[8])
                BS[8] += blk_integral_sq(WB[3], WN[3], lam, 0.0, te if te >= 0.0 else L) / Z
                blk_clear(WB[2], WN[2])
            else:
                blk_set_comb(WB[2], WN[2], 1.0, WB[0], WN[0], -Z, WB[8], WN[8])
            if te != 0.0:
                if not _emit(ws, goch, a, 2, valid, 0, 0.0):
                    return False
                if record:
                    blk_clear(WB[4], WN[4])
                    blk_axpy(WB[4], WN[4], 1.0, WB[7], WN[7])
                    if not _emit(ws, hch, a, 4, valid, br, ref):
                        return False
            tt = L if te < 0.0 else te
            x1, w1, _ = blk_eval(WB[7], WN[7], lam, tt)
            # work on the rock over the piece
            if br == LOAD:
                x1 = max(x1, x0)
                if x1 > x0:  # (p_max, R_max and when first reached: as they were at rest)
                    BS[7] += 0.5 * k * (x1 - x0) * (x1 + x0)
                    BS[6] += 0.5 * (1.0 - k / ku) * k * (x1 - x0) * (x1 + x0)
                    BS[3] = x1
                    BS[4] = k * x1
                    BS[5] = x1 - BS[4] / ku
                    BS[10] = a + tt
            elif br == ELASTIC:
                BS[7] += 0.5 * ku * (x1 - x0) * (x1 + x0)
            if te < 0.0:
                BS[1] = x1
                BS[2] = w1
                BS[0] = ref + x1
                break
            # a switch at a + te
            stall = stall + 1 if a + te == a else 0
            a += te
            switches += 1
            if stall > 64 or switches > MAX_BIT_SWITCHES:
                CI[4] += 1
                return True
            blk_shift(WB[0], WN[0], te, lam, BIN)
            blk_shift(WB[6], WN[6], te, lam, BIN)
            turned = br == LOAD
            pm = BS[2]  # (a massless bit's: p' at the end of the last piece, logged)
            if br == LOAD:  # unloading from p_max (an episode that did not advance is none)
                if x1 > BS[12]:
                    _episode_end(ws, a, x1)
                BI[0] = ELASTIC
                BS[1] = BS[4] / ku
                BS[2] = 0.0  # the turning point (w1 is zero to rounding)
                BS[0] = x1
            elif br == ELASTIC:
                if nxt == FREE:
                    BI[0] = FREE
                    BS[1] = 0.0
                    BS[2] = w1
                    BS[0] = BS[5]
                else:  # reloading at p_max
                    BI[0] = LOAD
                    BS[1] = BS[3]
                    BS[2] = w1
                    BS[0] = BS[3]
                    BS[11] = a
                    BS[12] = BS[3]
            else:  # touching the rock again
                BI[0] = ELASTIC
                BS[1] = 0.0
                BS[2] = w1
                BS[0] = BS[5]
            _log(RD, a, LOG_BIT + BI[0], pm, 0.0, 0.0)
        if b >= t1:
            return True
        a = b


@numba.njit(cache=CACHE, nogil=True)
def run(ws):
    """Window after window of length ``h`` (every node's inputs over a window left their source
    before it began) until the blow ends, ``t_max``, or the budget. ``CI[0]``: 0 done, 1 the pool is
    full (start again with a larger one)."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    J = SZ.size
    n_p = int(PR[21])
    h = PR[17]
    tmax = PR[18]
    maxp = PR[24]
    while True:
        w = CI[2]
        t = w * h
        if t >= tmax:
            CI[1] = TMAX
            account(ws, t)
            CI[0] = 0
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
        if not ok or CNT[3] != 0:
            CI[0] = 1
            return
        CI[2] = w + 1
        CT[0] = t1
        # a fixed horizon (the simulator's blow under a drive): on to t_max, nothing certified
        code = certify(ws, t1) if PR[6] == 0.0 else GOING
        if not (math.isfinite(BS[0]) and math.isfinite(CT[7])):  # overflowed pieces: stop, say so
            code = FAILED
        if code == GOING and t1 >= tmax:
            code = TMAX
        if code == GOING and (CNT[0] > maxp or CI[2] >= PR[19]):
            account(ws, t1)
            code = RINGS if (BI[0] != LOAD and CT[7] < CT[8]) else BUDGET
        if code != GOING:
            CI[1] = code
            CI[0] = 0
            return
