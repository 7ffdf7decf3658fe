"""Ctrl-C during a long :func:`impactbar.simulate` run: caught between blocks of impacts, so that
the run stops at a consistent state and keeps what it computed."""

from __future__ import annotations

import _signal  # signal.signal's own call, without its enum conversions (a short run's fixed cost)
import threading

__all__ = ["SimulationInterrupted"]


class SimulationInterrupted(KeyboardInterrupt):
    """Ctrl-C during a long :func:`~impactbar.simulate` run: a :class:`KeyboardInterrupt` that carries what
    the run computed until then.

    Attributes
    ----------
    trajectory : impactbar.Trajectory
        The run up to the block of impacts it had finished: ``t_end`` is the time reached, and the
        trajectory is the one a run ending there gives (``status`` ``"t_end"``, or
        ``"max_impacts"`` where it stopped at an impact).
    """

    def __init__(self, trajectory):
        super().__init__(f"simulate interrupted at t = {trajectory.t_end:.6g} after "
                         f"{trajectory.impact_times.size} impacts")
        self.trajectory = trajectory


class _CtrlC:
    """While a long run is in progress, Ctrl-C sets a flag the driver reads between blocks of
    impacts (so that it stops at a consistent state); a second Ctrl-C interrupts at once. Only in
    the main thread (elsewhere no handler can be set: the flag stays down)."""

    def __init__(self):
        self.pressed = False
        self._old = None

    def __bool__(self):
        return self.pressed

    def _handler(self, signum, frame):
        if self.pressed:
            raise KeyboardInterrupt
        self.pressed = True

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            try:
                self._old = _signal.signal(_signal.SIGINT, self._handler)
            except ValueError:  # pragma: no cover - not the main interpreter
                self._old = None
        return self

    def __exit__(self, *exc):
        if self._old is not None:
            _signal.signal(_signal.SIGINT, self._old)
        return False
