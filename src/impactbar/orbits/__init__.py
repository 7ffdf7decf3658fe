"""Periodic impacting motions and their stability (paper Sections 2 and 3).

Layout: ``phase`` (the phase equation, eq. 14, and its roots), ``admissibility`` (does the struck end
stay off the stop between impacts), ``stability`` (the exact Jacobian of the impact map with its
saltation term, and the paper's Schur blocks, eqs. 25-32), ``one_impact`` (:class:`PeriodicOrbit`,
:func:`periodic_orbits`), ``charts`` (existence, stability and admissibility edges, Figs. 5, 6, 8).
Part of the core: imports only ``impactbar.model``, ``impactbar.loads``, ``impactbar.dynamics``,
numpy and scipy.
"""

from .one_impact import OrbitList as OrbitList
from .one_impact import PeriodicOrbit as PeriodicOrbit
from .one_impact import orbit_multipliers as orbit_multipliers
from .one_impact import periodic_orbits as periodic_orbits
from .phase import phase_G as phase_G
from .phase import phase_residual as phase_residual
from .phase import phase_roots as phase_roots
from .stability import impact_map_jacobian as impact_map_jacobian

__all__ = [
    "PeriodicOrbit",
    "OrbitList",
    "periodic_orbits",
    "orbit_multipliers",
    "phase_G",
    "phase_residual",
    "phase_roots",
    "impact_map_jacobian",
]
