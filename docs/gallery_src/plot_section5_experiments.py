"""
Section 5: the random-start experiments
=======================================

The paper followed the bar "from arbitrary initial values" (theory §8). Here 24 seeded random starts
of 120 load periods each, for the pneumatic hammer inside its stable band and for the hydraulic
hammer; ``impactbar experiment`` runs 200 starts of 300 periods. The classes and the interval
statistics are those of :mod:`impactbar.simulation.experiments`; the findings against the paper are
on the :doc:`theory page <../theory>` and in :doc:`../experiments`.
"""

import matplotlib.pyplot as plt

from impactbar.plotting import plot_end_displacement, plot_intervals
from impactbar.simulation.experiments import hydraulic_setup, pneumatic_setup, run_experiment

# %%
# Pneumatic hammer, ``p0/p1 = 1.2``, ``R = 0.8``: the load always presses, so every start ends on the
# one-impact motion (``k=1``) or in permanent contact.
model, load = pneumatic_setup(p0=1.2, pk=1.0, R=0.8)
pneumatic = run_experiment(model, load, starts=24, periods=120, seed=0, keep=2)
print(pneumatic.summary())
pneumatic.to_dataframe()["kind"].value_counts()

# %%
# Hydraulic hammer, ``κ = 1.5``, ``R = 0.5``: no start settles; the intervals between main impacts
# spread far more than the paper's 5-10 %.
model, load = hydraulic_setup(kappa=1.5, R=0.5)
hydraulic = run_experiment(model, load, starts=24, periods=120, seed=0, keep=2)
print(hydraulic.summary())

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.6), layout="constrained")
plot_intervals(pneumatic, ax1)
ax1.set_title("pneumatic: " + ax1.get_title(), fontsize=9)
plot_intervals(hydraulic, ax2)
ax2.set_title("hydraulic: " + ax2.get_title(), fontsize=9)

# %%
# The struck end over the last load periods of two hydraulic runs: impacts, chatter and contact.
axes = plot_end_displacement(hydraulic)
