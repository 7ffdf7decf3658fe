"""
A Kolsky bar test from its raw channels
=======================================

One test of a miniature split-Hopkinson (Kolsky) bar, published with LANL's HopPyBar under the BSD
3-Clause licence (its notice is in ``examples/data/LICENSE.shpb_pmma13``): a PMMA specimen between
two 7075-T6 aluminium bars 2.11 mm square, struck by a 25.4 mm striker, recorded by four
oscilloscope channels at 8 ns, two gauges on each bar. The repository ships the part of the record
that holds the pulses (``examples/data/shpb_pmma13.npz``). Here we go from its voltages to the
striker's impact velocity and the specimen's stress-strain curve with the calls that
``impactbar measure examples/shpb_pmma13.toml`` makes (:doc:`../measurements` says what each step
is), and look at what a test engineer checks on the way: the windows the code chose, the two gauges
of each bar against each other, the force balance on the specimen and the noise.
"""

# %%
# The recording
# -------------
# :meth:`~impactbar.measure.Recording.from_npz` reads the stored channels in volts on one time base
# (s, from the oscilloscope's trigger).
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from impactbar.measure import Bar, Gauge, Recording, analyse_kolsky

try:  # (run as a file: the repository's; in the docs' build: from the docs folder)
    ROOT = Path(__file__).resolve().parents[2]
except NameError:
    ROOT = Path.cwd().parents[1]
recording = Recording.from_npz(ROOT / "examples" / "data" / "shpb_pmma13.npz")
time, dt = recording.time, recording.dt
print(f"{len(recording.channels)} channels ({', '.join(recording.channels)}), {time.size} samples at "
      f"{dt * 1e9:.0f} ns, from {time[0] * 1e6:.1f} us to {time[-1] * 1e6:.1f} us")

fig, ax = plt.subplots(figsize=(7, 3.6), layout="constrained")
for name, volts in recording.channels.items():
    ax.plot(time * 1e6, volts * 1e3, lw=0.6, label=name)
ax.set(xlabel="time (us)", ylabel="voltage (mV)", title="the four channels as recorded")
ax.legend(fontsize=8)
plt.show()

# %%
# The test's metadata
# -------------------
# The bars (Young's modulus, density, section), each channel's bridge, gauge factor, excitation, gain
# and its station (the distance from the specimen's face), the specimen and the striker, as the
# test's metadata file gives them (``examples/shpb_pmma13.toml`` states the same for the command
# line). The quiet samples before the trigger, -30 us to -2 us, give each channel's offset and the
# noise the pulses are found against.
aluminium = Bar(young_modulus=71.7e9, density=2810.0, area=4.4521e-6)
bridge = {"bridge": "half", "gauge_factor": 2.1, "excitation": 10.0, "gain": 100.0}
gauges = {"ch1": Gauge("incident", 0.10202, **bridge), "ch2": Gauge("incident", 0.10202, **bridge),
          "ch3": Gauge("transmitted", 0.10135, **bridge), "ch4": Gauge("transmitted", 0.10135, **bridge)}
baseline = slice(*(int(k) for k in np.searchsorted(time, [-30e-6, -2e-6])))
print(f"bars' wave speed {aluminium.wave_speed:.1f} m/s, impedance {aluminium.impedance:.3f} N s/m; "
      f"one volt at ch1 is a strain of {gauges['ch1'].strain_per_volt:.6g}")

# %%
# The analysis
# ------------
# :func:`~impactbar.measure.analyse_kolsky` converts each channel to strain, averages the gauges of
# each bar, finds the pulses where a bar's strain leaves its noise band (no window picked by hand),
# shifts them to the specimen's faces with the wave speed and computes what follows from them. Its
# ``report`` holds every number, its arrays the histories.
test = analyse_kolsky(recording, gauges, aluminium, aluminium, specimen_length=1.47e-3,
                      specimen_area=1.862e-6, striker_length=0.0254, baseline=baseline)
report = test.report

# %%
# The windows the code chose
# --------------------------
# The incident pulse is the first on the incident bar, the reflected one the next of the other sign,
# the transmitted one the first on the transmitted bar. Each window runs from the pulse's foot to its
# tail; below, each bar's strain with its windows shaded.
for name, w in report["windows"].items():
    print(f"{name:12s} window {w['start_us']:8.3f} .. {w['stop_us']:8.3f} us, peak strain "
          f"{w['peak'] * 1e3:+.3f}e-3")
a = report["arrivals"]
print(f"the reflected foot comes {a['reflected_early_us']:.2f} us before the computed "
      f"{a['reflected_computed_us']:.2f} us; the transmitted one {a['transmitted_late_us']:.2f} us after "
      f"the computed {a['transmitted_computed_us']:.2f} us")

fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 5), layout="constrained")
for ax, bar in zip(axes, ("incident", "transmitted"), strict=True):
    ax.plot(test.record_time * 1e6, test.bar_strain[bar] * 1e3, lw=0.6, color="k")
    for (name, w), color in zip(test.windows.items(), ("C0", "C2", "C1"), strict=True):
        if (bar == "transmitted") == (name == "transmitted"):
            ax.axvspan(w.t_start * 1e6, w.t_stop * 1e6, color=color, alpha=0.25, label=name)
    ax.set(ylabel="strain (1e-3)", title=f"the {bar} bar (mean of its two gauges)")
    ax.legend(fontsize=8)
axes[1].set_xlabel("time (us)")
plt.show()

# %%
# The reflection's delay, fitted
# ------------------------------
# The reflected pulse's foot comes early: read as a wave speed it is far from the bars' own. Fitting
# the whole echo as the incident pulse delayed and scaled (:func:`~impactbar.measure.fit_reflection`)
# says the same: the reflection starts where the incident ramp first loads the specimen, and the
# echo is no copy of the pulse (its misfit), so its delay is not the bar's.
f = a["reflection_fit"]
print(f"reflection's delay {f['delay_us']:.3f} +- {f['delay_std_us']:.3f} us, as a wave speed "
      f"{f['wave_speed_m_s']:.0f} +- {f['wave_speed_std_m_s']:.0f} m/s (the bars' {aluminium.wave_speed:.0f} "
      f"m/s); ratio {f['ratio']:.3f}, misfit {100 * f['misfit']:.0f} %")

# %%
# The gauge check
# ---------------
# Two gauges sit at one station of each bar: the second's least-squares scale on the first over the
# bar's pulse, and their r.m.s. difference point by point, as a fraction of the pulse's peak. A few
# percent is what such gauges give; the analysis averages them and carries half their difference
# into the impact velocity's uncertainty.
for bar, g in report["diagnostics"]["gauges"].items():
    first, second = g["channels"]
    print(f"{bar} bar: {second} = {g['scale']:.4f} x {first}, r.m.s. difference "
          f"{100 * g['rms_difference']:.1f} % of the peak")

fig, axes = plt.subplots(1, 2, figsize=(7.5, 3.2), layout="constrained")
for ax, (bar, pair), window in zip(axes, (("incident", ("ch1", "ch2")), ("transmitted", ("ch3", "ch4"))),
                                   (test.windows["incident"], test.windows["transmitted"]), strict=True):
    k = slice(window.start, window.stop)
    for channel in pair:
        volts = recording.channels[channel]
        strain = gauges[channel].strain(volts - np.median(volts[baseline]))
        ax.plot(time[k] * 1e6, strain[k] * 1e3, lw=0.8, label=channel)
    ax.set(xlabel="time (us)", ylabel="strain (1e-3)", title=f"the {bar} bar's gauges")
    ax.legend(fontsize=8)
plt.show()

# %%
# The waves at the specimen
# -------------------------
# Each pulse alone, shifted from its gauge to the specimen's face by the gauge's travel time, on the
# time from the incident wave's arrival there. The forces on the specimen's two faces follow from
# them; their balance, :math:`2(F_1-F_2)/(F_1+F_2)` where the mean force exceeds 30 % of its peak,
# says how far the specimen is from equilibrium.
fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 5.5), layout="constrained")
for name in ("incident", "reflected", "transmitted"):
    axes[0].plot(test.time * 1e6, getattr(test, name) * 1e3, label=name)
axes[0].set(ylabel="strain (1e-3)", title="the three waves at the specimen's faces")
axes[0].legend(fontsize=8)
axes[1].plot(test.time * 1e6, test.specimen.front_force, label="front face (incident and reflected)")
axes[1].plot(test.time * 1e6, test.specimen.back_force, label="back face (transmitted)")
axes[1].set(xlabel="time from the incident wave's arrival (us)", ylabel="force (N)")
axes[1].legend(fontsize=8)
plt.show()
balance = report["diagnostics"]["force_balance"]
print(f"force balance: median |2 (F1 - F2) / (F1 + F2)| {balance['median_abs']:.3f}, largest "
      f"{balance['max_abs']:.3f}")

# %%
# The striker's impact velocity
# -----------------------------
# A striker of the bar's material and section sends a pulse of particle velocity half its own:
# :math:`V = 2c|\bar\varepsilon|`, the mean strain of the incident pulse's plateau (its samples beyond
# 85 % of the peak). The uncertainty combines the plateau's scatter and half the two gauges'
# difference; the wave speed and the bridges' constants are taken exact.
v = report["impact_velocity"]
print(f"impact velocity {v['velocity']:.2f} +- {v['uncertainty']:.2f} m/s (plateau of "
      f"{v['plateau_samples']} samples, mean strain {v['plateau_strain'] * 1e3:.4f}e-3; scatter "
      f"{v['velocity_std']:.2f} m/s; gauges {v['per_gauge'][0]:.2f} and {v['per_gauge'][1]:.2f} m/s)")

# %%
# The wave energies
# -----------------
# A wave carries :math:`EAc\int\varepsilon^2\,dt`; the specimen absorbs the incident less the
# reflected and the transmitted. The force-velocity integral at the specimen's front face is the
# incident less the reflected, and the striker's kinetic energy :math:`\rho A L V^2/2` is what the
# incident wave came from.
e = report["energies_J"]
labels = {"incident": "the incident wave", "reflected": "the reflected wave",
          "transmitted": "the transmitted wave", "absorbed": "absorbed by the specimen",
          "force_velocity_at_specimen": "into the specimen's front face (force-velocity)",
          "striker_kinetic": "the striker's kinetic energy"}
for name, value in e.items():
    print(f"{labels[name]}: {value * 1e3:.2f} mJ")
print(f"the incident wave carries {e['incident'] / e['striker_kinetic']:.1%} of the striker's kinetic "
      "energy")

# %%
# The stress-strain curve
# -----------------------
# The one-wave stress is the back face's force over the specimen's section, the two-wave the front
# face's, the three-wave their mean; the strain is the strain rate's integral (one- and two-wave
# :math:`2c\varepsilon_R/L_s`, three-wave the faces' velocities' difference over the length).
fig, (curves, rates) = plt.subplots(1, 2, figsize=(8, 3.6), layout="constrained")
for k in ("1", "2", "3"):
    curves.plot(test.specimen.strain[k], test.specimen.stress[k] / 1e6, label=f"{k}-wave")
    rates.plot(test.time * 1e6, test.specimen.strain_rate[k], label=f"{k}-wave")
curves.set(xlabel="engineering strain", ylabel="stress (MPa)", title="the specimen's stress-strain")
rates.set(xlabel="time (us)", ylabel="strain rate (1/s)", title="its strain rate")
curves.legend(fontsize=8)
plt.show()
for k, s in report["stress_strain"].items():
    print(f"{k}-wave: peak stress {s['peak_stress_MPa']:.1f} MPa at strain {s['strain_at_peak']:.4f}, final "
          f"strain {s['final_strain']:.4f}, mean strain rate {s['mean_strain_rate']:.0f} /s")

# %%
# The noise
# ---------
# The pre-trigger samples' spectrum (Welch's periodogram, as the analysis takes it) shows one line on
# every channel: a pickup, which the pulse detection's 1 MHz low-pass lets through and the plateau's
# mean averages out.
from scipy.signal import welch

fig, ax = plt.subplots(figsize=(7, 3.4), layout="constrained")
for name, volts in recording.channels.items():
    quiet = volts[baseline]
    freq, power = welch(quiet - quiet.mean(), fs=1.0 / dt, nperseg=min(1024, quiet.size))
    ax.semilogy(freq / 1e6, power, lw=0.8, label=name)
ax.set(xlim=(0, 5), xlabel="frequency (MHz)", ylabel="power (V^2/Hz)", title="the pre-trigger noise")
ax.legend(fontsize=8)
plt.show()
for channel, line in report["diagnostics"]["noise_lines"].items():
    print(f"{channel}: a line at {line['frequency_MHz']:.3f} MHz, {line['above_median']:.0f} times the "
          "band's median")
