"""A drive with state under a law whose contact takes time (theory §11, "The coupled blow"): each
arrival a blow solved together with the drive's state
(:meth:`~impactbar.laws.abilities.CoupledBlow.driven_contact`), the run's piece over it a :class:`BlowPiece`;
the checks that refuse what the coupled blow cannot do, and the run's loop
(:func:`run_coupled`, which :func:`impactbar.simulation.driven.run_stateful` calls)."""

from __future__ import annotations

import numpy as np

from .._shared.status import RunStatus
from ..drives.base import DriveState
from ..drives.flight import END, EVENT, ModalEnd, fly
from ..laws.abilities import CoupledBlow, require

__all__ = ["BlowPiece", "BlowSummary", "check_coupling", "check_blow_switches", "driven_blow", "run_coupled",
           "PRESSED_BLOWS"]


class BlowPiece(ModalEnd):
    """A blow of a run under a drive with state and a law whose contact takes time (theory §11, "The
    coupled blow"): the law's record of the blow (solved with the drive's force as it evolved) and
    the drive's pieces over it; a piece of :attr:`DrivenTrajectory.pieces` like the flights.

    Attributes
    ----------
    t0, t_end : float
        The arrival and the blow's end (or the run's end, where the run ends inside the blow).
    record : object
        The law's record (:class:`~impactbar.WaveImpact`,
        :class:`~impactbar.laws.rodrock.contact.RockContact`).
    arrival : tuple of numpy.ndarray
        The modal state ``(q, q')`` at the arrival.
    drive_pieces : list
        The drive's pieces over the blow (histories, energy quadratures).
    t : numpy.ndarray
        The drive's integration steps over the blow (up to :attr:`t_end`).
    """

    __slots__ = ("t0", "t_end", "record", "arrival", "drive_pieces", "t", "c", "_starts", "_end_state")

    def __init__(self, t0, t_end, record, arrival, drive_pieces, c, end_state=None):
        self.t0, self.t_end, self.record, self.arrival = float(t0), float(t_end), record, arrival
        self.drive_pieces, self.c = drive_pieces, c
        steps = np.unique(np.concatenate([p.t for p in drive_pieces]))
        self.t = steps[steps <= self.t_end]
        self._starts = np.array([p.t0 for p in drive_pieces])
        self._end_state = end_state  # (q, v) where the piece ends; the record's after the whole blow

    def _pick(self, t):
        return np.clip(np.searchsorted(self._starts, t, side="right") - 1, 0, len(self.drive_pieces) - 1)

    def drive_state(self, t):
        """The drive's continuous state at times ``t`` in the blow, shape ``(k, T)``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        idx = self._pick(t)
        out = None
        for j in np.unique(idx):
            sel = idx == j
            z = self.drive_pieces[j].drive_state(t[sel])
            if out is None:
                out = np.empty((z.shape[0], t.size))
            out[:, sel] = z
        return out

    def force(self, t):
        """The drive's force on the piston at times ``t`` in the blow."""
        return self._scalar("force", t)

    def displacement(self, t):
        """The driven end's displacement ``w = -u(0, t)`` at times ``t`` in the blow as the drive
        integrated it (from the stop where it was at the arrival: the chambers' volumes follow it),
        shape ``(T,)``."""
        return self._scalar("displacement", t)

    def _scalar(self, name, t):
        """A scalar history of the drive pieces (their method ``name``) at times ``t``, each time
        from the piece that holds it."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        idx = self._pick(t)
        out = np.empty(t.size)
        for j in np.unique(idx):
            sel = idx == j
            out[sel] = getattr(self.drive_pieces[j], name)(t[sel])
        return out

    def energies(self):
        """The drive's energy quadratures over the piece (:meth:`HydraulicCircuitDrive.energy`
        sums them): to :attr:`t_end`."""
        return self._to_end("energies", "energies_at")

    def piston_work(self) -> float:
        """The drive's work on the piston over the piece to :attr:`t_end`, its pieces' ``piston_work``
        (the drive's ``Quadratures.piston_work``).

        Returns
        -------
        float
            In model energy units.
        """
        return float(self._to_end("piston_work", "piston_work_at"))

    def _to_end(self, whole, cut):
        """The sum over the drive pieces to :attr:`t_end` of their method ``whole`` (over a piece)
        or, for the piece that :attr:`t_end` cuts, ``cut`` (to a time)."""
        total = 0.0
        for p in self.drive_pieces:
            if p.t_end <= self.t_end:
                total = total + getattr(p, whole)()
            elif p.t0 < self.t_end:
                total = total + getattr(p, cut)(self.t_end)
        return total

    def extremes(self, k: int | str) -> tuple[float, float]:
        """The least and the greatest value of the drive's state component ``k`` (an index or a name of
        its layout) over the blow (its pieces' :meth:`extremes`)."""
        (lo,), (hi,) = self.extremes_of([k])
        return float(lo), float(hi)

    def extremes_of(self, ks) -> tuple[np.ndarray, np.ndarray]:
        """The least and the greatest value of each of the drive's state components ``ks`` over the
        blow: its pieces' :meth:`extremes`, the same numbers, taken together where the pieces can
        (``extremes_over``: a circuit's pieces solve their interpolants' cubics only where these can
        pass the blow's least or greatest sample; theory §11, *Limits of this version*).

        Parameters
        ----------
        ks : list of int or str
            The components (indices or names of the drive's layout).

        Returns
        -------
        lows, highs : numpy.ndarray, shape (len(ks),)
            In model units.
        """
        parts = self.drive_pieces
        if parts and all(hasattr(p, "extremes_over") for p in parts):
            return next(iter(parts)).extremes_over(parts, ks)
        ext = [[p.extremes(k) for p in parts] for k in ks]
        return (np.array([min(lo for lo, _ in e) for e in ext], float),
                np.array([max(hi for _, hi in e) for e in ext], float))

    def supply_extremes(self) -> tuple[float, float]:
        """The least and the greatest supply pressure over the blow (an oil circuit's)."""
        return self.extremes("supply")

    def account(self):
        """``(drive work, the law's drive work, energy out, field energy, q, v)`` to :attr:`t_end`:
        the drive's work on the piston along its integration, the law's record's balance
        (``energy_before + law's work = field + out``) and the modal state there."""
        tau = min(self.t_end - self.t0, self.record.duration)
        w_law, out, field_energy = self.record.account(tau)
        w_drive = self.piston_work()
        q, v = self.modal_end()
        return w_drive, w_law, out, field_energy, q, v

    def modal_end(self):
        """The modal state where the piece ends."""
        if self._end_state is not None:
            return self._end_state
        return self.record.state_at(min(self.t_end - self.t0, self.record.duration))

    def modal(self, t):
        """The piston's modal state at times ``t`` in the blow (the law's record, ``state_at``),
        shape ``(N + 1, T)`` each."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        q_arrival, _ = self.arrival
        M = q_arrival.size
        Q, V = np.empty((M, t.size)), np.empty((M, t.size))
        for i, tt in enumerate(t):
            if tt >= self.t_end and self._end_state is not None:
                Q[:, i], V[:, i] = self._end_state
            elif tt <= self.t0:
                Q[:, i], V[:, i] = self.arrival
            else:
                Q[:, i], V[:, i] = self.record.state_at(min(tt - self.t0, self.record.duration))
        return Q, V


class BlowSummary(BlowPiece):
    """A blow of a run that keeps no histories (:func:`impactbar.simulate` with ``histories=False``):
    a :class:`BlowPiece` less the drive's pieces over it, which hold the integrator's steps and their
    interpolants (under the rod-rock law some hundred pieces a blow, about 1.5 MB: a chattering
    drifter's run of 16 s grew past 6.5 GB, every contact a blow). What a run reads of a blow after it
    ends stays: the law's record (the impact's figures, the account, the modal state), the drive's
    energy quadratures and its work on the piston to :attr:`t_end`, and the least and the greatest
    value of each of the drive's state components over the blow (the pieces' extremes, the same
    numbers: a circuit's least pressures). The histories inside the blow (:meth:`drive_state`,
    :meth:`force`, :meth:`displacement`) are refused. Source: theory §11, "The coupled blow".

    Parameters
    ----------
    piece : BlowPiece
        The blow, with its drive's pieces.

    Attributes
    ----------
    layout : object or None
        The drive pieces' layout (a circuit's :class:`~impactbar.drives.circuit.CircuitLayout`: the
        names :meth:`extremes` takes), ``None`` where they have none.
    """

    __slots__ = ("layout", "_lows", "_highs", "_energies", "_work")

    def __init__(self, piece: BlowPiece):
        self.t0, self.t_end, self.record, self.arrival = piece.t0, piece.t_end, piece.record, piece.arrival
        self.c, self._end_state = piece.c, piece._end_state
        parts = piece.drive_pieces
        self.layout = getattr(next(iter(parts), None), "layout", None)

        def every(name):
            return bool(parts) and all(hasattr(p, name) for p in parts)

        self._energies = piece.energies() if every("energies") and every("energies_at") else None
        self._work = piece.piston_work() if every("piston_work") and every("piston_work_at") else None
        self._lows = self._highs = None
        states = getattr(self.layout, "n_states", 0)
        if states and every("extremes"):
            self._lows, self._highs = piece.extremes_of(range(states))
        self.drive_pieces = ()

    def _refuse(self, what):
        raise ValueError(f"the blow at t = {self.t0:.6g} keeps no {what}: the run was made with "
                         "histories=False (simulate again with histories=True)")

    def drive_state(self, t):
        """Refused (class docstring).

        Raises
        ------
        ValueError
            Always."""
        self._refuse("history of the drive's state")

    def force(self, t):
        """Refused (class docstring).

        Raises
        ------
        ValueError
            Always."""
        self._refuse("history of the drive's force")

    def displacement(self, t):
        """Refused (class docstring).

        Raises
        ------
        ValueError
            Always."""
        self._refuse("history of the driven end")

    def energies(self):
        """The drive's energy quadratures over the blow to :attr:`t_end` (:meth:`BlowPiece.energies`).

        Raises
        ------
        ValueError
            Where the drive's pieces had none."""
        if self._energies is None:
            self._refuse("energy quadratures")
        e = self._energies
        return e.copy() if isinstance(e, np.ndarray) else e

    def piston_work(self) -> float:
        """The drive's work on the piston over the blow to :attr:`t_end` (:meth:`BlowPiece.piston_work`),
        in model energy units; a ``ValueError`` where the drive's pieces had none."""
        if self._work is None:
            self._refuse("work of the drive")
        return self._work

    def extremes_of(self, ks) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`BlowPiece.extremes_of` (its parameters and returns) as the blow kept them
        (:meth:`BlowPiece.extremes` reads them here too).

        Raises
        ------
        ValueError
            Where the drive's pieces had no extremes."""
        if self._lows is None:
            self._refuse("extremes of the drive's state")
        j = [self.layout[k] if isinstance(k, str) else int(k) for k in ks]
        return self._lows[j], self._highs[j]


#: more blows than this, each starting at once where the last ended (the piston pressed on the stop
#: through them), end the run with a ``ValueError``
PRESSED_BLOWS = 1000


def check_coupling(model, drive) -> None:
    """Refuse, in one line, a drive with state under a law whose contact takes time where the law
    has no coupled blow (:class:`~impactbar.laws.abilities.CoupledBlow`) or the drive cannot
    follow one (its ability ``end_flight``, :class:`~impactbar.drives.abilities.DriveAbilities`).

    Raises
    ------
    ValueError
        Naming what is missing."""
    if model.law.ability(CoupledBlow) is None:
        raise ValueError(f"a drive with state ({type(drive).__name__}) under impact={model.impact!r}: the "
                         "law has no blow solved with a drive's state (the ability CoupledBlow); use the "
                         "paper's, the wave or the rod-rock law")
    if drive.abilities.end_flight is None:
        raise ValueError(f"a drive with state ({type(drive).__name__}) runs under an instantaneous impact "
                         f"law only: it cannot follow a blow (no end_flight in its abilities); got "
                         f"impact={model.impact!r}")


def check_blow_switches(drive, modes, gaps) -> None:
    """Refuse a blow during which the piston's rigid coordinate crosses one of the drive's position
    switches armed in ``modes`` (the coupled blow does not switch inside it): ``gaps`` the times and
    the coordinate (:attr:`~impactbar.laws.base.DrivenContact.gaps`, shape ``(2, P)``).

    Raises
    ------
    ValueError
        Naming the switch and where."""
    from ..drives.base import GapCrossing

    times, coordinate = gaps
    y = np.asarray(coordinate, dtype=float)
    for mode in modes:
        for e in drive.events(mode):
            if not isinstance(e, GapCrossing):
                continue
            g = y - e.level
            crossed = (np.any((g[:-1] < 0.0) & (g[1:] >= 0.0)) if e.direction >= 0 else False) or \
                (np.any((g[:-1] > 0.0) & (g[1:] <= 0.0)) if e.direction <= 0 else False)
            if crossed:
                raise ValueError(f"the piston crosses the drive's switch position {e.name!r} ({e.level:g}) "
                                 f"inside a blow near t = {float(times[0]):.6g}: the coupled blow does not "
                                 "switch inside it; give a switch position farther from the stop or a "
                                 "shorter blow (blow_time)")


def driven_blow(model, drive, state, t, q, v, settings=None):
    """The blow of an arrival at ``t`` in ``(q, q')`` with the drive's ``state`` on arrival: the
    law's blow solved with the drive's state (:meth:`~impactbar.laws.abilities.CoupledBlow.driven_contact`),
    the position switches checked (:func:`check_blow_switches`), then the drive's map at the impact
    where the blow ends (as for the valve of :class:`~impactbar.PositionSwitchedDrive` under these
    laws: the switch the impact triggers counts from the contact's end).

    Returns
    -------
    DrivenContact, DriveState
        The blow (:class:`~impactbar.laws.base.DrivenContact`) and the drive's state after its map.

    Raises
    ------
    ValueError
        From the law's coupled blow, or a switch crossed inside it (:func:`check_blow_switches`)."""
    c = model.end_weights
    q = np.array(q, dtype=float)
    v = np.array(v, dtype=float)
    q[0] -= float(c @ q)  # the end exactly on the stop
    res = require(model.law, CoupledBlow, "driven_contact").driven_contact(model, drive, state, t, q, v,
                                                                            settings=settings)
    modes = [state.mode] + [m for _, _, m in res.events]
    check_blow_switches(drive, modes, res.gaps)
    end = res.drive_state
    after = drive.impact(end.mode, end.z, res.t_release, res.q_after, res.v_after)
    return res, after


def fly_and_switch(model, drive, loop, t_end: float, settings):
    """One flight of a drive's run from ``loop``'s state (:func:`impactbar.drives.flight.fly`): its
    piece logged, the run moved to its end, and at a drive event the drive's jumps applied and the
    switch logged (an arrival's too: the events found on its root, the oil circuit's levels, turn their
    flags before the impact); returns the flight (its ``end`` says how it ended)."""
    mode = loop.state.mode
    fl = fly(model, drive, loop.state, loop.t, loop.q, loop.v, t_end, settings)
    loop.blocks.append(("py", fl.piece))
    loop.t, loop.q, loop.v = fl.t, fl.q, fl.v
    loop.state = DriveState(mode, fl.z)
    if fl.events:
        new = loop.state
        for e in fl.events:
            new = drive.jump(new.mode, new.z, e, fl.t, fl.q, fl.v)
        loop.switch(new, fl.t)
    return fl


def run_coupled(model, drive, q, v, t0, t_end, max_imp, make_state, settings, new_run, histories=True):
    """:func:`~impactbar.simulation.driven.run_stateful` under a law whose contact takes time:
    flights by :func:`impactbar.drives.flight.fly`, each arrival a blow of :func:`driven_blow` (a
    :class:`BlowPiece`); a blow that ends with the end pressed on the stop (moving into it) is
    followed at once by the next. ``new_run`` makes the run's log (the simulator's ``_Run``: its
    state, logs and result, a :class:`~impactbar.DrivenTrajectory`). Without ``histories`` each
    blow is logged as its :class:`BlowSummary` once it ends (its drive's pieces released).

    Returns
    -------
    DrivenTrajectory

    Raises
    ------
    ValueError
        From a blow (:func:`driven_blow`), or the piston pressed on the stop through
        ``PRESSED_BLOWS`` blows."""
    c = model.end_weights
    settings = settings if settings is not None else drive.traits.integrator
    loop = new_run(model, drive, q, v, t0, t_end, max_imp)
    loop.q, loop.v = np.array(q, dtype=float), np.array(v, dtype=float)
    pressed = 0
    while loop.t < t_end and not loop.done:
        on_stop = float(c @ loop.q) >= -1e-14 * max(1.0, float(np.abs(c) @ np.abs(loop.q))) \
            and float(c @ loop.v) > 0.0
        if on_stop:  # pressed on the stop at the end of a blow (or started there): it arrives at once
            pressed += 1
            if pressed > PRESSED_BLOWS:
                raise ValueError(f"the piston stays pressed on the stop through {PRESSED_BLOWS} blows from "
                                 f"t = {loop.t:.6g}: the drive holds it there")
            t_arr, q_arr, v_arr = loop.t, loop.q.copy(), loop.v.copy()
        else:
            pressed = 0
            fl = fly_and_switch(model, drive, loop, t_end, settings)
            if fl.end == END:
                break
            if fl.end == EVENT:
                continue
            t_arr, q_arr, v_arr = fl.t, fl.q, fl.v
        res, after = driven_blow(model, drive, loop.state, t_arr, q_arr, v_arr, settings)
        loop.imp_t.append(t_arr)
        loop.imp_v.append(float(c @ v_arr))
        loop.n_imp += 1
        q_arr = q_arr.copy()
        q_arr[0] -= float(c @ q_arr)
        if res.t_release > t_end:  # the run ends inside the blow
            piece = BlowPiece(t_arr, t_end, res.record, (q_arr, v_arr.copy()), res.pieces, c)
            loop.q, loop.v = (np.array(x, dtype=float) for x in piece.modal_end())
            loop.state = DriveState(_mode_at(res, t_end, loop.state.mode), piece.drive_state([t_end])[:, 0])
            loop.blocks.append(("py", piece if histories else BlowSummary(piece)))
            loop.t = t_end
            break
        piece = BlowPiece(t_arr, res.t_release, res.record, (q_arr, v_arr.copy()), res.pieces, c,
                          (res.q_after.copy(), res.v_after.copy()))
        loop.blocks.append(("py", piece if histories else BlowSummary(piece)))
        loop.t, loop.q, loop.v = res.t_release, res.q_after.copy(), res.v_after.copy()
        loop.switch(after, res.t_release)
        del piece, res  # (a summarised blow's drive pieces released now, not at the next blow)
        if loop.n_imp >= max_imp:
            loop.status = RunStatus.MAX_IMPACTS
            break
    return loop.result(make_state, None)


def _mode_at(res, t, mode):
    """The drive's mode at ``t`` inside the blow of ``res`` (``mode`` at its start)."""
    for te, _, m in res.events:
        if te <= t:
            mode = m
    return mode
