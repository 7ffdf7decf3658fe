"""
Fig. 7: phase against κ, hydraulic hammer
=========================================

Every one-impact orbit of the rigid bar under the square-wave load (eq. 34), ``d = 0``, for
``R = 0, ..., 0.9``. All are unstable (eq. 41, theory §6), so the legend has no "stable" entry; about
a third are not even admissible (crossed, theory §5).
"""

from impactbar import paper

rows = paper.fig7_data(n=20)
paper.fig7_plot(rows)
print(f"{len(rows)} orbits, {sum(r['stable'] for r in rows)} stable, "
      f"{sum(not r['admissible'] for r in rows)} inadmissible")
