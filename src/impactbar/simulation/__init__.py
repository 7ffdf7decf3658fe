"""Motion from any start (paper Section 5): the exact event-driven simulator and the random-start
experiments.

Layout: ``simulate`` (:func:`simulate`, :class:`InitialState`, :class:`Trajectory`,
:class:`EnergyAccount`; chatter, sticking on the fixed-free basis, release), ``experiments``
(random starts, classification of the long-run motion, the paper's pneumatic and hydraulic
experiments). Part of the core: imports ``impactbar.model``, ``impactbar.loads``,
``impactbar.dynamics``; matplotlib only lazily, inside the plotting helper of ``experiments``.
"""

from .simulate import EnergyAccount as EnergyAccount
from .simulate import InitialState as InitialState
from .simulate import Trajectory as Trajectory
from .simulate import simulate as simulate

__all__ = ["EnergyAccount", "InitialState", "Trajectory", "simulate"]
