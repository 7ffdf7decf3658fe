"""A drifter's oil circuit as a graph read from its configuration (theory §11, §13): its nodes (the
chambers, the supply, the tank and each part's own node) and its parts as labelled edges between
them (the pump, the front chamber's feed, the valve's two openings, the relief valve and each
``[parts.<name>]`` table's part), for the schematic (:func:`impactbar.plotting.plot_circuit_schematic`)
and for the lines of ``impactbar drifter`` that list the parts (:func:`part_lines`).
"""

from __future__ import annotations

from dataclasses import dataclass

from .circuit_parts import _has_node, part_kinds
from .display_units import format_key

__all__ = ["CircuitNode", "CircuitEdge", "CircuitGraph", "circuit_graph", "part_lines"]


@dataclass(frozen=True)
class CircuitNode:
    """A node of oil of the circuit.

    Attributes
    ----------
    name : str
        Its name in the configuration (``front``, ``rear``, ``supply``, ``tank``, a part's own).
    label : str
        What it is, in a few words.
    part : str
        The part whose node it is (``""``: the preset circuit's).
    """

    name: str
    label: str
    part: str = ""


@dataclass(frozen=True)
class CircuitEdge:
    """A part of the circuit between two nodes, its flow's positive way from ``source`` to ``target``.

    Attributes
    ----------
    source, target : str
        The nodes' names.
    label : str
        The part's name and kind.
    part : str
        The ``[parts.<name>]`` table's name (``""``: the preset circuit's).
    """

    source: str
    target: str
    label: str
    part: str = ""


@dataclass(frozen=True)
class CircuitGraph:
    """The circuit's nodes and its parts as edges (:func:`circuit_graph`).

    Attributes
    ----------
    nodes : tuple of CircuitNode
    edges : tuple of CircuitEdge
    """

    nodes: tuple
    edges: tuple


def _joins(cls, field: str) -> str:
    """What the field ``field`` of the part kind ``cls`` names: ``"node"`` or ``"port"``."""
    kind, _default = cls.connections[field]
    return kind


def circuit_graph(drifter) -> CircuitGraph:
    """The oil circuit of a drifter as its configuration gives it: the preset's nodes (``front``,
    ``rear``, ``supply``, ``tank``) and parts (the pump from the tank, the front chamber's feed, the
    valve's openings to the rear chamber and from it to its return port's node, the relief valve),
    then each ``[parts.<name>]`` part: its own node where it has one (a return line, a cushion),
    the valve's return port where it takes it, an edge to each node it connects to (from its own
    node, or from its first node to the others).

    Parameters
    ----------
    drifter : CircuitDrifter
        A drifter with its oil circuit (:func:`impactbar.physical.load`, its ``parts``).

    Returns
    -------
    CircuitGraph

    Examples
    --------
    >>> from impactbar.physical import circuit_preset
    >>> g = circuit_graph(circuit_preset("circuit-drifter"))
    >>> [n.name for n in g.nodes]
    ['supply', 'front', 'rear', 'tank']
    >>> [(e.source, e.target) for e in g.edges if e.label.startswith("valve")]
    [('supply', 'rear'), ('rear', 'tank')]
    """
    nodes = [CircuitNode("supply", "supply (pump, accumulator)"), CircuitNode("front", "front chamber"),
             CircuitNode("rear", "rear chamber"), CircuitNode("tank", "tank")]
    ports = {"valve_return": "tank"}
    edges, stand_in = [], None
    for spec in drifter.parts:
        cls = part_kinds()[spec.kind]
        linked = [v for c, v in spec.connections if _joins(cls, c) == "node"]
        if "valve" in getattr(cls, "replaces", ()):  # (in the valve's place: its edges, the valve's)
            stand_in = (spec, cls)
            nodes.append(CircuitNode(spec.name, f"{spec.name} ({spec.kind})", spec.name))
            continue
        if _has_node(cls):
            nodes.append(CircuitNode(spec.name, f"{spec.name} ({spec.kind})", spec.name))
            ports.update((v, spec.name) for c, v in spec.connections
                         if _joins(cls, c) == "port" and v in ports)
            ends = [(spec.name, v) for v in linked]
        else:
            ends = [(linked[0], v) for v in linked[1:]]
        edges += [CircuitEdge(a, b, f"{spec.name} ({spec.kind})", spec.name) for a, b in ends]
    preset = [CircuitEdge("tank", "supply", "pump"), CircuitEdge("supply", "front", "front feed")]
    if stand_in is None:
        preset += [CircuitEdge("supply", "rear", "valve (stroke)"),
                   CircuitEdge("rear", ports["valve_return"], "valve (return)")]
    else:
        spec, cls = stand_in
        preset += [CircuitEdge(a, b, f"{spec.name} ({spec.kind}) {what}", spec.name)
                   for a, b, what in _stand_in_edges(cls, spec.name, ports["valve_return"])]
    preset.append(CircuitEdge("supply", "tank", "relief valve"))
    return CircuitGraph(tuple(nodes), (*preset, *edges))


def _stand_in_edges(cls, name: str, ret: str) -> tuple:
    """The edges of a part in the valve's place: its kind's ``schematic_edges`` where it has them,
    else the valve's own two (the supply to the rear chamber, the rear chamber to ``ret``)."""
    edges = getattr(cls, "schematic_edges", None)
    return edges(name, ret) if edges else (("supply", "rear", "(stroke)"), ("rear", ret, "(return)"))


def part_lines(drifter) -> list[str]:
    """One line for each ``[parts.<name>]`` part of ``drifter``: its name, kind, connections (a port
    taken, its own node, the nodes it joins) and values in the units the config wrote them in (the
    key table's display units where it left them out), for ``impactbar drifter``'s header.

    Examples
    --------
    >>> from impactbar.physical import circuit_preset
    >>> part_lines(circuit_preset("circuit-drifter"))
    []
    """
    config = drifter.config or {}
    out = []
    for spec in drifter.parts:
        cls = part_kinds()[spec.kind]
        units = {f.name: f.unit for f in (*cls.si_fields, *cls.si_lists)}
        ports = [v for c, v in spec.connections if _joins(cls, c) == "port" and v != "none"]
        linked = [v for c, v in spec.connections if _joins(cls, c) == "node"]
        path = [*ports, spec.name, *linked] if _has_node(cls) else linked
        key = f"parts.{spec.name}."
        values = [f"{k} {format_key(v, units[k], config, key + k, 4)}" for k, v in spec.values]
        values += [f"{k} " + ", ".join(format_key(x, units[k], config, f"{key}{k}.{i}", 4)
                                       for i, x in enumerate(v)) for k, v in spec.lists]
        out.append(f"part {spec.name} ({spec.kind}): {' -> '.join(path)}; {', '.join(values)}")
    return out
