"""
The engineer's tour: a hammer in SI units, to blow energy and stability
=======================================================================

A rock-drill piston in metres, kilograms, newtons and hertz: from a configuration (or a preset), and
from a measured force curve, to its impact velocity, energy per blow, power, peak stress and whether
the motion is stable. :mod:`impactbar.physical` converts by eq. 2 (theory §1, SI scaling); the
dimensionless model does the rest.
"""

# %%
# A hammer from a configuration
# -----------------------------
# Every value with a dimension carries its unit. The same keys make a TOML file for
# ``impactbar orbits CONFIG.toml`` (see :doc:`../physical`).
from impactbar import physical

config = {
    "name": "my drill",
    "bar": {"E": "210 GPa", "density": "7850 kg/m^3", "length": "200 mm", "diameter": "40 mm"},
    "stop": {"area": "15.904 cm^2"},          # a 45 mm shank: R = (A_s - A)/(A_s + A)
    "drive": {"frequency": "40 Hz"},
    "force": {"kind": "pneumatic", "mean": "800 N", "amplitude": "2150 N"},
    "damping": {"coefficient": "2.4 N*s/m"},
    "model": {"n_modes": 16},
}
hammer = physical.Hammer.from_config(config)
print(f"piston {hammer.mass_kg:.3f} kg, R = {hammer.R:.3f}, s = {hammer.s:.2f}, d = {hammer.d:.2e}")
print(f"contact 2L/c = {hammer.contact_duration_s * 1e6:.1f} us "
      f"({hammer.contact_fraction:.2%} of the period): the short-impact assumption holds")

# %%
# Its periodic motions, in SI
# ---------------------------
# :func:`impactbar.physical.orbits` runs :func:`~impactbar.periodic_orbits` and converts: impact
# velocity ``v = L Omega u_t``, energy per blow ``m v^2 / 2``, power, peak stress ``Z v / A``.
found = physical.orbits(hammer)
for o in found:
    print(f"phase {o.phase_rad:.3f} rad: v = {o.impact_velocity_m_s:.2f} m/s, "
          f"E = {o.impact_energy_J:.1f} J, P = {o.impact_power_kW:.3f} kW, "
          f"sigma = {o.peak_piston_stress_Pa / 1e6:.0f} MPa, admissible {o.admissible}, stable {o.stable}")

# %%
# How the blow energy depends on the mean force
# ---------------------------------------------
# The rigid-limit identity ``v = F_mean / (f m (1 + R))`` (theory §4) predicts the impact velocity of
# any one-impact motion; the flexible piston follows it, and the motion stays stable only in a band
# of mean forces (theory §6). One-impact motions exist only below the existence edge (eq. 38:
# ``k p0/pk`` at most about ``(1/pi)(1 + R)/(1 - R)``, here with the damping), so the sweep runs up
# to that mean force for this amplitude: above it there is no one-impact motion to plot. Each mean
# force has two motions, a stable and an unstable one in the band, two unstable ones below it.
import matplotlib.pyplot as plt
import numpy as np

from impactbar.orbits.charts import pneumatic_existence_edge

F_edge = float(pneumatic_existence_edge(hammer.R, hammer.d, 1)) * 2150.0  # N, for 2150 N amplitude
print(f"one-impact motions exist up to a mean force of {F_edge:.0f} N")
means = np.linspace(400, F_edge, 25)
rows = []
for F in means:
    cfg = {**config, "force": {**config["force"], "mean": f"{F} N"}}
    h = physical.Hammer.from_config(cfg)
    for o in physical.orbits(h):
        rows.append((F, o.impact_energy_J, o.stable))
F, E, st = (np.array(c) for c in zip(*rows, strict=True))
fig, ax = plt.subplots(figsize=(6.5, 3.8))
ax.plot(F[st], E[st], "o", color="k", ms=4, label="stable")
ax.plot(F[~st], E[~st], "o", mfc="none", color="0.5", ms=4, label="unstable")
ax.set_xlabel("mean force / N")
ax.set_ylabel("energy per blow / J")
ax.legend()
fig.tight_layout()

# %%
# A measured force curve
# ----------------------
# A two-column CSV over one period (time and force, units in the header) becomes a Fourier load
# with the fewest harmonics that reproduce it within ``tolerance`` of its swing; the error is
# reported. Here we write a flattened cosine, the shape of a pressure curve with valve switching.
import tempfile
from pathlib import Path

work = Path(tempfile.mkdtemp())
t_ms = np.linspace(0.0, 25.0, 201)[:-1]
force = 800 + 1925 * np.tanh(1.5 * np.cos(2 * np.pi * t_ms / 25.0)) / np.tanh(1.5)
np.savetxt(work / "force.csv", np.column_stack((t_ms, force)), delimiter=",",
           header="time [ms],force [N]", comments="", fmt="%.6f")
measured = {**config, "name": "measured", "force": {"kind": "measured", "csv": "force.csv",
                                                     "tolerance": 0.01}}
hammer_m = physical.Hammer.from_config(measured, base_dir=work)
fit = hammer_m.fourier_fit
print(f"{fit.n_harmonics} harmonics, max error {fit.max_error_N:.1f} N "
      f"({fit.relative_error:.2%} of the swing)")
for o in physical.orbits(hammer_m):
    print(f"v = {o.impact_velocity_m_s:.2f} m/s, E = {o.impact_energy_J:.1f} J, stable {o.stable}")

# %%
# Simulated from rest
# -------------------
# :func:`impactbar.physical.simulate` starts the piston at rest against the stop and follows it
# impact by impact (theory §8). The blows settle on the stable periodic motion found above.
res = physical.simulate(hammer, periods=30)
fig, ax = plt.subplots(figsize=(7, 3.2))
ax.plot(res.impact_times_s * 1e3, res.impact_energies_J, "o-", ms=3, lw=0.6)
stable_E = [o.impact_energy_J for o in found if o.stable]
for e in stable_E:
    ax.axhline(e, color="tab:red", ls="--", label="stable periodic motion")
ax.set_xlabel("time / ms")
ax.set_ylabel("energy per blow / J")
if stable_E:
    ax.legend()
fig.tight_layout()
