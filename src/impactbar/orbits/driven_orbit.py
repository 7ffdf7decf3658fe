"""The result of :func:`impactbar.find_orbit` under a drive: :class:`DrivenOrbit`, a
:class:`~impactbar.PeriodicOrbit` with the drive's state, the flights and their multipliers
(theory §10, §11); :mod:`impactbar.orbits.driven` finds it."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..laws.abilities import BlowRecords
from .orbit import PeriodicOrbit

if TYPE_CHECKING:
    pass

__all__ = ["DrivenOrbit"]


def _constant_load(p: float):
    """The load of the constant force ``p`` (a one-piece :class:`~impactbar.FourierLoad`)."""
    from ..loads import FourierLoad

    return FourierLoad(p, [])


class _LazyContacts:
    """``DrivenOrbit.contacts``: set by the constructor (``None``: not computed yet), computed on
    first access from the arrivals (the law's :meth:`~impactbar.laws.abilities.BlowRecords.blow` under the
    force the drive holds during each contact)."""

    def __get__(self, obj, owner=None):
        if obj is None:
            return None
        value = obj.__dict__.get("_contacts")
        if value is None:
            value = obj.__dict__["_contacts"] = obj._blows()
        return value

    def __set__(self, obj, value):
        obj.__dict__["_contacts"] = value


@dataclass(frozen=True, eq=False, kw_only=True)
class DrivenOrbit(PeriodicOrbit):
    """A periodic motion with ``m`` impacts per period under a drive (a :class:`~impactbar.Drive`,
    theory §10): a :class:`~impactbar.PeriodicOrbit` whose ``load`` is the drive, whose period is an
    output and whose ``periods`` is 1.

    Orbit time ``t`` runs from :attr:`state`, just after the period's first impact (where its contact
    ends, under a law whose contact takes time). Impact ``k`` ends the ``k``-th interval: it happens
    at ``impact_times[k]`` (the last at ``period``, the first impact again), arriving at
    ``impact_velocities[k]`` from ``states_before_impact[k]``; ``states_after_impact[k]`` is the
    state just after it (``states`` lists the states where the intervals start, ``states[0]`` is
    ``state``).

    Attributes
    ----------
    model : BarModel
    load : Drive
        The drive (also :attr:`drive`).
    impacts : int
        ``m``.
    periods : int
        1.
    period : float
        Period ``T`` (the model's time unit, eq. 2).
    durations : numpy.ndarray
        The flights between consecutive events of the period (the drive's switches and the
        impacts), in order from :attr:`state`; for the valve four per impact: stroke ``tau``,
        return ``h1`` (to the switch crossing), return ``tau``, stroke ``h3`` (to the impact).
    impact_times : numpy.ndarray, shape (m,)
        Orbit times of the impacts (arrivals), increasing, the last equal to ``period`` less the last
        contact's duration.
    phases : numpy.ndarray, shape (m,)
        ``2 pi`` times the fraction of the period at each impact (rad, the last 0).
    impact_velocities : numpy.ndarray, shape (m,)
        ``u_t(1, t-)`` at each impact (``impact_velocity`` is the first's).
    multipliers : numpy.ndarray, shape (2 N + 1 + k,)
        Non-trivial Floquet multipliers (those of the Poincare map), largest modulus first.
    trivial_multiplier : float
        The multiplier along the flow, ``1`` in exact arithmetic (its distance from 1 measures the
        rounding of the monodromy matrix; exactly 1 where the multipliers are those of the return
        map on the arrival surface).
    admissibility : Admissibility
        Whether the motion is physical (theory §5 and §10).
    admissible, stable : bool
        ``admissibility`` is admissible; and every non-trivial multiplier inside the unit circle.
    switch_times : numpy.ndarray
        Times after :attr:`state` at which the drive switched (for the valve: to return, then to
        stroke, for each impact in turn).
    switch_velocity : float
        The gap's rate ``y' = -q_0'`` where it crosses a switch position (the smallest over the
        period's crossings): 0 where the orbit grazes the switching surface (theory §10); ``nan``
        for a drive without position crossings.
    contact_time : float
        Under a law whose contact takes time, the contact's duration (``ContactLaw.window``, or the
        blow's where it ends by its own test: the rod-rock law's under a drive with state, where
        the piston is free for good, theory §11; the longest of the period's): ``state`` and
        ``states`` are then where each contact ends. 0 under the paper's law.
    drive_states : numpy.ndarray, shape (m, k)
        The drive's continuous state where each interval starts (empty for a drive without state).
    contacts : tuple
        The record of each impact's contact under a law whose contact takes time, in order
        (:meth:`~impactbar.laws.abilities.BlowRecords.blow` of each arrival under the force the drive holds: a
        :class:`~impactbar.WaveImpact` under the wave law; under the rod-rock law a record with the
        blow's ``work_on_rock``, ``permanent_penetration``, ``efficiency``, ... of
        :class:`~impactbar.Blow`); empty under the paper's law. Computed on first access.
    clearance, clearance_error : float
        ``nan`` (admissibility is decided on the flights themselves).

    Examples
    --------
    >>> from impactbar import BarModel, PeriodicOrbit, PositionSwitchedDrive, find_orbit
    >>> drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    >>> orbit = find_orbit(BarModel(s=10.0, d=0.05, R=0.5, n_modes=0), drive)
    >>> round(orbit.period, 6), round(orbit.blow_frequency * orbit.period, 12)  # found, not given
    (4.607776, 1.0)
    >>> isinstance(orbit, PeriodicOrbit), orbit.drive is orbit.load
    (True, True)
    """

    period: float = math.nan
    durations: np.ndarray = field(default=None, repr=False)
    trivial_multiplier: float = math.nan
    switch_times: np.ndarray = field(default=None, repr=False)
    switch_velocity: float = math.nan
    contact_time: float = 0.0
    drive_states: np.ndarray = field(default=None, repr=False)
    contact_forces: np.ndarray = field(default=None, repr=False)
    _monodromy: np.ndarray = field(default=None, repr=False)
    _problem: object = field(default=None, repr=False)
    _unknowns: np.ndarray = field(default=None, repr=False)

    contacts = _LazyContacts()

    @property
    def drive(self):
        """The drive (the orbit's ``load``)."""
        return self.load

    @property
    def problem(self):
        """The :class:`~impactbar.drives.OrbitProblem` this orbit solves (continuation starts from
        it)."""
        return self._problem

    @property
    def state(self) -> np.ndarray:
        """The modal state ``(q_0..q_N, q_0'..q_N')`` just after the period's first impact (where its
        contact ends), shape ``(2 N + 2,)``."""
        return self.states[0]

    @property
    def states(self) -> np.ndarray:
        """``(m, 2 N + 2)``: the modal state where each interval starts (after the impact before
        it); ``states[0]`` is :attr:`state`."""
        after = self.states_after_impact
        return np.roll(after, 1, axis=0) if len(after) > 1 else after

    @property
    def impact_velocity(self) -> float:
        """``u_t(1, t-)`` at the first impact, the one that ends the first interval from
        :attr:`state` (for ``m = 1`` the one that :attr:`state` follows)."""
        return float(self.impact_velocities[0])

    @property
    def blow_frequency(self) -> float:
        """Blows per unit of the model's time, ``m / T`` (``m`` impacts per period); with the time
        scale ``t = Omega t_SI`` (eq. 2) the blow frequency in Hz is ``Omega m / T``."""
        return self.impacts / self.period

    @property
    def impact_energy(self) -> float:
        """Kinetic energy of the bar arriving at the stop, ``(1/2) int_0^1 u_t^2 dx`` (units of
        ``m L^2 Omega^2``, eq. 2), the mean over the ``m`` impacts of the period (so that the
        percussive power is ``impact_energy * blow_frequency``)."""
        M = self.model.n_modes + 1
        total = 0.0
        for zd in self.states_before_impact:
            v = zd[M:]
            total += 0.5 * (v[0] ** 2 + 2.0 * float(np.sum(v[1:] ** 2)))
        return total / self.impacts

    def _blows(self) -> tuple:
        blows = self.model.law.ability(BlowRecords)
        if blows is None:
            return ()
        records = getattr(self._problem, "blow_records", None)
        coupled = records(self._unknowns) if records is not None else None
        if coupled is not None:  # blows solved with the drive's state: their own records
            return tuple(coupled)
        return tuple(blows.blow(self.model, _constant_load(float(p)), 0.0, zd)
                     for p, zd in zip(self.contact_forces, self.states_before_impact, strict=True))

    def _state_in_period(self, t):
        """The modal state at orbit times ``0 <= t <= period`` from :attr:`state`: the flights of
        the period again (:meth:`OrbitProblem.pieces`); inside a contact the law's record where it
        has one (``state_at``), else ``nan``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        M = self.model.n_modes + 1
        q = np.full((M, t.size), np.nan)
        v = np.full((M, t.size), np.nan)
        for t0, t1, piece in self._problem.pieces(self._unknowns):
            sel = (t >= t0) & (t <= t1)
            if np.any(sel):
                q[:, sel], v[:, sel] = piece(t[sel])
        if self.contact_time:  # inside the contacts' windows: the law's records
            for ti, rec in zip(self.impact_times, self.contacts, strict=True):
                for i in np.flatnonzero((t >= ti) & (t <= ti + self.contact_time) & np.isnan(q[0])):
                    if hasattr(rec, "state_at"):
                        q[:, i], v[:, i] = rec.state_at(min(t[i] - ti, self.contact_time))
        return q, v

    def modal_state(self, t):
        """Modal displacements and velocities at orbit times ``t`` (from :attr:`state`, taken
        modulo the period), shape ``(N + 1, T)`` each."""
        t = np.atleast_1d(np.asarray(t, dtype=float)).ravel()
        return self._state_in_period(np.mod(t, self.period))

    def to_dict(self) -> dict:
        """A JSON-ready summary: :meth:`PeriodicOrbit.to_dict` with the ``period``, the
        ``blow_frequency``, the ``impact_energy``, the ``switch_times`` and the
        ``trivial_multiplier``."""
        out = super().to_dict()
        out.update(period=self.period, blow_frequency=self.blow_frequency, impact_energy=self.impact_energy,
                   switch_times=np.asarray(self.switch_times).tolist(),
                   trivial_multiplier=self.trivial_multiplier)
        return out

    def _attrs(self) -> dict:
        out = super()._attrs()
        out.update(period=self.period, drive=repr(self.load))
        return out
