"""Simulation under a position-switched drive: the valve's event loop (theory §10).

Between events the force is constant, so every mode moves in closed form (eq. 8) and the
existing driver of :mod:`impactbar.simulation.simulate` (certified impact search, chatter,
sustained contact, every impact law) follows the bar under that constant force. Around it this
module runs the valve: the rising crossing of the switch position by the gap ``y = -q_0`` is found in
closed form (``impactbar.drives.switched.first_rising_crossing``: the gap's rate is monotone under a
constant force, so no crossing is missed, and it is refined to rounding), each switch takes effect
``delay`` after its trigger, and each impact triggers the switch to return.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .._shared.status import RunStatus
from ..drives.switched import RETURN, STROKE, PositionSwitchedDrive
from ..dynamics import _switchkernel as SK
from ..dynamics._switchkernel import first_rising_crossing
from ..model import BarModel

__all__ = ["SwitchedTrajectory", "run_switched", "run_compiled"]

_KIND = {STROKE: "stroke", RETURN: "return"}


@dataclass(frozen=True, eq=False)
class SwitchedTrajectory:
    """The result of :func:`impactbar.simulate` under a
    :class:`~impactbar.PositionSwitchedDrive` (theory §10).

    Attributes
    ----------
    model : BarModel
    drive : PositionSwitchedDrive
    t0, t_end : float
        Start and end of the run.
    impact_times, impact_velocities : numpy.ndarray, shape (I,)
        Impacts and the struck end's velocity just before each, as in
        :class:`~impactbar.Trajectory`.
    switch_times : numpy.ndarray, shape (S,)
        Times at which the valve switched (took effect).
    switch_positions : numpy.ndarray, shape (S,)
        The gap ``y = -q_0`` there.
    switch_kinds : tuple of str, length S
        ``"stroke"`` or ``"return"``: the state the valve switched to.
    final_state : InitialState
        Modal state at ``t_end``.
    final_valve : str
        The valve's state at ``t_end``.
    status : RunStatus
        Why the run stopped.
    pieces : sequence
        The constant-force pieces, in order: each has ``t0``, ``t_end``, ``end_displacement(t)``
        and ``end_velocity(t)`` (a run of the ordinary driver, a :class:`~impactbar.Trajectory`,
        where the piece has a contact; else a closed-form flight); ``pieces.starts`` holds their
        ``t0``.

    Examples
    --------
    >>> from impactbar import BarModel, InitialState, PositionSwitchedDrive, simulate
    >>> drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    >>> run = simulate(BarModel(s=10.0, d=0.05, R=0.5, n_modes=0), drive,
    ...                InitialState.rigid(-0.5, 0.0), 60.0)
    >>> type(run).__name__, run.n_impacts > 5
    ('SwitchedTrajectory', True)
    """

    model: BarModel
    drive: PositionSwitchedDrive
    t0: float
    t_end: float
    impact_times: np.ndarray
    impact_velocities: np.ndarray
    switch_times: np.ndarray
    switch_positions: np.ndarray
    switch_kinds: tuple
    final_state: object
    final_valve: str
    status: RunStatus
    pieces: Sequence = field(repr=False)

    @property
    def n_impacts(self) -> int:
        return int(self.impact_times.size)

    def end_displacement(self, t) -> np.ndarray:
        """``u(1, t)`` at times in ``[t0, t_end]``, shape ``(T,)``."""
        return self._each(t, "end_displacement")

    def end_velocity(self, t) -> np.ndarray:
        """``u_t(1, t)`` at times in ``[t0, t_end]``, shape ``(T,)``."""
        return self._each(t, "end_velocity")

    def _each(self, t, name):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if np.any(t < self.t0) or np.any(t > self.t_end) or not np.all(np.isfinite(t)):
            raise ValueError(f"t must lie in [t0, t_end] = [{self.t0}, {self.t_end}]")
        starts = self.pieces.starts
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)
        out = np.empty_like(t)
        for j in np.unique(idx):
            sel = idx == j
            piece = self.pieces[j]
            out[sel] = getattr(piece, name)(np.minimum(t[sel], piece.t_end))
        return out


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

    def end_displacement(self, t):
        return np.minimum(self._at(np.asarray(t, dtype=float))[0], 0.0)

    def end_velocity(self, t):
        return self._at(np.asarray(t, dtype=float))[1]


def rigid_piece(model: BarModel):
    """The piece function of :func:`run_switched` for the rigid bar under the paper's law, in closed
    form: the impact is the first rising crossing of ``q_0`` through 0 (the same monotonicity
    argument as the switch's, theory §10), then ``v -> -R v`` (eq. 10); with the force pressing and
    a rebound too small to resolve (or ``R = 0``), the piston rests on the stop until ``t_stop``."""
    d, R = model.d, model.law.kernel_restitution(model)

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
            vm = float(f._at(np.array(t_imp))[1])
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


def initial_valve(drive: PositionSwitchedDrive, q0: float) -> int:
    """The valve's state at the start of a run: return while the gap is below ``switch_out``,
    stroke beyond it."""
    return RETURN if -q0 < drive.switch_out else STROKE


class _Flight:
    """One constant-force flight of the flexible bar that the compiled valve loop followed (no
    contact in it): evaluated by the driver's exact flow from its start (eq. 8)."""

    __slots__ = ("core", "t0", "t_end", "q", "v")

    def __init__(self, core, t0, t_end, q, v):
        self.core, self.t0, self.t_end, self.q, self.v = core, t0, t_end, q, v

    def _at(self, t):
        from .trajectory import _FREE

        return self.core.propagate(_FREE, self.t0, self.q, self.v, np.asarray(t, dtype=float))

    def end_displacement(self, t):
        return np.minimum(self.core.c @ self._at(t)[0], 0.0)

    def end_velocity(self, t):
        return self.core.c @ self._at(t)[1]


class _Pieces(Sequence):
    """The pieces of a switched run: those the Python loop ran (objects) and those the compiled
    loop logged (arrays of their starts, made into flights when asked for)."""

    def __init__(self, blocks, make):
        self._blocks = blocks  # ("py", piece) or ("k", t0, t1, code, q, v)
        self._make = make  # (t0, t1, code, q, v) -> a flight
        sizes = [1 if b[0] == "py" else b[1].size for b in blocks]
        self._ends = np.cumsum(sizes, dtype=np.int64)
        self.starts = np.concatenate([np.array([b[1].t0]) if b[0] == "py" else b[1] for b in blocks]) \
            if blocks else np.zeros(0)

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
        b = self._blocks[k]
        if b[0] == "py":
            return b[1]
        j = i - (int(self._ends[k - 1]) if k else 0)
        return self._make(float(b[1][j]), float(b[2][j]), int(b[3][j]), b[4][j], b[5][j])


class _Valve:
    """The valve's loop (theory §10), one piece per :meth:`step`: the Python reference, and the
    fallback of the compiled loop for the pieces it hands back."""

    def __init__(self, model, drive, q, v, t0, t_end, max_imp):
        self.model, self.drive = model, drive
        self.valve = initial_valve(drive, float(q[0]))
        self.pending: list[tuple[float, int]] = []  # (time the switch takes effect, state), sorted
        self.q, self.v, self.t, self.t0, self.t_end, self.max_imp = q, v, t0, t0, t_end, max_imp
        self.blocks: list = []
        self.imp_t: list = []
        self.imp_v: list = []
        self.sw_t: list = []
        self.sw_y: list = []
        self.sw_k: list = []
        self.n_imp = 0
        self.status = RunStatus.T_END
        self.done = False

    def step(self, piece) -> None:
        """Run the next piece with ``piece`` and apply the valve's rules at its end."""
        drive, q, v, t = self.drive, self.q, self.v, self.t
        pending = self.pending
        t_next = self.t_end
        if pending:
            t_next = min(t_next, pending[0][0])
        cross = math.inf
        if self.valve == RETURN and not any(k == STROKE for _, k in pending):
            a = -drive.level(RETURN)  # y'' + d y' = -p
            cross = t + first_rising_crossing(self.model.d, -float(q[0]), -float(v[0]), a, drive.switch_out)
            t_next = min(t_next, cross)
        traj = piece(drive.level(self.valve), q, v, t, t_next)
        self.blocks.append(("py", traj))
        state = traj.final_state
        self.q = q = state.modal_displacement
        self.v = state.modal_velocity
        self.t = t = traj.t_end
        if traj.n_impacts and (t < t_next or traj.status == RunStatus.MAX_IMPACTS):
            self.imp_t.extend(traj.impact_times.tolist())
            self.imp_v.extend(traj.impact_velocities.tolist())
            self.n_imp += traj.n_impacts
            pending.append((t + drive.delay, RETURN))  # the impact triggers the switch to return
            pending.sort()
            if self.n_imp >= self.max_imp:
                self.status = RunStatus.MAX_IMPACTS
                self.done = True
                return
        elif t >= self.t_end:
            self.done = True
            return
        elif t == cross:  # the gap rose through switch_out: the switch to stroke is triggered
            pending.append((cross + drive.delay, STROKE))
            pending.sort()
        while pending and pending[0][0] <= t:  # the switches due now take effect
            _, k = pending.pop(0)
            if k != self.valve:
                self.valve = k
                self.sw_t.append(t)
                self.sw_y.append(-float(q[0]))
                self.sw_k.append(_KIND[k])

    def result(self, make_state, make_piece) -> SwitchedTrajectory:
        return SwitchedTrajectory(
            model=self.model, drive=self.drive, t0=self.t0, t_end=self.t, impact_times=np.array(self.imp_t),
            impact_velocities=np.array(self.imp_v), switch_times=np.array(self.sw_t),
            switch_positions=np.array(self.sw_y), switch_kinds=tuple(self.sw_k),
            final_state=make_state(np.array(self.q, dtype=float), np.array(self.v, dtype=float)),
            final_valve=_KIND[self.valve], status=self.status, pieces=_Pieces(self.blocks, make_piece))


def run_switched(model: BarModel, drive: PositionSwitchedDrive, q, v, t0: float, t_end: float,
                 max_imp: int, piece, make_state) -> SwitchedTrajectory:
    """The valve's event loop in Python, piece by piece (theory §10; the reference of
    :func:`run_compiled`).

    ``piece(level, q, v, t, t_stop)`` runs the ordinary driver under the constant force ``level``
    from ``(q, v)`` at ``t`` until ``t_stop`` or its first impact, and returns its
    :class:`~impactbar.Trajectory` (or a :func:`rigid_piece` flight); ``make_state(q, v)`` makes
    the final :class:`~impactbar.InitialState`.
    """
    loop = _Valve(model, drive, q, v, t0, t_end, max_imp)
    while loop.t < t_end and not loop.done:
        loop.step(piece)
    return loop.result(make_state, None)


#: room in the compiled loop's pending list (more pending switches: the Python loop's step)
_PEND_CAP = 64
#: impacts in the compiled loop's first logs (doubled at each call, up to 65536)
_FIRST_CAP = 256


def run_compiled(model: BarModel, drive: PositionSwitchedDrive, q, v, t0: float, t_end: float,
                 max_imp: int, piece, make_state, cores, rigid: bool, fast_search: bool,
                 tail: float) -> SwitchedTrajectory:
    """The valve's event loop compiled (:func:`impactbar.dynamics._switchkernel.run_switched`),
    with the same pieces, impacts and switches as :func:`run_switched` (theory §10).

    ``cores`` are the driver's data of the one-piece loads ``+stroke`` and ``-ret``; with ``rigid``
    the rigid bar's pieces take the closed forms of :func:`rigid_piece`; a piece the compiled loop
    hands back (a touch without an impact, and the like) is run by ``piece``; ``fast_search``
    chooses the driver's impact search (``simulate.impact_search``); ``tail`` is the driver's
    chatter tolerance (``CHATTER_TAIL``).
    """
    loop = _Valve(model, drive, np.array(q, dtype=float), np.array(v, dtype=float), t0, t_end, max_imp)
    views = tuple(tuple(core.data) for core in cores)
    B = tuple(cores[0].free.view)
    R, c = cores[0].R, cores[0].c
    dview = tuple(drive.kernel_view)
    M = loop.q.size
    clock = np.array([t0, t_end, tail])
    ints = np.zeros(6, dtype=np.int64)
    pend_t = np.empty(_PEND_CAP)
    pend_k = np.empty(_PEND_CAP, dtype=np.int64)
    cap = _FIRST_CAP
    while loop.t < t_end and not loop.done:
        if len(loop.pending) + 2 > _PEND_CAP:
            loop.step(piece)
            continue
        left = loop.max_imp - loop.n_imp
        n_i = max(1, min(cap, left))
        n_p = 4 * n_i + 8
        logs = (np.empty(n_i), np.empty(n_i), np.empty(n_p + _PEND_CAP), np.empty(n_p + _PEND_CAP),
                np.empty(n_p + _PEND_CAP, dtype=np.int64), np.empty(n_p), np.empty(n_p),
                np.empty(n_p, dtype=np.int64), np.empty((n_p, M)), np.empty((n_p, M)),
                np.zeros(3, dtype=np.int64))
        cap = min(2 * cap, 1 << 16)
        n_pend = len(loop.pending)
        for i, (tp, kp) in enumerate(loop.pending):
            pend_t[i], pend_k[i] = tp, kp
        ints[:] = (loop.valve, n_pend, loop.n_imp, loop.max_imp, rigid, fast_search)
        clock[0] = loop.t
        q, v = np.array(loop.q, dtype=float), np.array(loop.v, dtype=float)
        st = SK.run_switched(views, B, dview, R, c, clock, (q, v), ints, (pend_t, pend_k), logs)
        ni, ns, npc = (int(x) for x in logs[-1])
        loop.imp_t.extend(logs[0][:ni].tolist())
        loop.imp_v.extend(logs[1][:ni].tolist())
        loop.sw_t.extend(logs[2][:ns].tolist())
        loop.sw_y.extend(logs[3][:ns].tolist())
        loop.sw_k.extend(_KIND[int(k)] for k in logs[4][:ns])
        if npc:
            loop.blocks.append(("k", logs[5][:npc], logs[6][:npc], logs[7][:npc], logs[8][:npc],
                                logs[9][:npc]))
        loop.valve, loop.n_imp = int(ints[0]), int(ints[2])
        loop.pending = [(float(pend_t[i]), int(pend_k[i])) for i in range(int(ints[1]))]
        loop.t, loop.q, loop.v = float(clock[0]), q, v
        if st == SK.MAX_IMPACTS:
            loop.status = RunStatus.MAX_IMPACTS
            break
        if st == SK.PYTHON:
            loop.step(piece)
        elif st == SK.DONE:
            break

    if rigid:
        d = model.d

        def make_piece(t0, t1, code, q, v):
            f = object.__new__(_RigidFlight)
            f.t0, f.t_end, f.level, f.d = t0, t1, drive.level(code % 2), d
            f.stuck = code >= 2
            f.q, f.v = (0.0, 0.0) if f.stuck else (float(q[0]), float(v[0]))
            return f
    else:
        def make_piece(t0, t1, code, q, v):
            return _Flight(cores[code], t0, t1, q, v)

    return loop.result(make_state, make_piece)
