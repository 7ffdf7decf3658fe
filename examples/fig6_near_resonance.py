"""Fig. 6 of the paper near resonance: the paper's stability edge (eqs. 37, 39) against the exact
multipliers (theory §7), k = 10, s pi = 10.1. Prints both edges for a few R.

``python examples/fig6_near_resonance.py``: about 2 s of CPU time once numba's kernels are cached
(1.9 s measured on a 2-core AMD EPYC machine); the first run with an empty cache compiles them
first, some 12-23 s more.
"""

import math

from impactbar import BarModel
from impactbar.orbits.charts import pneumatic_existence_edge, pneumatic_stability_edges

k = 10
for R in (0.0, 0.3, 0.6):
    bar = BarModel(s=10.1 / math.pi, d=0.0, R=R, n_modes=8)
    paper = pneumatic_stability_edges(bar, k, criterion="paper")
    exact = pneumatic_stability_edges(bar, k)
    print(f"R={R:.1f}  existence {pneumatic_existence_edge(R, 0.0, k):.5f}  "
          f"paper {paper[-1][0]:.5f} ({paper[-1][1]})  exact {exact[-1][0]:.5f} ({exact[-1][1]})")
