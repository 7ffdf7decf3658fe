"""Compiled tangent run of the exact blow (theory §4d, "the exact blow's Jacobian"): the derivative of
the blow's end state along a direction of its data, exact.

Between its switches the blow is linear in its data: the junctions and the piston-shank weld are
algebraic, the free ends reflect, the bit obeys a linear equation on each branch of the rock. So the
derivative of every wave along a direction of the data (the piston's modal state at impact, the
drive) is the same chain run on the direction's waves with the switches held where the blow put
them (the schedule the primal run logs, :data:`~impactbar.laws.rodrock._exactnode.LOG_SEP` ...),
plus what moving a switch moves:

- a switch across which every node's law is continuous moves nothing to first order: the piston
  leaving the shank (the force ``N`` falls to zero, the gap opens with zero rate), and every switch
  of the bit (its force ``R(p)`` is continuous across loading, unloading, lift-off and landing;
  ``p_max`` moves with ``p`` where ``p' = 0``, so ``p_perm`` is carried as a state);
- where the piston touches the shank again the weld's force jumps from 0 to ``N_+``: the contact
  time moves by ``dt = -dgap / gap'`` and both waves the contact emits get an impulse (a Dirac) of
  weight ``-N_+ dt``; the shank's position moves by ``-[v_s] dt``;
- a switch that a moving step sets off (the step a re-contact or a drive's jump sent arrives and at
  once turns the weld's force tensile, or a massless bit's ``p'`` negative) moves with the step, by
  its ``dt``: the piston leaves with the weld's last force ``N_-`` (an impulse ``N_- dt`` on both
  waves), the gap opens at its rate after the step, the shank moves at its welded speed until then;
  ``p_max`` grows by ``p'_- dt``.

The impulses are carried as such, each channel a list of (emission time, weight): a junction and a
weld transmit and reflect them by the same coefficients as waves; a free end reflects them; a free
piston end adds ``-2 w/Z`` to the gap; the bit takes ``2 w`` into ``Z p'`` (massless: ``p`` jumps by
``2 w/Z``, the reflected impulse ``-w``) or into ``m p''`` (``p'`` jumps by ``2 w/m``, reflected
``+w``). Those in the piston at the end are projected on its modes like its waves.

The tangent workspace is the primal's layout (:func:`impactbar.laws.rodrock.exact._workspace`, no
feed, nothing recorded), its ``RD`` the primal's log read as the schedule; ``tg`` holds the
impulses: ``IT`` emission times, ``IW`` weights, ``IN`` the next impulse of the same channel,
``IJ`` the primal's step each is the derivative of (its shift is ``-w/jump``), ``ICH (nch, 2)``
each channel's last impulse and its receiver's next, ``TCUR (7,)`` impulses stored, full, the
contact's and the bit's schedule cursors, a failure code (1 a grazing re-contact, where the map has
no derivative; 2 the schedule's branches out of step; 3 a switch met by an impulse that did not set
it off, or by steps moving apart), and the separations and the unloadings that a moving step set
off (its slots ``TCUR_*`` of :mod:`._records`).
"""

from __future__ import annotations

import cmath
import math

import numba

from ..._shared.literals import plain_literals
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from ._exactbit import bit_input, bit_solve
from ._exactloop import contact_emit, contact_node, node_end, node_junction
from ._exactmodal import piston_integrals
from ._exactnode import LOG_BIT, LOG_SEP, _emit, _load
from ._exactpieces import (
    ELASTIC,
    FREE,
    INF,
    LOAD,
    advance,
    blk_clear,
    blk_eval,
    blk_integral,
    blk_set_comb,
    blk_shift,
    window_break,
)
from ._records import (  # the records' slots
    B_E,
    B_IN,
    B_IN2,
    B_N,
    B_OUT,
    B_RATE,
    B_X,
    B_XD,
    BI_BRANCH,
    BITLOG_PDOT,
    BS_PMAX,
    BS_PPERM,
    BS_RMAX,
    BS_W,
    BS_X,
    CH_FAR_IN,
    CH_FAR_OUT,
    CHI_HEAD,
    CI_STATUS,
    CI_WIN,
    CNT_FULL,
    CT_T,
    END_GAP,
    END_PPERM,
    END_SEPS,
    END_SHANK,
    END_UNLOADS,
    ICH_HEAD,
    ICH_TAIL,
    IMP_DIR,
    IMP_JUMP,
    IMP_T,
    IMP_W,
    NSF_GAP,
    NSF_SHANK,
    NSI_CONTACT,
    NSI_IN,
    NSI_IN2,
    PR_K,
    PR_KU,
    PR_LB,
    PR_MASS,
    PR_NP,
    PR_SEMI,
    PR_TMAX,
    PR_WINDOW,
    PR_ZBIT,
    RD_CODE,
    RD_HEAD,
    RD_ROWS,
    RD_T,
    RECON_FORCE,
    RECON_GAPRATE,
    RECON_JUMP,
    SEP_F,
    SEP_G,
    TCUR_BIT,
    TCUR_CONTACT,
    TCUR_FAIL,
    TCUR_FULL,
    TCUR_N,
    TCUR_SEPS,
    TCUR_UNLOADS,
    TG_TCUR,
)


@numba.njit(cache=CACHE, nogil=True)
def imp_emit(tg, c, t, w, jump):
    """An impulse of weight ``w`` leaves on channel ``c`` at ``t``: the derivative of the primal's
    step ``jump`` there, moving by ``-w/jump`` (the emissions on a channel come in time order)."""
    IT, IW, IJ, IN, ICH, TCUR = tg
    if w == 0.0:
        return
    n = TCUR[TCUR_N]
    if n >= IT.size:
        TCUR[TCUR_FULL] = 1
        return
    IT[n] = t
    IW[n] = w
    IJ[n] = jump
    IN[n] = -1
    tail = ICH[c, ICH_TAIL]
    if tail >= 0:
        IN[tail] = n
    if ICH[c, ICH_HEAD] < 0:
        ICH[c, ICH_HEAD] = n
    ICH[c, ICH_TAIL] = n
    TCUR[TCUR_N] = n + 1


@numba.njit(cache=CACHE, nogil=True)
def imp_arrival(tg, c, T):
    """When the next impulse not yet received on channel ``c`` (travel time ``T``) arrives (inf:
    none in flight)."""
    IT, IW, IJ, IN, ICH, TCUR = tg
    n = ICH[c, ICH_HEAD]
    return INF if n < 0 else IT[n] + T


@numba.njit(cache=CACHE, nogil=True)
def imp_pop(tg, c):
    """Receive channel ``c``'s next impulse: its weight and its step."""
    IT, IW, IJ, IN, ICH, TCUR = tg
    n = ICH[c, ICH_HEAD]
    ICH[c, ICH_HEAD] = IN[n]
    return IW[n], IJ[n]


@numba.njit(cache=CACHE, nogil=True)
def _shift(tg, c1, T1, c2, T2, ts, dt):
    """The shift ``-w/jump`` shared by the impulses arriving at ``ts`` on channels ``c1`` and ``c2``
    (``c2`` < 0: one channel), compared with ``dt`` (NaN: none yet); NaN where they differ or a step
    is zero (no one step to move a switch with)."""
    IT, IW, IJ, IN, ICH, TCUR = tg
    for side in range(2):
        c = c1 if side == 0 else c2
        T = T1 if side == 0 else T2
        if c < 0:
            continue
        n = ICH[c, ICH_HEAD]
        while n >= 0 and _coincide(ts, IT[n] + T):
            if IJ[n] == 0.0:
                return math.nan
            d = -IW[n] / IJ[n]
            if math.isnan(dt):
                dt = d
            elif abs(d - dt) > 1e-9 * max(abs(d), abs(dt)):
                return math.nan
            n = IN[n]
    return dt


@numba.njit(cache=CACHE, nogil=True)
def _next_event(RD, cur, bit):
    """The schedule's next row at or after ``cur`` of the contact (``bit`` False) or of the bit; -1
    when none is left."""
    n = int(RD[RD_HEAD, RD_ROWS].real)
    i = max(cur, 1)  # (row 0 is the log's header)
    while i <= n:
        code = int(RD[i, RD_CODE].real)
        if (code >= LOG_BIT) == bit:
            return i
        i += 1
    return -1


@numba.njit(cache=CACHE, nogil=True)
def _coincide(ts, ti):
    """Whether an impulse arriving at ``ti`` meets a switch at ``ts`` (to ``1e-12`` of the clock): a
    moving step that may be what set the switch off, whose derivative the schedule does not hold."""
    return abs(ti - ts) <= 1e-12 * (1.0 + abs(ts))


@numba.njit(cache=CACHE, nogil=True)
def _pass(tg, c1, T1, c2, T2, t1, out1, out2, s11, s12, s21, s22):
    """Impulses arriving before ``t1`` on channels ``c1`` and ``c2`` (travel times ``T1``, ``T2``) sent
    on by a stateless node, in the order they arrive (each output channel's list stays in time
    order): ``s11`` times one from ``c1`` on ``out1``, ``s12`` on ``out2``; ``s21``, ``s22`` those
    from ``c2`` (an output channel < 0: none)."""
    while True:
        a1 = imp_arrival(tg, c1, T1)
        a2 = imp_arrival(tg, c2, T2)
        t = min(a1, a2)
        if t >= t1:
            return
        if a1 <= a2:
            w, jp = imp_pop(tg, c1)
            r1, r2 = s11, s12
        else:
            w, jp = imp_pop(tg, c2)
            r1, r2 = s21, s22
        if out1 >= 0:
            imp_emit(tg, out1, t, r1 * w, r1 * jp)
        if out2 >= 0:
            imp_emit(tg, out2, t, r2 * w, r2 * jp)


@numba.njit(cache=CACHE, nogil=True)
def t_node_contact(ws, tg, t, t1):
    """The piston's struck end and the shank on the schedule: welded or free as the primal was, the
    gap and the shank's position carried, a re-contact's impulses emitted (the module's text)."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    pool = (PF, PI, TK, TC, CNT, CHI, lam, BIN)
    Lb = PR[PR_LB]
    TCUR = tg[TG_TCUR]
    j, fch, gch, ZL, ZR, s = contact_node(PR, SZ)
    hch = 2 * SZ.size + 1 + j  # the node's force history (not recorded here)
    a = t
    dirty = False
    while True:
        cf, nbf = advance(fch, a, CHI, CH_T, PF, PI)
        cg, nbg = advance(gch, a, CHI, CH_T, PF, PI)
        if cf != NSI[j, NSI_IN] or cg != NSI[j, NSI_IN2]:
            dirty = True
        b = window_break(min(nbf, nbg), t1)
        k = _next_event(RD, TCUR[TCUR_CONTACT], False)
        TCUR[TCUR_CONTACT] = k if k >= 0 else int(RD[RD_HEAD, RD_ROWS].real) + 1
        ts = RD[k, RD_T].real if k >= 0 else INF
        ti = min(imp_arrival(tg, fch, CH_T[fch]), imp_arrival(tg, gch, CH_T[gch]))
        e = max(min(b, ts, ti), a)
        valid = min(_load(pool, CH_T, WB, WN, B_IN, fch, cf, a), _load(pool, CH_T, WB, WN, B_IN2, gch, cg, a))
        L = e - a
        if NSI[j, NSI_CONTACT] == 1:
            blk_set_comb(WB[B_N], WN[B_N], 2.0 * ZR / s, WB[B_IN], WN[B_IN], 2.0 * ZL / s, WB[B_IN2],
                         WN[B_IN2])
            if dirty:
                if not contact_emit(pool, CH_TOL, WB, WN, Lb, j, hch, a, valid, True, False, 0.0):
                    return False
                dirty = False
            if L > 0.0:
                blk_set_comb(WB[B_RATE], WN[B_RATE], 2.0 / ZL, WB[B_IN], WN[B_IN], -1.0 / ZL, WB[B_N],
                             WN[B_N])
                NSF[j, NSF_SHANK] += blk_integral(WB[B_RATE], WN[B_RATE], lam, 0.0, L)
        else:
            if dirty:
                if not contact_emit(pool, CH_TOL, WB, WN, Lb, j, hch, a, valid, False, False, 0.0):
                    return False
                dirty = False
            if L > 0.0:
                blk_set_comb(WB[B_RATE], WN[B_RATE], -2.0 / ZL, WB[B_IN], WN[B_IN], -2.0 / ZR, WB[B_IN2],
                             WN[B_IN2])
                NSF[j, NSF_GAP] += blk_integral(WB[B_RATE], WN[B_RATE], lam, 0.0, L)
                NSF[j, NSF_SHANK] += -2.0 / ZR * blk_integral(WB[B_IN2], WN[B_IN2], lam, 0.0, L)
        NSI[j, NSI_IN] = cf
        NSI[j, NSI_IN2] = cg
        a = e
        if k >= 0 and ts <= e:  # the schedule's switch (at once where overdue)
            hit = _coincide(ts, min(imp_arrival(tg, fch, CH_T[fch]), imp_arrival(tg, gch, CH_T[gch])))
            code = int(RD[k, RD_CODE].real)
            gap = NSF[j, NSF_GAP]
            NSF[j, NSF_GAP] = 0.0
            if code == LOG_SEP:
                NSI[j, NSI_CONTACT] = 0
                if hit:  # a moving step set it off: the weld's last force, the gap's and the shank's
                    dt = _shift(tg, fch, CH_T[fch], gch, CH_T[gch], ts, math.nan)  # rates before it
                    if math.isnan(dt):
                        TCUR[TCUR_FAIL] = 3
                        return True
                    fm = RD[k, SEP_F].real
                    gm = RD[k, SEP_G].real
                    Nm = 2.0 * (ZR * fm + ZL * gm) / s
                    imp_emit(tg, 2 * j, e, Nm * dt, -Nm)
                    imp_emit(tg, 2 * j - 1, e, Nm * dt, -Nm)
                    NSF[j, NSF_GAP] = (2.0 * fm / ZL + 2.0 * gm / ZR) * dt
                    NSF[j, NSF_SHANK] += ((2.0 * fm - Nm) / ZL + 2.0 * gm / ZR) * dt
                    TCUR[TCUR_SEPS] += 1
            else:
                gd = RD[k, RECON_GAPRATE].real
                if hit:
                    TCUR[TCUR_FAIL] = 3
                    return True
                if not gd < 0.0:  # a grazing re-contact: no derivative
                    TCUR[TCUR_FAIL] = 1
                    return True
                dts = -gap / gd
                Np = RD[k, RECON_FORCE].real
                imp_emit(tg, 2 * j, e, -Np * dts, Np)
                imp_emit(tg, 2 * j - 1, e, -Np * dts, Np)
                NSF[j, NSF_SHANK] += -RD[k, RECON_JUMP].real * dts
                NSI[j, NSI_CONTACT] = 1
            TCUR[TCUR_CONTACT] = k + 1
            dirty = True
            continue
        if ti <= e:  # impulses arriving now
            while imp_arrival(tg, fch, CH_T[fch]) <= e:
                w, jp = imp_pop(tg, fch)
                if NSI[j, NSI_CONTACT] == 1:
                    imp_emit(tg, 2 * j, e, 2.0 * ZR / s * w, 2.0 * ZR / s * jp)
                    imp_emit(tg, 2 * j - 1, e, (ZR - ZL) / s * w, (ZR - ZL) / s * jp)
                    NSF[j, NSF_SHANK] += 2.0 * w / s
                else:
                    imp_emit(tg, 2 * j - 1, e, -w, -jp)
                    NSF[j, NSF_GAP] += -2.0 * w / ZL
            while imp_arrival(tg, gch, CH_T[gch]) <= e:
                w, jp = imp_pop(tg, gch)
                if NSI[j, NSI_CONTACT] == 1:
                    imp_emit(tg, 2 * j, e, (ZL - ZR) / s * w, (ZL - ZR) / s * jp)
                    imp_emit(tg, 2 * j - 1, e, 2.0 * ZL / s * w, 2.0 * ZL / s * jp)
                    NSF[j, NSF_SHANK] += -2.0 * w / s
                else:
                    imp_emit(tg, 2 * j, e, -w, -jp)
                    NSF[j, NSF_GAP] += -2.0 * w / ZR
                    NSF[j, NSF_SHANK] += -2.0 * w / ZR
            continue
        if b >= t1:
            return True


@numba.njit(cache=CACHE, nogil=True)
def t_node_bit(ws, tg, t, t1):
    """The bit and the rock on the schedule: each branch's linear equation for the derivative,
    ``p_max`` and ``p_perm`` carried, arriving impulses taken (the module's text)."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    pool = (PF, PI, TK, TC, CNT, CHI, lam, BIN)
    Lb = PR[PR_LB]
    TCUR = tg[TG_TCUR]
    J = SZ.size
    fch = 2 * (J - 1)
    goch = 2 * J - 1
    k = PR[PR_K]
    ku = PR[PR_KU]
    m = PR[PR_MASS]
    Z = PR[PR_ZBIT]
    semi = PR[PR_SEMI] != 0.0
    a = t
    while True:
        b, vf = bit_input(pool, CH_T, WB, WN, PR, NSI, J, a, t1)  # (no feed in the tangent: E = 2 F)
        while True:
            br = BI[BI_BRANCH]
            ev = _next_event(RD, TCUR[TCUR_BIT], True)
            TCUR[TCUR_BIT] = ev if ev >= 0 else int(RD[RD_HEAD, RD_ROWS].real) + 1
            ts = RD[ev, RD_T].real if ev >= 0 else INF
            ti = imp_arrival(tg, fch, CH_T[fch])
            e = max(min(b, ts, ti), a)
            L = e - a
            if L > 0.0:
                series = bit_solve(WB, WN, lam, PR, RT, RC, CI, br, BS[BS_X], BS[BS_W], L)
                valid = min(vf, a + L) if series else vf
                if semi:
                    blk_clear(WB[B_OUT], WN[B_OUT])
                else:
                    blk_set_comb(WB[B_OUT], WN[B_OUT], 1.0, WB[B_IN], WN[B_IN], -Z, WB[B_XD], WN[B_XD])
                if not _emit(pool, CH_TOL, WB, WN, Lb, goch, a, B_OUT, valid, 0, 0.0):
                    return False
                x1, w1, _ = blk_eval(WB[B_X], WN[B_X], lam, L)
                blk_shift(WB[B_IN], WN[B_IN], L, lam, BIN)
                blk_shift(WB[B_E], WN[B_E], L, lam, BIN)
                BS[BS_X] = x1
                BS[BS_W] = w1
                if br == LOAD:
                    BS[BS_PMAX] = x1
                    BS[BS_RMAX] = k * x1
                    BS[BS_PPERM] = x1 - BS[BS_RMAX] / ku
                a = e
            if ev >= 0 and ts <= e:  # the schedule's switch
                hit = _coincide(ts, imp_arrival(tg, fch, CH_T[fch]))
                nxt = int(RD[ev, RD_CODE].real) - LOG_BIT
                if hit and not (m == 0.0 and br == LOAD and nxt == ELASTIC):
                    TCUR[TCUR_FAIL] = 3
                    return True
                if br == LOAD and nxt == ELASTIC:  # unloading from p_max: x = p - p_perm
                    if hit:  # a moving step set it off: p_max moves with it (p' before it)
                        dt = _shift(tg, fch, CH_T[fch], -1, 0.0, ts, math.nan)
                        if math.isnan(dt):
                            TCUR[TCUR_FAIL] = 3
                            return True
                        pd = RD[ev, BITLOG_PDOT].real
                        BS[BS_PMAX] += pd * dt
                        BS[BS_RMAX] = k * BS[BS_PMAX]
                        BS[BS_PPERM] = BS[BS_PMAX] - BS[BS_RMAX] / ku
                        BS[BS_X] = BS[BS_RMAX] / ku - pd * dt
                        TCUR[TCUR_UNLOADS] += 1
                    else:
                        BS[BS_X] = BS[BS_RMAX] / ku
                elif br == ELASTIC and nxt == LOAD:  # reloading: x = p
                    BS[BS_X] = BS[BS_PPERM] + BS[BS_X]
                elif not ((br == ELASTIC and nxt == FREE) or (br == FREE and nxt == ELASTIC)):
                    TCUR[TCUR_FAIL] = 2
                    return True
                BI[BI_BRANCH] = nxt
                TCUR[TCUR_BIT] = ev + 1
                continue
            if ti <= e:
                while imp_arrival(tg, fch, CH_T[fch]) <= e:
                    w, jp = imp_pop(tg, fch)
                    if m == 0.0:  # Z p' takes 2 w: p jumps
                        BS[BS_X] += 2.0 * w / Z
                        if not semi:
                            imp_emit(tg, goch, e, -w, -jp)
                    else:  # m p'' takes it: p' jumps
                        BS[BS_W] += 2.0 * w / m
                        if not semi:
                            imp_emit(tg, goch, e, w, jp)
                continue
            if e >= b:
                break
        if b >= t1:
            return True
        a = b


@numba.njit(cache=CACHE, nogil=True)
def t_run(ws, tg):
    """The tangent run to ``t_max`` window by window, as :func:`~._exactloop.run`; ``CI[CI_STATUS]``: 0
    done, 1 the pool full (again, larger), 2 the impulses' store full, 3 the schedule cannot be
    followed (``tg``'s failure code)."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    TCUR = tg[TG_TCUR]
    J = SZ.size
    n_p = int(PR[PR_NP])
    h = PR[PR_WINDOW]
    tmax = PR[PR_TMAX]
    dch = 2 * J
    while True:
        w = CI[CI_WIN]
        t = w * h
        if t >= tmax:
            CI[CI_STATUS] = 0
            return
        t1 = min((w + 1) * h, tmax)
        ok = node_end(ws, t, t1)  # f_out = p - g_in
        _pass(tg, CH_FAR_IN, CH_T[CH_FAR_IN], dch, CH_T[dch], t1, CH_FAR_OUT, -1, -1.0, 0.0, 1.0, 0.0)
        for j in range(1, J):
            if not ok:
                break
            if j == n_p:
                ok = t_node_contact(ws, tg, t, t1)
            else:
                ok = node_junction(ws, j, t, t1)
                ZL = SZ[j - 1]
                ZR = SZ[j]
                s = ZL + ZR
                fch = 2 * (j - 1)
                gch = 2 * j + 1
                _pass(tg, fch, CH_T[fch], gch, CH_T[gch], t1, 2 * j, 2 * j - 1, 2.0 * ZR / s, (ZR - ZL) / s,
                      (ZL - ZR) / s, 2.0 * ZL / s)
        if ok and TCUR[TCUR_FAIL] == 0:
            ok = t_node_bit(ws, tg, t, t1)
        if not ok or CNT[CNT_FULL] != 0:
            CI[CI_STATUS] = 1
            return
        if TCUR[TCUR_FULL] != 0:
            CI[CI_STATUS] = 2
            return
        if TCUR[TCUR_FAIL] != 0:
            CI[CI_STATUS] = 3
            return
        CI[CI_WIN] = w + 1
        CT[CT_T] = t1


@numba.njit(cache=CACHE, nogil=True)
def impulse_integrals(tg, travel, CH_T, t, om, out):
    """The impulses in the piston's segments at ``t`` projected as :func:`~._exactmodal.piston_integrals`
    projects its waves: ``out[i, n, 0] += w e^{i om_n theta}`` for an impulse on channel ``2 i`` at
    ``theta = t - t_e`` (``t_e`` its emission), ``out[i, n, 1]`` for channel ``2 i + 1`` at
    ``theta = T_i - t + t_e``."""
    IT, IW, IJ, IN, ICH, TCUR = tg
    for i in range(travel.size):
        T = travel[i]
        for side in range(2):
            c = 2 * i + side
            n = ICH[c, ICH_HEAD]
            while n >= 0:
                if IT[n] + CH_T[c] >= t:  # in flight at t
                    theta = t - IT[n] if side == 0 else T - t + IT[n]
                    for q in range(om.size):
                        out[i, q, side] += IW[n] * cmath.exp(1j * om[q] * theta)
                n = IN[n]


@numba.njit(cache=CACHE, nogil=True)
def _put(dst, src):
    """``dst[:len(src)] = src`` for 2-D arrays, written out."""
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i, j] = src[i, j]


@numba.njit(cache=CACHE, nogil=True)
def t_batch(ws, tg, template, slots, coefs, imps, out, ends, travel, om):
    """Tangent runs along many directions of the blow's data, one workspace reused: before each run
    the workspace is set back to ``template`` (``(PF, PI, TK, TC, CNT, CHI, NSI)`` as made, its first
    pieces the piston's waves and the drive's) with direction ``d``'s coefficients ``coefs[d]`` in
    the term slots ``slots``, and its impulses in the drive (the rows ``(d, t, w, jump)`` of
    ``imps``) sent; after it, the piston's waves and impulses projected into ``out[d]``
    (:func:`~._exactmodal.piston_integrals`, :func:`impulse_integrals`) and ``ends[d]`` the shank's
    displacement, the gap, ``p_perm`` and the separations and unloadings a moving step set off.
    Returns ``(d, status)``: the direction a run stopped at with :func:`t_run`'s nonzero status, or
    ``(coefs.shape[0], 0)``."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    PF0, PI0, TK0, TC0, CNT0, CHI0, NSI0 = template
    IT, IW, IJ, IN, ICH, TCUR = tg
    nt0 = TK0.size
    n_p = int(PR[PR_NP])
    for d in range(coefs.shape[0]):
        _put(PF, PF0)
        _put(PI, PI0)
        for i in range(nt0):  # (loops, not slice copies: numba's compiles for seconds)
            TK[i] = TK0[i]
            TC[i] = TC0[i]
        for i in range(slots.size):
            TC[slots[i]] = coefs[d, i]
        for i in range(CNT0.size):
            CNT[i] = CNT0[i]
        _put(CHI, CHI0)
        _put(NSI, NSI0)
        NSF[:] = 0.0
        BS[:] = 0.0
        BI[:] = 0
        CI[:] = 0
        CT[:] = 0.0
        for b in range(WB.shape[0]):
            blk_clear(WB[b], WN[b])
        TCUR[:] = 0
        ICH[:] = -1
        for r in range(imps.shape[0]):
            if int(imps[r, IMP_DIR]) == d:
                imp_emit(tg, 2 * SZ.size, imps[r, IMP_T], imps[r, IMP_W], imps[r, IMP_JUMP])
        t_run(ws, tg)
        if CI[CI_STATUS] != 0:
            return d, CI[CI_STATUS]
        heads = CHI[: 2 * n_p, CHI_HEAD].copy()
        piston_integrals((PF, PI, TK, TC, lam, BIN), heads, travel, CT[CT_T], om, out[d])
        impulse_integrals(tg, travel, CH_T, CT[CT_T], om, out[d])
        ends[d, END_SHANK] = NSF[n_p, NSF_SHANK]
        ends[d, END_GAP] = NSF[n_p, NSF_GAP]
        ends[d, END_PPERM] = BS[BS_PPERM]
        ends[d, END_SEPS] = TCUR[TCUR_SEPS]
        ends[d, END_UNLOADS] = TCUR[TCUR_UNLOADS]
    return coefs.shape[0], 0


plain_literals(globals())  # one machine code per kernel for all constant arguments (a shorter compile)
# the kernels Python calls keep their wrapper and cache entry; the others are link-only (for kernels)
internal_kernels(globals(), python=("t_batch",))
