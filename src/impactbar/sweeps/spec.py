"""Sweep specifications: the TOML schema, its validation, and the bar and load at a grid point."""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._shared.parameters import parameter_value, parameters, with_parameters
from .._shared.validate import check_int, check_real
from ..laws import get_law
from ..laws.rodrock import RodRock
from ..loads import LOADS, load_from_record
from ..model import BarModel
from .grid import ChunkedGrid, check_points
from .parts import DRIVE_MAX_ORBITS, drive_table, law_table

TASKS = ("orbits", "montecarlo", "bifurcation")

#: the fields of each load kind, in constructor order (the table of loads)
LOAD_KINDS = {kind: cls.traits.parameters.names for kind, cls in LOADS.items()}

#: the fields of the ``[model]`` table: the bar's parameters (:attr:`impactbar.BarModel.parameters`)
MODEL_FIELDS = BarModel.parameters.names
#: the integer fields (an axis of them holds integers)
INT_FIELDS = frozenset({"n_modes", *(f.name for cls in LOADS.values() for f in cls.traits.parameters
                                     if f.dtype.startswith("i"))})

#: task options: name -> (default, kind, lower bound, lower bound open, upper bound)
_OPTIONS = {
    "orbits": {"max_orbits": (None, int, 1, False, None)},
    "montecarlo": {
        "starts": (100, int, 1, False, None),
        "periods": (200.0, float, 0.0, True, None),
        "seed": (0, int, 0, False, None),
        "window": (0.25, float, 0.0, True, 1.0),
    },
    "bifurcation": {
        "periods": (400.0, float, 0.0, True, None),
        "keep": (64, int, 1, False, None),
        "seed": (0, int, 0, False, None),
    },
}

#: most values one variable of a work chunk may hold, ``chunk points * extra size``: the task
#: allocates each chunk's variables at once (32 MiB each as float64)
MAX_CHUNK_VALUES = 2**22

#: grid points per chunk when the spec does not say
DEFAULT_CHUNK_POINTS = {"orbits": 400, "montecarlo": 4, "bifurcation": 32}
#: ... and for a sweep in the rigid closed forms (:func:`closed_form_task`): a chunk of 32,768 points
#: takes some 30 ms to compute (the compiled closed forms), about what writing it costs, so that a
#: sweep is not bound by the store's writes (one file per variable and chunk)
DEFAULT_CLOSED_FORM_CHUNK_POINTS = 32768

_TOP_KEYS = ("task", "model", "load", "drive", "law", "axes", "rock", "chunk_points", *TASKS)

#: keys of the optional ``[rock]`` table (the rod-rock law, :class:`impactbar.RodRock`): the law's own
#: parameters (:attr:`impactbar.RodRock.parameters`, the rock's without ``rock.``), its blow's time
#: and lattice, its segments; and the keys of each of its ``segments``
_ROCK_PARAMETERS = tuple(n for n in RodRock.parameters if RodRock.has_parameter(n))
ROCK_KEYS = (*(n.removeprefix("rock.") for n in _ROCK_PARAMETERS), "blow_time", "cells_per_piston",
             "segments")
SEGMENT_KEYS = ("length", "impedance", "wave_speed")
#: grid points per chunk of an ``orbits`` sweep under the rod-rock law (Newton on a numerical blow
#: map: 0.1 to 0.7 s a point): small chunks, since the points' costs differ by up to 8 times and a
#: chunk's cost dwarfs its scheduling and writing (``benchmarks/bench_sweep_scale.py``: on 1,024
#: points, 16 workers were busy 94 % of the sweep's time in chunks of 4 against 88 % in chunks of 16)
DEFAULT_ROCK_CHUNK_POINTS = 4

#: names of the extra dimension of each task
_EXTRA_DIM = {"orbits": "orbit", "montecarlo": "motion", "bifurcation": "impact"}

_DONE = "chunk_done"
#: CRC-32 of each stored chunk's data (-1: none); checked on resume, a mismatch is recomputed
_SUM = "chunk_checksum"
_ATTR_SPEC = "impactbar_sweep_spec"
_ATTR_VERSION = "impactbar_version"


# ------------------------------------------------------------------------------------------------
# the spec
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Axis:
    """One axis of the grid: a bar or load field and the values it takes.

    Parameters
    ----------
    name : str
        A field of :class:`impactbar.BarModel` (``s``, ``d``, ``R``, ``n_modes``) or a number of the
        spec's load (``p0``, ``pk``, ``k`` of a cosine; ``q``, ``kappa`` of a square wave; ``p0`` of
        a Fourier load).
    values : tuple of float (tuple of int for ``n_modes`` and ``k``), shape (n,)
        The values, distinct, ``n >= 1``; dimensionless like the field.
    """

    name: str
    values: tuple

    @property
    def size(self) -> int:
        return len(self.values)


@dataclass(frozen=True)
class SweepSpec(ChunkedGrid):
    """A validated sweep: task, base bar and load, axes, task options and chunk size.

    Build it with :func:`load_spec` (a TOML file) or :func:`parse_spec` (a mapping of the same
    shape); constructing it directly validates the same way. Every failure is a ``ValueError`` that
    names the key (``[model] R``, ``[axes] p0``, ``[montecarlo] starts``, ...).

    Parameters
    ----------
    task : {"orbits", "montecarlo", "bifurcation"}
    model : dict
        ``s``, ``d``, ``R``, ``n_modes`` of :class:`impactbar.BarModel`, all required, and
        optionally its ``impact`` law (``"paper"`` or ``"wave"``; ``"rodrock"`` with ``rock``; not
        an axis).
    load : dict or None
        ``kind`` (a key of the table of loads, :data:`impactbar.loads.LOADS`) and that load's
        parameters (its ``traits.parameters``), all required: ``p0, pk, k``
        (:class:`impactbar.CosineLoad`), ``q, kappa`` (:class:`impactbar.SquareWaveLoad`),
        ``p0, coefficients`` (:class:`impactbar.FourierLoad`; ``coefficients`` as ``[[re, im],
        ...]`` or real numbers), ``breaks, levels`` (:class:`impactbar.PiecewiseConstantLoad`).
        ``None`` where ``drive`` is given.
    axes : tuple of Axis
        At least one; each names a parameter of the bar, the load or the impact law
        (:func:`impactbar.parameters.parameters` of the spec's bar and load: a field present in
        ``model`` or ``load``, its value there the base, replaced along the axis; with ``rock``
        also ``"rock.k"``, ``"rock.k_u"``, ``"bit_mass"``, ``"feed"``, ``"segment<i>.length"``).
        The grid is their outer product, first axis slowest.
    options : dict
        The task's options, defaults filled in. ``orbits``: ``max_orbits`` (length of the
        ``orbit`` dimension; default the most one-impact orbits the load can have: ``2 k`` for a
        cosine, ``2 K`` for ``K`` Fourier harmonics, 2 for the square wave). ``montecarlo``:
        ``starts`` (100), ``periods`` (200, load periods per run), ``seed`` (0), ``window`` (0.25,
        fraction of each run classified). ``bifurcation``: ``periods`` (400), ``keep`` (64 last
        impacts stored), ``seed`` (0).
    chunk_points : int
        Grid points per work chunk (about; chunks are blocks of the grid), ``>= 1``. Default 400
        for ``orbits`` (32,768 where every point takes the rigid closed forms,
        :func:`closed_form_task`; 16 under the rod-rock law), 4 for ``montecarlo``, 32 for
        ``bifurcation``.
    rock : dict, optional
        The rod and rock of the rod-rock law (:class:`impactbar.RodRock`, theory section 4d), in
        the law's dimensionless units: ``k``, ``k_u`` (:class:`impactbar.BilinearRock`),
        ``segments`` (a list of tables ``{length, impedance, wave_speed}``, shank first,
        :class:`impactbar.RodSegment`), and optionally ``bit_mass`` (0), ``feed`` (0),
        ``blow_time`` and ``cells_per_piston`` (the blows' grid). The model's law is then
        ``RodRock`` (``[model] impact`` absent or ``"rodrock"``), and the ``orbits`` task also
        stores, per orbit, the blow's ``work_on_rock``, ``penetration`` (permanent, per blow),
        ``efficiency`` and ``efficiency_with_rebound`` (:class:`impactbar.Blow`). Its orbits come
        from Newton's method from guesses (:func:`impactbar.orbits.rock_periodic_orbits`), not a
        certified search.
    law : dict, optional
        A registered impact law (:func:`impactbar.laws.register_law`): ``kind``, its name in
        :data:`impactbar.laws.LAWS`, and its fields (``[model] impact`` absent or the same name);
        its parameters are then axes too. Not with ``rock``.
    drive : dict, optional
        A registered drive in place of ``load`` (:func:`impactbar.drives.register_drive`):
        ``kind``, its key in :data:`impactbar.drives.DRIVES`, and its constructor's (or its
        registered factory's) arguments; the built drive's parameters are then axes. The ``orbits``
        task only; its orbits are :func:`impactbar.periodic_orbits`'s under the drive,
        ``max_orbits`` 8 unless given.

    Examples
    --------
    >>> from impactbar import CosineLoad
    >>> from impactbar.sweeps import parse_spec
    >>> spec = parse_spec({"task": "orbits",
    ...                    "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
    ...                    "load": CosineLoad(p0=0.5, pk=1.0, k=1).params.record(),
    ...                    "axes": {"R": {"start": 0.0, "stop": 0.9, "num": 10}}})
    >>> spec.task, spec.shape, spec.n_chunks
    ('orbits', (10,), 1)
    """

    task: str
    model: dict
    load: dict | None
    axes: tuple
    options: dict = field(default_factory=dict)
    chunk_points: int | None = None
    rock: dict | None = None
    law: dict | None = None
    drive: dict | None = None

    def __post_init__(self) -> None:
        if self.task not in TASKS:
            raise ValueError(f"task must be one of {list(TASKS)}; got {self.task!r}")
        if self.rock is not None:
            object.__setattr__(self, "rock", _check_rock(self.rock))
        if self.law is not None:
            if self.rock is not None:
                raise ValueError("[law] and [rock] both name the impact law: give one")
            _, table = law_table(self.law)
            object.__setattr__(self, "law", table)
        object.__setattr__(self, "model", _check_model(self.model, self.rock, self.law))
        if (self.load is None) == (self.drive is None):
            raise ValueError("give [load] or [drive] (the forcing), not both nor neither")
        if self.drive is not None:
            if self.task != "orbits":
                raise ValueError(f"task = {self.task!r}: a [drive] sweeps the 'orbits' task only")
            _, table = drive_table(self.drive)
            object.__setattr__(self, "drive", table)
        else:
            object.__setattr__(self, "load", _check_load(self.load))
        if isinstance(self.axes, tuple | list) and all(isinstance(ax, Axis) for ax in self.axes):
            check_points(self.axes)  # (before each value is checked by building its point)
        object.__setattr__(self, "axes", _check_axes(self.axes, self))
        object.__setattr__(self, "options", _check_options(self.task, self.options, self))
        cp = self.chunk_points
        if cp is None:
            closed = closed_form_task(self)
            cp = DEFAULT_CLOSED_FORM_CHUNK_POINTS if closed else DEFAULT_CHUNK_POINTS[self.task]
            if self.rock is not None and self.task == "orbits":
                cp = DEFAULT_ROCK_CHUNK_POINTS
        object.__setattr__(self, "chunk_points", check_int("chunk_points", cp, lo=1))
        self.check_grid()
        _check_chunk_size(self)

    # -- the grid (shape, chunks: ChunkedGrid) --------------------------------------------------
    @property
    def extra_size(self) -> int:
        """Length of the task's extra dimension (``orbit``, ``motion`` or ``impact``)."""
        if self.task == "orbits":
            return self.options["max_orbits"]
        if self.task == "bifurcation":
            return self.options["keep"]
        return len(motion_classes())

    def parameters(self) -> dict:
        """The parameters of the spec's base bar and load (:func:`impactbar.parameters.parameters`):
        every name an axis may take, with its record (value at the base, range, description).

        Returns
        -------
        dict of str to Parameter
        """
        return parameters(*_base(self))

    def point(self, index) -> tuple:
        """The bar and the load at a grid point.

        Parameters
        ----------
        index : tuple of int, shape (n_axes,)

        Returns
        -------
        BarModel, Load or Drive
        """
        changes = {a.name: a.values[i] for a, i in zip(self.axes, index, strict=True)}
        return _build(self, changes)

    # -- serialisation ------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The spec as plain JSON-able data of the TOML's shape, defaults filled in."""
        d = {"task": self.task, "model": dict(self.model)}
        if self.load is not None:
            d["load"] = {k: _lists(v) for k, v in self.load.items()}
        for name in ("drive", "law"):  # (only where given: a spec without them keeps its JSON)
            if getattr(self, name) is not None:
                d[name] = dict(getattr(self, name))
        d["axes"] = {a.name: {"values": list(a.values)} for a in self.axes}
        d["chunk_points"] = self.chunk_points
        if self.rock is not None:
            d["rock"] = {k: ([dict(g) for g in v] if k == "segments" else v) for k, v in self.rock.items()}
        d[self.task] = dict(self.options)
        return d

    def to_json(self) -> str:
        """Canonical JSON of :meth:`to_dict` (what the store keeps and resumption compares)."""
        return json.dumps(self.to_dict(), sort_keys=False, separators=(",", ":"))


def load_spec(path) -> SweepSpec:
    """Read and validate a sweep spec from a TOML file (see :class:`SweepSpec` for the keys).

    Raises
    ------
    ValueError
        If the file is not valid TOML, or a key is unknown, missing or out of range; the message
        names the key.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from impactbar import CosineLoad, load_spec
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "spec.toml"
    >>> load = CosineLoad(p0=0.5, pk=1.0, k=1).params.record()  # the [load] table's keys and values
    >>> with open(path, "w") as f:
    ...     for line in ['task = "orbits"', "[model]", "s = 100.0", "d = 0.0", "R = 0.5", "n_modes = 0",
    ...                  "[load]", *(f"{key} = {value!r}" for key, value in load.items()),
    ...                  "[axes]", "R = { start = 0.0, stop = 0.9, num = 10 }"]:
    ...         print(line, file=f)
    >>> load_spec(path).n_points
    10
    """
    path = Path(path)
    try:
        with path.open("rb") as f:
            doc = tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from exc
    except RecursionError as exc:  # tomllib recurses into nested arrays and inline tables
        raise ValueError(f"{path}: arrays or tables nested too deeply for a sweep spec") from exc
    except OSError as exc:
        raise ValueError(f"cannot read spec {path}: {exc}") from exc
    if isinstance(doc, dict) and "config" in doc:  # a drifter map: config keys in SI
        from .map_spec import parse_map_spec

        return parse_map_spec(doc, path.parent)
    return parse_spec(doc)


def parse_spec(doc) -> SweepSpec:
    """Validate a spec given as a mapping of the TOML's shape (see :class:`SweepSpec`).

    ``axes`` maps each field to ``{start, stop, num}`` (``numpy.linspace``, both ends included) or
    ``{values = [...]}``.

    Raises
    ------
    ValueError
        Naming the unknown, missing or out-of-range key.
    """
    if not isinstance(doc, dict):
        raise ValueError(f"spec must be a table; got {type(doc).__name__}")
    if "config" in doc:  # a drifter map (impactbar.sweeps.map_spec): config keys in SI
        from .map_spec import parse_map_spec

        return parse_map_spec(doc)
    unknown = [k for k in doc if k not in _TOP_KEYS]
    if unknown:
        raise ValueError(f"unknown top-level key(s) {unknown}; allowed: {list(_TOP_KEYS)}")
    for key in ("task", "model", "load" if "drive" not in doc else "drive", "axes"):
        if key not in doc:
            raise ValueError(f"missing top-level key {key!r}")
    task = doc["task"]
    if task not in TASKS:
        raise ValueError(f"task must be one of {list(TASKS)}; got {task!r}")
    for other in TASKS:
        if other != task and other in doc:
            raise ValueError(f"[{other}] is given but task = {task!r}; use [{task}] for its options")
    for key in ("model", "load", "drive", "law", "axes", task):
        if key in doc and not isinstance(doc[key], dict):
            raise ValueError(f"[{key}] must be a table; got {doc[key]!r}")
    axes_doc = doc["axes"]
    axes = tuple(Axis(name, _axis_values(name, table)) for name, table in axes_doc.items())
    load = dict(doc["load"]) if "load" in doc else None
    rock = doc.get("rock")
    if rock is not None and not isinstance(rock, dict):
        raise ValueError(f"[rock] must be a table; got {rock!r}")
    return SweepSpec(task=task, model=dict(doc["model"]), load=load, axes=axes,
                     options=dict(doc.get(task, {})), chunk_points=doc.get("chunk_points"), rock=rock,
                     law=doc.get("law"), drive=doc.get("drive"))


def _axis_values(name, table) -> tuple:
    if not isinstance(table, dict):
        raise ValueError(f"[axes] {name} must be a table {{start, stop, num}} or {{values}}; got {table!r}")
    keys = set(table)
    if keys == {"values"}:
        vals = table["values"]
        if not isinstance(vals, list) or not vals:
            raise ValueError(f"[axes] {name}.values must be a non-empty list of numbers; got {vals!r}")
        return tuple(vals)
    if keys == {"start", "stop", "num"}:
        start = check_real(f"[axes] {name}.start", table["start"])
        stop = check_real(f"[axes] {name}.stop", table["stop"])
        num = check_int(f"[axes] {name}.num", table["num"], lo=1, hi=10**7)
        vals = np.linspace(start, stop, num)
        if name in INT_FIELDS:
            if not np.all(vals == np.round(vals)):
                raise ValueError(f"[axes] {name}: start, stop, num must give integers for an integer "
                                 f"field; got {vals.tolist()}")
            return tuple(int(v) for v in np.round(vals))
        return tuple(float(v) for v in vals)
    raise ValueError(f"[axes] {name} must have keys start, stop, num or just values; got {sorted(keys)}")


def _complex_pairs(name, seq) -> tuple:
    """Complex numbers given as ``[re, im]`` pairs or real numbers, as ``(re, im)`` tuples."""
    out = []
    for j, c in enumerate(seq):
        if isinstance(c, list) and len(c) == 2:
            re_ = check_real(f"[load] {name}[{j}][0]", c[0])
            im_ = check_real(f"[load] {name}[{j}][1]", c[1])
        else:
            re_, im_ = check_real(f"[load] {name}[{j}]", c), 0.0
        out.append((re_, im_))
    return tuple(out)


def _check_model(model, rock=None, law=None) -> dict:
    if not isinstance(model, dict):
        raise ValueError(f"[model] must be a table; got {model!r}")
    unknown = [k for k in model if k not in (*MODEL_FIELDS, "impact")]
    if unknown:
        raise ValueError(f"[model] unknown key(s) {unknown}; allowed: {[*MODEL_FIELDS, 'impact']}")
    missing = [k for k in MODEL_FIELDS if k not in model]
    if missing:
        raise ValueError(f"[model] missing key(s) {missing}")
    impact = model.get("impact", "paper")
    if rock is not None:
        if "impact" in model and impact != "rodrock":
            raise ValueError(f"[model] impact = {impact!r} but the spec has a [rock] table (the rod-rock "
                             "law): drop impact or set it to 'rodrock'")
        impact = _rock_law(rock)
    elif law is not None:
        if "impact" in model and impact != law["kind"]:
            raise ValueError(f"[model] impact = {impact!r} but [law] kind = {law['kind']!r}: drop impact "
                             "or make them the same")
        impact, _ = law_table(law)
    elif impact == "rodrock":
        raise ValueError("[model] impact = 'rodrock' needs a [rock] table: k, k_u and segments")
    try:
        m = BarModel(**{k: model[k] for k in MODEL_FIELDS}, impact=impact)
    except ValueError as exc:
        raise ValueError(f"[model] {exc}") from None
    out = {k: getattr(m, k) for k in MODEL_FIELDS}
    if "impact" in model or rock is not None or law is not None:  # the impact law: "paper" (eq. 10,
        out["impact"] = m.impact                # default), "wave", "rodrock" (with [rock]) or [law]'s
    return out


def _check_rock(rock) -> dict:
    """The ``[rock]`` table, validated by building the law; its values normalised (floats, the
    segments as tables with every key)."""
    if not isinstance(rock, dict):
        raise ValueError(f"[rock] must be a table; got {rock!r}")
    unknown = [k for k in rock if k not in ROCK_KEYS]
    if unknown:
        raise ValueError(f"[rock] unknown key(s) {unknown}; allowed: {list(ROCK_KEYS)}")
    missing = [k for k in ("k", "k_u", "segments") if k not in rock]
    if missing:
        raise ValueError(f"[rock] missing key(s) {missing}")
    segs = rock["segments"]
    if not isinstance(segs, list | tuple) or not segs:
        raise ValueError(f"[rock] segments must be a non-empty list of tables {{length, impedance}}; "
                         f"got {segs!r}")
    out = {k: rock[k] for k in ROCK_KEYS if k in rock and k != "segments"}
    out["segments"] = []
    for i, g in enumerate(segs):
        if not isinstance(g, dict):
            raise ValueError(f"[rock] segments[{i}] must be a table {{length, impedance}}; got {g!r}")
        bad = [k for k in g if k not in SEGMENT_KEYS]
        if bad or not {"length", "impedance"} <= set(g):
            raise ValueError(f"[rock] segments[{i}] needs keys length and impedance (and optionally "
                             f"wave_speed); got {sorted(g)}")
        out["segments"].append(dict(g))
    try:
        law = _rock_law(out)
    except ValueError as exc:
        raise ValueError(f"[rock] {exc}") from None
    norm = {n.removeprefix("rock."): law.parameter_value(n) for n in _ROCK_PARAMETERS}
    if law.blow_time is not None:
        norm["blow_time"] = law.blow_time
    if law.cells_per_piston is not None:
        norm["cells_per_piston"] = law.cells_per_piston
    norm["segments"] = tuple({"length": g.length, "impedance": g.impedance, "wave_speed": g.wave_speed}
                             for g in law.segments)
    return norm


def _rock_law(rock: dict):
    """The :class:`impactbar.RodRock` of a ``[rock]`` table (its constructors validate)."""
    from ..laws import BilinearRock, RodRock, RodSegment

    segs = [RodSegment(**g) for g in rock["segments"]]
    return RodRock(segments=segs, rock=BilinearRock(k=rock["k"], k_u=rock["k_u"]),
                   bit_mass=rock.get("bit_mass", 0.0), feed=rock.get("feed", 0.0),
                   blow_time=rock.get("blow_time"), cells_per_piston=rock.get("cells_per_piston"))


def _lists(v):
    """Tuples (nested) as lists, for JSON."""
    return [_lists(x) for x in v] if isinstance(v, tuple | list) else v


def _check_load(load) -> dict:
    """The ``[load]`` table, validated by building the load (the table of loads); its numbers
    normalised (floats, ints), its arrays as tuples (complex numbers as ``(re, im)``)."""
    if not isinstance(load, dict):
        raise ValueError(f"[load] must be a table; got {load!r}")
    out = dict(load)
    kind = out.get("kind")
    cls = LOADS.get(kind) if isinstance(kind, str) else None
    for f in cls.traits.parameters if cls is not None else ():
        v = out.get(f.name)
        if f.per is not None and isinstance(v, list | tuple):  # arrays as tuples
            if f.dtype == "c16":
                v = (_complex_pairs(f.name, v) if isinstance(v, list)
                     else tuple(tuple(map(float, c)) for c in v))
            else:
                v = tuple(check_real(f"[load] {f.name}[{j}]", x) for j, x in enumerate(v))
            out[f.name] = v
    try:
        ld = load_from_record(out)
    except ValueError as exc:
        raise ValueError(f"[load] {exc}") from None
    for f in ld.traits.parameters:  # normalised numbers (floats, ints)
        if f.per is None:
            out[f.name] = getattr(ld, f.name)
    return out


def _check_axes(axes, spec) -> tuple:
    """The axes, each a parameter of the spec's bar, load (or drive) or impact law
    (:func:`impactbar.parameters.parameters`), its values checked by building the point."""
    if not isinstance(axes, tuple | list) or not axes:
        raise ValueError("[axes] must name at least one field to sweep")
    sweepable = list(parameters(*_base(spec)))
    forcing = (f"[load] (kind = {spec.load['kind']!r})" if spec.load is not None
               else f"[drive] (kind = {spec.drive['kind']!r})")
    seen = set()
    out = []
    for ax in axes:
        if not isinstance(ax, Axis):
            raise ValueError(f"[axes] entries must be Axis; got {ax!r}")
        if ax.name not in sweepable:
            raise ValueError(f"[axes] {ax.name!r} is not a field of [model] or of this {forcing}"
                             f"{' or [rock]' if spec.rock else ''}{' or [law]' if spec.law else ''}; "
                             f"sweepable: {sweepable}")
        if ax.name in seen:
            raise ValueError(f"[axes] {ax.name!r} is given twice")
        seen.add(ax.name)
        values = []
        for v in ax.values:
            try:
                m, ld = _build(spec, {ax.name: v})
            except ValueError as exc:
                raise ValueError(f"[axes] {ax.name} = {v!r}: {exc}") from None
            values.append(parameter_value(m, ld, ax.name))
        if len(set(values)) != len(values):
            raise ValueError(f"[axes] {ax.name}: values must be distinct; got {values}")
        out.append(Axis(ax.name, tuple(values)))
    return tuple(out)


def _check_options(task, options, spec) -> dict:
    if not isinstance(options, dict):
        raise ValueError(f"[{task}] must be a table; got {options!r}")
    allowed = _OPTIONS[task]
    unknown = [k for k in options if k not in allowed]
    if unknown:
        raise ValueError(f"[{task}] unknown key(s) {unknown}; allowed: {list(allowed)}")
    out = {}
    for name, (default, kind, lo, lo_open, hi) in allowed.items():
        v = options.get(name, default)
        if v is None and name == "max_orbits":
            v = _max_orbits_bound(spec)
        key = f"[{task}] {name}"
        if kind is int:
            out[name] = check_int(key, v, lo=lo, hi=hi)
        else:
            out[name] = check_real(key, v, lo=lo, lo_open=lo_open, hi=hi)
    return out


def _check_chunk_size(spec) -> None:
    """Refuse an extra dimension (``max_orbits``, ``keep``) that would make a work chunk's
    variables larger than ``MAX_CHUNK_VALUES`` values, before anything is allocated."""
    points = math.prod(spec.chunk_shape)
    values = points * spec.extra_size
    if values <= MAX_CHUNK_VALUES:
        return
    name = {"orbits": "max_orbits", "bifurcation": "keep"}.get(spec.task)
    key = f"[{spec.task}] {name} = {spec.extra_size}" if name else f"chunk_points = {spec.chunk_points}"
    hint = (f" (the load admits at most {_max_orbits_bound(spec)} one-impact orbits)"
            if name == "max_orbits" else "")
    vf = float(values) if values < 1e300 else math.inf  # (an integer beyond the float range)
    raise ValueError(f"{key}: a work chunk of {points} grid points would hold {vf:.3g} values per "
                     f"variable ({8 * vf / 2**30:.3g} GiB); the limit is {MAX_CHUNK_VALUES} "
                     f"values ({8 * MAX_CHUNK_VALUES // 2**20} MiB) per chunk: lower {name or 'it'}"
                     f"{hint} or chunk_points")


def _load_numbers(load: dict) -> tuple[str, ...]:
    """The numbers of the spec's load (its parameters an axis may sweep)."""
    return tuple(f.name for f in LOADS[load["kind"]].traits.parameters if f.per is None)


def _max_orbits_bound(spec) -> int:
    """Most one-impact orbits the load admits (its abilities' ``max_one_impact_orbits``) over
    the base load and every value of the load's axes (the bound of each load depends on one of its
    parameters at most: the order ``k`` of a cosine)."""
    if spec.drive is not None:
        return DRIVE_MAX_ORBITS
    extra = 1 if spec.rock is not None else 0  # the rod-rock law's guess from a settled run
    loads = [_make_load(spec.load)] + [_make_load({**spec.load, a.name: v}) for a in spec.axes
                                       if a.name in _load_numbers(spec.load) for v in a.values]
    return max(ld.abilities.max_one_impact_orbits for ld in loads) + extra


def _make_load(load: dict):
    return load_from_record(load)


def _base(spec):
    """The spec's bar (under the law of its ``[rock]`` or ``[law]`` table, if any) and its load or
    drive (the spec's tables, read before the spec is whole: its ``model``, ``load``, ``rock``,
    ``law`` and ``drive`` checked)."""
    from ..model import BarModel

    m = dict(spec.model)
    if spec.rock is not None:
        m["impact"] = _rock_law(spec.rock)
    elif spec.law is not None:
        m["impact"], _ = law_table(spec.law)
    model = BarModel(**m)
    if spec.drive is None:
        return model, _make_load(spec.load)
    drive, _ = drive_table(spec.drive)
    return model, drive


def _build(spec, changes: dict):
    """The bar and load (or drive) at a grid point: the spec's, with the axes' parameters changed
    (:func:`impactbar.parameters.with_parameters`)."""
    return with_parameters(*_base(spec), changes)

def motion_classes() -> tuple[str, ...]:
    """The ``motion`` coordinate of a ``montecarlo`` store: the classes of
    :func:`impactbar.simulation.experiments.classify` in their report order, and ``"k>8"`` for any longer
    one-impact cycle."""
    from ..simulation.experiments import CLASS_ORDER

    return (*CLASS_ORDER, "k>8")


def closed_form_task(spec) -> bool:
    """Whether every point of the sweep takes the rigid bar's vectorised closed forms: the ``orbits``
    task with ``n_modes = 0`` everywhere, the paper's impact law and a cosine or square-wave load
    (:mod:`impactbar.orbits.rigid`, some 200,000 points/s on one core). Such a sweep costs less
    than starting a cluster, so :func:`impactbar.sweeps.run_sweep` computes it in threads of the
    driver process by default, in chunks of :data:`DEFAULT_CLOSED_FORM_CHUNK_POINTS` points unless
    the spec gives ``chunk_points``."""
    from ..orbits.rigid import CLOSED_FORM_KINDS

    if spec.task != "orbits" or spec.load is None or spec.load["kind"] not in CLOSED_FORM_KINDS \
            or spec.rock is not None or spec.law is not None:
        return False
    if not get_law(spec.model.get("impact", "paper")).traits.rigid_closed_forms:
        return False
    modes = next((a.values for a in spec.axes if a.name == "n_modes"), (spec.model["n_modes"],))
    return all(int(n) == 0 for n in modes)
