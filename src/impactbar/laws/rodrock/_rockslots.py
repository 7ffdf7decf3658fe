r"""The rod-rock blow's lattice with *slots* (theory §11, "The coupled blow": the rod-rock law's slot
lattice): ``RodRock(contact_events="slots")``.

The lattice of :mod:`._rockloop` holds one value of each characteristic in each cell, so that an
event inside a step (the piston meeting the shank again, the bit landing, the rock changing branch)
is taken at a step's end, and a rod segment whose travel time is not whole steps is rounded to whole
cells; both make the blow converge at first order. Here every wave still travels one cell a step,
so a front that starts a fraction ``a`` into a step stays that fraction into every step it reaches.
Each step is cut into slots (fractions of the step, the same cuts in every cell) and each cell holds
one value of each characteristic per slot, the waves piecewise constant between the events' instants:

- a slot is a step of its own length (the welded junctions, the driven end's force of the step, the
  bit over the slot's time under its constant input, its outgoing wave the slot's average);
- an event inside a slot cuts it in every cell: the gap closing (linear in time under constant
  waves), the bit's first branch change (the rock loading, unloading, the bit lifting off or landing).
  A separation needs no cut: the welded force is constant over a slot, so the contact opens at a
  slot's start;
- a rod segment is its whole cells and a *delay* of the fraction ``delta`` of a step left over at its
  far end (before the next segment, or the bit); the delayed waves' slot averages are exact (each
  slot's integral of the wave one step and ``delta`` earlier), and the slots are cut where a delayed
  wave jumps by more than :data:`CUT_JUMP` of the largest wave;
- past :data:`MAX_SLOTS` slots, the two adjacent slots whose width-weighted average loses least (the
  L2 difference of their values over all cells times ``w_1 w_2 / (w_1 + w_2)``) are merged, and the
  energy each merge takes is booked with the grid's loss, as is what the cells' averages at the end
  drop from the slots'; the waves held in the delays are the rod's (the blow's account closes).

The loop is resumable: its state (:class:`SlotLattice`) is handed from one run of steps to the next,
as the coupled blow's chunks need (:mod:`.coupled`), and its last step may end inside the step
(``frac``: the blow ended at its exact instant; the cells then hold what has entered them before that
instant and what is left of them after it).

Measured against the exact blow on ``examples/circuit_drifter_rock.toml``'s rod (tests; the
project's benchmark history): the piston's velocity after a held-force blow within 1.8e-6, 1.4e-6 and
1.7e-7 on 8, 16 and 32 cells a piston, where the plain lattice is 5e-3 to 3e-2 off.
"""

from __future__ import annotations

import numba
import numpy as np

from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from ._records import (
    BIT_P,
    BIT_W,
    BIT_WORK,
    BITP_FEED,
    BITP_MASS,
)
from ._rockloop import _coeffs, _massless, _with_mass, bit_step
from ._slotgrid import (
    _nb_absmax,
    _nb_delayed,
    _nb_energy,
    _nb_gather,
    _nb_insert,
    _nb_jump_cuts,
    _nb_merge,
    _nb_refine,
    _nb_window,
)

__all__ = ["SlotLattice", "MAX_SLOTS", "CUT_JUMP"]

#: At most this many slots a step after each step's merges.
MAX_SLOTS = 24
#: A delay cuts the slots where the wave it delays jumps by more than this fraction of the largest wave.
CUT_JUMP = 1e-4
#: A cut closer than this fraction of a slot to one of its ends is not made (the event taken there).
TINY = 1e-12

# the loop's integer state ``ist``: the slots now and on the step before, the contact, the last step
# in contact (-1: none yet), the steps run, how the last run ended (0: its steps, 1: the energy
# stop, 2: separated); its float state ``fst``: the piston-shank gap, the
# shank's displacement, the grid's loss (the bit's averaged outgoing wave), the drive's work, the
# energy the merges took, and at the end the slots' energy in the piston and in the rod and the energy
# of the waves held in the delays
IS_NW, IS_NWS, IS_CONTACT, IS_LAST, IS_STEP, IS_ENDED, IS_SIZE = 0, 1, 2, 3, 4, 5, 6
FS_GAP, FS_USHANK, FS_LOSS, FS_WORK, FS_MERGED, FS_PISTON, FS_ROD, FS_HELD = 0, 1, 2, 3, 4, 5, 6, 7
FS_SIZE = 8
# a run's controls ``ctl``: the step, the energy that ends a separated blow, the separated steps that
# end it (0: none), the last step's fraction run, the slots kept a step, the cut rule
CT_DT, CT_STOP, CT_QUIET, CT_FRAC, CT_CAP, CT_CUT, CT_SIZE = 0, 1, 2, 3, 4, 5, 6


@numba.njit(cache=CACHE, nogil=True)
def _nb_advance(bs, trial, bp, E, T):
    """The time the bit takes under the constant input ``E`` to its first change of branch within
    ``T``, else ``T``: the bit's state ``bs`` advanced on its copy ``trial`` (left unchanged)."""
    for r in range(bs.size):
        trial[r] = bs[r]
    done = 0.0
    for _ in range(64):
        left = T - done
        if left <= 0.0:
            break
        if bp[BITP_MASS] == 0.0:
            tau = _massless(trial, bp, E, left)
        else:
            tau = _with_mass(trial, bp, E, left)
        if tau == 0.0:
            continue
        done += tau
        if tau < left:
            return done
    return T


@numba.njit(cache=CACHE, nogil=True)
def _nb_force(bs, bp):
    """The rock's force on the bit (``_Bit.force``), by the branch's line as the plain lattice's loop
    takes it (:func:`~impactbar.laws.rodrock._rockloop._coeffs`)."""
    b, ref = _coeffs(bs, bp)
    return max(b * (bs[BIT_P] - ref), 0.0)


@numba.njit(cache=CACHE, nogil=True)
def _nb_ends(state, nW, nWs, cur, n_cur, grid, at, dt, fst, F_out, G_out):
    """At the end of a run (``at`` into the step: 0 at its start, with ``n_cur`` rows of the step's
    sources ``curF``, ``curG`` run): the cells' averages ``F_out``, ``G_out``, and in ``fst`` the
    slots' energy in the piston and in the rod and the energy of the waves held in the delays (each
    delay's sources over the last ``delta`` of a step before ``at``). ``state``, ``grid``: as
    :func:`slot_steps`'s; ``cur``: the step's sources ``(curF, curG)``."""
    FF, GG, W, srcF, srcG, Wsrc = state
    Z, bounds, dj, dd = grid
    curF, curG = cur
    n_p = bounds[0]
    nc = F_out.size
    for j in range(nc):
        f, g = 0.0, 0.0
        for k in range(nW):
            f += FF[k, j] * W[k]
            g += GG[k, j] * W[k]
        F_out[j], G_out[j] = f, g
    fst[FS_PISTON] = _nb_energy(FF, GG, W, nW, Z, 0, n_p) * dt
    fst[FS_ROD] = _nb_energy(FF, GG, W, nW, Z, n_p, nc) * dt
    held = 0.0
    for r in range(dj.size):
        e = _nb_window(srcF[:, r], Wsrc, nWs, curF[:, r], W, n_cur, at - dd[r], at)
        e += _nb_window(srcG[:, r], Wsrc, nWs, curG[:, r], W, n_cur, at - dd[r], at)
        held += e * dt / Z[dj[r]]
    fst[FS_HELD] = held


@numba.njit(cache=CACHE, nogil=True)
def _send_cuts(state, nW, nWs, Gout, dd, cut_jump, rows, scratch):
    """The slots cut where a wave sent back into a delay (``Gout``, a column a delay) jumps by more
    than ``cut_jump`` of its largest value (each delay's sources on the step before, ``state``'s), the
    ``rows`` (a tuple of five ``(Kmax, m)`` arrays) gathered onto the new slots; ``scratch``: the loop's
    ``(cuts, eold, ubuf, idx, col, tmp)``. Returns the new count, ``-1`` where ``Kmax`` is too few."""
    _, _, W, _, srcG, Wsrc = state
    cuts, eold, ubuf, idx, col, tmp = scratch
    nd = dd.size
    thr = -1.0
    if cut_jump >= 0.0:
        thr = cut_jump * max(_nb_absmax(Gout, nW, nd), 1e-300)
    if nWs + nW + 1 > W.size or nd * (nWs + nW + 1) + nW + 1 > W.size:
        return -1
    ncut = 0
    for r in range(nd):
        for k in range(nW):
            col[k] = Gout[k, r]
        ncut = _nb_jump_cuts(srcG[:, r], Wsrc, nWs, col, W, nW, dd[r], thr, cuts, ncut)
    n_new = _nb_refine(W, nW, cuts, ncut, eold, ubuf, idx)
    if n_new != nW:
        for x in rows:
            _nb_gather(x, idx, n_new, tmp)
    return n_new


@numba.njit(cache=CACHE, nogil=True)
def slot_steps(state, ist, fst, grid, bit, drive, ctl, out):
    """``drive.size`` steps of the slot lattice from its state (the module's text), updated in place.

    ``state`` ``(FF, GG, W, srcF, srcG, Wsrc)``: the slots' waves ``(Kmax, cells)`` (rows ``:nW``),
    their widths (fractions of a step), each delay's sources and slots on the step before; ``ist``,
    ``fst`` (slots ``IS_*``, ``FS_*``); ``grid`` ``(Z, bounds, dj, dd)``: the cells' impedances, the
    segments' boundaries, the delays' cells and fractions of a step; ``bit`` ``(bs, bp)``: the bit's
    state (updated) and parameters; ``drive``: the driven end's force on each step; ``ctl`` (slots
    ``CT_*``): the last step is run to the fraction ``ctl[CT_FRAC]`` of it only (``< 1``: the blow's
    end inside it; the state is then not resumable). ``out`` ``(junc, bitf, pen, field, arriving,
    arr_n, arr_W, arr_G, F_out, G_out)``: the junctions' forces averaged over each step ``(n, J)``,
    the rock's force and the bit's penetration at the step ends ``(n + 1,)``, each cell's force at
    each step's start ``(n, cells)`` or ``(0, cells)``, the wave arriving at the driven end over each
    step (averaged), with ``arr_n`` of shape ``(n,)`` (else ``(0,)``) its slots too (``arr_n[i]`` of
    them, their widths ``arr_W[i]`` and values ``arr_G[i]``), and the cells' averages at the end. Ends
    early where the separated piston has been apart ``ctl[CT_QUIET]`` steps (> 0) or the rod's and
    the bit's energy falls below ``ctl[CT_STOP]`` (``ist[IS_ENDED]``: 1 energy, 2 separated; 0 none).
    Returns the steps run, or ``-1`` where ``Kmax`` slots were too few (the state then not valid: the
    caller runs again from a copy with more)."""
    FF, GG, W, srcF, srcG, Wsrc = state
    Z, bounds, dj, dd = grid
    bs, bp = bit
    junc, bitf, pen, field, arriving, arr_n, arr_W, arr_G, F_out, G_out = out
    dt, stop, quiet, frac = ctl[CT_DT], ctl[CT_STOP], int(ctl[CT_QUIET]), ctl[CT_FRAC]
    cap, cut_jump = int(ctl[CT_CAP]), ctl[CT_CUT]
    Kmax, nc = FF.shape
    nd = dj.size
    nb = bounds.size
    n_p = bounds[0]
    jc = n_p - 1
    n = drive.size
    m_bit, feed = bp[BITP_MASS], bp[BITP_FEED]
    wa = np.empty(nc - 1)
    wb = np.empty(nc - 1)
    for j in range(nc - 1):
        wa[j] = 2.0 * Z[j + 1] / (Z[j] + Z[j + 1])
        wb[j] = 2.0 * Z[j] / (Z[j] + Z[j + 1])
    Fn = np.empty((Kmax, nc))
    Gn = np.empty((Kmax, nc))
    tmp = np.empty((Kmax, nc))
    nd1 = max(nd, 1)
    Fd = np.empty((Kmax, nd1))
    Gout = np.empty((Kmax, nd1))
    ncut_max = nd1 * (2 * Kmax + 1) + 1
    cuts = np.empty(ncut_max)
    eold = np.empty(Kmax + 1)
    ubuf = np.empty(Kmax + 1 + ncut_max)
    idx = np.empty(Kmax + 1 + ncut_max, dtype=np.int64)
    edges = np.empty(2 * Kmax + 1)
    cum = np.empty(2 * Kmax + 1)
    col = np.empty(Kmax)
    scratch = (cuts, eold, ubuf, idx, col, tmp)
    out = np.empty(Kmax)
    Fs = np.empty(nc)
    N = np.empty(nc - 1)
    jrow = np.empty(nb)
    trial = np.empty(bs.size)
    nxt = np.empty(Kmax, dtype=np.int64)
    prv = np.empty(Kmax, dtype=np.int64)
    ver = np.empty(Kmax, dtype=np.int64)
    hk = np.empty(3 * Kmax)
    hi = np.empty(3 * Kmax, dtype=np.int64)
    hv = np.empty(3 * Kmax, dtype=np.int64)
    nW, nWs = ist[IS_NW], ist[IS_NWS]
    contact = ist[IS_CONTACT] != 0
    last, base = ist[IS_LAST], ist[IS_STEP]
    gap, u_shank, grid_loss, work = fst[FS_GAP], fst[FS_USHANK], fst[FS_LOSS], fst[FS_WORK]
    merged = fst[FS_MERGED]
    bitf[0] = _nb_force(bs, bp)
    pen[0] = bs[BIT_P]
    ran, ended = n, 0
    for i in range(n):
        step = base + i
        partial = i == n - 1 and frac < 1.0
        a = 0.0
        for k in range(nW):
            a += GG[k, 0] * W[k]
        arriving[i] = a
        if arr_n.size > 0:
            arr_n[i] = nW
            for k in range(nW):
                arr_W[i, k] = W[k]
                arr_G[i, k] = GG[k, 0]
        if field.shape[0] > 0:
            for j in range(nc):
                f = 0.0
                for k in range(nW):
                    f += (FF[k, j] + GG[k, j]) * W[k]
                field[i, j] = f
        if nd > 0 or partial:
            ncut = 0
            if nd > 0:
                thr = -1.0
                if cut_jump >= 0.0:
                    big = max(_nb_absmax(FF, nW, nc), _nb_absmax(GG, nW, nc))
                    thr = cut_jump * max(big, 1e-300)
                if nWs + nW + 2 > Kmax or nd * (nWs + nW + 1) + nW + 2 > Kmax:
                    return -1
                for r in range(nd):
                    for k in range(nW):
                        col[k] = FF[k, dj[r]]
                    ncut = _nb_jump_cuts(srcF[:, r], Wsrc, nWs, col, W, nW, dd[r], thr, cuts, ncut)
            if partial:
                if nW + 2 > Kmax:
                    return -1
                cuts[ncut] = frac
                ncut += 1
            n_new = _nb_refine(W, nW, cuts, ncut, eold, ubuf, idx)
            if n_new != nW:
                _nb_gather(FF, idx, n_new, tmp)
                _nb_gather(GG, idx, n_new, tmp)
                nW = n_new
        for r in range(nd):
            for k in range(nW):
                col[k] = FF[k, dj[r]]
            _nb_delayed(srcF[:, r], Wsrc, nWs, col, W, nW, dd[r], edges, cum, out)
            for k in range(nW):
                Fd[k, r] = out[k]
                Gout[k, r] = 0.0
        for r in range(nb):
            jrow[r] = 0.0
        pd = drive[i] / frac if partial else drive[i]  # (the drive's impulse over the part run)
        k = 0
        done = 0.0
        while k < nW:
            if partial and done >= frac - 1e-12:
                break
            for j in range(nc):
                Fs[j] = FF[k, j]
            for r in range(nd):
                Fs[dj[r]] = Fd[k, r]
            fa, ga = Fs[jc], GG[k, jc + 1]
            for j in range(nc - 1):
                N[j] = wa[j] * Fs[j] + wb[j] * GG[k, j + 1]
            nw = N[jc]
            if contact and nw < 0.0:
                contact = False  # the welded force pulls: apart from the slot's start
            elif not contact and gap <= 0.0 and nw >= 0.0:
                contact = True
            tau = W[k] * dt
            cut, closes = 1.0, False
            rate = -2.0 * ga / Z[jc + 1] - 2.0 * fa / Z[jc]
            if not contact and rate < 0.0 and gap + rate * tau < 0.0:
                cut, closes = -gap / (rate * tau), True
            Fi = Fs[nc - 1]
            adv = _nb_advance(bs, trial, bp, 2.0 * Fi + feed, tau) / tau
            if adv < cut:
                cut, closes = adv, False
            if TINY < cut < 1.0 - TINY:  # the slot cut at its first event, in every cell
                if nW + 1 > Kmax:
                    return -1
                for mm in range(nW, k + 1, -1):
                    W[mm] = W[mm - 1]
                w_k = W[k]
                W[k] = w_k * cut
                W[k + 1] = w_k * (1.0 - cut)
                _nb_insert(FF, k, nW)
                _nb_insert(GG, k, nW)
                _nb_insert(Fn, k, nW)
                _nb_insert(Gn, k, nW)
                _nb_insert(Fd, k, nW)
                _nb_insert(Gout, k, nW)
                nW += 1
                tau = W[k] * dt
            if contact:
                N[jc] = nw
            else:
                N[jc] = 0.0
                gap = 0.0 if closes else max(gap + rate * tau, 0.0)
            for j in range(nc - 1):
                Fn[k, j + 1] = N[j] - GG[k, j + 1]
                Gn[k, j] = N[j] - Fs[j]
            Fn[k, 0] = pd - GG[k, 0]
            work += pd * (pd - 2.0 * GG[k, 0]) / Z[0] * tau
            p0, w0, ke0 = bs[BIT_P], bs[BIT_WORK], 0.5 * m_bit * bs[BIT_W] * bs[BIT_W]
            bit_step(bs, bp, 2.0 * Fi + feed, tau)
            g_avg = Fi - Z[nc - 1] * (bs[BIT_P] - p0) / tau
            Gn[k, nc - 1] = g_avg
            for r in range(nd):
                Gout[k, r] = Gn[k, dj[r]]
            e_in = (bs[BIT_WORK] - w0) - feed * (bs[BIT_P] - p0) + 0.5 * m_bit * bs[BIT_W] * bs[BIT_W] - ke0
            grid_loss += (Fi * Fi - g_avg * g_avg) * tau / Z[nc - 1] - e_in
            u_shank += (Fn[k, jc + 1] - GG[k, jc + 1]) / Z[jc + 1] * tau
            for r in range(nb):
                jrow[r] += N[bounds[r] - 1] * W[k]
            done += W[k]
            k += 1
        if partial:  # the cells at the end inside the step: what entered before it, what is left after
            for kk in range(k, nW):
                for r in range(nd):
                    Gout[kk, r] = 0.0  # (not sent yet)
            if nd > 0:  # the slots cut where the waves sent back through a delay jump, as on a whole step
                n_new = _send_cuts(state, nW, nWs, Gout, dd, cut_jump, (FF, GG, Fn, Gn, Gout), scratch)
                if n_new < 0:
                    return -1
                if n_new != nW:
                    nW = n_new
                    k, done = 0, 0.0  # (the slots run: those that end by the end)
                    while k < nW and done + W[k] <= frac + 1e-12:
                        done += W[k]
                        k += 1
            for r in range(nd):  # the waves out of each delay over the part run, and its sources
                for kk in range(nW):
                    col[kk] = Gout[kk, r]
                _nb_delayed(srcG[:, r], Wsrc, nWs, col, W, nW, dd[r], edges, cum, out)
                for kk in range(k):
                    Gn[kk, dj[r]] = out[kk]
                    Fd[kk, r] = FF[kk, dj[r]]
            for kk in range(k):
                for j in range(nc):
                    FF[kk, j] = Fn[kk, j]
                    GG[kk, j] = Gn[kk, j]
            for r in range(nb):
                junc[i, r] = jrow[r] / frac
            bitf[i + 1] = _nb_force(bs, bp)
            pen[i + 1] = bs[BIT_P]
            ist[IS_NW], ist[IS_CONTACT], ist[IS_LAST], ist[IS_STEP] = nW, 1 if contact else 0, last, base + n
            ist[IS_ENDED] = 0
            fst[FS_GAP], fst[FS_USHANK], fst[FS_LOSS], fst[FS_WORK] = gap, u_shank, grid_loss, work
            fst[FS_MERGED] = merged
            _nb_ends(state, nW, nWs, (Fd, Gout), k, grid, frac, dt, fst, F_out, G_out)
            return n
        if nd > 0:  # the waves sent back through each delay, on slots cut where they jump
            nW = _send_cuts(state, nW, nWs, Gout, dd, cut_jump, (FF, GG, Fn, Gn, Gout), scratch)
            if nW < 0:
                return -1
        for r in range(nd):
            for k in range(nW):
                col[k] = Gout[k, r]
            _nb_delayed(srcG[:, r], Wsrc, nWs, col, W, nW, dd[r], edges, cum, out)
            for k in range(nW):
                Gn[k, dj[r]] = out[k]
        for r in range(nd):
            for k in range(nW):
                srcF[k, r] = FF[k, dj[r]]
                srcG[k, r] = Gout[k, r]
        for k in range(nW):
            Wsrc[k] = W[k]
        nWs = nW
        if nW > cap:  # (the energy the merges take: the pairs' differences, booked)
            e0 = _nb_energy(Fn, Gn, W, nW, Z, 0, nc)
            nW, _ = _nb_merge(W, nW, Fn, Gn, cap, nxt, prv, ver, hk, hi, hv)
            merged += (e0 - _nb_energy(Fn, Gn, W, nW, Z, 0, nc)) * dt
        for r in range(nb):
            junc[i, r] = jrow[r]
        bitf[i + 1] = _nb_force(bs, bp)
        pen[i + 1] = bs[BIT_P]
        for k in range(nW):
            for j in range(nc):
                FF[k, j] = Fn[k, j]
                GG[k, j] = Gn[k, j]
        if contact:
            last = step
        elif last < 0:
            pass
        elif quiet > 0 and step - last >= quiet:
            ran, ended = i + 1, 2
            break
        if not contact and last >= 0 and step % 8 == 0:
            rod_e = 0.0
            for j in range(n_p, nc):
                e = 0.0
                for k in range(nW):
                    e += (FF[k, j] * FF[k, j] + GG[k, j] * GG[k, j]) * W[k]
                rod_e += e / Z[j]
            if rod_e * dt + 0.5 * m_bit * bs[BIT_W] * bs[BIT_W] < stop:
                ran, ended = i + 1, 1
                break
    _nb_ends(state, nW, nWs, (Fd, Gout), 0, grid, 0.0, dt, fst, F_out, G_out)
    ist[IS_NW], ist[IS_NWS], ist[IS_CONTACT], ist[IS_LAST] = nW, nWs, 1 if contact else 0, last
    ist[IS_STEP], ist[IS_ENDED] = base + ran, ended
    fst[FS_GAP], fst[FS_USHANK], fst[FS_LOSS], fst[FS_WORK] = gap, u_shank, grid_loss, work
    fst[FS_MERGED] = merged
    return ran


class SlotLattice:
    """The slot lattice's state between runs of steps (the module's text), and its runs.

    Parameters
    ----------
    Z : numpy.ndarray, shape (cells,)
        The cells' impedances, piston first (``BlowGrid.Z``).
    bounds : numpy.ndarray of int, shape (J,)
        The cell right of each segment boundary, the shank first (``BlowGrid.bounds``).
    delays : sequence of (int, float)
        Each rod segment's index (0: the shank's) and the fraction of a step its travel time exceeds
        its whole cells by, ``0 <= delta < 1`` (``BlowGrid.delays``).
    F, G : numpy.ndarray, shape (cells,)
        The waves at the start (one slot a step).
    gap : float
        The piston-shank gap at the start (``>= 0``; 0: in contact).
    bs, bp : numpy.ndarray
        The bit's state (updated by :meth:`run`) and parameters (``blow._bit_records``).
    max_slots : int, optional
        At most this many slots a step after its merges (default :data:`MAX_SLOTS`).
    """

    def __init__(self, Z, bounds, delays, F, G, gap, bs, bp, max_slots=MAX_SLOTS):
        self.Z = np.ascontiguousarray(Z, dtype=float)
        self.bounds = np.ascontiguousarray(bounds, dtype=np.int64)
        nc = self.Z.size
        ends = [int(b) - 1 for b in self.bounds[1:]] + [nc - 1]  # each rod segment's last cell
        live = [(ends[int(i)], float(d)) for i, d in delays if d > 0.0]
        self.dj = np.array([j for j, _ in live], dtype=np.int64)
        self.dd = np.array([d for _, d in live], dtype=float)
        self.bs, self.bp = bs, bp
        self.max_slots = int(max_slots)
        kmax = 4 * self.max_slots + 64
        self.FF, self.GG = np.zeros((kmax, nc)), np.zeros((kmax, nc))
        self.FF[0], self.GG[0] = F, G
        self.W = np.zeros(kmax)
        self.W[0] = 1.0
        nd = max(self.dj.size, 1)
        self.srcF, self.srcG = np.zeros((kmax, nd)), np.zeros((kmax, nd))
        for r, j in enumerate(self.dj):
            self.srcF[0, r], self.srcG[0, r] = self.FF[0, j], self.GG[0, j]
        self.Wsrc = self.W.copy()
        self.ist = np.zeros(IS_SIZE, dtype=np.int64)
        self.ist[IS_NW] = self.ist[IS_NWS] = 1
        self.ist[IS_CONTACT] = 1 if gap <= 0.0 else 0
        self.ist[IS_LAST] = 0 if gap <= 0.0 else -1
        self.fst = np.zeros(FS_SIZE)
        self.fst[FS_GAP] = float(gap)

    _ARRAYS = ("FF", "GG", "W", "srcF", "srcG", "Wsrc", "ist", "fst", "bs")

    def copy(self) -> SlotLattice:
        """A copy that runs apart from this one (its arrays copied; the bit's parameters shared)."""
        other = object.__new__(SlotLattice)
        other.__dict__.update(self.__dict__)
        for name in self._ARRAYS:
            setattr(other, name, getattr(self, name).copy())
        return other

    def _grow(self):
        """Twice the rows for the slots (the state's rows kept)."""
        for name in ("FF", "GG", "W", "srcF", "srcG", "Wsrc"):
            a = getattr(self, name)
            b = np.zeros((2 * a.shape[0],) + a.shape[1:])
            b[:a.shape[0]] = a
            setattr(self, name, b)

    @property
    def steps(self) -> int:
        """The steps run so far."""
        return int(self.ist[IS_STEP])

    @property
    def gap(self) -> float:
        """The piston-shank gap now."""
        return float(self.fst[FS_GAP])

    def totals(self) -> tuple[float, float, float, float]:
        """``(u_shank, grid_loss, gap, drive_work)`` over all runs: the shank's displacement, the
        grid's loss (the bit's averaged outgoing wave and the merges), the piston-shank gap and the
        drive's work on the piston."""
        f = self.fst
        return float(f[FS_USHANK]), float(f[FS_LOSS] + f[FS_MERGED]), float(f[FS_GAP]), float(f[FS_WORK])

    def energies(self) -> tuple[float, float, float]:
        """At the end of the last run: the slots' wave energy in the piston and in the rod, and the
        energy of the waves held in the rod's delays (model units)."""
        f = self.fst
        return float(f[FS_PISTON]), float(f[FS_ROD]), float(f[FS_HELD])

    @property
    def ended(self) -> int:
        """How the last run ended: 0 its steps, 1 the energy stop, 2 the piston separated ``quiet``
        steps."""
        return int(self.ist[IS_ENDED])

    def run(self, dt, drive, *, stop=-1.0, quiet=0, frac=1.0, record_field=False, arriving_slots=False):
        """``drive.size`` steps (:func:`slot_steps`), the last to the fraction ``frac`` of it.

        Returns
        -------
        dict
            ``"junc"`` (n, J), ``"bitf"``, ``"pen"`` (n + 1,), ``"field"`` (n, cells) or (0, cells),
            ``"arriving"`` (n,), ``"F"``, ``"G"`` (cells,): the cells' averages at the end; ``n``
            the steps run. With ``arriving_slots`` also ``"arriving_slots"``: for each step the
            widths (fractions of the step) and values of the arriving wave's slots, two arrays each.
        """
        drive = np.ascontiguousarray(drive, dtype=float)
        n, nc, nb = drive.size, self.Z.size, self.bounds.size
        junc = np.zeros((n, nb))
        bitf, pen = np.zeros(n + 1), np.zeros(n + 1)
        field = np.zeros((n if record_field else 0, nc))
        arriving = np.zeros(n)
        F_out, G_out = np.zeros(nc), np.zeros(nc)
        arr_n = np.zeros(n if arriving_slots else 0, dtype=np.int64)
        while True:
            arr_W = np.zeros((arr_n.size, self.W.size))
            arr_G = np.zeros((arr_n.size, self.W.size))
            saved = self.copy()
            ctl = np.zeros(CT_SIZE)
            ctl[CT_DT], ctl[CT_STOP], ctl[CT_QUIET], ctl[CT_FRAC] = dt, stop, quiet, frac
            ctl[CT_CAP], ctl[CT_CUT] = self.max_slots, CUT_JUMP
            ran = slot_steps((self.FF, self.GG, self.W, self.srcF, self.srcG, self.Wsrc), self.ist, self.fst,
                             (self.Z, self.bounds, self.dj, self.dd), (self.bs, self.bp), drive, ctl,
                             (junc, bitf, pen, field, arriving, arr_n, arr_W, arr_G, F_out, G_out))
            if ran >= 0:
                break
            for name in self._ARRAYS:  # too few rows for the slots: again from the copy, with more
                getattr(self, name)[...] = getattr(saved, name)
            self._grow()
        out = {"junc": junc[:ran], "bitf": bitf[:ran + 1], "pen": pen[:ran + 1], "field": field[:ran],
               "arriving": arriving[:ran], "F": F_out, "G": G_out}
        if arriving_slots:
            out["arriving_slots"] = [(arr_W[i, :arr_n[i]].copy(), arr_G[i, :arr_n[i]].copy())
                                     for i in range(ran)]
        return out


internal_kernels(globals(), python=("slot_steps",))  # the others: link-only (kernels call them)
