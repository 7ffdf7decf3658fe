r"""The rod-rock law's blow with a drive that has state (theory §11, "The coupled blow"; §4d): the
lattice of :mod:`.contact` and the drive's state solved together, by a method of steps.

On the lattice the piston's driven end (the left edge of cell 0, impedance ``Z_0``) takes the drive's
force averaged over each step, ``p_k``, and moves during the step at
``u_t(0) = (p_k - 2 G_k) / Z_0``, ``G_k`` the left-going wave arriving in cell 0. A wave the drive
sends in reaches the first cell boundary where anything reflects (a change of impedance, the shank) in
``m`` steps and its echo comes back ``m`` steps later, so ``G_k`` over the ``2 m`` steps from ``K`` on
does not depend on the drive from ``K`` on. Chunk by chunk of ``2 m`` steps:

1. ``G_k`` of the chunk from the lattice run on with no drive (a probe: the same waves);
2. the drive's state over the chunk, step by step, with the driven end at
   ``u_t(0, t) = -2 G_k / Z_0 + p(t) / Z_0`` (its ability ``end_flight``: the oil circuit
   by CVODE), which gives each step's force average ``p_k = int p dt / dt``;
3. the lattice run on over the chunk with those averages.

No iteration: each chunk's force is exact (to the integrator's tolerance) for the lattice's driven
end, whose displacement at the step ends is the integrated one. The blow is then the lattice's with
those averages (:class:`~impactbar.laws.rodrock.contact.RockContact`, the same numbers). The drive's
work on the piston, ``int p u_t(0) dt``, exceeds the lattice's ``sum p_k (p_k - 2 G_k) dt / Z_0`` by
``sum int (p - p_k)^2 dt / Z_0 >= 0``, the part of the outgoing wave that the cell averages drop
(second order in the step); it is booked as energy the blow took.

On the slot lattice (``RodRock(contact_events="slots")``, :mod:`._rockslots`) the same chunks run on
its state (:class:`_Slots`): the wave arriving at the driven end is known slot by slot, and the drive
takes a break inside a step wherever it jumps by more than :data:`DRIVE_JUMP` of its largest value,
each interval's value its average (with each step's average alone the circuit's state after a blow
converged at first order only); and the blow ends at the multiple of ``h`` where the piston is found
free for good itself, its last step run to that fraction (the drive flown to there).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..base import DrivenContact, LawNotSupported
from . import _records as S
from ._records import JUNC_SHANK

__all__ = ["driven_rock_contact", "causal_cells", "END_DELAY"]

#: The slot lattice's coupled blow gives the drive a break inside a step where the wave arriving at
#: the driven end jumps by more than this fraction of its largest value over the chunk.
DRIVE_JUMP = 1e-4

#: The slot lattice's coupled blow joins an interval of the drive narrower than this fraction of a
#: step to its neighbour.
SLIVER = 1e-9

#: The blow's end moved this fraction of the law's window past where the piston is free for good
#: (0, the default: there; the orbit's sensitivity to the end, theory §11).
END_DELAY = 0.0


def causal_cells(Z, n_p: int) -> int:
    """The cells ``m`` from the driven end to the first boundary that reflects (a change of
    impedance inside the piston, else the shank after its ``n_p`` cells): the arriving waves of
    ``2 m`` steps do not depend on the drive over them (module docstring).

    Parameters
    ----------
    Z : array_like, shape (cells,)
        The cells' impedances, piston first (``BlowGrid.Z``).
    n_p : int
        The piston's cells.

    Returns
    -------
    int
        ``1 <= m <= n_p``.
    """
    Z = np.asarray(Z, dtype=float)
    for j in range(n_p - 1):
        if Z[j + 1] != Z[j]:
            return j + 1
    return n_p


def _bit_arrays(grid, law):
    from .blow import _bit_records, _start_bit

    return _bit_records(_start_bit(grid.Z, law.rock.k, law.rock.k_u, law.bit_mass, law.feed, None))


def _steps(grid, F, G, bs, bp, gap, drive, record, bounds=None):
    """``drive.size`` steps of the blow's compiled loop from the waves ``F, G`` and the bit ``bs``
    (updated in place) and the contact's state ``gap`` (shape (4,): the gap, then
    ``_loop_controls``'s ``switch``); returns that state after them, with ``record``
    the force in every cell at the start of each step, and the shank's force on the last step.
    ``bounds``: ``grid.bounds`` as int64 where the caller has it (a blow's chunks share it)."""
    from ._rockloop import blow_loop
    from .blow import _loop_controls

    L = drive.size
    if bounds is None:
        bounds = grid.bounds.astype(np.int64)
    junc = np.zeros((L, bounds.size))
    bitrec = np.zeros((L + 1, 2))
    field = np.zeros((L if record else 0, F.size))
    acc = np.zeros(S.ACC_SIZE)
    gap_now, *switch = gap  # (the gap, the contact's switch: held, the arriving waves)
    ctrl = _loop_controls(grid.cell_time, -1.0, 0, float(gap_now), locate=grid.locate, switch=tuple(switch))
    blow_loop(F, G, grid.Z, bounds, bs, bp, ctrl, np.ascontiguousarray(drive), junc, bitrec, field, acc)
    return acc[[S.ACC_GAP, S.ACC_HELD, S.ACC_FA, S.ACC_GA]], field, float(junc[-1, JUNC_SHANK])


def end_window(grid) -> float:
    """The instants the end of a blow under a drive is tested at, ``h, 2 h, ...`` from the impact:
    ``h`` the shortest travel time of the piston's and the rod's segments, the exact blow's window
    (:func:`impactbar.laws.rodrock.exact.exact_blow`), so that the lattice and the exact blow end at
    the same instant (to a step) where both find the piston free for good there."""
    travel = grid.travel if grid.piston_travel is None else np.concatenate((grid.piston_travel, grid.travel))
    return float(np.min(travel))


class _Cells:
    """The plain lattice's state between the coupled blow's chunks (:func:`_steps`): its waves, the
    bit's state and the contact's (``gap``)."""

    def __init__(self, grid, F, G, bs, bp, bounds):
        self.grid, self.F, self.G, self.bs, self.bp, self.bounds = grid, F, G, bs, bp, bounds
        self.gap = np.zeros(4)

    def copy(self):
        other = _Cells(self.grid, self.F.copy(), self.G.copy(), self.bs.copy(), self.bp, self.bounds)
        other.gap = self.gap.copy()
        return other

    def arriving(self, L):
        """The waves arriving at the driven end over the next ``L`` steps without drive (a copy run)."""
        _, field, _ = _steps(self.grid, self.F.copy(), self.G.copy(), self.bs.copy(), self.bp, self.gap,
                             np.zeros(L), True, self.bounds)
        column = field[:, 0].copy()
        column[0] = self.G[0]
        return np.add.accumulate(column)  # F[0] = 0 - G[0] after a step without drive

    def drive_input(self, arriving, k, t0, L, frac=1.0):
        """The drive's breaks over the ``L`` steps from step ``k`` (the blow from ``t0``), the wave
        arriving at the driven end on each interval (``-2 G / Z_0``), and each step's first interval:
        here the steps themselves."""
        dt = self.grid.cell_time
        breaks = t0 + dt * np.arange(k, k + L + 1)
        breaks[L] = t0 + (k + L - 1 + frac) * dt
        return breaks, -2.0 * arriving[:L] / float(self.grid.Z[0]), np.arange(L)

    def run(self, drive, frac=1.0):
        """``drive.size`` steps; the shank's force on the last."""
        self.gap, _, shank = _steps(self.grid, self.F, self.G, self.bs, self.bp, self.gap, drive, False,
                                    self.bounds)
        return shank

    def waves(self):
        return self.F, self.G


class _Slots:
    """The slot lattice's state between the coupled blow's chunks
    (:class:`~impactbar.laws.rodrock._rockslots.SlotLattice` ``lat``), and the cells' averages after
    its last run."""

    def __init__(self, grid, lat):
        self.grid, self.lat, self._waves = grid, lat, None

    @property
    def bs(self):
        return self.lat.bs

    @property
    def bp(self):
        return self.lat.bp

    def copy(self):
        return _Slots(self.grid, self.lat.copy())

    def arriving(self, L):
        return self.lat.copy().run(self.grid.cell_time, np.zeros(L), arriving_slots=True)["arriving_slots"]

    def drive_input(self, arriving, k, t0, L, frac=1.0):
        """:meth:`_Cells.drive_input` with the arriving wave's slots: a break at each slot's edge
        inside a step where the wave jumps by more than :data:`DRIVE_JUMP` of its largest value over
        the chunk; each interval's value the wave's average over it (up to the end, inside the last
        step where ``frac < 1``)."""
        dt = self.grid.cell_time
        w = np.concatenate([a[0] for a in arriving[:L]])
        g = np.concatenate([a[1] for a in arriving[:L]])
        counts = np.array([a[0].size for a in arriving[:L]])
        first = np.concatenate(([0], np.cumsum(counts)[:-1]))
        step = np.repeat(np.arange(L), counts)
        within = np.cumsum(w) - w - np.repeat(np.cumsum(w)[first] - w[first], counts)  # each slot's start
        edges = k + step + within
        keep = np.zeros(w.size, dtype=bool)
        keep[first] = True
        keep[1:] |= np.abs(np.diff(g)) > DRIVE_JUMP * max(float(np.max(np.abs(g))), 1e-300)
        if frac < 1.0:  # (the end inside the last step: the slots up to it, the last one's part)
            end = k + L - 1 + frac
            w = np.clip(end - edges, 0.0, w)
            keep &= w > 0.0
        is_first = np.zeros(w.size, dtype=bool)
        is_first[first] = True
        # (an interval narrower than SLIVER of a step joins its neighbour: the circuit's integrator
        # cannot step across a width at its times' rounding; a step's first edge stays)
        lo = np.flatnonzero(keep)
        at = np.concatenate((edges[lo], [k + L - 1 + frac]))
        narrow = np.diff(at) < SLIVER
        drop = np.zeros(lo.size, dtype=bool)
        drop[1:] = narrow[:-1] & ~is_first[lo[1:]]  # (its start too near the one before)
        drop[:-1] |= narrow[1:] & is_first[lo[1:]] & ~is_first[lo[:-1]]  # (the one before a step's first)
        drop[-1] |= narrow[-1] & ~is_first[lo[-1]]  # (the last, too near the end)
        lo = lo[~drop]
        width = np.add.reduceat(w, lo)
        values = np.add.reduceat(g * w, lo) / width
        starts = np.searchsorted(lo, first[:L])
        breaks = t0 + dt * np.concatenate((edges[lo], [k + L - 1 + frac]))
        return breaks, -2.0 * values / float(self.grid.Z[0]), starts

    def run(self, drive, frac=1.0):
        out = self.lat.run(self.grid.cell_time, drive, frac=frac)
        self._waves = out["F"], out["G"]
        return float(out["junc"][-1, JUNC_SHANK])

    def waves(self):
        return self._waves


def _steps_to_free(cells, drive, k, h):
    """The lattice ``cells`` (:class:`_Cells`, :class:`_Slots`) run over the chunk of ``drive.size``
    steps from step ``k``, the piston tested for free for good
    (:func:`~impactbar.laws.rodrock._rockloop.piston_free`, the contact open on the step before) at
    the first step end at or after each multiple of ``h`` only (the exact blow's instants,
    :func:`end_window`): ``(ran, at)``, the chunk's steps up to the first such end and that
    multiple of ``h`` (``(-1, None)``: none within it), the lattice then."""
    from ._rockloop import piston_free
    from .grid import whole_steps

    grid = cells.grid
    dt = grid.cell_time
    L = drive.size
    n_p = grid.piston_cells
    j = math.floor(k * dt / h * (1.0 + 1e-12)) + 1  # the next multiple of h not yet tested
    done = 0
    while done < L:
        test = whole_steps(j * h, dt) - k  # (the chunk's step after which the j-th end is tested)
        stop = min(max(test, done + 1), L)
        shank = cells.run(drive[done:stop])
        done = stop
        if done == test:
            j += 1
            F, G = cells.waves()
            if shank == 0.0 and piston_free(F, G, grid.Z, n_p, cells.bs, cells.bp, dt):
                return done, (j - 1) * h
        elif test < done:
            j += 1
    return -1, None


def driven_rock_contact(model, drive, state, t0: float, q, v, settings=None) -> DrivenContact:
    """The blow of a piston arriving at the shank in modal state ``(q, q')`` at ``t0`` with the drive
    in ``state`` (as it arrives), solved together (module docstring; theory §11, "The coupled
    blow").

    Parameters
    ----------
    model : BarModel
        Under :class:`~impactbar.RodRock` (its grid, rock, bit and feed; damping neglected in the
        blow, as in the law's own).
    drive, state : Drive, DriveState
        A drive with state that follows a blow (its ability ``end_flight``), and its state
        as the piston arrives.
    t0 : float
        Time of the arrival (model units).
    q, v : array_like, shape (N + 1,)
        Modal positions (from the shank, ``u(1) = 0``) and velocities at arrival.
    settings : FlightSettings, optional
        How the drive is integrated over the blow's steps (default the drive's own settings).

    Returns
    -------
    DrivenContact
        Its ``record`` a :class:`~impactbar.laws.rodrock.contact.RockContact` whose blow took the
        drive's step averages.

    Raises
    ------
    ValueError
        A drive that cannot follow a blow (no ``end_flight`` in its abilities), or
        the drive's integration failing.
    """
    from ...loads import FourierLoad
    from .contact import BlowMap
    from .coupled_exact import HORIZONS
    from .grid import whole_steps

    law = model.law
    q = np.array(q, dtype=float)
    v = np.array(v, dtype=float)
    p0 = float(drive.force(state.mode, state.z, q, v))
    free = law.driven_end == "free"  # (the end where the piston is free for good, else the window)
    window = law.window(model)
    bm = BlowMap(model, FourierLoad(p0, []), t0, averaged=False,  # (the drive's averages: set below)
                 duration=HORIZONS * window if free else None)
    grid = bm.grid
    n_p, dt, n_max = grid.piston_cells, grid.cell_time, bm.n_max
    later = whole_steps(END_DELAY * window, dt) if END_DELAY > 0.0 else 0
    h = end_window(grid)
    Z0 = float(grid.Z[0])
    F, G = bm.fields(q, v)
    F0, G0 = F.copy(), G.copy()
    bs, bp = _bit_arrays(grid, law)
    bounds = np.ascontiguousarray(grid.bounds, dtype=np.int64)
    if grid.slots:
        from ._rockslots import SlotLattice

        cells = _Slots(grid, SlotLattice(grid.Z, grid.bounds, grid.delays, F, G, 0.0, bs, bp))
    else:
        cells = _Cells(grid, F, G, bs, bp, bounds)
    m = causal_cells(grid.Z, n_p)
    # (a contact that reads the waves arriving on its next step, grid.locate, answers a step sooner)
    chunk = max(1, 2 * m - 1) if grid.locate else 2 * m
    averages = bm.drive
    w = -float(model.drive_weights @ q)
    st = state
    follow = drive.abilities.end_flight
    if follow is None:
        raise LawNotSupported(f"the drive {type(drive).__name__} has state but cannot follow a blow "
                              "(no end_flight in its abilities); it runs under an instantaneous impact "
                              "law only")
    pieces, events = [], []
    k, end, ended, frac = 0, n_max, False, 1.0
    while k < end:
        L = min(chunk, end - k)
        # 1. the waves arriving at the driven end over the chunk (not caused by its drive)
        arriving = cells.arriving(L)
        # 2. the drive over the chunk, the driven end at u_t(0) = (p - 2 G_k) / Z_0
        breaks, incoming, starts = cells.drive_input(arriving, k, t0, L)
        fl = follow(model, st, breaks, w, incoming, Z0, settings)
        averages[k:k + L] = np.add.reduceat(fl.impulses, starts) / dt
        # 3. the lattice on over the chunk with the drive's averages (to the piston free for good)
        start = cells.copy()
        ran = -1
        if free and not ended:
            ran, at = _steps_to_free(cells, averages[k:k + L], k, h)
        else:
            cells.run(averages[k:k + L])
        if ran >= 0:  # free for good after `ran` steps: the blow ends there (or `later` on)
            ended, end = True, min(k + ran + later, n_max)
            if grid.slots and later == 0:  # the slots end at the multiple of h itself, inside its step
                frac = min(max((at - (end - 1) * dt) / dt, 1e-9), 1.0)
        if end - k < L or frac < 1.0:  # the drive and the lattice again over the chunk's part up to the end
            L = end - k
            cells = start
            breaks, incoming, starts = cells.drive_input(arriving, k, t0, L, frac)
            fl = follow(model, st, breaks, w, incoming, Z0, settings)
            averages[k:k + L] = np.add.reduceat(fl.impulses, starts) / dt
            cells.run(averages[k:k + L], frac)
        elif 0 <= ran < L:  # the end moved on past the chunk: the whole chunk without the end's test
            cells = start
            cells.run(averages[k:k + L])
        st, w = fl.state, fl.w
        pieces += fl.pieces
        events += fl.events
        k += L
    bm.n_max = k
    bm.end_fraction = frac
    rec = bm.contact(q, v)
    if ended:
        rec.blow = dataclasses.replace(rec.blow, ended_by="separated")  # (the piston free for good)
    rec.blow = rec.blow.with_stored_apart()  # the work on rock the dissipated work (theory §11)
    if not (np.array_equal(rec._F0, F0) and np.array_equal(rec._G0, G0)):  # pragma: no cover - defensive
        raise RuntimeError("the blow's fields at impact changed between its chunks and its record")
    work = float(sum(p.piston_work() for p in pieces))
    gaps = _rigid_gaps(model, q, v, rec.blow, averages, t0)
    return DrivenContact(rec.q_after.copy(), rec.v_after.copy(), float(t0) + rec.duration, rec, st, pieces,
                         events, work, gaps)


def _rigid_gaps(model, q, v, blow, averages, t0):
    """The piston's rigid coordinate ``-q_0`` at the step ends of the blow (from the shank at
    impact): its momentum changes by the drive's average less the shank's force over each step, so
    that ``q_0`` is piecewise quadratic, exact on the lattice; the vertices inside the steps added."""
    dt = blow.cell_time
    n = blow.shank_forces.size
    force = averages[:n] - blow.shank_forces
    vel = float(v[0]) + dt * np.concatenate(([0.0], np.cumsum(force)))
    pos = float(q[0]) + dt * np.concatenate(([0.0], np.cumsum(0.5 * (vel[:-1] + vel[1:]))))
    times = t0 + dt * np.arange(n + 1)
    if blow.times[-1] < n * dt:  # the slot lattice's end inside its last step: that step's part only
        part = blow.times[-1] - (n - 1) * dt
        force[-1] = averages[n - 1] * dt / part - blow.shank_forces[-1]
        vel[-1] = vel[-2] + force[-1] * part
        pos[-1] = pos[-2] + 0.5 * (vel[-2] + vel[-1]) * part
        times[-1] = t0 + blow.times[-1]
    # where the momentum changes sign inside a step, the rigid coordinate turns there
    turn = (vel[:-1] * vel[1:] < 0.0) & (force != 0.0)
    if np.any(turn):
        i = np.flatnonzero(turn)
        tau = -vel[i] / force[i]
        times = np.concatenate((times, times[i] + tau))
        pos = np.concatenate((pos, pos[i] + vel[i] * tau + 0.5 * force[i] * tau * tau))
        order = np.argsort(times, kind="stable")
        times, pos = times[order], pos[order]
    return np.vstack((times, -pos))

