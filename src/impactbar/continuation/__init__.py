"""Continuation of periodic impacting motions: branches in one parameter, their folds, period doublings
(with branch switching), Neimark-Sacker points, grazing and losses of admissibility.

Layout: ``parameters`` (which model and load fields can vary), ``engine`` (the one pseudo-arclength
engine and its :class:`ContinuationSettings`), ``one_parameter`` (:func:`continue_orbit`: the segment problem
of :func:`impactbar.find_orbit` on the engine, event detection and location), ``cascade``
(:func:`doubling_cascade`: a branch and its successive doubled branches), ``branch``
(:class:`Branch`, :class:`BranchEvent`; their pandas, xarray and matplotlib views import those
libraries only when called), ``diagram`` (the brute-force bifurcation diagram from
:func:`impactbar.simulate`, to overlay on branches), ``two_parameter``
(:func:`continue_bifurcation`: folds, period doublings and grazing points followed in two
parameters, an augmented problem on the same engine). Imports the core (``orbits``, ``simulation``)
and numpy/scipy."""

from .branch import Branch as Branch
from .branch import BranchEvent as BranchEvent
from .cascade import DoublingCascade as DoublingCascade
from .cascade import doubling_cascade as doubling_cascade
from .diagram import simulated_diagram as simulated_diagram
from .engine import ContinuationSettings as ContinuationSettings
from .one_parameter import EVENT_KINDS as EVENT_KINDS
from .one_parameter import continue_orbit as continue_orbit
from .parameters import PARAMETERS as PARAMETERS
from .parameters import parameter_value as parameter_value
from .parameters import with_parameter as with_parameter
from .two_parameter import BifurcationCurve as BifurcationCurve
from .two_parameter import continue_bifurcation as continue_bifurcation

__all__ = ["Branch", "BranchEvent", "EVENT_KINDS", "continue_orbit", "simulated_diagram", "PARAMETERS",
           "parameter_value", "with_parameter", "BifurcationCurve", "continue_bifurcation",
           "ContinuationSettings", "DoublingCascade", "doubling_cascade"]
