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
from dataclasses import dataclass, field

import numpy as np

from .._shared.status import RunStatus
from ..drives.switched import RETURN, STROKE, PositionSwitchedDrive, first_rising_crossing
from ..model import BarModel

__all__ = ["SwitchedTrajectory", "run_switched"]

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
    pieces : tuple of Trajectory
        The constant-force pieces, in order (each a run of the ordinary driver).

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
    pieces: tuple = field(repr=False)

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
        starts = np.array([p.t0 for p in self.pieces])
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


def run_switched(model: BarModel, drive: PositionSwitchedDrive, q, v, t0: float, t_end: float,
                 max_imp: int, piece, make_state) -> SwitchedTrajectory:
    """The valve's event loop (theory §10).

    ``piece(level, q, v, t, t_stop)`` runs the ordinary driver under the constant force ``level``
    from ``(q, v)`` at ``t`` until ``t_stop`` or its first impact, and returns its
    :class:`~impactbar.Trajectory` (or a :func:`rigid_piece` flight); ``make_state(q, v)`` makes
    the final :class:`~impactbar.InitialState`.
    """
    d = model.d
    tau = drive.delay
    valve = initial_valve(drive, float(q[0]))
    pending: list[tuple[float, int]] = []  # (time the switch takes effect, new state), in order
    t = t0
    pieces = []
    imp_t, imp_v = [], []
    sw_t, sw_y, sw_k = [], [], []
    n_imp = 0
    status = RunStatus.T_END
    state = None
    while t < t_end:
        # the next rising crossing of switch_out while the valve is (and stays) in return
        t_next = t_end
        if pending:
            t_next = min(t_next, pending[0][0])
        cross = math.inf
        if valve == RETURN and not any(k == STROKE for _, k in pending):
            a = -drive.level(RETURN)  # y'' + d y' = -p
            cross = t + first_rising_crossing(d, -float(q[0]), -float(v[0]), a, drive.switch_out)
            t_next = min(t_next, cross)
        traj = piece(drive.level(valve), q, v, t, t_next)
        pieces.append(traj)
        state = traj.final_state
        q = state.modal_displacement
        v = state.modal_velocity
        t = traj.t_end
        if traj.n_impacts and (t < t_next or traj.status == RunStatus.MAX_IMPACTS):
            imp_t.extend(traj.impact_times.tolist())
            imp_v.extend(traj.impact_velocities.tolist())
            n_imp += traj.n_impacts
            pending.append((t + tau, RETURN))  # the impact triggers the switch to return
            pending.sort()
            if n_imp >= max_imp:
                status = RunStatus.MAX_IMPACTS
                break
        elif t >= t_end:
            break
        elif t == cross:  # the gap rose through switch_out: the switch to stroke is triggered
            pending.append((cross + tau, STROKE))
            pending.sort()
        while pending and pending[0][0] <= t:  # the switches due now take effect
            _, k = pending.pop(0)
            if k != valve:
                valve = k
                sw_t.append(t)
                sw_y.append(-float(q[0]))
                sw_k.append(_KIND[k])
    return SwitchedTrajectory(
        model=model, drive=drive, t0=t0, t_end=t, impact_times=np.array(imp_t),
        impact_velocities=np.array(imp_v), switch_times=np.array(sw_t),
        switch_positions=np.array(sw_y), switch_kinds=tuple(sw_k),
        final_state=make_state(np.array(q, dtype=float), np.array(v, dtype=float)),
        final_valve=_KIND[valve], status=status, pieces=tuple(pieces))
