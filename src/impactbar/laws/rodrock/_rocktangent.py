"""The tangent-linear (forward-mode) blow on the rod and the rock (theory §12): the loop of
:func:`impactbar.laws.rodrock._rockloop.blow_loop` without a drive (its junctions and the bit's
step the same arithmetic, the rod's uniform segments delay lines: the compiled loop's blow to
rounding), carrying beside every wave and every bit variable its derivatives in ``nv`` directions
of the piston's cells' impedances.

The switching schedule is held as the primal run decides it: the piston-shank contact on or off per
step, the rock's branch on each sub-step of the bit, the step that ends the blow. Inside a step a
branch change happens at an event time ``tau`` that moves with the state. A massless bit is put on
the switch's penetration (``p_max`` or ``p_perm``) and the closed form's ``tau`` is differentiated
(the logarithm's, or the lift-off's ``(p_perm - p)/rate``), so that the remaining time of the step
carries it. A bit with mass has its switch located by bisection to rounding; there ``tau`` is held,
as the flow's vector field is continuous across every switch of the bilinear law (the rock force
is, on the state the primal keeps: ``p_perm = p_max - R_max/k_u``) and the switch's moving changes
the state at the step's end only at second order. The derivative returned is thus that of the
lattice's work and shank forces as functions of the impedances on every piece where the schedule is
constant (the lattice's blow is piecewise smooth: kinks where the schedule changes).

Tangent bit state ``dbs`` (float64, (``BIT_SIZE``, nv)): the rows of ``bs`` (``p, w, -, p_max, R_max,
p_perm, work``, named ``BIT_*`` in :mod:`impactbar.laws.rodrock._records`; the branch row unused).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from . import _records as RS
from ._rockloop import (
    _ELASTIC,
    _LOAD,
    _branch_after,
    _coeffs,
    _damped,
    _flow,
    _lift_off,
    _massless_switch,
    _overdamped,
    _switch_time,
    _unload,
)


@numba.njit(cache=CACHE, nogil=True)
def _t_unload(bs, bp, dbs):
    _unload(bs, bp)
    for a in range(dbs.shape[1]):
        dbs[RS.BIT_PMAX, a] = dbs[RS.BIT_P, a]
        dbs[RS.BIT_RMAX, a] = bp[RS.BITP_K] * dbs[RS.BIT_P, a]
        dbs[RS.BIT_PPERM, a] = dbs[RS.BIT_PMAX, a] - dbs[RS.BIT_RMAX, a] / bp[RS.BITP_KU]


@numba.njit(cache=CACHE, nogil=True)
def _t_work(bs, dbs, b, ref, dref, p0, p1, dp0, dp1):
    """``work += b (p1 - p0)(0.5 (p0 + p1) - ref)`` and its tangent."""
    mid = 0.5 * (p0 + p1) - ref
    bs[RS.BIT_WORK] += b * (p1 - p0) * mid
    for a in range(dbs.shape[1]):
        dbs[RS.BIT_WORK, a] += b * ((dp1[a] - dp0[a]) * mid + (p1 - p0) * (0.5 * (dp0[a] + dp1[a]) - dref[a]))


@numba.njit(cache=CACHE, nogil=True)
def _t_start(bs, bp, dbs, dp0, dref):
    """A sub-step's start: the branch's ``(b, p_ref)`` (``_coeffs``), and the tangents of ``p`` and
    of ``p_ref`` into ``dp0``, ``dref`` (nv,)."""
    b, ref = _coeffs(bs, bp)
    elastic = bs[RS.BIT_BRANCH] == _ELASTIC
    for a in range(dbs.shape[1]):
        dp0[a] = dbs[RS.BIT_P, a]
        dref[a] = dbs[RS.BIT_PPERM, a] if elastic else 0.0
    return b, ref


@numba.njit(cache=CACHE, nogil=True)
def _t_massless(bs, bp, dbs, E, dE, T, dT, dtau, dp0, dref):
    """``_rockloop._massless`` and its tangent; ``dtau`` out (scratch ``dp0``, ``dref``)."""
    nv = dbs.shape[1]
    Z = bp[RS.BITP_Z]
    b, ref = _t_start(bs, bp, dbs, dp0, dref)
    p0 = bs[RS.BIT_P]
    if bs[RS.BIT_BRANCH] == _LOAD and E - b * p0 < 0.0:
        _t_unload(bs, bp, dbs)
        dtau[:] = 0.0
        return 0.0
    if b == 0.0:
        rate, t_hit, tau = _lift_off(bs, E, Z, T, p0)
        if tau == t_hit:
            p1 = bs[RS.BIT_PPERM]
            for a in range(nv):
                dtau[a] = (dbs[RS.BIT_PPERM, a] - dp0[a]) / rate - t_hit * dE[a] / Z / rate
                dbs[RS.BIT_P, a] = dbs[RS.BIT_PPERM, a]
        else:
            p1 = p0 + rate * tau
            for a in range(nv):
                dtau[a] = dT[a]
                dbs[RS.BIT_P, a] = dp0[a] + dE[a] / Z * tau + rate * dT[a]
        bs[RS.BIT_P] = p1
        if tau == t_hit:
            bs[RS.BIT_BRANCH] = _ELASTIC
        bs[RS.BIT_W] = rate
        for a in range(nv):
            dbs[RS.BIT_W, a] = dE[a] / Z
        return tau
    tau, nxt, p_nxt, which, g, lam = _massless_switch(bs, b, ref, E, Z, T, p0)
    if nxt < 0.0:
        e = -math.expm1(-lam * tau)
        p1 = p0 + g / Z * e / lam
        decay = math.exp(-lam * tau)
        for a in range(nv):
            dg = dE[a] - b * (dp0[a] - dref[a])
            dtau[a] = dT[a]
            dbs[RS.BIT_P, a] = dp0[a] + dg / Z * e / lam + g / Z * decay * dT[a]
    else:
        p1 = p_nxt
        q = (p_nxt - p0) * b / g  # tau_h = -log1p(-q) / lam
        for a in range(nv):
            dg = dE[a] - b * (dp0[a] - dref[a])
            dq = b * (dbs[which, a] - dp0[a]) / g - q * dg / g
            dtau[a] = dq / ((1.0 - q) * lam)
            dbs[RS.BIT_P, a] = dbs[which, a]
    _t_work(bs, dbs, b, ref, dref, p0, p1, dp0, dbs[RS.BIT_P])
    bs[RS.BIT_P] = p1
    bs[RS.BIT_W] = (E - b * (p1 - ref)) / Z
    for a in range(nv):
        dbs[RS.BIT_W, a] = (dE[a] - b * (dbs[RS.BIT_P, a] - dref[a])) / Z
    if nxt >= 0.0:
        bs[RS.BIT_BRANCH] = nxt
    return tau


@numba.njit(cache=CACHE, nogil=True)
def _flow_partials(bs, bp, E, tau, out):
    """The partial derivatives of ``_rockloop._flow``'s ``(p, w)`` after ``tau`` with respect to
    ``(p0, w0, E, p_ref)`` at fixed ``tau``, into ``out`` (2, 4): the flow is affine in them, its
    matrix from the same ``C``, ``S`` (``dp/dE = int_0^tau S / m``)."""
    b, ref = _coeffs(bs, bp)
    Z, m = bp[RS.BITP_Z], bp[RS.BITP_MASS]
    if b == 0.0:
        decay = math.exp(-Z * tau / m)
        Sf = (m / Z) * (-math.expm1(-Z * tau / m))
        out[0, 0], out[0, 1], out[0, 2], out[0, 3] = 1.0, Sf, (tau - Sf) / Z, 0.0
        out[1, 0], out[1, 1], out[1, 2], out[1, 3] = 0.0, decay, (1.0 - decay) / Z, 0.0
        return
    half = -Z / (2.0 * m)
    C, S, delta = _damped(b, m, half, tau)
    if delta > 0.5 * abs(half):
        f1, f2 = _overdamped(b, m, half, delta, tau)
        pE = (f1 - f2) / (2.0 * delta) / m
    else:
        pE = (1.0 - C + half * S) / b
    out[0, 0], out[0, 1], out[0, 2], out[0, 3] = 1.0 - b * pE, S, pE, b * pE
    out[1, 0], out[1, 1], out[1, 2], out[1, 3] = -b * S / m, C + half * S, S / m, b * S / m


@numba.njit(cache=CACHE, nogil=True)
def _t_with_mass(bs, bp, dbs, E, dE, T, dT, dtau, dp0, dref, J):
    """``_rockloop._with_mass`` and its tangent; ``dtau`` out (scratch ``dp0``, ``dref``, ``J``)."""
    nv = dbs.shape[1]
    if bs[RS.BIT_BRANCH] == _LOAD and bs[RS.BIT_W] < 0.0:
        _t_unload(bs, bp, dbs)
        dtau[:] = 0.0
        return 0.0
    if bs[RS.BIT_BRANCH] == _ELASTIC and bs[RS.BIT_P] >= bs[RS.BIT_PMAX] and bs[RS.BIT_W] > 0.0:
        bs[RS.BIT_BRANCH] = _LOAD
        dtau[:] = 0.0
        return 0.0
    p0 = bs[RS.BIT_P]
    b, ref = _t_start(bs, bp, dbs, dp0, dref)
    tau, hit = _switch_time(bs, bp, E, T)
    p1, w1 = _flow(bs, bp, E, tau)
    _flow_partials(bs, bp, E, tau, J)
    acc = (E - bp[RS.BITP_Z] * w1 - b * (p1 - ref)) / bp[RS.BITP_MASS]  # w' at tau on this branch
    # a switch's time is held: the flow is continuous across it (the rock force is, on the state the
    # primal keeps consistent: p_perm = p_max - R_max/k_u), so the switch's moving with the state
    # changes the state at the step's end only at second order; the step's end time moves with the
    # remaining time (the earlier switches of a massless bit)
    for a in range(nv):
        dpf = J[0, 0] * dp0[a] + J[0, 1] * dbs[RS.BIT_W, a] + J[0, 2] * dE[a] + J[0, 3] * dref[a]
        dwf = J[1, 0] * dp0[a] + J[1, 1] * dbs[RS.BIT_W, a] + J[1, 2] * dE[a] + J[1, 3] * dref[a]
        dt_a = 0.0 if hit else dT[a]
        dtau[a] = dt_a
        dbs[RS.BIT_P, a] = dpf + w1 * dt_a
        dbs[RS.BIT_W, a] = dwf + acc * dt_a
    _t_work(bs, dbs, b, ref, dref, p0, p1, dp0, dbs[RS.BIT_P])
    bs[RS.BIT_P], bs[RS.BIT_W] = p1, w1
    if hit:
        if bs[RS.BIT_BRANCH] == _LOAD:
            _t_unload(bs, bp, dbs)
        else:
            _branch_after(bs, p1)
    return tau


@numba.njit(cache=CACHE, nogil=True)
def bit_step_tangent(bs, bp, dbs, E, dE, dt, scratch, J):
    """``_rockloop.bit_step`` and its tangent: ``dE`` (nv,) the input's; ``scratch`` (``TSCR_SIZE``, nv)."""
    left = dt
    dleft, dtau = scratch[RS.TSCR_LEFT], scratch[RS.TSCR_TAU]
    dp0, dref = scratch[RS.TSCR_P0], scratch[RS.TSCR_REF]
    dleft[:] = 0.0
    for _ in range(64):
        if left <= 0.0:
            break
        if bp[RS.BITP_MASS] == 0.0:
            tau = _t_massless(bs, bp, dbs, E, dE, left, dleft, dtau, dp0, dref)
        else:
            tau = _t_with_mass(bs, bp, dbs, E, dE, left, dleft, dtau, dp0, dref, J)
        left -= tau
        for a in range(dleft.size):
            dleft[a] -= dtau[a]


@numba.njit(cache=CACHE, nogil=True)
def blow_loop_tangent(P, dP, seg_len, seg_z, bs, dbs, bp, ctrl, shank, dshank, acc):
    """The blow's loop (``_rockloop.blow_loop`` with no drive, the piston touching the shank at the
    start, the rod at rest) with its tangents. The piston's cells ``P = (F, G, Z)`` (3, n_p; rows ``CELL_*``)
    and their tangents ``dP`` (3, nv, n_p); the rod's uniform segments of ``seg_len`` cells and
    impedances ``seg_z`` (S,), each a delay line: inside a uniform segment the junction passes the
    waves on (``N = F + G``), so that its cells are a ring buffer shifted by the step and only the
    segments' ends meet junctions (the same blow to rounding). ``ctrl``: ``dt, energy_stop``;
    ``shank``, ``dshank`` out (n_max,), (n_max, nv): the piston-shank force per step and its tangent;
    ``acc`` out (``ACC_SIZE``,): its ``ACC_STEPS``, ``ACC_ENDED``."""
    dt, stop = ctrl[RS.CTRL_DT], ctrl[RS.CTRL_STOP]
    Fp, Gp, Zp = P[RS.CELL_F].copy(), P[RS.CELL_G].copy(), P[RS.CELL_Z]
    dFp, dGp, dZp = dP[RS.CELL_F].copy(), dP[RS.CELL_G].copy(), dP[RS.CELL_Z]
    n_p = Zp.size
    nv = dZp.shape[0]
    S = seg_len.size
    off = np.zeros(S + 1, np.int64)
    for q in range(S):
        off[q + 1] = off[q] + seg_len[q]
    Fr = np.zeros(off[S])  # F of cell i of segment q at step t in Fr[off[q] + (i - t) mod n_q]
    Gr = np.zeros(off[S])  # G of cell i in Gr[off[q] + (i + t) mod n_q]
    dFr = np.zeros((nv, off[S]))
    dGr = np.zeros((nv, off[S]))
    jc = n_p - 1
    feed, m = bp[RS.BITP_FEED], bp[RS.BITP_MASS]
    Zl = seg_z[S - 1]
    contact = True
    gap = 0.0
    last = 0
    Np = np.empty(max(n_p - 1, 0))
    Fn = np.empty(n_p)
    Gn = np.empty(n_p)
    dFn = np.zeros((nv, n_p))
    dGn = np.zeros((nv, n_p))
    Ns = np.empty(max(S - 1, 0))
    dNs = np.zeros((nv, max(S - 1, 0)))
    Ff, Fl, Gf, Gl = np.empty(S), np.empty(S), np.empty(S), np.empty(S)
    dFf, dFl, dGf, dGl = np.empty((nv, S)), np.empty((nv, S)), np.empty((nv, S)), np.empty((nv, S))
    dNc = np.empty(nv)
    dE = np.empty(nv)
    dp0 = np.empty(nv)
    scratch = np.zeros((RS.TSCR_SIZE, nv))
    J = np.zeros((2, 4))
    n_max = shank.size
    steps, ended = n_max, 0.0
    for step in range(n_max):
        for q in range(S):  # the segments' ends at this step
            n, o = seg_len[q], off[q]
            k = step % n
            i0, i1 = o + (n - k) % n, o + (2 * n - 1 - k) % n  # F of the first, last cell
            g0, g1 = o + k, o + (n - 1 + k) % n  # G of the first, last cell
            Ff[q], Fl[q], Gf[q], Gl[q] = Fr[i0], Fr[i1], Gr[g0], Gr[g1]
            for a in range(nv):
                dFf[a, q], dFl[a, q], dGf[a, q], dGl[a, q] = dFr[a, i0], dFr[a, i1], dGr[a, g0], dGr[a, g1]
        # the piston's junctions, welded
        for j in range(n_p - 1):
            za, zb = Zp[j], Zp[j + 1]
            Np[j] = (2.0 * zb * Fp[j] + 2.0 * za * Gp[j + 1]) / (za + zb)
        # the piston-shank contact
        za, zb = Zp[jc], seg_z[0]
        Nc = (2.0 * zb * Fp[jc] + 2.0 * za * Gf[0]) / (za + zb)
        if contact:
            contact = Nc >= 0.0
        else:
            contact = gap <= 0.0 and Nc >= 0.0
        if not contact:
            Nc = 0.0
            gap = max(gap + (-2.0 * Gf[0] / zb - 2.0 * Fp[jc] / za) * dt, 0.0)
        for a in range(nv):
            dNc[a] = 0.0 if not contact else (2.0 * (zb * dFp[a, jc] + dZp[a, jc] * Gf[0] + za * dGf[a, 0])
                                              - Nc * dZp[a, jc]) / (za + zb)
        # the rod's segments' junctions
        for q in range(S - 1):
            za, zb = seg_z[q], seg_z[q + 1]
            Ns[q] = (2.0 * zb * Fl[q] + 2.0 * za * Gf[q + 1]) / (za + zb)
            for a in range(nv):
                dNs[a, q] = (2.0 * zb * dFl[a, q] + 2.0 * za * dGf[a, q + 1]) / (za + zb)
        # the piston's waves at the next step
        Fn[0] = 0.0 - Gp[0]
        for j in range(n_p - 1):
            Fn[j + 1] = Np[j] - Gp[j + 1]
            Gn[j] = Np[j] - Fp[j]
        Gn[jc] = Nc - Fp[jc]
        for a in range(nv):
            dFa, dGa, dZa, dFna, dGna = dFp[a], dGp[a], dZp[a], dFn[a], dGn[a]
            dFna[0] = -dGa[0]
            for j in range(n_p - 1):
                za, zb = Zp[j], Zp[j + 1]
                dn = (2.0 * (zb * dFa[j] + dZa[j + 1] * Fp[j] + za * dGa[j + 1] + dZa[j] * Gp[j + 1])
                      - Np[j] * (dZa[j] + dZa[j + 1])) / (za + zb)
                dFna[j + 1] = dn - dGa[j + 1]
                dGna[j] = dn - dFa[j]
            dGna[jc] = dNc[a] - dFa[jc]
        # the bit and the rock
        Fi = Fl[S - 1]
        p0 = bs[RS.BIT_P]
        for a in range(nv):
            dE[a] = 2.0 * dFl[a, S - 1]
            dp0[a] = dbs[RS.BIT_P, a]
        bit_step_tangent(bs, bp, dbs, 2.0 * Fi + feed, dE, dt, scratch, J)
        g_end = Fi - Zl * (bs[RS.BIT_P] - p0) / dt
        # the segments' ends at the next step: F enters at the first cell (the slot of the last's
        # F, read above), G at the last (the slot of the first's)
        for q in range(S):
            n, o = seg_len[q], off[q]
            k = (step + 1) % n
            i0, g1 = o + (n - k) % n, o + (n - 1 + k) % n
            Fr[i0] = (Nc - Gf[0]) if q == 0 else (Ns[q - 1] - Gf[q])
            Gr[g1] = (Ns[q] - Fl[q]) if q < S - 1 else g_end
            for a in range(nv):
                dFr[a, i0] = (dNc[a] - dGf[a, 0]) if q == 0 else (dNs[a, q - 1] - dGf[a, q])
                dGr[a, g1] = ((dNs[a, q] - dFl[a, q]) if q < S - 1
                              else (dFl[a, q] - Zl * (dbs[RS.BIT_P, a] - dp0[a]) / dt))
        shank[step] = Nc
        for a in range(nv):
            dshank[step, a] = dNc[a]
        Fp, Fn = Fn, Fp
        Gp, Gn = Gn, Gp
        dFp, dFn = dFn, dFp
        dGp, dGn = dGn, dGp
        if contact:
            last = step
        if not contact and last >= 0 and step % 8 == 0:
            rod_e = 0.0
            for q in range(S):
                for i in range(off[q], off[q + 1]):
                    rod_e += (Fr[i] * Fr[i] + Gr[i] * Gr[i]) / seg_z[q]
            if rod_e * dt + 0.5 * m * bs[RS.BIT_W] * bs[RS.BIT_W] < stop:
                steps, ended = step + 1, 1.0
                break
    acc[RS.ACC_STEPS], acc[RS.ACC_ENDED] = steps, ended


internal_kernels(globals(), python=("blow_loop_tangent",))  # the others: link-only (kernels call them)
