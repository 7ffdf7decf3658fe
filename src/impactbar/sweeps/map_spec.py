r"""Design maps of a drifter: its operating point over a grid of its SI config keys.

A drifter map is a sweep spec (:class:`impactbar.sweeps.SweepSpec`) with a top-level ``config`` (a
TOML file, relative to the spec's folder, or a preset's name): the machine (the valve drifter or the
drifter with its oil circuit, with or without a drill string and rock), and ``[axes]`` over 1 to 3
of its dotted config keys with units::

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

import math
from pathlib import Path

from .._shared.schema import Field, Schema
from .._shared.validate import check_int
from ..physical.design_keys import INTEGER_KEYS
from ..physical.outputs import OUTPUTS, Output, outputs
from .grid import Axis, _check_options, _grid_values, cf_unit
from .map_task import REASON_CHARS, _one_line, compute_map_chunk

#: the top-level keys of a drifter map's spec
TOP_KEYS = ("task", "config", "axes", "chunk_points", "refine_edges", "chain", "settle")
#: most blows a settle may simulate per point
MAX_SETTLE_BLOWS = 100_000
#: the ``[settle]`` options of the ``settle`` task (:func:`settle_options`) and their defaults: the
#: blows simulated from rest, and the thresholds of
#: :meth:`impactbar.physical.SimulationResult.blow_statistics`
_SETTLE_OPTIONS = {"blows": (40, int, 8, False, MAX_SETTLE_BLOWS),
                   "blow_fraction": (0.25, float, 0.0, True, 1.0),
                   "settle_tolerance": (0.01, float, 0.0, True, 1.0, True)}
SETTLE_DEFAULTS = {name: default for name, (default, *_) in _SETTLE_OPTIONS.items()}
#: how the points of a chunk are found: "continue" (each from its neighbour, the default) or
#: "default" (each by the default chain from rest, as a fresh ``orbit()``)
CHAINS = ("continue", "default")
#: the status codes of a point
STATUS = {0: "orbit found", 1: "no orbit (ValueError)", 2: "failed (another error)"}


def _stored(output: Output, how: str = "", suffix: str = "", long_name: str | None = None) -> Field:
    """An output (:mod:`impactbar.physical.outputs`) as a map's stored variable: its name, long name,
    SI units and dtype, as the registry declares them; ``how`` it is measured the variable's
    description adds in parentheses (its ``long_name`` attribute stays the output's). A statistic
    of the output is another variable: its name the output's then ``suffix``, its own ``long_name``."""
    long = (long_name or output.long_name) + (f" ({how})" if how else "")
    return Field(output.name + suffix, long, cf_unit(output.si_unit), dtype=output.dtype)


_VELOCITY, _FREQUENCY = OUTPUTS["impact_velocity"], OUTPUTS["blow_frequency"]
#: the variables of the ``settle`` task (before its status and failure): the settled blows' impact
#: velocity and frequency are the outputs', averaged over the blows
_SETTLE = (
    Field("period_blows", "period of the settled motion in blows (0: not settled)", "", dtype="i2"),
    Field("settled", "the blows repeat a cycle (period_blows > 0)", "", dtype="b1"),
    Field("chatter_per_blow", "chatter impacts per blow over the last period (settled) or the second "
                              "half's blows (not settled)", "1"),
    _stored(_VELOCITY, "the mean at the blows of the last period (settled) or of the second half (not "
                       "settled)"),
    _stored(_VELOCITY, suffix="_spread", long_name="standard deviation of those blows' impact velocities"),
    _stored(_FREQUENCY, "blows per unit time over the last period (settled) or between the second half's "
                        "blows (not settled)"),
    _stored(_FREQUENCY, suffix="_spread",
            long_name="standard deviation of the inverse intervals between those blows"),
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
# the drifter as the machine of a sweep
# ------------------------------------------------------------------------------------------------
class _Drifter:
    """A drifter's config in SI as the machine of a sweep (tasks ``operating_point`` and
    ``settle``): its axes over dotted config keys with units, its points, its variables."""

    what = "a drifter's config"
    edges = True  # (its stores record their edges, :func:`impactbar.sweeps.maps.sweep_edges`)
    fields = ("config",)
    top_keys = TOP_KEYS

    def required(self, doc) -> tuple:
        return ("config",)

    def parse(self, doc, folder=None) -> dict:
        from ..physical.loader import read_config

        source = doc["config"]
        if isinstance(source, str) and folder is not None and not _is_preset(source):
            path = Path(source)
            source = str(path if path.is_absolute() else Path(folder) / path)
        try:
            config, _ = read_config(source)
        except ValueError as exc:
            raise ValueError(f"config: {exc}") from None
        axes = tuple(config_axis(config, name, table) for name, table in doc["axes"].items())
        task = doc["task"]
        if "settle" in doc and task != "settle":
            raise ValueError(f"[settle] gives the settle task's options; task is {task!r}")
        options = {"refine_edges": doc.get("refine_edges", False), "chain": doc.get("chain", "continue"),
                   **(settle_options(doc.get("settle")) if task == "settle" else {})}
        return {"task": task, "config": config, "axes": axes, "options": options,
                "chunk_points": doc.get("chunk_points")}

    def check(self, spec) -> None:
        from ..physical.config import config_kind

        kind = config_kind(spec.config)
        if kind not in ("drifter", "circuit"):
            raise ValueError("config must describe a drifter (a [valve] section) or a drifter with its "
                             f"oil circuit ([chambers]); it reads as a {kind}")
        opts = dict(spec.options)
        chain, refine = opts.pop("chain", "continue"), opts.pop("refine_edges", False)
        if chain not in CHAINS:
            raise ValueError(f"chain must be one of {list(CHAINS)}; got {chain!r}")
        if not isinstance(refine, bool):
            raise ValueError(f"refine_edges must be true or false; got {refine!r}")
        if spec.task == "settle":
            opts = settle_options(opts)
        elif opts:
            raise ValueError(f"task {spec.task!r} takes the options refine_edges and chain; got {list(opts)}")
        object.__setattr__(spec, "options", {"refine_edges": refine, "chain": chain, **opts})
        if not 1 <= len(spec.axes) <= 3:
            raise ValueError(f"[axes] must name 1 to 3 config keys; got {len(spec.axes)}")
        cp = spec.shape[-1] if spec.chunk_points is None else spec.chunk_points
        object.__setattr__(spec, "chunk_points", check_int("chunk_points", cp, lo=1))
        spec.check_grid()
        for a in spec.axes:  # the machine at each end of each axis, the other keys at the config's values
            for v in {a.values[0], a.values[-1]}:
                try:
                    spec.point(values={a.name: v})
                except ValueError as exc:
                    raise ValueError(f"[axes] {a.name} = {_config_value(a, v)!r}: {_one_line(exc)}") from None

    def extra_size(self, spec) -> int:
        return 0

    def point(self, spec, changes: dict):
        from ..physical.loader import build, with_values

        axes = {a.name: a for a in spec.axes}
        return build(with_values(spec.config, {k: _config_value(axes[k], v) for k, v in changes.items()}))

    def variables(self, spec) -> Schema:
        from ..physical.config import config_kind

        return map_variables(config_kind(spec.config), "rock" in spec.config, spec.task)

    def compute_chunk(self, spec, chunk: int) -> dict:
        return compute_map_chunk(spec, chunk)

    def axis_name(self, spec, name: str) -> str:
        return f"config key {name}"

    def axis_text(self, spec, name: str, value, digits: int = 6) -> str:
        from ..physical.display_units import format_key

        return format_key(value, next(a.unit for a in spec.axes if a.name == name), spec.config, name, digits)

    def to_dict(self, spec) -> dict:
        opts = dict(spec.options)
        out = {"task": spec.task, "config": spec.config,
               "axes": {a.name: {"values": list(a.values), "unit": a.unit} for a in spec.axes},
               "chunk_points": spec.chunk_points, "refine_edges": opts.pop("refine_edges"),
               "chain": opts.pop("chain")}
        if opts:
            out["settle"] = opts
        return out



#: a drifter's object (:attr:`impactbar.sweeps.SweepSpec.space` of its tasks)
DRIFTER = _Drifter()


def _config_value(axis, value):
    """An axis value as a config takes it: a number with the axis' unit, or a bare number (an
    integer for an integer key)."""
    from ..physical.display_units import config_quantity

    if axis.unit == "" and axis.name in INTEGER_KEYS:
        return int(value)
    return config_quantity(value, axis.unit)


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
    return _check_options("settle", {} if table is None else table, _SETTLE_OPTIONS)


def _is_preset(name: str) -> bool:
    from ..physical.circuit import CIRCUIT_PRESETS
    from ..physical.config import PRESETS
    from ..physical.drifter import DRIFTER_PRESETS

    return name in {**PRESETS, **DRIFTER_PRESETS, **CIRCUIT_PRESETS}


def config_axis(config: dict, name: str, table) -> Axis:
    """An axis over a config key: its SI unit from the config's own value, its values in it.

    Parameters
    ----------
    config : dict
        The drifter's configuration.
    name : str
        A dotted key of it (``"supply.pump_flow"``).
    table : dict
        ``{start, stop, num}`` or ``{values}``, each a quantity with a unit (``"80 L/min"``) or a
        number for a dimensionless key; a stored spec's ``{values, unit}`` in SI.

    Returns
    -------
    Axis
        With the key's SI unit (:func:`~impactbar.physical.design_keys.key_unit`).

    Raises
    ------
    ValueError
        One line naming the key: not one the config gives, a unit of the wrong dimension, an integer
        key's value not an integer, or values not distinct.
    """
    from ..physical.loader import config_value

    try:
        base = config_value(config, name)
    except ValueError as exc:
        raise ValueError(f"[axes] {_one_line(exc)}") from None  # (the message names the key)
    unit = _si_unit(name, base)
    values, ranged = _grid_values(name, table, lambda _, v: _in_unit(name, v, unit, base), hi=10**6)
    if not ranged and "unit" in table:  # a stored spec: SI numbers in the given unit
        if table["unit"] != unit:
            raise ValueError(f"[axes] {name}.unit must be {unit!r}; got {table['unit']!r}")
        values = [_number(name, v) for v in values]
    elif not ranged:
        values = [_in_unit(name, v, unit, base) for v in values]
    if name in INTEGER_KEYS:
        values = [_integer(name, v) for v in values]
    if len(set(values)) != len(values):
        raise ValueError(f"[axes] {name}: values must be distinct; got {values}")
    return Axis(name, tuple(values), unit)


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
