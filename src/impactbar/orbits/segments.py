"""The orbit solver's segment problem as the continuation uses it: the interface between Newton's
method on the ``m``-segment boundary-value problem (theory §5, §7; :mod:`impactbar.orbits.multi_impact`
and its private helpers) and :mod:`impactbar.continuation`, which follows its solutions as a
parameter changes. The continuation imports these names from here; the modules behind them may
change.

- :class:`SegmentProblem`: the problem for one model, load, ``m`` impacts and ``n`` load periods
  (unknowns ``u = (t_1, x_1, ..., t_m, x_m)``; ``evaluate``, ``newton``, ``scale``, ``split``);
- :func:`unknowns_from`: its unknowns from impact times, shape ``(m,)``, and full post-impact
  states, shape ``(m, 2 N + 2)``;
- :func:`normalise`: a solution's impact times shifted so that the first lies in ``[0, 2 pi)``
  (``None`` where they do not increase or a flight is shorter than the contact window);
- :func:`build_orbit`: the :class:`~impactbar.PeriodicOrbit` at a converged solution (multipliers,
  the law's record of each contact, admissibility);
- :func:`halves_gap`, :func:`same_orbit`: on a doubled problem (``2 m`` impacts in ``2 n``
  periods), the largest difference between the two halves of the unknowns, and whether a solution
  is the undoubled orbit traversed twice;
- :func:`doubling_direction`: the direction of the period-2 branch at a period doubling.
"""

from ._assemble import _build as build_orbit
from ._newton import _halves_gap as halves_gap
from ._newton import _normalise as normalise
from ._newton import _same_orbit as same_orbit
from .multi_impact import _Segments as SegmentProblem
from .multi_impact import _unknowns_from as unknowns_from
from .multi_impact import doubling_direction as doubling_direction

__all__ = ["SegmentProblem", "unknowns_from", "normalise", "build_orbit", "halves_gap", "same_orbit",
           "doubling_direction"]
