"""
Fig. 6: near resonance the paper's criterion fails
==================================================

The lower stability edge for ``k = 10`` (one impact per ten load periods) against ``R``: the paper's
criterion (eqs. 37, 39, dashed) and the exact Floquet multipliers of an 8-mode bar (theory §7, solid)
for ``sπ → ∞``, ``10.1`` and ``10.01``. Far from resonance they agree; near it the exact edge is far
lower (a Neimark-Sacker loss, not a period doubling).
"""

from impactbar import paper

data = paper.fig6_data(n=8)
ax = paper.fig6_plot(data)
