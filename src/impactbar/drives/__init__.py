"""Drives that are not functions of time (theory §10): the :class:`Drive` interface and the valve of
a hydraulic drifter switched by the piston's position. The system they drive is autonomous; its blow
frequency is an output.

Layout: ``base`` (:class:`Drive`, :class:`DriveTraits`, :class:`DriveState`, the events
:class:`DriveEvent`, :class:`GapCrossing`, :class:`RateCrossing`, :class:`TimedEvent`,
:class:`SurfaceEvent`, and the periodic-orbit problem a drive may bring, :class:`OrbitProblem`),
``abilities`` (what a drive may do beyond its required hooks, :class:`DriveAbilities`), ``params``
(its parameters for the parameter protocol), ``_crossing`` (the rigid
coordinate's crossings under a constant force in closed form, compiled), ``flight`` (the flight of a
drive with state between impacts, by scipy's ``solve_ivp``), ``valve`` (the valve,
:class:`PositionSwitchedDrive`, with its compiled loop; the numerics of its periodic orbits sit with
the orbit solvers, :mod:`impactbar.orbits.valve_segment`). Below the solvers:
imports only ``impactbar.model``, ``impactbar.dynamics`` and ``impactbar._shared``.
"""

from .abilities import CompiledLoop as CompiledLoop
from .abilities import DriveAbilities as DriveAbilities
from .abilities import OwnFlight as OwnFlight
from .abilities import Quadratures as Quadratures
from .base import DRIVES as DRIVES
from .base import Drive as Drive
from .base import DriveEvent as DriveEvent
from .base import DriveState as DriveState
from .base import DriveTraits as DriveTraits
from .base import FlightSettings as FlightSettings
from .base import GapCrossing as GapCrossing
from .base import RateCrossing as RateCrossing
from .base import SurfaceEvent as SurfaceEvent
from .base import TimedEvent as TimedEvent
from .base import register_drive as register_drive
from .orbitproblem import OrbitData as OrbitData
from .orbitproblem import OrbitProblem as OrbitProblem
from .orbitproblem import OrbitSearch as OrbitSearch
from .valve import PositionSwitchedDrive as PositionSwitchedDrive

__all__ = ["Drive", "DriveTraits", "DriveAbilities", "CompiledLoop", "OwnFlight", "Quadratures", "DriveState",
           "DriveEvent", "GapCrossing", "RateCrossing", "TimedEvent", "SurfaceEvent", "FlightSettings",
           "OrbitProblem", "OrbitData", "OrbitSearch", "PositionSwitchedDrive", "DRIVES", "register_drive"]

DRIVES[PositionSwitchedDrive.traits.kind] = PositionSwitchedDrive
