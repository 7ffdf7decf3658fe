"""The plumbing the exact blow's nodes share (theory §4d): the switch log, a block emitted into
or loaded from a wave channel, and a block's first crossing of zero (the driver and its nodes:
:mod:`impactbar.laws.rodrock._exactloop`; the bit and the rock: :mod:`._exactbit`)."""

from __future__ import annotations

import numba

from ..._shared.literals import plain_literals
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from ._exactpieces import (  # the pieces' algebra, the crossings, the pool and the channels
    emit,
    first_negative,
    load_input,
)
from ._records import (  # the records' slots
    B_EMIT,
    B_SCR1,
    B_SCR2,
    B_SCR3,
    CI_GIVEUP,
    RD_CODE,
    RD_FULL,
    RD_HEAD,
    RD_ROWS,
    RD_T,
    RD_V1,
    RD_V2,
    RD_V3,
)

#: the switch log's codes (RD): the piston leaves the shank, touches it again, the bit's new branch
LOG_SEP, LOG_RECON, LOG_BIT = 1, 2, 10


@numba.njit(cache=CACHE, nogil=True)
def _log(RD, t, code, x1, x2, x3):
    """Append a switch at ``t`` to the log ``RD`` (nothing where it has only its header row)."""
    if RD.shape[0] <= 1:
        return
    n = int(RD[RD_HEAD, RD_ROWS].real)
    if n + 1 >= RD.shape[0]:
        RD[RD_HEAD, RD_FULL] = 1.0
        return
    RD[n + 1, RD_T] = t
    RD[n + 1, RD_CODE] = code
    RD[n + 1, RD_V1] = x1
    RD[n + 1, RD_V2] = x2
    RD[n + 1, RD_V3] = x3
    RD[RD_HEAD, RD_ROWS] = n + 1


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
def _emit(pool, CH_TOL, WB, WN, Lb, c, a, blk, valid, flag, ref):
    """Emit block ``blk`` into channel ``c`` from ``a`` (:func:`emit`, its scratch the block
    ``B_EMIT``, pruned on the time scale ``Lb``): whether it found room."""
    return emit(c, a, WB[blk], WN[blk], valid, flag, ref, pool, WB[B_EMIT], WN[B_EMIT], CH_TOL[c], Lb)


@numba.njit(cache=CACHE, nogil=True)
def _load(pool, CH_T, WB, WN, blk, c, piece, a):
    """Load piece ``piece`` of channel ``c``, shifted to ``a``, into block ``blk``
    (:func:`load_input`): its validity."""
    PF, PI, TK, TC, CNT, CHI, lam, BIN = pool
    return load_input(WB[blk], WN[blk], c, piece, a, CH_T, PF, PI, TK, TC, lam, BIN)


@numba.njit(cache=CACHE, nogil=True)
def _crossing(WB, WN, lam, BIN, STK, CI, blk, L, a):
    """Where block ``blk`` first turns negative in ``[0, L]`` (:func:`first_negative`, the clock at
    ``a``; -1: nowhere), a search given up (-2) counted in ``CI[CI_GIVEUP]`` and read as none."""
    SCR = (WB[B_SCR1], WN[B_SCR1], WB[B_SCR2], WN[B_SCR2], WB[B_SCR3], WN[B_SCR3])
    tc = first_negative(WB[blk], WN[blk], lam, BIN, L, STK, SCR, a)
    if tc == -2.0:
        CI[CI_GIVEUP] += 1
        tc = -1.0
    return tc

plain_literals(globals())  # one machine code per kernel for all constant arguments (a shorter compile)
internal_kernels(globals())  # only kernels call them: link-only
