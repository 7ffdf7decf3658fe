r"""A turbulent leak between two nodes of the oil circuit (a worn seal's, a bypass's): an orifice

.. math::

    Q = K_\mathrm{leak}\,\phi(p_a - p_b)

from the node :math:`a` to the node :math:`b` (either way, by the sign of the drop; :math:`\phi` the
oil's smoothed orifice law, :class:`~impactbar.drives.circuit.Oil`), its loss
:math:`\int Q\,(p_a - p_b)\,dt` an energy integrand of its own in the account's ``orifices`` term. It
adds no state; :math:`K_\mathrm{leak} = 0` leaves the circuit as it is.
"""

from __future__ import annotations

from dataclasses import dataclass

from . import _network as NW
from .composition import NamedPart, PartField, node_of

__all__ = ["Leak"]


@dataclass(frozen=True)
class Leak(NamedPart):
    r"""A turbulent leak from ``source`` to ``target`` (the module's equation), dimensionless (units
    of :mod:`~impactbar.drives.circuit.parts`): a :class:`~impactbar.drives.circuit.CircuitPart`, or
    the kind ``"leak"`` of a configuration's ``[parts.<name>]`` table.

    Parameters
    ----------
    flow_coefficient : float
        :math:`K_\mathrm{leak}`, :math:`\ge 0` (0: no leak).
    source, target : str
        The nodes it joins (the preset's ``front``, ``rear``, ``supply``, ``tank`` or another part's),
        two different ones.
    name : str, optional
        Its name (an identifier: its energy integrand's and its parameter ``<name>.flow_coefficient``).
        Default ``"leak"``.

    Raises
    ------
    ValueError
        A coefficient out of its range, or ``source`` the same as ``target``.

    Examples
    --------
    >>> Leak(0.01, "rear", "front").parameters
    {'leak.flow_coefficient': 'flow_coefficient'}
    """

    flow_coefficient: float
    source: str
    target: str
    name: str = "leak"

    si_fields = (PartField("flow_coefficient", "m**3/s/Pa**0.5", "'1e-8 m^3/s/Pa^0.5'", "orifice",
                           low_open=False, description="the leak's flow coefficient"),)
    connections = {"source": ("node", None), "target": ("node", None)}

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.source == self.target:
            raise ValueError(f"{self.name}.target must be another node than its source; got {self.target!r} "
                             "for both")

    @property
    def energies(self) -> tuple:
        """Its loss, in the term ``orifices``."""
        return ((self.name, "orifices"),)

    def records(self, slots, oil) -> list:
        """Its orifice (:mod:`._network`)."""
        return [NW.record(NW.ORIFICE, source=node_of(slots, self, "source"),
                          target=node_of(slots, self, "target"), coefficient=self.flow_coefficient,
                          ptr2=oil.transition_pressure ** 2, energy=slots.energy[self.name])]
