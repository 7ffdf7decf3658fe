"""
A drill with the parts a real drifter has
=========================================

The preset drifter's circuit (:doc:`plot_3_drifter`) has a valve, two chambers, a pump, an
accumulator and a relief valve. A real drill has more: its rear chamber empties through a cushion, a
port the piston shuts over the top of its return stroke, into a return hose with a low-pressure
accumulator; oil leaks across the piston's clearances; a check valve lets the front chamber push oil
back into the supply. ``examples/circuit_drill_parts.toml`` adds each of them as a ``[parts.<name>]``
table (its comments give each value's source and usual range). Here we read it, draw its circuit,
find its operating point, look at the parts' pressures and flows over a blow, map it over the
cushion's two parameters and let the optimiser choose them.
"""

# %%
# The circuit, drawn from the config
# ----------------------------------
# :func:`~impactbar.plotting.plot_circuit_graph` draws the nodes of oil the config has (boxes: the
# chambers, the supply, the tank, each part's own node) and its parts (arrows, from the node a part's
# flow leaves to the one it enters). The valve's return port goes to the cushion's node, which drains
# through the cushion's port into the return line, which drains into the tank.
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from impactbar import physical
from impactbar.plotting import label_contours, plot_circuit_graph

try:  # (run as a file: the repository's; in the docs' build: from the docs folder)
    ROOT = Path(__file__).resolve().parents[2]
except NameError:
    ROOT = Path.cwd().parents[1]
DRILL = ROOT / "examples" / "circuit_drill_parts.toml"
drill = physical.load(DRILL)
plot_circuit_graph(drill)
plt.show()

# %%
# The parts, as ``impactbar drifter`` lists them
# ----------------------------------------------
# ``impactbar drifter examples/circuit_drill_parts.toml`` prints each part under the drifter's
# header: its kind, the nodes it joins and its values in the units the config wrote them in.
from impactbar.physical.circuit_graph import part_lines

print("\n".join(part_lines(drill)))

# %%
# The operating point
# -------------------
point = drill.orbit()
print(f"blow frequency {point.blow_frequency_Hz:.2f} Hz, impact energy {point.impact_energy_J:.1f} J, "
      f"impact power {point.impact_power_kW:.2f} kW, hydraulic efficiency {point.hydraulic_efficiency:.3f}, "
      f"largest |multiplier| {max(abs(point.multipliers)):.3f}")

# %%
# The parts over one period
# -------------------------
# The histories hold each part's node pressure (``p_<name>_Pa``) and each part's flow from its source
# to its target (``q_<name>_m3_s``): here the rear chamber's pressure beside the cushion's node (the
# oil between the valve and the cushion's port) and the return line's, and the flows through the
# cushion's port, out of the return line into the tank, through the check valve and across the
# piston's land.
h = point.histories(2000)
t = h["t_s"] * 1e3
fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 5.5), layout="constrained")
top.plot(t, h["p_r_Pa"] / 1e6, label="rear chamber")
top.plot(t, h["p_cushion_Pa"] / 1e6, label="cushion node")
top.plot(t, h["p_return_line_Pa"] / 1e6, label="return line")
top.set_ylabel("pressure (MPa)")
top.legend()
for name in ("cushion", "return_line", "check", "land"):
    bottom.plot(t, h[f"q_{name}_m3_s"] * 6e4, label=name)
bottom.set_ylabel("flow (L/min)")
bottom.set_xlabel("time from the impact (ms)")
bottom.legend()
plt.show()
print(f"the cushion's node peaks at {h['p_cushion_Pa'].max() / 1e6:.2f} MPa, the return line's at "
      f"{h['p_return_line_Pa'].max() / 1e6:.3f} MPa")

# %%
# A map over the cushion's volume and port
# ----------------------------------------
# The map of 15 x 15 operating points over ``parts.cushion.volume`` and ``parts.cushion.coefficient``
# was computed on a local dask cluster by ``benchmarks/make_drill_cushion_map.py`` (a
# :class:`~impactbar.sweeps.SweepSpec` with a ``config`` run by :func:`~impactbar.sweeps.run_map`,
# as ``impactbar sweep`` runs a design map) and stored as ``docs/data/drill_cushion_map.csv``; here
# it is read back.
# The filled contours are the impact power, the lines the blow frequency.
import csv


def stored_map(file, row_key, column_key):
    """A map stored in ``docs/data``: its two axes' values and a function that gives a stored column
    on its grid (``row_key`` along the rows)."""
    with (ROOT / "docs" / "data" / file).open() as fh:
        rows = list(csv.DictReader(fh))
    ys, xs = (np.unique([float(r[k]) for r in rows]) for k in (row_key, column_key))
    return ys, xs, lambda name: np.array([float(r[name]) for r in rows]).reshape(ys.size, xs.size)


volume, coefficient, grid = stored_map("drill_cushion_map.csv", "parts.cushion.volume",
                                       "parts.cushion.coefficient")

power = grid("impact_energy") * grid("blow_frequency") / 1e3
frequency = grid("blow_frequency")
fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
filled = ax.contourf(coefficient * 1e6, volume * 1e6, power, levels=12, cmap="viridis")
fig.colorbar(filled, ax=ax, label="impact power (kW)")
label_contours(ax, ax.contour(coefficient * 1e6, volume * 1e6, frequency, colors="white", linewidths=0.8),
               "Hz")
stable = grid("stable") > 0.5
C, V = np.meshgrid(coefficient * 1e6, volume * 1e6)
ax.plot(C[~stable], V[~stable], "rx")  # (none where every point is stable)
ax.set_xlabel("parts.cushion.coefficient (1e-6 m^3/s/Pa^0.5)")
ax.set_ylabel("parts.cushion.volume (mL)")
plt.show()
print(f"{power.size} points: impact power {power.min():.2f} to {power.max():.2f} kW, blow frequency "
      f"{frequency.min():.1f} to {frequency.max():.1f} Hz; stable at {int(stable.sum())} of {stable.size}")

# %%
# The optimiser over the cushion
# ------------------------------
# :func:`~impactbar.physical.optimize_drifter` takes the same keys as its variables, within bounds;
# here it maximises the impact power with the default constraints (a stable operating point, no
# cavitation, the mean supply pressure under the relief valve's setting). ``impactbar optimize
# examples/circuit_drill_parts.toml --objective impact_power --vary "parts.cushion.volume=5mL:40mL"
# --vary "parts.cushion.coefficient=2.5e-6 m^3/s/Pa^0.5:1.5e-5 m^3/s/Pa^0.5"`` does the same.
res = physical.optimize_drifter(
    DRILL, vary={"parts.cushion.volume": ("5 mL", "40 mL"),
                 "parts.cushion.coefficient": ("2.5e-6 m^3/s/Pa^0.5", "1.5e-5 m^3/s/Pa^0.5")},
    objective="impact_power", max_evaluations=12, progress=False)
print(res.table())

# %%
# The spool valve in the valve's place
# ------------------------------------
# A drifter's main valve is not a ramp on the piston's position: it is a spool that the oil moves,
# pushed open by a control chamber that the piston's pilot ports fill and drain.
# ``examples/circuit_drill_spool.toml`` is the same drill with a ``[parts.main_spool]`` of kind
# ``spool_valve`` and no ``[valve]`` table: the spool's mass, stroke, end areas and control chamber
# from a distributor spool's typical values (theory §11), its pilot ports where the drill's valve
# switched. With it the drill has every part a drifter has: it is the example drill whose rigid
# orbit ``benchmarks/bench_circuit.py --drill`` times against the preset's (at most 3 times its CPU
# time). Its operating point, and the spool's position and control pressure over a period:
spool_drill = physical.load(ROOT / "examples" / "circuit_drill_spool.toml")
spool_point = spool_drill.orbit()
print(f"blow frequency {spool_point.blow_frequency_Hz:.2f} Hz, impact energy "
      f"{spool_point.impact_energy_J:.1f} J, impact power {spool_point.impact_power_kW:.2f} kW, hydraulic "
      f"efficiency {spool_point.hydraulic_efficiency:.3f}, mean supply pressure "
      f"{spool_point.mean_supply_pressure_Pa / 1e6:.2f} MPa")
hs = spool_point.histories(2000)
fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 5), layout="constrained")
top.plot(hs["t_s"] * 1e3, hs["x_v"], label="spool position x_s / h_s")
top.plot(hs["t_s"] * 1e3, hs["gap_m"] / hs["gap_m"].max(), label="piston's gap / its largest")
top.legend()
bottom.plot(hs["t_s"] * 1e3, hs["p_main_spool_Pa"] / 1e6, label="control chamber")
bottom.plot(hs["t_s"] * 1e3, hs["p_r_Pa"] / 1e6, label="rear chamber")
bottom.set_ylabel("pressure (MPa)")
bottom.set_xlabel("time from the impact (ms)")
bottom.legend()
plt.show()

# %%
# A map over the spool's mass and control end
# -------------------------------------------
# The same way, ``benchmarks/make_drill_spool_map.py`` mapped the spool drill over
# ``parts.main_spool.mass`` and ``parts.main_spool.large_area`` (15 x 15 operating points on a local
# dask cluster), stored as ``docs/data/drill_spool_map.csv``: the impact power filled, the blow
# frequency in lines.
mass, area, spool_grid = stored_map("drill_spool_map.csv", "parts.main_spool.mass",
                                    "parts.main_spool.large_area")
spool_power = spool_grid("impact_energy") * spool_grid("blow_frequency") / 1e3
fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
filled = ax.contourf(area * 1e4, mass, spool_power, levels=12, cmap="viridis")
fig.colorbar(filled, ax=ax, label="impact power (kW)")
label_contours(ax, ax.contour(area * 1e4, mass, spool_grid("blow_frequency"), colors="white",
                              linewidths=0.8), "Hz")
ax.set_xlabel("parts.main_spool.large_area (cm^2)")
ax.set_ylabel("parts.main_spool.mass (kg)")
plt.show()
print(f"{spool_power.size} points: impact power {spool_power.min():.2f} to {spool_power.max():.2f} kW")

# %%
# The optimiser over the spool and the cushion
# --------------------------------------------
# The spool's fields are keys like any other (``parts.main_spool.mass``, ...). A run over the spool's
# mass and control end and the cushion's volume and coefficient, 28 designs at most (a Sobol sample of
# 16 evaluated together on a local dask cluster, then COBYLA from the best), was made by
# ``benchmarks/make_drill_spool_optimum.py`` and stored as ``docs/data/drill_spool_optimum.json``;
# here it is read back. The drill runs on its relief valve, so the mean supply pressure's cap is raised
# to 26 MPa (its test recomputes the stored optimum's orbit from the config).
import json

stored = json.loads((ROOT / "docs" / "data" / "drill_spool_optimum.json").read_text())
for key, value in stored["optimum"]["changes"].items():
    print(f"{key} = {value}  (the example's {stored['baseline']['changes'][key]})")
before, after = (stored[k]["objectives"]["impact_power_kW"] for k in ("baseline", "optimum"))
print(f"{stored['evaluations']} designs: impact power {before:.2f} kW -> {after:.2f} kW "
      f"({stored['gain']:+.1%})")
