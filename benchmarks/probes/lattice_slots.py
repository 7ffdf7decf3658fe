r"""Probe: a lattice whose steps carry the blow's events inside them ("slots"), against the exact blow
and the library's lattice, on ``examples/circuit_drifter_rock.toml``'s rod from the orbit's second
arrival (``bench_coupled_exact.arrival()``) with the drive's force held at the arrival's.

Why. The library's lattice (:func:`impactbar.laws.rodrock.blow._python_loop`, compiled as
``_rockloop.blow_loop``) holds one value of each characteristic in each cell. A piston-shank
re-contact, the bit's landing or a rock branch change inside a step sends a front into the rod or the
piston that starts inside a cell; the cell averages cannot say where, so the next switch that front
causes is found at a step's end again, and the blow converges at first order, not monotonically
(``probes/lattice_order.py``).

What is tried here. Every wave travels one cell a step, so a front that starts a fraction ``a`` into
a step stays that fraction into every step it reaches. Each step is cut into *slots* (fractions of
the step, the same cuts for every cell), and each cell holds one value of each characteristic per
slot: the waves are piecewise constant between the events' instants, exactly. A slot is processed
as a step of its own length: the welded junctions, the piston's driven end (the drive's force of
the step), the bit over the slot's time under its constant input (its outgoing wave the slot's
average). An event inside a slot (the gap closing, linear in time under constant waves; the bit's
first branch change, the rock's loading, unloading, the bit's lift-off or landing) cuts that slot,
and the cut is made in every cell, so the new front keeps its position for good. Separations need
no cut: the welded force is constant over a slot, so the contact opens at a slot's start. The cuts
are capped (``--max-slots``, default 24): past the cap two adjacent slots are merged, their values
averaged by width, the pair whose average loses least (the L2 difference of their values over the
cells times ``w_1 w_2 / (w_1 + w_2)``; ``--merge narrow``: the pair of least width). A rod segment
whose travel time is not whole steps ("segments delayed") is its whole cells and a delay of the
fraction ``delta`` of a step at its far end: the delayed waves' slot averages exact (each slot's
integral), the slots cut where a delayed wave jumps by more than ``F`` of the largest wave
(``--cut-jump F``, default 1e-4; ``-1``: at its every edge), so that they stay exact until a merge.

Measured on 0abc7a7d (``--cells 8 16 32 64 128 --delays-up-to 32 --max-slots 12 --cut-jump -1``,
the window 14 piston travel
times, one process), the piston's velocity after the blow relative to the exact blow's:

| cells | rounded rod: step | inside | slots | true rod: step | inside | slots | slots, delayed |
| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |
| 8 | 1.7e-2 | -1.4e-2 | 1.7e-3 | 5.3e-3 | -2.6e-2 | -1.0e-2 | 1.3e-5 |
| 16 | 3.0e-3 | -1.1e-3 | -9.0e-5 | -1.4e-2 | -1.8e-2 | -1.7e-2 | -4.3e-7 |
| 32 | 1.1e-2 | -1.4e-4 | -3.0e-7 | 2.9e-2 | 1.8e-2 | 1.8e-2 | 3.6e-7 |
| 64 | 4.5e-3 | -9.8e-5 | 8.3e-6 | 3.4e-3 | -1.2e-3 | -1.0e-3 | not run |
| 128 | 1.8e-3 | -2.5e-5 | 3.5e-6 | 7.5e-4 | -1.1e-3 | -1.1e-3 | not run |

The piston's displacement after the blow moves alike (with the delays 4.6e-5, 4.4e-6, 5.4e-6); the
work dissipated in the rock is the same in the three lattices without delays (5.7e-8 to 2e-10 on
the rounded rod, 1.7e-6 to 1.1e-7 on the true rod), with them -1.45e-6, -4.1e-7, -3.0e-8. So:

- the events inside the steps, held as slots, take out the error the events make: on the rounded
  rod the slots are 7 to 460 times closer to the exact blow than ``contact_events="inside"``, with
  9 or 10 cuts a blow (at most 10 slots a step);
- on the rod as given they change nothing: its segments rounded to whole cells (their travel times
  1.9 % off on 8 and 16 cells, 1.6 % on 32, 0.13 % on 64 and 128) make the error;
- the segments delayed bring the true rod to the rounded rod's accuracy and past it, 1.3e-5 on 8
  cells, but at a cost: every edge a delay moves is a cut, and 3,358, 104,263 and 995,312 merges a
  blow take the numpy loop to 0.40, 12 and 345 s (the slots without delays: 0.04, 0.08, 0.16 s).
  Merging the narrowest pair instead (``--merge narrow``, 48 slots) smears the fronts: 1.3e-4 and
  8.7e-4 on 8 and 16 cells. Cutting only where a delayed wave jumps by 1e-4 of the largest
  (``--cut-jump 1e-4``, 12 slots): 3.5e-5, 7.9e-6, 4.1e-6 on 8, 16, 32 cells, 593, 1,403 and 2,752
  merges, 0.17, 0.37 and 0.75 s; by 1e-3 or 1e-6 the same 3.5e-5 on 8 cells, nor do 2 or 4 equal
  slots a step at least (``--sub``) move it: what every edge's cut adds there was not traced.
  The cap is what holds it: with the jump rule 1e-4, at most 6, 24 and 48 slots give 1.8e-4, 1.8e-6
  and -1.4e-6 on 8 cells, 3.3e-5, 1.4e-6 and -7.4e-7 on 16 (the work -1.45e-6 and -4.5e-7 with 24
  and 48); with 24, on 32 cells 1.7e-7 (the displacement 5.2e-7, the work -2.1e-8), 545, 1,169 and
  2,271 merges a blow on 8, 16 and 32 cells. These two are the defaults.

Compiled. :func:`slot_loop_compiled` runs the library's slot lattice (``laws/rodrock/_rockslots.py``:
this loop compiled, the slots rows of preallocated arrays, the bit ``_rockloop``'s kernels, the merge
by least loss from a heap on a linked list of the slots; resumable since, and with the merges' energy
in its grid loss). Measured when it was this probe's own kernel, on 10e8756b (``--compiled --cells
8 16 32 --delays-up-to 32 --max-slots 12``, one process, the machine's 2 cores shared with a test
run, load 3 to 3.5): its ``v_after``, ``q_after`` and work are the numpy loop's
bit for bit (relative difference 0.0 in all nine cases, the 995,312 merges on
32 cells included), and the CPU ms of one blow (``law.contact``, best of 5 after a warm-up):

| cells | library lattice, step | slots | slots, delayed, every edge | slots, delayed, jump 1e-4 |
| ---: | ---: | ---: | ---: | ---: |
| 8 | 0.37 | 0.77 | 6.07 | 2.22 |
| 16 | 0.43 | 1.08 | 234 | 5.19 |
| 32 | 0.60 | 1.92 | 3,137 | 13.6 |

(the numpy loop: 0.05, 0.08, 0.17 s; 0.42, 12.3, 350 s; 0.17, 0.37, 0.76 s). The loops alone, timed
apart the same way (the blow's set-up and record, some 0.3 ms, left out): the library's 0.09, 0.15,
0.31 ms, the slots 0.41, 0.75, 1.55 ms (4.4 to 5 times: some 10 slots a step, each a step of the
lattice and two calls of the bit), delayed with the jump rule 1.9, 4.7, 13.2 ms (20 to 43 times).
With cuts at every edge the cost is the slots before each merge, 12 plus the merges a step: some 42,
480 and 2,230 on 8, 16 and 32 cells a piston (36, 72, 144 cells in all), each merge a pass over
every cell: 16, 540 and 5,200 times the library's blow. At the defaults (``--compiled --cells 8 16 32
--delays-up-to 8``, 24 slots, the jump rule 1e-4; 0abc7a7d's library, load about 1.5) the compiled
delayed slots take 3.2, 7.2 and 19.3 ms a blow against the library's 0.38, 0.43 and 0.60 ms (8, 17
and 32 times), the slots without delays 0.81, 1.13 and 1.96 ms, the compiled and numpy loops again
the same (at most 1.3e-16 apart).

The coupled blow under the oil circuit (``--driven --cells 8 16 32 64 --delays-up-to 32``, 0abc7a7d's
library, load about 1.5): :func:`driven_slots` is the library's method of steps (the drive by CVODE
over chunks of steps, the end where the piston is free for good tested at the exact blow's
instants) with the slot loop and the delayed segments, each chunk's lattice runs made again from
the impact. Against the exact coupled blow from the same arrival, the shank's impulse on the piston
(what the piston's momentum after the blow takes from the blow; the lattices end at the step end
after the exact blow's end, where the piston is already free), the work dissipated in the rock and
the permanent penetration, relative:

| cells | library lattice: impulse | work | penetration | slots, delayed: impulse | work | penetration |
| ---: | ---: | ---: | ---: | ---: | ---: | ---: |
| 8 | -4.0e-3 | 1.6e-6 | 8.1e-7 | 1.7e-6 | -1.5e-6 | -7.4e-7 |
| 16 | 2.2e-3 | 1.6e-6 | 8.0e-7 | 1.4e-6 | -4.6e-7 | -2.3e-7 |
| 32 | -6.2e-3 | -1.4e-6 | -7.0e-7 | 1.9e-7 | -2.3e-8 | -1.2e-8 |
| 64 | -7.8e-5 | 1.1e-7 | 5.5e-8 | not run | | |

The orbit (``--orbit --cells 8 16``, ``find_orbit`` from rest with :func:`driven_slots` in the
place of the library's coupled blow, its Newton steps on the library lattice's tangent), relative
to the exact blows' orbit (period 1.03408, impact velocity 0.490378, 2.7 s):

| orbit | period | impact velocity | CPU s |
| --- | ---: | ---: | ---: |
| 8 cells, library lattice | 2.3e-4 | -7.1e-4 | 0.3 |
| 8 cells, slots, the blow ended at the step's end | -3.4e-6 | 1.3e-4 | 38 |
| 8 cells, slots, the blow ended at the exact blow's instant | -9.6e-6 | 1.3e-5 | 38 |
| 16 cells, library lattice | -1.5e-4 | 4.1e-4 | 0.3 |
| 16 cells, slots, the step's end | -2.4e-6 | 1.2e-4 | 79 |
| 16 cells, slots, the exact instant | -2.9e-6 | 3.6e-6 | 78 |
| 64 cells, library lattice | 3.1e-6 | -1.0e-5 | 0.8 |
| 64 cells, library lattice, its end 1.31e-4 later | -5.5e-6 | 1.8e-4 | 0.8 |

Ended at the step's end (on 8 and 16 cells the same instant, 1.31e-4 after the exact blow's end, 13
times the shortest travel time), the slots' orbit is 1.2e-4 off in the impact velocity; the
library's lattice on 64 cells, whose step's end falls on the exact end, moves as far with its end
moved on as much. The piston is free there: what moves is where the blow hands it to the flight,
measured from the shank's new rest position while the rod still rings. Ended at the exact instant
(``exact_end``: the last step run to that fraction of it, the cells at the end what entered before
it and what is left after it), the orbit is 1.3e-5 and 3.6e-6 off (order 1.8); on 32 cells (that
row run alone, 168 s) -9.2e-8 in the period, 1.4e-7 in the impact velocity.

With the rod 1.1 m long (``--set "rod.segments.1.length=1.1 m"``: no travel time a multiple of
another), the jump rule 1e-4, 12 slots, on 8 and 16 cells: the library's lattice -1.2e-2 and -7.7e-3, the
slots alone -2.3e-2 and -1.9e-2, slots and delayed segments 3.0e-5 and 1.7e-5.

Run: ``python benchmarks/probes/lattice_slots.py [--cells 8 16 ...] [--max-slots K] [--window W]
[--delays-up-to N] [--merge loss|narrow] [--cut-jump F] [--compiled] [--driven] [--orbit]
[--set KEY=VALUE ...]``
(some 6 minutes with the delayed segments up to 32 cells, nearly all of it theirs on 32;
``--compiled`` as long, nearly all of it the numpy loop's check with cuts at every edge on 32
cells).
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # (bench_coupled_exact: the arrival)

#: a cut closer than this fraction of a slot to one of its ends is not made (the event is taken there)
TINY = 1e-12
STATS = {"cuts": 0, "merges": 0, "slots": 0}
#: a delay cuts the slots where the wave it delays jumps by more than this fraction of the largest
#: wave (< 0: at every edge)
CUT_JUMP = 1e-4
#: each step of the delayed segments' loop cut into at least this many equal slots
SUB = 1
#: which adjacent slots a merge takes: "narrow" (the pair of least width) or "loss" (least L2 loss)
MERGE = "loss"


def _bit_advance(bit, E, T):
    """Advance ``bit`` under ``E`` for at most ``T`` up to its first branch change that takes time:
    the time advanced (``T`` when none comes first)."""
    done = 0.0
    for _ in range(64):
        left = T - done
        if left <= 0.0:
            break
        tau = bit._substep_massless(E, left) if bit.m == 0.0 else bit._substep_mass(E, left)
        if tau == 0.0:
            continue  # a switch at once (unloading, loading again): go on on the new branch
        done += tau
        if tau < left:
            return done
    return T


def _integral(edges, values, at):
    """The integral from 0 of the piecewise-constant signal ``values`` on ``edges`` at ``at``."""
    cum = np.concatenate(([0.0], np.cumsum(values * np.diff(edges))))
    return np.interp(at, edges, cum)


def _delayed(prev, W_prev, cur, W, delta, target):
    """The slot averages on the slots ``target`` (widths, summing to 1) of a signal delayed by
    ``delta`` (a fraction of a step): over ``[0, delta)`` the last ``delta`` of the previous step's
    signal ``prev`` (on ``W_prev``), over ``[delta, 1)`` the first ``1 - delta`` of this step's
    ``cur`` (on ``W``); exact (each slot's integral)."""
    ep = np.concatenate(([0.0], np.cumsum(W_prev))) + delta - 1.0
    ec = np.concatenate(([0.0], np.cumsum(W))) + delta
    edges = np.concatenate((ep, ec[1:]))
    values = np.concatenate((prev, cur))
    et = np.concatenate(([0.0], np.cumsum(target)))
    et[-1] = 1.0
    return np.diff(_integral(edges, values, et)) / target


def _jump_cuts(prev, W_prev, cur, W, delta, thr):
    """Where the signal delayed by ``delta`` (:func:`_delayed`'s) jumps by more than ``thr``: the
    jumps of ``prev`` moved by ``delta - 1``, of ``cur`` by ``delta``, and ``delta`` itself (the
    step's boundary) where ``cur`` starts apart from where ``prev`` ended (``thr < 0``: every
    edge)."""
    ep = np.cumsum(W_prev)[:-1][np.abs(np.diff(prev)) > thr] + delta - 1.0
    ec = np.cumsum(W)[:-1][np.abs(np.diff(cur)) > thr] + delta
    out = [ep[ep > 0.0], ec[ec < 1.0]]
    if abs(cur[0] - prev[-1]) > thr and 0.0 < delta < 1.0:
        out.append([delta])
    return np.concatenate(out)


def _refine(W, arrays, cuts):
    """The slots ``W`` cut at ``cuts`` (positions in ``[0, 1)``), each array's columns (slots) copied
    into the pieces: ``(W, arrays)``."""
    edges = np.concatenate(([0.0], np.cumsum(W)))
    edges[-1] = 1.0
    new = np.unique(np.concatenate((edges, cuts)))
    keep = np.concatenate(([True], np.diff(new) > 1e-13))
    new = new[keep]
    if new[-1] < 1.0:
        new[-1] = 1.0
    if new.size == edges.size:
        return W, arrays
    mid = 0.5 * (new[:-1] + new[1:])
    idx = np.minimum(np.searchsorted(edges, mid, side="right") - 1, W.size - 1)
    return np.diff(new), [x[..., idx] for x in arrays]


def _merge(W, arrays, cap):
    """The adjacent slots of least total width merged (their values averaged by width) until at most
    ``cap`` are left."""
    arrays = [x.copy() for x in arrays]
    if MERGE == "loss" and W.size > cap:
        # the pair whose average loses least (its L2 error over the cells), one at a time, the
        # losses of the merged slot's two pairs computed again
        X = np.concatenate(arrays, axis=0)  # (rows, slots)
        W = W.copy()

        def pair_loss(i):
            d = X[:, i + 1] - X[:, i]
            return float(d @ d) * W[i] * W[i + 1] / (W[i] + W[i + 1])

        loss = np.array([pair_loss(i) for i in range(W.size - 1)])
        while W.size > cap:
            i = int(np.argmin(loss))
            w = W[i] + W[i + 1]
            X[:, i] = (X[:, i] * W[i] + X[:, i + 1] * W[i + 1]) / w
            W[i] = w
            X = np.delete(X, i + 1, axis=1)
            W = np.delete(W, i + 1)
            loss = np.delete(loss, i)
            if i < W.size - 1:
                loss[i] = pair_loss(i)
            if i > 0:
                loss[i - 1] = pair_loss(i - 1)
            STATS["merges"] += 1
        rows = np.cumsum([0] + [x.shape[0] for x in arrays])
        arrays = [X[rows[j]:rows[j + 1]] for j in range(len(arrays))]
    while W.size > cap:
        i = int(np.argmin(W[:-1] + W[1:]))
        w = W[i] + W[i + 1]
        for x in arrays:
            x[..., i] = (x[..., i] * W[i] + x[..., i + 1] * W[i + 1]) / w
        arrays = [np.delete(x, i + 1, axis=-1) for x in arrays]
        W = np.concatenate((W[:i], [w], W[i + 2:]))
        STATS["merges"] += 1
    return W, arrays


def slot_loop(F, G, Z, bounds, bit, dt, n_max, stop, quiet, gap0, drive, record_field, locate=False,
              max_slots=48, delays=(), hooks=None):
    """The blow's loop with slots (the module's text), the signature and results of
    ``blow._python_loop`` (``record_field`` and ``locate`` unused). ``delays``: ``(i, delta)``, the
    rod's segment ``i`` (0: the shank) longer than its whole cells by ``delta`` of a step's travel,
    a delay at its far end (before the next segment, or the bit). ``hooks`` (the coupled blow's,
    :func:`driven_slots`): ``"arriving"``, a list that takes the wave arriving at the driven end
    over each step (its slots' average); ``"stop"``, ``f(step, F, G, bit, shank)`` at each step's
    end (the cells' averages, the shank's force averaged over the step), the loop ended after a
    step where it returns True."""
    hooks = hooks or {}
    arriving, stop_hook = hooks.get("arriving"), hooks.get("stop")
    frac = float(hooks.get("end_fraction", 1.0))  # the last step run to this fraction of it only
    Za, Zb = Z[:-1], Z[1:]
    wa, wb = 2.0 * Zb / (Za + Zb), 2.0 * Za / (Za + Zb)
    n_p, m, feed = int(bounds[0]), bit.m, bit.f
    nc = Z.size
    jc = n_p - 1
    ends = list(bounds[1:] - 1) + [nc - 1]  # each rod segment's last cell
    D = [(int(ends[i]), float(d)) for i, d in delays if d > 0.0]
    nd = len(D)
    FF, GG = np.array(F, dtype=float)[:, None].copy(), np.array(G, dtype=float)[:, None].copy()
    W = np.array([1.0])
    # each delay's sources over the step before: the cell's F, the wave sent back into the cell
    srcF = np.array([[FF[j, 0]] for j, _ in D]).reshape(nd, 1)
    srcG = np.array([[GG[j, 0]] for j, _ in D]).reshape(nd, 1)
    W_src = W.copy()
    gap = float(gap0)
    contact = gap <= 0.0
    u_shank, grid_loss, work = 0.0, 0.0, 0.0
    last = 0 if contact else -1
    junc, bitf, pen = [], [bit.force()], [bit.p]
    ended = "t_max"
    for step in range(n_max):
        if arriving is not None:
            arriving.append(float(GG[0] @ W))
        if nd:
            thr = CUT_JUMP * max(float(np.abs(FF).max()), float(np.abs(GG).max()), 1e-300)
            if CUT_JUMP < 0.0:
                thr = -1.0
            cuts = [_jump_cuts(srcF[i], W_src, FF[j], W, d, thr) for i, (j, d) in enumerate(D)]
            cuts.append(np.arange(1, SUB) / SUB)
            W, (FF, GG) = _refine(W, [FF, GG], np.concatenate(cuts))
        partial = step == n_max - 1 and frac < 1.0
        if partial:
            W, (FF, GG) = _refine(W, [FF, GG], np.array([frac]))
        Fd = np.array([_delayed(srcF[i], W_src, FF[j], W, d, W)
                       for i, (j, d) in enumerate(D)]).reshape(nd, W.size)
        Gout = np.zeros((nd, W.size))
        Fn, Gn = np.empty_like(FF), np.empty_like(GG)
        jrow = np.zeros(bounds.size)
        pd = drive[step] / frac if partial else drive[step]  # (the drive's impulse over the part)
        k = 0
        while k < W.size:
            if partial and np.sum(W[:k]) >= frac - 1e-12:
                break
            Fs = FF[:, k].copy()
            for i, (j, _) in enumerate(D):
                Fs[j] = Fd[i, k]
            fa, ga = Fs[jc], GG[jc + 1, k]
            N = wa * Fs[:-1] + wb * GG[1:, k]
            nw = N[jc]
            if contact and nw < 0.0:
                contact = False  # the welded force pulls: apart from the slot's start
            elif not contact and gap <= 0.0 and nw >= 0.0:
                contact = True
            # the first event inside the slot: the gap closing, the bit's branch change
            tau = W[k] * dt
            cut, closes = 1.0, False
            rate = -2.0 * ga / Zb[jc] - 2.0 * fa / Za[jc]
            if not contact and rate < 0.0 and gap + rate * tau < 0.0:
                cut, closes = -gap / (rate * tau), True
            Fi = Fs[-1]
            trial = copy.copy(bit)
            adv = _bit_advance(trial, 2.0 * Fi + feed, tau) / tau
            if adv < cut:
                cut, closes = adv, False
            if TINY < cut < 1.0 - TINY:
                W = np.concatenate((W[:k], [W[k] * cut, W[k] * (1.0 - cut)], W[k + 1:]))
                FF, GG, Fn, Gn, Fd, Gout = (np.insert(x, k + 1, x[:, k], axis=1)
                                            for x in (FF, GG, Fn, Gn, Fd, Gout))
                STATS["cuts"] += 1
                tau = W[k] * dt
            if contact:
                N[jc] = nw
            else:
                N[jc] = 0.0
                gap = 0.0 if closes else max(gap + rate * tau, 0.0)
            Fn[1:, k] = N - GG[1:, k]
            Gn[:-1, k] = N - Fs[:-1]
            Fn[0, k] = pd - GG[0, k]
            work += pd * (pd - 2.0 * GG[0, k]) / Z[0] * tau
            p0, w0, ke0 = bit.p, bit.work, 0.5 * m * bit.w * bit.w
            bit.step(2.0 * Fi + feed, tau)
            g_avg = Fi - Z[-1] * (bit.p - p0) / tau
            Gn[-1, k] = g_avg
            for i, (j, _) in enumerate(D):
                Gout[i, k] = Gn[j, k]
            e_in = (bit.work - w0) - feed * (bit.p - p0) + 0.5 * m * bit.w * bit.w - ke0
            grid_loss += (Fi * Fi - g_avg * g_avg) * tau / Z[-1] - e_in
            u_shank += (Fn[jc + 1, k] - GG[jc + 1, k]) / Zb[jc] * tau
            jrow += N[bounds - 1] * W[k]
            k += 1
        if partial:  # the cells at the end inside the step: what entered before it, what is left after
            kf = k
            Fm = Fn[:, :kf] @ W[:kf] + FF[:, kf:] @ W[kf:]
            Gm = Gn[:, :kf] @ W[:kf] + GG[:, kf:] @ W[kf:]
            junc.append(jrow)
            bitf.append(bit.force())
            pen.append(bit.p)
            junc = np.array(junc).reshape(-1, bounds.size)
            return (Fm, Gm, junc, np.array(bitf), np.array(pen), np.array([]),
                    (u_shank, grid_loss, ended, gap, work))
        if nd:  # the waves sent back through each delay, on slots cut where they jump
            thr = -1.0 if CUT_JUMP < 0.0 else CUT_JUMP * max(float(np.abs(Gout).max()), 1e-300)
            cuts = np.concatenate([_jump_cuts(srcG[i], W_src, Gout[i], W, d, thr)
                                   for i, (_, d) in enumerate(D)])
            W, (FF, Fn, Gn, Gout) = _refine(W, [FF, Fn, Gn, Gout], cuts)
        for i, (j, d) in enumerate(D):
            Gn[j] = _delayed(srcG[i], W_src, Gout[i], W, d, W)
        srcF = np.array([FF[j] for j, _ in D]).reshape(nd, W.size)
        srcG, W_src = Gout, W.copy()
        W, (Fn, Gn) = _merge(W, [Fn, Gn], max_slots)
        STATS["slots"] = max(STATS["slots"], W.size)
        junc.append(jrow)
        bitf.append(bit.force())
        pen.append(bit.p)
        FF, GG = Fn, Gn
        if stop_hook is not None and stop_hook(step, FF @ W, GG @ W, bit, float(jrow[0])):
            break
        if contact:
            last = step
        elif last < 0:
            pass
        elif quiet > 0 and step - last >= quiet:
            ended = "separated"
            break
        if not contact and last >= 0 and step % 8 == 0:
            rod_e = float(np.sum((FF[n_p:] ** 2 + GG[n_p:] ** 2) @ W / Z[n_p:])) * dt
            if rod_e + 0.5 * m * bit.w * bit.w < stop:
                ended = "energy"
                break
    F_out, G_out = FF @ W, GG @ W  # the cells' averages
    junc = np.array(junc).reshape(-1, bounds.size)
    return (F_out, G_out, junc, np.array(bitf), np.array(pen), np.array([]),
            (u_shank, grid_loss, ended, gap, work))


# -- the slot loop compiled ----------------------------------------------------------------------------
# The library's slot lattice (:class:`impactbar.laws.rodrock._rockslots.SlotLattice`, compiled from
# this probe's loop and resumable), run whole: the same loop as :func:`slot_loop` at its defaults (the
# merge by least loss, one slot a step at least).


def slot_loop_compiled(F, G, Z, bounds, bit, dt, n_max, stop, quiet, gap0, drive, record_field,
                       locate=False, max_slots=48, delays=()):
    """:func:`slot_loop` on the library's compiled slot lattice: the same signature and results
    (``CUT_JUMP`` read here; ``MERGE`` must be ``"loss"`` and ``SUB`` 1, the library's rules)."""
    from impactbar.laws.rodrock import _rockslots as R
    from impactbar.laws.rodrock import blow as B

    if MERGE != "loss" or SUB != 1:
        raise ValueError(f"the compiled loop merges by least loss, one slot a step at least; got "
                         f"--merge {MERGE}, --sub {SUB}")
    R.CUT_JUMP = CUT_JUMP
    bs, bp = B._bit_records(bit)
    lat = R.SlotLattice(Z, bounds, list(delays), F, G, float(gap0), bs, bp, max_slots=max_slots)
    out = lat.run(dt, np.ascontiguousarray(drive[:n_max], dtype=float), stop=stop, quiet=quiet)
    B._set_bit(bit, lat.bs)
    u_shank, grid_loss, gap, work = lat.totals()
    ended = ("t_max", "energy", "separated")[lat.ended]
    return (out["F"], out["G"], out["junc"], out["bitf"], out["pen"], np.array([]),
            (u_shank, grid_loss, ended, gap, work))


def _end_window(model):
    """The instants' spacing ``h`` at which a blow under a drive is tested for its end: the shortest
    travel time of the piston's and the rod's segments as given (``coupled.end_window``'s, which
    takes them from a grid, and here the grid's segments are floored)."""
    return min([1.0 / model.s] + [g.travel_time(model) for g in model.law.segments])


def driven_slots(model, drive, state, t0, q, v, cells, max_slots, delays=True, pen=False,
                 full=False, settings=None, exact_end=False):
    """The coupled blow under the drive (``coupled.driven_rock_contact``'s method of steps, its end
    where the piston is free for good tested at the same instants) with the slot loop on ``cells``
    cells, the rod's segments delayed (``delays``) or rounded: ``(v_after[0], q_after[0], work
    dissipated in the rock, duration, the drive's state after, the shank's impulse on the
    piston)``, and with ``pen`` the permanent penetration; with ``full`` the library's
    :class:`~impactbar.laws.base.DrivenContact` instead (what an orbit takes). ``exact_end``: the
    blow ended at the multiple of ``h`` where the piston is found free for good, inside its step
    (the slots' last step run to that fraction), not at the step's end. Each chunk's lattice runs are
    the slot loop run again from the impact (the slots' state is not handed between chunks): the
    same numbers, at a cost the probe does not measure."""
    from impactbar.dynamics.implementations import use_reference
    from impactbar.laws.rodrock import blow as B
    from impactbar.laws.rodrock._rockloop import piston_free
    from impactbar.laws.rodrock.blow import _bit_records
    from impactbar.laws.rodrock.contact import BlowMap
    from impactbar.laws.rodrock.coupled import causal_cells
    from impactbar.laws.rodrock.coupled_exact import HORIZONS
    from impactbar.laws.rodrock.grid import whole_steps
    from impactbar.loads import FourierLoad

    law = dataclasses.replace(model.law, method="lattice", cells_per_piston=cells, contact_events="step",
                              driven_end="free")
    mdl = model.with_(impact=law)
    D = ()
    if delays:
        mdl, D = _floored_rod(mdl, cells)
        law = mdl.law
    q = np.array(q, dtype=float)
    v = np.array(v, dtype=float)
    p0 = float(drive.force(state.mode, state.z, q, v))
    horizon = HORIZONS * model.law.window(model)  # (the rod as given: the library's horizon)
    bm = BlowMap(mdl, FourierLoad(p0, []), t0, averaged=False, duration=horizon)
    grid = bm.grid
    n_p, dt, n_max = grid.piston_cells, grid.cell_time, bm.n_max
    h = _end_window(model)
    Z0 = float(grid.Z[0])
    F0, G0 = bm.fields(q, v)
    m = causal_cells(grid.Z, n_p)
    chunk = 2 * m
    averages = bm.drive
    w = -float(model.drive_weights @ q)
    st = state
    follow = drive.abilities.end_flight
    bounds = np.ascontiguousarray(grid.bounds, dtype=np.int64)
    pieces, events = [], []

    def run(n, hooks):
        bit = B._start_bit(grid.Z, law.rock.k, law.rock.k_u, law.bit_mass, law.feed, None)
        slot_loop(F0.copy(), G0.copy(), grid.Z, bounds, bit, dt, n, -1.0, 0, 0.0, averages[:n].copy(),
                  False, max_slots=max_slots, delays=D, hooks=hooks)

    def free_test(k0, k1):
        """A stop hook: the first step end in ``[k0, k1)`` at or after a multiple of ``h`` (past
        the impact) where the contact is open and the piston free for good; ``found`` its step + 1."""
        found = []

        def hook(step, F, G, bit, shank):
            if step < k0:
                return False
            n = step + 1
            j = math.floor(n * dt / h * (1.0 + 1e-12))  # (the last multiple of h at or before n dt)
            if j >= 1 and whole_steps(j * h, dt) == n and shank == 0.0:
                bs, bp = _bit_records(bit)
                if piston_free(F, G, grid.Z, n_p, bs, bp, dt):
                    found.append(step + 1)
                    return True
            return False
        return hook, found

    k, end, ended, frac = 0, n_max, False, 1.0
    while k < end:
        L = min(chunk, end - k)
        arr = []
        averages[k:k + L] = 0.0
        run(k + L, {"arriving": arr})
        arriving = np.array(arr[k:k + L])
        breaks = t0 + dt * np.arange(k, k + L + 1)
        fl = follow(mdl, st, breaks, w, -2.0 * arriving / Z0, Z0, settings)
        averages[k:k + L] = fl.impulses / dt
        if not ended:
            hook, found = free_test(k, k + L)
            run(k + L, {"stop": hook})
            if found:
                ended, end = True, found[0]
                if exact_end:  # the end at the multiple of h itself, inside the step
                    j = math.floor(end * dt / h * (1.0 + 1e-12))
                    frac = min(max((j * h - (end - 1) * dt) / dt, 1e-9), 1.0)
                if end - k < L or frac < 1.0:
                    L = end - k
                    b = breaks[:L + 1].copy()
                    b[L] = t0 + (end - 1 + frac) * dt
                    fl = follow(mdl, st, b, w, -2.0 * arriving[:L] / Z0, Z0, settings)
                    averages[k:k + L] = fl.impulses / dt
        st, w = fl.state, fl.w
        pieces += fl.pieces
        events += fl.events
        k += L
    bm.n_max = k
    plain = B._python_loop
    B._python_loop = lambda *a, **kw: slot_loop(*a, **kw, max_slots=max_slots, delays=D,
                                                 hooks={"end_fraction": frac})
    try:
        with use_reference("rock.blow"):
            rec = bm.contact(q, v)
    finally:
        B._python_loop = plain
    blow = rec.blow.with_stored_apart()
    if full:
        from impactbar.laws.base import DrivenContact
        from impactbar.laws.rodrock.coupled import _rigid_gaps

        rec.blow = dataclasses.replace(blow, ended_by="separated") if ended else blow
        work = float(sum(p.piston_work() for p in pieces))
        return DrivenContact(rec.q_after.copy(), rec.v_after.copy(), float(t0) + (k - 1 + frac) * dt, rec, st,
                             pieces, events, work, _rigid_gaps(model, q, v, rec.blow, averages, t0))
    out = (float(rec.v_after[0]), float(rec.q_after[0]), float(blow.work_on_rock), k * dt,
           np.array(st.z, dtype=float), float(np.sum(blow.shank_forces)) * dt)
    return out + (float(blow.permanent_penetration),) if pen else out


def driven_table(model, drive, state, t0, q, v, cells, max_slots, slots_up_to):
    """The coupled blow under the drive from the arrival, its end where the piston is free for good
    (the library's default), against the exact coupled blow (``method="exact"``): the relative
    differences of the shank's impulse on the piston (which the blow's end does not change once the
    piston is free), the work dissipated in the rock and the permanent penetration, for the
    library's lattice and the slots with delayed segments (:func:`driven_slots`, up to
    ``slots_up_to`` cells), and their CPU s (the slots' numpy loop run again from the impact for
    each chunk)."""
    ex = model.law.driven_contact(model, drive, state, t0, q, v)
    xr = ex.record.exact
    ref = (xr.junction_impulse(xr.contact_junction), ex.record.blow.work_on_rock,
           float(xr.permanent_penetration))
    print("\ncoupled blow under the oil circuit, from the arrival, ended where the piston is free for good: "
          "relative differences from the exact blow (shank impulse, work, permanent penetration); CPU s")
    print(f"{'cells':>5s} | {'lattice, step':>38s} | {'slots, segments delayed':>38s}")
    for n in cells:
        lat = dataclasses.replace(model.law, method="lattice", cells_per_piston=n)
        t = time.process_time()
        c = lat.driven_contact(model.with_(impact=lat), drive, state, t0, q, v)
        cpu = time.process_time() - t
        b = c.record.blow
        got = (float(np.sum(b.shank_forces)) * b.cell_time, b.work_on_rock, b.permanent_penetration)
        row = [" ".join(f"{(g - r) / abs(r):10.2e}" for g, r in zip(got, ref, strict=True)) + f" {cpu:6.2f}"]
        if n <= slots_up_to:
            t = time.process_time()
            out = driven_slots(model, drive, state, t0, q, v, n, max_slots, pen=True)
            cpu = time.process_time() - t
            got = (out[5], out[2], out[6])
            row.append(" ".join(f"{(g - r) / abs(r):10.2e}" for g, r in zip(got, ref, strict=True))
                       + f" {cpu:6.2f}")
        print(f"{n:5d} | " + " | ".join(f"{x:>38s}" for x in row))


def orbit_table(cells, max_slots):
    """The example's orbit (``find_orbit`` from rest) with the coupled blows of the library's
    lattice and of the slots with delayed segments (:func:`driven_slots` in the place of
    ``coupled.driven_rock_contact``; the orbit's Newton steps still take the library lattice's
    tangent), their blows ended at the step's end after the exact blow's end or at that end itself
    (``exact_end``), against the exact blows' orbit: the relative differences of the period and the
    impact velocity, CPU s. And the library's lattice on 64 cells with its blows' end moved on by
    what the step's end adds on 8 cells (``coupled.END_DELAY``): the orbit's sensitivity to the
    instant the blow hands the piston to the flight."""
    import impactbar as ib
    from impactbar import physical as ph
    from impactbar.laws.rodrock import coupled

    example = Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter_rock.toml"
    cfg, _ = ph.read_config(str(example))
    d = ph.build(cfg)
    model, drive = d.model(), d.drive()

    def orbit(law):
        t = time.process_time()
        o = ib.find_orbit(model.with_(impact=law), drive)
        return o, time.process_time() - t

    ex, cpu = orbit(dataclasses.replace(model.law, method="exact"))
    print(f"\nthe orbit against the exact blows' (period {ex.period!r}, impact velocity "
          f"{float(ex.impact_velocities[0])!r}, {cpu:.1f} s): relative differences of the period and the "
          "impact velocity, CPU s")

    def show(name, o, cpu):
        dp = (o.period - ex.period) / ex.period
        dv = float((o.impact_velocities[0] - ex.impact_velocities[0]) / ex.impact_velocities[0])
        print(f"{name:34s} {dp:10.2e} {dv:10.2e} {cpu:7.1f}", flush=True)

    plain = coupled.driven_rock_contact
    for n in cells:
        law = dataclasses.replace(model.law, method="lattice", cells_per_piston=n)
        show(f"{n:3d} cells, library lattice", *orbit(law))
        for exact_end in (False, True):
            def slots(model, drive, state, t0, q, v, settings=None, _e=exact_end):
                return driven_slots(model, drive, state, t0, q, v, model.law.cells_per_piston, max_slots,
                                    full=True, settings=settings, exact_end=_e)
            coupled.driven_rock_contact = slots
            try:
                got = orbit(law)
            finally:
                coupled.driven_rock_contact = plain
            show(f"{n:3d} cells, slots, " + ("the exact end" if exact_end else "the step's end"), *got)
    h = _end_window(model)
    dt = 1.0 / (model.s * 8)
    shift = math.ceil(13.0 * h / dt * (1.0 - 1e-12)) * dt - 13.0 * h
    law = dataclasses.replace(model.law, method="lattice", cells_per_piston=64)
    saved = coupled.END_DELAY
    for delay in (0.0, shift / law.window(model)):
        coupled.END_DELAY = delay
        try:
            show(f" 64 cells, library, end +{delay * law.window(model):.2e}", *orbit(law))
        finally:
            coupled.END_DELAY = saved


def _floored_rod(model, cells):
    """The model on the rod whose segments are their whole cells of the lattice of ``cells`` (at
    least one), and each segment's travel left over, in steps: ``(model, [(i, delta), ...])``."""
    law = model.law
    dt = 1.0 / (model.s * cells)
    segs, delays = [], []
    for i, g in enumerate(law.segments):
        T = g.travel_time(model)
        whole = max(1, int(np.floor(T / dt + 1e-9)))
        delays.append((i, max(T / dt - whole, 0.0)))
        segs.append(dataclasses.replace(g, length=g.length * whole * dt / T))
    return model.with_(impact=dataclasses.replace(law, segments=tuple(segs))), delays


def _blow(model, load, q, v, method, window, cells=None, loop=None, events="step"):
    """``(v_after[0], q_after[0], work dissipated in the rock, CPU s)`` of the held-force blow."""
    from impactbar.dynamics.implementations import use_reference
    from impactbar.laws.rodrock import blow as B

    extra = {} if cells is None else {"cells_per_piston": cells, "contact_events": events}
    law = dataclasses.replace(model.law, method=method, blow_time=window, **extra)
    m = model.with_(impact=law)
    t = time.process_time()
    if loop is None:
        qa, va, _, rec = law.contact(m, load, 0.0, q, v)
    else:
        plain = B._python_loop
        B._python_loop = loop
        try:
            with use_reference("rock.blow"):
                qa, va, _, rec = law.contact(m, load, 0.0, q, v)
        finally:
            B._python_loop = plain
    cpu = time.process_time() - t
    b = rec.blow
    return float(va[0]), float(qa[0]), float(b.work_on_rock - b.rock_stored_energy
                                             if hasattr(b, "rock_stored_energy") else b.work_on_rock), cpu


def _best_cpu(fn, repeats=5):
    """The least CPU s of ``repeats`` calls of ``fn`` (returning ``_blow``'s tuple), after one call
    not counted (the compile)."""
    fn()
    return min(fn()[3] for _ in range(repeats))


def compiled_table(model, load, q, v, window, cells, max_slots, check_every_edge_up_to):
    """The compiled slot loop against :func:`slot_loop` (the relative differences of ``v_after[0]``,
    ``q_after[0]`` and the work, the numpy loop's CPU s of one run) and the CPU s of one blow (best
    of 5 after a warm-up) of the library's lattice (``contact_events="step"``) and of the compiled
    slots, without delays and with (cut at every edge, ``--cut-jump -1``, and where a wave jumps by
    1e-4, ``--cut-jump 1e-4``), on the true rod. The numpy loop with cuts at every edge is checked
    only up to ``check_every_edge_up_to`` cells (345 s a blow on 32)."""
    global CUT_JUMP
    saved = CUT_JUMP
    print("\ncompiled slot loop on the true rod: relative differences from the numpy slot loop, "
          "v_after[0] q_after[0] work, and the numpy loop's CPU s; CPU ms of one blow (best of 5)")
    head = (f"{'cells':>5s} | {'slots':>35s} | {'delayed, every edge':>35s} | {'delayed, jump 1e-4':>35s} | "
            f"{'step':>8s} {'slots':>8s} {'every':>8s} {'1e-4':>8s}")
    print(head)
    try:
        for n in cells:
            floored, delays = _floored_rod(model, n)
            cases = [("slots", model, (), CUT_JUMP), ("every", floored, tuple(delays), -1.0),
                     ("jump", floored, tuple(delays), 1e-4)]
            diffs, cpus = [], []
            for name, m_, d, cj in cases:
                CUT_JUMP = cj

                def nb(*a, _d=d, **k):
                    return slot_loop_compiled(*a, **k, max_slots=max_slots, delays=_d)

                def py(*a, _d=d, **k):
                    return slot_loop(*a, **k, max_slots=max_slots, delays=_d)

                got = _blow(m_, load, q, v, "lattice", window, n, nb)
                if name == "every" and n > check_every_edge_up_to:
                    diffs.append(f"{'not run':>35s}")
                else:
                    ref = _blow(m_, load, q, v, "lattice", window, n, py)
                    rel = [abs(g - r) / abs(r) for g, r in zip(got[:3], ref[:3], strict=True)]
                    diffs.append(" ".join(f"{e:8.1e}" for e in rel) + f" {ref[3]:8.2f}")
                cpus.append(_best_cpu(lambda m_=m_, nb=nb, n=n: _blow(m_, load, q, v, "lattice", window, n,
                                                                      nb)))
            step = _best_cpu(lambda n=n: _blow(model, load, q, v, "lattice", window, n))
            print(f"{n:5d} | " + " | ".join(diffs) + " | "
                  + " ".join(f"{1e3 * c:8.2f}" for c in [step] + cpus), flush=True)
    finally:
        CUT_JUMP = saved


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, nargs="*", default=[8, 16, 32, 64, 128])
    ap.add_argument("--max-slots", type=int, default=24)
    ap.add_argument("--window", type=float, default=14.0, help="the blow's window in piston travel times")
    ap.add_argument("--delays-up-to", type=int, default=16,
                    help="the delayed segments' slots only up to this many cells (their cost grows fast)")
    ap.add_argument("--merge", choices=("narrow", "loss"), default="loss")
    ap.add_argument("--cut-jump", type=float, default=1e-4)
    ap.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE",
                    help="the example's dotted keys changed first (e.g. 'rod.segments.1.length=1.1 m')")
    ap.add_argument("--sub", type=int, default=1,
                    help="the delayed segments' loop: equal slots a step at least")
    ap.add_argument("--compiled", action="store_true",
                    help="only the compiled slot loop: its differences from the numpy loop and the CPU "
                         "time of one blow (the numpy loop with cuts at every edge up to --delays-up-to "
                         "cells)")
    ap.add_argument("--driven", action="store_true",
                    help="only the coupled blow under the oil circuit, its end where the piston is free for "
                         "good: the library's lattice and the slots with delayed segments against the exact")
    ap.add_argument("--orbit", action="store_true",
                    help="only the example's orbit with the slots' coupled blows against the exact blows' "
                         "(some 40 s an orbit on 8 cells, 80 s on 16)")
    args = ap.parse_args(argv)
    global MERGE, CUT_JUMP, SUB
    MERGE, CUT_JUMP, SUB = args.merge, args.cut_jump, args.sub

    from bench_coupled_exact import arrival
    from lattice_order import _rounded_rod  # (this folder's: the rod the lattice solves)

    from impactbar import FourierLoad

    model, drive, state, t0, q, v = arrival(dict(kv.split("=", 1) for kv in args.set) or None)
    load = FourierLoad(drive.force(state.mode, state.z, q, v), [])
    window = args.window / model.s

    if args.compiled:
        compiled_table(model, load, q, v, window, args.cells, args.max_slots, args.delays_up_to)
        return
    if args.orbit:
        orbit_table(args.cells, args.max_slots)
        return
    if args.driven:
        driven_table(model, drive, state, t0, q, v, args.cells, args.max_slots, args.delays_up_to)
        return

    names = ("v_after", "q_after", "work")
    rows = {}
    for rod in ("rounded", "true"):
        print(f"\n{rod} rod: relative differences from the exact blow of that rod, v_after[0] q_after[0] "
              "work, and the CPU s of the lattice's blow")
        head = f"{'cells':>5s} | {'lattice, step':>38s} | {'lattice, inside':>38s} | {'slots':>38s}"
        if rod == "true":
            head += f" | {'slots, segments delayed':>38s} {'slots':>5s} {'cuts':>5s} {'merges':>7s}"
        print(head)
        for n in args.cells:
            mdl = _rounded_rod(model, n) if rod == "rounded" else model
            ref = _blow(mdl, load, q, v, "exact", window)

            def plain_slots(*a, **k):
                return slot_loop(*a, **k, max_slots=args.max_slots)

            cases = [("step", mdl, None), ("inside", mdl, None), ("slots", mdl, plain_slots)]
            if rod == "true" and n <= args.delays_up_to:
                floored, delays = _floored_rod(model, n)

                def delayed_slots(*a, _d=tuple(delays), **k):
                    return slot_loop(*a, **k, max_slots=args.max_slots, delays=_d)

                cases.append(("delayed", floored, delayed_slots))
            out = []
            for name, m_, loop in cases:
                STATS.update(cuts=0, merges=0, slots=0)
                events = "inside" if name == "inside" else "step"
                got = _blow(m_, load, q, v, "lattice", window, n, loop, events)
                err = [(g - r) / abs(r) for g, r in zip(got[:3], ref[:3], strict=True)]
                rows.setdefault((rod, name), []).append(err)
                out.append(" ".join(f"{e:10.2e}" for e in err) + f" {got[3]:6.2f}")
            line = f"{n:5d} | " + " | ".join(f"{o:>38s}" for o in out)
            if len(out) > 3:
                line += f" {STATS['slots']:5d} {STATS['cuts']:5d} {STATS['merges']:7d}"
            print(line)
    print("\nobserved orders log2(e(n)/e(2n))")
    for (rod, name), e in rows.items():
        e = np.abs(np.array(e))
        for j, q_name in enumerate(names):
            o = np.log2(e[:-1, j] / e[1:, j])
            print(f"{rod:8s} {name:8s} {q_name:8s} " + " ".join(f"{x:6.2f}" for x in o))


if __name__ == "__main__":
    main()
