"""Sweep specifications: the TOML schema, its validation, and the machine at a grid point. One class
for both kinds of map; the task says which machine it sweeps, whose object (the dimensionless bar's,
:mod:`impactbar.sweeps.bar_spec`, or a drifter's config in SI, :mod:`impactbar.sweeps.map_spec`)
reads its axes, builds its points and names its variables."""

from __future__ import annotations

import json
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from .._shared.parameters import parameters
from ..loads import LOADS
from .bar_spec import BAR, _base
from .bar_spec import closed_form_task as closed_form_task
from .grid import BAR_TASKS, DRIFTER_TASKS, TASKS, Axis, ChunkedGrid, cf_unit
from .map_spec import DRIFTER
from .tasks import motion_classes as motion_classes

#: the fields of each load kind, in constructor order (the table of loads)
LOAD_KINDS = {kind: cls.traits.parameters.names for kind, cls in LOADS.items()}

#: task -> the object of the machine it sweeps (:attr:`SweepSpec.space`)
_SPACES = {**dict.fromkeys(BAR_TASKS, BAR), **dict.fromkeys(DRIFTER_TASKS, DRIFTER)}

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
class SweepSpec(ChunkedGrid):
    """A validated sweep or design map: task, machine, axes, task options and chunk size.

    Build it with :func:`load_spec` (a TOML file) or :func:`parse_spec` (a mapping of the same
    shape); constructing it directly validates the same way. Every failure is a ``ValueError`` that
    names the key (``[model] R``, ``[axes] p0``, ``[montecarlo] starts``, ...). The task says the
    machine: the dimensionless bar (``model``, ``load`` or ``drive``, ``rock``, ``law``) or a
    drifter's config (``config``, SI, :mod:`impactbar.sweeps.map_spec`); the other machine's fields
    stay ``None``.

    Parameters
    ----------
    task : {"orbits", "montecarlo", "bifurcation", "operating_point", "settle"}
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
        also ``"rock.k"``, ``"rock.k_u"``, ``"bit_mass"``, ``"feed"``, ``"segment<i>.length"``),
        or 1 to 3 config keys of a drifter (in SI, :func:`impactbar.sweeps.map_spec.config_axis`).
        The grid is their outer product, first axis slowest.
    options : dict
        The task's options, defaults filled in. ``orbits``: ``max_orbits`` (length of the
        ``orbit`` dimension; default the most one-impact orbits the load can have: ``2 k`` for a
        cosine, ``2 K`` for ``K`` Fourier harmonics, 2 for the square wave). ``montecarlo``:
        ``starts`` (100), ``periods`` (200, load periods per run), ``seed`` (0), ``window`` (0.25,
        fraction of each run classified). ``bifurcation``: ``periods`` (400), ``keep`` (64 last
        impacts stored), ``seed`` (0). ``operating_point`` and ``settle``: ``refine_edges`` (false)
        and ``chain`` (``"continue"``), the TOML's top-level keys; ``settle`` also the ``[settle]``
        table (:func:`impactbar.sweeps.map_spec.settle_options`).
    chunk_points : int
        Grid points per work chunk (about; chunks are blocks of the grid), ``>= 1``. Default 400
        for ``orbits`` (32,768 where every point takes the rigid closed forms,
        :func:`closed_form_task`; 4 under the rod-rock law), 4 for ``montecarlo``, 32 for
        ``bifurcation``, the length of the last axis for a design map.
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
    config : dict, optional
        A drifter's configuration (sections of keys with units, read and copied: the valve drifter
        or the drifter with its oil circuit, with or without a drill string and rock), the machine
        of the tasks ``operating_point`` and ``settle``.

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
    model: dict | None = None
    load: dict | None = None
    axes: tuple = ()
    options: dict = field(default_factory=dict)
    chunk_points: int | None = None
    rock: dict | None = None
    law: dict | None = None
    drive: dict | None = None
    config: dict | None = None

    def __post_init__(self) -> None:
        if self.task not in TASKS:
            raise ValueError(f"task must be one of {list(TASKS)}; got {self.task!r}")
        space = self.space
        other = [k for k in ("model", "load", "rock", "law", "drive", "config")
                 if k not in space.fields and getattr(self, k) is not None]
        if other:
            raise ValueError(f"task = {self.task!r} sweeps {space.what}: it takes no {other}")
        space.check(self)

    @property
    def space(self):
        """The machine this spec sweeps, the object of its task: the dimensionless bar
        (:data:`impactbar.sweeps.bar_spec.BAR`) or a drifter's config (:data:`~.map_spec.DRIFTER`)."""
        return _SPACES[self.task]

    # -- the grid (shape, chunks: ChunkedGrid) --------------------------------------------------
    @property
    def extra_size(self) -> int:
        """Length of the task's extra dimension (``orbit``, ``motion`` or ``impact``; 0 for none)."""
        return self.space.extra_size(self)

    def parameters(self) -> dict:
        """The parameters of the spec's base bar and load: every name an axis may take, with its
        record (theory section 2).

        Returns
        -------
        dict of str to Parameter
            :func:`impactbar.parameters.parameters` of the base bar and its load or drive: the value
            at the base, the range, the description.

        Raises
        ------
        ValueError
            For a drifter's design map, whose axes are its config's dotted keys in SI
            (:mod:`impactbar.physical.tree`), not the dimensionless bar's parameters.
        """
        if self.model is None:
            raise ValueError(f"task {self.task!r} sweeps {self.space.what}: its axes are the config's dotted "
                             "keys (impactbar.physical.tree.fields()), not the bar's parameters")
        return parameters(*_base(self))

    def point(self, index=None, values: dict | None = None):
        """The machine at a grid point.

        Parameters
        ----------
        index : tuple of int, shape (n_axes,), optional
            The point's index along each axis; ``None``: the base values.
        values : dict, optional
            Axis name to a value in the axis' unit (dimensionless, or SI for a design map),
            replacing the point's.

        Returns
        -------
        tuple or Drifter or CircuitDrifter
            ``(BarModel, Load or Drive)`` for a sweep of the dimensionless bar; the drifter built
            from the config for a design map.

        Raises
        ------
        ValueError
            Where the machine refuses a value (its one-line message, naming the key).
        """
        at = {} if index is None else {a.name: a.values[i] for a, i in zip(self.axes, index, strict=True)}
        return self.space.point(self, {**at, **(values or {})})

    def variables(self):
        """The variables the task stores.

        Returns
        -------
        Schema
            Of :class:`~impactbar._shared.schema.Field`: name, dtype, fill, long name, units (CF),
            ``per`` the extra dimension of those along it.
        """
        return self.space.variables(self)

    def _axis(self, name: str) -> Axis:
        """The axis ``name``; a ``ValueError`` listing the axes where there is none."""
        for a in self.axes:
            if a.name == name:
                return a
        raise ValueError(f"name must be an axis of this sweep, one of {[a.name for a in self.axes]}; "
                         f"got {name!r}")

    def axis_attrs(self, name: str) -> dict:
        """The attributes of an axis' stored coordinate.

        Parameters
        ----------
        name : str
            An axis of the spec.

        Returns
        -------
        dict
            ``long_name`` (its parameter's description, or its config key) and ``units`` (CF:
            ``"1"`` for a dimensionless parameter, eq. 2; SI for a design map's key).

        Raises
        ------
        ValueError
            ``name`` is not an axis.
        """
        ax = self._axis(name)
        return {"long_name": self.space.axis_name(self, name), "units": cf_unit(ax.unit) or "1"}

    def axis_text(self, name: str, value, digits: int = 6) -> str:
        """An axis value as a reader writes it.

        Parameters
        ----------
        name : str
            An axis of the spec.
        value : float
            In the axis' unit (dimensionless, or SI for a design map).
        digits : int
            Significant digits.

        Returns
        -------
        str
            A design map's value in the unit its config writes the key in
            (:func:`~impactbar.physical.display_units.format_key`), a dimensionless one bare.

        Raises
        ------
        ValueError
            ``name`` is not an axis.
        """
        self._axis(name)
        return self.space.axis_text(self, name, value, digits)

    # -- serialisation ------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The spec as plain JSON-able data of the TOML's shape, defaults filled in."""
        return self.space.to_dict(self)

    def to_json(self) -> str:
        """Canonical JSON of :meth:`to_dict` (what the store keeps and resumption compares)."""
        return json.dumps(self.to_dict(), sort_keys=False, separators=(",", ":"))


def load_spec(path) -> SweepSpec:
    """Read and validate a sweep spec from a TOML file (see :class:`SweepSpec` for the keys; a
    design map's ``config``, a path, is read relative to the file's folder).

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
    return parse_spec(doc, path.parent)


def parse_spec(doc, folder=None) -> SweepSpec:
    """Validate a spec given as a mapping ``doc`` of the TOML's shape (see :class:`SweepSpec`),
    before any work starts; a design map's relative ``config`` path is read against ``folder``.

    ``axes`` maps each parameter to ``{start, stop, num}`` (``numpy.linspace``, both ends included)
    or ``{values = [...]}``; a design map's values are quantities with units (``"80 L/min"``).

    Raises
    ------
    ValueError
        Naming the unknown, missing or out-of-range key.
    """
    if not isinstance(doc, dict):
        raise ValueError(f"spec must be a table; got {type(doc).__name__}")
    if "task" not in doc:
        raise ValueError("missing top-level key 'task'")
    task = doc["task"]
    if task not in TASKS:
        raise ValueError(f"task must be one of {list(TASKS)}; got {task!r}")
    space = _SPACES[task]
    unknown = [k for k in doc if k not in space.top_keys]
    if unknown:
        raise ValueError(f"unknown top-level key(s) {unknown} (task {task!r} sweeps {space.what}); "
                         f"allowed: {list(space.top_keys)}")
    for key in (*space.required(doc), "axes"):
        if key not in doc:
            raise ValueError(f"missing top-level key {key!r}")
    if not isinstance(doc["axes"], dict):
        raise ValueError(f"[axes] must be a table; got {doc['axes']!r}")
    return SweepSpec(**space.parse(doc, folder))


