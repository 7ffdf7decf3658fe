"""The drifter's oil circuit as a drive with state (theory §11): chambers, main valve, supply node
with pump, gas accumulator and relief valve, and its numerics.

Layout: ``parts`` (the frozen parts: :class:`Chambers`, :class:`Valve`, :class:`Supply`,
:class:`Accumulator`, :class:`Oil`), ``drive`` (:class:`HydraulicCircuitDrive`, the
:class:`~impactbar.Drive` interface composed from the parts; :class:`CircuitEnergy`), ``layout``
(where the circuit keeps its states and energy terms, read by name), ``settings`` (how its flights
are integrated: :class:`CircuitFlightSettings`, handed to the solvers), ``composition`` (the
circuit's parts, :class:`CircuitPart`, :class:`PartField`, and the numbering of its nodes, energy and
event slots: :func:`~.composition.compose_parts`), ``preset`` (the preset circuit as a tuple of
such parts, that an extra part may replace by name), ``return_line`` and ``leak`` (two parts of the
network's kinds: :class:`ReturnAccumulator`, :class:`Leak`), ``_network``
(the part records a part writes, :func:`record`, of the kinds :data:`NODE`, :data:`PUMP`,
:data:`ORIFICE`, :data:`VALVE`, :data:`RELIEF`, :data:`CHAMBER`, :data:`ACCUM`, and those written
each in a module of its own, ``kinds``: :data:`LEAK`, :data:`CUSHION`, :data:`CHECK`, :data:`LEVEL`),
``leakage``, ``cushion``, ``check_valve``, ``spool_valve`` (:class:`LaminarLeak`, :class:`Cushion`,
:class:`CheckValve`, :class:`SpoolValve`: parts of a drill's circuit; the spool valve stands in for
the valve, of the kinds :data:`SPOOL` and :data:`SPOOL_PORT`), ``flight`` (one
flight integrated by SUNDIALS' CVODE, with the variational equations on request), ``_netgen`` and
``_endgen`` (the compiled vector field, Jacobian and event functions generated for the network's
topology, a flight's and a blow's; ``_bar`` the bar's share of them), ``_sundials`` and ``_cvode``
(CVODE driven from compiled code, on the SUNDIALS libraries that scikit-sundae ships).
"""

from ._network import ACCUM as ACCUM
from ._network import CHAMBER as CHAMBER
from ._network import CHECK as CHECK
from ._network import CUSHION as CUSHION
from ._network import LEAK as LEAK
from ._network import LEVEL as LEVEL
from ._network import NODE as NODE
from ._network import ORIFICE as ORIFICE
from ._network import PUMP as PUMP
from ._network import RELIEF as RELIEF
from ._network import SPOOL as SPOOL
from ._network import SPOOL_PORT as SPOOL_PORT
from ._network import VALVE as VALVE
from ._network import record as record
from .check_valve import CheckValve as CheckValve
from .composition import TERMS as TERMS
from .composition import CircuitPart as CircuitPart
from .composition import NamedPart as NamedPart
from .composition import PartField as PartField
from .composition import PartSlots as PartSlots
from .cushion import Cushion as Cushion
from .drive import PARAMETERS as PARAMETERS
from .drive import HydraulicCircuitDrive as HydraulicCircuitDrive
from .energy import CircuitEnergy as CircuitEnergy
from .leak import Leak as Leak
from .leakage import LaminarLeak as LaminarLeak
from .parts import Accumulator as Accumulator
from .parts import Chambers as Chambers
from .parts import Oil as Oil
from .parts import Supply as Supply
from .parts import Valve as Valve
from .preset import PORTS as PORTS
from .return_line import ReturnAccumulator as ReturnAccumulator
from .settings import CircuitFlightSettings as CircuitFlightSettings
from .spool_valve import SpoolValve as SpoolValve

__all__ = ["HydraulicCircuitDrive", "CircuitFlightSettings", "CircuitEnergy", "PARAMETERS", "Chambers",
           "Valve", "Supply", "Accumulator", "Oil", "CircuitPart", "NamedPart", "PartField", "PartSlots",
           "ReturnAccumulator", "Leak", "PORTS", "TERMS", "record", "NODE", "PUMP", "ORIFICE", "VALVE",
           "RELIEF", "CHAMBER", "ACCUM", "LEAK", "CUSHION", "CHECK", "LEVEL", "LaminarLeak", "Cushion",
           "CheckValve", "SpoolValve", "SPOOL", "SPOOL_PORT"]
