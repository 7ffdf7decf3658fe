"""Motion from any start (paper Section 5): the exact event-driven simulator and the random-start
experiments.

Layout: ``simulate`` (:func:`simulate`, :class:`InitialState`; one driver for every impact law:
chatter, sticking on the fixed-free basis, release, the law's contact step), ``trajectory``
(:class:`Trajectory`, :class:`EnergyAccount`: the logged pieces of motion), ``experiments``
(random starts, classification of the long-run motion, the paper's pneumatic and hydraulic
experiments), ``driven`` (the event loop under a drive, theory §10), ``driven_trajectory``
(its result).
Part of the core: imports ``impactbar.model``, ``impactbar.loads``, ``impactbar.drives``,
``impactbar.dynamics``, ``impactbar.laws`` through ``model.law``; never matplotlib
(``Trajectory.plot`` calls :mod:`impactbar.plotting`, imported on that call).
"""

import sys

from .._shared.renamed import renamed
from .driven_trajectory import DrivenTrajectory as DrivenTrajectory
from .simulate import EnergyAccount as EnergyAccount
from .simulate import InitialState as InitialState
from .simulate import SimulationInterrupted as SimulationInterrupted
from .simulate import Trajectory as Trajectory
from .simulate import simulate as simulate

__all__ = ["EnergyAccount", "InitialState", "Trajectory", "simulate", "DrivenTrajectory",
           "SimulationInterrupted"]


def __getattr__(name: str):
    if (value := renamed(sys.modules[__name__], name)) is not None:
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
