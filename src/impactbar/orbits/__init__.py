"""Periodic impacting motions and their stability (paper Sections 2 and 3).

Layout: ``phase`` (the phase equation, eq. 14, and its roots), ``admissibility`` (does the struck end
stay off the stop between impacts), ``stability`` (the exact Jacobian of the impact map with its
saltation term, the Floquet multipliers by a dense or a structured O(N^2) eigenvalue method, and the
paper's Schur blocks, eqs. 25-32), ``rigid`` (the rigid bar in closed form, vectorised over
parameter arrays), ``wave`` (the phase equation, periodic states and impact-map Jacobian under the
wave impact law, theory §4b), ``one_impact`` (:class:`PeriodicOrbit`, :func:`periodic_orbits`),
``multi_impact`` (:class:`MultiImpactOrbit`, :func:`find_orbit`: ``m`` impacts in ``n`` load
periods by Newton on the segment problem, one segment per flight), ``charts`` (existence, stability
and admissibility edges, Figs. 5, 6, 8).
Part of the core: imports only ``impactbar.model``, ``impactbar.loads``, ``impactbar.dynamics``,
numpy and scipy.
"""

from .multi_impact import MultiImpactOrbit as MultiImpactOrbit
from .multi_impact import find_orbit as find_orbit
from .multi_impact import impact_law as impact_law
from .one_impact import OrbitList as OrbitList
from .one_impact import PeriodicOrbit as PeriodicOrbit
from .one_impact import orbit_multipliers as orbit_multipliers
from .one_impact import periodic_orbits as periodic_orbits
from .phase import phase_G as phase_G
from .phase import phase_residual as phase_residual
from .phase import phase_roots as phase_roots
from .rigid import RigidOrbits as RigidOrbits
from .rigid import rigid_cosine_orbits as rigid_cosine_orbits
from .rigid import rigid_square_orbits as rigid_square_orbits
from .stability import floquet_multipliers as floquet_multipliers
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
    "floquet_multipliers",
    "RigidOrbits",
    "rigid_cosine_orbits",
    "rigid_square_orbits",
    "MultiImpactOrbit",
    "find_orbit",
    "impact_law",
]
