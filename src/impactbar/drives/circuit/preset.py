r"""The preset drifter's oil circuit as a tuple of parts (theory §11), composed by the same
:func:`~impactbar.drives.circuit.composition.compose_parts` as any extra part.

Each part here is a :class:`~impactbar.drives.circuit.CircuitPart` that holds one of the drive's
frozen parts (:mod:`.parts`) and declares what it adds to the circuit:

- ``chambers``: the nodes ``front``, ``rear`` (states), their compression work (``front``,
  ``rear``), a chamber on each;
- ``supply``: the node ``supply`` (a state) and the ``tank`` (held at its pressure), the hose's
  compression work (``supply``), the pump and the front chamber's feed;
- ``valve``: the spool between ``supply``, ``rear`` and its return port, which it offers
  (``valve_return``, the tank where no part takes it); its event ``ramp_end``;
- ``accumulator``: the gas on ``supply``, its work (``gas``), its event ``accumulator``;
- ``relief``: the relief valve from ``supply`` to the tank, its event ``relief``.

In that order they number the preset's layout (:data:`~impactbar.drives.circuit.layout.PRESET`:
the states ``p_f, p_r, p_s, x_v``, the tank node 3, the integrands ``pump``, ``piston``,
``orifices``, ``tank`` of :data:`~impactbar.drives.circuit.composition.SHARED_ENERGIES` then
``front``, ``rear``, ``supply``, ``gas``; the events' slots 0, 1, 2) and write the network the
kernel written by hand describes (the tests' reference, ``tests/circuit_field_reference.py``),
record for record. An extra part whose
:attr:`~impactbar.drives.circuit.CircuitPart.replaces` names one of them takes its place.
"""

from __future__ import annotations

from dataclasses import dataclass

from .composition import CircuitPart, compose_parts
from .parts import Accumulator, Chambers, Supply, Valve

__all__ = ["ChambersPart", "SupplyPart", "ValvePart", "AccumulatorPart", "ReliefPart", "PRESET_PARTS",
           "preset_parts", "PORTS", "PRESET_NODES"]


@dataclass(frozen=True)
class ChambersPart(CircuitPart):
    """The piston's chambers (:class:`~impactbar.drives.circuit.Chambers`): the nodes ``front`` and
    ``rear``, their oil's compression work, a chamber on each (the rear's first)."""

    chambers: Chambers | None = None

    name = "chambers"
    nodes = ("front", "rear")
    symbols = ("p_f", "p_r")
    energies = (("front", "compression"), ("rear", "compression"))

    def records(self, slots, oil) -> list:
        """:meth:`Chambers.records <impactbar.drives.circuit.Chambers.records>` on its nodes."""
        return self.chambers.records(slots.nodes["front"], slots.nodes["rear"], oil.bulk_modulus,
                                     front_energy=slots.energy["front"], rear_energy=slots.energy["rear"])


@dataclass(frozen=True)
class SupplyPart(CircuitPart):
    """The supply line (:class:`~impactbar.drives.circuit.Supply` but its relief valve): the node
    ``supply`` (the hose; held at its pressure for a held supply), the tank held at its pressure, the
    pump and the front chamber's feed."""

    supply: Supply | None = None

    name = "supply"
    nodes = ("supply",)
    symbols = ("p_s",)
    held_nodes = ("tank",)
    energies = (("supply", "compression"),)

    def records(self, slots, oil) -> list:
        """:meth:`Supply.line_records <impactbar.drives.circuit.Supply.line_records>` on its nodes."""
        en = slots.energy
        return self.supply.line_records(slots.nodes["supply"], slots.nodes["tank"], slots.nodes["front"], oil,
                                        {"pump": en["pump"], "orifices": en["orifices"], "tank": en["tank"],
                                         "compression": en["supply"]})


@dataclass(frozen=True)
class ValvePart(CircuitPart):
    """The main valve (:class:`~impactbar.drives.circuit.Valve`): its spool between the supply, the
    rear chamber and its return port (offered, the tank where no part takes it), ramping at
    ``+-1 / switching_time`` toward the mode's target while the mode says it moves; the ramp's end its
    event (the network's slot 0)."""

    valve: Valve | None = None

    name = "valve"
    events = ("ramp_end",)
    offers = {"valve_return": "tank"}

    def records(self, slots, oil) -> list:
        """:meth:`Valve.records <impactbar.drives.circuit.Valve.records>` in the mode's ramp."""
        (target, *_), moving = slots.mode, slots.flags["ramp_end"]  # (the mode: target, then the flags)
        tau = self.valve.switching_time
        return self.valve.records(slots.nodes["supply"], slots.nodes["rear"], slots.ports["valve_return"],
                                  oil.transition_pressure,
                                  rate=(1.0 if target else -1.0) / tau if moving else 0.0,
                                  opening=(1 if target else -1) if moving else 0,
                                  energy=slots.energy["orifices"], event=slots.events["ramp_end"])


@dataclass(frozen=True)
class AccumulatorPart(CircuitPart):
    """The gas accumulator on the supply (:class:`~impactbar.drives.circuit.Accumulator`; one of no
    volume where there is none or the supply is held, as the compiled kernel has, its event then not
    watched)."""

    accumulator: Accumulator | None = None
    supply_held: bool = False

    name = "accumulator"
    energies = (("gas", "accumulator"),)
    events = ("accumulator",)

    def records(self, slots, oil) -> list:
        """:meth:`Accumulator.records <impactbar.drives.circuit.Accumulator.records>` on ``supply``."""
        ac = self.accumulator
        has_acc = ac is not None and ac.volume > 0 and not self.supply_held
        gas = Accumulator(precharge=ac.precharge if ac is not None else 1.0,
                          volume=ac.volume if has_acc else 0.0,
                          polytropic_exponent=ac.polytropic_exponent if ac is not None else 1.4)
        return gas.records(slots.nodes["supply"], holding=slots.flags["accumulator"], watched=has_acc,
                           energy=slots.energy["gas"], event=slots.events["accumulator"])


@dataclass(frozen=True)
class ReliefPart(CircuitPart):
    """The supply's relief valve to the tank (:meth:`Supply.relief_records
    <impactbar.drives.circuit.Supply.relief_records>`), its loss among the orifices'."""

    supply: Supply | None = None

    name = "relief"
    events = ("relief",)

    def records(self, slots, oil) -> list:
        """The relief valve from ``supply`` to ``tank`` in the mode's flag."""
        return self.supply.relief_records(slots.nodes["supply"], slots.nodes["tank"], slots.flags["relief"],
                                          slots.events["relief"], slots.energy["orifices"])


#: The preset's parts in their order, without the drive's values (their names, nodes, ports, energy
#: integrands and events: enough to number a composition, :func:`compose_parts`' ``base``)
PRESET_PARTS = (ChambersPart(), SupplyPart(), ValvePart(), AccumulatorPart(), ReliefPart())


def preset_parts(drive) -> tuple:
    """The preset's parts of a :class:`~impactbar.drives.circuit.HydraulicCircuitDrive`, in the order
    of :data:`PRESET_PARTS`, holding its parts.

    Returns
    -------
    tuple of CircuitPart

    Examples
    --------
    >>> from impactbar.physical import circuit_preset
    >>> [p.name for p in preset_parts(circuit_preset("circuit-drifter").drive())]
    ['chambers', 'supply', 'valve', 'accumulator', 'relief']
    """
    return (ChambersPart(drive.chambers), SupplyPart(drive.supply), ValvePart(drive.valve),
            AccumulatorPart(drive.accumulator, drive.supply.held), ReliefPart(drive.supply))


#: the preset's ports an extra part may take over, and the node each joins without one: the valve's
#: return port (the tank)
PORTS = {port: node for p in PRESET_PARTS for port, node in p.offers.items()}
#: the preset's nodes a part may connect to by name (those with a state, then the tank held at its
#: pressure)
PRESET_NODES = tuple(compose_parts((), PRESET_PARTS).nodes)
