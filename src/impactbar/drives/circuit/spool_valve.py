r"""A pilot-operated spool valve in place of the preset's ramped valve (theory §11, *Parts of a drill's
circuit*): a part of its own (:class:`~impactbar.drives.circuit.CircuitPart`) that stands in for the
valve (``replaces = ("valve",)``), its equations in :mod:`.kinds.spool` (the spool), :mod:`.kinds.spool_port`
(its main ports), :mod:`.kinds.cushion` (the pilot ports the piston uncovers) and :mod:`.kinds.level`
(their kinks).

References
----------
Hopsan's component library, ``componentLibraries/defaultLibrary/Hydraulic``:
``Valves/Hydraulic43Valve.hpp`` (a spool's ports' openings with a lap, its ``x_0`` overlap),
``Valves/HydraulicPressureControlledValve.hpp`` (a spool driven by pressures on its ends, with mass
and damping, stopped at its ends), ``Volumes&Lines/HydraulicVolume.hpp`` (the control chamber);
Merritt, *Hydraulic Control Systems* (Wiley, 1967), ch. 5 (spool valves, their lap).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._network import CUSHION, LEVEL, NODE, SPOOL, SPOOL_PORT, record
from .composition import NamedPart, PartField
from .cushion import opening_segment
from .kinds.level import SPOOL as AT_SPOOL
from .kinds.spool import stop_quantity

__all__ = ["SpoolValve", "port_openings"]

_ORIFICE = "m**3/s/Pa**0.5"


def port_openings(x, lap):
    """The main ports' openings ``(o_P, o_T)`` at the spool's position ``x = x_s / h_s`` with the lap
    ``l`` (a fraction of the stroke; ``l > 0`` overlap: both shut for ``|x - 1/2| < l / 2``):
    ``o_P = clip((x - (1 + l)/2) / ((1 - l)/2), 0, 1)``, ``o_T = clip(((1 - l)/2 - x) / ((1 - l)/2), 0, 1)``.

    Examples
    --------
    >>> port_openings(0.0, 0.2), port_openings(0.5, 0.2), port_openings(1.0, 0.2)
    ((0.0, 1.0), (0.0, 0.0), (1.0, 0.0))
    """
    h = 0.5 * (1.0 - lap)
    return (float(np.clip((x - 0.5 * (1.0 + lap)) / h, 0.0, 1.0)), float(np.clip((h - x) / h, 0.0, 1.0)))


@dataclass(frozen=True)
class SpoolValve(NamedPart):
    r"""A pilot-operated spool valve in the preset valve's place: a spool of mass ``m_s`` and stroke
    ``h_s`` (its position ``x_s``, ``x = x_s / h_s`` the state ``x_v``), viscous damping ``b_s``,
    :math:`m_s x_s'' = p_c A_c - p_s A_0 - b_s x_s'`: the control chamber's pressure ``p_c`` on its large
    end ``A_c`` opens it, the supply's on its small end ``A_0 < A_c`` closes it. At a stop (``x = 0``,
    ``1``) it stops (inelastic: its kinetic energy is lost) and rests while the force pushes it in or is
    zero; it leaves when the force points strictly away. Its main ports: supply -> rear chamber through
    ``K_v o_P(x)``, rear chamber -> the valve's return port through ``K_v o_T(x)``
    (:func:`port_openings`, lap ``l``). The control chamber (a node named ``name``, volume
    ``V_c + A_c x_s``) is switched by the ports the piston uncovers: to the supply through
    ``K_c a_P(y)``, ``a_P = clip((y - y_open) / d_y + 1, 0, 1)``, and to the return through
    ``K_c a_T(y)``, ``a_T = clip((y_close - y) / d_y + 1, 0, 1)``, shut between (its memory). The
    spool's small end is a volume of the supply node, ``V_s - A_0 x_s``. The spool's velocity is a
    state of its own (a node ``<name>_v``, :mod:`.kinds.spool`).

    Events: the valve's ``ramp_end`` (its slot kept, never armed), the spool's arrival at a stop and
    its leaving it (``<name>_stop``), the main ports' kinks
    (``<name>_open_p``, ``<name>_open_t``: ``x`` through ``(1 + l)/2``, ``(1 - l)/2``), the pilot
    ports' kinks (``<name>_pilot0`` .. ``3``: ``y`` through ``y_open - d_y``, ``y_open``, ``y_close``,
    ``y_close + d_y``). Energy integrands: the main ports' loss (``<name>_ports``) and the pilot's
    (``<name>_pilot``, ``orifices``), the control chamber's compression (``name``), and in the
    account's ``spool`` term the kinetic energy's rate less the stops' losses
    :math:`\int m_s x_s' x_s'' dt` (``<name>_kinetic``: over a period the stops' losses) and the
    damping's :math:`\int b_s x_s'^2 dt` (``<name>_damping``). The limit ``m_s``, ``b_s``, ``V_c``,
    ``h_s`` to 0 (``h_s`` with ``m_s``) and ``K_c`` to infinity is the preset's valve with
    ``tau_v = 0``, ``switch_out = y_open - d_y``, ``switch_in = y_close + d_y``. The kind
    ``"spool_valve"`` of a configuration's ``[parts.<name>]`` table.

    Parameters
    ----------
    mass : float
        ``m_s > 0`` (the piston's mass scale).
    stroke : float
        ``h_s > 0`` (bar lengths).
    damping : float
        :math:`b_s \ge 0` (the piston's mass times the circuit's frequency scale).
    large_area, small_area : float
        ``A_c > A_0 > 0`` (the rear area's scale).
    control_volume : float
        ``V_c > 0``, the control chamber's volume with the spool shut (``A_r L``).
    coefficient : float
        ``K_v > 0``, the main ports' fully open coefficient (an orifice's, model units).
    pilot_coefficient : float
        ``K_c > 0``, the pilot ports' fully open coefficient.
    lap : float
        ``l`` in ``(-1, 1)``, a fraction of the stroke.
    open_gap, close_gap, port_span : float
        ``y_open``, ``y_close``, ``d_y > 0`` (bar lengths), ``y_close + d_y < y_open - d_y``.
    name : str, optional
        Its control chamber's name, its events', integrands' and parameters' prefix, an identifier.
    port : str, optional
        The preset's port its return ports drain to (``"valve_return"``: the tank, or the node of a
        part that takes it).

    Raises
    ------
    ValueError
        A value out of its range, :math:`A_0 \ge A_c`, the pilot ports overlapping.

    Examples
    --------
    >>> from dataclasses import replace
    >>> from impactbar.physical import circuit_preset
    >>> sv = SpoolValve(mass=0.02, stroke=0.01, damping=0.0, large_area=0.3, small_area=0.15,
    ...                 control_volume=0.01, coefficient=2.0, pilot_coefficient=2.0, lap=0.1,
    ...                 open_gap=0.05, close_gap=0.01, port_span=0.005)
    >>> drive = replace(circuit_preset("circuit-drifter").drive(), extra_parts=(sv,))
    >>> drive.layout.states, drive.layout.state_names[-3:]  # doctest: +NORMALIZE_WHITESPACE
    (('front', 'rear', 'supply', 'spool_valve', 'spool_valve_v', 'spool'),
     ('p_spool_valve', 'v_spool_valve', 'x_v'))
    """

    mass: float
    stroke: float
    damping: float
    large_area: float
    small_area: float
    control_volume: float
    coefficient: float
    pilot_coefficient: float
    lap: float
    open_gap: float
    close_gap: float
    port_span: float
    name: str = "spool_valve"
    port: str = "valve_return"

    replaces = ("valve",)
    #: the valve's return port, offered as the valve offered it (the tank where no part takes it)
    offers = {"valve_return": "tank"}
    si_fields = (
        PartField("mass", "kg", "'0.2 kg'", "mass", description="the spool's mass"),
        PartField("stroke", "m", "'8 mm'", "length", description="the spool's stroke"),
        PartField("damping", "N*s/m", "'50 N*s/m'", "damping", low_open=False,
                  description="the spool's viscous damping"),
        PartField("large_area", "m**2", "'3 cm^2'", "area",
                  description="the spool's large end area (the control pressure's: opens it)"),
        PartField("small_area", "m**2", "'1.5 cm^2'", "area",
                  description="the spool's small end area (the supply pressure's: closes it)"),
        PartField("control_volume", "m**3", "'10 cm^3'", "volume",
                  description="the control chamber's volume with the spool shut"),
        PartField("coefficient", _ORIFICE, "'7.5e-6 m^3/s/Pa^0.5'", "orifice",
                  description="the spool valve's main ports' full opening coefficient"),
        PartField("pilot_coefficient", _ORIFICE, "'2e-6 m^3/s/Pa^0.5'", "orifice",
                  description="the pilot ports' full opening coefficient"),
        PartField("lap", "", "0.1", "one", low=-1.0, high=1.0,
                  description="the spool's lap, a fraction of its stroke (> 0 overlap)"),
        PartField("open_gap", "m", "'40 mm'", "length",
                  description="the piston's gap where the pilot's supply port is fully open"),
        PartField("close_gap", "m", "'5 mm'", "length",
                  description="the piston's gap where the pilot's return port is fully open"),
        PartField("port_span", "m", "'2 mm'", "length", description="the pilot ports' opening span"))
    connections = {"port": ("port", "valve_return")}

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.small_area < self.large_area:
            raise ValueError(f"{self.name}.small_area must be below large_area {self.large_area:g} (the "
                             f"control pressure must be able to open the spool); got {self.small_area:g}")
        if not self.close_gap + self.port_span < self.open_gap - self.port_span:
            raise ValueError(f"{self.name}: close_gap + port_span must be below open_gap - port_span (the "
                             f"pilot's ports must not overlap); got {self.close_gap:g} + {self.port_span:g} "
                             f">= {self.open_gap:g} - {self.port_span:g}")

    @staticmethod
    def schematic_edges(name: str, ret: str) -> tuple:
        """The edges ``(source, target, what)`` of a spool valve named ``name`` in the circuit's graph
        (:func:`~impactbar.physical.circuit_graph.circuit_graph`), as :meth:`records` joins them: its
        main ports (the supply to the rear chamber, the rear chamber to ``ret``, the node the valve's
        return port joins) and its pilot ports (the supply to its control chamber ``name``, the
        chamber to ``ret``).

        Examples
        --------
        >>> [e[:2] for e in SpoolValve.schematic_edges("spool", "tank")]
        [('supply', 'rear'), ('rear', 'tank'), ('supply', 'spool'), ('spool', 'tank')]
        """
        return (("supply", "rear", "main port P"), ("rear", ret, "main port T"),
                ("supply", name, "pilot supply port"), (name, ret, "pilot return port"))

    @property
    def nodes(self) -> tuple:
        """The control chamber (``name``) and the spool's velocity (``<name>_v``)."""
        return (self.name, f"{self.name}_v")

    @property
    def symbols(self) -> tuple:
        return (f"p_{self.name}", f"v_{self.name}")

    @property
    def mechanical(self) -> tuple:
        return (f"{self.name}_v",)

    @property
    def energies(self) -> tuple:
        n = self.name
        return ((f"{n}_ports", "orifices"), (f"{n}_pilot", "orifices"), (n, "compression"),
                (f"{n}_kinetic", "spool"), (f"{n}_damping", "spool"))

    @property
    def events(self) -> tuple:
        n = self.name  # (the valve's ramp's end first, its slot kept: never armed)
        return ("ramp_end", self.stop_event, f"{n}_open_p", f"{n}_open_t",
                *(f"{n}_pilot{i}" for i in range(4)))

    @property
    def stop_event(self) -> str:
        """The name of the spool's arrival at a stop (its event, :meth:`at_event`)."""
        return f"{self.name}_stop"

    @property
    def pilot_gaps(self) -> tuple:
        """The pilot ports' kinks: ``(y_open - d_y, y_open)`` (its supply port's), ``(y_close,
        y_close + d_y)`` (its return port's)."""
        return ((self.open_gap - self.port_span, self.open_gap),
                (self.close_gap, self.close_gap + self.port_span))

    def at_event(self, event, flag, z, layout):
        """At the spool's arrival at a stop (``<name>_stop`` to 1): the spool put on the stop at rest,
        and left free where the force already points away from it."""
        if flag != 1 or event != self.stop_event:
            return flag, z
        z = np.array(z, dtype=float)
        x = 1.0 if z[layout["spool"]] >= 0.5 else 0.0
        z[layout["spool"]], z[layout[f"{self.name}_v"]] = x, 0.0
        force = self.large_area * z[layout[self.name]] - self.small_area * z[layout["supply"]]
        return (1 if stop_quantity(x, force) >= 0.0 else 0), z

    def records(self, slots, oil) -> list:
        """The control chamber's and the velocity's nodes, the spool (:mod:`.kinds.spool`), its main
        ports (:mod:`.kinds.spool_port`) and the pilot ports (:mod:`.kinds.cushion`) on the pieces
        the mode's flags give, and their kinks' watched levels (:mod:`.kinds.level`)."""
        n, f, ev, en = self.name, slots.flags, slots.events, slots.energy
        c, v = slots.node(n, self), slots.node(f"{n}_v", self)
        supply, rear, ret = slots.nodes["supply"], slots.nodes["rear"], slots.ports["valve_return"]
        _, stop, open_p, open_t, p0, p1, p2, p3 = self.events
        ptr2, lap = oil.transition_pressure ** 2, self.lap
        h = 0.5 * (1.0 - lap)
        kp_i, kp_s = (-(0.5 * (1.0 + lap)) / h, 1.0 / h) if f[open_p] else (0.0, 0.0)
        kt_i, kt_s = (0.0, 0.0) if f[open_t] else (1.0, -1.0 / h)
        (a0, a1), (t0, t1) = self.pilot_gaps
        ap_i, ap_s = opening_segment((a0, a1), (0.0, 1.0), (f[p0], f[p1]))
        at_i, at_s = opening_segment((t0, t1), (1.0, 0.0), (f[p2], f[p3]))
        ports, pl = slots.loss(f"{n}_ports"), slots.loss(f"{n}_pilot")
        out = [record(NODE, id=c, volume=self.control_volume, beta=oil.bulk_modulus,
                      compression_energy=en[n]),
               record(NODE, id=v, volume=self.mass, beta=1.0, held=f[stop],
                      compression_energy=en[f"{n}_kinetic"]),
               record(SPOOL, control=c, supply=supply, velocity=v, large_area=self.large_area,
                      small_area=self.small_area, stroke=self.stroke, damping=self.damping,
                      energy=en[f"{n}_damping"], event=ev[stop]),
               record(SPOOL_PORT, source=supply, target=rear, coefficient=self.coefficient, ptr2=ptr2,
                      intercept=kp_i, slope=kp_s, energy=ports),
               record(SPOOL_PORT, source=rear, target=ret, coefficient=self.coefficient, ptr2=ptr2,
                      intercept=kt_i, slope=kt_s, energy=ports),
               record(LEVEL, gap=AT_SPOOL, level=0.5 * (1.0 + lap), on=f[open_p], event=ev[open_p]),
               record(LEVEL, gap=AT_SPOOL, level=h, on=f[open_t], event=ev[open_t]),
               record(CUSHION, source=supply, target=c, coefficient=self.pilot_coefficient, ptr2=ptr2,
                      intercept=ap_i, slope=ap_s, energy=pl),
               record(CUSHION, source=c, target=ret, coefficient=self.pilot_coefficient, ptr2=ptr2,
                      intercept=at_i, slope=at_s, energy=pl)]
        for e, y in zip((p0, p1, p2, p3), (a0, a1, t0, t1), strict=True):
            out.append(record(LEVEL, gap=1, level=y, on=f[e], event=ev[e]))
        return out
