"""The drifter's oil circuit as a drive with state (theory §11): chambers, main valve, supply node
with pump, gas accumulator and relief valve, and its numerics.

Layout: ``parts`` (the frozen parts: :class:`Chambers`, :class:`Valve`, :class:`Supply`,
:class:`Accumulator`, :class:`Oil`), ``drive`` (:class:`HydraulicCircuitDrive`, the
:class:`~impactbar.Drive` interface composed from the parts; :class:`CircuitEnergy`), ``layout``
(where the circuit keeps its states and energy terms, read by name), ``settings`` (how its flights
are integrated: :class:`CircuitFlightSettings`, handed to the solvers), ``composition`` (parts added to
the circuit, :class:`CircuitPart`, and the numbering of its nodes, energy and event slots), ``_network``
(the part records a part writes, :func:`record`, of the kinds :data:`NODE`, :data:`PUMP`,
:data:`ORIFICE`, :data:`VALVE`, :data:`RELIEF`, :data:`CHAMBER`, :data:`ACCUM`), ``flight`` (one
flight integrated by SUNDIALS' CVODE, with the variational equations on request), ``_kernel`` (the
compiled vector field, Jacobian and event functions), ``_sundials`` and ``_cvode`` (CVODE driven from
compiled code, on the SUNDIALS libraries that scikit-sundae ships).
"""

from ._network import ACCUM as ACCUM
from ._network import CHAMBER as CHAMBER
from ._network import NODE as NODE
from ._network import ORIFICE as ORIFICE
from ._network import PUMP as PUMP
from ._network import RELIEF as RELIEF
from ._network import VALVE as VALVE
from ._network import record as record
from .composition import PORTS as PORTS
from .composition import TERMS as TERMS
from .composition import CircuitPart as CircuitPart
from .composition import PartSlots as PartSlots
from .drive import PARAMETERS as PARAMETERS
from .drive import CircuitEnergy as CircuitEnergy
from .drive import HydraulicCircuitDrive as HydraulicCircuitDrive
from .parts import Accumulator as Accumulator
from .parts import Chambers as Chambers
from .parts import Oil as Oil
from .parts import Supply as Supply
from .parts import Valve as Valve
from .settings import CircuitFlightSettings as CircuitFlightSettings

__all__ = ["HydraulicCircuitDrive", "CircuitFlightSettings", "CircuitEnergy", "PARAMETERS", "Chambers",
           "Valve", "Supply", "Accumulator", "Oil", "CircuitPart", "PartSlots", "PORTS", "TERMS", "record",
           "NODE", "PUMP", "ORIFICE", "VALVE", "RELIEF", "CHAMBER", "ACCUM"]
