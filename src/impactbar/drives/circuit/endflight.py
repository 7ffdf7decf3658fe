r"""The oil circuit during a blow (theory §11, "The coupled blow"): its state integrated by CVODE with
the piston's driven end moved by the law's waves, ``u_t(0, t) = a(t) + p / Z``.

A law whose contact takes time (the wave law, the rod-rock law) cannot hold the drive's force during
the blow: the piston's travel changes the chambers' volumes and so the pressures. Over a stretch of
the blow the law knows the wave ``a(t)`` arriving at the driven end from inside the piston (the
piston's state at impact and what the far end sent back, none of it caused by the drive within the
round trip to the first change of impedance), and the driven end answers the drive's force as a
semi-infinite bar of impedance ``Z``. :func:`circuit_end_flight` integrates the circuit over such a
stretch, cut at the law's ``breaks`` (where ``a`` may jump: the lattice's steps, the window's
corners), with the circuit's own events inside it (the ramp's end, the accumulator, the relief), and
returns the force's integral over each interval, the driven end's displacement and the pieces
(histories, energy quadratures). The law then solves its blow with that force; the next stretch's
``a`` follows from it (a method of steps; no iteration).
"""

from __future__ import annotations

import contextlib
import functools
import io
from typing import NamedTuple

import numpy as np

from ..base import DriveState, FlightSettings
from . import _endgen as EK
from ._bar import RAMP_EV
from .flight import _MAX_STEPS, HermiteSteps, _compiled_driver, _message
from .settings import circuit_settings

__all__ = ["EndFlight", "EndPiece", "circuit_end_flight"]

#: What a blow that empties a chamber is told (:meth:`~impactbar.drives.circuit.Chambers.check_volumes`).
_EMPTIED_IN_BLOW = "during the blow near t = {t:.6g}: give a larger {which}_volume (now {now:g})"


class EndPiece(HermiteSteps):
    """The circuit over one interval of a blow: the integrator's steps and a cubic Hermite
    interpolant between them (as :class:`~impactbar.drives.circuit.flight.CircuitPiece`).

    Attributes
    ----------
    t0, t_end : float
    t : numpy.ndarray, shape (S,)
    y : numpy.ndarray, shape (S, 2 + n_states + n_energy)
        ``(w, z, I, E)`` at the steps (``z`` the circuit's states, ``p_f, p_r, p_s, x_v`` for the
        preset), ``I`` and the energies from 0 at ``t0``.
    layout : CircuitLayout
        Where the circuit keeps its states and energy terms (:attr:`HydraulicCircuitDrive.layout`).
    """

    __slots__ = ("f", "alpha", "layout")

    def __init__(self, t, y, f, alpha, layout):
        self.t, self.y, self.f, self.alpha, self.layout = t, y, f, alpha, layout
        self.t0, self.t_end = float(t[0]), float(t[-1])
        self._spline = None

    def drive_state(self, t):
        """The circuit's states ``z`` at times ``t``, shape ``(n_states, T)``."""
        return self._at(t)[1:1 + self.layout.n_states]

    def force(self, t):
        """The force on the piston, ``p_r - alpha p_f``, at times ``t``, shape ``(T,)``."""
        Y, L = self._at(t), self.layout
        return Y[1 + L["rear"]] - self.alpha * Y[1 + L["front"]]

    def displacement(self, t):
        """The driven end's displacement ``w = -u(0, t)`` at times ``t``, shape ``(T,)``."""
        return self._at(t)[0]

    def impulse_at(self, t):
        """``int p dt`` from ``t0`` to the times ``t``, shape ``(T,)``."""
        return self._at(t)[1 + self.layout.n_states]

    def energies(self):
        """The energy quadratures over the piece (theory §11; ``layout.energies``)."""
        return self.y[-1, self._energy_start:].copy()

    def energies_at(self, t: float):
        """The energy quadratures from ``t0`` to ``t`` (interpolated)."""
        return self._at([t])[self._energy_start:, 0]

    @property
    def _energy_start(self):
        """Where the energy terms start in a row of ``y`` (after ``w, z, I``)."""
        return 2 + self.layout.n_states

    def piston_work(self) -> float:
        """The circuit's work on the piston over the piece, its layout's ``"piston"`` energy term
        (:attr:`HydraulicCircuitDrive.piston_work_quadrature`; its column looked up once a layout: a
        blow sums some hundred pieces).

        Returns
        -------
        float
            In model energy units.
        """
        return float(self.y[-1, _work_column(self.layout)])

    def piston_work_at(self, t: float) -> float:
        """The circuit's work on the piston from ``t0`` to ``t`` (interpolated, as :meth:`energies_at`).

        Parameters
        ----------
        t : float
            A time in the piece (model units; clipped to ``[t0, t_end]``).

        Returns
        -------
        float
            In model energy units.
        """
        return float(self._at([t])[self._energy_start + self.layout.energy["piston"], 0])

    def _column(self, k: int | str) -> int:
        return 1 + (self.layout[k] if isinstance(k, str) else k)


class EndFlight(NamedTuple):
    """What :func:`circuit_end_flight` returns.

    Attributes
    ----------
    state : DriveState
        The circuit's state at the last break.
    w : float
        The driven end's displacement there.
    impulses : numpy.ndarray, shape (n,)
        ``int p dt`` over each of the ``n`` intervals between the breaks.
    pieces : list of EndPiece
        In order (an interval cut by an event gives two).
    events : list of tuple
        ``(t, event, mode after)`` of the circuit's events inside the stretch.
    """

    state: DriveState
    w: float
    impulses: np.ndarray
    pieces: list
    events: list


def _solver(drive, mode, settings, ext, model1, state_size):
    from sksundae.cvode import CVODE

    par = drive._network_par(model1, mode)
    code = _end_code(drive)
    rhs, jac, events = code.end_rhs, code.end_jac, code.end_events

    def f(t, y, yp):
        fn = ext_fn[0]
        if fn is not None:
            ext[EK.EXT_A] = fn(t)
        rhs(y, yp, par, ext)

    def jf(t, y, yp, JJ):
        jac(y, JJ, par, ext)

    def ev(t, y, g):
        events(y, g, par)

    ext_fn = [None]
    ev.terminal = [True] * code.NEV
    ev.direction = list(_end_directions(drive, mode))
    solver = CVODE(f, method="BDF", rtol=settings.rtol, atol=settings.atol, jacfn=jf, eventsfn=ev,
                   num_events=code.NEV, max_num_steps=_MAX_STEPS)
    return solver, par, ext_fn


def circuit_end_flight(drive, model, state: DriveState, breaks, w0: float, incoming, impedance: float,
                       settings: FlightSettings | None = None, one_mode=None) -> EndFlight:
    """The circuit from ``state`` at ``breaks[0]`` to ``breaks[-1]`` with the driven end moving at
    ``u_t(0, t) = a(t) + p / Z`` (module docstring).

    Parameters
    ----------
    drive : HydraulicCircuitDrive
    model : BarModel
        The bar (only checked: the circuit's chambers follow the driven end, whatever the piston).
    state : DriveState
    breaks : array_like, shape (n + 1,)
        Increasing times; ``a`` is constant (a float of ``incoming``) or smooth (a callable) on each
        interval.
    w0 : float
        The driven end's displacement ``-u(0)`` at ``breaks[0]``.
    incoming : sequence of float or callable, length n
        ``a`` on each interval: a value, or a function of the time.
    impedance : float
        ``Z > 0`` of the piston at its driven end (model units: ``s`` for a uniform piston).
    settings : CircuitFlightSettings or FlightSettings, optional
        CVODE's tolerances and whether it runs compiled (``compiled``; default the drive's,
        :func:`.settings.circuit_settings`).
    one_mode : object
        The one-mode bar of the compiled kernels' parameters (``drive._rate_model(1)``: what
        :meth:`HydraulicCircuitDrive.end_flight` passes).

    Returns
    -------
    EndFlight

    Raises
    ------
    ValueError
        Where CVODE fails, or a chamber empties.
    """
    settings = circuit_settings(settings)
    breaks = np.asarray(breaks, dtype=float)
    n = breaks.size - 1
    model1 = one_mode
    ext = np.zeros(EK.EXT_SIZE)
    ext[EK.EXT_IZ] = 1.0 / float(impedance)
    solvers: dict = {}  # by mode: scikit-sundae's solver (a wave that varies within a stretch)
    mode, z = state.mode, np.array(state.z, dtype=float)
    ns = drive.layout.n_states
    w = float(w0)
    impulses = np.zeros(n)
    pieces: list = []
    fired_log: list = []
    compiled = _compiled_end(settings)
    # (an array of floats holds no callable: the coupled blow's waves, not looked through)
    values = isinstance(incoming, np.ndarray) and incoming.dtype == np.float64
    # no Python between the events where each interval's wave is a value
    if compiled is not None and (values or not any(callable(a) for a in incoming)):
        return _compiled_stretches(compiled, drive, model1, state, breaks, w,
                                   np.asarray(incoming, dtype=float), impedance, settings)
    if compiled is not None and n and all(hasattr(a, "spline") for a in incoming):  # (the coupled
        # exact blow's splines: compiled, the same steps)
        return _compiled_stretches(compiled, drive, model1, state, breaks, w, np.zeros(n), impedance,
                                   settings, compiled.spline_data(incoming))
    for k in range(n):
        a = incoming[k]
        t, t1 = float(breaks[k]), float(breaks[k + 1])
        while t < t1:
            y0 = np.zeros(_end_code(drive).NE)
            y0[0], y0[1:1 + ns] = w, z
            if mode not in solvers:
                solvers[mode] = _solver(drive, mode, settings, ext, model1, drive.state_size)
            solver, par, ext_fn = solvers[mode]
            if callable(a):
                ext_fn[0] = a
            else:
                ext_fn[0] = None
                ext[EK.EXT_A] = float(a)
            with contextlib.redirect_stdout(io.StringIO()):  # (CVODE's errors are in sol.message)
                sol = solver.solve(np.array([t, t1]), y0)
            if sol.status < 0 or not np.all(np.isfinite(sol.y[-1])):
                raise ValueError(f"the oil circuit during the blow from t = {t:.6g} could not be "
                                 f"integrated ({sol.message})")
            ts, Y, status = sol.t, sol.y, int(sol.status)
            hit = [] if sol.i_events is None else list(np.flatnonzero(np.atleast_2d(sol.i_events)[-1]))
            ts = np.asarray(ts, dtype=float)
            Y = np.asarray(Y, dtype=float)
            keep = np.concatenate(([True], np.diff(ts) > 0.0))
            ts, Y = ts[keep], np.ascontiguousarray(Y[keep])
            exts = np.empty((ts.size, EK.EXT_SIZE))
            exts[:, EK.EXT_IZ] = ext[EK.EXT_IZ]
            exts[:, EK.EXT_A] = [a(tt) for tt in ts] if callable(a) else float(a)
            f = np.empty_like(Y)
            _end_code(drive).end_field_at(Y, par, exts, f)
            piece = EndPiece(ts, Y, f, drive.chambers.area_ratio, drive.layout)
            pieces.append(piece)
            drive.chambers.check_volumes(Y[:, EK.Y_W], t, _EMPTIED_IN_BLOW)
            impulses[k] += Y[-1, EK.Y_CIRCUIT + ns]  # I
            w, z = float(Y[-1, EK.Y_W]), Y[-1, EK.Y_CIRCUIT:EK.Y_CIRCUIT + ns].copy()
            te = float(ts[-1])
            if status == 2 and hit:
                st = DriveState(mode, z)
                for e in drive._fired(mode, [RAMP_EV + i for i in hit]):
                    st = drive.jump(st.mode, st.z, e, te, None, None)
                    fired_log.append((te, e, st.mode))
                mode, z = st.mode, np.array(st.z, dtype=float)
            t = te if te < t1 else t1
    return EndFlight(DriveState(mode, z), w, impulses, pieces, fired_log)


def _compiled_stretches(compiled, drive, model1, state, breaks, w, incoming, impedance, settings,
                        splines=None):
    """:func:`circuit_end_flight` with a constant ``a`` on each interval, or with ``splines``
    (:func:`._endcvode.spline_data`) a spline on each: the stretches between the circuit's events in
    one compiled call each (the generated ``fly_intervals``, :mod:`._endgen`, the same steps as one
    :func:`._cvode.fly` a stretch), Python only at the events."""
    n = breaks.size - 1
    code = _end_code(drive)
    if splines is None:
        splines, room = (np.empty(0), np.empty(0, dtype=np.int64)), 0
        ws = compiled.CV.workspace(code.NE, 0, code.CALLBACKS)
    else:
        _, offsets = splines
        room = int(np.max(np.diff(offsets)))
        ws = compiled.CV.workspace(code.NE, 0, code.SPLINE_CALLBACKS)
    ch = drive.chambers
    volumes = np.array([ch.rear_volume, ch.front_volume, ch.area_ratio])
    alpha = ch.area_ratio
    layout = drive.layout
    impulses = np.zeros(n)
    pieces: list = []
    fired_log: list = []
    mode, z = state.mode, np.array(state.z, dtype=float)
    k, t = 0, float(breaks[0])
    rtol, atol = float(settings.rtol), float(settings.atol)
    while True:
        directions, data = _mode_data(compiled, drive, model1, mode, float(impedance))
        # (the callbacks write their scratch into it: one a call, threads apart; a spline's room)
        data = np.concatenate((data, np.zeros(room))) if room else data.copy()
        flag, k, t, T, Y, F, starts, roots = code.fly_intervals(
            ws.mem, ws.y, breaks, k, t, w, z, incoming, rtol, atol, directions, data, _MAX_STEPS, volumes,
            impulses, *splines)
        rows = starts.tolist()
        for a, b in zip(rows[:-1], rows[1:], strict=True):
            pieces.append(EndPiece(T[a:b], Y[a:b], F[a:b], alpha, layout))
        if flag in (compiled.REAR_EMPTY, compiled.FRONT_EMPTY):
            which = "rear" if flag == compiled.REAR_EMPTY else "front"
            raise ValueError(f"the {which} chamber empties (V <= 0) during the blow near t = {t:.6g}: give a "
                             f"larger {which}_volume (now {getattr(ch, which + '_volume'):g})")
        if flag < 0:
            why = "a state not finite" if flag == compiled.NOT_FINITE else _message(flag)
            raise ValueError(f"the oil circuit during the blow from t = {t:.6g} could not be integrated "
                             f"({why})")
        if starts.size > 1:
            w, z = float(Y[-1, EK.Y_W]), Y[-1, EK.Y_CIRCUIT:EK.Y_CIRCUIT + drive.layout.n_states].copy()
        if flag != 2:
            break
        te = float(T[-1])
        st = DriveState(mode, z)
        for e in drive._fired(mode, [RAMP_EV + i for i in np.flatnonzero(roots)]):
            st = drive.jump(st.mode, st.z, e, te, None, None)
            fired_log.append((te, e, st.mode))
        mode, z = st.mode, np.array(st.z, dtype=float)
    return EndFlight(DriveState(mode, z), w, impulses, pieces, fired_log)


@functools.lru_cache(maxsize=16)
def _work_column(layout) -> int:
    """The column of the piston's work in a row of :class:`EndPiece`'s ``y``."""
    return 2 + layout.n_states + layout.energy["piston"]


def _compiled_end(settings):
    """:mod:`._endcvode` where the settings fly compiled (``compiled`` of a
    :class:`~.settings.CircuitFlightSettings`) and the SUNDIALS libraries bind, else None."""
    return _end_module(settings.compiled)


@functools.lru_cache(maxsize=2)
def _end_module(compiled: bool):
    """:func:`_compiled_end` by the settings' flag (looked up once: a blow asks at each stretch)."""
    if _compiled_driver(compiled) is None:
        return None
    from . import _endcvode

    return _endcvode


@functools.lru_cache(maxsize=256)
def _mode_data(compiled, drive, model1, mode, impedance: float):
    """The root directions and the callbacks' user data (:func:`._endcvode.user_data`, the wave
    ``a`` 0) of the circuit in ``mode`` during a blow, kept by drive, mode and impedance (a blow
    asks at each stretch, the same few modes): the directions shared (the generated ``fly_intervals``
    only reads them), the data read-only, for a copy a call."""
    par = drive._network_par(model1, mode)
    directions = np.array(_end_directions(drive, mode), dtype=np.int32)
    data = compiled.user_data(par, 0.0, impedance, scratch=_end_code(drive).SCRATCH)
    data.flags.writeable = False
    return directions, data


@functools.lru_cache(maxsize=64)
def _end_code(drive):
    """The coupled blow's code generated for the drive's circuit (:func:`._endgen.generate`: one
    module a topology, every mode's flags values of ``par``), kept by drive."""
    from . import _endgen

    return _endgen.generate(drive, (0,) * (1 + len(drive._composition.events)))


def _end_directions(drive, mode) -> tuple:
    """The root directions of the network's events during a blow (the ramp's end, then one a flag of
    the mode), as the flight's from its ramp's end on."""
    return drive._directions(mode)[RAMP_EV:]

