r"""One flight of the bar under a drive, from a start to the first of: the next arrival at the stop,
the drive's next event, a stop time (theory §10). The solvers' common step: the generic periodic
orbits of :mod:`impactbar.orbits.driven` fly with it, and so does the simulator for a drive with
state (:mod:`impactbar.simulation.driven`).

Two kinds of flight, by the drive:

- **a force constant between events** (``traits.piecewise_constant``, no continuous state): every
  mode moves in closed form (eq. 8, :func:`~impactbar.dynamics.modal.step_constant`); the arrival is
  found by the compiled certified impact search (:func:`impactbar.dynamics._event_loop.run_free`, or
  the rigid coordinate's closed form), the drive's events in closed form
  (:meth:`~impactbar.drives.DriveEvent.first_time`: position and velocity crossings, scheduled
  times), both to rounding; an event without a closed form (a :class:`~impactbar.drives.SurfaceEvent`)
  is bracketed on a grid finer than the stiffest mode's period and refined by Brent's method (to
  rounding, but a pair of crossings inside one grid step is not seen).
- **a drive with state** ``z`` (``z' = rate(mode, z, q, q')``, the force ``p(mode, z, q, q')``): the
  bar's modes ``q_n'' + d q_n' + (s n pi)^2 q_n = p`` (eq. 6) and ``z`` are integrated together by
  scipy's ``solve_ivp`` (the drive's method: ``"LSODA"`` by default, which turns to BDF where the
  problem is stiff, as an oil column against the piston's inertia is)
  with the arrival ``c . q = 0`` (rising) and the drive's events as terminal event functions,
  located by scipy to the integrator's tolerance (``rtol``, ``atol`` of the drive's
  ``traits.integrator``, a :class:`~impactbar.drives.base.FlightSettings`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..dynamics.modal import step_constant
from .base import DriveEvent, DriveState, FlightSettings

__all__ = ["FlightSettings", "Flight", "ClosedPiece", "OdePiece", "RestPiece", "QuadratureRestPiece", "fly",
           "bracket_event", "solver_settings", "ARRIVAL", "EVENT", "END"]

#: how a flight ended
ARRIVAL, EVENT, END = 0, 1, 2


DEFAULT_SETTINGS = FlightSettings()


def solver_settings(settings, forcing, drive_solver: bool) -> dict:
    """The keywords by which an entry point (:func:`impactbar.simulate`, :func:`impactbar.find_orbit`,
    :func:`impactbar.periodic_orbits`) hands its ``settings`` to the solver it chose for ``forcing``.

    Parameters
    ----------
    settings : FlightSettings or None
        How a drive's flights with state are integrated (the oil circuit's
        :class:`~impactbar.drives.circuit.CircuitFlightSettings`); ``None``: the drive's
        :attr:`~impactbar.Drive.integrator`.
    forcing : Load or Drive
        Named in the refusal.
    drive_solver : bool
        Whether the chosen solver is the drives' (its table's ``"drive"`` entry).

    Returns
    -------
    dict
        ``{}`` without settings, else ``{"settings": settings}``.

    Raises
    ------
    ValueError
        Settings for a load's solver (its flights are closed forms), or settings that are not a
        :class:`FlightSettings`.
    """
    if settings is None:
        return {}
    if not drive_solver:
        raise ValueError("settings: the integrator of a drive's flights; give it only with a Drive (a "
                         f"load's flights are closed forms); got a {type(forcing).__name__}")
    if not isinstance(settings, FlightSettings):
        raise ValueError(f"settings must be a FlightSettings (the oil circuit's: CircuitFlightSettings) or "
                         f"None; got {type(settings).__name__}")
    return {"settings": settings}


class ModalEnd:
    """The struck end's displacement and velocity of a piece from its modal state: ``modal(t)`` gives
    ``(q, v)``, shapes ``(M, k)``, and ``c`` the end's weights, shape ``(M,)``; the end's displacement
    ``c . q`` is at most 0, the stop (theory §2). A flight's pieces share it."""

    __slots__ = ()

    def end_displacement(self, t):
        """The end's displacement at the times ``t``, shape ``(k,)``: ``min(c . q, 0)``."""
        q, _ = self.modal(t)
        return np.minimum(self.c @ q, 0.0)

    def end_velocity(self, t):
        """The end's velocity at the times ``t``, shape ``(k,)``: ``c . v``."""
        _, v = self.modal(t)
        return self.c @ v


class ClosedPiece(ModalEnd):
    """A flight under a constant force ``p`` from ``(q, v)`` at ``t0``, to ``t_end``, in closed form
    (eq. 8)."""

    __slots__ = ("t0", "t_end", "p", "q", "v", "w2", "d", "c", "z")

    def __init__(self, t0, t_end, p, q, v, w2, d, c, z):
        self.t0, self.t_end, self.p, self.q, self.v = t0, t_end, p, q, v
        self.w2, self.d, self.c, self.z = w2, d, c, z

    def modal(self, t):
        """``(q, v)`` at times ``t`` in the piece, shape ``(M, T)`` each."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return step_constant(self.w2, self.d, self.p, self.q, self.v, t - self.t0)

    def force(self, t):
        """The force on the piston at times ``t``: ``p``."""
        return np.full(np.atleast_1d(t).shape, float(self.p))

    def drive_state(self, t):
        """The drive's continuous state at times ``t``: constant, shape ``(k, T)``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return np.repeat(np.asarray(self.z, dtype=float)[:, None], t.size, axis=1)


class OdePiece(ModalEnd):
    """A flight of a drive with state, by ``solve_ivp``'s dense output from ``t0`` to ``t_end``;
    ``p(q, v, z)`` the drive's force in the flight's mode."""

    __slots__ = ("t0", "t_end", "sol", "M", "c", "p")

    def __init__(self, t0, t_end, sol, M, c, p=None):
        self.t0, self.t_end, self.sol, self.M, self.c, self.p = t0, t_end, sol, M, c, p

    def force(self, t):
        """The force on the piston at times ``t``."""
        y = self._y(t)
        M = self.M
        return np.array([self.p(y[:M, j], y[M:2 * M, j], y[2 * M:, j]) for j in range(y.shape[1])])

    def _y(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if self.sol is None:  # a piece of no length
            return None
        return np.atleast_2d(self.sol(np.clip(t, self.t0, self.t_end)).T).T

    def modal(self, t):
        y = self._y(t)
        return y[:self.M], y[self.M:2 * self.M]

    def drive_state(self, t):
        return self._y(t)[2 * self.M:]


class RestPiece:
    r"""The rigid piston resting on the stop while the drive presses it (:math:`p \ge 0`) and its state
    evolves: :math:`q = q' = 0`, ``z`` by ``solve_ivp``'s dense output (``sol``, or constant ``z``)."""

    __slots__ = ("t0", "t_end", "sol", "z", "M", "c")

    def __init__(self, t0, t_end, sol, z, M, c):
        self.t0, self.t_end, self.sol, self.z, self.M, self.c = t0, t_end, sol, z, M, c

    def modal(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return np.zeros((self.M, t.size)), np.zeros((self.M, t.size))

    def force(self, t):
        return np.zeros(np.atleast_1d(t).size)  # (no work: the piston does not move)

    def drive_state(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        k = len(self.z)
        if self.sol is None:
            return np.repeat(np.asarray(self.z, dtype=float)[:, None], t.size, axis=1)
        return np.atleast_2d(self.sol(np.clip(t, self.t0, self.t_end)).T).T[:k]

    def end_displacement(self, t):
        return np.zeros(np.atleast_1d(t).size)

    def end_velocity(self, t):
        return np.zeros(np.atleast_1d(t).size)


class QuadratureRestPiece(RestPiece):
    """A :class:`RestPiece` of a drive that keeps quadratures of its own
    (:class:`~impactbar.drives.abilities.Quadratures`, the oil circuit's energy account): ``sol``
    carries them after ``z``, from 0 at ``t0``; ``totals`` are their values at ``t_end``; ``work``
    the index of the drive's work on the piston among them
    (the ability's ``piston_work``, ``None``: none of them).

    Raises
    ------
    ValueError
        For a ``work`` that is not ``None`` or an index of ``totals``.
    """

    __slots__ = ("totals", "work")

    def __init__(self, t0, t_end, sol, z, M, c, totals, work=None):
        super().__init__(t0, t_end, sol, z, M, c)
        self.totals = np.asarray(totals, dtype=float)
        if work is not None and not (isinstance(work, (int, np.integer)) and 0 <= work < self.totals.size):
            raise ValueError(f"piston_work must be None or an integer in [0, "
                             f"{self.totals.size}) (the drive's quadratures' count); got {work!r}")
        self.work = work

    def energies(self):
        """The drive's quadratures over the rest (the oil circuit's eight energy terms)."""
        return self.totals.copy()

    def piston_work(self) -> float:
        """The drive's work on the piston over the rest: its quadrature ``work``, or 0 without one (the
        piston does not move).

        Returns
        -------
        float
            In model energy units.
        """
        return 0.0 if self.work is None else float(self.totals[self.work])


class Flight(NamedTuple):
    """The end of one flight (:func:`fly`).

    Attributes
    ----------
    t : float
        Where it ended.
    q, v : numpy.ndarray, shape (N + 1,)
        The bar's modal state there (on arrival: before the impact).
    z : numpy.ndarray, shape (k,)
        The drive's continuous state there.
    end : int
        :data:`ARRIVAL`, :data:`EVENT` or :data:`END`.
    events : tuple of DriveEvent
        The drive's events at ``t`` (with :data:`EVENT`, or with :data:`ARRIVAL` those its root finder
        found on the arrival's own root: the oil circuit's levels, whose flags the caller turns before
        the impact's map), in the drive's order.
    piece : ClosedPiece or OdePiece
        The flight, to evaluate it at any time in it.
    sensitivity : numpy.ndarray or None
        From a drive's own flight with the variational equations (its ability
        :class:`~impactbar.drives.abilities.OwnFlight` with ``variational=True``): the fundamental
        matrix of ``(q, q', z)`` from the start to the end (before the map of the event that ends
        it); ``None`` otherwise.
    """

    t: float
    q: np.ndarray
    v: np.ndarray
    z: np.ndarray
    end: int
    events: tuple
    piece: object
    sensitivity: np.ndarray | None = None


def fly(model, drive, state: DriveState, t: float, q, v, t_stop: float,
        settings: FlightSettings | None = None, variational: bool = False, start=None) -> Flight:
    r"""One flight from ``(q, v)`` and the drive's ``state`` at ``t`` to the next arrival at the stop
    (``c . q = 0`` with ``c . q' > 0``), the drive's next event or ``t_stop`` (module docstring).

    Parameters
    ----------
    model : BarModel
    drive : Drive
    state : DriveState
    t : float
    q, v : numpy.ndarray, shape (N + 1,)
        Off the stop, or on it leaving (:math:`c \cdot q \le 0`).
    t_stop : float
    settings : FlightSettings, optional
        The integrator of a drive with state (default: the drive's, ``traits.integrator``).
    variational : bool, optional
        Ask a drive's own flight (its ability :class:`~impactbar.drives.abilities.OwnFlight`) for
        the fundamental matrix of the flight (``Flight.sensitivity``).
    start : numpy.ndarray or None, optional
        With ``variational``, the matrix the variational equations start from (a drive whose own
        flight carries it, ``OwnFlight.carried``), passed on to its ``fly``; default the identity.

    Returns
    -------
    Flight
        A drive that integrates its flights itself (its ability ``flight``, e.g. the oil circuit's
        CVODE) gives its own.
    """
    q = np.array(q, dtype=float)
    v = np.array(v, dtype=float)
    own = drive.abilities.flight
    if own is not None:
        if start is not None:
            return own.fly(model, state, t, q, v, t_stop, settings, variational, start=start)
        return own.fly(model, state, t, q, v, t_stop, settings, variational)
    traits = drive.traits
    if traits.piecewise_constant:
        return _closed(model, drive, state, t, q, v, t_stop)
    return _ode(model, drive, state, t, q, v, t_stop, settings if settings is not None else traits.integrator)


# --------------------------------------------------------------------------------------------------
# a force constant between events: closed forms
# --------------------------------------------------------------------------------------------------
def _closed(model, drive, state, t, q, v, t_stop):
    mode, z = state
    p = float(drive.force(mode, z, q, v))
    d, w2, c = model.d, model.frequencies**2, model.end_weights
    events = drive.events(mode)
    times = [e.first_time(d, p, t, q, v) for e in events]
    for i, (e, te) in enumerate(zip(events, times, strict=True)):
        if math.isnan(te):  # no closed form: bracketed on the closed-form flight
            times[i] = bracket_event(e, model, p, t, q, v, z, t_stop)
    t_ev = min(times, default=math.inf)
    t_next = min(t_ev, t_stop)
    t_arr, qa, va, arrived = arrival(model, p, t, q, v, t_next)
    if arrived:
        return Flight(t_arr, qa, va, z, ARRIVAL, (), ClosedPiece(t, t_arr, p, q, v, w2, d, c, z))
    fired = tuple(e for e, te in zip(events, times, strict=True) if te == t_next)
    return Flight(t_next, qa, va, z, EVENT if fired else END, fired,
                  ClosedPiece(t, t_next, p, q, v, w2, d, c, z))


def arrival(model, p: float, t: float, q, v, t_stop: float):
    """The first arrival at the stop under the constant force ``p`` from ``(q, v)`` at ``t``
    before ``t_stop``: ``(t_arrival, q, v, True)`` there, or ``(t_stop, q, v, False)`` at ``t_stop``
    without one.
    The rigid bar's in closed form (``q_0`` rising through 0, theory §10); a flexible bar's by the
    compiled certified impact search (:func:`impactbar.dynamics._event_loop.run_free`, stopping at the
    arrival); both to rounding."""
    d = model.d
    if model.n_modes == 0:
        from ._crossing import first_rising_crossing, rigid_flight

        q0, v0 = float(q[0]), float(v[0])
        ta = t + first_rising_crossing(d, q0, v0, p, 0.0)
        if ta < t_stop:
            _, va = rigid_flight(d, q0, v0, p, ta - t)
            return ta, np.zeros(1), np.array([va]), True
        if not math.isfinite(t_stop):
            return t_stop, q, v, False
        qe, ve = rigid_flight(d, q0, v0, p, t_stop - t)
        return t_stop, np.array([qe]), np.array([ve]), False
    from ..dynamics import compiled as K
    from ..dynamics.compiled_views import LoadKernelView, ModalBasisView

    w2 = model.frequencies**2
    c = np.ascontiguousarray(model.end_weights)
    load = tuple(LoadKernelView.fourier(p, [], []))
    basis = tuple(ModalBasisView.unforced(w2, d))
    out_t, out_vel, out_q, out_v = np.empty(1), np.empty(1), np.empty((1, q.size)), np.empty((1, q.size))
    out = (out_t, out_vel, out_q, out_v)  # the arrival's time, speed and modal state (_run_free)
    qk, vk = q.copy(), v.copy()
    horizon = t_stop if math.isfinite(t_stop) else t + 1e8
    n, st, tn = K.run_free(load, basis, -1.0, c, (float(t), qk, vk), float(horizon), 1, 1e-9, out, None, True)
    if n:  # an arrival with speed (R = -1: the kernel changes nothing and stops)
        qa, va = out_q[0].copy(), out_v[0].copy()
        qa[0] -= float(c @ qa)  # exactly on the stop
        return float(out_t[0]), qa, va, True
    if st == K.CONTACT:  # a touch at zero speed: the arrival, tangential
        qe, ve = step_constant(w2, d, p, q, v, float(tn) - t)
        qe[0] -= float(c @ qe)
        return float(tn), qe, ve, True
    if math.isfinite(t_stop):
        qe, ve = step_constant(w2, d, p, q, v, t_stop - t)
        return t_stop, qe, ve, False
    return t_stop, q, v, False


def bracket_event(event: DriveEvent, model, p, t, q, v, z, t_stop) -> float:
    """The first crossing of a drive event without a closed form on the closed-form flight: the
    event function sampled on a grid (a quarter of the stiffest mode's period, at most 0.05) and the
    bracket refined by Brent's method (shared with the simulator's drive loop).

    Parameters
    ----------
    event : DriveEvent
        The event (its ``value(t, q, v, z)`` and ``direction``).
    model : BarModel
    p : float
        The constant force over the flight (dimensionless, eq. 2).
    t : float
        The flight's start (load time).
    q, v : numpy.ndarray, shape (N + 1,)
        The modal state at ``t``.
    z : numpy.ndarray, shape (k,)
        The drive's state (constant over the flight).
    t_stop : float
        The end of the search (``inf``: a horizon of ``1e4``).

    Returns
    -------
    float
        The crossing's time; ``inf`` before ``t_stop`` without one.
    """
    from scipy.optimize import brentq

    w2, d = model.frequencies**2, model.d
    wmax = math.sqrt(float(np.max(w2))) if model.n_modes else 0.0
    h = min(0.05, 0.25 * 2.0 * math.pi / wmax) if wmax else 0.05
    end = t_stop if math.isfinite(t_stop) else t + 1e4

    def g(tt):
        qq, vv = step_constant(w2, d, p, q, v, tt - t)
        return event.value(tt, qq, vv, z)

    a, ga = t, g(t)
    while a < end:
        ts = np.minimum(a + h * np.arange(1, 257), end)
        qs, vs = step_constant(w2, d, p, q, v, ts - t)
        gs = np.array([event.value(tt, qs[:, j], vs[:, j], z) for j, tt in enumerate(ts)])
        prev = np.concatenate(([ga], gs[:-1]))
        up = (prev < 0.0) & (gs >= 0.0)
        down = (prev > 0.0) & (gs <= 0.0)
        hit = up if event.direction > 0 else down if event.direction < 0 else up | down
        if np.any(hit):
            j = int(np.argmax(hit))
            lo = a if j == 0 else float(ts[j - 1])
            return brentq(g, lo, float(ts[j]), xtol=4 * np.finfo(float).eps * max(1.0, abs(lo)),
                          rtol=4 * np.finfo(float).eps)
        a, ga = float(ts[-1]), float(gs[-1])
    return math.inf


# --------------------------------------------------------------------------------------------------
# a drive with state: solve_ivp
# --------------------------------------------------------------------------------------------------
def vector_field(model, drive, mode):
    """``f(t, y)`` of ``y = (q, q', z)`` in ``mode``: ``q' = v``, ``v' = p - d v - w2 q`` (eq. 6),
    ``z' = rate``."""
    M = model.n_modes + 1
    w2, d = model.frequencies**2, model.d

    def f(t, y):
        q, v, z = y[:M], y[M:2 * M], y[2 * M:]
        out = np.empty_like(y)
        out[:M] = v
        out[M:2 * M] = drive.force(mode, z, q, v) - d * v - w2 * q
        if z.size:
            out[2 * M:] = (drive.rate(mode, z, q, v) if model.piston is None
                           else drive.rate(mode, z, q, v, model=model))
        return out

    return f


def _ode(model, drive, state, t, q, v, t_stop, settings):
    from scipy.integrate import solve_ivp

    mode, z = state
    M = q.size
    c = model.end_weights
    z = np.asarray(z, dtype=float)
    events = drive.events(mode)

    def arrive(tt, y):
        return float(c @ y[:M])

    arrive.terminal, arrive.direction = True, 1
    fns = [arrive]
    for e in events:
        def g(tt, y, e=e):
            return e.value(tt, y[:M], y[M:2 * M], y[2 * M:])

        g.terminal, g.direction = True, e.direction
        fns.append(g)
    y0 = np.concatenate((q, v, z))
    end = t_stop if math.isfinite(t_stop) else t + 1e6
    if end <= t:
        return Flight(t, q, v, z, END, (), OdePiece(t, t, None, M, c))
    sol = solve_ivp(vector_field(model, drive, mode), (t, end), y0, method=settings.method,
                    rtol=settings.rtol, atol=settings.atol, max_step=settings.max_step, events=fns,
                    dense_output=True)
    if sol.status < 0:
        raise ValueError(f"the flight of the drive's state could not be integrated from t = {t:.6g}: "
                         f"{sol.message}")
    te = float(sol.t[-1])
    y = sol.y[:, -1].copy()
    piece = OdePiece(t, te, sol.sol, M, c, lambda q, v, z: drive.force(mode, z, q, v))
    if sol.status == 1:  # an event ended it
        hit = [i for i, tt in enumerate(sol.t_events) if tt.size]
        if 0 in hit:
            qa, va = y[:M], y[M:2 * M]
            qa[0] -= float(c @ qa)  # exactly on the stop
            return Flight(te, qa, va, y[2 * M:], ARRIVAL, (), piece)
        fired = tuple(events[i - 1] for i in hit)
        return Flight(te, y[:M], y[M:2 * M], y[2 * M:], EVENT, fired, piece)
    return Flight(te, y[:M], y[M:2 * M], y[2 * M:], END, (), piece)
