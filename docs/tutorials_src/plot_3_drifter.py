"""
Your drifter, from a blank config
=================================

A hydraulic top-hammer drifter driven by its oil circuit (theory §11): a pump feeds a supply line
with a gas accumulator and a relief valve; the front (return) chamber is always on supply, and the
main valve puts the rear (stroke) chamber on supply or on tank as the piston passes its switch
points. Here we write such a drifter from its drawings and its parts' datasheets, find its operating
point (blow frequency, impact energy, supply pressure, efficiency, stability), read its chambers'
p-V diagrams, follow it as the pump's flow changes, and map it over two keys. Every key and its
typical range are in the table of :doc:`../physical` ("A drifter with its oil circuit").

The piston is rigid (``n_modes = 0``, the default), which is what the circuit's design needs; give
``[model] n_modes`` to let its flexible modes take part.
"""

# %%
# The circuit
# -----------
# :func:`~impactbar.plotting.plot_circuit_schematic` draws the parts the model has and how they are
# connected, with the symbols of theory §11. The stroke axis below the piston is the gap from the
# impact position (the piston's front end on the shank): on the way out the valve starts toward
# stroke when the gap rises through ``switch_out``; it starts back at the impact, or, with
# ``switch_in``, when the gap falls through that on the way in.
import matplotlib.pyplot as plt

from impactbar import physical
from impactbar.plotting import label_contours, plot_circuit_schematic

plot_circuit_schematic()
plt.show()

# %%
# From a datasheet to a flow coefficient
# --------------------------------------
# The model's openings follow ``Q = K sqrt(dp)`` (the relief valve ``Q = K_rel (p_s - p_rel)``).
# A datasheet gives a nominal flow at a pressure drop instead; :func:`~impactbar.physical.flow_coefficient`
# turns it into the coefficient in SI. Our main valve passes 360 L/min at 10 bar per control edge,
# the front chamber's feed 250 L/min at 5 bar, and the relief valve 30 L/min at 1 MPa over its
# setting.
K_valve = physical.flow_coefficient("360 L/min", "10 bar")
K_front = physical.flow_coefficient("250 L/min", "5 bar")
K_relief = physical.flow_coefficient("30 L/min", "1 MPa", law="linear")
print(f"valve.flow_coefficient         = {K_valve:.4g} m^3/s/Pa^0.5")
print(f"supply.front_flow_coefficient  = {K_front:.4g} m^3/s/Pa^0.5")
print(f"supply.relief_coefficient      = {K_relief:.4g} m^3/s/Pa")

# %%
# The config
# ----------
# Every section and key, each value with its unit as a string (a bare number where a unit is due is
# refused, naming the key). Pressures are absolute. The volumes of the chambers are those with the
# piston at its impact position; the switch points are gaps from it.
config = {
    "name": "my drifter",
    "bar": {                                # the piston (a list of lengths and diameters: stepped)
        "E": "210 GPa",                     # Young's modulus
        "density": "7850 kg/m^3",
        "length": "448.5 mm",
        "diameter": "45 mm",                # or "area"
    },
    "stop": {"restitution": 0.215},         # the shank's R; or "area" of the shank (same steel)
    "damping": {"coefficient": "0 N*s/m"},  # optional: viscous damping of the piston
    "model": {"n_modes": 0},                # optional: flexible modes of the piston (0: rigid)
    "chambers": {
        "rear_area": "5.6 cm^2",            # A_r, pushes the piston toward the shank
        "front_area": "2.8 cm^2",           # A_f < A_r, the annulus that returns it
        "rear_volume": "0.1 L",             # oil in the rear chamber at impact
        "front_volume": "0.05 L",           # oil in the front chamber at impact
    },
    "valve": {
        "switch_out": "21.5 mm",            # gap at which the valve starts toward stroke
        "switch_in": "8 mm",                # optional: gap at which it starts back (default: impact)
        "switching_time": "1 ms",           # a full stroke of the spool
        "flow_coefficient": f"{K_valve} m^3/s/Pa^0.5",
    },
    "supply": {
        "pump_flow": "70 L/min",            # a constant-flow pump
        "hose_volume": "0.25 L",            # the oil between the pump and the valve block
        "front_flow_coefficient": f"{K_front} m^3/s/Pa^0.5",
        "tank_pressure": "0.3 MPa",         # the return line's back pressure (absolute)
        "relief_pressure": "25 MPa",        # optional: the relief valve's setting
        "relief_coefficient": f"{K_relief} m^3/s/Pa",   # optional, with it
    },
    "accumulator": {                        # optional section: a gas accumulator on the supply
        "precharge": "10 MPa",              # the gas pressure with no oil in it
        "volume": "0.5 L",                  # its gas volume at the pre-charge
        "polytropic_exponent": 1.4,         # optional: 1 isothermal, 1.4 adiabatic nitrogen
    },
    "oil": {
        "bulk_modulus": "1.4 GPa",          # effective: oil, entrained air and the hoses' compliance
        "transition_pressure": "0.2 MPa",   # where the orifice law turns laminar near zero flow
    },
}
drifter = physical.CircuitDrifter.from_config(config)
print(f"{drifter.name}: piston {drifter.bar.mass_kg:.3f} kg, R = {drifter.restitution}, "
      f"time scale 1/Omega = {1e3 / drifter.omega_rad_s:.3f} ms")

# %%
# The same in a TOML file
# -----------------------
# A file holds the same sections and keys; :func:`~impactbar.physical.load` reads it (a
# ``[chambers]`` section makes it a drifter with its oil circuit), and so do the command-line tools
# (``impactbar drifter my_drifter.toml``, ``impactbar continue my_drifter.toml ...``). Written from
# the dict here, it gives the same drifter.
import json
import tempfile
from pathlib import Path


def toml_text(cfg):
    """The config as TOML text (its values are strings and numbers)."""
    lines = [f"name = {json.dumps(cfg['name'])}"]
    for section, keys in cfg.items():
        if isinstance(keys, dict):
            lines += ["", f"[{section}]"] + [f"{k} = {json.dumps(v)}" for k, v in keys.items()]
    return "\n".join(lines) + "\n"


path = Path(tempfile.mkdtemp()) / "my_drifter.toml"
path.write_text(toml_text(config))
print(path.read_text().split("[chambers]")[1].split("[valve]")[0].strip())
print("the file gives the same drifter:", physical.load(path).si == drifter.si)

# %%
# Your drifter, drawn with its numbers
# ------------------------------------
plot_circuit_schematic(drifter)
plt.show()

# %%
# The operating point
# -------------------
# :meth:`~impactbar.physical.CircuitDrifter.orbit` follows the motion from rest until it settles,
# then solves for the periodic motion (one blow a period) with Newton's method; its Floquet
# multipliers decide its stability. The hydraulic efficiency is the energy the blows take over the
# pump's hydraulic work; the minimum pressures tell whether a chamber would cavitate.
point = drifter.orbit()
print(f"blow frequency     {point.blow_frequency_Hz:.2f} Hz")
print(f"impact velocity    {point.impact_velocity_m_s:.3f} m/s")
print(f"impact energy      {point.impact_energy_J:.1f} J")
print(f"impact power       {point.impact_power_kW:.2f} kW  (pump {point.pump_power_kW:.2f} kW)")
print(f"mean supply        {point.mean_supply_pressure_Pa / 1e6:.2f} MPa")
print(f"hydraulic eff.     {point.hydraulic_efficiency:.3f}")
print(f"largest |mult.|    {max(abs(point.multipliers)):.3f}  -> stable: {point.stable}")
print("minimum pressures  " + ", ".join(f"{k} {v / 1e6:.2f} MPa" for k, v in
                                         point.minimum_pressures_Pa.items())
      + f"  (cavitates: {point.cavitates})")

# %%
# Pressures and p-V diagrams
# --------------------------
# :meth:`~impactbar.physical.circuit.CircuitDrifterOrbit.plot` draws the pressures and the valve
# over one period from the impact, and each chamber's indicator (p-V) diagram: the rear chamber's
# loop is the work the oil does on the piston, the front one's the work it takes back.
# :meth:`~impactbar.physical.circuit.CircuitDrifterOrbit.indicator_work_J` integrates the loops. On a
# rigid piston without damping their sum is what each impact takes from the piston, the kinetic
# energy before it less after it, ``E (1 - R^2)``.
point.plot()
plt.show()
work = point.indicator_work_J()
R = drifter.restitution
print(f"rear loop {work['rear']:.2f} J, front loop {work['front']:.2f} J, "
      f"sum {work['piston']:.2f} J a period")
print(f"E (1 - R^2) = {point.impact_energy_J * (1 - R**2):.2f} J")

# %%
# Following the operating point in a config key
# ---------------------------------------------
# :func:`~impactbar.physical.continue_circuit` follows the operating point as one key changes, given
# by its config name and a value in SI units (every key of
# :data:`~impactbar.physical.circuit.SI_PARAMETERS`). More pump flow gives more blows and harder
# ones, and a higher supply pressure; every event on the way (a fold, a period doubling, the
# accumulator emptying during the cycle, the supply's peak reaching the relief valve's setting) is
# located, listed in ``branch.events`` and marked on the diagram. The command line does the same:
# ``impactbar continue my_drifter.toml --parameter supply.pump_flow --to "75 L/min"``. The
# continuation's step (``max_step``, dimensionless) is kept small enough here to show the branch's
# points.
branch = physical.continue_circuit(drifter, "supply.pump_flow", "75 L/min", max_step=0.05)
print(branch)
for i in (0, -1):
    print(f"{branch.values[i] * 6e4:6.2f} L/min: {branch.blow_frequency_Hz[i]:6.2f} Hz, "
          f"{branch.impact_energy_J[i]:6.1f} J")
print(f"stable all along: {bool(branch.stable.all())}, "
      f"largest |multiplier| {branch.max_abs_multiplier.max():.3f}")
for event in branch.events:
    print(f"{event['kind']} at {event['value'] * 6e4:.2f} L/min")
branch.plot()
plt.show()

# %%
# A map over two keys
# -------------------
# A designer asks how the operating point moves over two keys at once, here the pump flow and the
# accumulator's pre-charge: each point of the grid is the operating point of the config with those
# two values (:meth:`~impactbar.physical.CircuitDrifter.orbit` from rest, a quarter of a second of
# CPU for this rigid piston). The filled contours are the hydraulic efficiency, the lines the blow
# frequency; a cross marks a point whose operating point is not stable. Past the pump flow at which
# the continuation above found the relief valve starting to open, the oil it passes is lost and the
# efficiency falls.
import numpy as np

flows = np.linspace(60.0, 80.0, 5)      # L/min
precharges = np.linspace(6.0, 14.0, 5)  # MPa
frequency = np.empty((precharges.size, flows.size))
efficiency = np.empty_like(frequency)
stable = np.empty(frequency.shape, dtype=bool)
for i, p0 in enumerate(precharges):
    for j, q in enumerate(flows):
        cfg = {**config, "supply": {**config["supply"], "pump_flow": f"{q} L/min"},
               "accumulator": {**config["accumulator"], "precharge": f"{p0} MPa"}}
        op = physical.CircuitDrifter.from_config(cfg).orbit()
        frequency[i, j], efficiency[i, j], stable[i, j] = (op.blow_frequency_Hz, op.hydraulic_efficiency,
                                                           op.stable)
fig, ax = plt.subplots(figsize=(6.4, 4.4))
filled = ax.contourf(flows, precharges, efficiency, levels=12, cmap="viridis")
fig.colorbar(filled, ax=ax, label="hydraulic efficiency")
lines = ax.contour(flows, precharges, frequency, colors="white", linewidths=0.8)
label_contours(ax, lines, "Hz")  # decimals from the levels' spacing, upright, inside
Q, P = np.meshgrid(flows, precharges)
ax.plot(Q[~stable], P[~stable], "rx")  # (none where every point is stable)
ax.set_xlabel("supply.pump_flow (L/min)")
ax.set_ylabel("accumulator.precharge (MPa)")
plt.show()
print(f"blow frequency {frequency.min():.1f} to {frequency.max():.1f} Hz, hydraulic efficiency "
      f"{efficiency.min():.3f} to {efficiency.max():.3f}; stable at {int(stable.sum())} of "
      f"{stable.size} points")
