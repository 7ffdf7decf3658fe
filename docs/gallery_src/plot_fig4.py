"""
Fig. 4: phase against load factor, pneumatic hammer
===================================================

The phase lag ``φ`` of every one-impact orbit of the rigid bar (``s π → ∞``) under the pneumatic load
``p0 + pk cos(k t)`` (eq. 33), ``d = 0``, for ``R = 0, 0.1, ..., 0.9``: stable solid, unstable
dashed by the exact multipliers (theory §7), orbits that are not motions at all crossed (theory §5).
At ``R = 0`` part of the paper's stable branch sticks to the stop. ``impactbar paper`` draws the same
with 120 points per curve; here 20.
"""

from impactbar import paper

rows = paper.fig4_data(n=20)
ax = paper.fig4_plot(rows)
