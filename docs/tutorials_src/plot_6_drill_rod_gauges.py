"""
Two gauges on a drill rod
=========================

On a drill rod the stress pulse is longer than the distance from a gauge to the bit, so the wave
going down and the one coming back from the rock overlap at every gauge: no time window parts them.
Two gauges do (Lundberg and Henchoz's two-point separation). Here the library's own exact blow of a
piston on a stepped rod with its bit on a bilinear rock gives the strains at two gauge stations,
with 1 % noise added; from them we separate the waves at the bit, draw its force-penetration curve
and fit the rock's loading and unloading stiffnesses, and hold each result against the blow that
made the strains. :doc:`../measurements` says what each step is.
"""

# %%
# The blow and its gauges
# -----------------------
# A uniform steel piston strikes a shank and a rod of a smaller section; the bit at the rod's far end
# presses on Lundberg's bilinear rock (:math:`k` on loading, :math:`k_u` on unloading).
# :func:`~impactbar.measure.gauge_strains` computes the blow (exact, theory §12) and reads the strain
# at two stations near the bit; white noise of 1 % of the larger gauge's peak strain is added to each
# (a fixed seed, so the numbers below stay the same).
import matplotlib.pyplot as plt
import numpy as np

from impactbar.measure import (
    Bar,
    end_history,
    fit_bilinear_rock,
    fit_blow,
    gauge_strains,
    separate_two_point,
)
from impactbar.physical.piston import piston_blow
from impactbar.physical.rock import RodPiece

STEEL = {"E_Pa": 2.0e11, "density_kg_m3": 8000.0}
ROD = [RodPiece(length_m=0.5, area_m2=1.2e-3, **STEEL),  # the shank
       RodPiece(length_m=3.0, area_m2=0.8e-3, **STEEL)]  # the rod, down to the bit
PISTON = {"piston_lengths": [0.3], "piston_areas": [1.0e-3]}
TRUE = {"impact_velocity": 10.0, "rock.k": 3e8, "rock.k_u": 3e9}
NEAR, FAR = 0.15, 0.20  # the gauges' distances from the bit (m)
NOISE, SEED = 0.01, 1

length = sum(p.length_m for p in ROD)
time = 0.4e-3 + 0.5e-6 * np.arange(2480)  # s from the impact: 2 MHz, to the blow's end
clean = gauge_strains(ROD, **PISTON, values=TRUE, stations=[length - NEAR, length - FAR], time=time)
near_clean, far_clean = clean[length - NEAR], clean[length - FAR]
peak_strain = max(np.abs(near_clean).max(), np.abs(far_clean).max())
rng = np.random.default_rng(SEED)
near, far = (e + NOISE * peak_strain * rng.standard_normal(time.size) for e in (near_clean, far_clean))
rod = Bar(STEEL["E_Pa"], STEEL["density_kg_m3"], ROD[-1].area_m2)  # the section the gauges sit on
quiet = time < (length - FAR) / rod.wave_speed  # before the wave reaches the gauges
print(f"wave speed {rod.wave_speed:.0f} m/s: the wave reaches the far gauge at "
      f"{(length - FAR) / rod.wave_speed * 1e3:.3f} ms; peak strain {peak_strain * 1e6:.1f} microstrain, "
      f"noise {NOISE * peak_strain * 1e6:.2f} microstrain r.m.s.")

fig, ax = plt.subplots(figsize=(7, 3.6), layout="constrained")
ax.plot(time * 1e3, near * 1e6, lw=0.6, label=f"{NEAR} m from the bit")
ax.plot(time * 1e3, far * 1e6, lw=0.6, label=f"{FAR} m from the bit")
ax.plot(time * 1e3, near_clean * 1e6, "k", lw=0.8, label="without the noise")
ax.set(xlabel="time from the impact (ms)", ylabel="strain (microstrain)", title="the gauges' strains")
ax.legend(fontsize=8)
plt.show()

# %%
# The blow that made them
# -----------------------
# :func:`~impactbar.physical.piston.piston_blow` computes the same blow and returns it in the model's
# units (the piston's mass and length and the wave speed 1): the bit's force is in units of
# :math:`m c^2/L`, the time of :math:`L/c`, the penetration of :math:`L`. This is the reference.
exact = piston_blow(ROD, (TRUE["rock.k"], TRUE["rock.k_u"]), lengths=PISTON["piston_lengths"],
                    areas=PISTON["piston_areas"], impact_velocity=TRUE["impact_velocity"])
blow, L, c = exact["blow"], exact["length_m"], rod.wave_speed
force_unit, time_unit = exact["mass_kg"] * c * c / L, L / c
exact_peak_force = float(np.max(blow.bit_forces)) * force_unit
print(f"the exact blow: peak force {exact_peak_force / 1e3:.1f} kN on the rock, largest penetration "
      f"{blow.max_penetration * L * 1e3:.3f} mm, work on the rock {exact['work_on_rock_J']:.2f} J of the "
      f"piston's {exact['impact_energy_J']:.0f} J")

# %%
# Two-point separation without the noise
# --------------------------------------
# With :math:`x` from the bit, the strain is :math:`\varepsilon(x,t) = a(t+x/c) + b(t-x/c)`;
# :func:`~impactbar.measure.separate_two_point` marches the wave toward the bit from a quiet start
# and shifts both waves to the bit. On the strains without noise the force at the bit,
# :math:`F = -EA(a+b)`, is the exact blow's to rounding.
waves_clean = separate_two_point(time, near_clean, far_clean, NEAR, FAR, rod)
bit_clean = end_history(waves_clean, rod)
force_exact = blow.bit_force(waves_clean.time / time_unit) * force_unit
force_error = np.max(np.abs(bit_clean.force - force_exact)) / exact_peak_force
print(f"without noise: the bit's force within {force_error:.1e} of its peak")

# %%
# Two-point separation with the noise
# -----------------------------------
# The method fails where the two gauges see the same thing: at :math:`f = n c / (2 (x_B - x_A))`, the
# march's poles, where noise adds up. Both channels are low-passed below the first of them (0.8 of
# it), their pre-trigger medians removed; the waves that come back are those of the blow low-passed
# alike, so they are held against the noise-free strains separated with the same low-pass.
failing = rod.wave_speed / (2 * (FAR - NEAR))
cutoff = 0.8 * failing
waves = separate_two_point(time, near, far, NEAR, FAR, rod, baseline=quiet, cutoff=cutoff)
waves_alike = separate_two_point(time, near_clean, far_clean, NEAR, FAR, rod, baseline=quiet, cutoff=cutoff)
bit, bit_alike = end_history(waves, rod), end_history(waves_alike, rod)
print(f"first failing frequency {failing / 1e3:.1f} kHz, low-passed at {cutoff / 1e3:.1f} kHz")
off_exact = np.max(np.abs(bit.force - force_exact)) / exact_peak_force
off_alike = np.max(np.abs(bit.force - bit_alike.force)) / exact_peak_force
print(f"with {NOISE:.0%} noise: the bit's force off the exact blow's by at most {off_exact:.1%} of its peak, "
      f"off the noise-free one low-passed alike by {off_alike:.1%}")

fig, ax = plt.subplots(figsize=(7, 3.6), layout="constrained")
ms = waves.time * 1e3
ax.plot(ms, waves.toward * 1e6, lw=0.8, label="toward the bit, from the noisy gauges")
ax.plot(ms, waves.away * 1e6, lw=0.8, label="back from the bit, from the noisy gauges")
ax.plot(ms, waves_clean.toward * 1e6, "k--", lw=0.7, label="without the noise")
ax.plot(ms, waves_clean.away * 1e6, "k--", lw=0.7)
ax.set(xlim=(0.6, 1.0), xlabel="time from the impact (ms)", ylabel="strain (microstrain)",
       title="the waves at the bit")
ax.legend(fontsize=8)
plt.show()

# %%
# The bit's force-penetration curve
# ---------------------------------
# :func:`~impactbar.measure.end_history` gives the bit's force, its velocity :math:`v = c(b - a)`, its
# penetration (the velocity's integral) and the energy that passed into it (the force-velocity
# integral of ASTM D4633). The penetration adds up the noise's slow part, which no low-pass removes.
fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
ax.plot(bit.displacement * 1e3, bit.force / 1e3, lw=0.8, label="from the noisy gauges")
ax.plot(blow.penetrations * L * 1e3, blow.bit_forces * force_unit / 1e3, "k", lw=1.0, label="the exact blow")
ax.set(xlabel="penetration (mm)", ylabel="force on the rock (kN)", title="the bit's force-penetration curve")
ax.legend(fontsize=8)
plt.show()
print(f"from the gauges: peak force {bit.force.max() / 1e3:.1f} kN, largest penetration "
      f"{bit.displacement.max() * 1e3:.3f} mm, energy into the bit {bit.energy_fv[-1]:.2f} J")

# %%
# The rock's stiffnesses from the curve
# -------------------------------------
# :func:`~impactbar.measure.fit_bilinear_rock` reads :math:`k` as the least-squares slope of the
# force's steps against the penetration's on virgin loading, :math:`k_u` below it, where the force
# exceeds a tenth of its peak (in contact), with the standard errors of those slopes. Without noise
# it returns the rock that made the blow (to the trapezoid's bias); the low-pass alone, on the strains
# without noise, moves them little. With the noise the slopes scatter, and more than their standard
# errors say: those count the steps' scatter about one slope, not how the noise and the rounded
# fronts move the slope itself (most the unloading's, which is short). The spread over other seeds
# of the same noise shows by how much.
dt = time[1] - time[0]
rock_clean = fit_bilinear_rock(bit_clean.force, bit_clean.velocity, dt, contact=0.1)
rock_alike = fit_bilinear_rock(bit_alike.force, bit_alike.velocity, dt, contact=0.1)
rock = fit_bilinear_rock(bit.force, bit.velocity, dt, contact=0.1)
print(f"without noise: k {rock_clean['k']:.6g} N/m, k_u {rock_clean['k_u']:.6g} N/m; low-passed: k "
      f"{rock_alike['k']:.4g} N/m, k_u {rock_alike['k_u']:.4g} N/m")
print(f"with {NOISE:.0%} noise: k {rock['k']:.4g} +- {rock['k_std']:.2g} N/m, k_u {rock['k_u']:.4g} +- "
      f"{rock['k_u_std']:.2g} N/m")


def curve_fit_of_seed(seed):
    """The rock from the curve, the noise drawn with ``seed``."""
    draw = np.random.default_rng(seed)
    noisy = (e + NOISE * peak_strain * draw.standard_normal(time.size) for e in (near_clean, far_clean))
    h = end_history(separate_two_point(time, *noisy, NEAR, FAR, rod, baseline=quiet, cutoff=cutoff), rod)
    return fit_bilinear_rock(h.force, h.velocity, dt, contact=0.1)


seeds = [curve_fit_of_seed(s) for s in range(100, 120)]
for name in ("k", "k_u"):
    values, errors = (np.array([r[key] for r in seeds]) for key in (name, f"{name}_std"))
    print(f"over {len(seeds)} other seeds: {name} {values.mean():.4g} N/m, scatter {values.std(ddof=1):.2g} "
          f"N/m (its standard error {errors.mean():.2g} N/m)")

# %%
# The model's blow fitted to the gauges
# -------------------------------------
# :func:`~impactbar.measure.fit_blow` needs no separation and no low-pass: it varies the blow's
# parameters (by the configuration's dotted names) until the model's strains at the two stations
# match the recorded ones in the least squares, and gives each parameter a standard error from the
# fit's Jacobian. Started well off, it returns the impact velocity and both stiffnesses that made the
# strains; its misfit is the noise's share of the signal.
start = {**TRUE, "impact_velocity": 8.0, "rock.k": 2e8, "rock.k_u": 2e9}
fit = fit_blow(time, {length - NEAR: near, length - FAR: far}, ROD, **PISTON, values=start,
               vary=["impact_velocity", "rock.k", "rock.k_u"])
for name, error in fit.errors.items():
    print(f"{name}: {fit.values[name]:.5g} +- {error:.2g} (made with {TRUE[name]:.5g})")
print(f"misfit {fit.misfit:.2%} after {fit.evaluations} blows")
fig, ax = plt.subplots(figsize=(7, 3.6), layout="constrained")
fit.comparisons[length - NEAR].plot(ax, label="strain")
ax.set_title(f"the fitted blow at the gauge {NEAR} m from the bit")
plt.show()
