"""The two measurement tutorials (``docs/tutorials_src/plot_5_kolsky_bar.py`` and
``plot_6_drill_rod_gauges.py``) run, and every number they print is recomputed here.

- The Kolsky bar's: each printed line is rebuilt from ``run_spec`` on ``examples/shpb_pmma13.toml``
  (the path ``impactbar measure`` takes, the metadata read from the spec rather than typed in the
  tutorial), and the numbers that follow from the raw file by a formula (the recording's size, the
  bars' wave speed and impedance, a volt's strain, the impact velocity, the waves' and the striker's
  energies, the noise's line) are recomputed from the stored counts with numpy and scipy alone.
- The drill rod's: the chain is repeated through the same public calls and each printed line
  rebuilt from it; the results are held against the blow that made the strains: the waves at the
  bit to 1e-9 without noise, the rock without noise to the trapezoid's bias, the model's fit within
  three of its standard errors (the noise's bound), and the curve's fit with noise within three
  times the scatter that the same noise gives over other seeds.
"""

import contextlib
import io
import runpy
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
TUTORIALS = ROOT / "docs" / "tutorials_src"


def _run(name: str) -> tuple[list[str], dict]:
    """The tutorial's printed lines and its namespace, its figures closed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        namespace = runpy.run_path(str(TUTORIALS / name), run_name="__main__")
    plt.close("all")
    return out.getvalue().splitlines(), namespace


# --------------------------------------------------------------------------------------------------
# The Kolsky bar's tutorial


@pytest.fixture(scope="module")
def kolsky():
    return _run("plot_5_kolsky_bar.py")


@pytest.fixture(scope="module")
def spec_report():
    from impactbar.measure import run_spec

    return run_spec(ROOT / "examples" / "shpb_pmma13.toml").report


@pytest.fixture(scope="module")
def raw():
    """The stored recording read with numpy alone: time (s) and each channel's strain, its
    pre-trigger median removed (the half bridge: 4 V / (G Vex GF 2))."""
    with np.load(ROOT / "examples" / "data" / "shpb_pmma13.npz") as data:
        t0, dt, scale = float(data["t0"]), float(data["dt"]), float(data["volts_per_code"])
        volts = {c: data[c].astype(float) * scale for c in ("ch1", "ch2", "ch3", "ch4")}
    t = t0 + dt * np.arange(volts["ch1"].size)
    quiet = (t >= -30e-6) & (t < -2e-6)
    per_volt = 4.0 / (100.0 * 10.0 * 2.1 * 2)
    strain = {c: (v - np.median(v[quiet])) * per_volt for c, v in volts.items()}
    return t, dt, volts, strain, quiet


def _kolsky_lines(report, t, dt) -> list[str]:
    """What the tutorial prints, rebuilt from the spec's report and the raw file."""
    c = np.sqrt(71.7e9 / 2810.0)
    lines = [f"4 channels (ch1, ch2, ch3, ch4), {t.size} samples at {dt * 1e9:.0f} ns, from "
             f"{t[0] * 1e6:.1f} us to {t[-1] * 1e6:.1f} us",
             f"bars' wave speed {c:.1f} m/s, impedance {71.7e9 * 4.4521e-6 / c:.3f} N s/m; one volt at ch1 "
             f"is a strain of {4.0 / (100.0 * 10.0 * 2.1 * 2):.6g}"]
    for name, w in report["windows"].items():
        lines.append(f"{name:12s} window {w['start_us']:8.3f} .. {w['stop_us']:8.3f} us, peak strain "
                     f"{w['peak'] * 1e3:+.3f}e-3")
    a = report["arrivals"]
    lines.append(f"the reflected foot comes {a['reflected_early_us']:.2f} us before the computed "
                 f"{a['reflected_computed_us']:.2f} us; the transmitted one "
                 f"{a['transmitted_late_us']:.2f} us after the computed "
                 f"{a['transmitted_computed_us']:.2f} us")
    f = a["reflection_fit"]
    lines.append(f"reflection's delay {f['delay_us']:.3f} +- {f['delay_std_us']:.3f} us, as a wave speed "
                 f"{f['wave_speed_m_s']:.0f} +- {f['wave_speed_std_m_s']:.0f} m/s (the bars' {c:.0f} m/s); "
                 f"ratio {f['ratio']:.3f}, misfit {100 * f['misfit']:.0f} %")
    for bar, g in report["diagnostics"]["gauges"].items():
        lines.append(f"{bar} bar: {g['channels'][1]} = {g['scale']:.4f} x {g['channels'][0]}, r.m.s. "
                     f"difference {100 * g['rms_difference']:.1f} % of the peak")
    b = report["diagnostics"]["force_balance"]
    lines.append(f"force balance: median |2 (F1 - F2) / (F1 + F2)| {b['median_abs']:.3f}, largest "
                 f"{b['max_abs']:.3f}")
    v = report["impact_velocity"]
    lines.append(f"impact velocity {v['velocity']:.2f} +- {v['uncertainty']:.2f} m/s (plateau of "
                 f"{v['plateau_samples']} samples, mean strain {v['plateau_strain'] * 1e3:.4f}e-3; scatter "
                 f"{v['velocity_std']:.2f} m/s; gauges {v['per_gauge'][0]:.2f} and "
                 f"{v['per_gauge'][1]:.2f} m/s)")
    e = report["energies_J"]
    for label, key in (("the incident wave", "incident"), ("the reflected wave", "reflected"),
                       ("the transmitted wave", "transmitted"), ("absorbed by the specimen", "absorbed"),
                       ("into the specimen's front face (force-velocity)", "force_velocity_at_specimen"),
                       ("the striker's kinetic energy", "striker_kinetic")):
        lines.append(f"{label}: {e[key] * 1e3:.2f} mJ")
    lines.append(f"the incident wave carries {e['incident'] / e['striker_kinetic']:.1%} of the striker's "
                 "kinetic energy")
    for k, s in report["stress_strain"].items():
        lines.append(f"{k}-wave: peak stress {s['peak_stress_MPa']:.1f} MPa at strain "
                     f"{s['strain_at_peak']:.4f}, final strain {s['final_strain']:.4f}, mean strain rate "
                     f"{s['mean_strain_rate']:.0f} /s")
    for channel, line in report["diagnostics"]["noise_lines"].items():
        lines.append(f"{channel}: a line at {line['frequency_MHz']:.3f} MHz, {line['above_median']:.0f} "
                     "times the band's median")
    return lines


def test_the_kolsky_tutorial_prints_what_the_spec_gives(kolsky, spec_report, raw):
    """Every line the tutorial prints, rebuilt from ``run_spec`` on the example's spec."""
    printed, namespace = kolsky
    t, dt, *_ = raw
    assert printed == _kolsky_lines(spec_report, t, dt)
    assert namespace["report"] == spec_report


def test_the_kolsky_numbers_from_the_raw_file(spec_report, raw):
    """The impact velocity (2 c times the incident plateau's mean, the samples beyond 85 % of its
    peak, of the two gauges' mean), the waves' energies (E A c times the integral of the squared
    strain over each window) and the striker's kinetic energy, from the stored counts with numpy,
    within 1e-12; the pre-trigger noise's line by scipy's Welch periodogram."""
    from scipy.signal import welch

    t, dt, volts, strain, quiet = raw
    E, rho, A = 71.7e9, 2810.0, 4.4521e-6
    c = np.sqrt(E / rho)
    w = {name: np.searchsorted(t, [d["start_us"] * 1e-6 - dt / 2, d["stop_us"] * 1e-6 + dt / 2])
         for name, d in spec_report["windows"].items()}
    bar = {"incident": (strain["ch1"] + strain["ch2"]) / 2,
           "transmitted": (strain["ch3"] + strain["ch4"]) / 2}
    # the windows' sample ranges: from the sample at the start's time to the one at the stop's
    pulse = {name: bar["transmitted" if name == "transmitted" else "incident"][k0:k1]
             for name, (k0, k1) in w.items()}
    incident = pulse["incident"]
    plateau = incident[incident / incident[np.argmax(np.abs(incident))] >= 0.85]
    v = 2 * c * abs(plateau.mean())
    assert spec_report["impact_velocity"]["velocity"] == pytest.approx(v, rel=1e-12)
    energies = spec_report["energies_J"]
    for name, p in pulse.items():
        assert energies[name] == pytest.approx(E * A * c * np.sum(p ** 2) * dt, rel=1e-12), name
    assert energies["striker_kinetic"] == pytest.approx(0.5 * rho * A * 0.0254 * v ** 2, rel=1e-12)
    for channel, v_ch in volts.items():
        quiet_v = v_ch[quiet]
        f, pxx = welch(quiet_v - quiet_v.mean(), fs=1 / dt, nperseg=min(1024, quiet_v.size))
        band = (f >= 2e5) & (f <= 5e6)
        line = spec_report["diagnostics"]["noise_lines"][channel]["frequency_MHz"]
        assert line == round(f[band][np.argmax(pxx[band])] / 1e6, 3)


# --------------------------------------------------------------------------------------------------
# The drill rod's tutorial


@pytest.fixture(scope="module")
def drill():
    return _run("plot_6_drill_rod_gauges.py")


@pytest.fixture(scope="module")
def chain():
    """The tutorial's computation repeated through the same public calls."""
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

    steel = {"E_Pa": 2.0e11, "density_kg_m3": 8000.0}
    rod_pieces = [RodPiece(length_m=0.5, area_m2=1.2e-3, **steel),
                  RodPiece(length_m=3.0, area_m2=0.8e-3, **steel)]
    piston = {"piston_lengths": [0.3], "piston_areas": [1.0e-3]}
    true = {"impact_velocity": 10.0, "rock.k": 3e8, "rock.k_u": 3e9}
    near_x, far_x, noise = 0.15, 0.20, 0.01
    t = 0.4e-3 + 0.5e-6 * np.arange(2480)
    eps = gauge_strains(rod_pieces, **piston, values=true, stations=[3.5 - near_x, 3.5 - far_x], time=t)
    clean = (eps[3.5 - near_x], eps[3.5 - far_x])
    peak = max(float(np.abs(e).max()) for e in clean)

    def noisy(seed):
        rng = np.random.default_rng(seed)
        return tuple(e + noise * peak * rng.standard_normal(t.size) for e in clean)

    rod = Bar(2.0e11, 8000.0, 0.8e-3)
    quiet = t < 3.3 / 5000.0
    cutoff = 0.8 * 5000.0 / (2 * 0.05)
    dt = 0.5e-6

    def bit_of(near, far, **kw):
        return end_history(separate_two_point(t, near, far, near_x, far_x, rod, **kw), rod)

    lowpassed = {"baseline": quiet, "cutoff": cutoff}
    out = {"t": t, "peak": peak, "noise": noise * peak, "rod": rod, "cutoff": cutoff, "true": true,
           "bit_clean": bit_of(*clean), "bit_alike": bit_of(*clean, **lowpassed),
           "bit": bit_of(*noisy(1), **lowpassed)}
    for name in ("clean", "alike", ""):
        h = out[f"bit_{name}" if name else "bit"]
        out[f"rock_{name}" if name else "rock"] = fit_bilinear_rock(h.force, h.velocity, dt, contact=0.1)
    out["seeds"] = []
    for s in range(100, 120):
        h = bit_of(*noisy(s), **lowpassed)
        out["seeds"].append(fit_bilinear_rock(h.force, h.velocity, dt, contact=0.1))
    out["exact"] = piston_blow(rod_pieces, (3e8, 3e9), lengths=[0.3], areas=[1.0e-3], impact_velocity=10.0)
    near, far = noisy(1)
    out["fit"] = fit_blow(t, {3.5 - near_x: near, 3.5 - far_x: far}, rod_pieces, **piston,
                          values={**true, "impact_velocity": 8.0, "rock.k": 2e8, "rock.k_u": 2e9},
                          vary=["impact_velocity", "rock.k", "rock.k_u"])
    return out


def _exact_units(chain):
    """The exact blow's force (N) and time (s) units: m c^2 / L and L / c (piston_blow's model units)."""
    ex = chain["exact"]
    return ex["mass_kg"] * 5000.0 ** 2 / ex["length_m"], ex["length_m"] / 5000.0


def _drill_lines(ch) -> list[str]:
    """What the tutorial prints, rebuilt from the repeated chain."""
    force_unit, time_unit = _exact_units(ch)
    ex, blow = ch["exact"], ch["exact"]["blow"]
    peak_force = float(np.max(blow.bit_forces)) * force_unit
    force = blow.bit_force(ch["bit_clean"].time / time_unit) * force_unit
    bit, clean, alike = ch["bit"], ch["bit_clean"], ch["bit_alike"]
    lines = [f"wave speed 5000 m/s: the wave reaches the far gauge at {3.3 / 5000 * 1e3:.3f} ms; peak strain "
             f"{ch['peak'] * 1e6:.1f} microstrain, noise {ch['noise'] * 1e6:.2f} microstrain r.m.s.",
             f"the exact blow: peak force {peak_force / 1e3:.1f} kN on the rock, largest penetration "
             f"{blow.max_penetration * ex['length_m'] * 1e3:.3f} mm, work on the rock "
             f"{ex['work_on_rock_J']:.2f} J of the piston's {ex['impact_energy_J']:.0f} J",
             f"without noise: the bit's force within "
             f"{np.max(np.abs(clean.force - force)) / peak_force:.1e} of its peak",
             f"first failing frequency {5000 / 0.1 / 1e3:.1f} kHz, low-passed at "
             f"{ch['cutoff'] / 1e3:.1f} kHz",
             f"with 1% noise: the bit's force off the exact blow's by at most "
             f"{np.max(np.abs(bit.force - force)) / peak_force:.1%} of its peak, off the noise-free one "
             f"low-passed alike by {np.max(np.abs(bit.force - alike.force)) / peak_force:.1%}",
             f"from the gauges: peak force {bit.force.max() / 1e3:.1f} kN, largest penetration "
             f"{bit.displacement.max() * 1e3:.3f} mm, energy into the bit {bit.energy_fv[-1]:.2f} J",
             f"without noise: k {ch['rock_clean']['k']:.6g} N/m, k_u {ch['rock_clean']['k_u']:.6g} N/m; "
             f"low-passed: k {ch['rock_alike']['k']:.4g} N/m, k_u {ch['rock_alike']['k_u']:.4g} N/m",
             f"with 1% noise: k {ch['rock']['k']:.4g} +- {ch['rock']['k_std']:.2g} N/m, k_u "
             f"{ch['rock']['k_u']:.4g} +- {ch['rock']['k_u_std']:.2g} N/m"]
    for name in ("k", "k_u"):
        values = np.array([r[name] for r in ch["seeds"]])
        errors = np.array([r[f"{name}_std"] for r in ch["seeds"]])
        lines.append(f"over 20 other seeds: {name} {values.mean():.4g} N/m, scatter {values.std(ddof=1):.2g} "
                     f"N/m (its standard error {errors.mean():.2g} N/m)")
    fit = ch["fit"]
    for name, error in fit.errors.items():
        lines.append(f"{name}: {fit.values[name]:.5g} +- {error:.2g} (made with {ch['true'][name]:.5g})")
    lines.append(f"misfit {fit.misfit:.2%} after {fit.evaluations} blows")
    return lines


def test_the_drill_rod_tutorial_prints_what_its_chain_gives(drill, chain):
    """Every line the tutorial prints, rebuilt from the chain repeated here."""
    printed, _ = drill
    assert printed == _drill_lines(chain)


def test_the_drill_rods_waves_and_bit_against_the_blow(chain):
    """Without noise the bit's force is the exact blow's to 1e-9 of its peak and the penetration
    (the velocity's trapezoid, which misses a part of a sample's width at each of the velocity's
    jumps, the wave fronts) to 1e-2 of its largest; with 1 % noise, low-passed, the force within
    15 % of the exact blow's peak (the bound of the noise on the gauges carried through the march
    and the low-pass's rounded fronts) and within 3 % of the noise-free strains low-passed alike."""
    force_unit, time_unit = _exact_units(chain)
    blow, L = chain["exact"]["blow"], chain["exact"]["length_m"]
    clean = chain["bit_clean"]
    force = blow.bit_force(clean.time / time_unit) * force_unit
    assert np.max(np.abs(clean.force - force)) < 1e-9 * force.max()
    penetration = np.interp(clean.time / time_unit, blow.times, blow.penetrations) * L
    assert np.max(np.abs(clean.displacement - penetration)) < 1e-2 * blow.max_penetration * L
    assert np.max(np.abs(chain["bit"].force - force)) < 0.15 * force.max()
    assert np.max(np.abs(chain["bit"].force - chain["bit_alike"].force)) < 0.03 * force.max()


def test_the_drill_rods_rock_against_the_values_that_made_it(chain):
    """Without noise the curve gives k and k_u within 1e-3 (the trapezoid's bias at 0.5 us); with
    1 % noise the model's blow fitted to the gauges gives the impact velocity, k and k_u within three
    of its standard errors, and the curve's fit lies within three times the scatter the same noise
    gives over 20 other seeds (its own standard errors undercount it: that scatter is larger)."""
    true = chain["true"]
    for name in ("k", "k_u"):
        assert chain["rock_clean"][name] == pytest.approx(true[f"rock.{name}"], rel=1e-3)
    fit = chain["fit"]
    for name, error in fit.errors.items():
        assert abs(fit.values[name] - true[name]) < 3 * error, name
    for name in ("k", "k_u"):
        scatter = np.std([r[name] for r in chain["seeds"]], ddof=1)
        assert abs(chain["rock"][name] - true[f"rock.{name}"]) < 3 * scatter, name
        assert scatter > np.mean([r[f"{name}_std"] for r in chain["seeds"]])
