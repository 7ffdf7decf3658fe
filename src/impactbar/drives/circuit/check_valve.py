r"""A check valve between two nodes of the circuit (theory §11, *Parts of a drill's circuit*): a
part of its own (:class:`~impactbar.drives.circuit.CircuitPart`), its equations in
:mod:`.kinds.check` (the flow) and :mod:`.kinds.level` (its kinks).

References
----------
Hopsan's component library, ``componentLibraries/defaultLibrary/Hydraulic``:
``Restrictors/HydraulicCheckValve.hpp`` (a turbulent orifice open one way),
``Restrictors/HydraulicCheckValvePreLoaded.hpp`` (with a cracking pressure),
``Valves/PressureControlValves/HydraulicPressureControlledValve.hpp`` (an opening that rises with the
pressure over a span).
"""

from __future__ import annotations

from dataclasses import dataclass

from ._network import CHECK, LEVEL, record
from .composition import PartField
from .leakage import BetweenNodes

__all__ = ["CheckValve"]


@dataclass(frozen=True)
class CheckValve(BetweenNodes):
    r"""A check valve from node ``source`` to node ``target``: ``q = K_cv o(dp) phi(dp)``,
    ``dp = p_source - p_target``, opening ``o(dp) = clip((dp - p_crack) / dp_open, 0, 1)``: shut
    below its cracking pressure, fully open ``dp_open`` above it. Its kinks are events of the flights
    (``<name>_crack`` at ``dp = p_crack``, ``<name>_open`` at ``p_crack + dp_open``); its loss
    :math:`\int q \, dp \, dt` an energy integrand of its own (``name``, in ``orifices``).
    ``K_cv = 0`` removes it. The kind ``"check_valve"`` of a configuration's ``[parts.<name>]`` table
    (its parameters ``<name>.<field>``).

    Parameters
    ----------
    source, target : str
        The nodes it joins (the preset's ``front``, ``rear``, ``supply``, ``tank`` or another part's).
    coefficient : float
        :math:`K_{cv} \ge 0`, its fully open flow coefficient (model units, as an orifice's).
    cracking_pressure : float
        :math:`p_\mathrm{crack} \ge 0` (the pressure scale).
    opening_span : float
        :math:`\Delta p_\mathrm{open} > 0`: the pressure over which it opens fully.
    name : str, optional
        Its events', integrand's and parameters' prefix (``<name>.coefficient``, ...), an identifier.

    Raises
    ------
    ValueError
        A value out of its range, the same node twice.

    Examples
    --------
    >>> from dataclasses import replace
    >>> from impactbar.physical import circuit_preset
    >>> cv = CheckValve("front", "supply", coefficient=1.0, cracking_pressure=0.05, opening_span=0.1)
    >>> drive = replace(circuit_preset("circuit-drifter").drive(), extra_parts=(cv,))
    >>> [e.name for e in drive.events((1, 0, 1, 0, 0, 0))][-2:]
    ['check_crack', 'check_open']
    """

    source: str
    target: str
    coefficient: float
    cracking_pressure: float
    opening_span: float
    name: str = "check"

    si_fields = (
        PartField("coefficient", "m**3/s/Pa**0.5", "'1e-6 m^3/s/Pa^0.5'", "orifice", low_open=False,
                  description="the check valve's full opening coefficient"),
        PartField("cracking_pressure", "Pa", "'0.5 MPa'", "pressure", low_open=False,
                  description="the check valve's cracking pressure"),
        PartField("opening_span", "Pa", "'1 MPa'", "pressure",
                  description="the pressure over which the check valve opens"))
    @property
    def events(self) -> tuple:
        return (f"{self.name}_crack", f"{self.name}_open")

    def records(self, slots, oil) -> list:
        """The valve's flow (:mod:`.kinds.check`) on the piece of ``o`` the mode's flags give, and
        its two kinks' watched levels (:mod:`.kinds.level`)."""
        a, b = slots.node(self.source, self), slots.node(self.target, self)
        crack, full = self.events
        p0, span = self.cracking_pressure, self.opening_span
        k = int(slots.flags[crack]) + int(slots.flags[full])
        intercept, slope = ((0.0, 0.0), (-p0 / span, 1.0 / span), (1.0, 0.0))[k]
        return [record(CHECK, source=a, target=b, coefficient=self.coefficient,
                       ptr2=oil.transition_pressure ** 2, intercept=intercept, slope=slope,
                       energy=slots.loss(self.name)),
                record(LEVEL, source=a, target=b, level=p0, on=slots.flags[crack], event=slots.events[crack]),
                record(LEVEL, source=a, target=b, level=p0 + span, on=slots.flags[full],
                       event=slots.events[full])]
