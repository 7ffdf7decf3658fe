"""Results of a continuation: :class:`Branch` and its :class:`BranchEvent` s (theory §4-§7).

numpy only at import; pandas, xarray and matplotlib are imported inside ``to_dataframe``,
``to_xarray`` and ``plot``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from .._shared.schema import Field, Schema
from .._shared.validate import check_real
from ..orbits.find import find_orbit
from ..orbits.orbit import ORBIT_FIELDS, MultiImpactOrbit
from .parameters import with_parameter

__all__ = ["Branch", "BranchEvent", "orbit_columns"]

TWO_PI = 2.0 * math.pi

#: the orbit's fields at each point of a branch: those of :data:`ORBIT_FIELDS` in the view ``"branch"``
POINT_FIELDS = ORBIT_FIELDS.select("branch")


def orbit_columns(orbits) -> dict:
    """The orbits of a branch or curve as a table's columns (:data:`POINT_FIELDS`): ``name ->
    array`` of one value per orbit, an array along impacts or multipliers spread over columns
    ``<element>_<j>`` (a complex one as ``<element>_<j>_real`` and ``_imag``)."""
    out = {}
    scalars = Schema(*(f for f in POINT_FIELDS if f.per is None)).columns(orbits)
    for f in POINT_FIELDS:
        if f.per is None:
            out[f.name] = scalars[f.name]
            continue
        values = POINT_FIELDS.stack(orbits, f.name).reshape(len(orbits), -1)
        for j in range(values.shape[1]):
            if f.dtype == "c16":
                out[f"{f.item}_{j}_real"], out[f"{f.item}_{j}_imag"] = values[:, j].real, values[:, j].imag
            else:
                out[f"{f.item}_{j}"] = values[:, j]
    return out

# ------------------------------------------------------------------------------------------------
# results
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class BranchEvent:
    """A special point located on a branch.

    Attributes
    ----------
    kind : EventKind
        A string: ``"fold"`` (a multiplier through ``+1`` where the branch turns back in the parameter),
        ``"branch-point"`` (a multiplier through ``+1`` without a turn), ``"period-doubling"``
        (``-1``), ``"neimark-sacker"`` (a complex pair through the unit circle), ``"grazing"`` (the
        end touches the stop between impacts, or an impact velocity goes through 0) or
        ``"admissibility"`` (another change of admissibility, e.g. sticking at ``R = 0``) or, under
        a drive with state, ``"border-collision"`` (its state touches one of its switching surfaces
        during the period: its ability ``border_tests``; which one in ``surface``).
    parameter : str
        Name of the continuation parameter.
    value : float
        Its value at the event, located to ``xtol`` (default ``1e-10``) along the branch.
    index : int
        The event lies between branch points ``index - 1`` and ``index``.
    orbit : MultiImpactOrbit
        The orbit at the event.
    multiplier : complex
        The critical multiplier (NaN for grazing, admissibility and border-collision events).
    surface : str
        A border collision's surface, as the drive names it (e.g. the oil circuit's
        ``"accumulator"``, ``"relief"``); ``""`` for the other kinds.

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, continue_orbit, periodic_orbits
    >>> start = periodic_orbits(BarModel(s=3.0, d=0.0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))[1]
    >>> fold = continue_orbit(start, "p0", to=1.5).events[0]  # the rigid fold: (1 + R)/(pi (1 - R))
    >>> str(fold.kind), round(fold.value, 6), round(fold.multiplier.real, 6)
    ('fold', 1.27324, 1.0)
    """

    kind: str
    parameter: str
    value: float
    index: int
    orbit: MultiImpactOrbit = field(repr=False)
    multiplier: complex
    _point: np.ndarray = field(repr=False, default=None)
    surface: str = ""

    #: the declared fields: :meth:`to_dict`, :meth:`Branch.events_dataframe` and the ``event_``
    #: variables of :meth:`Branch.to_xarray` (those in the view ``"branch"``)
    fields: ClassVar[Schema] = Schema(
        Field("kind", "the kind of event", "", dtype="U", views={"branch"}),
        Field("parameter", "the continuation parameter", "", dtype="U"),
        Field("value", "the parameter's value at the event", views={"branch"}),
        Field("index", "the event lies between branch points index - 1 and index", "", dtype="i8",
              views={"branch"}),
        Field("multiplier", "the critical multiplier (NaN for grazing and admissibility)", dtype="c16",
              views={"branch"}),
        Field("phase", "load phase of the first impact", "rad", attr="orbit.phase", views={"branch"}),
        Field("impacts", "impacts per period of the motion, m", "", dtype="i8", attr="orbit.impacts"),
        Field("periods", "load periods per period of the motion, n", "", dtype="i8",
              attr="orbit.periods"),
        Field("surface", "the border a border collision crosses (empty for other events)", "",
              dtype="U"))

    def __repr__(self) -> str:
        """One line: the kind, where, the multiplier."""
        mu = "" if math.isnan(self.multiplier.real) else f", multiplier {self.multiplier:.6g}"
        return f"BranchEvent({str(self.kind)!r} at {self.parameter} = {self.value:.10g}{mu})"

    def to_dict(self) -> dict:
        """A JSON-ready summary: the fields of :attr:`fields`."""
        return self.fields.record(self)


@dataclass(frozen=True, eq=False)
class Branch:
    """A branch of periodic motions with ``impacts`` impacts in ``periods`` load periods.

    Attributes
    ----------
    parameter : str
        The continuation parameter (one of :data:`PARAMETERS`).
    values : numpy.ndarray, shape (P,)
        Its value at each point.
    orbits : tuple of MultiImpactOrbit, length P
        The motion at each point (admissibility and multipliers included).
    events : tuple of BranchEvent
        Located special points, in the order met.
    status : BranchStatus
        Why the continuation stopped (a string; ``status.message`` explains it): ``"reached"``
        (the target value), ``"max_points"``, ``"step too small"`` (Newton failed at the smallest
        step), ``"parameter range"`` (the parameter left its allowed range), ``"turned back"`` (a
        fold led out of the range between start and target), ``"impact at a load jump"`` (the
        branch has a corner where an impact meets a jump of the load) or
        ``"stopped at <event kind>"``.
    impacts, periods : int
        ``m`` and ``n``.

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, continue_orbit, periodic_orbits
    >>> start = periodic_orbits(BarModel(s=3.0, d=0.0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))[1]
    >>> branch = continue_orbit(start, "p0", to=0.66)
    >>> branch.parameter, branch.impacts, branch.periods, str(branch.status)
    ('p0', 1, 1, 'reached')
    >>> [(str(e.kind), round(e.value, 6)) for e in branch.events]
    [('period-doubling', 0.756847)]
    """

    parameter: str
    values: np.ndarray
    orbits: tuple
    events: tuple
    status: str
    impacts: int
    periods: int
    _points: np.ndarray = field(repr=False, default=None)

    #: the orbits' fields at each point (:data:`POINT_FIELDS`): the tables' columns and what
    #: :meth:`plot` can draw (the drawing reads them here, below which it does not import)
    point_fields: ClassVar[Schema] = POINT_FIELDS

    def __len__(self) -> int:
        return int(self.values.size)

    def __repr__(self) -> str:
        """One line: the motion, the parameter's range, the points, the events, the status."""
        if len(self):
            span = f"{self.parameter} {self.values[0]:.6g} -> {self.values[-1]:.6g}"
        else:
            span = f"{self.parameter} (empty)"
        kinds: dict[str, int] = {}
        for e in self.events:
            kinds[str(e.kind)] = kinds.get(str(e.kind), 0) + 1
        ev = ", ".join(f"{n} {k}" if n > 1 else k for k, n in kinds.items()) or "none"
        return (f"Branch({self.impacts} per {self.periods}, {span}, {len(self)} points, "
                f"events: {ev}, status {str(self.status)!r})")

    def _repr_html_(self) -> str:
        """A short table for notebooks: the summary line and one row per event."""
        import html

        rows = "".join(
            f"<tr><td>{html.escape(str(e.kind))}</td><td>{e.value:.10g}</td><td>{e.index}</td>"
            f"<td>{'' if math.isnan(e.multiplier.real) else f'{e.multiplier:.6g}'}</td></tr>"
            for e in self.events)
        table = ("<table><thead><tr><th>event</th><th>" + html.escape(self.parameter)
                 + "</th><th>index</th><th>multiplier</th></tr></thead><tbody>" + rows
                 + "</tbody></table>") if self.events else ""
        return f"<p><code>{html.escape(repr(self))}</code></p>{table}"

    def _along(name, doc):  # noqa: N805 - a property of the orbits' field ``name`` along the branch
        return property(lambda self: POINT_FIELDS.stack(self.orbits, name), doc=doc)

    stable = _along("stable", "``(P,)`` bool: admissible with every ``|multiplier| < 1``.")
    admissible = _along("admissible", "``(P,)`` bool.")
    multipliers = _along("multipliers", "``(P, 2 N + 2)`` complex, by decreasing modulus.")
    phases = _along("phases", "``(P, m)`` load phases of the impacts (rad).")
    impact_times = _along("impact_times", "``(P, m)`` load times of the impacts.")
    impact_velocities = _along("impact_velocities", "``(P, m)`` velocities of the end before each impact.")
    max_abs_multiplier = _along("max_abs_multiplier",
                                "``(P,)`` spectral radius of the ``m``-fold impact map.")
    del _along

    def to_xarray(self):
        """The branch as an :class:`xarray.Dataset`; requires xarray.

        Returns
        -------
        xarray.Dataset
            Dims ``point`` (P), ``impact`` (m), ``multiplier`` (2 N + 2), ``event``; the parameter
            is a coordinate along ``point``; the orbits' fields of :data:`POINT_FIELDS` along
            ``point`` (``impact_time``, ``phase``, ``impact_velocity`` along ``impact`` too,
            ``multiplier_real``/``_imag`` along ``multiplier``; ``stable``, ``admissible``,
            ``admissibility``, ``clearance``, ``max_abs_multiplier``), and the events' fields
            (:attr:`BranchEvent.fields`, ``event_kind``, ``event_value``, ``event_index``,
            ``event_phase``, ``event_multiplier_real``/``_imag``) along ``event``; every variable
            with ``long_name`` and ``units``; attributes ``parameter``, ``impacts``, ``periods``,
            ``status``.
        """
        import xarray as xr

        P, m = len(self), self.impacts
        data = {}
        for dim, fields, objs, prefix in (("point", POINT_FIELDS, self.orbits, ""),
                                          ("event", BranchEvent.fields.select("branch"), self.events,
                                           "event_")):
            for f in fields:
                values = fields.stack(objs, f.name) if f.dtype != "U" else \
                    np.array([str(f.get(o)) for o in objs], dtype=str)
                dims = (dim,) if f.per is None else (dim, f.per)
                attrs = {"long_name": f.long_name, "units": f.units}
                name = prefix + f.item
                if f.dtype == "c16":
                    data[name + "_real"] = (dims, values.real, attrs)
                    data[name + "_imag"] = (dims, values.imag, attrs)
                else:
                    data[name] = (dims, values, attrs)
        return xr.Dataset(data, coords={self.parameter: ("point", self.values), "point": np.arange(P),
                                        "impact": np.arange(m)},
                          attrs={"parameter": self.parameter, "impacts": m, "periods": self.periods,
                                 "status": self.status})

    def to_dataframe(self):
        """The branch as a table; requires pandas.

        Returns
        -------
        pandas.DataFrame
            One row per point (index ``point``): the parameter, then the orbits' fields
            (:func:`orbit_columns`): ``impact_time_j``, ``phase_j``, ``impact_velocity_j`` for each
            impact ``j``, ``admissible``, ``admissibility``, ``clearance``, ``stable``,
            ``max_abs_multiplier``, and ``multiplier_k_real``, ``multiplier_k_imag`` for each
            multiplier ``k`` (by decreasing modulus).
        """
        import pandas as pd

        df = pd.DataFrame({self.parameter: self.values, **orbit_columns(self.orbits)})
        df.index.name = "point"
        return df

    def events_dataframe(self):
        """The events as a table; requires pandas.

        Returns
        -------
        pandas.DataFrame
            One row per event: the fields of :attr:`BranchEvent.fields` (``kind``, ``parameter``,
            ``value``, ``index``, ``multiplier`` as ``[re, im]``, ``phase``, ``impacts``,
            ``periods``).
        """
        import pandas as pd

        return pd.DataFrame([e.to_dict() for e in self.events], columns=list(BranchEvent.fields.names))

    def plot(self, ax=None, *, y: str = "phase", color=None, label=None, events=True):
        """Plot the branch: stable stretches solid, unstable or inadmissible dashed, events marked
        (:func:`impactbar.plotting.plot_branch`, with these keywords; it returns the axes). ``y``
        names what is plotted against the parameter (the phase, the default, separates the two
        sides of a fold)."""
        from ..plotting.continuation import plot_branch

        return plot_branch(self, ax, y=y, color=color, label=label, events=events)

    def orbit_at(self, value: float) -> MultiImpactOrbit:
        """The orbit where the branch first passes ``value`` (Newton at that parameter value, from
        the linear interpolation of the two branch points around it).

        Parameters
        ----------
        value : float
            A parameter value between two points of the branch.

        Returns
        -------
        MultiImpactOrbit

        Raises
        ------
        ValueError
            If the branch never passes ``value``.
        """
        value = check_real("value", value)
        v = self.values
        hit = np.flatnonzero((v[:-1] - value) * (v[1:] - value) <= 0.0)
        if hit.size == 0:
            raise ValueError(f"value must lie in the branch's range [{v.min()}, {v.max()}]; got {value}")
        i = int(hit[0])
        a, b = self.orbits[i], self.orbits[i + 1]
        w = 0.0 if v[i + 1] == v[i] else (value - v[i]) / (v[i + 1] - v[i])
        times = (1 - w) * a.impact_times + w * b.impact_times
        states = (1 - w) * a.states_after_impact + w * b.states_after_impact
        model, load = with_parameter(a.model, a.load, self.parameter, value)
        return find_orbit(model, load, a.impacts, a.periods, guess=(times, states))
