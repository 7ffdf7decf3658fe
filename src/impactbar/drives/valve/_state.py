"""The valve's state (theory §10): its two positions, the compiled loop's view of the drive, and
the rules that move the valve (no import of the valve's other modules: they all read these)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["STROKE", "RETURN", "KIND", "DriveKernelView", "initial_valve"]

#: The valve's two states (indices into :meth:`PositionSwitchedDrive.level`).
STROKE = 0
RETURN = 1
#: The name of each state, logged at each switch (``DrivenTrajectory.switch_kinds``).
KIND = {STROKE: "stroke", RETURN: "return"}

_NO_STATE = np.zeros(0)
_NO_STATE.flags.writeable = False


class DriveKernelView(NamedTuple):
    """A position-switched drive as the compiled valve loop reads it (theory §10; built once by
    :attr:`impactbar.PositionSwitchedDrive.kernel_view`).

    Attributes
    ----------
    stroke, ret : float
        Force toward the stop in the stroke state and away from it in the return state
        (dimensionless, eq. 2), both ``> 0``.
    switch_out : float
        Gap ``y = -q_0`` at which the return force gives way to the stroke force on the way out.
    delay_out : float
        The valve's delay after the ``switch_out`` crossing (the switch to stroke; dimensionless
        time), ``>= 0``.
    delay_in : float
        Its delay after the impact (the switch to return), ``>= 0``.
    """

    stroke: float
    ret: float
    switch_out: float
    delay_out: float
    delay_in: float


def initial_valve(drive, q0: float) -> int:
    """The valve's state at the start of a run: return while the gap is below ``switch_out``,
    stroke beyond it."""
    return RETURN if -q0 < drive.switch_out else STROKE


def _due(valve: int, pending: tuple, t: float) -> tuple:
    """The mode after the switches due at ``t`` take effect, in order."""
    while pending:
        t_switch, switched = pending[0]
        if not t_switch <= t:
            break
        valve, pending = switched, pending[1:]
    return (valve, pending)
