r"""The drifter's oil circuit as a composition of parts (theory §11): the protocol of a part and the
numbering of the circuit's nodes, energy and event slots and layout from its parts, the preset's and
the extra ones alike.

A part (:class:`CircuitPart`) names its nodes (each with a pressure state; :attr:`~CircuitPart.held_nodes`
without one, held at their pressure: the tank), its energy integrands (each with the term of the
account it belongs to), its watched events, the ports it offers to other parts (each to the node it
joins unless a part takes it) and those it takes, and the parts it replaces by name.
:func:`compose_parts` puts the extra parts after the circuit's own (the preset's,
:mod:`~impactbar.drives.circuit.preset`: ``chambers``, ``supply``, ``valve``, ``accumulator``,
``relief``), each part that :attr:`~CircuitPart.replaces` one of them in its place, and numbers what
they declare in that order: the nodes with a state first, then the held ones; the account's shared
integrands (:data:`SHARED_ENERGIES`) then the parts'; the events. Each part's
:meth:`CircuitPart.records` writes its network records (:mod:`._network`) with those numbers, and
:meth:`Composition.network` gathers them. Nothing here names a part's kind: a part made of the
network's kinds needs no edit of the drive or of a kernel. A part may
change the state at its own events (:meth:`CircuitPart.at_event`: a spool valve, which replaces the
preset's valve, stopped at its stop).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..._shared.validate import check_real
from . import _network as NW
from .layout import _TERMS, PRESET, CircuitLayout

__all__ = ["CircuitPart", "PartField", "PartSlots", "Composition", "compose_parts", "TERMS",
           "SHARED_ENERGIES", "NamedPart", "check_part", "node_of", "NO_PORT"]

#: a port connection's value for a part that takes no port (a return line that a cushion drains into)
NO_PORT = "none"

#: the terms of the energy account (:class:`~impactbar.drives.circuit.CircuitEnergy`) an energy
#: integrand can belong to
TERMS = _TERMS

#: the energy integrands the composition opens with, before the parts' own: one for each term the
#: parts share, which a part adds to by name (a pump's work, the oil's work on the piston, every
#: orifice's loss, the flow into the tank at its pressure)
SHARED_ENERGIES = (("pump", "pump"), ("piston", "piston"), ("orifices", "orifices"), ("tank", "tank"))


class CircuitPart:
    r"""The protocol of a part added to the oil circuit (``HydraulicCircuitDrive(...,
    extra_parts=(part, ...))``): a frozen dataclass (hashable: the drive's caches are keyed by it)
    with these class attributes and :meth:`records`. A part is written in the user's own file, of
    the network's kinds (:func:`~impactbar.drives.circuit.record`): a node of oil (``NODE``: its
    volume and bulk modulus, a pressure state), a pump (``PUMP``), a turbulent orifice (``ORIFICE``:
    ``q = K phi(p_source - p_target)``, ``phi`` the orifice law smoothed below the oil's transition
    pressure), a relief valve (``RELIEF``), a chamber on the piston (``CHAMBER``), a gas accumulator
    (``ACCUM``), and the kinds written each in a module of its own (:mod:`.kinds`: laminar leakage
    ``LEAK``, a position-controlled orifice ``CUSHION``, a check valve ``CHECK``, a watched level of
    the piston's gap or of a pressure drop ``LEVEL``); the drive composes it with the preset's parts,
    and the code generated for the composed network (its flights, their variational equations, the
    coupled blows on the rod and rock) runs it with no edit of the drive or of a kernel.

    Attributes
    ----------
    name : str or None
        Its name among the circuit's parts (the preset's ``chambers``, ``supply``, ``valve``,
        ``accumulator``, ``relief``; a :class:`NamedPart`'s field); ``None``: none.
    nodes : tuple of str
        Its nodes, each with a pressure state (the names of the drive's layout; distinct from the
        preset's ``front``, ``rear``, ``supply``, ``spool``, ``tank`` and the other parts').
    symbols : tuple of str
        The nodes' symbols (``"p_ret"``), the keys of the histories.
    held_nodes : tuple of str
        Its nodes held at their pressure, without a state (the preset supply's ``tank``).
    energies : tuple of (str, str)
        Its energy integrands: ``(name, term)`` pairs, ``term`` one of :data:`TERMS` (the term of
        the account each adds to: ``"compression"`` for an oil volume's, ``"accumulator"`` for a
        gas's, ``"orifices"`` for an orifice's loss). It may also add to the preset's integrands by
        name (``"orifices"``, ``"tank"``).
    events : tuple of str
        Its watched events (each an accumulator's or a relief's pressure through its level, or a
        ``LEVEL`` record's gap or pressure drop through its level), one flag of the drive's mode
        each.
    ports : dict
        The ports of the circuit's parts it takes over (:data:`~impactbar.drives.circuit.PORTS`, those
        the parts :attr:`offers`), each to one of its nodes by name: ``{"valve_return": "return"}``
        joins the valve's return port to its node ``return`` instead of the tank.
    offers : dict
        The ports it offers, each to the node it joins where no part takes it (the preset valve's
        ``{"valve_return": "tank"}``); its records read the node's number from
        :attr:`PartSlots.ports`.
    replaces : tuple of str
        The circuit's parts it takes the place of, by :attr:`name`: ``("valve",)`` puts it where the
        preset's valve was (its nodes, energy integrands, events and records in the valve's place),
        and the valve's records leave the network. It then offers what it replaces offered that
        other parts use (a replacing valve its ``valve_return``), and writes the records the network
        needs (exactly one ``VALVE`` or ``SPOOL``, :func:`._network.compose`). A part that replaces the
        valve with records of another kind (a spool valve, :class:`~impactbar.drives.circuit.SpoolValve`,
        its state the network's ``x_v``) leaves the drive's switches, ramp and impact's closing unused.
    parameters : dict
        Its continuation parameters: the drive's parameter name to the part's field
        (``{"return_volume": "volume"}``); ``parameter_ranges`` their ranges as
        :data:`~impactbar.drives.circuit.drive.PARAMETERS`' (optional).
    si_fields : tuple of PartField
        Its fields as a configuration gives them in SI (optional: for a kind a config's
        ``[parts.<name>]`` builds, :func:`impactbar.physical.register_part`).
    connections : dict
        Its fields that name a node or a port, each to ``("node" | "port", default)`` (optional, as
        ``si_fields``).
    si_lists : tuple of PartField
        Its fields that hold a list of values (a configuration's array, each element in the field's
        unit and range; optional, as ``si_fields``; not a parameter).
    mechanical : tuple of str
        Its nodes whose state is not a pressure (a spool's velocity; optional): they start at 0, may be
        negative and are not watched for cavitation.

    See Also
    --------
    impactbar.drives.circuit.record : a part's network record, by kind and fields.
    impactbar.drives.circuit.PartSlots : the numbers a part writes its records with.

    Examples
    --------
    A leak from the front chamber to the tank through an orifice of coefficient ``K`` (model units,
    :mod:`~impactbar.drives.circuit.parts`), its loss an energy integrand of its own:

    >>> from dataclasses import dataclass, replace
    >>> from impactbar.drives.circuit import ORIFICE, CircuitPart, record
    >>> @dataclass(frozen=True)
    ... class Leak(CircuitPart):
    ...     coefficient: float
    ...     energies = (("leak", "orifices"),)
    ...     parameters = {"leak_coefficient": "coefficient"}
    ...     def records(self, slots, oil):
    ...         return [record(ORIFICE, source=slots.nodes["front"], target=slots.nodes["tank"],
    ...                        coefficient=self.coefficient, ptr2=oil.transition_pressure ** 2,
    ...                        energy=slots.energy["leak"])]
    >>> from impactbar.drives.circuit.preset import PRESET_PARTS
    >>> compose_parts((Leak(0.1),), PRESET_PARTS).layout.energies[-1]
    'leak'
    >>> from impactbar.physical import circuit_preset
    >>> drive = replace(circuit_preset("circuit-drifter").drive(), extra_parts=(Leak(0.1),))
    >>> drive.with_(leak_coefficient=0.2).value("leak_coefficient")
    0.2
    """

    name = None
    nodes: tuple = ()
    symbols: tuple = ()
    #: its nodes held at their pressure (no state; numbered after every node with one)
    held_nodes: tuple = ()
    energies: tuple = ()
    events: tuple = ()
    ports: dict = {}
    #: the ports it offers to other parts, each to the node it joins unless a part takes it
    offers: dict = {}
    #: the circuit's parts it takes the place of, by name
    replaces: tuple = ()
    parameters: dict = {}
    parameter_ranges: dict = {}
    #: its fields a configuration gives in SI (:class:`PartField`; read where the part's kind is
    #: registered, :func:`impactbar.physical.register_part`)
    si_fields: tuple = ()
    #: its fields that name a node or a port: field to ``("node" | "port", default)`` (``None``:
    #: required)
    connections: dict = {}
    #: its fields that hold a list of values, each in the :class:`PartField`'s unit and range
    si_lists: tuple = ()
    #: its nodes whose state is not a pressure
    mechanical: tuple = ()

    def at_event(self, event: str, flag: int, z, layout) -> tuple:
        """The mode's flag and the circuit's state ``z`` after the part's event ``event`` (its flag
        toggled to ``flag``): unchanged, unless the part says otherwise (a spool's arrival at its
        stop stops it).

        Returns
        -------
        tuple
            ``(flag, z)``.
        """
        return flag, z

    def records(self, slots: PartSlots, oil) -> list:
        """The part's network records (:func:`._network.record`).

        Parameters
        ----------
        slots : PartSlots
            The numbers of the nodes (the preset's and its own), the energy slots and its events'
            slots, by name, and its events' flags in the drive's mode.
        oil : Oil
            The circuit's oil (its bulk modulus and transition pressure).

        Returns
        -------
        list of numpy.ndarray
        """
        raise NotImplementedError


@dataclass(frozen=True)
class PartField:
    """One of a part's fields as a configuration gives it in SI: its unit, the scale that makes it
    dimensionless and its range, declared once with the part's class (in the terms of
    :class:`impactbar.physical.tree.Field`; plain strings here, the units read on the SI side).

    Parameters
    ----------
    name : str
        The part's dataclass field and the config's key (``"volume"``).
    unit : str
        Its SI unit in pint's spelling (``"m**3"``; ``""`` for a bare number).
    example : str
        An example value as a config writes it (``"'0.2 L'"``).
    scale : str
        The name of its scale in :data:`impactbar.physical.tree.SCALES` (``"volume"``, ``"orifice"``,
        ``"pressure"``, ``"one"``, ...).
    low, high : float, optional
        Its range (default: above 0). The scales are positive factors, so a range of 0 and ``inf``
        holds for the SI value and the dimensionless one alike; any other bound needs the scale
        ``"one"``.
    low_open, high_open : bool, optional
        Whether the bound is excluded (default: both).
    default : str or float or None, optional
        The value of a key left out (as a config writes it); ``None``: required.
    description : str, optional
        What it is, in a few words (the parameter table's).

    Raises
    ------
    ValueError
        A bound other than 0 or ``inf`` on a scale other than ``"one"``.
    """

    name: str
    unit: str
    example: str
    scale: str
    low: float = 0.0
    high: float = math.inf
    low_open: bool = True
    high_open: bool = True
    default: str | float | None = None
    description: str = ""

    def __post_init__(self) -> None:
        if self.scale != "one" and (self.low not in (0.0, -math.inf) or self.high != math.inf):
            raise ValueError(f"the field {self.name}'s range ({self.low}, {self.high}) must be 0 to inf on "
                             f"the scale {self.scale!r} (a bound moves with the scale): give it the scale "
                             "'one'")

    @property
    def range(self) -> dict:
        """Its range as the drive's ``parameter_ranges`` give one."""
        out = {"low": self.low, "low_open": self.low_open, "description": self.description}
        if math.isfinite(self.high):
            out["high"] = self.high
        out["high_open"] = self.high_open
        return out

    def check(self, label: str, value) -> float:
        """``value`` as a float in the field's range, else a :class:`ValueError` naming ``label``."""
        return check_real(label, value, lo=self.low if math.isfinite(self.low) else None,
                          hi=self.high if math.isfinite(self.high) else None, lo_open=self.low_open,
                          hi_open=self.high_open)


def check_part(part: CircuitPart) -> None:
    """Check a part's :attr:`~CircuitPart.si_fields` against their ranges (in place, as floats), its
    :attr:`~CircuitPart.si_lists` element by element (in place, as tuples of floats) and its name:
    the ``__post_init__`` of a part made of them.

    Raises
    ------
    ValueError
        A value out of its range, or a name that is not an identifier (each named).
    """
    name = getattr(part, "name", "")
    if not (isinstance(name, str) and name.isidentifier()):
        raise ValueError(f"a {type(part).__name__}'s name must be an identifier (its node's and its "
                         f"parameters'); got {name!r}")
    for f in part.si_fields:
        object.__setattr__(part, f.name, f.check(f"{name}.{f.name}", getattr(part, f.name)))
    for f in part.si_lists:
        values = np.atleast_1d(getattr(part, f.name)).tolist()
        object.__setattr__(part, f.name, tuple(f.check(f"{name}.{f.name}", v) for v in values))


class OwnNode:
    """A part with one node of its own, named as the part (its pressure ``p_<name>``): the
    mixin of :class:`~impactbar.drives.circuit.ReturnAccumulator` and
    :class:`~impactbar.drives.circuit.Cushion` (before :class:`NamedPart` in their bases)."""

    @property
    def nodes(self) -> tuple:
        """Its node, by its name."""
        return (self.name,)

    @property
    def symbols(self) -> tuple:
        """Its pressure's symbol ``p_<name>``."""
        return (f"p_{self.name}",)


class NamedPart(CircuitPart):
    """A :class:`CircuitPart` with a ``name`` field and :attr:`~CircuitPart.si_fields`: its
    parameters are ``<name>.<field>`` (each field's range), checked on construction
    (:func:`check_part`). A base for a part's frozen dataclass."""

    def __post_init__(self) -> None:
        check_part(self)

    @property
    def parameters(self) -> dict:
        """``<name>.<field>`` to its field, for each of :attr:`~CircuitPart.si_fields`."""
        return {f"{self.name}.{f.name}": f.name for f in self.si_fields}

    @property
    def parameter_ranges(self) -> dict:
        """The ranges of :attr:`parameters`."""
        return {f"{self.name}.{f.name}": f.range for f in self.si_fields}


def node_of(slots: PartSlots, part: CircuitPart, connection: str) -> int:
    """The number of the node a part's ``connection`` field names.

    Raises
    ------
    ValueError
        A node the circuit does not have (the nodes listed).
    """
    node = getattr(part, connection)
    if node not in slots.nodes:
        raise ValueError(f"{part.name}.{connection} must be one of the circuit's nodes {tuple(slots.nodes)}; "
                         f"got {node!r}")
    return slots.nodes[node]


@dataclass(frozen=True)
class PartSlots:
    """What :meth:`CircuitPart.records` writes its records with.

    Attributes
    ----------
    nodes : dict
        Every node's number by name (the preset's ``front``, ``rear``, ``supply``, ``tank``, the
        extra parts' nodes).
    energy : dict
        Every energy integrand's slot by name.
    events : dict
        The part's events' slots in the network (slot 0 the valve's ramp's end) by name.
    flags : dict
        The part's events' flags in the drive's mode by name (``True``: an accumulator holds oil, a
        relief is open, the valve's spool ramps).
    ports : dict
        The parts' ports (:attr:`CircuitPart.offers`) to the numbers of the nodes they join.
    mode : tuple
        The drive's mode ``(target, moving, flags...)`` (the valve's commanded position first).
    """

    nodes: dict
    energy: dict
    events: dict
    flags: dict
    ports: dict = dataclasses.field(default_factory=dict)
    mode: tuple = ()

    def node(self, name: str, part) -> int:
        """The number of the node ``name`` that ``part`` names (a clear error where there is none).

        Raises
        ------
        ValueError
            No node of that name in the circuit.
        """
        if name not in self.nodes:
            raise ValueError(f"a {type(part).__name__} names the node {name!r}; the circuit's nodes are "
                             f"{tuple(self.nodes)}")
        return self.nodes[name]

    def loss(self, name: str) -> int:
        """The energy slot of the loss integrand ``name``, or the preset's ``orifices`` where the part
        declares none of its own."""
        return self.energy.get(name, self.energy["orifices"])


@dataclass(frozen=True)
class Composition:
    """The circuit composed of its parts (:func:`compose_parts`).

    Attributes
    ----------
    layout : CircuitLayout
        States in node order then ``spool``, the shared energy integrands (:data:`SHARED_ENERGIES`)
        then the parts'.
    nodes : dict
        Every node's number by name (the ``n_states`` nodes with a state first, then the held ones).
    n_states : int
        The nodes with a pressure state.
    events : tuple of str
        The network's events in slot order (slot ``i``: the mode's flag ``1 + i``; slot 0 the valve's
        ramp's end, its flag whether the spool moves).
    ports : dict
        The parts' ports (:attr:`CircuitPart.offers`) to node numbers.
    parts : tuple of CircuitPart
        The parts in their order (the circuit's own, each replaced where a part replaces it, then the
        extra ones).
    """

    layout: CircuitLayout
    nodes: dict
    n_states: int
    events: tuple
    ports: dict
    parts: tuple = ()

    def slots(self, part: CircuitPart, mode) -> PartSlots:
        """The :class:`PartSlots` of ``part`` in the drive's mode ``mode`` (``(target, moving,
        flags...)``)."""
        ev = {name: self.events.index(name) for name in part.events}
        return PartSlots(nodes=self.nodes, energy=self.layout.energy, events=ev,
                         flags={name: bool(mode[1 + slot]) for name, slot in ev.items()},
                         ports=self.ports, mode=tuple(mode))

    def network(self, mode, oil) -> np.ndarray:
        """The circuit as a network of part records in the drive's mode ``mode``: each part's
        :meth:`~CircuitPart.records` in the parts' order, composed (:func:`._network.compose`).

        Parameters
        ----------
        mode : tuple
            ``(target, moving, flags...)``, a flag for each of :attr:`events` after the first.
        oil : Oil
            The circuit's oil.

        Returns
        -------
        numpy.ndarray
            The network's header and records.
        """
        recs: list = []
        for part in self.parts:
            recs += part.records(self.slots(part, mode), oil)
        return NW.compose(recs, self.n_states, self.layout.n_energy, len(self.events),
                          self.layout.energy["piston"])


def _in_place(base, parts) -> list:
    """The circuit's parts: ``base`` with each part of ``parts`` that :attr:`~CircuitPart.replaces`
    some of them in the place of the first it names (the others left out), then the rest of ``parts``."""
    names = [p.name for p in base]
    out: list = list(base)
    added, gone = [], set()
    for p in parts:
        replaced = tuple(p.replaces)
        if not replaced:
            added.append(p)
            continue
        for name in replaced:
            if name not in names or name in gone:
                raise ValueError(f"a {type(p).__name__} replaces the circuit's parts by name, each once: "
                                 f"one of {tuple(n for n in names if n is not None)}; got {name!r}")
            gone.add(name)
            out[names.index(name)] = None
        out[names.index(replaced[0])] = p
    return [p for p in out if p is not None] + added


def compose_parts(parts, base=()) -> Composition:
    """The circuit composed of its parts: its nodes, energy and event slots and layout.

    Parameters
    ----------
    parts : tuple of CircuitPart
        The extra parts, after the circuit's own; a part with :attr:`~CircuitPart.replaces` in the
        place of those it names.
    base : tuple of CircuitPart, optional
        The circuit's own parts: the preset's (:func:`~impactbar.drives.circuit.preset.preset_parts`
        of a drive, or :data:`~impactbar.drives.circuit.preset.PRESET_PARTS`, their names and
        numbering without a drive's values). Default: none.

    Returns
    -------
    Composition
        With the preset's parts alone: :data:`~impactbar.drives.circuit.layout.PRESET`, the tank node 3.

    Raises
    ------
    ValueError
        A part that is not a :class:`CircuitPart`, a name repeated, an energy term or a port that is
        not known, a port given to a node that is not the part's, a part replaced that the circuit
        does not have (or twice).

    Examples
    --------
    >>> from impactbar.drives.circuit.preset import PRESET_PARTS
    >>> c = compose_parts((), PRESET_PARTS)
    >>> c.layout is PRESET, c.nodes["tank"], c.events
    (True, 3, ('ramp_end', 'accumulator', 'relief'))
    >>> [p.name for p in c.parts]
    ['chambers', 'supply', 'valve', 'accumulator', 'relief']
    """
    parts = tuple(parts)
    for p in parts:
        if not isinstance(p, CircuitPart):
            raise ValueError(f"extra_parts must be CircuitPart instances; got {type(p).__name__}")
    circuit = _in_place(tuple(base), parts)
    nodes: list = []
    held: list = []
    symbols: list = []
    energies = [name for name, _ in SHARED_ENERGIES]
    terms = [term for _, term in SHARED_ENERGIES]
    events: list = []
    offers: dict = {}
    mechanical: list = []
    for p in circuit:
        mechanical += p.mechanical
        if len(p.symbols) != len(p.nodes):
            raise ValueError(f"a {type(p).__name__}'s symbols must name its nodes {p.nodes}; got {p.symbols}")
        nodes += p.nodes
        held += p.held_nodes
        symbols += p.symbols
        for name, term in p.energies:
            if term not in TERMS:
                raise ValueError(f"a {type(p).__name__}'s energy {name!r} must belong to one of {TERMS}; "
                                 f"got {term!r}")
            energies.append(name)
            terms.append(term)
        events += p.events
        for port, node in p.offers.items():
            if port in offers:
                raise ValueError(f"the port {port!r} is offered by two parts (a {type(p).__name__} again)")
            offers[port] = node
    taken: dict = {}
    for p in circuit:
        for port, node in p.ports.items():
            if port not in offers or port in taken or node not in p.nodes:
                raise ValueError(f"a {type(p).__name__} takes a port of {tuple(offers)} (one part each) to "
                                 f"one of its nodes {p.nodes}; got {port!r} to {node!r}")
            taken[port] = node
    names = nodes + ["spool"] + held
    if len(set(names)) != len(names) or len(set(events)) != len(events):
        raise ValueError(f"the parts' nodes and events must have names of their own; got nodes {nodes}, "
                         f"held nodes {held}, events {events}")
    number = {n: i for i, n in enumerate(nodes + held)}
    for port, node in offers.items():
        if taken.get(port, node) not in number:
            raise ValueError(f"the port {port!r} joins the node {node!r}; the circuit's nodes are "
                             f"{tuple(number)}")
    layout = CircuitLayout(states=(*nodes, "spool"), state_names=(*symbols, "x_v"), energies=tuple(energies),
                           terms=tuple(terms), mechanical=tuple(mechanical))
    return Composition(PRESET if layout == PRESET else layout, number, len(nodes), tuple(events),
                       {port: number[taken.get(port, node)] for port, node in offers.items()}, tuple(circuit))
