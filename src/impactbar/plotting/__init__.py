"""Every figure of impactbar, in one place (matplotlib is imported lazily, inside the functions).

One convention throughout: a drawing function takes a finished result first and an optional ``ax``
(or ``axes``), draws on it (a new figure when it is ``None``) and returns what it drew on. Results
that plot themselves (``PeriodicOrbit.plot``, ``Trajectory.plot``, ``Branch.plot``,
``BifurcationCurve.plot``) call these functions; nothing here computes dynamics again.

- :mod:`~impactbar.plotting.orbits`: a periodic orbit's end motion, field and multipliers;
- :mod:`~impactbar.plotting.simulation`: simulations and the random-start experiments;
- :mod:`~impactbar.plotting.continuation`: branches and two-parameter bifurcation curves;
- :mod:`~impactbar.plotting.physical`: results in SI units (motion, energy per blow, force waves);
- :mod:`~impactbar.plotting.paper`: the paper's Figs. 4-8;
- :mod:`~impactbar.plotting.sweeps`: stored sweeps (stability charts, fraction maps, diagrams);
- :mod:`~impactbar.plotting.rock`: a blow on the rod and rock (Lagrange diagram, force-penetration loop);
- :mod:`~impactbar.plotting.circuit`: a drifter's operating point with its oil circuit (pressures,
  valve, indicator diagrams), its bifurcation diagram in a circuit parameter, and the circuit's
  schematic (its parts, their connections and the valve's switch points);
- :mod:`~impactbar.plotting.circuit_graph`: the circuit's nodes and parts (its config's
  ``[parts.<name>]`` among them) as a graph.
"""

from ._common import label_contours as label_contours
from .circuit import plot_circuit_branch as plot_circuit_branch
from .circuit import plot_circuit_orbit as plot_circuit_orbit
from .circuit import plot_circuit_run as plot_circuit_run
from .circuit import plot_circuit_schematic as plot_circuit_schematic
from .circuit_graph import plot_circuit_graph as plot_circuit_graph
from .continuation import plot_bifurcation_curve as plot_bifurcation_curve
from .continuation import plot_branch as plot_branch
from .orbits import plot_multipliers as plot_multipliers
from .orbits import plot_orbit as plot_orbit
from .orbits import plot_orbit_field as plot_orbit_field
from .physical import plot_blows as plot_blows
from .physical import plot_force_waves as plot_force_waves
from .physical import plot_motion as plot_motion
from .rock import plot_force_penetration as plot_force_penetration
from .rock import plot_lagrange as plot_lagrange
from .simulation import plot_end_displacement as plot_end_displacement
from .simulation import plot_experiment as plot_experiment
from .simulation import plot_impact_map as plot_impact_map
from .simulation import plot_intervals as plot_intervals
from .simulation import plot_trajectory as plot_trajectory
from .sweeps import plot_bifurcation as plot_bifurcation
from .sweeps import plot_efficiency_map as plot_efficiency_map
from .sweeps import plot_fraction_maps as plot_fraction_maps
from .sweeps import plot_stability_chart as plot_stability_chart

__all__ = ["label_contours",
           "plot_orbit", "plot_orbit_field", "plot_multipliers", "plot_trajectory", "plot_end_displacement",
           "plot_impact_map", "plot_intervals", "plot_experiment", "plot_branch", "plot_bifurcation_curve",
           "plot_motion", "plot_blows", "plot_force_waves", "plot_stability_chart", "plot_fraction_maps",
           "plot_bifurcation", "plot_lagrange", "plot_force_penetration", "plot_efficiency_map",
           "plot_circuit_orbit", "plot_circuit_branch", "plot_circuit_run", "plot_circuit_schematic",
           "plot_circuit_graph"]
