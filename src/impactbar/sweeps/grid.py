"""The grid of a sweep and its work chunks (:class:`~impactbar.sweeps.SweepSpec`: the dimensionless
bar's sweeps and a drifter's design maps)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._shared.validate import check_int, check_real

#: the tasks of the dimensionless bar, then those of a drifter's design map (SI)
BAR_TASKS = ("orbits", "montecarlo", "bifurcation")
DRIFTER_TASKS = ("operating_point", "settle")
TASKS = BAR_TASKS + DRIFTER_TASKS

#: most grid points a sweep or a map may have: the driver, the edges and the plots read whole
#: variables of the grid (800 MB a float64 variable at this size), and a point costs from a
#: microsecond (the rigid closed forms) to a second (a drifter's orbit)
MAX_GRID_POINTS = 10**8
#: most work chunks: each is a task on the cluster, and its flag and checksum are held in memory
MAX_CHUNKS = 10**6


def check_points(axes) -> None:
    """Refuse axes (each with a ``name`` and a ``size``) whose outer product has more than
    :data:`MAX_GRID_POINTS` points: a ``ValueError`` naming the axes and their product. Cheap: a spec
    asks it before it checks each axis value (a point built per value: hours on a mistyped size).

    Raises
    ------
    ValueError
        Too many points.
    """
    n = math.prod(a.size for a in axes)
    if n > MAX_GRID_POINTS:
        sizes = " x ".join(f"{a.name} ({a.size})" for a in axes)
        raise ValueError(f"[axes] {sizes} make {n} grid points; the limit is {MAX_GRID_POINTS}: fewer "
                         "values along an axis")


class ChunkedGrid:
    """The outer product of ``axes`` (each with a ``size``), first axis slowest, cut into blocks of
    about ``chunk_points`` neighbouring points: what the store and the driver read of a spec."""

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

    def check_grid(self) -> None:
        """Refuse a grid of more than :data:`MAX_GRID_POINTS` points or :data:`MAX_CHUNKS` work
        chunks (a ``ValueError`` naming the axes and their product), before anything is created."""
        check_points(self.axes)
        sizes = " x ".join(f"{a.name} ({a.size})" for a in self.axes)
        if self.n_chunks > MAX_CHUNKS:
            raise ValueError(f"chunk_points = {self.chunk_points}: the {self.n_points} grid points of "
                             f"[axes] {sizes} make {self.n_chunks} work chunks; the limit is "
                             f"{MAX_CHUNKS}: raise chunk_points")

    def block(self, chunk: int) -> tuple[slice, ...]:
        """The block of the grid covered by work chunk ``chunk`` (C order over :attr:`chunk_grid`;
        not checked: :func:`impactbar.sweeps.chunk_slices` checks it)."""
        idx = np.unravel_index(chunk, self.chunk_grid)
        return tuple(slice(int(i) * c, min((int(i) + 1) * c, n))
                     for i, c, n in zip(idx, self.chunk_shape, self.shape, strict=True))


@dataclass(frozen=True)
class Axis:
    """One axis of the grid: a parameter of the machine and the values it takes.

    Parameters
    ----------
    name : str
        A parameter of the dimensionless bar, its load, drive or law (``s``, ``R``, ``p0``,
        ``rock.k``, ``segment0.length``; :func:`impactbar.parameters.parameters`), or a dotted
        config key of a drifter (``supply.pump_flow``, ``rod.segments.0.length``).
    values : tuple of float (tuple of int for an integer parameter), shape (n,)
        The values, distinct, ``n >= 1``; in ``unit``.
    unit : str
        The SI unit of a drifter's config key (pint's spelling, ``"m**3/s"``); ``""`` for a
        dimensionless parameter (every one of the bar's, theory section 2).
    """

    name: str
    values: tuple
    unit: str = ""

    @property
    def size(self) -> int:
        return len(self.values)


def cf_unit(unit: str) -> str:
    """A pint unit as a CF ``units`` string (``"m**3/s"`` -> ``"m3/s"``; ``""`` stays)."""
    return unit.replace("**", "").replace(" ", "")


def _check_options(task: str, options, allowed: dict, fill=None) -> dict:
    """A task's options table checked against ``allowed`` (name -> ``(default, kind, lower bound,
    lower bound open, upper bound[, upper bound open])``), defaults filled in (``fill(name)`` where
    the default is ``None``)."""
    if not isinstance(options, dict):
        raise ValueError(f"[{task}] must be a table; got {options!r}")
    unknown = [k for k in options if k not in allowed]
    if unknown:
        raise ValueError(f"[{task}] unknown key(s) {unknown}; allowed: {list(allowed)}")
    out = {}
    for name, (default, kind, lo, lo_open, hi, *hi_open) in allowed.items():
        v = options.get(name, default)
        v, key = fill(name) if v is None else v, f"[{task}] {name}"
        out[name] = (check_int(key, v, lo=lo, hi=hi) if kind is int
                     else check_real(key, v, lo=lo, lo_open=lo_open, hi=hi, hi_open=hi_open == [True]))
    return out


def _grid_values(name: str, table, number, hi: int = 10**7) -> tuple[list, bool]:
    """An axis table's values and whether they come from ``{start, stop, num}`` (``numpy.linspace``
    of the ends read by ``number(key, value)``, both included; ``num <= hi``) rather than
    ``{values}`` (as given)."""
    if not isinstance(table, dict):
        raise ValueError(f"[axes] {name} must be a table {{start, stop, num}} or {{values}}; got {table!r}")
    keys = set(table)
    if "values" in keys and keys <= {"values", "unit"}:
        vals = table["values"]
        if not isinstance(vals, list) or not vals:
            raise ValueError(f"[axes] {name}.values must be a non-empty list of numbers; got {vals!r}")
        return vals, False
    if keys == {"start", "stop", "num"}:
        start = number(f"[axes] {name}.start", table["start"])
        stop = number(f"[axes] {name}.stop", table["stop"])
        num = check_int(f"[axes] {name}.num", table["num"], lo=1, hi=hi)
        return [float(v) for v in np.linspace(start, stop, num)], True
    raise ValueError(f"[axes] {name} must have keys start, stop, num or just values; got {sorted(keys)}")
