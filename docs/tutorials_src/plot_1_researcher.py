"""
The researcher's tour: orbits, stability, simulation, sweeps
============================================================

A bar with ``N`` flexible modes, driven by the pneumatic load ``p0 + pk cos(k t)`` (eq. 33), strikes
a stop once per load period. We find every such motion, decide which are physical and stable, check
one against a simulation from a nearby start, and map the stable band over a grid of parameters.
The formulas are on the :doc:`theory page <../theory>`.
"""

# %%
# Every one-impact orbit
# ----------------------
# :func:`~impactbar.periodic_orbits` returns every root of the phase equation (eq. 14, theory §4) as a
# :class:`~impactbar.PeriodicOrbit`, sorted by phase. The list converts to a table.
from impactbar import BarModel, CosineLoad, periodic_orbits

bar = BarModel(s=5.0, d=0.1, R=0.5, n_modes=8)  # wave-speed ratio, damping, restitution, modes
load = CosineLoad(p0=0.6, pk=1.0, k=1)
orbits = periodic_orbits(bar, load)
orbits.to_dataframe()[["phase", "impact_velocity", "admissibility", "max_abs_multiplier", "stable",
                       "schur_stable"]]

# %%
# Two orbits: the paper's stability criterion (Schur's conditions on its blocks, theory §6) and the
# exact Floquet multipliers of the impact map (theory §7) agree here. An orbit is ``stable`` only if
# it is also *admissible* (theory §5): the struck end stays off the stop between impacts.
#
# Draw the stable one: the end's displacement over one period, and its multipliers against the
# unit circle.
import matplotlib.pyplot as plt

from impactbar.plotting import plot_multipliers, plot_orbit

stable = next(o for o in orbits if o.stable)
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.6), width_ratios=(1.6, 1))
plot_orbit(stable, ax=ax1)
plot_multipliers(stable, ax=ax2)
fig.tight_layout()

# %%
# Where stability is lost
# -----------------------
# Lower the mean load: at the rigid limit the stable branch loses stability by period doubling at
# ``p0/p1 = (1+R)^2 / sqrt(4 (1+R^2)^2 + pi^2 (1-R^2)^2)`` (eq. 39 with ``sigma = 0``, theory §6).
# Scanning the load factor shows the largest multiplier of the branch crossing 1.
import numpy as np

rigid = BarModel(s=50.0, d=0.0, R=0.5, n_modes=0)
x = np.linspace(0.12, 0.95, 60)
rows = []
for p0 in x:
    for o in periodic_orbits(rigid, CosineLoad(p0, 1.0)):
        if np.cos(o.phase) < 0:  # the branch on which the load falls through its mean at impact
            rows.append((p0, o.max_abs_multiplier))
edge = (1.5**2) / np.sqrt(4 * (1 + 0.25) ** 2 + np.pi**2 * (1 - 0.25) ** 2)
fig, ax = plt.subplots(figsize=(6, 3.4))
ax.plot(*np.array(rows).T, "k-")
ax.axhline(1.0, color="0.5", lw=0.8)
ax.axvline(edge, color="tab:red", ls="--", label=f"eq. 39: {edge:.4f}")
ax.set_xlabel("load factor p0 / p1")
ax.set_ylabel("largest |multiplier|")
ax.legend()
fig.tight_layout()

# %%
# Simulation from a nearby start
# ------------------------------
# :func:`~impactbar.simulate` follows the bar from any start (theory §8): exact between impacts, with
# chatter jumped to its accumulation point and sticking on the fixed-free modes. Started next to the
# stable orbit, the impact velocity settles on the orbit's, and the energy account balances.
from impactbar import InitialState, simulate

q, v = stable.modal_state_after_impact
start = InitialState(q, v * 1.02)  # 2 % off in velocity
traj = simulate(bar, load, start, t_end=2 * np.pi * 40, t0=stable.phase)
print(f"{traj.n_impacts} impacts; last impact velocity {traj.impact_velocities[-1]:.6f}, "
      f"orbit {stable.impact_velocity:.6f}")
print(f"energy balance: relative residual {traj.energy.relative_residual:.1e}")

fig, ax = plt.subplots(figsize=(7, 3))
ax.plot(np.arange(traj.n_impacts), traj.impact_velocities, "o-", ms=3)
ax.axhline(stable.impact_velocity, color="tab:red", ls="--", label="periodic orbit")
ax.set_xlabel("impact number")
ax.set_ylabel("impact velocity")
ax.legend()
fig.tight_layout()

# %%
# A sweep over a grid
# -------------------
# :func:`~impactbar.run_sweep` computes a :class:`~impactbar.SweepSpec` chunk by chunk on
# ``dask.distributed`` into a zarr store that a later run resumes (see :doc:`../sweep`). Here a
# small grid over ``R`` and ``p0`` for the rigid bar: the stability chart of Fig. 5 as a map.
import tempfile
from pathlib import Path

from impactbar import load_spec, open_sweep, run_sweep

work = Path(tempfile.mkdtemp())
(work / "grid.toml").write_text("""
task = "orbits"
[model]
s = 100.0
d = 0.0
R = 0.5
n_modes = 0
[load]
kind = "cosine"
p0 = 0.3
pk = 1.0
k = 1
[axes]
R = { start = 0.0, stop = 0.9, num = 16 }
p0 = { start = 0.2, stop = 0.45, num = 16 }
""")
spec = load_spec(work / "grid.toml")
run = run_sweep(spec, work / "grid.zarr", n_workers=1, progress=False)
ds = open_sweep(work / "grid.zarr")
print(ds)

# %%
# Every stored variable carries ``units`` and ``long_name``; the chart is drawn from the store.
from impactbar.sweeps.plot import plot_stability_chart, reduce_axes

print(ds["phase"].attrs["long_name"], "/", ds["phase"].attrs["units"])
grid, dims = reduce_axes(ds, None, 2)
ax = plot_stability_chart(grid, dims)
