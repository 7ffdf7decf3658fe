"""The verdicts and statuses the library reports, as string-valued enums whose members carry their
meaning (as diffrax's ``RESULTS``): admissibility verdicts of orbits (theory §5), why a simulation
run stopped, why a continuation stopped, the kinds of events located on a branch and of the
two-parameter curves.

Each enum is a :class:`enum.StrEnum`: a member *is* its string (``Admissibility.ADMISSIBLE ==
"admissible"``, ``str()``, ``format()``, ``json.dumps`` and pandas give the plain value), so
results compare, print and serialise as the strings they replace (``repr`` too); ``member.message``
explains it.
Imports only the standard library (every layer may import it).
"""

from __future__ import annotations

import enum

__all__ = ["Admissibility", "RunStatus", "BranchStatus", "EventKind", "CurveKind"]


class _Explained(enum.StrEnum):
    """A string enum whose members are ``(value, message)``."""

    def __new__(cls, value: str, message: str):
        member = str.__new__(cls, value)
        member._value_ = value
        member.message = message
        return member

    def __repr__(self) -> str:  # as the string it stands for (doctests, printed lists, JSON)
        return repr(self._value_)


class Admissibility(_Explained):
    """Whether a periodic motion is physical (theory §5), and if not, why (the first reason met, in
    the order of :attr:`rank`).

    Attributes
    ----------
    message : str
        One sentence explaining the verdict.

    Examples
    --------
    >>> from impactbar import Admissibility
    >>> Admissibility("sticks") == "sticks"  # a member is its string
    True
    >>> Admissibility.STICKS.message.split(":")[0]
    'the end does not leave the stop after the impact'
    """

    PENETRATES = ("penetrates", "the struck end swings through the stop between impacts "
                  "(u(1, t) > 0 at some t inside a flight)")
    BACKWARD_IMPACT = ("backward impact", "the end reaches the stop moving away from it, u_t(1, t-) < 0")
    GRAZING = ("grazing", "the end touches the stop with zero velocity, between impacts or at the "
               "impact itself (the boundary of admissibility)")
    STICKS = ("sticks", "the end does not leave the stop after the impact: with R = 0 the load "
              "presses it on the stop; under the wave law it still moves into the rod when the "
              "contact window ends")
    SEPARATES = ("separates", "under the wave law, contact with the rod is lost inside the contact "
                 "window, so the orbit's contact map does not hold")
    ADMISSIBLE = ("admissible", "the end stays off the stop between impacts, leaves it after each "
                  "impact and arrives moving forward: a physical motion")
    UNCHECKED = ("unchecked", "not decided: a continuation's intermediate point, not checked")

    @property
    def rank(self) -> int:
        """Order in which reasons are reported when several flights of a motion fail (smaller
        first; ``admissible`` last)."""
        return list(type(self)).index(self)


class RunStatus(_Explained):
    """Why a simulation run (:func:`impactbar.simulate`) stopped.

    Examples
    --------
    >>> from impactbar import RunStatus
    >>> RunStatus.T_END, RunStatus.T_END.message
    ('t_end', 'the run reached its end time t_end')
    """

    T_END = ("t_end", "the run reached its end time t_end")
    MAX_IMPACTS = ("max_impacts", "the run recorded its largest number of impacts, max_impacts, "
                   "before t_end")


class EventKind(_Explained):
    """The kinds of special points located on a branch of periodic motions (theory §7), in the
    order they are reported.

    Examples
    --------
    >>> from impactbar import EventKind
    >>> EventKind("fold").message
    'a multiplier goes through +1 where the branch turns back in the parameter'
    """

    FOLD = ("fold", "a multiplier goes through +1 where the branch turns back in the parameter")
    BRANCH_POINT = ("branch-point", "a multiplier goes through +1 without a turn of the branch")
    PERIOD_DOUBLING = ("period-doubling", "a multiplier goes through -1: a branch with twice the "
                       "impacts and periods is born there")
    NEIMARK_SACKER = ("neimark-sacker", "a complex pair of multipliers crosses the unit circle")
    GRAZING = ("grazing", "the end touches the stop between impacts, or an impact velocity goes "
               "through zero")
    ADMISSIBILITY = ("admissibility", "another change of admissibility, e.g. sticking at R = 0")
    LOAD_JUMP = ("load-jump", "an impact runs into a jump of a piecewise-constant load, where the "
                 "branch has a corner (e.g. the hydraulic existence edge, Fig. 8)")
    BORDER_COLLISION = ("border-collision", "a drive's state touches one of its switching surfaces "
                        "during the period (the oil circuit's supply pressure at the accumulator's "
                        "pre-charge or the relief pressure): the return map changes its formula there "
                        "and the multipliers jump")


class CurveKind(_Explained):
    """The kinds of events a two-parameter curve follows (:func:`continue_bifurcation`).

    Examples
    --------
    >>> from impactbar import CurveKind
    >>> [str(k) for k in CurveKind]
    ['fold', 'period-doubling', 'grazing']
    """

    FOLD = ("fold", "a curve of folds: a multiplier stays at +1")
    PERIOD_DOUBLING = ("period-doubling", "a curve of period doublings: a multiplier stays at -1")
    GRAZING = ("grazing", "a curve of grazing orbits: the clearance stays zero")


def _stopped_at(kind: EventKind) -> tuple[str, str]:
    return f"stopped at {kind.value}", f"the continuation stopped at a {kind.value} event (stop_on)"


class BranchStatus(_Explained):
    """Why a continuation (:func:`continue_orbit`, :func:`continue_bifurcation`) stopped.

    Examples
    --------
    >>> from impactbar import BranchStatus
    >>> status = BranchStatus("reached")  # a string, with its message
    >>> status == "reached", status.message
    (True, 'the parameter reached its target value')
    """

    REACHED = ("reached", "the parameter reached its target value")
    MAX_POINTS = ("max_points", "the curve has its largest number of points, max_points")
    STEP_TOO_SMALL = ("step too small", "the corrector failed down to the smallest step, min_step")
    PARAMETER_RANGE = ("parameter range", "the parameter left the range where the model and load "
                       "are defined")
    TURNED_BACK = ("turned back", "the curve left the range between its start and the target, "
                   "after a fold")
    LOAD_JUMP = ("impact at a load jump", "an impact ran into a jump of a piecewise-constant load: "
                 "the branch has a corner there (a load-jump event is located at it) and cannot be "
                 "continued smoothly")
    STOPPED_AT_FOLD = _stopped_at(EventKind.FOLD)
    STOPPED_AT_BRANCH_POINT = _stopped_at(EventKind.BRANCH_POINT)
    STOPPED_AT_PERIOD_DOUBLING = _stopped_at(EventKind.PERIOD_DOUBLING)
    STOPPED_AT_NEIMARK_SACKER = _stopped_at(EventKind.NEIMARK_SACKER)
    STOPPED_AT_GRAZING = _stopped_at(EventKind.GRAZING)
    STOPPED_AT_ADMISSIBILITY = _stopped_at(EventKind.ADMISSIBILITY)
    STOPPED_AT_LOAD_JUMP = _stopped_at(EventKind.LOAD_JUMP)
    STOPPED_AT_BORDER_COLLISION = _stopped_at(EventKind.BORDER_COLLISION)

    @classmethod
    def stopped_at(cls, kind: str) -> BranchStatus:
        """The status of a continuation stopped at an event of this kind."""
        return cls(f"stopped at {EventKind(kind).value}")
