"""The valve's compiled closed forms that the orbit solvers read: the interface between the drive's
private kernels and the valve's periodic-orbit numerics (:mod:`impactbar.orbits.valve_segment`,
:mod:`impactbar.orbits.valve_search`).

- :func:`first_rising_crossing`, :func:`rate_zero`, :func:`rigid_flight`: the rigid coordinate under
  a constant force in closed form (compiled, :mod:`impactbar.drives._crossing`);
- :func:`end_max_sampled`: the struck end's largest displacement at a flight's samples (the flights'
  admissibility);
- :func:`rigid_orbit_start`: the fixed point of the rigid piston's map of arrival velocities
  (Newton's start on the rigid bar).
"""

from .._crossing import first_rising_crossing as first_rising_crossing
from .._crossing import rate_zero as rate_zero
from .._crossing import rigid_flight as rigid_flight
from ._compiled_loop import end_max_sampled as end_max_sampled
from ._compiled_loop import rigid_orbit_start as rigid_orbit_start

__all__ = ["first_rising_crossing", "rate_zero", "rigid_flight", "end_max_sampled", "rigid_orbit_start"]
