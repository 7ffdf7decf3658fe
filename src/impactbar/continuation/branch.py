"""Results of a continuation: :class:`Branch` and its :class:`BranchEvent` s (theory §4-§7).

numpy only at import; pandas, xarray and matplotlib are imported inside ``to_dataframe``,
``to_xarray`` and ``plot``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._shared.validate import check_real
from ..orbits.multi_impact import MultiImpactOrbit, find_orbit
from .parameters import with_parameter

__all__ = ["Branch", "BranchEvent"]

TWO_PI = 2.0 * math.pi

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
        during the period: :meth:`~impactbar.Drive.border_tests`; which one in ``surface``).
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

    def to_dict(self) -> dict:
        """A JSON-ready summary."""
        out = {"kind": self.kind, "parameter": self.parameter, "value": self.value,
               "index": self.index, "multiplier": [self.multiplier.real, self.multiplier.imag],
               "phase": self.orbit.phase, "impacts": self.orbit.impacts,
               "periods": self.orbit.periods}
        if self.surface:
            out["surface"] = self.surface
        return out


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

    @property
    def stable(self) -> np.ndarray:
        """``(P,)`` bool: admissible with every ``|multiplier| < 1``."""
        return np.array([o.stable for o in self.orbits], dtype=bool)

    @property
    def admissible(self) -> np.ndarray:
        """``(P,)`` bool."""
        return np.array([o.admissible for o in self.orbits], dtype=bool)

    @property
    def multipliers(self) -> np.ndarray:
        """``(P, 2 N + 2)`` complex, by decreasing modulus."""
        return np.array([o.multipliers for o in self.orbits])

    @property
    def phases(self) -> np.ndarray:
        """``(P, m)`` load phases of the impacts (rad)."""
        return np.array([o.phases for o in self.orbits])

    @property
    def impact_times(self) -> np.ndarray:
        """``(P, m)`` load times of the impacts."""
        return np.array([o.impact_times for o in self.orbits])

    @property
    def impact_velocities(self) -> np.ndarray:
        """``(P, m)`` velocities of the end before each impact."""
        return np.array([o.impact_velocities for o in self.orbits])

    @property
    def max_abs_multiplier(self) -> np.ndarray:
        """``(P,)`` spectral radius of the ``m``-fold impact map."""
        return np.array([o.max_abs_multiplier for o in self.orbits])

    def to_xarray(self):
        """The branch as an :class:`xarray.Dataset`; requires xarray.

        Returns
        -------
        xarray.Dataset
            Dims ``point`` (P), ``impact`` (m), ``multiplier`` (2 N + 2), ``event``; the parameter
            is a coordinate along ``point``; ``impact_time``, ``phase``, ``impact_velocity``
            (point, impact), ``multiplier_real``/``_imag`` (point, multiplier), ``stable``,
            ``admissible``, ``admissibility``, ``clearance``, ``max_abs_multiplier`` (point), and
            ``event_kind``, ``event_value``, ``event_index``, ``event_phase``,
            ``event_multiplier_real``/``_imag`` (event); attributes ``parameter``, ``impacts``,
            ``periods``, ``status``.
        """
        import xarray as xr

        P, m = len(self), self.impacts
        mu = self.multipliers
        ev = self.events
        ds = xr.Dataset(
            {
                "impact_time": (("point", "impact"), self.impact_times),
                "phase": (("point", "impact"), self.phases),
                "impact_velocity": (("point", "impact"), self.impact_velocities),
                "multiplier_real": (("point", "multiplier"), mu.real),
                "multiplier_imag": (("point", "multiplier"), mu.imag),
                "max_abs_multiplier": ("point", self.max_abs_multiplier),
                "stable": ("point", self.stable),
                "admissible": ("point", self.admissible),
                "admissibility": ("point", np.array([o.admissibility for o in self.orbits], dtype=str)),
                "clearance": ("point", np.array([o.clearance for o in self.orbits])),
                "event_kind": ("event", np.array([e.kind for e in ev], dtype=str)),
                "event_value": ("event", np.array([e.value for e in ev], dtype=float)),
                "event_index": ("event", np.array([e.index for e in ev], dtype=int)),
                "event_phase": ("event", np.array([e.orbit.phase for e in ev], dtype=float)),
                "event_multiplier_real": ("event", np.array([e.multiplier.real for e in ev])),
                "event_multiplier_imag": ("event", np.array([e.multiplier.imag for e in ev])),
            },
            coords={self.parameter: ("point", self.values), "point": np.arange(P),
                    "impact": np.arange(m)},
            attrs={"parameter": self.parameter, "impacts": m, "periods": self.periods,
                   "status": self.status},
        )
        return ds

    def to_dataframe(self):
        """The branch as a table; requires pandas.

        Returns
        -------
        pandas.DataFrame
            One row per point (index ``point``): the parameter, ``phase_j``, ``impact_time_j``,
            ``impact_velocity_j`` for each impact ``j``, ``stable``, ``admissible``,
            ``admissibility``, ``clearance``, ``max_abs_multiplier``, and ``multiplier_k_real``,
            ``multiplier_k_imag`` for each multiplier ``k`` (by decreasing modulus).
        """
        import pandas as pd

        data = {self.parameter: self.values}
        for j in range(self.impacts):
            data[f"phase_{j}"] = self.phases[:, j]
            data[f"impact_time_{j}"] = self.impact_times[:, j]
            data[f"impact_velocity_{j}"] = self.impact_velocities[:, j]
        data["stable"] = self.stable
        data["admissible"] = self.admissible
        data["admissibility"] = [o.admissibility for o in self.orbits]
        data["clearance"] = [o.clearance for o in self.orbits]
        data["max_abs_multiplier"] = self.max_abs_multiplier
        mu = self.multipliers
        for k in range(mu.shape[1]):
            data[f"multiplier_{k}_real"] = mu[:, k].real
            data[f"multiplier_{k}_imag"] = mu[:, k].imag
        df = pd.DataFrame(data)
        df.index.name = "point"
        return df

    def events_dataframe(self):
        """The events as a table; requires pandas.

        Returns
        -------
        pandas.DataFrame
            One row per event: ``kind``, ``parameter``, ``value``, ``index``, ``multiplier``
            (``[re, im]``), ``phase``, ``impacts``, ``periods``.
        """
        import pandas as pd

        return pd.DataFrame([e.to_dict() for e in self.events],
                            columns=["kind", "parameter", "value", "index", "multiplier", "phase",
                                     "impacts", "periods"])

    def plot(self, ax=None, *, y: str = "phase", color=None, label=None, events=True):
        """Plot the branch: stable stretches solid, unstable or inadmissible dashed, events marked.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Drawn on a new figure's axes if omitted.
        y : {"phase", "impact_velocity", "max_abs_multiplier"}
            What to plot against the parameter; per-impact quantities give one curve per impact
            (phases unwrapped along the branch, so a curve does not jump at ``2 pi``). The default,
            the phase, separates the two sides of a fold; the impact velocity is ``2 pi p0/(1 + R)``
            on every one-impact orbit (theory §4).
        color, label : optional
            Line colour and legend label.
        events : bool
            Mark and name the events.

        Returns
        -------
        matplotlib.axes.Axes
        """
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
