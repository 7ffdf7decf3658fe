"""The generic periodic-orbit problem of a drive (theory §10, §11): :class:`ShootingProblem`,
multiple shooting over the ``m`` impacts of the period, for any drive without a problem of its own
(:func:`~impactbar.orbits.driven.orbit_problem` chooses; the module docstring of
:mod:`impactbar.orbits.driven` gives the unknowns, the residual and the measured errors of its
finite-difference Jacobian). Its module constants set the differences' steps (``FD_STEP_CLOSED``,
``FD_STEP_ODE``), how a start for Newton is settled (``SETTLE_*``) and the steering Jacobians'
Magnus steps (``STEER_THETA``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np

from .._shared.forcing import alike
from .._shared.status import Admissibility
from .._shared.validate import check_int
from ..drives.base import DriveState
from ..drives.flight import ARRIVAL, EVENT, FlightSettings, fly
from ..drives.orbitproblem import OrbitData, OrbitProblem, StalledIteration, chord, newton
from ..model import BarModel
from . import _closing as C
from ._closing import SETTLE_HANDOVER, SETTLE_LIFTED, checked_root, close
from ._saltation import map_jacobian, through
from ._settling import (
    DRIFT_AHEAD,
    DRIFT_PROBE,
    SETTLE_DRIFT_IMPACTS,
    dominant_limit,
    drift_to_surface,
    drifting,
    expanding_to_surface,
    nearing,
    other_period,
    surfaces_ahead,
)
from ._shooting_data import block_mode, event_pattern, on_section, orbit_data, start_modes
from .driven_orbit import DrivenOrbit, _constant_load

__all__ = ["ShootingProblem"]

TWO_PI = 2.0 * math.pi


class _Iterate(NamedTuple):
    """An impact the settling run met: its time, the drive's mode, the state after it and its source."""

    tau: float
    mode: object
    y: np.ndarray
    source: tuple | None


class _LastFlight(NamedTuple):
    """The flight :meth:`ShootingProblem._flight` remembers: its start's key, whether its pieces were
    kept, its Jacobian's level (``_JACOBIAN_LEVEL``) and what it returned."""
    key: tuple
    keep: bool
    level: int
    flight: tuple


#: central-difference steps of the shooting Jacobian (relative to ``max(1, |X_j|)``): closed-form
#: flights (rounding ~1e-16; the measured errors are in the module docstring: smaller steps meet the
#: rounding, larger ones the truncation) and integrated ones (rtol 1e-10: noise / step ~1e-6 at most)
FD_STEP_CLOSED = 1e-6
FD_STEP_ODE = 1e-4
#: impacts followed from rest (or from a run's end) before Newton starts, at most
SETTLE_IMPACTS = 400
#: the Magnus steps (``h ||A|| = theta``, :attr:`FlightSettings.magnus_theta`) of the variational
#: flights whose Jacobian only steers Newton's method (the chord's, its closing step): four times the
#: drive's own, a quarter of the steps (two squarings more each), the preset's first flight's Jacobian
#: within 1.5e-5, 4.9e-5 and 2.1e-6 of its largest entry with 4, 8 and 16 modes (at twice the drive's
#: steps 2.4e-7, 1.1e-6, 6.7e-8); the preset's orbits the same to 2e-13 and some 10 % cheaper than at
#: twice; the multipliers' keep the drive's. As a closing step meets it, that error reaches 6e-3 when
#: the preset's parameters change (``_closing.STEER_ERROR``: chord steps follow a large closing step)
STEER_THETA = 4.0
#: the Jacobians a flight can carry (:meth:`ShootingProblem._flight`'s ``variational``), by how much
#: each holds: a remembered flight answers a request for as much or less
_JACOBIAN_LEVEL = {False: 0, "state": 1, "steer": 2, True: 3}
#: longest flight between two impacts (model time units) before a flight counts as never arriving
HORIZON = 1e4


def _same_problem(a, b) -> bool:
    """Whether the shooting problems ``a`` and ``b`` fly the same flights: one class, the same model,
    drive, integrator, impacts and blocks (``False`` where they cannot be compared)."""
    try:
        return bool(type(a) is type(b) and a.impacts == b.impacts and a.model == b.model
                    and a.drive == b.drive and a.settings == b.settings and list(a.blocks) == list(b.blocks))
    except (TypeError, ValueError):  # (an array among them)
        return False


class ShootingProblem(OrbitProblem):
    """The generic periodic-orbit problem of a drive (module docstring): multiple shooting over the
    ``m`` intervals between impacts, with the drive's flights (:func:`impactbar.drives.flight.fly`),
    the impact law and the drive's maps.

    Unknowns: ``m`` blocks ``(q, q', z)`` just after each impact (where its contact ends), each
    flown from its projection on the section ``c . q = 0`` (``q_0`` shifted: a perturbation of the
    unknowns must not start a flight through the stop). Each block starts at a fixed time ``tau_k``
    in a fixed mode (those of the guess: the system is autonomous, the mode's scheduled events are
    counted from ``tau_k``). Residual: the block's flight to its impact, the impact law (eq. 10, or
    the law's contact under the drive's force) and the drive's map at the impact, minus the next
    block. Jacobian: central differences.

    Parameters
    ----------
    model : BarModel
    drive : Drive
    impacts : int
    settings : FlightSettings, optional
        The integrator of a drive with state (default: the drive's, ``traits.integrator``).
    newton : {"chord", "full"}, optional
        Where the drive's flights integrate the variational equations (the oil circuit), how
        :meth:`solve` iterates: ``"chord"`` (default), the Jacobian of one variational flight at a
        looser tolerance (``SETTLE_RTOL``) at the start, the residuals by plain flights (a fraction
        of the cost: the variational flight carries ``n^2`` more unknowns and takes about four times
        the steps), the Jacobian taken again only where the steps stop shrinking
        (:func:`~impactbar.drives.orbitproblem.chord`); ``"full"``, Newton's method with a variational
        flight at every step (the way before). The orbit's multipliers come from one variational
        flight at the root either way (:meth:`orbit`).
    """

    default_start = "the motion from rest on the stop, followed until its impacts settle"
    starts_from_rest = True
    #: the coupled blows' columns of the multipliers' Jacobian by forward differences (half the blows)
    forward_blows = False

    def __init__(self, model: BarModel, drive, impacts: int = 1, settings: FlightSettings | None = None,
                 *, newton: str = "chord"):
        if newton not in ("chord", "full"):
            raise ValueError(f"newton must be 'chord' or 'full'; got {newton!r}")
        self.model, self.drive, self.newton = model, drive, newton
        self.impacts = check_int("impacts", impacts, lo=1)
        traits, own = drive.traits, drive.abilities.flight
        self.settings = settings if settings is not None else traits.integrator
        law = model.law
        #: a drive with state under a law whose contact takes time: each impact a blow solved with
        #: the drive's state (theory §11, "The coupled blow"), its Jacobian by central differences
        self.coupled = not traits.piecewise_constant and not law.traits.restitution_in_kernel
        if self.coupled:
            from ..simulation.blows import check_coupling

            check_coupling(model, drive)
        if law.traits.restitution_in_kernel and model.R >= 1.0:
            raise ValueError("model.R must be < 1 for a periodic motion under a drive (with R = 1 no "
                             "energy leaves at the impacts)")
        #: every flight starts on the stop, else where a blow left it (:func:`._shooting_data.starts_on_stop`)
        self.on_stop = law.traits.flight_starts_on_stop
        self.M = model.n_modes + 1
        self.k = traits.state_size
        self.n = 2 * self.M + self.k
        self.size = self.impacts * self.n
        self.positive = np.zeros(0, dtype=np.int64)
        self.closed = traits.piecewise_constant
        #: the Jacobian from the variational equations (a drive whose own flights integrate them)
        self.variational = own is not None and own.variational and not self.closed
        #: whether the variational flights carry the Jacobian so far (``OwnFlight.carried``), or None
        self._carries = own.carried if self.variational else None
        self.accuracy = 1e-13 if self.closed else 10.0 * self.settings.rtol
        self.blocks: list = []  # (tau_k, mode_k) of each block, from the guess
        self.sources: list = []  # the impact before each block: (mode, z on arrival, tau_k, q, v after)
        self._last = None  # the last flight: (its start, keep, its Jacobian's level, its result)

    # -- flights ------------------------------------------------------------------------------------
    def _flight(self, tau, mode, y, keep=False, variational=False, settings=None):
        """From ``y = (q, q', z)`` in ``mode`` at ``tau`` to the next impact and through it: the
        state after it, the time it ends, the mode at the arrival and, with ``keep``, the pieces and
        the drive's events ``(time, event, mode after)``; with ``variational`` (a drive whose flights
        integrate the variational equations, ``OwnFlight.variational``) also the
        Jacobian of the state after the impact with respect to ``y`` (``_saltation.through``):
        ``True`` the multipliers' (a coupled blow's by central differences), ``"steer"`` one that
        only steers Newton's method (a coupled blow's by forward differences, half the blows),
        ``"state"`` the variational flights' state, the Jacobian not wanted (a coupled blow's not
        taken: ``None`` in its place). The
        last flight is remembered: the same start asked again (an orbit's data, then its
        admissibility) is not flown again, nor one whose Jacobian is at least as good. The flight
        starts in the mode its state says (:func:`._shooting_data.block_mode`), its key too."""
        mode = block_mode(self, mode, y)
        try:
            key = (float(tau), mode, np.asarray(y, dtype=float).tobytes(), settings)
            hash(key)
        except TypeError:  # a mode that cannot be a key
            key = None
        last = self._last
        level = _JACOBIAN_LEVEL[variational]
        if key is not None and last is not None and last.key == key and (last.keep or not keep) and \
                last.level >= level:
            return last.flight if level else last.flight[:6]
        plain = self._state_settings(settings) if variational == "state" else None
        if plain is not None:  # the variational flight's state by its plain flight: no Jacobian taken
            out = self._fly(tau, mode, y, keep, False, plain)
        else:
            out = self._fly(tau, mode, y, keep, variational, settings)
        self._last = None if key is None else _LastFlight(key, keep, level, out)
        return out

    def _state_settings(self, settings=None):
        """The integrator of the plain flight whose state is the variational flight's with
        ``settings`` (``OwnFlight.state_settings``; not with coupled blows, whose ``"state"``
        flights skip only the blow's Jacobian), or ``None``."""
        own = self.drive.abilities.flight
        if self.coupled or not self.variational or own.state_settings is None:
            return None
        return own.state_settings(self.model, settings or self.settings)

    @property
    def state_flights(self) -> bool:
        """Whether the variational flights' state comes from a plain flight at its own tolerance
        (:meth:`_state_settings`: the oil circuit's flexible piston), so that :meth:`root_value`
        costs a fraction of :meth:`residual`."""
        return self._state_settings() is not None

    def _fly(self, tau, mode, y, keep, variational, settings):
        """:meth:`_flight`, flown."""
        model, drive, M = self.model, self.drive, self.M
        c = model.end_weights
        (q, onto), t, v, z = on_section(self, y), tau, y[M:2 * M], y[2 * M:]
        state = DriveState(mode, np.array(z, dtype=float))  # (mode: :meth:`_flight`'s, as the state says)
        pieces, events = [], []
        end = tau + HORIZON
        D = None
        if variational:  # the projection on the section
            D = np.eye(self.n)
            if onto:
                D[0, :M] -= c
        carries = self._carries  # (the flights started from D: their sensitivity the Jacobian so far)
        carry = bool(variational) and carries is not None and carries(model, settings or self.settings)
        exact = bool(variational) and C.root_settings(self) is not None  # (the maps' exact Jacobians)
        while True:
            fl = fly(model, drive, state, t, q, v, end, settings or self.settings, bool(variational),
                     start=D if carry else None)
            if keep:
                pieces.append(fl.piece)
            t, q, v = fl.t, fl.q, fl.v
            before = state.mode
            state = DriveState(state.mode, fl.z)
            if fl.end not in (ARRIVAL, EVENT):
                raise ValueError(f"no impact within {HORIZON:g} of t = {tau:.6g} under the drive: the "
                                 "piston does not come back to the stop")
            for e in fl.events:  # (an arrival's too: the levels crossed on its root, before the impact)
                state = drive.jump(state.mode, state.z, e, t, q, v)
                if keep:
                    events.append((t, e, state.mode, e.crossing_speed(q, v)))
            if fl.end == ARRIVAL:
                if variational:
                    D = through(model, drive, self.k, before, fl, None, None if carry else D, exact)
                break
            if variational:
                D = through(model, drive, self.k, before, fl, fl.events, None if carry else D, exact)
        arrival = (t, q.copy(), v.copy(), state)
        law = model.law
        if self.coupled:  # the blow and the drive's state together, the drive's map at its end
            from .coupled import blow_jacobian, blow_piece, blow_state

            blow_settings = settings or self.settings
            out, res, after = blow_state(model, drive, t, q, v, state, blow_settings)
            t_after = res.t_release
            if keep:  # (no piece to keep: not made)
                pieces.append(blow_piece(model, t, q, v, res))
            if variational == "state":
                return out, t_after, after.mode, arrival, pieces, events, None
            if variational:
                G = blow_jacobian(model, drive, t, q, v, state, blow_settings,
                                  forward=out if variational == "steer" or self.forward_blows else None,
                                  blow=(res, after))
                return out, t_after, after.mode, arrival, pieces, events, G @ D
            return out, t_after, after.mode, arrival, pieces, events
        if law.traits.restitution_in_kernel:
            qa, va = q, -law.traits.kernel_restitution(model) * v
            t_after = t
        else:
            p = drive.force(state.mode, state.z, q, v)
            ya, _, _ = law.impact_map(model, _constant_load(float(p)), 0.0, np.concatenate((q, v)))
            qa, va = np.asarray(ya[:M], dtype=float), np.asarray(ya[M:], dtype=float)
            t_after = t + float(law.window(model))
        after = drive.impact(state.mode, state.z, t_after, qa, va)
        if variational:  # the impact law (eq. 10) and the drive's map at the impact
            G = np.eye(self.n)
            G[M:2 * M, M:2 * M] *= -law.traits.kernel_restitution(model)
            G[2 * M:, 2 * M:] = map_jacobian(lambda zz: drive.impact(state.mode, zz, t_after, qa, va).z,
                                                   state.z)
            D = G @ D
        out = np.concatenate((qa, va, after.z))
        if variational:
            return out, t_after, after.mode, arrival, pieces, events, D
        return out, t_after, after.mode, arrival, pieces, events

    def _map(self, k, y):  # (the plain flights of the orbit's root: C.root_settings, default None)
        tau, mode = self.blocks[k]
        y_after, *_ = self._flight(tau, mode, y, settings=C.root_settings(self))
        return y_after

    # -- the problem --------------------------------------------------------------------------------
    def initial(self, guess, tol, max_iter):
        """The blocks' start times, modes and states: from a :class:`DrivenOrbit` of the same drive
        or of the same kind at other parameter values (its states, the drive's states, its impact
        times; the modes made again by this drive), from a run of :func:`impactbar.simulate`
        (continued from its end) or, without one, from rest on the stop (the rigid bar; a flexible bar
        from the rigid bar's orbit, its modes at rest), the motion followed impact after impact until
        the impact velocities settle (at most ``SETTLE_IMPACTS``; from the rigid bar's orbit
        ``SETTLE_LIFTED`` where the drive's flights are variational)."""
        model, drive, m, M = self.model, self.drive, self.impacts, self.M
        if isinstance(guess, DrivenOrbit):
            problem = guess._problem
            if isinstance(problem, ShootingProblem) and problem.impacts == m and problem.blocks and (
                    problem.drive == drive or (alike(problem.drive, drive) and problem.M == M
                                               and problem.coupled == self.coupled)):
                self.adopt(problem)  # (a neighbour's orbit, at other parameter values: its unknowns)
                return np.asarray(guess._unknowns, dtype=float).copy()
            if guess.impacts == 1 and m > 1 and isinstance(problem, ShootingProblem) and problem.blocks:
                tau, mode = problem.blocks[0]
                source = problem.sources[0] if problem.sources else None
                return self._settle(tau, mode, np.asarray(guess._unknowns, dtype=float), m - 1, source)
            raise ValueError("guess: an orbit of another problem (drive or impacts); give a run of "
                             "simulate under the drive")
        if guess is None and M > 1:  # the rigid bar's orbit, lifted, then followed
            rigid = ShootingProblem(model.with_(n_modes=0), drive, m, self.settings)
            Xr = rigid.initial(None, tol, max_iter)
            if rigid.variational and rigid.newton == "chord":  # (a start: its first Newton steps)
                Xr, _ = rigid._steered_chord(Xr, max(tol, rigid.accuracy), max_iter, C.LIFTED_HANDOVER)
            else:
                Xr = rigid.solve(Xr, tol, max_iter)
            y = np.zeros(self.n)
            y[0], y[M], y[2 * M:] = Xr[0], Xr[1], Xr[2:self.n - 2 * M + 2]
            tau, mode = rigid.blocks[0]
            # (the drive's state already periodic, only the modes start off it, at rest: what they
            # do after is linear and decays, which the chord's Jacobian carries; a few impacts give
            # them the blows' excitation, and the impact velocities agree to 2e-3, where the eight
            # impacts that the agreement to SETTLE_HANDOVER took on the preset's 8-mode orbit led
            # to the same chord steps)
            return self._settle(tau, mode, y, SETTLE_LIFTED if self.variational else SETTLE_IMPACTS)
        if guess is None:
            q, v = np.zeros(M), np.zeros(M)
            state = C.settle_start(self, q, v)  # (the drive's start, or one nearer the orbit)
            return self._settle(0.0, state.mode, np.concatenate((q, v, state.z)), SETTLE_IMPACTS)
        if hasattr(guess, "final_state") and hasattr(guess, "switch_kinds"):  # a run under the drive
            fin = guess.final_state
            q = np.asarray(fin.modal_displacement, dtype=float)
            v = np.asarray(fin.modal_velocity, dtype=float)
            if q.size != M:
                raise ValueError("guess: the run's model has another number of modes")
            final = guess._final_drive
            if final is None or guess.load != drive:
                raise ValueError("guess: a run under another drive")
            y = np.concatenate((q, v, final.z))
            return self._settle(float(guess.t_end), final.mode, y, SETTLE_IMPACTS)
        raise ValueError("guess must be a DrivenOrbit of the drive, a run of simulate under it or None")

    def _settle(self, tau, mode, y, n_max, source=None):
        """Follow the motion from ``y`` in ``mode`` at ``tau`` impact after impact, at most ``n_max``
        impacts (stopping once the impact velocities repeat every ``m`` impacts to ``1e-11``, or
        ``settle_handover``'s for a drive with variational flights; a drift too slow to tell at 1e-4
        carried to the switching surface ahead of it, :meth:`_carried`; ``m = 1``, variational: or
        every ``k > 1`` impacts, :func:`~._settling.other_period`, noted in ``settled_into``), and
        take the starts of the last ``m`` intervals as the blocks (with the impacts before them)."""
        m, M = self.impacts, self.M
        # a drive whose flights give Newton the exact Jacobian (variational equations) is handed
        # over once the impacts agree to 1e-4: Newton's quadratic convergence does the rest, where
        # a slow mode (the oil circuit's supply pressure, multiplier ~0.9) would take hundreds of
        # impacts to settle to 1e-11
        settle = SETTLE_HANDOVER if self.variational else 1e-11
        agree = C.settle_handover(self, settle)  # (the impacts' agreement: the drift's tests keep settle)
        # and where one real multiplier is left (the supply's), its mode is extrapolated away (Aitken's
        # delta-squared on the map's iterates, as in Steffensen's method; the quadratic's fixed point
        # where the steps' multiple still falls: dominant_limit) instead of followed
        accelerate = self.variational and m == 1 and n_max > m
        hist = [_Iterate(tau, mode, y, source)]
        speeds = []
        iterates = 1  # consecutive iterates of the map at the end of hist
        # the motion is followed only to hand Newton a start: where Newton's flights are the
        # variational ones, at a looser tolerance (SETTLE_RTOL, or ROOT_SETTLE_RTOL where the chord's
        # plain flights are the root's; Newton's own flights keep the drive's)
        loose = C.settle_settings(self, C.loose_settings(self.settings) if self.variational else None)
        budget, count = n_max, 0
        other, self.settled_into = self.variational and m == 1 and n_max > m, None
        while count < budget:  # (more impacts only while the drive's state drifts: SETTLE_DRIFT_IMPACTS)
            count += 1
            tau, mode, y, source, speed = self._follow(tau, mode, y, loose)
            hist.append(_Iterate(tau, mode, y, source))
            iterates += 1
            speeds.append(speed)
            if speeds[-1] <= 0.0:
                raise ValueError("find_orbit: the motion followed from the guess (from rest on the stop "
                                 "without one) does not strike the stop: give a guess")
            if n_max > m and len(speeds) > C.least_impacts(self, m) and \
                    abs(speeds[-1] - speeds[-1 - m]) <= agree * max(1.0, abs(speeds[-1])):
                ahead = y + DRIFT_AHEAD * (y - hist[-1 - m].y)  # (where the drift takes it next)
                if not (self.variational and (drifting(hist[-1 - 2 * m].y, hist[-1 - m].y, y, settle)
                                              or not surfaces_ahead(self.drive, mode, ahead, M))):
                    carried = self._carried(hist, loose) if self.variational else None
                    if carried is None:
                        break
                    hist.extend(carried)  # (the last state carried to the surface: followed on)
                    tau, mode, y, _ = hist[-1]
                    count, speeds, iterates = count + len(carried), [], 1
                    continue
                budget = max(budget, SETTLE_DRIFT_IMPACTS)
            elif other and (k := other_period(speeds, settle)):
                self.settled_into = (k, count)
                break
            # (the last three iterates in one mode, the drift carried in it; Aitken's limit the four)
            if accelerate and iterates >= 4 and mode == hist[-2].mode == hist[-3].mode:
                star = dominant_limit(*(h.y for h in hist[-4:])) if mode == hist[-4].mode else None
                if star is None:  # (steps that grow: no limit ahead, the drift carried to a surface)
                    star = expanding_to_surface(self.drive, mode, hist[-4].y, hist[-3].y, hist[-2].y, y, M)
                if star is not None and surfaces_ahead(self.drive, mode, star, M):  # (none jumped over)
                    y = star
                    hist[-1] = _Iterate(tau, mode, y, source)
                    iterates = 1
        blocks = hist[-m:]
        self.blocks = [(b.tau, b.mode) for b in blocks]
        self.sources = [b.source for b in blocks] if all(b.source is not None for b in blocks) else []
        return np.concatenate([np.asarray(b.y, dtype=float) for b in blocks])

    def _follow(self, tau, mode, y, settings):
        """One impact of the motion followed to a start: ``(tau, mode, y, source, speed)`` after it,
        ``source`` the impact's (:attr:`sources`) and ``speed`` the end's impact velocity."""
        M = self.M
        y, tau, mode, arrival, _, _ = self._flight(tau, mode, y, settings=settings)
        _, _, v_arrival, state_arrival = arrival
        source = (state_arrival.mode, state_arrival.z, tau, y[:M].copy(), y[M:2 * M].copy())
        return tau, mode, y, source, float(self.model.end_weights @ v_arrival)

    def _carried(self, hist, settings):
        """Where the drive's state at the end of ``hist`` (the motion followed to a start, settled at
        its tolerance) still drifts toward a surface of its mode, too slowly to tell at that
        tolerance (:func:`~._settling.drift_to_surface`): where a surface's value steps toward it
        steadily (:func:`~._settling.nearing`: the drift alone, where the state's steps still carry
        its fast parts' settling), the impacts followed on, at most :data:`~._settling.DRIFT_PROBE`,
        until the drift's steps fit one multiple, the last state carried to the surface; ``None``
        (the start as it was) where no surface nears so, the steps never fit or the surface lies past
        the drift's linear limit."""
        m, M, drive = self.impacts, self.M, self.drive
        if not nearing(drive, hist[-1].mode, hist[-1 - 2 * m].y, hist[-1 - m].y, hist[-1].y, M):
            return None
        seq = list(hist[-1 - 2 * m:])
        for _ in range(DRIFT_PROBE):
            last = seq[-1]
            tau, mode, y, source, _ = self._follow(last.tau, last.mode, last.y, settings)
            seq.append(_Iterate(tau, mode, y, source))
            if mode == seq[-1 - m].mode == seq[-1 - 2 * m].mode:
                far = drift_to_surface(drive, mode, seq[-1 - 2 * m].y, seq[-1 - m].y, y, M)
                if far is not None:
                    seq[-1] = _Iterate(tau, mode, far, source)
                    return seq[2 * m + 1:]
        return None

    def residual(self, X, settings=None, *, steer: bool = False, keep: bool = False):
        """The shooting residual and its Jacobian: from the variational equations where the drive's
        flights integrate them (``OwnFlight.variational``, ``_saltation.through``; ``settings``
        their integrator, default the problem's; with ``steer``, a Jacobian that only steers
        Newton's method: a coupled blow's by forward differences; with ``keep``, the flights kept
        whole, so that the orbit's data at ``X`` (:meth:`orbit`, one impact) takes the last one
        without flying it again), else by central differences."""
        n, m = self.n, self.impacts
        r = np.empty(X.size)
        J = np.zeros((X.size, X.size))
        step = FD_STEP_CLOSED if self.closed else FD_STEP_ODE
        for k in range(m):
            y = X[k * n:(k + 1) * n]
            nxt = ((k + 1) % m) * n
            if self.variational:
                tau, mode = self.blocks[k]
                y_after, _, _, _, _, _, Phi = self._flight(tau, mode, y, keep=keep,
                                                           variational="steer" if steer else True,
                                                           settings=settings)
                r[k * n:(k + 1) * n] = y_after - X[nxt:nxt + n]
                J[k * n:(k + 1) * n, k * n:(k + 1) * n] = Phi
                J[k * n:(k + 1) * n, nxt:nxt + n] -= np.eye(n)
                continue
            r[k * n:(k + 1) * n] = self._map(k, y) - X[nxt:nxt + n]
            for j in range(n):
                h = step * max(1.0, abs(y[j]))
                yp, ym = y.copy(), y.copy()
                yp[j] += h
                ym[j] -= h
                J[k * n:(k + 1) * n, k * n + j] = (self._map(k, yp) - self._map(k, ym)) / (2.0 * h)
            J[k * n:(k + 1) * n, nxt:nxt + n] -= np.eye(n)
        return r, J

    def value(self, X):
        """The shooting residual alone: the flights without their variational equations."""
        n, m = self.n, self.impacts
        r = np.empty(X.size)
        for k in range(m):
            nxt = ((k + 1) % m) * n
            r[k * n:(k + 1) * n] = self._map(k, X[k * n:(k + 1) * n]) - X[nxt:nxt + n]
        return r

    def solve(self, X, tol, max_iter):
        """Newton's method (:func:`~impactbar.drives.orbitproblem.newton`), the tolerance no finer than the
        flights' accuracy; where the flights integrate the variational equations and ``newton`` is
        ``"chord"``, the chord method (:func:`~impactbar.drives.orbitproblem.chord`) from the Jacobian of a
        variational flight at ``SETTLE_RTOL``, the residuals by plain flights (where it fails,
        Newton's method from the same start), then one Newton step with a variational flight; the
        Jacobians of the chord and of that step only steer, and take Magnus' coarser steps
        (``STEER_THETA``) and a coupled blow's forward differences; with coupled blows that step
        takes the chord's last Jacobian (a fresh one would cost a blow a column). A one-impact orbit
        whose variational flights' state is a plain flight's hands over to that step after a Newton
        step below ``CLOSING_HANDOVER``, and its multipliers' flight checks the root (:mod:`._closing`).
        A chord whose Newton steps stall (:class:`~impactbar.drives.orbitproblem.StalledIteration`)
        ends it: no root near ``X``."""
        tol = max(tol, self.accuracy)
        if not (self.variational and self.newton == "chord"):
            return newton(self.residual, X, self.positive, tol, max_iter)
        checked = self.impacts == 1 and self.state_flights  # (the multipliers' flight checks the root)
        try:
            root, J = self._steered_chord(X, tol, max_iter, C.CLOSING_HANDOVER if checked else 0.0)
        except StalledIteration:  # (its Newton steps circled: Newton's method from X circles alike,
            raise  # at some 1.5 times the cost of each step)
        except ValueError:  # (a plain flight off the way, a chord that does not converge: Newton's
            return newton(self.residual, X, self.positive, tol, max_iter)  # method of before, its verdict)
        if not checked:  # (no closing step where the chord's flights' root is the orbit's)
            return root if C.root_settings(self) is not None else self._close(root, J)
        return checked_root(self, self._close(root, J, tol), tol, max_iter)

    def _steered_chord(self, X, tol: float, max_iter: int, handover: float = 0.0):
        """:meth:`solve`'s chord from ``X``: the steering Jacobian of a variational flight at
        ``SETTLE_RTOL`` (its residual the chord's first where :func:`._closing.first_residual` lets
        it), the plain flights' root (with ``handover``, the iterate after a Newton step of at most that
        size) and the last Jacobian."""
        steer = self._steer(C.steer_settings(self, C.loose_settings(self.settings)))
        r, first = self.residual(X, settings=steer, steer=True)
        r = C.first_residual(self, X, steer, r)  # (the chord's first residual, where it may be this)
        return self._chord(X, first, tol, max_iter, r, handover, first_here=True)

    def polish(self, rough: DrivenOrbit, tol: float, max_iter: int):
        """The root of this problem from ``rough``, the orbit of a cheaper model of the same motion
        (:meth:`~impactbar.laws.abilities.NewtonStart.coarse_model`: a coupled blow on the lattice
        where this problem's are exact; theory §11, "The coupled blow"): its unknowns and blocks the
        start, the Jacobian of its residual there the chord's (within the coarse blow's error of this
        one's: some 1e-3 on the example, its lattice's blows ended where the exact ones end, so each
        step gains some three digits), the residuals this problem's. With one impact that Jacobian
        is ``rough``'s monodromy less the identity (its multipliers' flight: no flight more).

        Parameters
        ----------
        rough : DrivenOrbit
            An orbit of the same drive and impacts under the coarse model.
        tol : float
            Relative tolerance of the steps (no finer than the flights' accuracy).
        max_iter : int
            Largest number of chord steps.

        Returns
        -------
        numpy.ndarray, shape (m n,)
            The unknowns.

        Raises
        ------
        ValueError
            Where the chord steps do not converge (the caller then solves this problem from its
            own start).
        """
        X = self.initial(rough, tol, max_iter)
        if self.impacts == 1 and rough._monodromy is not None:
            first = rough._monodromy - np.eye(self.n)
        else:
            _, first = rough._problem.steering_residual(np.asarray(rough._unknowns, dtype=float))
        return self._close(*self._chord(X, first, max(tol, self.accuracy), max_iter))

    def _chord(self, X, first, tol: float, max_iter: int, first_value=None, handover: float = 0.0,
               first_here: bool = False):
        """:meth:`solve`'s chord method from ``X`` with the Jacobian ``first`` (taken again, steering,
        where its steps stop shrinking; ``first_value``, ``handover`` and ``first_here``
        :func:`~impactbar.drives.orbitproblem.chord`'s): the plain flights' root and the last Jacobian."""
        used = [first]

        def jacobian(XX):  # (the chord's Jacobian taken again: the last one kept)
            _, used[0] = self.steering_residual(XX)
            return used[0]

        return chord(self.value, jacobian, X, self.positive, tol, max_iter, first=first,
                     first_value=first_value, handover=handover, first_here=first_here,
                     first_bound=None if first_value is None else C.loose_contraction(self)), used[0]

    def _close(self, X, last, tol: float = 0.0):
        """:meth:`solve`'s closing step from the plain flights' root ``X``, ``last`` the chord's last
        Jacobian; with ``tol``, the steps after it that the check asks (:func:`._closing.close`)."""
        return close(self, X, last, tol)

    def root_value(self, X):
        """The shooting residual whose root the orbit is: by the variational flights' state where the
        drive's flights integrate the variational equations (Newton's last steps and the orbit's
        multipliers take those flights; by a plain flight at their tolerance where the drive has one,
        :attr:`state_flights`, else by the variational flights themselves), else :meth:`value`.

        Parameters
        ----------
        X : numpy.ndarray, shape (m n,)
            The unknowns: the state after each of the ``m`` impacts, stacked.

        Returns
        -------
        residual : numpy.ndarray, shape (m n,)
            Zero at the orbit.
        """
        if not self.variational:
            return self.value(X)
        return self._variational_value(X, None)

    def _variational_value(self, X, settings):
        """The shooting residual by the variational flights with ``settings`` (their state, which is
        not the plain flights': its Jacobian not taken)."""
        n, m = self.n, self.impacts
        r = np.empty(X.size)
        for k in range(m):
            tau, mode = self.blocks[k]
            nxt = ((k + 1) % m) * n
            y_after, *_ = self._flight(tau, mode, X[k * n:(k + 1) * n], variational="state",
                                       settings=settings)
            r[k * n:(k + 1) * n] = y_after - X[nxt:nxt + n]
        return r

    def steering_residual(self, X):
        """The shooting residual and a Jacobian that only steers Newton's method (a corrector's
        step, not the multipliers'): where the drive's flights integrate the variational equations,
        with Magnus' coarser steps (``STEER_THETA``; the residual the same flights') and a coupled
        blow's Jacobian by forward differences; else :meth:`residual`'s.

        Parameters
        ----------
        X : numpy.ndarray, shape (m n,)
            The unknowns.

        Returns
        -------
        r : numpy.ndarray, shape (m n,)
        J : numpy.ndarray, shape (m n, m n)
        """
        if not self.variational:
            return self.residual(X)
        return self.residual(X, settings=self._steer(self.settings), steer=True)

    @staticmethod
    def _steer(settings: FlightSettings) -> FlightSettings:
        """``settings`` with the Magnus steps of a Jacobian that only steers Newton's method
        (``STEER_THETA``; a drive whose variational flights integrate ``Phi`` beside the state, the
        rigid piston's CVODE, reads none)."""
        return dataclasses.replace(settings, magnus_theta=STEER_THETA)

    def unknowns(self, orbit):
        """The unknowns of a found orbit of this problem."""
        return np.asarray(orbit._unknowns, dtype=float).copy()

    def adopt(self, other: OrbitProblem) -> ShootingProblem:
        """The blocks' start times and modes of ``other`` (each of its blocks for each of ours, in
        turn: a doubled branch repeats the one-impact orbit's), each mode made again by this drive's
        map at the impact before the block (its scheduled events follow this drive's parameters)."""
        blocks = getattr(other, "blocks", None)
        if not blocks:
            return self
        sources = getattr(other, "sources", None) or []
        self.blocks, self.sources = [], []
        for k in range(self.impacts):
            tau, mode = blocks[k % len(blocks)]
            if sources and not self.coupled:  # (a coupled blow's mode is the one at its end: kept)
                source = sources[k % len(sources)]
                arr_mode, z, _, q, v = source
                mode = self.drive.impact(arr_mode, z, tau, q, v).mode
                self.sources.append(source)
            self.blocks.append((tau, mode))
        if _same_problem(self, other):  # its last flight is ours too
            self._last = other._last
        return self

    def admissibility(self, X, k):
        """By construction each flight ends at its first arrival and each event is its first
        crossing; an arrival must come forward (``"backward impact"``), and the end must leave the
        stop after it (``"sticks"``)."""
        n, M = self.n, self.M
        c = self.model.end_weights
        y = X[k * n:(k + 1) * n]
        tau, mode = self.blocks[k]
        y_after, _, _, (_, _, v_arrival, _), _, _ = self._flight(tau, mode, y)
        if float(c @ v_arrival) <= 0.0:
            return Admissibility.BACKWARD_IMPACT
        if c @ y_after[M:2 * M] >= 0.0 and self.model.R > 0.0 and \
                self.model.law.traits.restitution_in_kernel:
            return Admissibility.STICKS
        return Admissibility.ADMISSIBLE

    def orbit(self, X, multipliers: bool = True) -> OrbitData:
        """The period, durations, states, switches and the multipliers of the return map on the
        section after the impacts (the product of the blocks' Jacobians projected on ``c . q = 0``
        times the drive's states); without ``multipliers``, ``nan`` in their place and no
        monodromy (no Jacobian computed): :func:`._shooting_data.orbit_data`. The blocks' modes
        become those their flights from ``X`` start in (:meth:`start_modes`: the same flights), so that
        the orbit's discrete state, read from :attr:`blocks`, is its flights'."""
        self.blocks = list(zip((tau for tau, _ in self.blocks), self.start_modes(X), strict=True))
        return orbit_data(self, X, multipliers)

    def start_modes(self, X) -> list:
        """Each block's mode its flight from ``X`` starts in (:func:`._shooting_data.start_modes`)."""
        return start_modes(self, X)

    def blow_records(self, X):
        """The records of the period's blows in order (a drive with state under a law whose contact
        takes time: each blow solved with the drive's state), ``None`` otherwise."""
        if not self.coupled:
            return None
        return [p.record for p in self.flights(X) if hasattr(p, "record")]

    def flights(self, X) -> list:
        """The period's flights as the drive's flights give them (their own times: each block
        from its start ``tau_k``), e.g. for the drive's ``border_tests`` (its abilities)."""
        n = self.n
        out = []
        for k in range(self.impacts):
            tau, mode = self.blocks[k]
            _, _, _, _, pieces, *_ = self._flight(tau, mode, X[k * n:(k + 1) * n], keep=True)
            out += pieces
        return out

    def event_pattern(self, X) -> tuple:
        """The period's sequence of the drive's discrete states: per block its start mode, then
        each event's name and the mode after it, in order. Two solutions (or two flights from
        nearby unknowns) with the same pattern lie on one smooth piece of the problem; a changed
        pattern is a border collision (a switch changing order, a relief valve opening, an
        accumulator emptying, a block's state passing a level: its start mode,
        :meth:`start_modes`, the one its flight starts in): :func:`._shooting_data.event_pattern`."""
        return event_pattern(self, X)

    def pieces(self, X):
        """The flights of the period as ``(t0, t1, f)``, ``f(t) -> (q, v)`` at orbit times."""
        n, m = self.n, self.impacts
        out = []
        shift = 0.0
        for k in range(m):
            tau, mode = self.blocks[k]
            y = X[k * n:(k + 1) * n]
            _, t_after, _, _, pieces, _ = self._flight(tau, mode, y, keep=True)
            for p in pieces:
                off = shift - tau
                out.append((p.t0 + off, p.t_end + off, lambda tt, p=p, off=off: p.modal(tt - off)))
            shift += t_after - tau
        return out

