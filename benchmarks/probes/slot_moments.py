r"""Probe: the slot lattice with each slot's slope carried ("moments"), in numpy, against the exact
blow and the slots as they are (one value a slot), with the drive's force held.

The slot lattice (theory §11; ``RodRock(contact_events="slots")``, its numpy form
:func:`lattice_slots.slot_loop`) holds one value of each wave in each slot, the slot's average. A
cut gives both parts that value: where the wave is not constant over the slot, each part then holds
the average of a wider span than its own, and the events located from those values inside the step
(the re-contact, the bit's) come late or early. Here each slot holds each wave's average and its
slope in time (per unit of the step's fraction), the wave linear inside the slot:

- a cut gives each part the value of the line at its own centre, the same slope;
- the welded junctions, the open and closed contact and the driven end are linear in the waves, so
  the slopes pass through them as the values do (the driven end's force held: slope 0);
- the gap closes on a rate linear in the slot: its first root of a quadratic; a closed contact opens
  where the welded force, linear in the slot, falls through 0 (a cut there);
- a delay projects the delayed line pieces on the slots (each slot's average and first moment, in
  coordinates about the slot's centre), and cuts where the pieces' end values jump;
- a merge projects two slots' lines on one (the L2 projection; the pair that loses least merged);
- the bit is solved under the slot's average input, as now; its outgoing wave gets the slope of the
  incoming wave less the impedance times the bit's velocity change over the slot
  (``bit_slope=False``: 0);
- the fields at impact (cell averages: the piston's linear in space) get slopes in time from the
  differences of the cells' averages within each run of one impedance, a right-going wave's
  reversed (``init_slopes=False``: 0).

Run: ``python benchmarks/probes/slot_moments.py [--rod example] [--cells 8 16 32 64 128]`` from the
repository's root (``--rod`` as in ``slot_delay_fraction.py``). Printed per cell count: the relative
differences of the piston's velocity after the blow and of the work dissipated in the rock from the
exact blow's, for the slots as they are (numpy), the slots with moments, and the moments without the
impact's slopes and without the bit's. With ``--coupled``: the library's coupled blow under the oil
circuit from the tests' arrival (its chunks, its drive, its end) on the library's slots and on
:class:`MomentLattice` (the moments resumable, in ``SlotLattice``'s place), against the exact blow;
``--drive-pieces``: the moments' driven end takes the circuit's force over the drive's intervals;
``--linear-drive``: the circuit takes the moments' arriving wave linear in each slot (every slot's
edge a break of the drive, for both columns).
Figures: ``benchmarks/HISTORY.md``, "slots that carry their slopes".
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks" / "probes"))
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT / "tests" / "laws"))

import lattice_slots as LS  # noqa: E402
from coupled_reference import drifter_arrival, slots_model  # noqa: E402
from slot_delay_fraction import RODS  # noqa: E402

#: A cut closer than this fraction of a step to one of its slot's ends is not made.
TINY = 1e-12
#: A delay cuts where its pieces' ends jump by more than this fraction of the largest wave.
CUT_JUMP = 1e-4
#: More events' cuts in one step than this is taken for a loop that does not advance.
MAX_CUTS = 10_000
#: With ``--linear-drive``, a slot narrower than this fraction of a step hands the circuit its average
#: only (its slope 0: a narrow slot's slope is mostly its rounding).
SLIVER_SLOPE = 1e-6
_bit_advance = LS._bit_advance


def _edges(W):
    e = np.concatenate(([0.0], np.cumsum(W)))
    e[-1] = 1.0
    return e


def _refine(W, pairs, cuts):
    """Slots ``W`` cut at ``cuts``; ``pairs``: list of (values, slopes) arrays (..., slots): the new
    pieces' values moved along the slope to their centres."""
    edges = _edges(W)
    new = np.unique(np.concatenate((edges, cuts)))
    keep = np.concatenate(([True], np.diff(new) > 1e-13))
    new = new[keep]
    if new[-1] < 1.0:
        new[-1] = 1.0
    if new.size == edges.size:
        return W, pairs
    mid = 0.5 * (new[:-1] + new[1:])
    idx = np.minimum(np.searchsorted(edges, mid, side="right") - 1, W.size - 1)
    cold = 0.5 * (edges[:-1] + edges[1:])[idx]
    out = []
    for v, s in pairs:
        out.append((v[..., idx] + s[..., idx] * (mid - cold), s[..., idx].copy()))
    return np.diff(new), out


def _project(pe, pv, ps, te):
    """The piecewise-linear signal (pieces on edges ``pe``, averages ``pv``, slopes ``ps`` per unit)
    projected on the slots of edges ``te`` (within its span): averages and slopes."""
    n = te.size - 1
    av, sl = np.zeros(n), np.zeros(n)
    pc = 0.5 * (pe[:-1] + pe[1:])
    i = 0
    for t in range(n):
        a, b = te[t], te[t + 1]
        w = b - a
        m = 0.5 * (a + b)
        while i < pv.size - 1 and pe[i + 1] <= a:
            i += 1
        j = i
        S0 = S1 = 0.0
        while j < pv.size and pe[j] < b:
            lo, hi = max(pe[j], a), min(pe[j + 1], b)
            if hi > lo:
                # f = a0 + b0 y, y = x - m
                b0 = ps[j]
                a0 = pv[j] + ps[j] * (m - pc[j])
                l, h = lo - m, hi - m
                S0 += a0 * (h - l) + b0 * (h * h - l * l) / 2.0
                S1 += a0 * (h * h - l * l) / 2.0 + b0 * (h ** 3 - l ** 3) / 3.0
            j += 1
        av[t] = S0 / w
        sl[t] = 12.0 * S1 / (w ** 3) if w > 1e-300 else 0.0
    return av, sl


def _joined(prev, W_prev, cur, W, shift):
    """The step before's pieces ``prev`` (on ``W_prev``) and this step's ``cur`` (on ``W``), each
    ``(values, slopes)``, as one signal moved by ``shift`` (fractions of a step): its edges, values and
    slopes."""
    pe = np.concatenate((_edges(W_prev) + shift - 1.0, _edges(W)[1:] + shift))
    return pe, np.concatenate((prev[0], cur[0])), np.concatenate((prev[1], cur[1]))


def _delayed(prev, W_prev, cur, W, delta, target):
    """(averages, slopes) on ``target`` of the P1 signal delayed by ``delta``: ``prev``, ``cur`` each
    (values, slopes)."""
    return _project(*_joined(prev, W_prev, cur, W, delta), _edges(target))


def _ends(v, s, W):
    """Left and right end values of each piece."""
    return v - 0.5 * s * W, v + 0.5 * s * W


def _jump_cuts(prev, W_prev, cur, W, delta, thr):
    lp, rp = _ends(prev[0], prev[1], W_prev)
    lc, rc = _ends(cur[0], cur[1], W)
    ep = np.cumsum(W_prev)[:-1][np.abs(lp[1:] - rp[:-1]) > thr] + delta - 1.0
    ec = np.cumsum(W)[:-1][np.abs(lc[1:] - rc[:-1]) > thr] + delta
    out = [ep[ep > 0.0], ec[ec < 1.0]]
    if abs(lc[0] - rp[-1]) > thr and 0.0 < delta < 1.0:
        out.append([delta])
    return np.concatenate(out)


def _merge(W, pairs, cap):
    """Adjacent slots merged (their P1 pieces projected on one) by least L2 loss until ``cap``."""
    if W.size <= cap:
        return W, pairs
    V = np.concatenate([p[0] for p in pairs], axis=0)
    S = np.concatenate([p[1] for p in pairs], axis=0)
    W = W.copy()

    def merged(i):
        w1, w2 = W[i], W[i + 1]
        w = w1 + w2
        c1, c2, cm = -0.5 * w1, 0.5 * w2, 0.5 * (w2 - w1)
        v = (V[:, i] * w1 + V[:, i + 1] * w2) / w
        M = (V[:, i] * w1 * (c1 - cm) + S[:, i] * w1 ** 3 / 12.0
             + V[:, i + 1] * w2 * (c2 - cm) + S[:, i + 1] * w2 ** 3 / 12.0)
        s = 12.0 * M / w ** 3
        return v, s

    def pair_loss(i):
        v, s = merged(i)
        return float(np.sum(_piece_energies(V[:, i], S[:, i], W[i])
                            + _piece_energies(V[:, i + 1], S[:, i + 1], W[i + 1])
                            - _piece_energies(v, s, W[i] + W[i + 1])))

    loss = np.array([pair_loss(i) for i in range(W.size - 1)])
    while W.size > cap:
        i = int(np.argmin(loss))
        v, s = merged(i)
        V[:, i], S[:, i] = v, s
        W[i] = W[i] + W[i + 1]
        V = np.delete(V, i + 1, axis=1)
        S = np.delete(S, i + 1, axis=1)
        W = np.delete(W, i + 1)
        loss = np.delete(loss, i)
        if i < W.size - 1:
            loss[i] = pair_loss(i)
        if i > 0:
            loss[i - 1] = pair_loss(i - 1)
    rows = np.cumsum([0] + [p[0].shape[0] for p in pairs])
    return W, [(V[rows[j]:rows[j + 1]], S[rows[j]:rows[j + 1]]) for j in range(len(pairs))]


def _root_quadratic(g0, A, B, w):
    """First 0 < y <= w with g0 + B y + A y^2 = 0 (g0 > 0), else None."""
    best = None
    if A == 0.0:
        if B < 0.0:
            y = -g0 / B
            if 0.0 < y <= w:
                best = y
        return best
    D = B * B - 4.0 * A * g0
    if D < 0.0:
        return None
    sq = math.sqrt(D)
    q = -0.5 * (B + sq) if B >= 0.0 else -0.5 * (B - sq)
    for y in (q / A, g0 / q if q != 0.0 else None):
        if y is not None and 0.0 < y <= w and (best is None or y < best):
            best = y
    return best


def _root_linear(v0, v1, w):
    """Where the linear function from ``v0`` (at 0) to ``v1`` (at w) crosses 0, inside."""
    if (v0 >= 0.0) == (v1 >= 0.0) or v0 == v1:
        return None
    return w * v0 / (v0 - v1)


def _split(v, s, k, w1, w2):
    """Slot ``k`` (width ``w1 + w2``) of the lines ``v``, ``s`` (rows, slots) cut in two: each part
    the line's value at its own centre, the same slope."""
    out = np.insert(v, k + 1, v[:, k] + s[:, k] * 0.5 * w1, axis=1)
    out[:, k] = out[:, k] - s[:, k] * 0.5 * w2
    return out, np.insert(s, k + 1, s[:, k], axis=1)


def _piece_energies(v, s, W):
    """Each slot's ``int (v + s y)^2`` over it (per unit of the step's fraction)."""
    return W * (v * v + s * s * W * W / 12.0)


def _wave_energy(F, SF, G, SG, W, Z, cells):
    """The waves' energy over the step in the cells ``cells`` (both families; per unit time of a
    step's fraction): ``sum (int F^2 + int G^2) / Z``."""
    return sum((float(np.sum(_piece_energies(F[j], SF[j], W)))
                + float(np.sum(_piece_energies(G[j], SG[j], W)))) / Z[j] for j in cells)


def _window_energy(prev, W_prev, cur, W, a, b):
    """int over [a, b] (fractions of the current step; a may be < 0: the step before) of the P1
    signal (the step before ``prev`` on ``W_prev``, this one ``cur`` on ``W``) squared."""
    pe, pv, ps = _joined(prev, W_prev, cur, W, 0.0)
    pc = 0.5 * (pe[:-1] + pe[1:])
    e = 0.0
    for j in range(pv.size):
        lo, hi = max(pe[j], a), min(pe[j + 1], b)
        if hi > lo:
            l, h = lo - pc[j], hi - pc[j]
            v, s = pv[j], ps[j]
            e += v * v * (h - l) + v * s * (h * h - l * l) + s * s * (h ** 3 - l ** 3) / 3.0
    return e


class _DrivePieces:
    """The oil circuit's force over the intervals of the coupled blow's drive (the intervals its
    :meth:`~impactbar.drives.circuit.HydraulicCircuitDrive.end_flight` was flown over, inside the
    steps where the arriving wave jumps), recorded by :meth:`wrap` and read by :class:`MomentLattice`
    in place of each step's average (``--drive-pieces``)."""

    def __init__(self):
        self.on, self.t0, self.intervals = False, 0.0, {}

    def wrap(self, end_flight):
        def recorded(model, state, breaks, w0, incoming, impedance, settings=None):
            fl = end_flight(model, state, breaks, w0, incoming, impedance, settings)
            self.intervals[float(breaks[0])] = (np.asarray(breaks, dtype=float), np.asarray(fl.impulses))
            return fl
        return recorded

    def pieces(self, step, dt, average):
        """The intervals inside step ``step`` (edges as fractions of it, their forces) whose impulse
        is ``average`` times the step (the lattice's drive of the step), else ``None``."""
        if not self.on:
            return None
        a, b = self.t0 + step * dt, self.t0 + (step + 1) * dt
        for _start, (breaks, impulses) in sorted(self.intervals.items(), key=lambda kv: -kv[0]):
            if breaks[0] > a + 1e-9 * dt or breaks[-1] < a + 1e-9 * dt:
                continue
            inside = (breaks[:-1] >= a - 1e-9 * dt) & (breaks[:-1] < b - 1e-9 * dt)
            idx = np.flatnonzero(inside)
            if idx.size == 0:
                continue
            edges = np.concatenate(((breaks[idx] - a) / dt, [(breaks[idx[-1] + 1] - a) / dt]))
            if abs(np.sum(impulses[idx]) / dt - average) > 1e-9 * max(abs(average), 1e-300):
                continue
            values = impulses[idx] / (np.diff(edges) * dt)
            edges[0], edges[-1] = 0.0, min(edges[-1], 1.0)
            return edges, values
        return None


DRIVE_PIECES = _DrivePieces()


class MomentLattice:
    """The slots with moments in the interface of the library's
    :class:`~impactbar.laws.rodrock._rockslots.SlotLattice` (resumable between the coupled blow's
    chunks; numpy, the bit as :class:`~impactbar.laws.rodrock._bit._Bit`), to run the library's
    coupled blow under the oil circuit on them (``--coupled``). Its energy account is not kept to
    rounding (what a step's end inside a step leaves in the delays is approximated)."""

    init_slopes = True
    bit_slope = True

    def __init__(self, Z, bounds, delays, F, G, gap, bs, bp, max_slots=24):
        self.Z = np.ascontiguousarray(Z, dtype=float)
        self.bounds = np.ascontiguousarray(bounds, dtype=np.int64)
        nc = self.Z.size
        ends = [int(b) - 1 for b in self.bounds[1:]] + [nc - 1]
        self.D = [(ends[int(i)], float(d)) for i, d in delays if d > 0.0]
        self.bs, self.bp = bs, bp
        self.max_slots = int(max_slots)
        self.FF = np.array(F, dtype=float)[:, None].copy()
        self.GG = np.array(G, dtype=float)[:, None].copy()
        self.SF, self.SG = np.zeros_like(self.FF), np.zeros_like(self.GG)
        if self.init_slopes:
            runs = [0] + [j for j in range(1, nc) if self.Z[j] != self.Z[j - 1]] + [nc]
            for a_, b_ in zip(runs[:-1], runs[1:], strict=True):
                if b_ - a_ >= 2:
                    self.SF[a_:b_, 0] = -np.gradient(self.FF[a_:b_, 0])
                    self.SG[a_:b_, 0] = np.gradient(self.GG[a_:b_, 0])
        self.W = np.array([1.0])
        self.srcF = [(self.FF[j].copy(), self.SF[j].copy()) for j, _ in self.D]
        self.srcG = [(self.GG[j].copy(), self.SG[j].copy()) for j, _ in self.D]
        self.W_src = self.W.copy()
        self._gap = float(gap)
        self.contact = gap <= 0.0
        self.last = 0 if gap <= 0.0 else -1
        self.base = 0
        self.u_shank = self.grid_loss = self.work = self.merged = 0.0
        self._ended = 0
        self._energies = (0.0, 0.0, 0.0)

    def copy(self):
        other = object.__new__(MomentLattice)
        other.__dict__.update(self.__dict__)
        for name in ("FF", "GG", "SF", "SG", "W", "W_src", "bs"):  # (the bit's parameters shared)
            setattr(other, name, getattr(self, name).copy())
        other.srcF = [(a.copy(), b.copy()) for a, b in self.srcF]
        other.srcG = [(a.copy(), b.copy()) for a, b in self.srcG]
        return other

    @property
    def steps(self):
        return self.base

    @property
    def gap(self):
        return self._gap

    def totals(self):
        return self.u_shank, self.grid_loss + self.merged, self._gap, self.work

    def energies(self):
        return self._energies

    @property
    def ended(self):
        return self._ended

    def _end_energies(self, FF, SF, GG, SG, W, dt, Fcur, Gout_cur, at):
        Z = self.Z
        n_p = int(self.bounds[0])
        ep = sum(_wave_energy(FF, SF, GG, SG, W, Z, [j]) * dt for j in range(n_p))
        er = sum(_wave_energy(FF, SF, GG, SG, W, Z, [j]) * dt for j in range(n_p, Z.size))
        held = 0.0
        for i, (j, d) in enumerate(self.D):
            e = _window_energy(self.srcF[i], self.W_src, Fcur[i], W, at - d, at)
            e += _window_energy(self.srcG[i], self.W_src, Gout_cur[i], W, at - d, at)
            held += e * dt / Z[j]
        self._energies = (ep, er, held)

    def run(self, dt, drive, *, stop=-1.0, quiet=0, frac=1.0, record_field=False, arriving_slots=False):
        from impactbar.laws.rodrock._bit import _Bit
        from impactbar.laws.rodrock._records import BITP_FEED, BITP_K, BITP_KU, BITP_MASS, BITP_Z
        from impactbar.laws.rodrock.blow import _bit_records, _set_bit

        drive = np.asarray(drive, dtype=float)
        Z = self.Z
        Za, Zb = Z[:-1], Z[1:]
        wa, wb = 2.0 * Zb / (Za + Zb), 2.0 * Za / (Za + Zb)
        bounds = self.bounds
        n_p = int(bounds[0])
        nc = Z.size
        jc = n_p - 1
        D = self.D
        nd = len(D)
        bs, bp = self.bs, self.bp
        m, feed = bp[BITP_MASS], bp[BITP_FEED]
        bit = _Bit(bp[BITP_Z], bp[BITP_K], bp[BITP_KU], m, feed)
        _set_bit(bit, bs)
        FF, GG, SF, SG, W = self.FF, self.GG, self.SF, self.SG, self.W
        n = drive.size
        junc = np.zeros((n, bounds.size))
        bitf, pen = np.zeros(n + 1), np.zeros(n + 1)
        field = np.zeros((n if record_field else 0, nc))
        arriving = np.zeros(n)
        arr = []
        bitf[0], pen[0] = bit.force(), bit.p
        gap, contact, last = self._gap, self.contact, self.last
        ran, ended = n, 0
        for i in range(n):
            step = self.base + i
            arriving[i] = float(GG[0] @ W)
            if arriving_slots:
                arr.append((W.copy(), GG[0].copy(), SG[0].copy()))  # (a third: the slopes)
            if record_field:
                field[i] = (FF + GG) @ W
            partial = i == n - 1 and frac < 1.0
            if nd:
                big = max(float(np.abs(FF).max()), float(np.abs(GG).max()), 1e-300)
                thr = CUT_JUMP * big
                cuts = [_jump_cuts(self.srcF[r], self.W_src, (FF[j], SF[j]), W, d, thr)
                        for r, (j, d) in enumerate(D)]
                W, ((FF, SF), (GG, SG)) = _refine(W, [(FF, SF), (GG, SG)], np.concatenate(cuts))
            if partial:
                W, ((FF, SF), (GG, SG)) = _refine(W, [(FF, SF), (GG, SG)], np.array([frac]))
            pieces = DRIVE_PIECES.pieces(self.base + i, dt, drive[i])
            if pieces is not None:  # the drive's intervals inside the step: the slots cut at their edges
                W, ((FF, SF), (GG, SG)) = _refine(W, [(FF, SF), (GG, SG)], pieces[0][1:-1])
            Fd, Sd = np.zeros((nd, W.size)), np.zeros((nd, W.size))
            for r, (j, d) in enumerate(D):
                Fd[r], Sd[r] = _delayed(self.srcF[r], self.W_src, (FF[j], SF[j]), W, d, W)
            Gout, SGout = np.zeros((nd, W.size)), np.zeros((nd, W.size))
            Fn, Gn = np.zeros_like(FF), np.zeros_like(GG)
            SFn, SGn = np.zeros_like(FF), np.zeros_like(GG)
            jrow = np.zeros(bounds.size)
            pd = drive[i] / frac if partial else drive[i]
            k, at, ncuts = 0, 0.0, 0

            def slot_values(k, FF, SF, GG, SG, Fd, Sd):
                """Slot ``k``'s arriving waves (the delays' outputs in their cells), the welded
                junctions' forces and the open gap's closing rate, each value and slope."""
                Fs, Ss = FF[:, k].copy(), SF[:, k].copy()
                for r, (j, _d) in enumerate(D):
                    Fs[j], Ss[j] = Fd[r, k], Sd[r, k]
                N = wa * Fs[:-1] + wb * GG[1:, k]
                NS = wa * Ss[:-1] + wb * SG[1:, k]
                rv = -2.0 * GG[jc + 1, k] / Zb[jc] - 2.0 * Fs[jc] / Za[jc]
                rs = -2.0 * SG[jc + 1, k] / Zb[jc] - 2.0 * Ss[jc] / Za[jc]
                return Fs, Ss, N, NS, rv, rs

            while k < W.size:
                if partial and at >= frac - 1e-12:
                    break
                Fs, Ss, N, NS, rv, rs = slot_values(k, FF, SF, GG, SG, Fd, Sd)
                w = W[k]
                nw, nws = N[jc], NS[jc]
                nw0 = nw - 0.5 * nws * w
                if contact and (nw0 < 0.0 or (nws < 0.0 and nw0 <= -1e-9 * nws * w)):
                    contact = False
                elif (not contact and gap <= 0.0 and nw0 >= 0.0
                      and not (nws < 0.0 and nw0 <= -1e-9 * nws * w)):
                    contact = True
                cut, closes = 1.0, False
                if not contact:
                    y = None
                    if gap > 0.0:
                        y = _root_quadratic(gap, dt * rs / 2.0, dt * (rv - rs * w / 2.0), w)
                    if y is not None:
                        cut, closes = min(y / w, 1.0), True
                else:
                    y = _root_linear(nw0, nw + 0.5 * nws * w, w)
                    if y is not None:
                        cut = y / w
                adv = _bit_advance(copy.copy(bit), 2.0 * Fs[-1] + feed, w * dt) / (w * dt)
                if adv < cut:
                    cut, closes = adv, False
                if TINY < cut * w and (1.0 - cut) * w > TINY:  # the slot cut at its first event
                    ncuts += 1
                    if ncuts > MAX_CUTS:
                        raise RuntimeError(f"step {step}: too many cuts")
                    w1, w2 = w * cut, w * (1.0 - cut)
                    W = np.concatenate((W[:k], [w1, w2], W[k + 1:]))
                    FF, SF = _split(FF, SF, k, w1, w2)
                    GG, SG = _split(GG, SG, k, w1, w2)
                    Fd, Sd = _split(Fd, Sd, k, w1, w2)
                    Fn, SFn, Gn, SGn, Gout, SGout = (np.insert(x, k + 1, x[:, k], axis=1)
                                                     for x in (Fn, SFn, Gn, SGn, Gout, SGout))
                    Fs, Ss, N, NS, rv, rs = slot_values(k, FF, SF, GG, SG, Fd, Sd)  # (its left part's)
                    w = W[k]
                    nw, nws = N[jc], NS[jc]
                Fi = Fs[-1]
                tau = w * dt
                if contact:
                    N[jc], NS[jc] = nw, nws
                else:
                    N[jc], NS[jc] = 0.0, 0.0
                    gap = 0.0 if closes else max(gap + rv * tau, 0.0)
                Fn[1:, k] = N - GG[1:, k]
                SFn[1:, k] = NS - SG[1:, k]
                Gn[:-1, k] = N - Fs[:-1]
                SGn[:-1, k] = NS - Ss[:-1]
                if pieces is not None:  # (the drive's interval that holds the slot)
                    c = at + 0.5 * W[k]
                    pd = pieces[1][min(np.searchsorted(pieces[0], c) - 1, pieces[1].size - 1)]
                Fn[0, k] = pd - GG[0, k]
                SFn[0, k] = -SG[0, k]
                self.work += pd * (pd - 2.0 * GG[0, k]) / Z[0] * tau
                p0, w0, ke0 = bit.p, bit.work, 0.5 * m * bit.w ** 2
                E = 2.0 * Fi + feed
                if m == 0.0:
                    b_, ref_ = bit._coeffs()
                    v_start = (E - b_ * (p0 - ref_)) / Z[-1]
                else:
                    v_start = bit.w
                bit.step(E, tau)
                g_avg = Fi - Z[-1] * (bit.p - p0) / tau
                Gn[-1, k] = g_avg
                SGn[-1, k] = (Ss[-1] - Z[-1] * (bit.w - v_start) / w) if self.bit_slope else 0.0
                for r, (j, _d) in enumerate(D):
                    Gout[r, k], SGout[r, k] = Gn[j, k], SGn[j, k]
                e_in = (bit.work - w0) - feed * (bit.p - p0) + 0.5 * m * bit.w ** 2 - ke0
                self.grid_loss += ((Fi * Fi + Ss[-1] ** 2 * w * w / 12.0)
                                   - (g_avg * g_avg + SGn[-1, k] ** 2 * w * w / 12.0)) * tau / Z[-1] - e_in
                self.u_shank += (Fn[jc + 1, k] - GG[jc + 1, k]) / Zb[jc] * tau
                jrow += N[bounds - 1] * W[k]
                at += W[k]
                k += 1
            if partial:
                kf = k
                F_out = Fn[:, :kf] @ W[:kf] + FF[:, kf:] @ W[kf:]
                G_out = Gn[:, :kf] @ W[:kf] + GG[:, kf:] @ W[kf:]
                junc[i] = jrow / frac
                bitf[i + 1], pen[i + 1] = bit.force(), bit.p
                # energies at the end: the slots run (their new waves) and those not run
                FFe = np.concatenate((Fn[:, :kf], FF[:, kf:]), axis=1)
                SFe = np.concatenate((SFn[:, :kf], SF[:, kf:]), axis=1)
                GGe = np.concatenate((Gn[:, :kf], GG[:, kf:]), axis=1)
                SGe = np.concatenate((SGn[:, :kf], SG[:, kf:]), axis=1)
                self._end_energies(FFe, SFe, GGe, SGe, W, dt, [(FF[j], SF[j]) for j, _ in D],
                                   [(Gout[r], SGout[r]) for r in range(nd)], frac)
                self.FF, self.GG, self.SF, self.SG, self.W = FFe, GGe, SFe, SGe, W
                self._gap, self.contact, self.last, self.base = gap, contact, last, self.base + n
                self._ended = 0
                bs[:] = _bit_records(bit)[0]
                return self._out(junc, bitf, pen, field, arriving, F_out, G_out, arr)
            if nd:
                thr = CUT_JUMP * max(float(np.abs(Gout).max()), 1e-300)
                cuts = np.concatenate([_jump_cuts(self.srcG[r], self.W_src, (Gout[r], SGout[r]), W, d, thr)
                                       for r, (_j, d) in enumerate(D)])
                W, ((FF, SF), (Fn, SFn), (Gn, SGn), (Gout, SGout)) = _refine(
                    W, [(FF, SF), (Fn, SFn), (Gn, SGn), (Gout, SGout)], cuts)
            for r, (j, d) in enumerate(D):
                Gn[j], SGn[j] = _delayed(self.srcG[r], self.W_src, (Gout[r], SGout[r]), W, d, W)
            self.srcF = [(FF[j].copy(), SF[j].copy()) for j, _ in D]
            self.srcG = [(Gout[r].copy(), SGout[r].copy()) for r in range(nd)]
            self.W_src = W.copy()
            if W.size > self.max_slots:
                e0 = _wave_energy(Fn, SFn, Gn, SGn, W, Z, range(nc))
                W, ((Fn, SFn), (Gn, SGn)) = _merge(W, [(Fn, SFn), (Gn, SGn)], self.max_slots)
                self.merged += (e0 - _wave_energy(Fn, SFn, Gn, SGn, W, Z, range(nc))) * dt
            junc[i] = jrow
            bitf[i + 1], pen[i + 1] = bit.force(), bit.p
            FF, GG, SF, SG = Fn, Gn, SFn, SGn
            if contact:
                last = step
            elif last < 0:
                pass
            elif quiet > 0 and step - last >= quiet:
                ran, ended = i + 1, 2
                break
            if not contact and last >= 0 and step % 8 == 0:
                rod_e = _wave_energy(FF, SF, GG, SG, W, Z, range(n_p, nc))
                if rod_e * dt + 0.5 * m * bit.w ** 2 < stop:
                    ran, ended = i + 1, 1
                    break
        self.FF, self.GG, self.SF, self.SG, self.W = FF, GG, SF, SG, W
        self._gap, self.contact, self.last, self.base = gap, contact, last, self.base + ran
        self._ended = ended
        bs[:] = _bit_records(bit)[0]
        self._end_energies(FF, SF, GG, SG, W, dt, [(FF[j], SF[j]) for j, _ in D],
                           [(np.zeros(W.size), np.zeros(W.size)) for r in range(nd)], 0.0)
        return self._out(junc[:ran], bitf[:ran + 1], pen[:ran + 1], field[:ran], arriving[:ran],
                         FF @ W, GG @ W, arr[:ran])

    @staticmethod
    def _out(junc, bitf, pen, field, arriving, F, G, arr):
        return {"junc": junc, "bitf": bitf, "pen": pen, "field": field, "arriving": arriving, "F": F, "G": G,
                "arriving_slots": arr}


class _NoImpactSlopes(MomentLattice):
    init_slopes = False


class _NoBitSlope(MomentLattice):
    bit_slope = False


def held(rod, cells) -> None:
    """The blow with the drive's force held (``coupled_reference.held_blow``) on the library's slots
    and on :class:`MomentLattice` and its two variants (each in ``SlotLattice``'s place, 24 slots a
    step), against the exact blow: the relative differences of the velocity after and the work
    dissipated."""
    from coupled_reference import held_blow

    from impactbar.laws.rodrock import _rockslots

    arrival = drifter_arrival(RODS[rod])
    model = arrival[0]
    v_ex, w_ex = held_blow(arrival, model)
    plain = _rockslots.SlotLattice
    variants = {"slots": plain, "moments": MomentLattice, "no impact slopes": _NoImpactSlopes,
                "no bit slope": _NoBitSlope}
    print(f"rod {rod}: relative differences from the exact blow (velocity after, work dissipated)")
    print("cells | " + " | ".join(f"{name:>19s}" for name in variants))
    try:
        for n in cells:
            cols = []
            for cls in variants.values():
                _rockslots.SlotLattice = cls
                v, w = held_blow(arrival, slots_model(model, n))
                cols.append(f"{v / v_ex - 1.0:+.2e} {w / w_ex - 1.0:+.2e}")
            print(f"{n:5d} | " + " | ".join(cols), flush=True)
    finally:
        _rockslots.SlotLattice = plain


def _linear_drive_input(plain):
    """``_Slots.drive_input`` whose intervals take the arriving wave linear in each of its slots
    (:class:`MomentLattice`'s slopes, where its arriving slots carry them) rather than constant: a
    callable with a ``spline`` (the form the circuit's compiled flight takes, as the exact blow's)."""

    def drive_input(self, arriving, k, t0, L, frac=1.0):
        breaks, values, starts = plain(self, arriving, k, t0, L, frac)
        if not all(len(a) == 3 for a in arriving[:L]):
            return breaks, values, starts
        dt, z0 = self.grid.cell_time, float(self.grid.Z[0])
        lo, hi, val, slope = [], [], [], []
        for i in range(L):
            W, g, sg = arriving[i]
            edges = t0 + dt * (k + i + np.concatenate(([0.0], np.cumsum(W))))
            lo += list(edges[:-1])
            hi += list(edges[1:])
            val += list(-2.0 * g / z0)
            slope += list(-2.0 * sg / z0 / dt)  # (per unit time)
        lo, hi, val, slope = (np.array(x) for x in (lo, hi, val, slope))
        slope[hi - lo < SLIVER_SLOPE * dt] = 0.0  # (a sliver's slope is its rounding: constant there)
        incoming = []
        for a, b in zip(breaks[:-1], breaks[1:], strict=True):
            inside = np.flatnonzero((hi > a + 1e-12 * dt) & (lo < b - 1e-12 * dt))
            starts_ = np.maximum(lo[inside], a) - a
            keep = np.ones(inside.size, dtype=bool)  # (a segment narrower than 1e-9 of a step: its
            last = 0                                  # neighbour's line goes on over it)
            for j in range(1, inside.size):
                if starts_[j] - starts_[last] <= 1e-9 * dt or (b - a) - starts_[j] <= 1e-9 * dt:
                    keep[j] = False
                else:
                    last = j
            inside, starts_ = inside[keep], starts_[keep]
            knots = np.concatenate((starts_, [b - a]))
            centre = 0.5 * (lo[inside] + hi[inside]) - a
            c = np.zeros((4, inside.size))
            c[2] = slope[inside]
            c[3] = val[inside] + slope[inside] * (knots[:-1] - centre)
            incoming.append(_spline_function(knots, c, float(a)))
        return breaks, incoming, starts

    return drive_input


def _spline_function(x, c, t0):
    """A callable of the time with the ``spline`` attribute ``(x, c, t0)`` (piecewise cubic in
    ``t - t0``, scipy's order of coefficients)."""

    def a(t):
        tt = t - t0
        i = min(max(int(np.searchsorted(x, tt, side="right")) - 1, 0), x.size - 2)
        s = tt - x[i]
        return ((c[3, i] + c[2, i] * s) + c[1, i] * s * s) + c[0, i] * s ** 3

    a.spline = (x, c, t0)
    return a


def coupled(rod, cells, drive_pieces=False, linear_drive=False) -> None:
    """The library's coupled blow under the oil circuit from the tests' arrival on the slots as they
    are and on :class:`MomentLattice` (put in the place of ``SlotLattice``), against the exact
    blow: the relative differences of the work dissipated in the rock, the circuit's state after the
    blow (its largest component's) and the piston's velocity after it."""
    from coupled_reference import blow_differences

    from impactbar.laws.rodrock import _rockslots
    from impactbar.laws.rodrock import coupled as coupled_module

    model, drive, state, t0, q, v = drifter_arrival(RODS[rod])
    ex = model.law.driven_contact(model, drive, state, t0, q, v)
    plain = _rockslots.SlotLattice
    plain_input = coupled_module._Slots.drive_input
    plain_jump = coupled_module.DRIVE_JUMP
    if linear_drive:  # (every slot's edge a break: the lines meet the integrator one at a time)
        coupled_module._Slots.drive_input = _linear_drive_input(plain_input)
        coupled_module.DRIVE_JUMP = -1.0
    if drive_pieces:  # (the moments take the circuit's force over the drive's intervals)
        drive.__dict__["abilities"] = dataclasses.replace(
            drive.abilities, end_flight=DRIVE_PIECES.wrap(drive.abilities.end_flight))
        DRIVE_PIECES.t0 = float(t0)
    print(f"rod {rod}, the coupled blow: relative differences from the exact blow (work, circuit's state, "
          "velocity after)")
    print(f"cells | {'slots':>26s} | {'moments':>26s}")
    try:
        for n in cells:
            cols = []
            for cls in (plain, MomentLattice):
                _rockslots.SlotLattice = cls  # (both at their default of 24 slots a step)
                DRIVE_PIECES.on, DRIVE_PIECES.intervals = drive_pieces and cls is MomentLattice, {}
                m = slots_model(model, n)
                d = blow_differences(m.law.driven_contact(m, drive, state, t0, q, v), ex)
                cols.append(f"{d[0]:.2e} {d[2]:.2e} {d[3]:.2e}")
            print(f"{n:5d} | " + " | ".join(cols), flush=True)
    finally:
        _rockslots.SlotLattice = plain
        coupled_module._Slots.drive_input = plain_input
        coupled_module.DRIVE_JUMP = plain_jump


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rod", choices=sorted(RODS), default="example")
    parser.add_argument("--cells", type=int, nargs="+", default=[8, 16, 32, 64, 128])
    parser.add_argument("--coupled", action="store_true",
                        help="the coupled blow under the oil circuit (the slots and the moments only)")
    parser.add_argument("--drive-pieces", action="store_true",
                        help="with --coupled: the moments' driven end takes the circuit's force over the "
                             "drive's intervals inside each step, not the step's average")
    parser.add_argument("--linear-drive", action="store_true",
                        help="with --coupled: the circuit takes the moments' arriving wave linear in "
                             "each slot")
    args = parser.parse_args(argv)
    if args.coupled:
        coupled(args.rod, args.cells, args.drive_pieces, args.linear_drive)
        return

    held(args.rod, args.cells)


if __name__ == "__main__":
    main()
