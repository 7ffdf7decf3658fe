"""A drifter's operating point followed in one parameter of its oil circuit, in SI (theory §11):
the branch of :func:`~impactbar.continue_orbit` read through the drifter's scales."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .circuit import CircuitDrifter, CircuitDrifterOrbit
from .display_units import format_si

__all__ = ["CircuitBranch", "continue_circuit"]


def continue_circuit(drifter: CircuitDrifter, parameter: str, to, *, step=None, max_step=None,
                     max_points: int = 2000) -> CircuitBranch:
    """The drifter's operating point (:meth:`CircuitDrifter.orbit`) followed in one parameter of
    its circuit, with its folds, period doublings, Neimark-Sacker points and border collisions (the
    accumulator emptying, the relief valve opening, and a drill's parts': a check valve starting to
    crack open, a cushion's kink passed, a spool reaching a stop or not) located
    (:func:`~impactbar.continue_orbit`, theory §5 and §11).

    Parameters
    ----------
    drifter : CircuitDrifter
    parameter : str
        A dotted SI name of the parameter tree (``"accumulator.precharge"``,
        ``"stop.restitution"``; :data:`~impactbar.physical.tree.FIELDS`, refused with its declared
        reason where it cannot be continued; a part's ``"parts.<name>.<field>"``), ``to`` then a
        quantity with its unit (``"12 MPa"``), or a dimensionless name of the problem
        (``"precharge"``, pressures in 10 MPa), ``to`` then a number.
    to : str, pint.Quantity or float
        The value to reach.
    step, max_step : float, optional
        The first and the largest arclength step (dimensionless; default: the continuation's).
    max_points : int
        Most points on the branch.

    Returns
    -------
    CircuitBranch

    Raises
    ------
    ValueError
        An unknown parameter, ``to`` without its unit for a config key (or with one for a
        dimensionless name); as :func:`~impactbar.continue_orbit`.
    """
    from ..continuation import continue_orbit

    if not isinstance(drifter, CircuitDrifter):
        raise ValueError(f"drifter must be a CircuitDrifter; got {type(drifter).__name__}")
    if drifter.key_field(parameter) is not None:  # (the tree's key, or a part's)
        name, value = drifter.to_dimensionless(parameter, to)
        unit = drifter.key_field(parameter).unit
    else:
        if isinstance(to, str) or hasattr(to, "magnitude"):
            raise ValueError(f"to must be a number for the dimensionless parameter {parameter}; got {to!r} "
                             "(a config key such as accumulator.precharge takes a unit)")
        name, value, unit = parameter, float(to), ""
    start = drifter.orbit().orbit
    b = continue_orbit(start, name, value, step=step, max_step=max_step, max_points=max_points)
    return CircuitBranch(drifter=drifter, parameter=parameter, unit=unit, branch=b)


@dataclass(frozen=True, repr=False)
class CircuitBranch:
    """A drifter's operating point followed in one circuit parameter, in SI (theory §11).

    Attributes
    ----------
    drifter : CircuitDrifter
        The drifter at the branch's start (its scales convert every point).
    parameter : str
        The config key (``"accumulator.precharge"``) or the dimensionless name.
    unit : str
        The parameter's SI unit (``""`` for a dimensionless name).
    branch : Branch
        The dimensionless branch (:func:`~impactbar.continue_orbit`).
    """

    drifter: CircuitDrifter
    parameter: str
    unit: str
    branch: object

    def __repr__(self) -> str:
        v = self.values
        return (f"CircuitBranch({self.parameter} from {format_si(v[0], self.unit)} to "
                f"{format_si(v[-1], self.unit)}, "
                f"{len(v)} points, {len(self.events)} events, {self.branch.status})")

    def __len__(self) -> int:
        return len(self.branch.values)

    def _si(self, x: float) -> float:
        return self.drifter.from_dimensionless(self.parameter, x) \
            if self.drifter.key_field(self.parameter) is not None else float(x)

    @cached_property
    def points(self) -> tuple:
        """Every point's operating point (:class:`CircuitDrifterOrbit`)."""
        return tuple(CircuitDrifterOrbit(self.drifter, o) for o in self.branch.orbits)

    @property
    def values(self) -> np.ndarray:
        """The parameter at each point, shape ``(n,)``, in :attr:`unit`."""
        return np.array([self._si(x) for x in self.branch.values])

    @property
    def blow_frequency_Hz(self) -> np.ndarray:
        """Blows per second at each point, shape ``(n,)``."""
        return np.array([p.blow_frequency_Hz for p in self.points])

    @property
    def impact_energy_J(self) -> np.ndarray:
        """The piston's kinetic energy at impact (J) at each point, shape ``(n,)``."""
        return np.array([p.impact_energy_J for p in self.points])

    @property
    def max_abs_multiplier(self) -> np.ndarray:
        """The largest Floquet multiplier's modulus at each point, shape ``(n,)``."""
        return np.array([float(np.max(np.abs(p.multipliers))) if p.multipliers.size else 0.0
                         for p in self.points])

    @property
    def stable(self) -> np.ndarray:
        """Whether each point is stable (admissible, every multiplier inside the unit circle)."""
        return np.array([p.stable for p in self.points], dtype=bool)

    @property
    def events(self) -> list:
        """The located events as dicts: ``kind`` (fold, period doubling, Neimark-Sacker, border
        collision with its surface, ...) and ``value`` (the parameter, in :attr:`unit`)."""
        return [{"kind": e.kind + (f" {e.surface}" if e.surface else ""), "value": self._si(e.value)}
                for e in self.branch.events]

    def plot(self, axes=None):
        """The bifurcation diagram in SI (:func:`impactbar.plotting.circuit.plot_circuit_branch`).

        Returns
        -------
        numpy.ndarray of matplotlib.axes.Axes, shape (2,)
        """
        from ..plotting.circuit import plot_circuit_branch

        return plot_circuit_branch(self, axes=axes)
