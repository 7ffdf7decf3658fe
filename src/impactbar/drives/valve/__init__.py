"""The hydraulic drifter's valve: a drive switched by the piston's position (theory §10), with its
numerics.

Layout: ``drive`` (:class:`PositionSwitchedDrive`, the :class:`~impactbar.Drive` interface: force
levels, the switch crossing and the delayed switches, their maps), ``loop`` (the compiled event loop
the simulator runs under an instantaneous law), ``_compiled_loop`` (its numba kernels, the rigid piston's
closed forms), ``closed_forms`` (those of them the orbit solvers read). The periodic orbits' segment
problem (closed-form flights, the exact Jacobian, Newton's start, the monodromy matrix and the
flights' admissibility) and the certified search of every one-impact orbit sit with the orbit
solvers: :mod:`impactbar.orbits.valve_segment`, :mod:`impactbar.orbits.valve_search`.
"""

from .drive import RETURN as RETURN
from .drive import STROKE as STROKE
from .drive import PositionSwitchedDrive as PositionSwitchedDrive
from .drive import first_rising_crossing as first_rising_crossing

__all__ = ["PositionSwitchedDrive", "STROKE", "RETURN", "first_rising_crossing"]
