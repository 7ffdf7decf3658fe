"""Simulation under a position-switched drive: the valve's event loop (theory §10).

Between events the force is constant, so every mode moves in closed form (eq. 8) and the
existing driver of :mod:`impactbar.simulation.simulate` (certified impact search, chatter,
sustained contact, every impact law) follows the bar under that constant force. Around it this
module runs the valve: the rising crossing of the switch position by the gap ``y = -q_0`` is found in
closed form (:func:`impactbar.drives.switched.first_rising_crossing`: ``y' `` is monotone under a
constant force, so no crossing is missed, and it is refined to rounding), each switch takes effect
``delay`` after its trigger, and each impact triggers the switch to return.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._status import RunStatus
from ..drives.switched import RETURN, STROKE, PositionSwitchedDrive, first_rising_crossing
from ..model import BarModel

__all__ = ["SwitchedTrajectory", "run_switched"]

_KIND = {STROKE: "stroke", RETURN: "return"}


@dataclass(frozen=True, eq=False)
class SwitchedTrajectory:
    """The result of :func:`impactbar.simulate` under a
    :class:`~impactbar.drives.PositionSwitchedDrive` (theory §10).

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


def initial_valve(drive: PositionSwitchedDrive, q0: float) -> int:
    """The valve's state at the start of a run: return while the gap is below ``switch_out``,
    stroke beyond it."""
    return RETURN if -q0 < drive.switch_out else STROKE


def run_switched(model: BarModel, drive: PositionSwitchedDrive, q, v, t0: float, t_end: float,
                 max_imp: int, piece) -> SwitchedTrajectory:
    """The valve's event loop (theory §10).

    ``piece(level, q, v, t, t_stop)`` runs the ordinary driver under the constant force ``level``
    from ``(q, v)`` at ``t`` until ``t_stop`` or its first impact, and returns its
    :class:`~impactbar.Trajectory`.
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
        q = np.array(state.modal_displacement)
        v = np.array(state.modal_velocity)
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
        switch_positions=np.array(sw_y), switch_kinds=tuple(sw_k), final_state=state,
        final_valve=_KIND[valve], status=status, pieces=tuple(pieces))
