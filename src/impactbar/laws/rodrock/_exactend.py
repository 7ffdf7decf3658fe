"""When the exact blow ends (theory §4d, "when a blow ends"): the energy account of piston, rod, bit
and rock at a time, and the certificate that no contact can happen again (the piston gone for good,
the bit lifted with the rod's waves unable to close the gap, or every wave energy spent), with
:func:`may_end`, a necessary condition of every end :func:`certify` finds, tested first so that the
energy pass runs only where an end is possible. The workspace's layout is
:mod:`impactbar.laws.rodrock._exactloop`'s."""

from __future__ import annotations

import math

import numba

from ..._shared.literals import plain_literals
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from ._exactpieces import (  # the pieces' algebra, the crossings, the pool and the channels
    ELASTIC,
    FREE,
    GOING,
    INF,
    LIFTED,
    LOAD,
    MAY_YIELD,
    SEPARATED,
    SPENT,
    blk_integral,
    blk_integral_sq,
    piece_span,
    pool_load,
)
from ._records import (  # the records' slots and the pool's columns
    B_AUX,
    BI_BRANCH,
    BS_P,
    BS_PPERM,
    BS_PSTART,
    BS_RMAX,
    BS_W,
    BS_X,
    CHI_HEAD,
    CI_WIN,
    CT_EP,
    CT_ER,
    CT_PP,
    CT_PR,
    CT_PSI,
    CT_TACC,
    CT_THR,
    NSF_GAP,
    NSF_SHANK,
    NSI_CONTACT,
    PF_INT,
    PF_INT2,
    PI_COUNT,
    PR_CBIT,
    PR_CP,
    PR_CROD,
    PR_CSHANK,
    PR_DRIVEN,
    PR_E0,
    PR_FEED,
    PR_K,
    PR_KU,
    PR_MASS,
    PR_MP,
    PR_MR,
    PR_NP,
    PR_SPENT,
    PR_TMAX,
)


@numba.njit(cache=CACHE, nogil=True)
def _cached_integrals(p, L, pool, B, N, first, second):
    """``int f`` (with ``first``) and ``int f^2`` (with ``second``) of the closed piece ``p`` over its
    whole span ``L``, each computed once (``PF[p, PF_INT]``, ``PF[p, PF_INT2]``, NaN until then)."""
    PF, PI, TK, TC, CNT, CHI, lam, BIN = pool
    one = first and math.isnan(PF[p, PF_INT])
    two = second and math.isnan(PF[p, PF_INT2])
    if one or two:
        pool_load(B, N, p, 0.0, lam, BIN, PI, TK, TC)
        if one:
            PF[p, PF_INT] = blk_integral(B, N, lam, 0.0, L)
        if two:
            PF[p, PF_INT2] = blk_integral_sq(B, N, lam, 0.0, L)


@numba.njit(cache=CACHE, nogil=True)
def _chan_sums(c, t, CH_T, pool, B, N, second):
    """``int f`` and, with ``second`` (else 0), ``int f^2`` over the wave now in the channel's segment
    (emitted in ``[t - T, t]``), a closed piece's whole integrals computed once (``PF[p, PF_INT]``,
    ``PF[p, PF_INT2]``);
    ``pool`` as :func:`emit`'s, ``B, N`` a scratch block."""
    PF, PI, TK, TC, CNT, CHI, lam, BIN = pool
    lo = t - CH_T[c]
    p = CHI[c, CHI_HEAD]
    s1 = 0.0
    s2 = 0.0
    while p >= 0:
        t0, nx, tend, a, b = piece_span(PF, PI, p, lo, t)
        if b > a and PI[p, PI_COUNT] > 0:
            if nx >= 0 and a == t0 and b == tend:  # the whole of a closed piece: computed once
                _cached_integrals(p, tend - t0, pool, B, N, True, second)
                s1 += PF[p, PF_INT]
                if second:
                    s2 += PF[p, PF_INT2]
            else:
                pool_load(B, N, p, 0.0, lam, BIN, PI, TK, TC)
                s1 += blk_integral(B, N, lam, a - t0, b - t0)
                if second:
                    s2 += blk_integral_sq(B, N, lam, a - t0, b - t0)
        if tend >= t:
            break
        p = nx
    return s1, s2


@numba.njit(cache=CACHE, nogil=True)
def chan_integrals(c, t, Z, CH_T, pool, B, N):
    """``int f`` and ``int f^2 / Z`` over the wave now in the channel's segment (emitted in
    ``[t - T, t]``); ``pool`` as :func:`emit`'s, ``B, N`` a scratch block."""
    s1, s2 = _chan_sums(c, t, CH_T, pool, B, N, True)
    return s1, s2 / Z


@numba.njit(cache=CACHE, nogil=True)
def chan_closed_sq(c, t, CH_T, pool, B, N, exact):
    """A lower bound of ``int f^2`` over the wave now in the channel's segment (emitted in
    ``[t - T, t]``): the closed pieces wholly in it (:func:`chan_integrals`' sum without its partial
    pieces at the segment's two ends), each by its ``int f^2`` where cached or ``exact`` (computed
    and cached as chan_integrals does), else by ``(int f)^2 / L`` (Cauchy-Schwarz; ``int f``
    cached, several times cheaper: no products of pairs of exponents)."""
    PF, PI, TK, TC, CNT, CHI, lam, BIN = pool
    lo = t - CH_T[c]
    p = CHI[c, CHI_HEAD]
    s2 = 0.0
    while p >= 0:
        t0, nx, tend, _, _ = piece_span(PF, PI, p, lo, t)
        if nx >= 0 and lo <= t0 < tend <= t and PI[p, PI_COUNT] > 0:
            L = tend - t0
            if exact or not math.isnan(PF[p, PF_INT2]):
                _cached_integrals(p, L, pool, B, N, False, True)
                s2 += PF[p, PF_INT2]
            else:
                _cached_integrals(p, L, pool, B, N, True, False)
                s2 += PF[p, PF_INT] * PF[p, PF_INT] / L
        if tend >= t:
            break
        p = nx
    return s2


@numba.njit(cache=CACHE, nogil=True)
def piece_momentum(CH_T, pool, WB, WN, c, t):
    """``int f`` over the wave now in channel ``c``'s segment."""
    momentum, _ = _chan_sums(c, t, CH_T, pool, WB[B_AUX], WN[B_AUX], False)
    return momentum


@numba.njit(cache=CACHE, nogil=True)
def _momentum(CH_T, pool, WB, WN, t, first, last):
    """The momentum of segments ``first`` to ``last`` (1-based) at ``t``: ``int (f - g)`` over
    their waves (:func:`piece_momentum`)."""
    P = 0.0
    for i in range(first, last + 1):
        P += (piece_momentum(CH_T, pool, WB, WN, 2 * (i - 1), t)
              - piece_momentum(CH_T, pool, WB, WN, 2 * i - 1, t))
    return P


@numba.njit(cache=CACHE, nogil=True)
def _bit_rock_energy(PR, BS, BI):
    """The terms of ``Psi`` besides the rod's waves: the bit's kinetic energy and the two potential
    terms of the rock and the feed above the static state under the feed (the second 0 with the bit
    on the rock), which :func:`account` and :func:`may_end` add in this order."""
    m = PR[PR_MASS]
    w = BS[BS_W]
    ku = PR[PR_KU]
    f = PR[PR_FEED]
    br = BI[BI_BRANCH]
    if br == FREE:
        return 0.5 * m * w * w, f * (BS[BS_PPERM] - BS[BS_P]), f * f / (2.0 * ku)
    R = PR[PR_K] * BS[BS_X] if br == LOAD else ku * BS[BS_X]
    return 0.5 * m * w * w, (R - f) * (R - f) / (2.0 * ku), 0.0


@numba.njit(cache=CACHE, nogil=True)
def account(ws, t):
    """Momenta and wave energies of the piston and the rod at ``t`` (into ``CT[CT_PP:CT_ER + 1]``),
    and ``Psi``, the energy of rod, bit and rock above the static state under the feed
    (``CT[CT_PSI]``), and the energy a new yield of the rock needs (``CT[CT_THR]``)."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    J = SZ.size
    n_p = int(PR[PR_NP])
    Pp = 0.0
    Ep = 0.0
    Pr = 0.0
    Er = 0.0
    for i in range(1, J + 1):
        Z = SZ[i - 1]
        pool = (PF, PI, TK, TC, CNT, CHI, lam, BIN)
        m1, e1 = chan_integrals(2 * (i - 1), t, Z, CH_T, pool, WB[B_AUX], WN[B_AUX])
        m2, e2 = chan_integrals(2 * i - 1, t, Z, CH_T, pool, WB[B_AUX], WN[B_AUX])
        if i <= n_p:
            Pp += m1 - m2
            Ep += e1 + e2
        else:
            Pr += m1 - m2
            Er += e1 + e2
    Pr += PR[PR_MASS] * BS[BS_W]
    ku = PR[PR_KU]
    f = PR[PR_FEED]
    kin, pot, pot_feed = _bit_rock_energy(PR, BS, BI)
    psi = Er + kin + pot + pot_feed
    CT[CT_PP] = Pp
    CT[CT_EP] = Ep
    CT[CT_PR] = Pr
    CT[CT_ER] = Er
    CT[CT_PSI] = psi
    CT[CT_THR] = (BS[BS_RMAX] - f) * (BS[BS_RMAX] - f) / (2.0 * ku)
    CT[CT_TACC] = t


@numba.njit(cache=CACHE, nogil=True)
def may_end(ws, t):
    """Whether :func:`certify` could find an end at ``t``, decided without its energy pass (most of
    a blow's cost). Its ends hold for an energy ``Psi`` of rod, bit and rock only below bounds
    (:func:`_could_end`), so none can where even a lower bound of ``Psi`` exceeds them: the bit's
    and the rock's energy with that of the rod's closed pieces in flight (the partial pieces at its
    segments' ends left out; each by ``(int f)^2 / L`` first, then by ``int f^2``, cached), added
    channel by channel until no end is possible, less 1e-9 of it for rounding. A necessary
    condition of every end :func:`certify` finds (its momenta are certify's to the bit): keep the
    two in step."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    pool = (PF, PI, TK, TC, CNT, CHI, lam, BIN)
    J = SZ.size
    n_p = int(PR[PR_NP])
    kin, pot, pot_feed = _bit_rock_energy(PR, BS, BI)
    psi = kin + pot + pot_feed
    m, w, ku, f, br = PR[PR_MASS], BS[BS_W], PR[PR_KU], PR[PR_FEED], BI[BI_BRANCH]
    # what certify's ends need besides Psi: the piston out of contact and not moving on (its
    # momentum), and without a feed whether the rod may fly free of the rock (the rod's momentum)
    gone = False
    vp = 0.0
    Pr = 1.0  # (> 0: the rod cannot fly free)
    if NSI[n_p, NSI_CONTACT] != 1:
        Pq = _momentum(CH_T, pool, WB, WN, t, 1, n_p)
        gone = Pq <= 0.0
        vp = Pq / PR[PR_MP]
        if gone and f == 0.0 and br == FREE and BS[BS_P] < BS[BS_PPERM]:
            Pr = _momentum(CH_T, pool, WB, WN, t, n_p + 1, J) + m * w
    xs = NSF[n_p, NSF_SHANK]
    avail = PR[PR_E0] + f * xs + f * f * (PR[PR_CROD] * 0.5 + 0.5 / ku)
    if not _could_end(psi, PR, BS, BI, NSF, avail, gone, vp, Pr):
        return False
    for exact in (False, True):  # the cheap bound of the pieces' energies first
        er = 0.0
        for c in range(2 * n_p, 2 * J):
            er += chan_closed_sq(c, t, CH_T, pool, WB[B_AUX], WN[B_AUX], exact) / SZ[c // 2]
            if not _could_end(psi + er, PR, BS, BI, NSF, avail, gone, vp, Pr):
                return False
    return True


@numba.njit(cache=CACHE, nogil=True)
def _could_end(psi, PR, BS, BI, NSF, avail, gone, vp, Pr):
    """Whether :func:`certify` could end the blow were ``Psi`` at least ``psi`` (less 1e-9 of it),
    its tests with that bound: ``SPENT`` needs ``Psi`` below twice the spent fraction of ``avail``;
    ``SEPARATED``, ``LIFTED`` and ``MAY_YIELD`` the piston out of contact and not moving on
    (``gone``) and the rock unable to yield (``Psi < thr``) or the rod flying free, or (with a
    feed) the rock not loading and no ``t_max``; without a feed the rod flying free (``Pr <= 0``
    and the bit held off the rock by more than the rod's internal motion can bring it back) ahead
    of the piston (``vp <= Pr / M_r``), or the piston's mean velocity ``vp`` at most
    ``-sqrt(2 Psi / M_r)``, and its struck end behind the shank's lowest reach. Non-increasing in
    ``psi``."""
    if not math.isfinite(psi):
        return True  # (overflowed pieces: certify's pass says so)
    psi = max(psi * (1.0 - 1e-9), 0.0)
    if psi <= 2.0 * PR[PR_SPENT] * avail:
        return True
    if not gone:
        return False
    f = PR[PR_FEED]
    br = BI[BI_BRANCH]
    thr = (BS[BS_RMAX] - f) * (BS[BS_RMAX] - f) / (2.0 * PR[PR_KU])
    if f > 0.0:
        return br != LOAD and (psi < thr or PR[PR_TMAX] == INF or PR[PR_DRIVEN] != 0.0)
    n_p = int(PR[PR_NP])
    xs = NSF[n_p, NSF_SHANK]
    xp = xs - NSF[n_p, NSF_GAP]
    Mr = PR[PR_MR]
    rod_free = False
    if br == FREE and Pr <= 0.0:
        eint = max(psi - 0.5 * Pr * Pr / Mr, 0.0)
        if (BS[BS_P] - BS[BS_PPERM]) + 2.0 * math.sqrt(2.0 * PR[PR_CBIT] * eint) < 0.0:
            rod_free = True
            if vp <= Pr / Mr and xp < xs - 2.0 * math.sqrt(2.0 * PR[PR_CSHANK] * eint):
                return True
    if not ((br != LOAD and psi < thr) or rod_free):
        return False
    if PR[PR_DRIVEN] != 0.0:  # under a drive: the piston gone once out of contact and moving back
        return True
    return vp <= -math.sqrt(2.0 * psi / Mr) and xp < xs - 2.0 * math.sqrt(2.0 * PR[PR_CSHANK] * psi)


@numba.njit(cache=CACHE, nogil=True)
def certify(ws, t):
    """Whether the blow has ended at ``t`` (an end code, or ``GOING``): the piston can never touch the
    shank again and the rock can never yield again (``SEPARATED``; ``LIFTED`` when the rod has left
    the rock for good too), or the energy that could still reach the rock is below the spent
    fraction of the energy available (``SPENT``). The bounds (theory §4d): the piston's struck end
    stays below ``x_p + 2 sqrt(2 C_p E_int)`` while its mean velocity is ``<= 0``; with a feed the
    shank stays above the static position less ``Delta(Psi)`` while the rock cannot yield
    (``Psi < (R_max - f)^2/(2 k_u)``), else above ``-Phi/f``; without one, the rod's mean velocity
    stays above ``-sqrt(2 Psi / M_r)``, or is constant once the rod flies free of the rock."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    pool = (PF, PI, TK, TC, CNT, CHI, lam, BIN)
    n_p = int(PR[PR_NP])
    # the energies cost a pass over every piece in flight: only when the piston may have gone, or
    # every 16 windows for the spent energy
    if CI[CI_WIN] % 16 != 0:
        if NSI[n_p, NSI_CONTACT] == 1:
            return GOING
        if _momentum(CH_T, pool, WB, WN, t, 1, n_p) > 0.0:
            return GOING
    if not may_end(ws, t):  # no end possible whatever the energies in flight: no energy pass
        return GOING
    account(ws, t)
    Pp, Ep, Pr, Er, psi, thr = CT[CT_PP], CT[CT_EP], CT[CT_PR], CT[CT_ER], CT[CT_PSI], CT[CT_THR]
    f = PR[PR_FEED]
    ku = PR[PR_KU]
    m = PR[PR_MASS]
    br = BI[BI_BRANCH]
    Mp = PR[PR_MP]
    Mr = PR[PR_MR]
    contact = NSI[n_p, NSI_CONTACT] == 1
    gap = NSF[n_p, NSF_GAP]
    xs = NSF[n_p, NSF_SHANK]
    avail = PR[PR_E0] + f * xs + f * f * (PR[PR_CROD] * 0.5 + 0.5 / ku)
    vp = Pp / Mp
    gone = False
    rod_free = False
    if not contact and vp <= 0.0:
        eint = max(Ep - 0.5 * Pp * Pp / Mp, 0.0)
        dp = 2.0 * math.sqrt(2.0 * PR[PR_CP] * eint)
        xp = xs - gap
        if f > 0.0:
            if br != LOAD and psi < thr:
                ctot = PR[PR_CROD] + 1.0 / ku
                xeq = BS[BS_PPERM] + f / ku - BS[BS_PSTART]
                if psi <= 0.5 * f * f * ctot:
                    delta = math.sqrt(2.0 * ctot * psi)
                else:
                    delta = f * ctot + (psi - 0.5 * f * f * ctot) / f
                bs = xeq - delta
            else:
                R = PR[PR_K] * BS[BS_X] if br == LOAD else (ku * BS[BS_X] if br == ELASTIC else 0.0)
                phi = Er + 0.5 * m * BS[BS_W] * BS[BS_W] - f * (BS[BS_P] - BS[BS_PSTART]) \
                    + 0.5 * f * f * PR[PR_CROD] \
                    + R * R / (2.0 * ku)
                bs = -phi / f
            gone = xp + dp < bs
        else:
            ekin = Er + 0.5 * m * BS[BS_W] * BS[BS_W]
            if br == FREE and Pr <= 0.0:
                eint_r = max(ekin - 0.5 * Pr * Pr / Mr, 0.0)
                db = 2.0 * math.sqrt(2.0 * PR[PR_CBIT] * eint_r)
                if (BS[BS_P] - BS[BS_PPERM]) + db < 0.0:
                    rod_free = True
                    ds = 2.0 * math.sqrt(2.0 * PR[PR_CSHANK] * eint_r)
                    if vp <= Pr / Mr and xp + dp < xs - ds:
                        gone = True
            if not gone:
                vmax = math.sqrt(2.0 * psi / Mr)
                if vp <= -vmax and xp + dp < xs - 2.0 * math.sqrt(2.0 * PR[PR_CSHANK] * psi):
                    gone = True
    if PR[PR_DRIVEN] != 0.0 and not contact and vp <= 0.0:  # under a drive: what the piston does next
        gone = True  # is the drive's (its flight's), whatever the rod's waves could reach
    frozen = (br != LOAD and psi < thr) or rod_free
    if gone and frozen:
        return LIFTED if rod_free else SEPARATED
    rem = psi if gone else psi + Ep
    if rem <= PR[PR_SPENT] * avail:
        return SPENT
    # the rock may yield to the ringing rod for ever (a caller's t_max: on to it, but under a drive the
    # piston's next touch is a new blow's, and the rod's ringing is dropped with it: an end)
    if gone and f > 0.0 and br != LOAD and (PR[PR_TMAX] == INF or PR[PR_DRIVEN] != 0.0):
        return MAY_YIELD
    return GOING


plain_literals(globals())  # one machine code per kernel for all constant arguments (a shorter compile)
internal_kernels(globals())  # kernels call them all (Python calls account through run): link-only
