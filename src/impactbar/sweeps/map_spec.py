r"""Design maps of a drifter: its operating point over a grid of its SI config keys.

A drifter map is a sweep spec with a top-level ``config`` (a TOML file, relative to the spec's
folder, or a preset's name): the machine (the valve drifter or the drifter with its oil circuit,
with or without a drill string and rock), and ``[axes]`` over 1 to 3 of its dotted config keys with
units::

    task = "operating_point"
    config = "circuit-drifter"
    refine_edges = true                      # optional (default false)
    chunk_points = 21                        # optional (default: a line along the last axis)
    [axes]
    "supply.pump_flow" = { start = "50 L/min", stop = "150 L/min", num = 41 }
    "accumulator.precharge" = { values = ["3 MPa", "9 MPa", "15 MPa"] }

Task ``operating_point``: each work chunk is a block of neighbouring grid points, walked in a
snake order so that each point's predecessor is its neighbour along one axis; the first point's
orbit comes from the library's default chain (``orbit()``), each next one's is continued from its
neighbour's (``orbit(guess=...)``: Newton from the neighbour's unknowns, fewer flights), falling back
to the default chain where that fails or lands more than
:data:`~impactbar.sweeps.map_task.JUMP` away in period or impact velocity. ``origin`` says which
it was (0 the default chain; ``+k`` continued from the neighbour one step down axis ``k``, counted
from 1; ``-k`` from the one a step up). Every variable is stored in SI
with its ``units`` and ``long_name`` (:func:`map_variables`). The chunks are written by the sweep
machinery of :mod:`impactbar.sweeps` (stored as they finish, a rerun resumes, checksums checked).

Task ``settle`` (options in ``[settle]``: ``blows = 40``, ``blow_fraction``, ``settle_tolerance``,
:func:`settle_options`): each point simulated from rest up to its ``blows``-th blow and classified
by :meth:`impactbar.physical.SimulationResult.blow_statistics`
(:func:`impactbar.physical.settle.settle_point`): ``period_blows`` (0 not settled), ``settled``,
``chatter_per_blow`` and the mean and spread of the last period's impact velocity and blow frequency.

Edges (:func:`impactbar.sweeps.maps.map_edges`): along each axis, between two neighbouring points
with an orbit where ``stable``, ``cavitates``, ``relief_opens`` or ``accumulator_empties`` changes;
stored in the store
(``edge_axis``, ``edge_index``, ``edge_flag``, ``edge_low``, ``edge_high``, ``edge_value``), and
with ``refine=True`` each located by bisection on the parameter to ``1e-6`` relative.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._shared.schema import Field, Schema
from .._shared.validate import check_int
from ..physical.design_keys import INTEGER_KEYS
from ..physical.outputs import OUTPUTS, Output, outputs
from .grid import ChunkedGrid

DRIFTER_TASKS = ("operating_point", "settle")
#: the top-level keys of a drifter map's spec
TOP_KEYS = ("task", "config", "axes", "chunk_points", "refine_edges", "chain", "settle")
#: the ``[settle]`` options of the ``settle`` task and their defaults: the blows simulated from rest,
#: and the thresholds of :meth:`impactbar.physical.SimulationResult.blow_statistics`
SETTLE_DEFAULTS = {"blows": 40, "blow_fraction": 0.25, "settle_tolerance": 0.01}
#: most blows a settle may simulate per point
MAX_SETTLE_BLOWS = 100_000
#: how the points of a chunk are found: "continue" (each from its neighbour, the default) or
#: "default" (each by the default chain from rest, as a fresh ``orbit()``)
CHAINS = ("continue", "default")
#: longest failure message kept per point (characters)
REASON_CHARS = 200
#: the config keys that take integers: an axis over one takes integer values, stored as integers

#: the status codes of a point
STATUS = {0: "orbit found", 1: "no orbit (ValueError)", 2: "failed (another error)"}


def _cf_output_unit(unit: str) -> str:
    """An output's SI unit as a CF ``units`` string (a flag's ``""`` stays)."""
    return unit.replace("**", "").replace(" ", "")


def _stored(output: Output, long_name: str | None = None, suffix: str = "") -> Field:
    """An output (:mod:`impactbar.physical.outputs`) as a map's stored variable: its name (then
    ``suffix``), long name (or ``long_name``), SI units and dtype, as the registry declares them."""
    return Field(output.name + suffix, long_name or output.long_name, _cf_output_unit(output.si_unit),
                 dtype=output.dtype)


_VELOCITY, _FREQUENCY = OUTPUTS["impact_velocity"], OUTPUTS["blow_frequency"]
#: the variables of the ``settle`` task (before its status and failure): the settled blows' impact
#: velocity and frequency are the outputs', averaged over the blows
_SETTLE = (
    Field("period_blows", "period of the settled motion in blows (0: not settled)", "", dtype="i2"),
    Field("settled", "the blows repeat a cycle (period_blows > 0)", "", dtype="b1"),
    Field("chatter_per_blow", "chatter impacts per blow over the last period (settled) or the second "
                              "half's blows (not settled)", "1"),
    _stored(_VELOCITY, "mean piston velocity at the blows of the last period (settled) or of the second "
                       "half (not settled)"),
    _stored(_VELOCITY, "standard deviation of those blows' impact velocities", "_spread"),
    _stored(_FREQUENCY, "blows per unit time over the last period (settled) or between the second half's "
                        "blows (not settled)"),
    _stored(_FREQUENCY, "standard deviation of the inverse intervals between those blows", "_spread"),
    Field("n_blows", "blows of the run (impacts at least blow_fraction of the hardest)", "", dtype="i4"),
    Field("n_impacts", "impacts of the run, blows and chatter", "", dtype="i4"),
    Field("simulated_time", "time simulated from rest, to the last blow counted", "s"),
)
_SETTLE_TAIL = (
    Field("status", "0 simulated, 1 refused (ValueError), 2 failed (another error)", "", dtype="i1"),
    Field("failure", "why the point has no motion", "", dtype=f"U{REASON_CHARS}"),
)
_TAIL = (
    Field("origin", "where the orbit came from: 0 the default chain, +k / -k continued from the "
                    "neighbour a step down / up axis k (from 1)", "", dtype="i1"),
    Field("status", "0 orbit found, 1 no orbit (ValueError), 2 failed (another error)", "", dtype="i1"),
    Field("failure", "why the point has no orbit", "", dtype=f"U{REASON_CHARS}"),
)


def _kind(config: dict) -> str:
    from ..physical.config import config_kind

    return config_kind(config)


def map_variables(kind: str, rock: bool, task: str = "operating_point") -> Schema:
    """The variables a map stores for a machine.

    Parameters
    ----------
    kind : {"drifter", "circuit"}
        The valve drifter or the drifter with its oil circuit.
    rock : bool
        Whether the config has a drill string and rock.
    task : {"operating_point", "settle"}
        The map's task (``settle`` stores the same variables for every machine).

    Returns
    -------
    Schema
        Its fields (name, long name, SI units, dtype): the outputs of the view ``"store"``
        (:mod:`impactbar.physical.outputs`) the machine has, then ``origin``, ``status``, ``failure``.

    Examples
    --------
    >>> from impactbar.sweeps.map_spec import map_variables
    >>> "hydraulic_efficiency" in map_variables("circuit", False).names
    True
    >>> map_variables("circuit", False, "settle").names[:3]
    ('period_blows', 'settled', 'chatter_per_blow')
    """
    if task == "settle":
        return Schema(*_SETTLE, *_SETTLE_TAIL)
    return Schema(*(_stored(o) for o in outputs("store", kind, rock)), *_TAIL)


# ------------------------------------------------------------------------------------------------
# the spec
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MapAxis:
    """One axis of a drifter map: a dotted config key, its SI unit and its values in that unit.

    Parameters
    ----------
    name : str
        The dotted key (``"supply.pump_flow"``, ``"rod.segments.0.length"``).
    values : tuple of float or tuple of int
        Distinct values in ``unit`` (integers for a key of :data:`INTEGER_KEYS`).
    unit : str
        The SI unit (pint's spelling, ``"m**3/s"``), ``""`` for a dimensionless key.
    """

    name: str
    values: tuple
    unit: str = ""

    @property
    def size(self) -> int:
        return len(self.values)

    def config_value(self, value):
        """The value as a config takes it: a number with this unit, or a bare number (an integer
        for an integer axis)."""
        from ..physical.display_units import config_quantity

        if self.unit == "" and self.name in INTEGER_KEYS:
            return int(value)
        return config_quantity(value, self.unit)


@dataclass(frozen=True)
class DrifterMapSpec(ChunkedGrid):
    """A validated drifter map: a config, 1 to 3 axes over its SI keys, the task and its options.

    Build it with :func:`parse_map_spec` (a mapping; :func:`impactbar.sweeps.parse_spec` and
    :func:`impactbar.sweeps.load_spec` dispatch here on a top-level ``config``).

    Parameters
    ----------
    task : {"operating_point", "settle"}
    config : dict
        The machine's configuration (sections of keys with units), read and copied.
    axes : tuple of MapAxis
    chunk_points : int, optional
        Grid points per work chunk (a block of the grid, last axes first); default the length of
        the last axis (a line).
    refine_edges : bool
        Whether :func:`run_map` refines each edge by bisection.
    chain : {"continue", "default"}
        Each point from its neighbour (default) or each by the default chain (``operating_point``).
    settle : dict, optional
        The ``settle`` task's options (:data:`SETTLE_DEFAULTS` filled in); only with that task.
    """

    task: str
    config: dict
    axes: tuple
    chunk_points: int | None = None
    refine_edges: bool = False
    chain: str = "continue"
    settle: dict | None = None
    kind: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        if self.task not in DRIFTER_TASKS:
            raise ValueError(f"task must be one of {list(DRIFTER_TASKS)} for a drifter map (a spec with "
                             f"config); got {self.task!r}")
        if self.chain not in CHAINS:
            raise ValueError(f"chain must be one of {list(CHAINS)}; got {self.chain!r}")
        if not isinstance(self.refine_edges, bool):
            raise ValueError(f"refine_edges must be true or false; got {self.refine_edges!r}")
        kind = _kind(self.config)
        if kind not in ("drifter", "circuit"):
            raise ValueError("config must describe a drifter (a [valve] section) or a drifter with its "
                             f"oil circuit ([chambers]); it reads as a {kind}")
        object.__setattr__(self, "kind", kind)
        if self.task == "settle":
            object.__setattr__(self, "settle", settle_options(self.settle))
        elif self.settle is not None:
            raise ValueError(f"[settle] gives the settle task's options; task is {self.task!r}")
        if not 1 <= len(self.axes) <= 3:
            raise ValueError(f"[axes] must name 1 to 3 config keys; got {len(self.axes)}")
        cp = self.shape[-1] if self.chunk_points is None else self.chunk_points
        object.__setattr__(self, "chunk_points", check_int("chunk_points", cp, lo=1))
        self.check_grid()

    # -- the grid (the interface of impactbar.sweeps.SweepSpec the store and the driver use) ---------
    @property
    def extra_size(self) -> int:
        return 0

    @property
    def rock(self) -> bool:
        return "rock" in self.config

    def variables(self) -> Schema:
        """The stored variables (:func:`map_variables`)."""
        return map_variables(self.kind, self.rock, self.task)

    def axis_attrs(self, name: str) -> dict:
        """``long_name`` and ``units`` of an axis' coordinate."""
        ax = next(a for a in self.axes if a.name == name)
        return {"long_name": f"config key {name}", "units": _cf_unit(ax.unit)}

    def machine(self, index=None, values: dict | None = None):
        """The machine at a grid point (``index``) or at given axis values (key to SI value)."""
        from ..physical.loader import build, with_values

        changes = {}
        if index is not None:
            changes.update({a.name: a.values[i] for a, i in zip(self.axes, index, strict=True)})
        changes.update(values or {})
        units = {a.name: a for a in self.axes}
        return build(with_values(self.config, {k: units[k].config_value(v) for k, v in changes.items()}))

    # -- serialisation -----------------------------------------------------------------------------
    def to_dict(self) -> dict:
        out = {"task": self.task, "config": self.config,
               "axes": {a.name: {"values": list(a.values), "unit": a.unit} for a in self.axes},
               "chunk_points": self.chunk_points, "refine_edges": self.refine_edges,
               "chain": self.chain}
        if self.settle is not None:
            out["settle"] = dict(self.settle)
        return out

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=False, separators=(",", ":"))


def settle_options(table) -> dict:
    """The ``settle`` task's options, checked, with :data:`SETTLE_DEFAULTS` filled in.

    Parameters
    ----------
    table : dict or None
        ``blows`` (blows simulated from rest, an integer in ``[8, MAX_SETTLE_BLOWS]``),
        ``blow_fraction`` (in ``(0, 1]``) and ``settle_tolerance`` (in ``(0, 1)``), each optional.

    Returns
    -------
    dict

    Raises
    ------
    ValueError
        One line naming the option: an unknown one, or a value outside its range.

    Examples
    --------
    >>> from impactbar.sweeps.map_spec import settle_options
    >>> settle_options({"blows": 80})
    {'blows': 80, 'blow_fraction': 0.25, 'settle_tolerance': 0.01}
    >>> settle_options({"blows": 2})
    Traceback (most recent call last):
    ...
    ValueError: [settle] blows must be an integer in [8, 100000]; got 2
    """
    from .._shared.validate import check_real

    table = {} if table is None else table
    if not isinstance(table, dict):
        raise ValueError(f"[settle] must be a table of options {list(SETTLE_DEFAULTS)}; got {table!r}")
    unknown = sorted(set(table) - set(SETTLE_DEFAULTS))
    if unknown:
        raise ValueError(f"unknown [settle] option(s) {unknown}; allowed: {list(SETTLE_DEFAULTS)}")
    opts = {**SETTLE_DEFAULTS, **table}
    return {"blows": check_int("[settle] blows", opts["blows"], lo=8, hi=MAX_SETTLE_BLOWS),
            "blow_fraction": check_real("[settle] blow_fraction", opts["blow_fraction"], lo=0.0, hi=1.0,
                                        lo_open=True),
            "settle_tolerance": check_real("[settle] settle_tolerance", opts["settle_tolerance"], lo=0.0,
                                           hi=1.0, lo_open=True, hi_open=True)}


def _cf_unit(unit: str) -> str:
    """A pint unit as a CF ``units`` string (``"m**3/s"`` -> ``"m3/s"``; dimensionless ``"1"``)."""
    return "1" if unit == "" else unit.replace("**", "").replace(" ", "")


def is_map_spec(doc) -> bool:
    """Whether a spec mapping is a drifter map (it has a top-level ``config``)."""
    return isinstance(doc, dict) and "config" in doc


def parse_map_spec(doc: dict, folder=None) -> DrifterMapSpec:
    """Validate a drifter map's spec (a mapping of the TOML's shape), before any work starts.

    Parameters
    ----------
    doc : dict
        ``task``, ``config`` (a TOML path, relative to ``folder``, a preset's name, or the config
        itself as a table), ``[axes]`` (dotted key to ``{start, stop, num}`` or ``{values}``, each
        value a quantity with a unit, ``"80 L/min"``, or a number for a dimensionless key; a stored
        spec gives ``{values, unit}`` in SI), and optionally ``chunk_points``, ``refine_edges``,
        ``chain``; with task ``settle``, the table ``[settle]`` (:func:`settle_options`).
    folder : path-like, optional
        The spec's folder, against which a relative config path is read.

    Returns
    -------
    DrifterMapSpec

    Raises
    ------
    ValueError
        One line naming the key: an unknown top-level key, a config that is not a drifter, 0 or more
        than 3 axes, an axis over an unknown key or one the config does not give, a unit of the
        wrong dimension, or a value the machine refuses (each axis' end values are built).

    Examples
    --------
    >>> from impactbar.sweeps.map_spec import parse_map_spec
    >>> spec = parse_map_spec({"task": "operating_point", "config": "circuit-drifter",
    ...                        "axes": {"supply.pump_flow": {"start": "60 L/min", "stop": "80 L/min",
    ...                                                      "num": 3}}})
    >>> spec.shape, spec.axes[0].unit, round(spec.axes[0].values[0] * 6e4, 9)
    ((3,), 'm**3/s', 60.0)
    >>> parse_map_spec({"task": "operating_point", "config": "circuit-drifter",
    ...                 "axes": {"supply.pump_flow": {"values": ["3 MPa"]}}})
    Traceback (most recent call last):
    ...
    ValueError: [axes] supply.pump_flow must be in m**3/s as the config's '70 L/min' ...
    """
    from ..physical.loader import read_config

    if not isinstance(doc, dict):
        raise ValueError(f"spec must be a table; got {type(doc).__name__}")
    unknown = [k for k in doc if k not in TOP_KEYS]
    if unknown:
        raise ValueError(f"unknown top-level key(s) {unknown} of a drifter map; allowed: {list(TOP_KEYS)}")
    for key in ("task", "config", "axes"):
        if key not in doc:
            raise ValueError(f"missing top-level key {key!r}")
    source = doc["config"]
    if isinstance(source, str) and folder is not None and not _is_preset(source):
        path = Path(source)
        source = str(path if path.is_absolute() else Path(folder) / path)
    try:
        config, _ = read_config(source)
    except ValueError as exc:
        raise ValueError(f"config: {exc}") from None
    axes_doc = doc["axes"]
    if not isinstance(axes_doc, dict):
        raise ValueError(f"[axes] must be a table of config keys; got {axes_doc!r}")
    if not 1 <= len(axes_doc) <= 3:
        raise ValueError(f"[axes] must name 1 to 3 config keys; got {len(axes_doc)}")
    axes = tuple(_axis(config, name, table) for name, table in axes_doc.items())
    spec = DrifterMapSpec(task=doc["task"], config=config, axes=axes, chunk_points=doc.get("chunk_points"),
                          refine_edges=doc.get("refine_edges", False), chain=doc.get("chain", "continue"),
                          settle=doc.get("settle"))
    for a in axes:  # the machine at each end of each axis, the other keys at the config's values
        for v in {a.values[0], a.values[-1]}:
            try:
                spec.machine(values={a.name: v})
            except ValueError as exc:
                raise ValueError(f"[axes] {a.name} = {a.config_value(v)!r}: {_one_line(exc)}") from None
    return spec


def _one_line(exc) -> str:
    return " ".join(str(exc).split())


def _is_preset(name: str) -> bool:
    from ..physical.circuit import CIRCUIT_PRESETS
    from ..physical.config import PRESETS
    from ..physical.drifter import DRIFTER_PRESETS

    return name in {**PRESETS, **DRIFTER_PRESETS, **CIRCUIT_PRESETS}


def _axis(config: dict, name: str, table) -> MapAxis:
    """An axis over a config key: its SI unit from the config's own value, its values in it."""
    from ..physical.loader import config_value

    try:
        base = config_value(config, name)
    except ValueError as exc:
        raise ValueError(f"[axes] {_one_line(exc)}") from None  # (the message names the key)
    unit = _si_unit(name, base)
    if not isinstance(table, dict):
        raise ValueError(f"[axes] {name} must be a table {{start, stop, num}} or {{values}}; got {table!r}")
    keys = set(table)
    if keys in ({"values"}, {"values", "unit"}):
        raw = table["values"]
        if not isinstance(raw, list) or not raw:
            raise ValueError(f"[axes] {name}.values must be a non-empty list; got {raw!r}")
        if "unit" in table:  # a stored spec: SI numbers in the given unit
            if table["unit"] != unit:
                raise ValueError(f"[axes] {name}.unit must be {unit!r}; got {table['unit']!r}")
            values = [_number(name, v) for v in raw]
        else:
            values = [_in_unit(name, v, unit, base) for v in raw]
    elif keys == {"start", "stop", "num"}:
        start = _in_unit(name, table["start"], unit, base)
        stop = _in_unit(name, table["stop"], unit, base)
        num = check_int(f"[axes] {name}.num", table["num"], lo=1, hi=10**6)
        values = [float(v) for v in np.linspace(start, stop, num)]
    else:
        raise ValueError(f"[axes] {name} must have keys start, stop, num or just values; got {sorted(keys)}")
    if name in INTEGER_KEYS:
        values = [_integer(name, v) for v in values]
    if len(set(values)) != len(values):
        raise ValueError(f"[axes] {name}: values must be distinct; got {values}")
    return MapAxis(name, tuple(values), unit)


def _integer(name: str, v: float) -> int:
    """An integer key's value: an integer-valued number, as an int."""
    if not float(v).is_integer():
        raise ValueError(f"[axes] {name} takes integers (the config key is an integer); got {v!r}")
    return int(v)


def _number(name, v) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ValueError(f"[axes] {name}: values must be finite numbers; got {v!r}")
    return float(v)


def _si_unit(name: str, base) -> str:
    """The SI unit of a key (:func:`~impactbar.physical.design_keys.key_unit`: the one
    :mod:`~impactbar.physical.tree` declares, else the base units of the config's
    value, ``""`` for a bare number)."""
    from ..physical.design_keys import key_unit

    try:
        return key_unit(name, base)
    except ValueError as exc:
        raise ValueError(f"[axes] {exc}") from None


def _in_unit(name: str, value, unit: str, base) -> float:
    """``value`` (a quantity string, or a number for a dimensionless key) in ``unit``
    (:func:`~impactbar.physical.design_keys.key_value`)."""
    from ..physical.design_keys import key_value

    try:
        return key_value(f"[axes] {name}", value, unit, base)
    except ValueError as exc:
        raise ValueError(_one_line(exc)) from None
