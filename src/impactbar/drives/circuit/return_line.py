r"""A return line with a low-pressure gas accumulator (theory §13, "Return line and low-pressure
accumulator"): the valve's return port ends at a node of oil instead of the tank, a gas accumulator
on it, drained to the tank through an orifice, so that the pressure the rear chamber empties into is
a state.

With :math:`p` the line's pressure, :math:`Q_\mathrm{in}` the oil the valve returns to it, the tank
at :math:`p_t` and the orifice law :math:`\phi` of the oil
(:class:`~impactbar.drives.circuit.Oil`),

.. math::

    p' = \frac{Q_\mathrm{in} - K_\mathrm{ret}\,\phi(p - p_t)}{V_\mathrm{ret} / \beta + C_a(p)},
    \qquad C_a(p) = \frac{V_0}{n}\,p_0^{1/n}\,p^{-1/n - 1} \ (p \ge p_0), \quad 0 \ (p < p_0),

the accumulator's compliance :math:`C_a` that of the supply's (:class:`Accumulator`): it holds oil
only above its pre-charge, an event where the pressure crosses it. Its energy integrands: the line's
oil compression (term ``compression``), the gas's work (``accumulator``); the orifice's loss adds to
the preset's ``orifices``. As :math:`K_\mathrm{ret} \to \infty` the line's pressure tends to the
tank's and the circuit to the preset's.
"""

from __future__ import annotations

from dataclasses import dataclass

from . import _network as NW
from .composition import NO_PORT, NamedPart, OwnNode, PartField, node_of
from .parts import Accumulator

__all__ = ["ReturnAccumulator"]

_ORIFICE = "m**3/s/Pa**0.5"


@dataclass(frozen=True)
class ReturnAccumulator(OwnNode, NamedPart):
    r"""A return line with a gas accumulator (the module's equations), dimensionless (units of
    :mod:`~impactbar.drives.circuit.parts`): a :class:`~impactbar.drives.circuit.CircuitPart` for
    ``HydraulicCircuitDrive(..., extra_parts=(line,))``, or the kind ``"return_accumulator"`` of a
    configuration's ``[parts.<name>]`` table.

    Parameters
    ----------
    volume : float
        :math:`V_\mathrm{ret}`, the line's oil volume, ``> 0``.
    flow_coefficient : float
        :math:`K_\mathrm{ret}` of the orifice to the drain, ``> 0``.
    precharge : float
        :math:`p_0` (absolute), ``> 0``.
    gas_volume : float
        :math:`V_0`, :math:`\ge 0` (0: no gas).
    polytropic_exponent : float, optional
        :math:`n` in ``[1, 2]``. Default 1.4.
    name : str, optional
        Its node's name (an identifier; its state ``p_<name>``, its parameters ``<name>.<field>``).
        Default ``"return_line"``.
    port : str, optional
        The preset's port it takes (``"valve_return"``), or ``"none"``: none (its node fed by
        another part that names it, as a cushion's ``target``).
    drain : str, optional
        The node it drains to. Default ``"tank"``.

    Raises
    ------
    ValueError
        A value out of its range (named).

    Examples
    --------
    >>> line = ReturnAccumulator(volume=0.3, flow_coefficient=1.2, precharge=0.02, gas_volume=0.5)
    >>> line.nodes, line.ports, line.events
    (('return_line',), {'valve_return': 'return_line'}, ('return_line.gas',))
    """

    volume: float
    flow_coefficient: float
    precharge: float
    gas_volume: float
    polytropic_exponent: float = 1.4
    name: str = "return_line"
    port: str = "valve_return"
    drain: str = "tank"

    si_fields = (
        PartField("volume", "m**3", "'0.2 L'", "volume", description="the return line's oil volume"),
        PartField("flow_coefficient", _ORIFICE, "'2e-5 m^3/s/Pa^0.5'", "orifice",
                  description="flow coefficient of the line's orifice to its drain"),
        PartField("precharge", "Pa", "'0.2 MPa'", "pressure",
                  description="the line's accumulator's gas pre-charge"),
        PartField("gas_volume", "m**3", "'0.5 L'", "volume", low_open=False,
                  description="the line's accumulator's gas volume"),
        PartField("polytropic_exponent", "", "1.4", "one", low=1.0, high=2.0, low_open=False,
                  high_open=False, default=1.4, description="the line's gas's polytropic exponent"))
    connections = {"port": ("port", "valve_return"), "drain": ("node", "tank")}

    @property
    def energies(self) -> tuple:
        """The line's oil compression and its gas's work."""
        return ((self.name, "compression"), (f"{self.name}.gas", "accumulator"))

    @property
    def events(self) -> tuple:
        """Its accumulator's pressure through the pre-charge (watched where it has gas)."""
        return (f"{self.name}.gas",)

    @property
    def ports(self) -> dict:
        """The port it takes, to its node."""
        return {} if self.port == NO_PORT else {self.port: self.name}

    def records(self, slots, oil) -> list:
        """Its node, its accumulator and its orifice to the drain (:mod:`._network`)."""
        node, gas = slots.nodes[self.name], f"{self.name}.gas"
        accumulator = Accumulator(self.precharge, self.gas_volume, self.polytropic_exponent)
        return [NW.record(NW.NODE, id=node, volume=self.volume, beta=oil.bulk_modulus,
                          compression_energy=slots.energy[self.name]),
                *accumulator.records(node, holding=slots.flags[gas], watched=self.gas_volume > 0.0,
                                     energy=slots.energy[gas], event=slots.events[gas]),
                NW.record(NW.ORIFICE, source=node, target=node_of(slots, self, "drain"),
                          coefficient=self.flow_coefficient, ptr2=oil.transition_pressure ** 2,
                          energy=slots.energy["orifices"])]
