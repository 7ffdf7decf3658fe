"""Parts added to a drifter's oil circuit by its configuration (theory §13): the table of part kinds
(:func:`register_part`) and the reading of a config's ``[parts.<name>]`` tables into parts in SI.

A part is one TOML table under ``[parts]``, named by the user::

    [parts.return_line]
    kind = "return_accumulator"   # a kind of the table (part_kinds())
    port = "valve_return"         # its connections: the preset's ports ("none": no port) and nodes, or
    drain = "tank"                #   another part's node (a part's node is named after it)
    volume = "0.2 L"              # its SI fields, each with its unit
    flow_coefficient = "2e-5 m^3/s/Pa^0.5"

A kind's fields that hold a list (:attr:`~impactbar.drives.circuit.CircuitPart.si_lists`: a
cushion's ``gaps = ["3 mm", "5 mm"]``) take a TOML array, each element in the field's unit and range;
they are keys of the table, not parameters.

Each kind is a :class:`~impactbar.drives.circuit.CircuitPart` dataclass that declares its SI fields
once (:attr:`~impactbar.drives.circuit.CircuitPart.si_fields`: unit, scale, range) and its
connections; every field is then a key ``parts.<name>.<field>`` of the parameter tree
(:func:`part_field`, a :class:`~impactbar.physical.tree.Field`), set by
:func:`~impactbar.physical.with_values`, swept, optimised and continued by that name. The drive's
classes are imported only where a config has parts.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
from dataclasses import dataclass

from . import tree
from .units import to_si

__all__ = ["register_part", "part_kinds", "PartSpec", "read_parts", "part_field", "part_keys",
           "declared_unit", "library_fields", "split_key", "markdown_table", "valve_stand_in",
           "unused_valve"]

#: the kinds that come with the library: ``kind -> "module:class"``, imported on first use
_BUILTIN = {"return_accumulator": "impactbar.drives.circuit.return_line:ReturnAccumulator",
            "leak": "impactbar.drives.circuit.leak:Leak",
            "laminar_leak": "impactbar.drives.circuit.leakage:LaminarLeak",
            "cushion": "impactbar.drives.circuit.cushion:Cushion",
            "check_valve": "impactbar.drives.circuit.check_valve:CheckValve",
            "spool_valve": "impactbar.drives.circuit.spool_valve:SpoolValve"}
_KINDS: dict[str, type] = {}
#: what a part's name may not be: the preset's nodes and ports, the valve's spool
_TAKEN = ("front", "rear", "supply", "tank", "spool", "valve_return", "kind")


def register_part(kind: str, cls: type) -> type:
    """Enter a part's class in the table of kinds, so that a config's ``[parts.<name>]`` table with
    ``kind = "<kind>"`` builds it (as :func:`~impactbar.laws.register_law` does for laws).

    Parameters
    ----------
    kind : str
        The kind's name, an identifier.
    cls : type
        A frozen dataclass subclass of :class:`~impactbar.drives.circuit.CircuitPart` with a field
        ``name`` (its node's and parameters' name), one field per entry of its ``si_fields``
        (:class:`~impactbar.drives.circuit.PartField`, dimensionless values) and one per entry of its
        ``connections`` (``{field: ("node" | "port", default)}``, a node's or port's name; a default
        ``None`` takes the dataclass field's, if it has one). Where
        its ``nodes`` is a property, the part has one node, named after it, that other parts may
        connect to.

    Returns
    -------
    type
        ``cls`` (a decorator returns it).

    Raises
    ------
    ValueError
        A kind that is not an identifier or that another class holds, a class that is not such a
        dataclass.

    Examples
    --------
    >>> from impactbar.drives.circuit import Leak
    >>> register_part("leak", Leak) is Leak  # already there: registering again changes nothing
    True
    """
    from ..drives.circuit import CircuitPart

    if not (isinstance(kind, str) and kind.isidentifier()):
        raise ValueError(f"kind must be an identifier; got {kind!r}")
    if not (isinstance(cls, type) and issubclass(cls, CircuitPart) and dataclasses.is_dataclass(cls)):
        raise ValueError(f"cls must be a dataclass subclass of CircuitPart; got {cls!r}")
    names = {f.name for f in dataclasses.fields(cls)}
    wanted = {"name", *(f.name for f in (*cls.si_fields, *cls.si_lists)), *cls.connections}
    if not wanted <= names:
        raise ValueError(f"a part kind's class needs the fields {sorted(wanted)} (name, its si_fields, "
                         f"si_lists and connections); {cls.__name__} lacks {sorted(wanted - names)}")
    bad = [c for c, (what, _) in cls.connections.items() if what not in ("node", "port")]
    if bad:
        raise ValueError(f"{cls.__name__}.connections[{bad[0]!r}] must connect to a 'node' or a 'port'")
    held = part_kinds().get(kind)
    if held is not None and held is not cls:
        raise ValueError(f"kind {kind!r} is already the part {held.__name__}; choose another kind")
    _KINDS[kind] = cls
    return cls


def part_kinds() -> dict[str, type]:
    """The part kinds by name (the library's ``return_accumulator``, ``leak``, ``laminar_leak``,
    ``cushion``, ``check_valve`` and ``spool_valve``, then those registered), their classes imported."""
    for kind, where in _BUILTIN.items():
        if kind not in _KINDS:
            module, name = where.split(":")
            _KINDS[kind] = getattr(importlib.import_module(module), name)
    return _KINDS


def part_keys(kind) -> tuple[str, ...]:
    """The keys a ``[parts.<name>]`` table of ``kind`` takes: ``kind``, its connections, its fields
    (then its lists).

    Raises
    ------
    ValueError
        An unknown kind (the kinds listed).
    """
    kinds = part_kinds()
    if kind not in kinds:
        raise ValueError(f"kind must be one of {', '.join(kinds)}; got {kind!r}")
    cls = kinds[kind]
    return ("kind", *cls.connections, *(f.name for f in (*cls.si_fields, *cls.si_lists)))


@dataclass(frozen=True)
class PartSpec:
    """A part as a config gives it, in SI (:func:`read_parts`).

    Attributes
    ----------
    name : str
        Its table's name (``[parts.<name>]``).
    kind : str
        Its kind (:func:`part_kinds`).
    connections : tuple of (str, str)
        Each connection and the node or port it names.
    values : tuple of (str, float)
        Each SI field and its value (in the field's unit).
    lists : tuple of (str, tuple of float)
        Each list field and its values (in the field's unit).
    """

    name: str
    kind: str
    connections: tuple
    values: tuple
    lists: tuple = ()

    def field(self, name: str) -> tree.Field:
        """The parameter tree's declaration of the field ``name`` (:func:`part_field`)."""
        return _tree_field(self.name, next(f for f in part_kinds()[self.kind].si_fields if f.name == name))

    def build(self, drifter):
        """The dimensionless part for ``drifter``'s scales: each field's SI value (each element of a
        list's) converted by its scale's steps (:func:`~impactbar.physical.tree.convert`, theory §11,
        eq. 2), as the tree's own fields and a continuation's target are."""
        cls = part_kinds()[self.kind]
        scale = {f.name: f.scale for f in (*cls.si_fields, *cls.si_lists)}
        return cls(name=self.name, **dict(self.connections),
                   **{k: tree.convert(scale[k], drifter, v) for k, v in self.values},
                   **{k: tuple(tree.convert(scale[k], drifter, x) for x in v) for k, v in self.lists})


def _tree_field(name: str, f) -> tree.Field:
    """A part's :class:`~impactbar.drives.circuit.PartField` as the tree's ``parts.<name>.<field>``."""
    return tree.Field(f"parts.{name}.{f.name}", f.unit, f.example, f.scale, f"{name}.{f.name}", "drive",
                      required=f.default is None, default=f.default)


def library_fields() -> tuple[tree.Field, ...]:
    """The fields of the library's part kinds as keys ``parts.<kind>.<field>`` (``<kind>`` standing for
    the name of a part of that kind): the rows of :func:`~impactbar.physical.tree.markdown_table`."""
    return tuple(_tree_field(f"<{kind}>", f) for kind in _BUILTIN for f in part_kinds()[kind].si_fields)


def markdown_table() -> str:
    """The parameter tree's table of keys (:func:`~impactbar.physical.tree.markdown_table`) with the
    fields of the library's part kinds after it (:func:`library_fields`): the documentation's list of
    keys is this text."""
    return tree.markdown_table(library_fields())


def _has_node(cls) -> bool:
    """Whether a kind's part has a node of its own, named after it (its ``nodes`` a property)."""
    return isinstance(inspect.getattr_static(cls, "nodes"), property)


#: ``(name, field)`` of a key ``parts.<name>.<field>``; ``None`` for a key of another form (the
#: tree's :func:`~impactbar.physical.tree.part_key`)
split_key = tree.part_key


def part_field(parts, key: str) -> tree.Field | None:
    """The declaration of ``parts.<name>.<field>`` among ``parts`` (:class:`PartSpec`), ``None`` for
    a key of another form or a part they do not have."""
    name, field = split_key(key) or ("", "")
    for p in parts:
        if p.name == name and field in dict(p.values):
            return p.field(field)
    return None


def declared_unit(config: dict, key: str) -> str | None:
    """The SI unit a part's kind declares for ``parts.<name>.<field>`` of ``config`` (``None``: not a
    part's field the config has)."""
    (name, field), tables = split_key(key) or ("", ""), config.get("parts")
    if not isinstance(tables, dict) or not isinstance(tables.get(name), dict):
        return None
    cls = part_kinds().get(tables[name].get("kind"))
    units = {f.name: f.unit for f in cls.si_fields} if cls is not None else {}
    return units.get(field)


def read_parts(tables) -> tuple[PartSpec, ...]:
    """A config's ``[parts]`` tables as parts in SI, in their order, every one checked before any is
    built.

    Parameters
    ----------
    tables : dict or None
        ``{name: {"kind": ..., connections..., fields...}}``.

    Returns
    -------
    tuple of PartSpec

    Raises
    ------
    ValueError
        One line naming the part and the key: an unknown kind or key, a missing key, a connection to
        a node or port the circuit does not have, a port two parts take, a value without its unit or
        out of its range.

    Examples
    --------
    >>> p = read_parts({"leak": {"kind": "leak", "source": "rear", "target": "front",
    ...                          "flow_coefficient": "1e-8 m^3/s/Pa^0.5"}})
    >>> p[0].values
    (('flow_coefficient', 1e-08),)
    >>> read_parts({"leak": {"kind": "leak", "source": "rear", "target": "back",
    ...                      "flow_coefficient": "1e-8 m^3/s/Pa^0.5"}})
    Traceback (most recent call last):
    ...
    ValueError: parts.leak.target must be one of the nodes front, rear, supply, tank; got 'back'
    """
    from ..drives.circuit.composition import NO_PORT
    from ..drives.circuit.preset import PORTS, PRESET_NODES

    if tables is None:
        return ()
    if not isinstance(tables, dict):
        raise ValueError(f"[parts] must be tables [parts.<name>]; got {type(tables).__name__}")
    kinds = {}
    for name, table in tables.items():
        if not (isinstance(name, str) and name.isidentifier()) or name in _TAKEN:
            raise ValueError(f"a part's name [parts.<name>] must be an identifier other than "
                             f"{', '.join(_TAKEN)}; got {name!r}")
        if not isinstance(table, dict) or "kind" not in table:
            raise ValueError(f"[parts.{name}] must be a table with a kind (one of {', '.join(part_kinds())})")
        try:
            keys = part_keys(table["kind"])
        except ValueError as exc:
            raise ValueError(f"parts.{name}.{exc}") from None
        unknown = [k for k in table if k not in keys]
        if unknown:
            raise ValueError(f"unknown key parts.{name}.{unknown[0]}; a {table['kind']} takes "
                             f"{', '.join(keys)}")
        kinds[name] = part_kinds()[table["kind"]]
    nodes = (*PRESET_NODES, *(n for n in tables if _has_node(kinds[n])))
    taken: dict = {}
    out = []
    for name, table in tables.items():
        cls = kinds[name]
        connections = []
        defaults = {f.name: f.default for f in dataclasses.fields(cls)}
        for c, (what, default) in cls.connections.items():
            default = defaults.get(c, default) if default is None else default
            default = None if default is dataclasses.MISSING else default
            value = table.get(c, default)
            allowed = nodes if what == "node" else (*PORTS, NO_PORT)
            if value is None:
                raise ValueError(f"missing key parts.{name}.{c} (a {what}: one of {', '.join(allowed)})")
            if value not in allowed or value == name:
                raise ValueError(f"parts.{name}.{c} must be one of the {what}s "
                                 f"{', '.join(a for a in allowed if a != name)}; got {value!r}")
            if what == "port" and value != NO_PORT and value not in cls.offers:  # (a port it offers
                if value in taken:  # itself, a spool valve's return, is one another part may take)
                    raise ValueError(f"parts.{name}.{c}: the port {value} is taken by parts.{taken[value]} "
                                     "already (one part a port)")
                taken[value] = name
            if what == "node" and value in dict(connections).values():
                raise ValueError(f"parts.{name}.{c} must be another node than the part's other "
                                 f"connections; got {value!r} twice")
            connections.append((c, value))
        values = []
        for f in cls.si_fields:
            key = f"parts.{name}.{f.name}"
            if f.name not in table and f.default is None:
                raise ValueError(f"missing key {key}, e.g. {f.example}")
            given = table.get(f.name, f.default)
            v = to_si(key, given, f.unit, f.example, what=tree.WORDS.get(f.unit))
            values.append((f.name, f.check(key, v)))
        lists = tuple((f.name, _read_list(f"parts.{name}.{f.name}", table, f)) for f in cls.si_lists)
        if lists:  # (the part's own checks across its lists, in SI: the scales are positive factors)
            try:
                cls(name=name, **dict(connections), **dict(values), **dict(lists))
            except ValueError as exc:
                raise ValueError(f"parts.{exc}" if str(exc).startswith(f"{name}.") else
                                 f"parts.{name}: {exc}") from None
        out.append(PartSpec(name, table["kind"], tuple(connections), tuple(values), lists))
    return tuple(out)


def _read_list(key: str, table: dict, f) -> tuple[float, ...]:
    """A list field's values in SI, each in the field's range (a :class:`ValueError` naming ``key``)."""
    given = table.get(f.name)
    if given is None:
        raise ValueError(f"missing key {key}, a list, e.g. {f.example}")
    if not isinstance(given, list) or not given:
        raise ValueError(f"{key} must be a list of one or more values, e.g. {f.example}; got {given!r}")
    return tuple(f.check(key, to_si(key, v, f.unit, f.example, what=tree.WORDS.get(f.unit))) for v in given)


def valve_stand_in(config, parts) -> str | None:
    """The part that stands in for the circuit's ramped valve (theory §13, a pilot-operated spool
    valve): the name of the part whose kind replaces the valve
    (:attr:`~impactbar.drives.circuit.CircuitPart.replaces`), where the configuration has no
    ``[valve]`` table.

    Parameters
    ----------
    config : dict or None
        The drifter's configuration (``None`` or a preset's: it has its valve).
    parts : sequence of PartSpec
        Its ``[parts.<name>]`` parts (:func:`read_parts`).

    Returns
    -------
    str or None
        The part's name; ``None`` where the configuration has a ``[valve]`` table (or is none).

    Raises
    ------
    ValueError
        Neither a ``[valve]`` table nor a part in the valve's place.

    Examples
    --------
    >>> valve_stand_in({"valve": {}}, ()) is None
    True
    """
    if not isinstance(config, dict) or "valve" in config:
        return None
    kinds = part_kinds()
    name = next((p.name for p in parts if "valve" in getattr(kinds[p.kind], "replaces", ())), None)
    if name is None:
        stand = sorted(k for k, c in kinds.items() if "valve" in getattr(c, "replaces", ()))
        raise ValueError("a drifter with its oil circuit needs a valve: a [valve] table (switch_out, "
                         "switching_time, flow_coefficient) or a part in its place ([parts.<name>] of "
                         f"kind {' or '.join(stand)}); got neither")
    return name


def unused_valve(si: dict) -> dict:
    """The ramped valve's SI values where a part stands in for it (:func:`valve_stand_in`): the
    drive keeps the valve's record but never arms its switches, so these only need to be valid.

    Parameters
    ----------
    si : dict
        The circuit's SI values (``rear_volume_m3``, ``rear_area_m2``).

    Returns
    -------
    dict
        ``switch_out_m`` half way along the rear chamber, no ``switch_in_m``, an instant switch
        (``switching_time_s`` 0) and the key table's example ``valve_coefficient`` (m³/s/Pa^0.5).
    """
    return {"switch_out_m": 0.5 * si["rear_volume_m3"] / si["rear_area_m2"], "switch_in_m": None,
            "switching_time_s": 0.0,
            "valve_coefficient": tree.read_si("valve.flow_coefficient", "7.5e-6 m^3/s/Pa^0.5")}
