r"""The characteristics grid of a blow (theory §4d): the common cell time of the piston's and the
rod's segments (:func:`blow_grid`, :class:`BlowGrid`), the bounds on a blow's size that refuse a grid
which would not finish in bounded time or memory, and the whole steps of a duration on it. The
blow itself, stepped on this grid, is :mod:`impactbar.laws.rodrock.blow`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._piston import piston_cells, piston_segments


def commensurate_cells(times, max_cells: int = 1000, rtol: float = 1e-9):
    """Smallest ``n`` such that every travel time in ``times`` (shape ``(J,)``, the piston's first)
    is a whole number of cells ``times[0]/n``; ``None`` if none up to ``max_cells`` for the piston."""
    r = np.asarray(times, dtype=float) / times[0]
    for n in range(1, max_cells + 1):
        c = r * n
        if np.all(np.abs(c - np.round(c)) <= rtol * np.maximum(c, 1.0)):
            return n
    return None


#: Most cell updates (cells times steps) one blow may take (some seconds), and most stored
#: values with ``record_field`` (1 GiB as float64): beyond, it is refused before any allocation.
MAX_CELL_STEPS = 5e9
MAX_FIELD_VALUES = 2**27


def _check_blow_size(n_cells, n_steps, record_field) -> None:
    """Refuse a blow whose characteristics grid would not finish in bounded time or memory (a rod
    far longer, in travel time, than the piston)."""
    work = float(n_cells) * max(1.0, float(n_steps))
    if not work <= MAX_CELL_STEPS:
        raise ValueError(f"single blow: {n_cells:.6g} cells over {n_steps:.4g} steps "
                         f"({work:.3g} cell updates) exceed {MAX_CELL_STEPS:g}: the rod's travel "
                         "time is too long against the piston's (segment lengths / wave speeds), or "
                         "the grid too fine; use fewer cells_per_piston or a shorter t_max")
    if record_field and not work <= MAX_FIELD_VALUES:
        raise ValueError(f"single blow: record_field would keep {work:.3g} values (more than "
                         f"{MAX_FIELD_VALUES}); use a shorter t_max or fewer cells_per_piston")


@dataclass(frozen=True)
class BlowGrid:
    """The common cell grid of a blow (see the module's text).

    Attributes
    ----------
    s : float
        The piston's impedance (the model's ``s``).
    cell_time : float
        ``dt``, the time a wave takes to cross any cell.
    piston_cells : int
        Cells along the piston (its far, driven end is cell 0; the shank is right of the last).
    segment_cells : tuple of int
        Each segment's cells.
    Z : numpy.ndarray, shape (cells,)
        Every cell's impedance, piston then rod.
    bounds : numpy.ndarray of int, shape (J,)
        The cell right of each segment boundary, the shank first.
    edges : numpy.ndarray, shape (cells + 1,)
        Cell boundaries in piston lengths, the shank at 0.
    travel : numpy.ndarray, shape (J,)
        The segments' exact travel times.
    static : float
        The rod's strain energy under a unit feed force (``sum n dt / (2 Z)``).
    piston_segment_cells : tuple of int
        Each of the piston's segments' cells, from its driven end (one segment: the uniform piston).
    piston_travel : numpy.ndarray, shape (n_segments,), or None
        The piston's segments' exact travel times.
    locate : bool
        Whether a piston-shank re-contact is located inside its step (the contact's force from
        where the gap closes, averaged over the step; ``RodRock(contact_events="inside")``), else
        from the next step (default).
    slots : bool
        Whether the blow runs on the slot lattice (``RodRock(contact_events="slots")``,
        :mod:`~impactbar.laws.rodrock._rockslots`): the events inside the steps, each rod segment its
        whole cells (``floor``, at least one) and a delay of the rest.
    delays : tuple of (int, float)
        With ``slots``, each rod segment's index and the fraction of a step ``0 <= delta < 1`` its
        travel time exceeds its cells' by; else empty.
    """

    s: float
    cell_time: float
    piston_cells: int
    segment_cells: tuple
    Z: np.ndarray
    bounds: np.ndarray
    edges: np.ndarray
    travel: np.ndarray
    static: float
    piston_segment_cells: tuple = (1,)
    piston_travel: np.ndarray | None = None
    locate: bool = False
    slots: bool = False
    delays: tuple = ()

    @property
    def length_error(self) -> float:
        """Largest relative change of a segment's travel time (the rod's and the piston's) by
        rounding it to whole cells (on the slot lattice, a rod segment's cells and its delay)."""
        held = np.array(self.segment_cells, dtype=float)
        for i, d in self.delays:
            held[i] += d
        cells = held * self.cell_time
        err = float(np.max(np.abs(cells - self.travel) / self.travel))
        if self.piston_travel is not None:
            pc = np.array(self.piston_segment_cells) * self.cell_time
            err = max(err, float(np.max(np.abs(pc - self.piston_travel) / self.piston_travel)))
        return err


def blow_grid(s, lengths, impedances, speeds, cells_per_piston=None, piston=None, locate=False,
              slots=False) -> BlowGrid:
    """The cell grid of :func:`rod_rock_blow` (its parameters of the same names; the piston's cells:
    :func:`~impactbar.laws.rodrock._piston.piston_cells`; ``locate``, ``slots``: ``BlowGrid``'s)."""
    with np.errstate(over="ignore"):  # a wave speed near 0: an infinite travel time, refused below
        travel = np.asarray(lengths, float) / (np.asarray(speeds, float) * s)
    Tp = 1.0 / s
    if not np.all(np.isfinite(travel)):
        _check_blow_size(math.inf, math.inf, False)
    p_len, p_mu = piston_segments(piston)
    p_travel = p_len * Tp
    if cells_per_piston is None:
        n0 = commensurate_cells(np.concatenate(([Tp], p_travel, travel)))
        cells_per_piston = 64 if n0 is None else n0 * math.ceil(8 / n0)
    n_p = int(cells_per_piston)
    dt = Tp / n_p
    _check_blow_size(n_p + float(np.sum(travel)) / dt, 1, False)  # the steps: in solve_blow
    delays = ()
    if slots:  # each segment its whole cells and a delay of the rest (_rockslots)
        seg_cells = [max(1, math.floor(T / dt * (1.0 + 1e-12))) for T in travel]
        delays = tuple((i, max(float(T / dt) - n, 0.0))
                       for i, (T, n) in enumerate(zip(travel, seg_cells, strict=True)))
    else:
        seg_cells = [max(1, round(T / dt)) for T in travel]
    pieces = list(zip(seg_cells, impedances, strict=True))
    dx = np.concatenate([np.full(n_p, 1.0 / n_p)]
                        + [np.full(n, c / n_p) for n, c in zip(seg_cells, speeds, strict=True)])
    edges = np.concatenate(([0.0], np.cumsum(dx))) - 1.0
    p_cells, Z_p = piston_cells(s, p_len, p_mu, n_p)
    Z = np.concatenate([Z_p] + [np.full(n, s * z) for n, z in pieces])
    bounds = np.cumsum([n_p] + seg_cells)[:-1]  # cell index right of each segment boundary
    held = [n + d for n, (_, d) in zip(seg_cells, delays, strict=True)] if delays else seg_cells
    static = float(sum(n * dt / (2.0 * s * z) for n, z in zip(held, impedances, strict=True)))
    return BlowGrid(s=float(s), cell_time=dt, piston_cells=n_p, segment_cells=tuple(seg_cells), Z=Z,
                    bounds=bounds.astype(np.int64), edges=edges, travel=travel, static=static,
                    piston_segment_cells=tuple(int(n) for n in p_cells), piston_travel=p_travel,
                    locate=bool(locate), slots=bool(slots), delays=delays)


def incident_steps(shank_forces, starts, round_trip: float) -> int:
    """How many of a lattice blow's first steps carry its incident wave (``Blow.incident_peak_force``,
    the gradient search of ``optimize_piston``): those that start (``starts``, shape ``(n,)``, of
    the ``shank_forces``' steps) before ``round_trip``, or before the first step after the first
    without force (the piston's first separation), whichever are more; at least one."""
    return max(1, first_free_step(shank_forces), int(np.searchsorted(starts, round_trip, side="left")))


def first_free_step(shank_forces) -> int:
    """The index of a lattice blow's first step without piston-shank force, the first step aside
    (the piston's first separation; ``len(shank_forces)`` where there is none)."""
    off = np.flatnonzero(np.asarray(shank_forces)[1:] <= 0.0)
    return int(off[0]) + 1 if off.size else len(shank_forces)


def whole_steps(duration: float, dt: float) -> int:
    """Cell steps of length ``dt`` a blow of ``duration`` lasts: ``ceil(duration / dt)``, at least
    one (a duration within rounding of a whole number of steps is that number)."""
    return max(1, math.ceil(float(duration) / dt * (1.0 - 1e-12)))
