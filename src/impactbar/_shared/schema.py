"""The declared fields of a result type, from which its views are generated (private).

Each result type (:class:`~impactbar.PeriodicOrbit`, :class:`~impactbar.Trajectory`,
:class:`~impactbar.Branch`, :class:`~impactbar.Blow`, a sweep's variables, a load's parameters)
declares its fields once, as a :class:`Schema` of :class:`Field` s: name, long name, units (the CF
convention: ``"1"`` for a dimensionless number, eq. 2; ``""`` for flags and text), dtype, and
where the field has one, its SI column. ``to_dict``, ``to_dataframe``, ``to_xarray``, the sweep's
stored variables, the SI columns of :mod:`impactbar.physical` and the CLI's tables are generated
from it: a field appears in the views named in its ``views``.

The views (names used across the package):

``"dict"`` (``"dict_one_impact"`` for a one-impact orbit)
    the JSON-ready summary (``to_dict``);
``"table"``
    one column per field in a table of results (``to_dataframe``, ``to_xarray``);
``"branch"``
    the orbit's columns along a branch of orbits (``Branch.to_dataframe``, ``to_xarray``);
``"drifter_branch"``
    a column of a drifter's ``branch.csv`` (``impactbar continue``,
    :mod:`impactbar.physical.branch_table`);
``"sweep"``
    one variable per field in a sweep's store (per orbit);
``"si"``
    the field copied, as it is, into the SI results of :mod:`impactbar.physical`;
``"cli"`` (``"cli_rock"``: the drilling table)
    a column of the CLI's tables (its ``label`` and ``fmt``);
``"repr"``
    a number in the short ``repr`` (its ``label`` and ``fmt``).

A view name is a plain string: a field in no view is still declared (its long name and units
label it wherever it is shown by name).

Examples
--------
>>> from impactbar._shared.schema import Field, Schema
>>> fields = Schema(Field("phase", "phase of the impact", "rad", views={"table", "repr"}, fmt=".4f"),
...                 Field("stable", "every |multiplier| < 1", "", dtype="b1", views={"table"}))
>>> fields.names
('phase', 'stable')
>>> fields.select("repr").names
('phase',)
>>> fields.meta()
{'phase': ('phase of the impact', 'rad'), 'stable': ('every |multiplier| < 1', '')}
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

__all__ = ["Field", "SI", "Schema", "END_MOTION"]

#: the value a field of each dtype kind takes where it has none (a sweep's fill, an empty table)
_FILL = {"f": math.nan, "c": complex(math.nan, math.nan), "b": False, "i": 0, "u": 0, "U": "", "O": None}


@dataclass(frozen=True)
class SI:
    """The SI column a dimensionless field converts to.

    Attributes
    ----------
    name : str
        The column's name, its unit in the name (``"impact_velocity_m_s"``).
    units : str
        Its units (``"m/s"``).
    scale : str or None
        The attribute of the hammer's scales (:class:`impactbar.physical.Scales`) the value is
        multiplied by (``"velocity_m_s"``); ``None`` for a value that keeps its number (an angle).
    long_name : str, optional
        Its long name; the field's own by default.
    label, fmt : str, optional
        Its header and format in CLI tables (:class:`Field`).
    """

    name: str
    units: str
    scale: str | None = None
    long_name: str | None = None
    label: str | None = None
    fmt: str = ".4g"


@dataclass(frozen=True)
class Field:
    """One declared field of a result type.

    Attributes
    ----------
    name : str
        The key in every view (``to_dict``, table column, stored variable).
    long_name : str
        What it is, in words (the CF ``long_name``).
    units : str
        ``"1"`` for a dimensionless number (eq. 2), ``"rad"``, ``"load periods"``, ..., ``""`` for a
        flag, a count or text.
    dtype : str
        numpy dtype of its values: ``"f8"``, ``"i8"``, ``"i4"``, ``"b1"``, ``"c16"``, ``"U"`` (text).
    views : frozenset of str
        The generated views that show it (module docstring).
    si : SI, optional
        The SI column it converts to.
    label : str, optional
        Short header in CLI tables and the repr; the name by default.
    fmt : str
        Format spec of its value in CLI tables and the repr.
    attr : str, optional
        Where the value is read on the result, a dotted path (``"impact.rod_energy"``; ``None``
        anywhere along it gives ``None``); the name by default.
    per : str, optional
        ``None`` for one value per result; the name of a dimension (``"impact"``, ``"multiplier"``)
        for an array of values along it.
    element : str, optional
        The name of one of an array's values, where they are spread over columns or a table's
        dimension (``"phase"`` for ``phases``: ``phase_0``, ``phase_1``, ...); the name by default.
    optional : bool
        Left out of a record (``to_dict``) where its value is ``None`` (a figure only some results
        have).
    scale : float
        The value is shown divided by it in CLI tables (``1e6`` for a stress in Pa shown in MPa).
    """

    name: str
    long_name: str
    units: str = "1"
    dtype: str = "f8"
    views: frozenset = field(default_factory=frozenset)
    si: SI | None = None
    label: str | None = None
    fmt: str = ""
    attr: str | None = None
    per: str | None = None
    element: str | None = None
    optional: bool = False
    scale: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "views", frozenset(self.views))

    @property
    def fill(self):
        """The value where there is none: NaN, 0, ``False`` or ``""`` by dtype."""
        return _FILL[np.dtype(self.dtype).kind]

    @property
    def header(self) -> str:
        """The label, or the name."""
        return self.label or self.name

    @property
    def item(self) -> str:
        """The name of one of an array's values (:attr:`element`, or the name)."""
        return self.element or self.name

    def get(self, obj):
        """The field's value on ``obj`` (following :attr:`attr`)."""
        value = obj
        for part in (self.attr or self.name).split("."):
            if value is None:
                return None
            value = getattr(value, part)
        return value

    def plain(self, value):
        """``value`` as plain JSON-ready Python: ``bool``, ``int``, ``float``, ``str``, a complex
        number as ``[re, im]``, an array as a (nested) list of those; ``None`` stays ``None``."""
        if value is None:
            return None
        if isinstance(value, np.ndarray | list | tuple):
            return [self.plain(v) for v in value]
        kind = np.dtype(self.dtype).kind
        if kind == "c":
            value = complex(value)
            return [value.real, value.imag]
        if kind == "b":
            return bool(value)
        if kind in "iu":
            return int(value)
        if kind == "f":
            return float(value)
        return value if isinstance(value, str) else str(value)

    def format(self, value, most: int = 6) -> str:
        """``value`` by :attr:`fmt` (``str`` for a flag, text, or ``None``); an array as ``[a, b,
        ...]``, its first ``most`` values and the count of the others."""
        if isinstance(value, np.ndarray | list | tuple):
            items = [self.format(v) for v in value[:most]]
            more = f", ... ({len(value)} in all)" if len(value) > most else ""
            return f"[{', '.join(items)}{more}]"
        if value is None or not self.fmt or isinstance(value, bool | np.bool_ | str):
            return str(value)
        return format(value / self.scale if self.scale != 1.0 else value, self.fmt)


class Schema(tuple):
    """The declared fields of one result type, in order: a tuple of :class:`Field` with lookups and
    the generated views.

    Parameters
    ----------
    *fields : Field
        Names unique.

    Raises
    ------
    ValueError
        If two fields have one name.
    """

    def __new__(cls, *fields: Field):
        names = [f.name for f in fields]
        if len(set(names)) != len(names):
            raise ValueError(f"field names must be unique; got {names}")
        return super().__new__(cls, fields)

    def __add__(self, other) -> Schema:
        return Schema(*self, *other)

    def __getitem__(self, key):
        if isinstance(key, str):
            for f in self:
                if f.name == key:
                    return f
            raise KeyError(key)
        return super().__getitem__(key)

    def __contains__(self, key) -> bool:
        if isinstance(key, str):
            return key in self.names
        return super().__contains__(key)

    @cached_property
    def names(self) -> tuple[str, ...]:
        """The fields' names, in order."""
        return tuple(f.name for f in self)

    def select(self, view: str | None = None, *, names: Iterable[str] | None = None) -> Schema:
        """The fields in ``view`` (all with ``None``), or those named (in the order given)."""
        if names is not None:
            return Schema(*(self[n] for n in names))
        return Schema(*(f for f in self if view is None or view in f.views))

    def meta(self) -> dict[str, tuple[str, str]]:
        """``name -> (long_name, units)`` (what :func:`impactbar._shared.tables.frame` labels a table
        with)."""
        return {f.name: (f.long_name, f.units) for f in self}

    def record(self, obj) -> dict:
        """``name -> value`` of every field on ``obj``, JSON-ready (:meth:`Field.plain`); an
        ``optional`` field whose value is ``None`` is left out."""
        out = {}
        for f in self:
            value = f.get(obj)
            if value is None and f.optional:
                continue
            out[f.name] = f.plain(value)
        return out

    def columns(self, objs) -> dict:
        """``name -> values`` of every field over ``objs`` (one value each): an array of the
        field's dtype (a float's ``None`` as NaN), or a list for text and where a flag or count
        is ``None`` (pandas infers the column's type from it, ``None`` kept)."""
        objs = list(objs)
        out = {}
        for f in self:
            values = [f.get(o) for o in objs]
            kind = np.dtype(f.dtype).kind
            if kind == "f":
                values = [f.fill if v is None else v for v in values]
            if not values:
                out[f.name] = np.zeros(0, dtype=object if kind in "UO" else f.dtype)
            elif kind in "UO" or any(v is None for v in values):
                out[f.name] = values
            else:
                out[f.name] = np.array(values, dtype=f.dtype)
        return out

    def stack(self, objs, name: str) -> np.ndarray:
        """The field ``name`` over ``objs`` as one array of its dtype, shape ``(len(objs), ...)``."""
        f = self[name]
        values = [f.get(o) for o in objs]
        return np.array(values, dtype=f.dtype) if values else np.zeros(0, f.dtype)

    def frame(self, objs, *, index: str, index_meta: tuple[str, str], extra: Mapping | None = None,
              extra_meta: Mapping | None = None, attrs: Mapping | None = None):
        """A :class:`pandas.DataFrame` of one row per object: index ``index`` (0, 1, ...), a column
        per field (then ``extra``'s), ``long_name`` and ``units`` of each in
        ``attrs["columns"]``."""
        from . import tables

        cols = {index: np.arange(len(objs))}
        cols.update(self.columns(objs))
        cols.update(extra or {})
        meta = {index: index_meta, **self.meta(), **(extra_meta or {})}
        return tables.frame(cols, meta, index=index, attrs=attrs)

    def table(self, objs, *, width: int = 1) -> list[str]:
        """The CLI's table of ``objs``: a header line of labels, then a line per object, each
        value by its field's ``fmt`` right-aligned in its column."""
        rows = [[f.format(f.get(o)) for f in self] for o in objs]
        widths = [max([len(f.header)] + [len(r[j]) for r in rows]) for j, f in enumerate(self)]
        sep = " " * width
        lines = [sep.join(f.header.rjust(w) for f, w in zip(self, widths, strict=True))]
        lines += [sep.join(v.rjust(w) for v, w in zip(r, widths, strict=True)) for r in rows]
        return lines

    def summary(self, obj) -> list[str]:
        """``"label value"`` of every field on ``obj`` whose value is not ``None`` (the repr's
        items): a flag gives its label when true, ``"not <label>"`` when false; text gives its
        value alone (after its label where it has one); an array of one value gives it under its
        :attr:`Field.item` name."""
        out = []
        for f in self:
            value = f.get(obj)
            if value is None:
                continue
            label = f.header
            if isinstance(value, np.ndarray) and value.shape == (1,):
                value, label = value[0], f.label or f.item
            label = label.replace("_", " ")
            if isinstance(value, bool | np.bool_):
                out.append(label if value else f"not {label}")
            elif np.dtype(f.dtype).kind == "U":  # text: its value, after its label if it has one
                out.append(f"{f.label} {value}" if f.label else str(value))
            else:
                out.append(f"{label} {f.format(value)}")
        return out


#: The struck end's motion sampled in time, a table's columns (:meth:`impactbar.PeriodicOrbit.to_dataframe`,
#: :meth:`impactbar.Trajectory.to_xarray`), dimensionless (eq. 2)
END_MOTION = Schema(Field("end_displacement", "displacement u(1, t) of the struck end"),
                    Field("end_velocity", "velocity u_t(1, t) of the struck end"))
