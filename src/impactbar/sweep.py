"""Parameter sweeps and Monte Carlo on ``dask.distributed``, stored chunk by chunk in zarr (issue 4).

A sweep is described by a :class:`SweepSpec` (usually read from a TOML file with
:func:`load_spec`): a task, a base bar and load, and axes, each sweeping one scalar field of the
bar or the load. The grid is the outer product of the axes, cut into blocks of neighbouring points
("chunks"); :func:`compute_chunk` computes one chunk from plain arguments (no dask, no storage) and
:func:`run_sweep` farms the chunks out to a ``dask.distributed`` cluster and writes each one into a
zarr store as soon as it arrives.

Tasks
-----
``orbits``
    :func:`impactbar.periodic_orbits` at every point: ``phase``, ``admissible``, ``stable``,
    ``schur_stable``, ``max_abs_multiplier``, ``impact_velocity`` along an ``orbit`` dimension
    (padded with NaN / False) and ``n_orbits``.
``montecarlo``
    :func:`impactbar.experiments.run_experiment` at every point: ``starts`` seeded random starts of
    ``periods`` load periods each, the long-run motion of each classified
    (:func:`impactbar.experiments.classify`); ``fraction`` of each class along a ``motion``
    dimension and the impact-interval statistics.
``bifurcation``
    One long run from a seeded random start at every point; the velocities and load phases of the
    last ``keep`` impacts along an ``impact`` dimension (a brute-force bifurcation diagram).

Store layout and resumption
---------------------------
The whole store (every variable, its fill value, a zarr chunk grid equal to the work chunks, the
spec and the package version as attributes) is created up front, into a temporary folder that is
renamed into place, so a store either exists complete or not at all. Each finished chunk is
written into its own zarr chunks; only then its entry of ``chunk_done`` (one ``int8`` per chunk) is
set. zarr's local store replaces files atomically, so a run killed at any moment, SIGKILL included,
loses only the chunks in flight. Rerunning resumes: the stored spec must equal the requested one,
and only chunks whose flag is unset are computed. Every random start is seeded from the spec's
``seed`` and the point's flat index in the grid (``numpy.random.SeedSequence([seed, index])``),
never from the chunk order or the worker, so a resumed sweep equals an uninterrupted one.

Nothing here imports matplotlib; :mod:`impactbar.sweep_plot` draws from a finished store.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import sys
import time
import tomllib
import uuid
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._validate import check_int, check_real

__all__ = [
    "TASKS",
    "LOAD_KINDS",
    "Axis",
    "SweepSpec",
    "SweepRun",
    "load_spec",
    "parse_spec",
    "chunk_slices",
    "compute_chunk",
    "run_sweep",
    "open_sweep",
    "point_done",
    "stored_spec",
    "sweep_progress",
]

TASKS = ("orbits", "montecarlo", "bifurcation")

#: the fields of each load kind, in constructor order
LOAD_KINDS = {"cosine": ("p0", "pk", "k"), "square": ("q", "kappa"), "fourier": ("p0", "coefficients")}

MODEL_FIELDS = ("s", "d", "R", "n_modes")
INT_FIELDS = frozenset({"n_modes", "k"})

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

#: grid points per chunk when the spec does not say
DEFAULT_CHUNK_POINTS = {"orbits": 400, "montecarlo": 4, "bifurcation": 32}

_TOP_KEYS = ("task", "model", "load", "axes", "chunk_points", *TASKS)

#: names of the extra dimension of each task
_EXTRA_DIM = {"orbits": "orbit", "montecarlo": "motion", "bifurcation": "impact"}

_DONE = "chunk_done"
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
        A field of :class:`impactbar.BarModel` (``s``, ``d``, ``R``, ``n_modes``) or of the spec's
        load (``p0``, ``pk``, ``k`` for ``cosine``; ``q``, ``kappa`` for ``square``; ``p0`` for
        ``fourier``).
    values : tuple of float (tuple of int for ``n_modes`` and ``k``), shape (n,)
        The values, distinct, ``n >= 1``; dimensionless like the field.
    """

    name: str
    values: tuple

    @property
    def size(self) -> int:
        return len(self.values)


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: task, base bar and load, axes, task options and chunk size.

    Build it with :func:`load_spec` (a TOML file) or :func:`parse_spec` (a mapping of the same
    shape); constructing it directly validates the same way. Every failure is a ``ValueError`` that
    names the key (``[model] R``, ``[axes] p0``, ``[montecarlo] starts``, ...).

    Parameters
    ----------
    task : {"orbits", "montecarlo", "bifurcation"}
    model : dict
        ``s``, ``d``, ``R``, ``n_modes`` of :class:`impactbar.BarModel`, all required.
    load : dict
        ``kind`` (``"cosine"``, ``"square"`` or ``"fourier"``) and that load's fields, all required:
        ``p0, pk, k`` (:class:`impactbar.CosineLoad`), ``q, kappa``
        (:class:`impactbar.SquareWaveLoad`), ``p0, coefficients``
        (:class:`impactbar.FourierLoad`; ``coefficients`` as ``[[re, im], ...]`` or real numbers).
    axes : tuple of Axis
        At least one; each names a field present in ``model`` or ``load`` (its value there is the
        base, replaced along the axis). The grid is their outer product, first axis slowest.
    options : dict
        The task's options, defaults filled in. ``orbits``: ``max_orbits`` (length of the
        ``orbit`` dimension; default the most one-impact orbits the load can have: ``2 k`` for a
        cosine, ``2 K`` for ``K`` Fourier harmonics, 2 for the square wave). ``montecarlo``:
        ``starts`` (100), ``periods`` (200, load periods per run), ``seed`` (0), ``window`` (0.25,
        fraction of each run classified). ``bifurcation``: ``periods`` (400), ``keep`` (64 last
        impacts stored), ``seed`` (0).
    chunk_points : int
        Grid points per work chunk (about; chunks are blocks of the grid), ``>= 1``. Default 400
        for ``orbits``, 4 for ``montecarlo``, 32 for ``bifurcation``.
    """

    task: str
    model: dict
    load: dict
    axes: tuple
    options: dict = field(default_factory=dict)
    chunk_points: int | None = None

    def __post_init__(self) -> None:
        if self.task not in TASKS:
            raise ValueError(f"task must be one of {list(TASKS)}; got {self.task!r}")
        object.__setattr__(self, "model", _check_model(self.model))
        object.__setattr__(self, "load", _check_load(self.load))
        object.__setattr__(self, "axes", _check_axes(self.axes, self.model, self.load))
        object.__setattr__(self, "options", _check_options(self.task, self.options, self))
        cp = DEFAULT_CHUNK_POINTS[self.task] if self.chunk_points is None else self.chunk_points
        object.__setattr__(self, "chunk_points", check_int("chunk_points", cp, lo=1))

    # -- the grid ----------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape, one entry per axis."""
        return tuple(a.size for a in self.axes)

    @property
    def n_points(self) -> int:
        return math.prod(self.shape)

    @property
    def chunk_shape(self) -> tuple[int, ...]:
        """Shape of a work chunk (and of the zarr chunks along the axes): the last axes are filled
        first, up to ``chunk_points`` points."""
        left = self.chunk_points
        out = []
        for n in reversed(self.shape):
            c = max(1, min(n, left))
            out.append(c)
            left = max(1, left // c)
        return tuple(reversed(out))

    @property
    def chunk_grid(self) -> tuple[int, ...]:
        """Number of chunks along each axis."""
        return tuple(-(-n // c) for n, c in zip(self.shape, self.chunk_shape, strict=True))

    @property
    def n_chunks(self) -> int:
        return math.prod(self.chunk_grid)

    @property
    def extra_size(self) -> int:
        """Length of the task's extra dimension (``orbit``, ``motion`` or ``impact``)."""
        if self.task == "orbits":
            return self.options["max_orbits"]
        if self.task == "bifurcation":
            return self.options["keep"]
        return len(motion_classes())

    def point(self, index) -> tuple:
        """The bar and the load at a grid point.

        Parameters
        ----------
        index : tuple of int, shape (n_axes,)

        Returns
        -------
        BarModel, Load
        """
        changes = {a.name: a.values[i] for a, i in zip(self.axes, index, strict=True)}
        return _build(self.model, self.load, changes)

    # -- serialisation ------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The spec as plain JSON-able data of the TOML's shape, defaults filled in."""
        d = {
            "task": self.task,
            "model": dict(self.model),
            "load": {k: ([list(c) for c in v] if k == "coefficients" else v) for k, v in self.load.items()},
            "axes": {a.name: {"values": list(a.values)} for a in self.axes},
            "chunk_points": self.chunk_points,
        }
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
    """
    path = Path(path)
    try:
        with path.open("rb") as f:
            doc = tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from exc
    except OSError as exc:
        raise ValueError(f"cannot read spec {path}: {exc}") from exc
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
    unknown = [k for k in doc if k not in _TOP_KEYS]
    if unknown:
        raise ValueError(f"unknown top-level key(s) {unknown}; allowed: {list(_TOP_KEYS)}")
    for key in ("task", "model", "load", "axes"):
        if key not in doc:
            raise ValueError(f"missing top-level key {key!r}")
    task = doc["task"]
    if task not in TASKS:
        raise ValueError(f"task must be one of {list(TASKS)}; got {task!r}")
    for other in TASKS:
        if other != task and other in doc:
            raise ValueError(f"[{other}] is given but task = {task!r}; use [{task}] for its options")
    for key in ("model", "load", "axes", task):
        if key in doc and not isinstance(doc[key], dict):
            raise ValueError(f"[{key}] must be a table; got {doc[key]!r}")
    axes_doc = doc["axes"]
    axes = tuple(Axis(name, _axis_values(name, table)) for name, table in axes_doc.items())
    load = dict(doc["load"])
    if "coefficients" in load and isinstance(load["coefficients"], list):
        load["coefficients"] = _coefficients(load["coefficients"])
    return SweepSpec(task=task, model=dict(doc["model"]), load=load, axes=axes,
                     options=dict(doc.get(task, {})), chunk_points=doc.get("chunk_points"))


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


def _coefficients(seq) -> tuple:
    out = []
    for j, c in enumerate(seq):
        if isinstance(c, list) and len(c) == 2:
            re_ = check_real(f"[load] coefficients[{j}][0]", c[0])
            im_ = check_real(f"[load] coefficients[{j}][1]", c[1])
        else:
            re_, im_ = check_real(f"[load] coefficients[{j}]", c), 0.0
        out.append((re_, im_))
    return tuple(out)


def _check_model(model) -> dict:
    if not isinstance(model, dict):
        raise ValueError(f"[model] must be a table; got {model!r}")
    unknown = [k for k in model if k not in MODEL_FIELDS]
    if unknown:
        raise ValueError(f"[model] unknown key(s) {unknown}; allowed: {list(MODEL_FIELDS)}")
    missing = [k for k in MODEL_FIELDS if k not in model]
    if missing:
        raise ValueError(f"[model] missing key(s) {missing}")
    from .model import BarModel

    try:
        m = BarModel(**{k: model[k] for k in MODEL_FIELDS})
    except ValueError as exc:
        raise ValueError(f"[model] {exc}") from None
    return {"s": m.s, "d": m.d, "R": m.R, "n_modes": m.n_modes}


def _check_load(load) -> dict:
    if not isinstance(load, dict):
        raise ValueError(f"[load] must be a table; got {load!r}")
    if "kind" not in load:
        raise ValueError(f"[load] missing key 'kind' (one of {list(LOAD_KINDS)})")
    kind = load["kind"]
    if kind not in LOAD_KINDS:
        raise ValueError(f"[load] kind must be one of {list(LOAD_KINDS)}; got {kind!r}")
    fields = LOAD_KINDS[kind]
    unknown = [k for k in load if k != "kind" and k not in fields]
    if unknown:
        raise ValueError(f"[load] unknown key(s) {unknown} for kind = {kind!r}; allowed: {list(fields)}")
    missing = [k for k in fields if k not in load]
    if missing:
        raise ValueError(f"[load] missing key(s) {missing} for kind = {kind!r}")
    out = {"kind": kind}
    for k in fields:
        v = load[k]
        if k == "coefficients":
            v = _coefficients(v) if isinstance(v, list) else tuple(tuple(map(float, c)) for c in v)
        out[k] = v
    try:
        ld = _make_load(out)
    except ValueError as exc:
        raise ValueError(f"[load] {exc}") from None
    for k in fields:  # normalised values (floats, ints)
        if k != "coefficients":
            out[k] = getattr(ld, k) if hasattr(ld, k) else out[k]
    if kind == "fourier":
        out["p0"] = float(ld.p0)
    return out


def _check_axes(axes, model, load) -> tuple:
    if not isinstance(axes, tuple | list) or not axes:
        raise ValueError("[axes] must name at least one field to sweep")
    sweepable = [*MODEL_FIELDS, *(f for f in LOAD_KINDS[load["kind"]] if f != "coefficients")]
    seen = set()
    out = []
    for ax in axes:
        if not isinstance(ax, Axis):
            raise ValueError(f"[axes] entries must be Axis; got {ax!r}")
        if ax.name not in sweepable:
            raise ValueError(f"[axes] {ax.name!r} is not a field of [model] or of this [load] "
                             f"(kind = {load['kind']!r}); sweepable: {sweepable}")
        if ax.name in seen:
            raise ValueError(f"[axes] {ax.name!r} is given twice")
        seen.add(ax.name)
        values = []
        for v in ax.values:
            try:
                m, ld = _build(model, load, {ax.name: v})
            except ValueError as exc:
                raise ValueError(f"[axes] {ax.name} = {v!r}: {exc}") from None
            values.append(getattr(m, ax.name) if ax.name in MODEL_FIELDS else getattr(ld, ax.name))
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


def _max_orbits_bound(spec) -> int:
    """Most one-impact orbits the load admits: the phase equation (eq. 14) is a trigonometric
    polynomial of degree ``K`` (at most ``2 K`` roots); for the square wave ``V`` is monotone on
    each of its two pieces."""
    kind = spec.load["kind"]
    if kind == "square":
        return 2
    if kind == "fourier":
        return max(2, 2 * len(spec.load["coefficients"]))
    ks = [spec.load["k"]] + [v for a in spec.axes if a.name == "k" for v in a.values]
    return 2 * max(ks)


def _make_load(load: dict):
    from .loads import CosineLoad, FourierLoad, SquareWaveLoad

    kind = load["kind"]
    if kind == "cosine":
        return CosineLoad(load["p0"], load["pk"], load["k"])
    if kind == "square":
        return SquareWaveLoad(load["q"], load["kappa"])
    return FourierLoad(load["p0"], [complex(re_, im_) for re_, im_ in load["coefficients"]])


def _build(model: dict, load: dict, changes: dict):
    from .model import BarModel

    m = {k: changes.get(k, v) for k, v in model.items()}
    ld = {k: changes.get(k, v) for k, v in load.items()}
    return BarModel(**m), _make_load(ld)


# ------------------------------------------------------------------------------------------------
# chunks and the task functions (plain numbers, no dask)
# ------------------------------------------------------------------------------------------------
def chunk_slices(spec: SweepSpec, chunk: int) -> tuple[slice, ...]:
    """The block of the grid covered by work chunk ``chunk`` (C order over :attr:`chunk_grid`).

    Returns
    -------
    tuple of slice, shape (n_axes,)
    """
    chunk = check_int("chunk", chunk, lo=0, hi=spec.n_chunks - 1)
    idx = np.unravel_index(chunk, spec.chunk_grid)
    return tuple(slice(int(i) * c, min((int(i) + 1) * c, n))
                 for i, c, n in zip(idx, spec.chunk_shape, spec.shape, strict=True))


def motion_classes() -> tuple[str, ...]:
    """The ``motion`` coordinate of a ``montecarlo`` store: the classes of
    :func:`impactbar.experiments.classify` in their report order, and ``"k>8"`` for any longer
    one-impact cycle."""
    from .experiments import CLASS_ORDER

    return (*CLASS_ORDER, "k>8")


def point_seed(base_seed: int, flat_index: int) -> int:
    """Seed of the random start(s) at the grid point with C-order index ``flat_index``: from
    ``numpy.random.SeedSequence([base_seed, flat_index])``, independent of chunks and workers."""
    return int(np.random.SeedSequence([base_seed, flat_index]).generate_state(1, np.uint64)[0])


def _variables(spec: SweepSpec) -> dict:
    """Name -> (dtype, fill, has the extra dimension, description) of the task's variables."""
    f8, b1 = np.dtype("float64"), np.dtype("bool")
    common = {"failed": (b1, False, False, "the computation raised ValueError at this point "
                                            "(e.g. an undamped resonance s n pi = k)")}
    if spec.task == "orbits":
        return {
            "phase": (f8, np.nan, True, "phase lag of the one-impact orbit (rad, in [0, 2 pi))"),
            "impact_velocity": (f8, np.nan, True, "velocity of the struck end before impact"),
            "admissible": (b1, False, True, "end stays off the stop between impacts"),
            "stable": (b1, False, True, "admissible and every |Floquet multiplier| < 1"),
            "schur_stable": (b1, False, True, "the paper's Schur criterion (eqs. 27-31)"),
            "max_abs_multiplier": (f8, np.nan, True, "largest |Floquet multiplier|"),
            "n_orbits": (np.dtype("int32"), 0, False, "number of one-impact orbits"),
            **common,
        }
    if spec.task == "montecarlo":
        return {
            "fraction": (f8, np.nan, True, "fraction of the random starts in each long-run motion"),
            "interval_mean": (f8, np.nan, False, "mean interval between main impacts (load periods)"),
            "interval_std": (f8, np.nan, False, "std of the intervals between main impacts "
                                                "(load periods)"),
            "all_interval_mean": (f8, np.nan, False, "mean interval between any impacts (load periods)"),
            "all_interval_std": (f8, np.nan, False, "std of the intervals between any impacts "
                                                    "(load periods)"),
            "run_spread": (f8, np.nan, False, "median over runs of each run's interval std/mean"),
            **common,
        }
    return {
        "impact_velocity": (f8, np.nan, True, "velocity of the struck end before each of the last "
                                              "impacts (oldest first)"),
        "impact_phase": (f8, np.nan, True, "load phase of each of the last impacts (load periods, "
                                           "in [0, 1))"),
        "n_impacts": (np.dtype("int64"), 0, False, "impacts in the whole run"),
        **common,
    }


def compute_chunk(spec: SweepSpec, chunk: int) -> dict[str, np.ndarray]:
    """Compute one work chunk; this is what runs on a worker. No dask, no storage.

    Parameters
    ----------
    spec : SweepSpec
    chunk : int
        Chunk number, ``0 <= chunk < spec.n_chunks``.

    Returns
    -------
    dict of str to numpy.ndarray
        Every variable of the task (see the module docstring), each of shape ``block`` or
        ``block + (extra,)`` where ``block`` is the chunk's part of the grid.

    Raises
    ------
    RuntimeError
        If an ``orbits`` point has more than ``max_orbits`` orbits (the default cannot be exceeded).
        A ``ValueError`` from the library at one point (e.g. an undamped resonance) only sets
        ``failed`` there.
    """
    from ._threads import single_threaded_blas

    slices = chunk_slices(spec, chunk)
    block = tuple(s.stop - s.start for s in slices)
    out = {}
    for name, (dtype, fill, extra, _) in _variables(spec).items():
        shape = block + ((spec.extra_size,) if extra else ())
        out[name] = np.full(shape, fill, dtype=dtype)
    one = {"orbits": _orbits_point, "montecarlo": _montecarlo_point, "bifurcation": _bifurcation_point}
    with single_threaded_blas():
        for local in np.ndindex(*block):
            index = tuple(s.start + i for s, i in zip(slices, local, strict=True))
            flat = int(np.ravel_multi_index(index, spec.shape))
            try:
                model, load = spec.point(index)
                one[spec.task](spec, model, load, flat, out, local)
            except ValueError:
                for name, (_, fill, _, _) in _variables(spec).items():
                    out[name][local] = fill
                out["failed"][local] = True
    return out


def _orbits_point(spec, model, load, flat, out, local) -> None:
    from .orbits import periodic_orbits

    orbits = periodic_orbits(model, load)
    n = len(orbits)
    if n > spec.options["max_orbits"]:
        raise RuntimeError(f"{n} orbits at grid point {flat} ({model}, {load!r}) exceed [orbits] "
                         f"max_orbits = {spec.options['max_orbits']}; raise it in the spec")
    out["n_orbits"][local] = n
    for j, o in enumerate(orbits):
        at = (*local, j)
        out["phase"][at] = o.phase
        out["impact_velocity"][at] = o.impact_velocity
        out["admissible"][at] = o.admissible
        out["stable"][at] = o.stable
        out["schur_stable"][at] = o.schur_stable
        out["max_abs_multiplier"][at] = o.max_abs_multiplier


def _montecarlo_point(spec, model, load, flat, out, local) -> None:
    from .experiments import run_experiment

    opt = spec.options
    res = run_experiment(model, load, starts=opt["starts"], periods=opt["periods"],
                         seed=point_seed(opt["seed"], flat), workers=1, keep=0, window=opt["window"])
    classes = motion_classes()
    frac = np.zeros(len(classes))
    for kind, f in res.fractions.items():
        if kind in classes:
            frac[classes.index(kind)] += f
        elif kind.startswith("k="):
            frac[classes.index("k>8")] += f
        else:  # pragma: no cover - a class the experiments module added
            raise RuntimeError(f"unknown motion class {kind!r}; update impactbar.sweep.motion_classes")
    out["fraction"][local] = frac
    out["interval_mean"][local] = res.interval_mean
    out["interval_std"][local] = res.interval_std
    out["all_interval_mean"][local] = res.all_interval_mean
    out["all_interval_std"][local] = res.all_interval_std
    out["run_spread"][local] = res.run_spread


def _bifurcation_point(spec, model, load, flat, out, local) -> None:
    from .experiments import load_period, random_start
    from .simulate import simulate

    opt = spec.options
    rng = np.random.default_rng(point_seed(opt["seed"], flat))
    t0, start = random_start(model, load, rng)
    T = load_period(load)
    tr = simulate(model, load, start, t0 + opt["periods"] * T, t0=t0)
    keep = opt["keep"]
    v = tr.impact_velocities[-keep:]
    t = tr.impact_times[-keep:]
    out["impact_velocity"][(*local, slice(0, v.size))] = v
    out["impact_phase"][(*local, slice(0, t.size))] = np.mod(t / T, 1.0)
    out["n_impacts"][local] = tr.n_impacts


# ------------------------------------------------------------------------------------------------
# the store
# ------------------------------------------------------------------------------------------------
def _template(spec: SweepSpec):
    """The dataset to create the store from: lazy (dask) fill values, coordinates, attributes."""
    import dask.array as da
    import xarray as xr

    from . import __version__

    dims = tuple(a.name for a in spec.axes)
    extra_dim = _EXTRA_DIM[spec.task]
    chunks = spec.chunk_shape
    data_vars = {}
    for name, (dtype, fill, extra, desc) in _variables(spec).items():
        shape = spec.shape + ((spec.extra_size,) if extra else ())
        ch = chunks + ((spec.extra_size,) if extra else ())
        arr = da.full(shape, fill, dtype=dtype, chunks=ch)
        data_vars[name] = xr.Variable(dims + ((extra_dim,) if extra else ()), arr,
                                      attrs={"description": desc})
    data_vars[_DONE] = xr.Variable(("chunk",), da.zeros(spec.n_chunks, dtype=np.int8,
                                                          chunks=spec.n_chunks),
                                   attrs={"description": "1 once the work chunk is stored"})
    coords = {a.name: np.asarray(a.values) for a in spec.axes}
    if spec.task == "montecarlo":
        coords["motion"] = np.asarray(motion_classes(), dtype=object)  # variable-length strings
    attrs = {
        _ATTR_SPEC: spec.to_json(),
        _ATTR_VERSION: __version__,
        "task": spec.task,
        "chunk_shape": list(spec.chunk_shape),
    }
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def _is_sweep_store(path: Path) -> bool:
    return (path / "zarr.json").is_file() and _ATTR_SPEC in _read_attrs(path)


def _read_attrs(path: Path) -> dict:
    try:
        doc = json.loads((path / "zarr.json").read_text())
    except (OSError, ValueError):
        return {}
    return doc.get("attributes", {}) or {}


def _create_store(spec: SweepSpec, path: Path) -> None:
    """Create the full store in a temporary folder next to ``path`` and rename it into place
    (removing what a run killed during this step left behind)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    for stale in path.parent.glob(f".{path.name}.creating-*"):
        shutil.rmtree(stale, ignore_errors=True)
    tmp = path.with_name(f".{path.name}.creating-{uuid.uuid4().hex}")
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
            _template(spec).to_zarr(tmp, mode="w-", compute=False, zarr_format=3, consolidated=True)
        os.rename(tmp, path)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def _prepare_store(spec: SweepSpec, path: Path, overwrite: bool) -> np.ndarray:
    """Create the store or check that it holds this sweep; return the done flags, shape
    ``(n_chunks,)``."""
    from . import __version__

    if path.exists():
        if not _is_sweep_store(path):
            raise ValueError(f"--out {path} exists and is not an impactbar sweep store; "
                             "choose another path")
        if overwrite:
            shutil.rmtree(path)
        else:
            attrs = _read_attrs(path)
            if attrs.get(_ATTR_SPEC) != spec.to_json():
                stored = json.loads(attrs.get(_ATTR_SPEC, "{}"))
                new = spec.to_dict()
                diff = sorted(k for k in set(stored) | set(new) if stored.get(k) != new.get(k))
                raise ValueError(f"--out {path} holds a different sweep (differs in {diff}); "
                                 "use --overwrite to replace it, or another --out")
            if attrs.get(_ATTR_VERSION) != __version__:
                raise ValueError(f"--out {path} was computed by impactbar {attrs.get(_ATTR_VERSION)}, "
                                 f"this is {__version__}; use --overwrite to recompute it")
            return _read_done(path, spec.n_chunks)
    _create_store(spec, path)
    return np.zeros(spec.n_chunks, dtype=np.int8)


def _read_done(path: Path, n_chunks: int) -> np.ndarray:
    import zarr

    done = np.asarray(zarr.open_array(store=str(path), path=_DONE, mode="r")[:], dtype=np.int8)
    if done.shape != (n_chunks,):  # pragma: no cover - the spec check makes this impossible
        raise ValueError(f"{path}: chunk_done has shape {done.shape}, expected ({n_chunks},)")
    return done


def _write_chunk(spec: SweepSpec, path: Path, chunk: int, result: dict) -> None:
    import xarray as xr

    slices = chunk_slices(spec, chunk)
    dims = tuple(a.name for a in spec.axes)
    extra_dim = _EXTRA_DIM[spec.task]
    data = {}
    for name, arr in result.items():
        d = dims + ((extra_dim,) if arr.ndim > len(dims) else ())
        data[name] = (d, arr)
    region = {a.name: s for a, s in zip(spec.axes, slices, strict=True)}
    xr.Dataset(data).to_zarr(path, region=region, mode="r+", consolidated=False)


def _write_done(path: Path, done: np.ndarray) -> None:
    import xarray as xr

    xr.Dataset({_DONE: (("chunk",), done)}).to_zarr(path, region={"chunk": slice(0, done.size)},
                                                    mode="r+", consolidated=False)


def open_sweep(path):
    """Open a sweep store as an ``xarray.Dataset`` (lazily; ``xarray.open_zarr`` does the same).

    Raises
    ------
    ValueError
        If ``path`` is not an impactbar sweep store.
    """
    import xarray as xr

    path = Path(path)
    if not _is_sweep_store(path):
        raise ValueError(f"{path} is not an impactbar sweep store")
    return xr.open_zarr(path)


def stored_spec(ds) -> SweepSpec:
    """The spec of a sweep store, from the attributes of its dataset (:func:`open_sweep`)."""
    if _ATTR_SPEC not in ds.attrs:
        raise ValueError("the dataset is not an impactbar sweep store (no spec attribute)")
    return parse_spec(json.loads(ds.attrs[_ATTR_SPEC]))


def point_done(ds):
    """Which grid points are stored: ``chunk_done`` spread over the grid.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep store (:func:`open_sweep`).

    Returns
    -------
    xarray.DataArray of bool, shape of the grid
        Dimensions and coordinates of the axes.
    """
    import xarray as xr

    spec = stored_spec(ds)
    flags = np.asarray(ds[_DONE].values, dtype=bool).reshape(spec.chunk_grid)
    grid = flags
    for axis, c in enumerate(spec.chunk_shape):
        grid = np.repeat(grid, c, axis=axis)
    grid = grid[tuple(slice(0, n) for n in spec.shape)]
    dims = tuple(a.name for a in spec.axes)
    return xr.DataArray(grid, dims=dims, coords={d: ds[d].values for d in dims})


def sweep_progress(path) -> tuple[int, int]:
    """``(chunks done, chunks in all)`` of a sweep store, from its done flags."""
    path = Path(path)
    if not _is_sweep_store(path):
        raise ValueError(f"{path} is not an impactbar sweep store")
    spec = parse_spec(json.loads(_read_attrs(path)[_ATTR_SPEC]))
    done = _read_done(path, spec.n_chunks)
    return int(done.sum()), int(done.size)


# ------------------------------------------------------------------------------------------------
# the driver
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SweepRun:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    store : pathlib.Path
    n_chunks : int
        Chunks in the sweep.
    already_done : int
        Chunks found finished in the store (resumed).
    computed : int
        Chunks computed by this run.
    seconds : float
        Wall time of the computation (s), cluster start-up excluded.
    """

    store: Path
    n_chunks: int
    already_done: int
    computed: int
    seconds: float

    @property
    def complete(self) -> bool:
        return self.already_done + self.computed == self.n_chunks


def default_workers() -> int:
    """Worker processes of the default local cluster: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def run_sweep(spec: SweepSpec, store, *, client=None, scheduler: str | None = None,
              n_workers: int | None = None, overwrite: bool = False, progress: bool = True) -> SweepRun:
    """Compute a sweep into a zarr store, resuming whatever an earlier run finished.

    Parameters
    ----------
    spec : SweepSpec
    store : str or os.PathLike
        Folder of the zarr store; created if absent, resumed if it holds the same sweep.
    client : distributed.Client, optional
        Use this client's cluster.
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:port``); its workers must be able to import
        impactbar.
    n_workers : int, optional
        Size of the local cluster started when neither ``client`` nor ``scheduler`` is given
        (processes of one thread each); default the number of cores.
    overwrite : bool, optional
        Replace a store holding another sweep (or one from another impactbar version).
    progress : bool, optional
        Show a progress bar (chunks done, rate, time left) on stderr.

    Returns
    -------
    SweepRun

    Raises
    ------
    ValueError
        If the store holds another sweep and ``overwrite`` is false, or ``store`` is a folder that
        is not a sweep store; nothing is computed then.
    """
    if not isinstance(spec, SweepSpec):
        raise ValueError(f"spec must be a SweepSpec; got {type(spec).__name__}")
    if sum(x is not None for x in (client, scheduler, n_workers)) > 1:
        raise ValueError("give at most one of client, scheduler, n_workers")
    if n_workers is not None:
        n_workers = check_int("n_workers", n_workers, lo=1)
    path = Path(store)
    done = _prepare_store(spec, path, overwrite)
    todo = [int(i) for i in np.flatnonzero(done == 0)]
    already = spec.n_chunks - len(todo)
    if not todo:
        return SweepRun(path, spec.n_chunks, already, 0, 0.0)
    if client is not None:
        return _drive(spec, path, done, todo, client, progress)
    from distributed import Client, LocalCluster

    if scheduler is not None:
        with Client(scheduler) as cl:
            return _drive(spec, path, done, todo, cl, progress)
    import logging

    n = default_workers() if n_workers is None else n_workers
    with (LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                       dashboard_address=None, silence_logs=logging.ERROR) as cluster,
          Client(cluster) as cl):
        return _drive(spec, path, done, todo, cl, progress)


def _drive(spec, path, done, todo, client, progress) -> SweepRun:
    from distributed import as_completed
    from tqdm import tqdm

    already = spec.n_chunks - len(todo)
    tag = uuid.uuid4().hex[:8]
    t_start = time.perf_counter()
    futures = [client.submit(compute_chunk, spec, i, key=f"impactbar-{spec.task}-{tag}-{i}",
                             pure=False) for i in todo]
    chunk_of = {f.key: i for f, i in zip(futures, todo, strict=True)}
    computed = 0
    bar = tqdm(total=len(todo), unit="chunk", file=sys.stderr, disable=not progress,
               desc=f"{spec.task} ({already}/{spec.n_chunks} stored before)", smoothing=0.1)
    try:
        for fut in as_completed(futures):
            result = fut.result()  # a task error propagates; every finished chunk is stored
            i = chunk_of[fut.key]
            _write_chunk(spec, path, i, result)
            done[i] = 1
            _write_done(path, done)  # after the data: a kill in between loses only this chunk
            fut.release()
            computed += 1
            bar.update(1)
    finally:
        bar.close()
        for f in futures:
            if not f.done():
                f.cancel()
    return SweepRun(path, spec.n_chunks, already, computed, time.perf_counter() - t_start)
