"""The result of a simulation under a drive (theory §10): :class:`DrivenTrajectory`, the run's
pieces (flights, rests, blows) with the drive's state and switches, and its energy account with the
drive's work. The run that builds it is :mod:`impactbar.simulation.driven`."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..drives.base import DriveState
from .blows import BlowPiece
from .trajectory import EnergyAccount, Trajectory

__all__ = ["DrivenTrajectory"]


@dataclass(frozen=True, eq=False, kw_only=True)
class DrivenTrajectory(Trajectory):
    """The result of :func:`impactbar.simulate` under a drive (a :class:`~impactbar.Drive`, theory
    §10): a :class:`~impactbar.Trajectory` whose ``load`` is the drive, with the drive's switches
    logged and the run kept as its flights.

    Attributes
    ----------
    model : BarModel
    load : Drive
        The drive (also :attr:`drive`).
    t0, t_end : float
        Start and end of the run.
    impact_times, impact_velocities : numpy.ndarray, shape (I,)
        Impacts and the struck end's velocity just before each, as in
        :class:`~impactbar.Trajectory`.
    contact_intervals : numpy.ndarray, shape (m, 2)
        The intervals of sustained contact of the flights (the bar held on the stop).
    switch_times : numpy.ndarray, shape (S,)
        Times at which the drive's mode changed (a switch took effect).
    switch_positions : numpy.ndarray, shape (S,)
        The gap ``y = -q_0`` there.
    switch_kinds : tuple of str, length S
        The name of the mode switched to (:meth:`~impactbar.Drive.mode_name`; the valve's
        ``"stroke"`` or ``"return"``).
    final_state : InitialState
        Modal state at ``t_end``.
    final_mode : str
        The name of the drive's mode at ``t_end`` (also :attr:`final_valve`).
    final_drive_state : numpy.ndarray, shape (k,)
        The drive's continuous state at ``t_end`` (empty for a drive without state).
    status : RunStatus
        Why the run stopped.
    pieces : sequence
        The flights, in order: each has ``t0``, ``t_end``, ``end_displacement(t)``,
        ``end_velocity(t)`` and ``modal(t)`` (a run of the ordinary driver, a
        :class:`~impactbar.Trajectory`, where the flight has a contact; else a closed-form flight or,
        for a drive with state, ``solve_ivp``'s dense output); ``pieces.starts`` holds their ``t0``.

    Examples
    --------
    >>> from impactbar import BarModel, InitialState, PositionSwitchedDrive, simulate, Trajectory
    >>> drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    >>> run = simulate(BarModel(s=10.0, d=0.05, R=0.5, n_modes=0), drive,
    ...                InitialState.rigid(-0.5, 0.0), 60.0)
    >>> type(run).__name__, isinstance(run, Trajectory), run.n_impacts > 5
    ('DrivenTrajectory', True, True)
    """

    switch_times: np.ndarray
    switch_positions: np.ndarray
    switch_kinds: tuple
    final_mode: str
    pieces: Sequence = field(repr=False)
    final_drive_state: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    _final_drive: DriveState | None = field(default=None, repr=False)

    def __repr__(self) -> str:
        """One line: model, drive, time span, impacts, switches, status (not the arrays)."""
        return (f"DrivenTrajectory({self.model!r}, {self.load!r}, t {self.t0:.6g} -> {self.t_end:.6g}, "
                f"{self.impact_times.size} impacts, {len(self.switch_kinds)} switches, "
                f"status {str(self.status)!r})")

    @property
    def drive(self):
        """The drive (the trajectory's ``load``)."""
        return self.load

    @property
    def final_valve(self) -> str:
        """The valve's state at ``t_end`` (:attr:`final_mode`)."""
        return self.final_mode

    @property
    def in_contact_at_end(self) -> bool:
        last = self.pieces[-1] if len(self.pieces) else None
        return bool(getattr(last, "in_contact_at_end", False))

    def end_displacement(self, t) -> np.ndarray:
        """``u(1, t)`` at times in ``[t0, t_end]``, shape ``(T,)``."""
        return self._each(t, "end_displacement")

    def end_velocity(self, t) -> np.ndarray:
        """``u_t(1, t)`` at times in ``[t0, t_end]``, shape ``(T,)``."""
        return self._each(t, "end_velocity")

    def _times(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if np.any(t < self.t0) or np.any(t > self.t_end) or not np.all(np.isfinite(t)):
            raise ValueError(f"t must lie in [t0, t_end] = [{self.t0}, {self.t_end}]")
        starts = self.pieces.starts
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)
        return t, idx

    def _each(self, t, name):
        t, idx = self._times(t)
        out = np.empty_like(t)
        for j in np.unique(idx):
            sel = idx == j
            piece = self.pieces[j]
            out[sel] = getattr(piece, name)(np.minimum(t[sel], piece.t_end))
        return out

    def modal_state(self, t):
        """Free-free modal state ``(q, v)`` at times ``t`` in ``[t0, t_end]``, shape ``(N + 1, T)``
        each."""
        t, idx = self._times(t)
        M = self.model.n_modes + 1
        Q, V = np.zeros((M, t.size)), np.zeros((M, t.size))
        for j in np.unique(idx):
            sel = idx == j
            piece = self.pieces[j]
            tt = np.minimum(t[sel], piece.t_end)
            Q[:, sel], V[:, sel] = piece.modal_state(tt) if isinstance(piece, Trajectory) else piece.modal(tt)
        return Q, V

    def displacement(self, x, t) -> np.ndarray:
        """``u(x, t)`` on a grid, shape ``(T, X)`` (``x`` in ``[0, 1]``, ``t`` in ``[t0, t_end]``)."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        q, _ = self.modal_state(t)
        return (self.model.shape_functions(x) @ q).T

    def drive_state(self, t) -> np.ndarray:
        """The drive's continuous state ``z`` at times ``t`` in ``[t0, t_end]``, shape ``(k, T)``
        (the chamber pressures of an oil circuit; ``(0, T)`` for a drive without state)."""
        t, idx = self._times(t)
        k = self.final_drive_state.size
        out = np.zeros((k, t.size))
        if not k:
            return out
        for j in np.unique(idx):
            sel = idx == j
            piece = self.pieces[j]
            out[:, sel] = piece.drive_state(np.minimum(t[sel], piece.t_end))
        return out

    @property
    def impacts(self) -> tuple:
        """The record of each impact, in order, one per :attr:`impact_times` (the law's per-blow
        output, :attr:`impactbar.Trajectory.impacts`): the driver's runs give theirs; a closed-form or
        integrated flight that ends at an impact, the law's contact of its arrival under the force
        there (:meth:`impactbar.laws.ContactLaw.contact`), built on access."""
        from ..loads import FourierLoad

        model, law = self.model, self.model.law
        hits = set(self.impact_times.tolist())
        blows = {float(p.t0) for p in self.pieces if isinstance(p, BlowPiece)}
        out = []
        for j in range(len(self.pieces)):
            piece = self.pieces[j]
            if isinstance(piece, Trajectory):
                out.extend(piece.impacts)
            elif isinstance(piece, BlowPiece):
                out.append(piece.record)
            elif piece.t_end in blows:  # a flight ending at a blow solved with the drive (its record)
                continue
            elif piece.t_end in hits and piece.t_end > piece.t0:
                q, v = piece.modal([piece.t_end])
                p = float(piece.force([piece.t_end])[0])
                _, _, _, record = law.contact(model, FourierLoad(p, []), piece.t_end, q[:, 0], v[:, 0])
                out.append(record)
        return tuple(out)

    @cached_property
    def energy(self) -> EnergyAccount:
        """The bar's energy account of the run (:class:`~impactbar.EnergyAccount`): the flights that
        are runs of the ordinary driver give their own accounts; on the others the drive's work
        ``int p u_t(0, t) dt`` and the damping loss by Gauss-Legendre quadrature (16 nodes on steps of
        at most ``1.5 / (w_max + 1)``), and the energy lost between one flight's end and the next one's
        start (the impacts, eq. 10) counted as impact loss. The drive's own energy (an oil circuit's)
        is not in it."""
        return _drive_energy(self)


_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)


def _drive_energy(tr: DrivenTrajectory) -> EnergyAccount:
    """:attr:`DrivenTrajectory.energy`."""
    model = tr.model
    kappa = model.drive_weights  # (1, 2, .., 2): u_t(0) = kappa . q'
    w2 = model.frequencies**2
    d = model.d
    hmax = 1.5 / (math.sqrt(float(np.max(w2))) + 1.0)

    def energy(q, v):
        return float(0.5 * np.sum(kappa * v * v) + 0.5 * np.sum(kappa * w2 * q * q))

    work = damp = imp = chat = proj = 0.0
    initial = final = None
    for j in range(len(tr.pieces)):
        piece = tr.pieces[j]
        if isinstance(piece, Trajectory):
            acc = piece.energy
            work, damp, imp = work + acc.work, damp + acc.damping_loss, imp + acc.impact_loss
            chat, proj = chat + acc.chatter_loss, proj + acc.projection
            start, end = acc.initial, acc.final
        elif isinstance(piece, BlowPiece):  # a blow with the drive's state: the law's account
            w_drive, w_law, out, field_energy, q1, v1 = piece.account()
            q0, v0 = piece.arrival
            start, end = energy(q0, v0), energy(q1, v1)
            work += w_drive
            imp += out + (w_drive - w_law)  # the blow's grid drops what its force averages miss
            proj += end - field_energy + piece.record.energy_before - start
        else:
            a, b = float(piece.t0), float(piece.t_end)
            if b > a:
                edges = np.linspace(a, b, max(1, math.ceil((b - a) / hmax)) + 1)
                half = 0.5 * np.diff(edges)
                nodes = (half[:, None] * (_GL_X[None, :] + 1.0) + edges[:-1, None]).ravel()
                weights = (half[:, None] * _GL_W[None, :]).ravel()
                _, v = piece.modal(nodes)
                if hasattr(piece, "piston_work"):  # the drive's own quadrature along its integration
                    work += piece.piston_work()
                else:
                    work += float(np.sum(weights * piece.force(nodes) * (kappa @ v)))
                damp += d * float(np.sum(weights * (kappa @ (v * v))))
            (q0, v0), (q1, v1) = piece.modal([a]), piece.modal([b])
            start, end = energy(q0[:, 0], v0[:, 0]), energy(q1[:, 0], v1[:, 0])
        if initial is None:
            initial = start
        else:
            imp += final - start  # the impact between two flights (eq. 10)
        final = end
    last = energy(tr.final_state.modal_displacement, tr.final_state.modal_velocity)
    if initial is None:
        initial = final = last
    elif not isinstance(tr.pieces[len(tr.pieces) - 1], Trajectory):  # a run ending at an impact
        imp += final - last
        final = last
    return EnergyAccount(work=work, initial=initial, final=final, damping_loss=damp, impact_loss=imp,
                         chatter_loss=chat, projection=proj)

