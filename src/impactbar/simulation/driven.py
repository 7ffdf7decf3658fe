"""Simulation under a drive (theory §10): the event-driven run of any :class:`~impactbar.Drive`,
whose result is a :class:`~impactbar.simulation.driven_trajectory.DrivenTrajectory`.

The run calls only the drive's interface (:mod:`impactbar.drives.base`):

- **a force constant between events** (no continuous state, e.g. the valve of
  :class:`~impactbar.PositionSwitchedDrive`): each flight is a piece of the ordinary driver of
  :mod:`impactbar.simulation.simulate` (certified impact search, chatter, sustained contact, every
  impact law) under that constant force, run until the drive's next event, whose time comes in
  closed form (:meth:`~impactbar.drives.DriveEvent.first_time`: no crossing is missed, each is
  refined to rounding) or, for an event surface without one, by bracketing on the closed-form
  flight; at the event the drive's map acts, at each impact :meth:`~impactbar.Drive.impact`. A drive
  with a compiled event loop (:attr:`~impactbar.Drive.abilities`) runs there under an
  instantaneous law, handing back the pieces it does not resolve (the same pieces, impacts and
  switches; switch ``simulate.valve_loop``).
- **a drive with state** ``z``: the bar's modes and ``z`` are integrated together by scipy's
  ``solve_ivp`` (:func:`impactbar.drives.flight.fly`, a stiff method), the arrivals and the drive's
  events located to the integrator's tolerance; at an impact the paper's law acts (eq. 10) and the
  rigid piston rests on the stop while the drive presses it; under a law whose contact takes time
  (the wave law, the rod-rock law) the blow and the drive's state are solved together
  (:meth:`~impactbar.laws.abilities.CoupledBlow.driven_contact`, theory §11, "The coupled blow"), the run's
  piece over the blow a :class:`~impactbar.simulation.blows.BlowPiece`. A flexible bar held on the
  stop is refused for such a drive (for now).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np

from .._shared.status import RunStatus
from ..drives.base import DriveState, FlightKernel, KernelRun
from ..drives.flight import END, EVENT, QuadratureRestPiece, RestPiece
from ..dynamics.implementations import use_fast
from ..model import BarModel
from .blows import check_coupling, fly_and_switch, run_coupled
from .driven_trajectory import DrivenTrajectory as DrivenTrajectory
from .trajectory import Trajectory

__all__ = ["DrivenTrajectory", "Driver", "run_drive", "run_stateful"]


class Driver(NamedTuple):
    """The ordinary driver of :mod:`impactbar.simulation.simulate` as a drive's run uses it.

    Attributes
    ----------
    core_for : callable
        ``core_for(model, load)``: the driver's data of a (model, load) pair.
    run : callable
        ``run(core, q, v, t, t_stop, max_impacts)``: a run of the driver (a
        :class:`~impactbar.Trajectory`).
    push_off : callable
        ``push_off(c, q)``: refuses a start through the stop (shifts one within rounding off it).
    make_state : callable
        ``make_state(q, v)``: an :class:`~impactbar.InitialState`.
    tail : float
        The driver's chatter tolerance.
    """

    core_for: Callable
    run: Callable
    push_off: Callable
    make_state: Callable
    tail: float


class _State:
    """A modal state as the pieces hand it on (the driver's ``InitialState`` has the same fields)."""

    __slots__ = ("modal_displacement", "modal_velocity")

    def __init__(self, q, v):
        self.modal_displacement = q
        self.modal_velocity = v


class _RigidFlight:
    """One constant-force piece of the rigid bar under the paper's law, in closed form (theory §10):
    the same fields and evaluations as a :class:`~impactbar.Trajectory` piece."""

    __slots__ = ("t0", "t_end", "q", "v", "level", "d", "impact_times", "impact_velocities",
                 "final_state", "status", "stuck")

    @property
    def n_impacts(self) -> int:
        return int(self.impact_times.size)

    def _at(self, t):
        if self.stuck:
            return np.zeros_like(t), np.zeros_like(t)
        e = -np.expm1(-self.d * (t - self.t0)) / self.d if self.d else t - self.t0
        h = t - self.t0
        c = (h - e) / self.d if self.d else 0.5 * h * h
        return self.q + self.v * e + self.level * c, self.v * (1.0 - self.d * e) + self.level * e

    def modal(self, t):
        q, v = self._at(np.atleast_1d(np.asarray(t, dtype=float)))
        return q[None, :], v[None, :]

    def force(self, t):
        return np.full(np.atleast_1d(t).shape, float(self.level))

    def end_displacement(self, t):
        q, _ = self._at(np.asarray(t, dtype=float))
        return np.minimum(q, 0.0)

    def end_velocity(self, t):
        _, v = self._at(np.asarray(t, dtype=float))
        return v


def rigid_piece(model: BarModel):
    """The piece function of :func:`run_drive` for the rigid bar under the paper's law, in closed
    form: the impact is the first rising crossing of ``q_0`` through 0 (the same monotonicity
    argument as the switch's, theory §10), then ``v -> -R v`` (eq. 10); with the force pressing and
    a rebound too small to resolve (or ``R = 0``), the piston rests on the stop until ``t_stop``."""
    from ..drives.valve import first_rising_crossing

    d, R = model.d, model.law.traits.kernel_restitution(model)

    def piece(level, q, v, t, t_stop):
        f = object.__new__(_RigidFlight)
        q0, v0 = float(q[0]), float(v[0])
        f.t0, f.level, f.d = t, level, d
        resting = q0 >= 0.0 and abs(v0) <= 1e-13 * (1.0 + abs(level)) and level > 0.0
        f.stuck = resting
        f.q, f.v = (0.0, 0.0) if resting else (q0, v0)
        t_imp = math.inf if resting else t + first_rising_crossing(d, q0, v0, level, 0.0)
        if t_imp < t_stop:
            f.t_end = t_imp
            _, vm = f._at(np.array(t_imp))
            vm = float(vm)
            f.impact_times = np.array([t_imp])
            f.impact_velocities = np.array([vm])
            f.status = RunStatus.MAX_IMPACTS
            vp = -R * vm
            if level > 0.0 and abs(vp) * vp_scale(d, level) <= 1e-13 * (1.0 + t_imp):
                vp = 0.0  # the rebound lasts less than rounding: the piston rests on the stop
            f.final_state = _State(np.zeros(1), np.array([vp]))
        else:
            f.t_end = t_stop
            f.impact_times = f.impact_velocities = np.zeros(0)
            f.status = RunStatus.T_END
            qe, ve = f._at(np.array(t_stop))
            f.final_state = _State(np.array([min(float(qe), 0.0)]), np.array([float(ve)]))
        return f

    return piece


def vp_scale(d: float, level: float) -> float:
    """Duration of a rebound per unit rebound speed under a pressing force (``2 / level``)."""
    return 2.0 / level


class _Flight:
    """One constant-force flight of the flexible bar that a compiled event loop followed (no
    contact in it): evaluated by the driver's exact flow from its start (eq. 8)."""

    __slots__ = ("core", "t0", "t_end", "q", "v")

    def __init__(self, core, t0, t_end, q, v):
        self.core, self.t0, self.t_end, self.q, self.v = core, t0, t_end, q, v

    def modal(self, t):
        from .trajectory import _FREE

        return self.core.propagate(_FREE, self.t0, self.q, self.v, np.atleast_1d(np.asarray(t, dtype=float)))

    def force(self, t):
        return np.full(np.atleast_1d(t).shape, float(self.core.load.p0))

    def end_displacement(self, t):
        q, _ = self.modal(t)
        return np.minimum(self.core.c @ q, 0.0)

    def end_velocity(self, t):
        _, v = self.modal(t)
        return self.core.c @ v


class _Pieces(Sequence):
    """The pieces of a driven run: those the Python loop ran (objects) and those a compiled loop
    logged (arrays of their starts, made into flights when asked for)."""

    def __init__(self, blocks, make):
        self._blocks = blocks  # ("py", piece) or ("k", t0, t1, code, q, v)
        self._make = make  # (t0, t1, code, q, v) -> a flight
        sizes = [1 if kind == "py" else first.size for kind, first, *_ in blocks]
        self._ends = np.cumsum(sizes, dtype=np.int64)
        self.starts = np.concatenate([np.array([first.t0]) if kind == "py" else first
                                      for kind, first, *_ in blocks]) if blocks else np.zeros(0)

    def __len__(self):
        return int(self._ends[-1]) if self._ends.size else 0

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        i = int(i)
        if i < 0:
            i += len(self)
        if not 0 <= i < len(self):
            raise IndexError("piece index out of range")
        k = int(np.searchsorted(self._ends, i, side="right"))
        kind, *rest = self._blocks[k]
        if kind == "py":
            (piece,) = rest
            return piece
        t0, t1, code, q, v = rest
        j = i - (int(self._ends[k - 1]) if k else 0)
        return self._make(float(t0[j]), float(t1[j]), int(code[j]), q[j], v[j])


class _Run:
    """The state and the logs of a run under a drive; :meth:`step` runs one flight of a drive
    without state (the Python reference, and the fallback of a compiled loop)."""

    def __init__(self, model, drive, q, v, t0, t_end, max_imp):
        self.model, self.drive = model, drive
        self.state = drive.start(model, q, v)
        self.q, self.v, self.t, self.t0, self.t_end, self.max_imp = q, v, t0, t0, t_end, max_imp
        self.blocks: list = []
        self.imp_t: list = []
        self.imp_v: list = []
        self.sw_t: list = []
        self.sw_y: list = []
        self.sw_k: list = []
        self.rests: list = []  # a drive with state: the rigid piston at rest on the stop
        self.n_imp = 0
        self.status = RunStatus.T_END
        self.done = False

    def switch(self, new: DriveState, t: float) -> None:
        """Take the drive's new state, logging a switch where its mode's name changes."""
        drive = self.drive
        name = drive.mode_name(new.mode)
        if name != drive.mode_name(self.state.mode):
            self.sw_t.append(t)
            self.sw_y.append(-float(self.q[0]))
            self.sw_k.append(name)
        self.state = new

    def step(self, piece) -> None:
        """Run the next flight with ``piece`` (the ordinary driver under the drive's constant force)
        until the drive's next event, and apply the drive's map at its end."""
        drive, q, v, t = self.drive, self.q, self.v, self.t
        mode, z = self.state
        level = drive.force(mode, z, q, v)
        events = drive.events(mode)
        t_next = self.t_end
        times = []
        for e in events:
            te = e.first_time(self.model.d, level, t, q, v)
            if math.isnan(te):  # an event surface without a closed form: bracketed
                from ..drives.flight import bracket_event

                te = bracket_event(e, self.model, level, t, q, v, z, self.t_end)
            times.append(te)
            t_next = min(t_next, te)
        traj = piece(level, q, v, t, t_next)
        self.blocks.append(("py", traj))
        state = traj.final_state
        self.q = q = state.modal_displacement
        self.v = state.modal_velocity
        self.t = t = traj.t_end
        if traj.n_impacts and (t < t_next or traj.status == RunStatus.MAX_IMPACTS):
            self.imp_t.extend(traj.impact_times.tolist())
            self.imp_v.extend(traj.impact_velocities.tolist())
            self.n_imp += traj.n_impacts
            if self.n_imp >= self.max_imp:  # the run ends at the impact, the drive as it arrived
                self.status = RunStatus.MAX_IMPACTS
                self.done = True
                return
            self.switch(drive.impact(mode, z, t, q, self.v), t)
        elif t >= self.t_end:
            self.done = True
            return
        else:  # the drive's events due now, in its order
            new = self.state
            for e, te in zip(events, times, strict=True):
                if te == t:
                    new = drive.jump(new.mode, new.z, e, t, q, self.v)
            self.switch(new, t)

    def absorb(self, res: KernelRun) -> None:
        """Take what a compiled loop did."""
        self.imp_t.extend(res.impact_times.tolist())
        self.imp_v.extend(res.impact_velocities.tolist())
        self.sw_t.extend(res.switch_times.tolist())
        self.sw_y.extend(res.switch_gaps.tolist())
        self.sw_k.extend(res.switch_names)
        for block in res.pieces:
            self.blocks.append(("k", *block))
        self.state, self.n_imp = res.state, res.n_impacts
        self.t, self.q, self.v = res.t, res.q, res.v

    def result(self, make_state, make_piece) -> DrivenTrajectory:
        pieces = _Pieces(self.blocks, make_piece)
        runs = [piece for kind, piece, *_ in self.blocks if kind == "py" and isinstance(piece, Trajectory)]
        spans = [r.contact_intervals for r in runs if r.contact_intervals.size] + \
            [np.array(self.rests, dtype=float).reshape(-1, 2)]
        contact = np.concatenate(spans)
        retries = sum(r.n_release_retries for r in runs)
        return DrivenTrajectory(
            model=self.model, load=self.drive, t0=self.t0, t_end=self.t, impact_times=np.array(self.imp_t),
            impact_velocities=np.array(self.imp_v), contact_intervals=contact,
            final_state=make_state(np.array(self.q, dtype=float), np.array(self.v, dtype=float)),
            status=self.status, _core=None, _segments=None, n_release_retries=retries,
            switch_times=np.array(self.sw_t), switch_positions=np.array(self.sw_y),
            switch_kinds=tuple(self.sw_k),
            final_mode=self.drive.mode_name(self.state.mode), pieces=pieces,
            final_drive_state=np.array(self.state.z, dtype=float), _final_drive=self.state)


def run_drive(model: BarModel, drive, q, v, t0: float, t_end: float, max_imp: int,
              driver: Driver, settings=None, histories: bool = True) -> DrivenTrajectory:
    """A drive's run (module docstring): a drive with state by ``solve_ivp``'s flights or its own
    (:func:`run_stateful`, with ``settings``, default the drive's integrator); a force constant
    between events over pieces of the ordinary driver under that force (``driver``), with the drive's
    compiled loop where it has one (its ability :class:`~impactbar.drives.abilities.CompiledLoop`,
    switch ``simulate.valve_loop``, an instantaneous law), in Python piece by piece otherwise
    (:func:`run_pieces`). ``histories``: as :func:`run_stateful` takes it."""
    if not drive.traits.piecewise_constant:
        return run_stateful(model, drive, q, v, t0, t_end, max_imp, driver.make_state, settings, histories)
    from ..loads import FourierLoad

    law = model.law  # an instantaneous law the kernel applies, v -> -R v (eq. 10): closed forms
    rigid = model.n_modes == 0 and law.traits.restitution_in_kernel and use_fast("simulate.valve_rigid")
    cores: dict = {}

    def core_of(level):
        core = cores.get(level)
        if core is None:
            core = cores[level] = driver.core_for(model, FourierLoad(level, []))
        return core

    if rigid:
        piece = rigid_piece(model)
    else:
        def piece(level, q, v, t, t_stop):
            q = np.array(q, dtype=float)
            v = np.array(v, dtype=float)
            core = core_of(level)
            driver.push_off(core.c, q)
            return driver.run(core, q, v, t, t_stop, 1)

    loop = drive.abilities.compiled_loop
    if loop is None or not law.traits.restitution_in_kernel or not use_fast("simulate.valve_loop"):
        return run_pieces(model, drive, q, v, t0, t_end, max_imp, piece, driver.make_state)
    level_cores = tuple(core_of(lv) for lv in loop.levels)
    first = level_cores[0]
    kernel = FlightKernel(loads=tuple(tuple(core.data) for core in level_cores), basis=tuple(first.free.view),
                          R=first.R, c=first.c, tail=driver.tail, rigid=rigid,
                          fast_search=use_fast("simulate.impact_search"))
    return run_pieces(model, drive, q, v, t0, t_end, max_imp, piece, driver.make_state, kernel, level_cores,
                      loop)


def run_pieces(model: BarModel, drive, q, v, t0: float, t_end: float, max_imp: int, piece, make_state,
               kernel: FlightKernel | None = None, cores=None, compiled=None) -> DrivenTrajectory:
    """The event-driven run of a drive whose force is constant between events (module docstring).

    ``piece(level, q, v, t, t_stop)`` runs the ordinary driver under the constant force ``level``
    from ``(q, v)`` at ``t`` until ``t_stop`` or its first impact, and returns its
    :class:`~impactbar.Trajectory` (or a :func:`rigid_piece` flight); ``make_state(q, v)`` makes the
    final :class:`~impactbar.InitialState`. With ``compiled``, the drive's compiled loop (its ability
    :class:`~impactbar.drives.abilities.CompiledLoop`), and ``kernel`` (the driver's data of its
    ``levels``, ``cores`` their driver objects) that loop runs the flights it resolves, and this loop
    the others, one at a time.
    """
    loop = _Run(model, drive, q, v, t0, t_end, max_imp)
    runner = compiled.build(model, kernel) if compiled is not None and kernel is not None else None
    if runner is not None:
        loop.q, loop.v = np.array(q, dtype=float), np.array(v, dtype=float)
    while loop.t < t_end and not loop.done:
        if runner is not None:
            res = runner.run(loop.state, loop.t, np.array(loop.q, dtype=float), np.array(loop.v, dtype=float),
                             t_end, loop.n_imp, loop.max_imp)
            loop.absorb(res)
            if res.status == KernelRun.MAX_IMPACTS:
                loop.status = RunStatus.MAX_IMPACTS
                break
            if res.status == KernelRun.DONE:
                break
            if loop.t >= t_end:  # pragma: no cover - the compiled loop reports DONE there
                break
        loop.step(piece)
    make_piece = None
    if runner is not None:
        levels = compiled.levels
        L = len(levels)
        if kernel.rigid:
            d = model.d

            def make_piece(t0, t1, code, q, v):
                f = object.__new__(_RigidFlight)
                f.t0, f.t_end, f.level, f.d = t0, t1, levels[code % L], d
                f.stuck = code >= L
                f.q, f.v = (0.0, 0.0) if f.stuck else (float(q[0]), float(v[0]))
                return f
        else:
            def make_piece(t0, t1, code, q, v):
                return _Flight(cores[code], t0, t1, q, v)

    return loop.result(make_state, make_piece)


# --------------------------------------------------------------------------------------------------
# a drive with state
# --------------------------------------------------------------------------------------------------
#: a rebound slower than this (relative to the arrival speed, or absolute) ends in rest on the stop
REST_SPEED = 1e-9
#: more impacts than this within ``CHATTER_WINDOW`` of each other: a flexible bar held on the stop
CHATTER_IMPACTS = 200
CHATTER_WINDOW = 1e-6
#: the methods of scipy's ``solve_ivp``
_SCIPY_METHODS = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")


def run_stateful(model: BarModel, drive, q, v, t0: float, t_end: float, max_imp: int, make_state,
                 settings=None, histories: bool = True) -> DrivenTrajectory:
    """The event-driven run of a drive with state (module docstring): flights by
    :func:`impactbar.drives.flight.fly`, the paper's impact law (eq. 10) at each arrival, the
    drive's maps at its events and impacts; a rigid piston whose rebound is slower than
    ``REST_SPEED`` while the drive presses it rests on the stop until the force turns or a drive
    event comes, as does one that starts on the stop at rest (``c q >= 0``, ``|c q'| <= REST_SPEED``)
    while the drive presses it.

    Under a law whose contact takes time each arrival is a blow solved together with the drive's
    state (:func:`impactbar.simulation.blows.driven_blow`); without ``histories`` each blow is kept
    as its :class:`~impactbar.simulation.blows.BlowSummary` (the drive's pieces over it released once
    it ends), the flights as they are.

    Raises
    ------
    ValueError
        A drive or a law that cannot solve a blow together (:func:`check_coupling`), or where a
        flexible bar would be held on the stop.
    """
    law = model.law
    if not law.traits.restitution_in_kernel:
        check_coupling(model, drive)
        return run_coupled(model, drive, q, v, t0, t_end, max_imp, make_state, settings, _Run, histories)
    R = law.traits.kernel_restitution(model)
    c = model.end_weights
    M = model.n_modes + 1
    settings = settings if settings is not None else drive.traits.integrator
    loop = _Run(model, drive, q, v, t0, t_end, max_imp)
    loop.q, loop.v = np.array(q, dtype=float), np.array(v, dtype=float)
    if M == 1 and float(c @ loop.q) >= 0.0 and abs(float(c @ loop.v)) <= REST_SPEED and _pressed(drive, loop):
        _rest(model, drive, loop, t_end, settings)  # a start on the stop at rest: no arrival to find
    recent: list[float] = []
    while loop.t < t_end and not loop.done:
        fl = fly_and_switch(model, drive, loop, t_end, settings)
        if fl.end == END:
            break
        if fl.end == EVENT:
            continue
        # an arrival: the paper's law, then the drive's map
        arrival = float(c @ fl.v)
        loop.imp_t.append(fl.t)
        loop.imp_v.append(arrival)
        loop.n_imp += 1
        v_after = -R * fl.v
        recent = [tt for tt in recent if fl.t - tt <= CHATTER_WINDOW] + [fl.t]
        if loop.n_imp >= max_imp:
            loop.v = v_after
            loop.status = RunStatus.MAX_IMPACTS
            break
        loop.v = v_after
        loop.switch(drive.impact(loop.state.mode, loop.state.z, fl.t, fl.q, v_after), fl.t)
        pressing = _pressed(drive, loop)
        slow = abs(float(c @ v_after)) <= REST_SPEED * max(1.0, arrival)
        if M > 1 and (len(recent) > CHATTER_IMPACTS or (slow and pressing)):
            raise ValueError(f"the flexible bar is held on the stop at t = {fl.t:.6g} under a drive with "
                             "state: sustained contact is not supported for such a drive yet (use "
                             "n_modes = 0)")
        if M == 1 and slow and pressing:
            _rest(model, drive, loop, t_end, settings)
    return loop.result(make_state, None)


def _pressed(drive, loop) -> bool:
    """Whether the drive's force, in its state now, presses the bar at rest where it is onto the stop."""
    return drive.force(loop.state.mode, loop.state.z, loop.q, np.zeros(loop.q.size)) > 0.0


def _rest(model, drive, loop, t_end, settings) -> None:
    """The rigid piston at rest on the stop while the drive presses it (its velocity set to 0 here):
    ``z`` integrated with ``q = q' = 0`` until the force turns (falls through 0), a drive event or
    ``t_end``; with it the drive's own quadratures (its ability
    :class:`~impactbar.drives.abilities.Quadratures`: the oil circuit's energy account), from 0. A
    drive whose flights have an integrator of their own (the circuit's CVODE) rests under scipy's
    ``Radau`` at its tolerances."""
    from scipy.integrate import solve_ivp

    mode, z = loop.state
    q0, v0 = np.zeros(1), np.zeros(1)
    t = loop.t
    events = drive.events(mode)
    own = drive.abilities.quadratures
    k, nq = len(z), int(own.count) if len(z) and own is not None else 0

    def push(tt, y):
        return drive.force(mode, y[:k], q0, v0)

    push.terminal, push.direction = True, -1
    fns = [push]
    for e in events:
        def g(tt, y, e=e):
            return e.value(tt, q0, v0, y[:k])

        g.terminal, g.direction = True, e.direction
        fns.append(g)
    totals = None
    if k:
        extra = {} if model.piston is None else {"model": model}

        def f(tt, y):
            zz = y[:k]
            rate = drive.rate(mode, zz, q0, v0, **extra)
            return np.concatenate((rate, own.integrands(mode, zz, q0, v0, **extra))) if nq else rate

        method = settings.method if settings.method in _SCIPY_METHODS else "Radau"
        sol = solve_ivp(f, (t, t_end), np.concatenate((np.asarray(z, dtype=float), np.zeros(nq))),
                        method=method, rtol=settings.rtol, atol=settings.atol, events=fns,
                        dense_output=True)
        if sol.status < 0:
            raise ValueError(f"the drive's state could not be integrated with the piston at rest on the "
                             f"stop from t = {t:.6g}: {sol.message}")
        te, z_end, dense = float(sol.t[-1]), sol.y[:k, -1].copy(), sol.sol
        totals = sol.y[k:, -1].copy()
        hit = [i for i, tt in enumerate(sol.t_events) if tt.size] if sol.status == 1 else []
    else:  # no state: only the drive's scheduled or surface events can end the rest
        times = [e.first_time(model.d, 0.0, t, q0, v0) for e in events]
        te = min([tt for tt in times if not math.isnan(tt)] + [t_end])
        z_end, dense = z, None
        hit = [i + 1 for i, tt in enumerate(times) if tt == te]
    piece = RestPiece(t, te, dense, z, 1, model.end_weights) if not nq else \
        QuadratureRestPiece(t, te, dense, z, 1, model.end_weights, totals, own.piston_work)
    loop.blocks.append(("py", piece))
    loop.rests.append((t, te))
    loop.t, loop.q, loop.v = te, q0.copy(), v0.copy()
    loop.state = DriveState(mode, z_end)
    fired = [events[i - 1] for i in hit if i > 0]
    if fired:
        new = loop.state
        for e in fired:
            new = drive.jump(new.mode, new.z, e, te, loop.q, loop.v)
        loop.switch(new, te)

