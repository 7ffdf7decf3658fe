"""The dimensionless bar of the paper as the machine of a sweep (tasks ``orbits``, ``montecarlo``,
``bifurcation``): its tables (``[model]``, ``[load]`` or ``[drive]``, ``[rock]``, ``[law]``), their
validation, and the bar and forcing at a grid point (:class:`impactbar.sweeps.SweepSpec`)."""

from __future__ import annotations

import math

from .._shared.parameters import parameter_value, parameters, with_parameters
from .._shared.validate import check_int, check_real
from ..laws import get_law
from ..laws.rodrock import RodRock
from ..loads import LOADS, load_from_record
from ..model import BarModel
from .grid import BAR_TASKS, Axis, _check_options, _grid_values, check_points
from .parts import DRIVE_MAX_ORBITS, drive_table, law_table
from .tasks import _bar_chunk, _bar_variables, motion_classes

#: the fields of the ``[model]`` table: the bar's parameters (:attr:`impactbar.BarModel.parameters`)
MODEL_FIELDS = BarModel.parameters.names
#: the integer fields (an axis of them holds integers)
INT_FIELDS = frozenset({"n_modes", *(f.name for cls in LOADS.values() for f in cls.traits.parameters
                                     if f.dtype.startswith("i"))})

#: task options (:func:`~impactbar.sweeps.spec._check_options`)
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

_TOP_KEYS = ("task", "model", "load", "drive", "law", "axes", "rock", "chunk_points", *BAR_TASKS)

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



class _Bar:
    """The dimensionless bar of the paper under a load or a drive (tasks ``orbits``,
    ``montecarlo``, ``bifurcation``): its tables, its points, its variables."""

    what = "the dimensionless bar"
    edges = False  # (its stores have no edges, :func:`impactbar.sweeps.maps.sweep_edges`)
    fields = ("model", "load", "rock", "law", "drive")
    top_keys = _TOP_KEYS

    def required(self, doc) -> tuple:
        return ("model", "load" if "drive" not in doc else "drive")

    def parse(self, doc, folder=None) -> dict:
        task = doc["task"]
        for other in BAR_TASKS:
            if other != task and other in doc:
                raise ValueError(f"[{other}] is given but task = {task!r}; use [{task}] for its options")
        for key in ("model", "load", "drive", "law", "rock", task):
            if key in doc and not isinstance(doc[key], dict):
                raise ValueError(f"[{key}] must be a table; got {doc[key]!r}")
        axes = tuple(Axis(name, _axis_values(name, table)) for name, table in doc["axes"].items())
        load = dict(doc["load"]) if "load" in doc else None
        return {"task": task, "model": dict(doc["model"]), "load": load, "axes": axes,
                "options": dict(doc.get(task, {})), "chunk_points": doc.get("chunk_points"),
                "rock": doc.get("rock"), "law": doc.get("law"), "drive": doc.get("drive")}

    def check(self, spec) -> None:
        if spec.rock is not None:
            object.__setattr__(spec, "rock", _check_rock(spec.rock))
        if spec.law is not None:
            if spec.rock is not None:
                raise ValueError("[law] and [rock] both name the impact law: give one")
            _, table = law_table(spec.law)
            object.__setattr__(spec, "law", table)
        object.__setattr__(spec, "model", _check_model(spec.model, spec.rock, spec.law))
        if (spec.load is None) == (spec.drive is None):
            raise ValueError("give [load] or [drive] (the forcing), not both nor neither")
        if spec.drive is not None:
            if spec.task != "orbits":
                raise ValueError(f"task = {spec.task!r}: a [drive] sweeps the 'orbits' task only")
            _, table = drive_table(spec.drive)
            object.__setattr__(spec, "drive", table)
        else:
            object.__setattr__(spec, "load", _check_load(spec.load))
        if isinstance(spec.axes, tuple | list) and all(isinstance(ax, Axis) for ax in spec.axes):
            check_points(spec.axes)  # (before each value is checked by building its point)
        object.__setattr__(spec, "axes", _check_axes(spec.axes, spec))
        object.__setattr__(spec, "options", _check_options(spec.task, spec.options, _OPTIONS[spec.task],
                                                          lambda _: _max_orbits_bound(spec)))
        cp = spec.chunk_points
        if cp is None:
            closed = closed_form_task(spec)
            cp = DEFAULT_CLOSED_FORM_CHUNK_POINTS if closed else DEFAULT_CHUNK_POINTS[spec.task]
            if spec.rock is not None and spec.task == "orbits":
                cp = DEFAULT_ROCK_CHUNK_POINTS
        object.__setattr__(spec, "chunk_points", check_int("chunk_points", cp, lo=1))
        spec.check_grid()
        _check_chunk_size(spec)

    def extra_size(self, spec) -> int:
        if spec.task == "orbits":
            return spec.options["max_orbits"]
        if spec.task == "bifurcation":
            return spec.options["keep"]
        return len(motion_classes())

    def point(self, spec, changes: dict):
        return _build(spec, changes)

    def variables(self, spec):
        return _bar_variables(spec)

    def compute_chunk(self, spec, chunk: int) -> dict:
        return _bar_chunk(spec, chunk)

    def axis_name(self, spec, name: str) -> str:
        return spec.parameters()[name].description

    def axis_text(self, spec, name: str, value, digits: int = 6) -> str:
        return f"{value:.{digits}g}"

    def to_dict(self, spec) -> dict:
        d = {"task": spec.task, "model": dict(spec.model)}
        if spec.load is not None:
            d["load"] = {k: _lists(v) for k, v in spec.load.items()}
        for name in ("drive", "law"):  # (only where given: a spec without them keeps its JSON)
            if getattr(spec, name) is not None:
                d[name] = dict(getattr(spec, name))
        d["axes"] = {a.name: {"values": list(a.values)} for a in spec.axes}
        d["chunk_points"] = spec.chunk_points
        if spec.rock is not None:
            d["rock"] = {k: ([dict(g) for g in v] if k == "segments" else v) for k, v in spec.rock.items()}
        d[spec.task] = dict(spec.options)
        return d



#: the dimensionless bar's object (:attr:`SweepSpec.space` of its tasks)
BAR = _Bar()


def _axis_values(name, table) -> tuple:
    vals, ranged = _grid_values(name, table, check_real)
    if ranged and name in INT_FIELDS:
        if not all(v == round(v) for v in vals):
            raise ValueError(f"[axes] {name}: start, stop, num must give integers for an integer "
                             f"field; got {vals}")
        return tuple(int(round(v)) for v in vals)
    return tuple(vals)


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
    loads = [load_from_record(spec.load)] + [load_from_record({**spec.load, a.name: v}) for a in spec.axes
                                       if a.name in _load_numbers(spec.load) for v in a.values]
    return max(ld.abilities.max_one_impact_orbits for ld in loads) + extra


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
        return model, load_from_record(spec.load)
    drive, _ = drive_table(spec.drive)
    return model, drive


def _build(spec, changes: dict):
    """The bar and load (or drive) at a grid point: the spec's, with the axes' parameters changed
    (:func:`impactbar.parameters.with_parameters`)."""
    return with_parameters(*_base(spec), changes)


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
