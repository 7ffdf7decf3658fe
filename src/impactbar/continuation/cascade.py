"""The period-doubling cascade: a branch, the doubled branch born at its first period doubling, the
branch doubled again, ... (theory §7), each by branch switching (:func:`continue_orbit` started at
a ``"period-doubling"`` :class:`BranchEvent`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._shared.status import EventKind
from .._shared.validate import check_int
from .branch import Branch, BranchEvent
from .engine import ContinuationSettings
from .one_parameter import continue_orbit

__all__ = ["DoublingCascade", "doubling_cascade"]


@dataclass(frozen=True, eq=False)
class DoublingCascade:
    """The branches of a period-doubling cascade and its located doublings.

    Attributes
    ----------
    branches : tuple of Branch
        The start's branch (``m`` impacts in ``n`` periods), then the branch with ``2 m`` impacts in
        ``2 n`` periods born at its first period doubling, and so on.
    doublings : tuple of BranchEvent
        The first period doubling located on each branch, in order (one fewer than the branches
        when the last branch has none): branch ``k + 1`` starts at ``doublings[k]``.
    """

    branches: tuple[Branch, ...]
    doublings: tuple[BranchEvent, ...] = field(repr=False)

    @property
    def values(self) -> np.ndarray:
        """The parameter at each doubling, shape ``(len(doublings),)``."""
        return np.array([e.value for e in self.doublings])

    @property
    def gap_ratios(self) -> np.ndarray:
        """Ratios of successive gaps between the doublings, ``(v_k - v_{k+1}) / (v_{k+1} -
        v_{k+2})``, shape ``(len(doublings) - 2,)`` (or empty): they tend to Feigenbaum's
        ``4.6692...`` along a cascade of a one-humped map."""
        gaps = np.diff(self.values)
        return gaps[:-1] / gaps[1:]


def doubling_cascade(orbit, parameter: str, to: float, *, doublings: int = 1,
                     settings: ContinuationSettings | None = None, step: float | None = None,
                     max_step: float | None = None, min_step: float | None = None,
                     max_points: int | None = None, tol: float | None = None, xtol: float = 1e-10,
                     stop_on=()) -> DoublingCascade:
    """Follow a branch and the branches born at its successive period doublings (theory §7).

    The start's branch is continued towards ``to`` (:func:`continue_orbit`); at its first located
    period doubling (a multiplier through ``-1``) the doubled branch (twice the impacts and periods)
    is started by branch switching and continued towards ``to`` in turn; and so on, ``doublings``
    times or until a branch has no period doubling.

    Parameters
    ----------
    orbit : PeriodicOrbit or BranchEvent
        The start, as for :func:`continue_orbit`.
    parameter : str
        The continuation parameter (one of :data:`PARAMETERS`).
    to : float
        Target value of every branch.
    doublings : int
        How many period doublings to follow onto the doubled branches (``>= 0``); the cascade has
        at most ``doublings + 1`` branches. Default 1.
    settings, step, max_step, min_step, max_points, tol, xtol, stop_on : optional
        As for :func:`continue_orbit`, for every branch. ``stop_on=("period-doubling",)`` stops
        each branch at its first doubling: the cascade's doublings at the least cost.

    Returns
    -------
    DoublingCascade

    Raises
    ------
    ValueError
        For a bad argument (named), as :func:`continue_orbit`.

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, periodic_orbits
    >>> from impactbar.continuation import doubling_cascade
    >>> start = periodic_orbits(BarModel(s=3, d=0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))[1]
    >>> c = doubling_cascade(start, "p0", to=0.5, doublings=5, stop_on=("period-doubling",))
    >>> [b.impacts for b in c.branches], [round(float(v), 6) for v in c.values[:3]]
    ([1, 2, 4, 8, 16, 32], [0.756847, 0.685946, 0.673695])
    >>> [round(float(r), 3) for r in c.gap_ratios]  # Feigenbaum's 4.669
    [5.787, 4.839, 4.67, 4.668]
    """
    doublings = check_int("doublings", doublings, lo=0)
    kw = {"settings": settings, "step": step, "max_step": max_step, "min_step": min_step,
          "max_points": max_points, "tol": tol, "xtol": xtol, "stop_on": stop_on}
    branches = [continue_orbit(orbit, parameter, to, **kw)]
    found = []
    while True:
        pd = next((e for e in branches[-1].events if e.kind == EventKind.PERIOD_DOUBLING), None)
        if pd is None:
            break
        found.append(pd)
        if len(branches) > doublings:
            break
        branches.append(continue_orbit(pd, parameter, to, **kw))
    return DoublingCascade(branches=tuple(branches), doublings=tuple(found))
