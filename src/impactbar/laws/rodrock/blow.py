"""One blow of the piston on a finite, stepped rod whose bit loads a bilinear rock (theory §4d).

Method (Bacon's characteristics on segments, as in elwaspatid and in Lundberg's rod analyses): the
piston (uniform, length 1, impedance ``s``, crossing time ``1/s``) and the rod's segments are cut into
cells of one common travel time ``dt``; each cell carries a right-going force wave ``F`` and a
left-going one ``G`` (compressive force ``N = F + G``, velocity ``v = (F - G)/Z``, ``Z`` the cell's
impedance). Per step every wave moves one cell; at a cell boundary between impedances ``Z_a`` (left)
and ``Z_b`` (right) the welded junction gives ``N = 2 (Z_b F_a + Z_a G_b)/(Z_a + Z_b)``, ``G_a = N - F_a``,
``F_b = N - G_b``. This is exact for waves constant on cells (the uniform piston's), and energy is
conserved step by step (``F_a^2/Z_a + G_b^2/Z_b = G_a^2/Z_a + F_b^2/Z_b``).

- A stepped piston (theory §12): cells of its segments' impedances, welded (``_piston``).
- Piston's far end: ``N = p``, the drive's force averaged over each step (:func:`solve_blow`, the
  simulator's blow); free, ``F = -G``, in a :func:`rod_rock_blow`.
- Piston-shank contact: unilateral; the welded junction while its force is compressive, free ends
  (``N = 0``) otherwise, with the gap ``g' = v_shank - v_piston`` summed per step (and floored at
  0); contact resumes at the first step that starts with the gap closed and the welded force
  compressive (timing error below one step). With ``BlowGrid.locate`` (``RodRock(contact_events=
  "inside")``) both switches are placed inside their steps: each arriving wave's cell average read
  as its value on the step before up to a front and on the next after it (``_bit.opens_inside``,
  ``closes_inside``), the step's force the welded force's integral up to the switch (or from it).
- Bit and rock: with the incident wave ``F`` constant over the cell, the bit (mass ``m >= 0``,
  displacement into the rock ``p``) obeys ``m p'' + Z p' + R(p) = 2 F + f`` (``f`` the feed force),
  solved exactly per cell on each branch of Lundberg's bilinear law ``R(p)``: loading ``R = k p`` at
  the largest penetration so far, unloading and reloading ``R = k_u (p - p_perm)`` with
  ``p_perm = p_max - R_max/k_u``, lift-off ``R = 0`` for ``p < p_perm``. Branch changes inside a cell are
  located exactly (massless bit: closed form; bit with mass: bisection of the exact solution
  sampled at 4 points per cell, or 4 per half period of an oscillating bit). The reflected wave is
  stored as its cell average ``F - Z (p_end - p_start)/dt``; the
  energy this averaging removes (``int G^2 dt/Z - G_avg^2 dt/Z >= 0``, zero for a wave constant on
  cells) is reported as ``grid_loss`` so that the energy account closes to rounding.
- The feed force ``f`` acts on the shank throughout; before the blow the rod is statically compressed
  by it and the bit rests on fresh rock loaded to ``f`` (``p = f/k``): every blow meets fresh rock
  (Lundberg's per-blow model). The waves carry the force above that static state.

Sources: Lundberg, B., "Microcomputer simulation of stress wave energy transfer to rock in
percussive drilling", Int. J. Rock Mech. Min. Sci. 19 (1982) 229-239 (the bilinear bit-rock law and
``eta = (2/alpha)(1 - e^-alpha)^2 (1 - 1/gamma)``); Karlsson, Lundberg, Sundin, "Experimental study of
a percussive process for rock fragmentation", Int. J. Rock Mech. Min. Sci. 26 (1989) 45-50;
Chiang, L.E., Elias, D.A., "Modeling impact in down-the-hole rock drilling", Int. J. Rock Mech. Min.
Sci. 37 (2000) 599-613; Song et al. (2018); Bacon's method as in the elwaspatid package.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import ClassVar

import numpy as np

from ..._shared.schema import Field, Schema
from . import _records as S
from ._bit import _FREE, _LOAD, _Bit, _python_loop, feed_gain
from ._records import BITREC_FORCE, BITREC_PEN, JUNC_SHANK
from .grid import BlowGrid, _check_blow_size, blow_grid, first_free_step, incident_steps, whole_steps

__all__ = ["Blow", "BlowGrid", "blow_grid", "rod_rock_blow", "solve_blow"]

@dataclass
class Blow:
    """One blow on the rod and the rock (theory §4d), in the model's units (time ``t``, forces and
    energies as in :class:`~impactbar.BarModel`: the piston's mass and length are 1, its impedance
    ``s``).

    Attributes
    ----------
    times : numpy.ndarray, shape (n + 1,)
        Step ends ``0, dt, ..., n dt`` from the impact.
    shank_forces : numpy.ndarray, shape (n,)
        Piston-shank contact force on each step (constant on it).
    junction_forces : numpy.ndarray, shape (n, J)
        Force at every segment boundary (the shank first), constant on each step.
    bit_forces, penetrations : numpy.ndarray, shape (n + 1,)
        Rock force ``R`` and penetration ``p`` (from the rock's surface before the feed) at the step
        ends.
    field : numpy.ndarray, shape (n, cells) or None
        Force (above the feed's) in every cell, piston then rod (``record_field=True``).
    energy_at_impact : float
        The piston's energy at impact (of its fields on the grid): ``V^2/2`` for a rigid piston.
    drive_work : float
        Work of the drive's force on the piston's far end during the blow (0 for
        :func:`rod_rock_blow`; the step-averaged drive of :func:`solve_blow`).
    feed_work : float
        Work of the feed force on the shank during the blow.
    available_energy : float
        ``energy_at_impact + drive_work + feed_work`` plus the energy stored under the feed at the start: the
        rod's static strain energy and the rock's recoverable elastic energy ``f^2/(2 k_u)``.
    work_on_rock : float
        ``int R dp`` over the blow plus ``f^2/(2 k_u)`` (the rock's elastic energy under the feed
        at the start, which the blow may take back): ``>= 0``; the rock's elastic energy left at
        the end is included.
    rock_stored_energy : float
        The rock's elastic energy at the end, ``R^2/(2 k_u)`` of the rock force ``R`` left then
        (what its unloading line would give back; 0 once the bit has lifted, or with a rigid
        unloading).
    rock_dissipated : float
        ``work_on_rock - rock_stored_energy``: the work the rock has taken for good (crushing), which
        a longer window can only increase; ``work_on_rock`` of a window cut while the bit still
        loads includes elastic energy a longer one gives back (``work_on_rock`` with ``stored_apart``).
    stored_apart : bool
        ``rock_stored_energy`` apart in the energy account, ``work_on_rock`` the dissipated work
        (the blows under a drive with state, theory §11).
    piston_energy : float
        Energy returned to the piston (its wave energy at the end).
    rebound_velocity : float
        The piston's mean velocity at the end (negative: moving back).
    rod_energy, bit_energy : float
        The rod's residual energy (waves, strain under the feed) plus the bit's kinetic energy; that
        kinetic energy ``m w^2/2`` at the end (the bit's part of ``rod_energy``, its term apart).
    grid_loss : float
        Energy removed by storing the bit's reflected wave as cell averages (0 for a massless bit
        and a rock force constant on cells; ``O(dt^2)``).
    energy_error : float
        ``|available - (work_on_rock + piston_energy + rod_energy + grid_loss)| / available`` (with
        ``stored_apart`` also ``rock_stored_energy``).
    max_penetration, permanent_penetration, advance : float
        Largest penetration; the penetration where the rock force vanishes on the last unloading
        line (``p_max - R_max/k_u``); the bit's displacement over the blow.
    cell_time, piston_cells, segment_cells : float, int, tuple of int
        The grid: ``dt``, the piston's cells, each segment's cells.
    length_error : float
        Largest relative change of a segment's travel time by rounding it to whole cells (0 on a
        commensurate grid): the blow is exact for the rod so changed; the error this makes in the
        results is ``O(dt)``.
    cell_edges : numpy.ndarray, shape (cells + 1,)
        Cell boundaries in piston lengths, the shank at 0 (the piston in ``[-1, 0]``).
    ended_by : str
        ``"energy"`` (the piston separated and the rod's wave energy below the fraction),
        ``"separated"`` (the piston separated for ``separation_time``, :func:`solve_blow`) or
        ``"t_max"``; by the exact method those of
        ``ExactBlow.ended_by`` (``impactbar.laws.rodrock.exact``).
    gap, shank_displacement : float
        At the end: the piston-shank gap (0 in contact) and the shank's displacement from its
        static position at impact.
    piston_waves : tuple of numpy.ndarray, shape (piston_cells,) each, or None
        The piston's right- and left-going force waves ``(F, G)`` at the end (cell 0 at its driven
        end).
    rod_waves : tuple of numpy.ndarray, shape (rod cells,) each, or None
        The rod's waves ``(F, G)`` at the end, above the feed's static state.
    bit_velocity : float
        The bit's velocity at the end.
    method, uncertainty, loadings, radiated : str, float, numpy.ndarray (n, 5) or None, float
        ``"exact"`` (``impactbar.laws.rodrock.exact``: the arrays sample exact histories, which the
        force methods evaluate) or ``"lattice"`` (first order in ``cell_time``); 0 for a certified
        end (or a lattice's end by energy or separation), else (a horizon, a cost bound) a bound on
        the rock work still possible over the available energy, the
        efficiency still to gain by it (with a feed the efficiency also follows the feed's work,
        which a rod ringing on the rock moves either way); exact: per loading of the rock (its
        yielding), start and end time and penetration, the work dissipated; the energy a
        semi-infinite rod radiated.

    Examples
    --------
    >>> from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow
    >>> law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
    >>> blow = single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, t_max=39.0)
    >>> round(blow.work_on_rock / blow.energy_at_impact, 6) == round(blow.efficiency, 6)
    True
    >>> blow  # a short repr: the energy account and the rock's penetration (to_dict: every number)
    Blow(ended by t_max, energy at impact 0.5, work on rock 0.3665, efficiency 0.7331, permanent
         penetration 0.5137, duration 39, rebound velocity 0)
    """

    #: the declared fields, the numbers of a blow (model units): :meth:`to_dict`, and those in the
    #: view ``"repr"`` the short repr; the arrays are the attributes
    fields: ClassVar[Schema] = Schema(
        Field("ended_by", "why the blow ended", "", dtype="U", views={"repr"}, label="ended by"),
        *(Field(name, long_name, views=views, fmt=".4g") for name, long_name, views in (
            ("energy_at_impact", "the piston's energy at impact", {"repr"}),
            ("drive_work", "work of the drive on the piston during the blow", ()),
            ("feed_work", "work of the feed force on the shank during the blow", ()),
            ("available_energy", "energy available to the blow", ()),
            ("work_on_rock", "work done on the rock", {"repr"}),
            ("rock_dissipated", "work on rock taken for good: the work less the rock's elastic energy",
             ()),
            ("rock_stored_energy", "the rock's elastic energy at the end", ()),
            ("efficiency", "work on rock over the available energy", {"repr"}),
            ("efficiency_with_rebound", "the same with the piston's rebound energy credited", ()),
            ("piston_energy", "energy returned to the piston", ()),
            ("rod_energy", "the rod's residual energy and the bit's kinetic energy", ()),
            ("bit_energy", "the bit's kinetic energy at the end (a part of rod_energy)", ()),
            ("grid_loss", "energy removed by the cell averages of the bit's reflected wave", ()),
            ("energy_error", "relative mismatch of the energy account", ()),
            ("max_penetration", "largest penetration", ()),
            ("permanent_penetration", "permanent penetration", {"repr"}),
            ("advance", "the bit's displacement over the blow", ()),
            ("duration", "length of the blow", {"repr"}),
            ("rebound_velocity", "the piston's mean velocity at the end", {"repr"}),
            ("bit_velocity", "the bit's velocity at the end", ()),
            ("gap", "piston-shank gap at the end", ()),
            ("shank_displacement", "the shank's displacement from its static position at impact", ()),
            ("uncertainty", "bound on the efficiency the blow could still gain", ()),
            ("radiated", "energy radiated by a semi-infinite rod", ()),
            ("cell_time", "the grid's time step dt", ()),
            ("length_error", "largest relative change of a segment's travel time by the grid", ()))),
        Field("piston_cells", "cells along the piston", "", dtype="i8"),
        Field("method", "the blow's solver", "", dtype="U"))

    def __repr__(self) -> str:
        """One line: why it ended, the energy account, the penetration (the arrays: the
        attributes; every number: :meth:`to_dict`)."""
        return f"Blow({', '.join(self.fields.select('repr').summary(self))})"

    def to_dict(self) -> dict:
        """Every number of the blow (:attr:`fields`), JSON-ready; the arrays (force histories,
        penetrations, the field) are the attributes."""
        return self.fields.record(self)

    times: np.ndarray
    shank_forces: np.ndarray
    junction_forces: np.ndarray
    bit_forces: np.ndarray
    penetrations: np.ndarray
    field: np.ndarray | None
    energy_at_impact: float
    feed_work: float
    available_energy: float
    work_on_rock: float
    piston_energy: float
    rebound_velocity: float
    rod_energy: float
    grid_loss: float
    max_penetration: float
    permanent_penetration: float
    advance: float
    ended_by: str
    cell_time: float
    piston_cells: int
    segment_cells: tuple = field(default=())
    cell_edges: np.ndarray | None = None
    length_error: float = 0.0
    drive_work: float = 0.0
    gap: float = 0.0
    shank_displacement: float = 0.0
    piston_waves: tuple | None = None
    rod_waves: tuple | None = None
    bit_velocity: float = 0.0
    rock_stored_energy: float = 0.0
    method: str = "lattice"
    uncertainty: float = 0.0
    bit_energy: float = 0.0
    loadings: np.ndarray | None = None
    radiated: float = 0.0
    exact: object = field(default=None, repr=False)
    stored_apart: bool = False

    def __post_init__(self) -> None:
        # the scalars as plain floats (the solver hands numpy scalars), like every other result
        for f in ("energy_at_impact", "feed_work", "available_energy", "work_on_rock", "piston_energy",
                  "rebound_velocity", "rod_energy", "grid_loss", "max_penetration",
                  "permanent_penetration", "advance", "cell_time", "length_error", "drive_work", "gap",
                  "shank_displacement", "bit_velocity", "rock_stored_energy", "uncertainty",
                  "radiated", "bit_energy"):
            object.__setattr__(self, f, float(getattr(self, f)))

    @property
    def energy_error(self) -> float:
        """Relative mismatch of the energy account (rounding only; ``inf`` where the available
        energy is not positive, a blow gone wrong)."""
        total = (self.work_on_rock + self.piston_energy + self.rod_energy + self.grid_loss
                 + (self.rock_stored_energy if self.stored_apart else 0.0))
        err = abs(self.available_energy - total) / abs(self.available_energy)
        return err if self.available_energy > 0.0 and err == err else math.inf

    @property
    def rock_dissipated(self) -> float:
        """The work the rock keeps (theory §4d): ``work_on_rock`` less any ``rock_stored_energy`` in it."""
        return self.work_on_rock if self.stored_apart else self.work_on_rock - self.rock_stored_energy

    def with_stored_apart(self) -> Blow:
        """This blow with ``stored_apart``: ``work_on_rock`` the work dissipated in the rock."""
        return self if self.stored_apart else replace(self, work_on_rock=self.rock_dissipated,
                                                      stored_apart=True)

    @property
    def energy_into_rod(self) -> float:
        """Energy the piston gave the rod: ``energy_at_impact + drive_work - piston_energy``."""
        return self.energy_at_impact + self.drive_work - self.piston_energy

    @property
    def efficiency(self) -> float:
        """Work on rock over the energy available to the blow (``<= 1``)."""
        return self.work_on_rock / self.available_energy

    @property
    def efficiency_with_rebound(self) -> float:
        """Work on rock over the available energy less the energy returned to the piston (the
        rebound credited; ``<= 1``); 0 when the piston took back all of it (a rod of far higher
        impedance: the rod and rock took nothing to credit)."""
        delivered = self.available_energy - self.piston_energy
        return self.work_on_rock / delivered if delivered > 0.0 else 0.0

    @property
    def duration(self) -> float:
        """Length of the blow (model time)."""
        return float(self.times[-1])

    def shank_force(self, t) -> np.ndarray:
        """Piston-shank force at times ``t`` (lattice: constant on each step; 0 outside)."""
        return self.junction_force(0, t)

    def junction_force(self, j: int, t) -> np.ndarray:
        """Force at segment boundary ``j`` (0: the shank) at times ``t`` (exact method: exact)."""
        if self.exact is not None:
            t = np.asarray(t, dtype=float)
            j = self.exact.contact_junction + int(j)
            return np.where((t >= 0.0) & (t < self.duration), self.exact.junction_force(j, t), 0.0)
        return self._steps(self.junction_forces[:, j], t)

    def junction_impulse(self, j: int = 0) -> float:
        """The impulse ``int N dt`` of segment boundary ``j``'s force (0: the shank) over the blow:
        exact piece by piece (exact method), or the steps' forces times the cell time (lattice)."""
        if self.exact is not None:
            return self.exact.junction_impulse(self.exact.contact_junction + int(j))
        return float(np.sum(self.junction_forces[:, j])) * self.cell_time

    def bit_force(self, t) -> np.ndarray:
        """Rock force at times ``t`` (exact method: exact; lattice: linear between step ends)."""
        if self.exact is not None:
            return self.exact.bit_force(np.clip(np.asarray(t, dtype=float), 0.0, self.duration))
        return np.interp(t, self.times, self.bit_forces, left=self.bit_forces[0], right=self.bit_forces[-1])

    def peak_forces(self):
        """The largest force at every segment boundary (the shank first) and at the bit, and when
        first reached (exact method: the maxima of the pieces; lattice: of the step values):
        ``values, times``, arrays of shape ``(J + 1,)``."""
        if self.exact is not None:  # (a stepped piston's own steps first: not the rod's)
            values, times = self.exact.peak_forces()
            first = self.exact.contact_junction - 1
            return values[first:], times[first:]
        i, jb = np.argmax(self.junction_forces, axis=0), int(np.argmax(self.bit_forces))
        return (np.append(self.junction_forces[i, np.arange(i.size)], self.bit_forces[jb]),
                np.append(self.times[i], self.times[jb]))

    @property
    def first_separation(self) -> float:
        """When the piston first left the shank (exact method: the start of the shank force's first
        zero piece; lattice: the first step without force); ``duration`` where it never did."""
        if self.exact is not None:
            return self.exact.first_separation
        i = first_free_step(self.shank_forces)
        return float(self.times[i]) if i < self.shank_forces.size else self.duration

    def peak_shank_force(self, t_end: float | None = None) -> tuple[float, float]:
        """The largest piston-shank force up to ``t_end`` (default: over the whole blow) and when
        first reached: ``value, time`` (exact method: the maximum of its pieces; lattice: of the
        steps that start before ``t_end``)."""
        t_end = self.duration if t_end is None else min(float(t_end), self.duration)
        if self.exact is not None:
            return self.exact.shank_peak(t_end)
        n = max(1, int(np.searchsorted(self.times[:-1], t_end, side="left")))
        i = int(np.argmax(self.shank_forces[:n]))
        return float(self.shank_forces[i]), float(self.times[i])

    def incident_peak_force(self, round_trip: float) -> float:
        """The peak of the incident wave (theory §12): the largest piston-shank force before the
        wave the rock reflects first is back at the shank, at ``round_trip`` (the rod's, shank to
        bit and back, model time), or over the piston's first contact where that lasts longer (a
        stepped piston's own re-strikes are part of its incident wave; what the rock sends back is
        not, nor a re-contact on it). Lattice: over the steps that ``incident_steps`` counts."""
        if self.exact is not None:
            force, _ = self.peak_shank_force(max(float(round_trip), self.first_separation))
            return force
        n = incident_steps(self.shank_forces, self.times[:-1], round_trip)
        return float(np.max(self.shank_forces[:n]))

    def _steps(self, values, t):
        t = np.asarray(t, dtype=float)
        i = np.floor(t / self.cell_time).astype(int)
        inside = (i >= 0) & (i < values.size)
        return np.where(inside, values[np.clip(i, 0, values.size - 1)], 0.0)

    def plot_lagrange(self, ax=None, **kwargs):
        """Draw the x-t (Lagrange) diagram of force in piston and rod
        (:func:`impactbar.plotting.rock.plot_lagrange`; matplotlib imported on this call).

        Returns
        -------
        matplotlib.axes.Axes
        """
        from ...plotting.rock import plot_lagrange

        return plot_lagrange(self, ax=ax, **kwargs)

    def plot_loop(self, ax=None, **kwargs):
        """Draw the bit's force against penetration, the loading and unloading loop
        (:func:`impactbar.plotting.rock.plot_force_penetration`).

        Returns
        -------
        matplotlib.axes.Axes
        """
        from ...plotting.rock import plot_force_penetration

        return plot_force_penetration(self, ax=ax, **kwargs)


def rod_rock_blow(s, V, lengths, impedances, speeds, k, k_u, bit_mass, feed, *, cells_per_piston=None,
                  t_max=None, energy_fraction=1e-9, record_field=False, piston=None) -> Blow:
    """One blow by characteristics on the piston and the rod's segments (see the module's text).

    Parameters
    ----------
    s : float
        The model's wave-speed ratio: the piston's impedance and ``1/s`` its crossing time.
    V : float
        Impact velocity (> 0), the piston moving rigidly and unstressed.
    lengths, impedances, speeds : sequence of float, shape (J,)
        The segments' lengths (piston lengths), impedances and wave speeds (relative to the piston's).
    k, k_u : float
        Loading and unloading stiffness of the rock (model units of force per length).
    bit_mass : float
        In piston masses (>= 0).
    feed : float
        Static feed force on the shank (model units, >= 0).
    cells_per_piston : int, optional
        Cells along the piston. Default: the smallest count making every segment a whole number of
        cells (at least 8), else 64 with the segments rounded to whole cells.
    t_max : float, optional
        Longest blow (model time). Default ``20 (1/s + sum of the segments' travel times)``.
    energy_fraction : float
        The blow ends once the piston has separated and the rod's wave energy (plus the bit's kinetic
        energy) is below this fraction of the impact energy.
    record_field : bool
        Keep the force in every cell at every step (for the Lagrange diagram).
    piston : SteppedPiston, optional
        A stepped piston (theory §12): its segments, from the driven end to the struck end, carried
        by characteristics as cells of impedances ``s mu_j`` (``mu_j`` the segments' masses per
        length, the piston's mass 1 and length 1, one material: wave speed 1), welded to each other
        and joined to the shank by the same unilateral contact (the rod's impedances stay relative
        to ``s``, a uniform piston's of the same mass and length). Default None: the uniform piston
        (the same as a one-segment ``SteppedPiston``, cell for cell). The default grid makes its
        segments whole numbers of cells too (``Blow.length_error`` counts them).

    Returns
    -------
    Blow
    """
    grid = blow_grid(s, lengths, impedances, speeds, cells_per_piston, piston)
    n_p = grid.piston_cells
    F = np.zeros(grid.Z.size)
    G = np.zeros(grid.Z.size)
    F[:n_p] = 0.5 * grid.Z[:n_p] * V  # moving rigidly at V, unstressed: v = (F - G)/Z, N = F + G = 0
    G[:n_p] = -F[:n_p]
    if t_max is None:
        t_max = 20.0 * (grid.cell_time * n_p + float(np.sum(grid.travel)))
    return solve_blow(grid, F, G, None, k, k_u, bit_mass, feed, t_max=t_max,
                      energy_fraction=energy_fraction, record_field=record_field)


def solve_blow(grid: BlowGrid, F, G, drive, k, k_u, bit_mass, feed, *, t_max, energy_fraction=1e-9,
               separation_time=None, gap=0.0, bit_state=None, record_field=False, n_steps=None,
               end_fraction=1.0) -> Blow:
    """A blow on ``grid`` from the piston's waves ``F, G`` (shape ``(cells,)``, the rod's zero: at rest
    under the feed), with the drive's force ``drive`` on the piston's far end averaged over each step
    (shape ``(n_max,)`` for ``n_max = ceil(t_max / dt)`` steps, or None for no drive); the rest as
    :func:`rod_rock_blow`. ``separation_time`` (model time) also ends the blow once the piston has been
    separated from the shank that long (``ended_by = "separated"``). ``gap >= 0``: the piston's struck
    end that far behind the shank at the start (0: touching). ``bit_state = (p, w)``: the bit at
    penetration ``p`` into fresh rock (lifted off for ``p < 0``) moving at ``w`` (default: at rest
    under the feed, ``p = f/k``). ``n_steps`` stops after that many steps
    whatever the energy (a state inside a blow). The result's ``piston_waves`` are the piston's
    final ``(F, G)``, ``gap`` the piston-shank gap and ``shank_displacement`` the shank's dynamic
    displacement at the end. ``end_fraction`` (the slot lattice, ``grid.slots``, with ``n_steps``):
    the last step run to that fraction of it only, the blow's end inside it."""
    s, dt, n_p, Z = grid.s, grid.cell_time, grid.piston_cells, grid.Z
    F = np.array(F, dtype=float)
    G = np.array(G, dtype=float)
    E0 = float(np.sum((F[:n_p] ** 2 + G[:n_p] ** 2) / Z[:n_p])) * dt
    _check_blow_size(grid.Z.size, (t_max / dt if n_steps is None else n_steps), record_field)
    n_max = whole_steps(t_max, dt) if n_steps is None else max(1, int(n_steps))
    stop = energy_fraction * E0 if n_steps is None else -1.0
    bit = _start_bit(Z, k, k_u, bit_mass, feed, bit_state)
    p_start = bit.p
    static = grid.static * feed * feed
    F, G, junc, bitf, pen, fld, acc = _run(grid, F, G, drive, bit, n_max, stop, separation_time, gap,
                                           record_field, end_fraction)
    u_shank, grid_loss, ended, gap, drive_work, *slots = acc
    shank = junc[:, JUNC_SHANK]
    n = shank.size
    e = (F * F + G * G) / Z * dt
    piston_e = float(np.sum(e[:n_p]))
    rod_waves = float(np.sum(e[n_p:]))
    if slots:  # the slot lattice: what the cells' averages drop from its slots' energies is the grid's
        # loss; the waves held in its delays are the rod's
        piston_slots, rod_slots, held = slots
        grid_loss += (piston_slots - piston_e) + (rod_slots - rod_waves)
        rod_waves += held
    feed_work = feed * u_shank
    rock0 = feed * feed / (2.0 * k_u)  # the rock's recoverable elastic energy under the feed
    rod_energy = rod_waves + feed * (u_shank - (bit.p - p_start)) + static + 0.5 * bit_mass * bit.w * bit.w
    available = E0 + drive_work + feed_work + static + rock0
    uncertainty = 0.0
    if ended == "t_max" and n_steps is None:  # stopped at the horizon, nothing certified
        uncertainty = _still_possible(rod_waves, piston_e, float(bitf[-1]), bit, feed) / available
    times = dt * np.arange(n + 1)
    if end_fraction < 1.0 and n == n_max:  # (the slot lattice's end inside its last step)
        times[-1] = (n - 1 + end_fraction) * dt
    return Blow(
        times=times, shank_forces=shank, junction_forces=junc,
        bit_forces=bitf, penetrations=pen, field=fld if record_field else None,
        energy_at_impact=E0, feed_work=feed_work,
        available_energy=available, work_on_rock=bit.work + rock0,
        piston_energy=piston_e, rebound_velocity=float(np.mean((F[:n_p] - G[:n_p]) / s)),
        rod_energy=rod_energy, grid_loss=grid_loss, max_penetration=bit.p_max,
        permanent_penetration=bit.p_perm, advance=bit.p - p_start, ended_by=ended, cell_time=dt,
        piston_cells=n_p, segment_cells=grid.segment_cells, cell_edges=grid.edges,
        length_error=grid.length_error, drive_work=drive_work, gap=gap, shank_displacement=u_shank,
        piston_waves=(F[:n_p].copy(), G[:n_p].copy()), rod_waves=(F[n_p:].copy(), G[n_p:].copy()),
        bit_velocity=bit.w, rock_stored_energy=_rock_stored(float(bitf[-1]), bit.k_u),
        uncertainty=uncertainty, bit_energy=0.5 * bit_mass * bit.w * bit.w)


def _still_possible(rod_waves, piston_e, R, bit, feed) -> float:
    """The rock work a lattice blow stopped at its horizon could still take (theory §4d, as the
    exact blow's bound): the energy ``Psi`` of rod, bit and rock above the static state under the
    feed (``R`` the rock's force at the end) and the piston's, times what each unit of it can buy
    under the feed (:func:`~._bit.feed_gain`)."""
    kinetic = 0.5 * bit.m * bit.w * bit.w
    rock = 0.0 if math.isinf(bit.k_u) else 1.0 / (2.0 * bit.k_u)
    if bit.branch == _FREE:
        psi = rod_waves + kinetic + feed * (bit.p_perm - bit.p) + feed * feed * rock
    else:
        psi = rod_waves + kinetic + (R - feed) * (R - feed) * rock
    return max(psi + piston_e, 0.0) * feed_gain(bit.R_max, feed)


def _start_bit(Z, k, k_u, bit_mass, feed, bit_state) -> _Bit:
    """The bit at the blow's start (:func:`solve_blow`'s ``bit_state``)."""
    bit = _Bit(float(Z[-1]), k, k_u, bit_mass, feed)
    if bit_state is not None:
        p, w = bit_state
        bit.p, bit.w = float(p), float(w)
        if bit.p < 0.0:
            bit.branch, bit.p_max, bit.R_max, bit.p_perm = _FREE, 0.0, 0.0, 0.0
        else:
            bit.p_max, bit.R_max = bit.p, k * bit.p
            bit.p_perm = bit.p_max - bit.R_max / k_u
    return bit


def _run(grid, F, G, drive, bit, n_max, stop, separation_time, gap, record_field, end_fraction=1.0):
    """The blow's loop (compiled, or numpy's under ``use_reference("rock.blow")``) over at most
    ``n_max`` steps from the waves ``F, G`` (copied), the bit ``bit`` updated in place; the bit's
    largest and permanent penetrations taken at the end if it was still advancing. Returns the
    loop's ``(F, G, junctions, bit forces, penetrations, field, accounts)``."""
    from ...dynamics.implementations import use_fast

    dt = grid.cell_time
    drive = np.zeros(n_max) if drive is None else np.ascontiguousarray(drive[:n_max], dtype=float)
    if drive.size < n_max:
        raise ValueError(f"drive must have at least {n_max} steps; got {drive.size}")
    quiet = 0 if separation_time is None else max(1, math.ceil(separation_time / dt))
    if grid.slots:
        out = _slots_loop(grid, F, G, bit, n_max, stop, quiet, float(gap), drive, record_field, end_fraction)
    else:
        loop = _compiled_loop if use_fast("rock.blow") else _python_loop
        out = loop(F, G, grid.Z, grid.bounds, bit, dt, n_max, stop, quiet, float(gap), drive, record_field,
                   grid.locate)
    if bit.branch == _LOAD and bit.p > bit.p_max:
        # the window ended while the bit still advanced into the rock: its largest penetration is the
        # last, and what would stay of it the unloading line from there (not those of the last
        # unloading, 0 on a first loading)
        bit.p_max, bit.R_max = bit.p, bit.k * bit.p
        bit.p_perm = bit.p_max - bit.R_max / bit.k_u
    return out


def blow_end(grid: BlowGrid, F, G, drive, k, k_u, bit_mass, feed, n_steps: int):
    """What the next flight needs of a blow of exactly ``n_steps`` steps (the simulator's impact map,
    :class:`~impactbar.laws.rodrock.contact.BlowMap`), by the same loop as :func:`solve_blow` and
    without its record: the piston's final waves ``(F, G)`` (shape ``(piston cells,)`` each), the
    piston-shank gap, the shank's displacement and the bit's permanent penetration, the same numbers
    as the :class:`Blow` of ``solve_blow(..., n_steps=n_steps)``."""
    n_p = grid.piston_cells
    bit = _start_bit(grid.Z, k, k_u, bit_mass, feed, None)
    F, G, *_, (u_shank, _, _, gap, *_) = _run(grid, np.array(F, dtype=float), np.array(G, dtype=float), drive,
                                             bit, max(1, int(n_steps)), -1.0, None, 0.0, False)
    return F[:n_p], G[:n_p], gap, u_shank, bit.p_perm


def _rock_stored(R, k_u) -> float:
    """The rock's elastic energy ``R^2/(2 k_u)`` under the rock force ``R`` (0 off the rock or with
    a rigid unloading)."""
    return 0.0 if R <= 0.0 or math.isinf(k_u) else R * R / (2.0 * k_u)


def _compiled_loop(F, G, Z, bounds, bit, dt, n_max, stop, quiet, gap0, drive, record_field, locate=False):
    """The blow's loop compiled (:func:`impactbar.laws.rodrock._rockloop.blow_loop`)."""
    from ._rockloop import blow_loop

    F, G = F.copy(), G.copy()
    bs, bp = _bit_records(bit)
    junc = np.zeros((n_max, bounds.size))
    bitrec = np.zeros((n_max + 1, 2))
    field = np.zeros((n_max if record_field else 0, F.size))
    acc = np.zeros(S.ACC_SIZE)
    ctrl = _loop_controls(dt, stop, quiet, gap0, locate=locate)
    blow_loop(F, G, Z, bounds.astype(np.int64), bs, bp, ctrl, drive, junc, bitrec, field, acc)
    _set_bit(bit, bs)
    n = int(acc[S.ACC_STEPS])
    ended = ("t_max", "energy", "separated")[int(acc[S.ACC_ENDED])]
    return (F, G, junc[:n], bitrec[:n + 1, BITREC_FORCE], bitrec[:n + 1, BITREC_PEN], field[:n],
            (float(acc[S.ACC_USHANK]), float(acc[S.ACC_LOSS]), ended, float(acc[S.ACC_GAP]),
             float(acc[S.ACC_WORK])))


def _slots_loop(grid, F, G, bit, n_max, stop, quiet, gap0, drive, record_field, end_fraction=1.0):
    """The blow's loop on the slot lattice (:class:`~impactbar.laws.rodrock._rockslots.SlotLattice`,
    ``grid.slots``): the results of :func:`_compiled_loop`, the waves the cells' averages, and after
    its accounts the slots' energies in the piston and the rod and the delays' (``SlotLattice.energies``);
    the last step run to ``end_fraction`` of it."""
    from ._rockslots import SlotLattice

    bs, bp = _bit_records(bit)
    lat = SlotLattice(grid.Z, grid.bounds, grid.delays, F, G, gap0, bs, bp)
    out = lat.run(grid.cell_time, drive[:n_max], stop=stop, quiet=quiet, frac=end_fraction,
                  record_field=record_field)
    _set_bit(bit, lat.bs)
    u_shank, grid_loss, gap, work = lat.totals()
    ended = ("t_max", "energy", "separated")[lat.ended]
    return (out["F"], out["G"], out["junc"], out["bitf"], out["pen"], out["field"],
            (u_shank, grid_loss, ended, gap, work, *lat.energies()))


def _set_bit(bit, bs):
    """The bit ``bit`` set from the compiled loop's state ``bs``."""
    bit.p, bit.w, bit.branch = bs[S.BIT_P], bs[S.BIT_W], int(bs[S.BIT_BRANCH])
    bit.p_max, bit.R_max = bs[S.BIT_PMAX], bs[S.BIT_RMAX]
    bit.p_perm, bit.work = bs[S.BIT_PPERM], bs[S.BIT_WORK]


def _bit_records(bit):
    """The compiled loop's records of the bit ``bit``: its state ``bs`` and parameters ``bp``
    (their slots ``BIT_*``, ``BITP_*`` of :mod:`impactbar.laws.rodrock._records`)."""
    bs = np.empty(S.BIT_SIZE)
    bs[S.BIT_P], bs[S.BIT_W], bs[S.BIT_BRANCH] = bit.p, bit.w, float(bit.branch)
    bs[S.BIT_PMAX], bs[S.BIT_RMAX] = bit.p_max, bit.R_max
    bs[S.BIT_PPERM], bs[S.BIT_WORK] = bit.p_perm, bit.work
    return bs, _bit_params(bit.Z, bit.k, bit.k_u, bit.m, bit.f)


def _bit_params(Z, k, k_u, m, feed):
    """The compiled loop's bit parameters ``bp`` (slots ``BITP_*``): the impedance ``Z`` at the bit,
    the rock's stiffnesses ``k``, ``k_u``, the bit's mass ``m`` and the feed force."""
    bp = np.empty(S.BITP_SIZE)
    bp[S.BITP_Z], bp[S.BITP_K], bp[S.BITP_KU], bp[S.BITP_MASS], bp[S.BITP_FEED] = Z, k, k_u, m, feed
    return bp


def _loop_controls(dt, stop, quiet, gap, free=False, locate=False, switch=(0.0, 0.0, 0.0)):
    """The compiled loop's controls ``ctrl`` (slots ``CTRL_*``): its step ``dt``, the energy ``stop``
    that ends a separated blow, the separated steps ``quiet`` that end it (0: none), the piston-shank
    ``gap`` at the start, ``free``: end where the piston is free for good (under a drive),
    ``locate``: the contact's switches inside their steps (``BlowGrid.locate``), and ``switch``:
    whether the waves arriving at the contact on the step before are held, and they (``F``, ``G``;
    a blow run on)."""
    ctrl = np.empty(S.CTRL_SIZE)
    ctrl[S.CTRL_DT], ctrl[S.CTRL_STOP], ctrl[S.CTRL_QUIET], ctrl[S.CTRL_GAP] = dt, stop, float(quiet), gap
    ctrl[S.CTRL_FREE] = 1.0 if free else 0.0
    ctrl[S.CTRL_LOCATE] = 1.0 if locate else 0.0
    ctrl[S.CTRL_HELD], ctrl[S.CTRL_FA], ctrl[S.CTRL_GA] = switch
    return ctrl
