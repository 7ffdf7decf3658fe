"""Periodic impacting motions and their stability (paper Sections 2 and 3).

Layout: ``phase`` (the phase equation, eq. 14, and its roots: the paper law's, with the solvers'
check of their inputs), ``admissibility`` (does the struck end stay off the stop between impacts),
``stability`` (the verdict and the paper's Schur blocks, eqs. 25-32, for every one-impact orbit),
``rigid`` (the rigid bar in closed form, vectorised over parameter arrays), ``orbit``
(:class:`PeriodicOrbit`, the one result type: ``m`` impacts in ``n`` load periods;
``MultiImpactOrbit`` is another name for it), ``one_impact`` (the one-impact orbits from the law's
phase equation), ``multi_impact`` (the segment problem of ``m`` impacts in ``n`` load periods, one segment
per flight, whose parts the continuation uses through ``segments``), ``find`` (:func:`find_orbit`:
Newton on that problem from a guess; and :func:`periodic_orbits`, the one-impact orbits
under every law: from the phase equation, or by Newton's method from guesses for a law without one,
:func:`periodic_orbits_by_newton`), ``charts`` (existence, stability
and admissibility edges, Figs. 5, 6, 8), ``driven`` (orbits with an unknown period under a
drive, theory §10; the problem of each built-in drive from its table ``ORBIT_PROBLEMS``),
``shooting`` (the generic problem of a drive's orbits, by multiple shooting), ``valve_segment`` and
``valve_search`` (the valve's segment problem with the exact Jacobian and its certified search of
every one-impact orbit; the admissibility of its flights in ``valve_admissibility``).

Each law's own numerics (its phase equation, the states of its orbits, the exact Jacobian of its
impact map and its Floquet multipliers) are in :mod:`impactbar.laws`; the solvers here reach them
through ``model.law`` and build the results. Part of the core: imports only ``impactbar.laws``,
``impactbar.model``, ``impactbar.loads``, ``impactbar.drives``, ``impactbar.dynamics``, the simulator
(``impactbar.simulation``, whose runs are guesses), numpy and scipy.
"""

import importlib
import sys

from .._shared.renamed import renamed

#: where each public name lives (PEP 562: a submodule is imported on first use, so the rigid closed
#: forms, e.g. a sweep's chunks, do not load the wave law's scipy.optimize and numba)
_HOME = {
    "MultiImpactOrbit": "orbit", "find_orbit": "find", "impact_law": "multi_impact",
    "OrbitList": "one_impact", "PeriodicOrbit": "orbit", "orbit_multipliers": "one_impact",
    "periodic_orbits": "find",
    "phase_G": "phase", "phase_residual": "phase", "phase_roots": "phase",
    "RigidOrbits": "rigid", "rigid_cosine_orbits": "rigid", "rigid_square_orbits": "rigid",
    "floquet_multipliers": "stability", "impact_map_jacobian": "stability",
    "DrivenOrbit": "driven", "find_driven_orbit": "driven_search", "drive_orbits": "driven_search",
    "periodic_orbits_by_newton": "find", "rock_periodic_orbits": "find",
}

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
    "DrivenOrbit",
    "find_driven_orbit",
    "drive_orbits",
    "periodic_orbits_by_newton",
    "rock_periodic_orbits",
]


def __getattr__(name: str):
    if name in _HOME:
        value = getattr(importlib.import_module(f".{_HOME[name]}", __name__), name)
        globals()[name] = value
        return value
    if (value := renamed(sys.modules[__name__], name)) is not None:
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
