"""The SI-units layer (``impactbar.physical``): conversion by eq. 2, the rigid-limit identity in SI,
round trips, unit errors, configs and presets, a measured force curve, and the CLI."""

import argparse
import copy
import json
import math
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import impactbar
from impactbar import BarModel, CosineLoad, FourierLoad, PiecewiseConstantLoad, SquareWaveLoad
from impactbar import physical as ph
from impactbar.cli.physical import add_physical_arguments, run_physical_orbits

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
HAS_ORBITS = hasattr(impactbar, "periodic_orbits")
HAS_SIM = hasattr(impactbar, "simulate") and hasattr(impactbar, "InitialState")
needs_orbits = pytest.mark.skipif(not HAS_ORBITS,
                                  reason="impactbar.periodic_orbits not in this build")
needs_sim = pytest.mark.skipif(not HAS_SIM, reason="impactbar.simulate not in this build")

RHO, E, L, DIA = 7850.0, 210e9, 0.2, 0.04
AREA = math.pi * DIA**2 / 4
MASS = RHO * AREA * L

BASE = {
    "name": "test",
    "bar": {"E": "210 GPa", "density": "7850 kg/m^3", "length": "200 mm", "diameter": "40 mm"},
    "stop": {"restitution": 0.3},
    "drive": {"frequency": "40 Hz"},
    "force": {"kind": "pneumatic", "mean": "800 N", "amplitude": "2150 N"},
    "model": {"n_modes": 0},
}


def config(**sections):
    """BASE with some sections replaced (``None`` deletes one)."""
    c = copy.deepcopy(BASE)
    for k, v in sections.items():
        if v is None:
            c.pop(k, None)
        else:
            c[k] = v
    return c


# ------------------------------------------------------------------------------------------
# conversion (eq. 2) and the rigid-limit identity in SI
# ------------------------------------------------------------------------------------------
def test_conversion_follows_eq2():
    h = ph.Hammer.from_config(config())
    om = 2 * math.pi * 40.0
    c = math.sqrt(E / RHO)
    assert h.mass_kg == pytest.approx(MASS, rel=1e-14)
    assert h.s == pytest.approx(c / (L * om), rel=1e-14)
    # p = P / (M L^2 Omega^2) = P / (m L Omega^2): dimensionless (see the module docstring)
    assert h.load.p0 == pytest.approx(800.0 / (MASS * L * om**2), rel=1e-14)
    assert h.load.pk == pytest.approx(2150.0 / (MASS * L * om**2), rel=1e-14)
    assert h.model == BarModel(s=h.s, d=0.0, R=0.3, n_modes=0)
    assert h.scales.velocity_m_s == pytest.approx(L * om, rel=1e-14)


@pytest.mark.parametrize("k", [1, 2, 5])
@pytest.mark.parametrize("R", [0.0, 0.3, 0.9])
def test_rigid_limit_identity_si(k, R):
    # v = F_mean / (f_b m (1 + R)), f_b = f / k: written from the SI inputs only
    force = {"kind": "pneumatic", "mean": "800 N", "amplitude": "2150 N", "k": k}
    h = ph.Hammer.from_config(config(force=force, stop={"restitution": R}))
    v = 800.0 / ((40.0 / k) * MASS * (1 + R))
    assert h.blow_frequency_Hz == pytest.approx(40.0 / k)
    assert h.rigid_impact_velocity_m_s == pytest.approx(v, rel=1e-13)
    # the dimensionless identity 2 pi p0 / (1 + R) carried back by L Omega
    v_dimless = 2 * math.pi * h.load.p0 / (1 + R)
    assert v_dimless * h.scales.velocity_m_s == pytest.approx(v, rel=1e-13)


@needs_orbits
@pytest.mark.parametrize(("k", "R"), [(1, 0.3), (1, 0.6), (2, 0.6)])  # orbits exist (eq. 38)
def test_rigid_limit_identity_orbits(k, R):
    force = {"kind": "pneumatic", "mean": "800 N", "amplitude": "2150 N", "k": k}
    h = ph.Hammer.from_config(config(force=force, stop={"restitution": R}))
    found = ph.orbits(h)
    assert found
    fb = 40.0 / k  # one blow every k cycles of the force
    v = 800.0 / (fb * MASS * (1 + R))
    for o in found:
        assert o.impact_velocity_m_s == pytest.approx(v, rel=1e-9)
        assert o.impact_energy_J == pytest.approx(0.5 * MASS * v * v, rel=1e-9)
        assert o.impact_power_kW == pytest.approx(0.5 * MASS * v * v * fb / 1e3, rel=1e-9)
        assert o.blow_frequency_Hz == fb


# ------------------------------------------------------------------------------------------
# round trips SI <-> dimensionless
# ------------------------------------------------------------------------------------------
BAR = ph.Bar(E_Pa=E, density_kg_m3=RHO, length_m=L, area_m2=AREA)


@settings(max_examples=60, deadline=None)
@given(s=st.floats(0.5, 500), d=st.floats(0, 2), R=st.floats(0, 1), p0=st.floats(-1, 1),
       pk=st.floats(-2, 2), k=st.integers(1, 6), n=st.integers(0, 8))
def test_round_trip_pneumatic(s, d, R, p0, pk, k, n):
    model, load = BarModel(s=s, d=d, R=R, n_modes=n), CosineLoad(p0, pk, k)
    h = ph.Hammer.from_dimensionless(model, load, BAR)
    m2, l2 = h.model, h.load
    for a, b in [(m2.s, s), (m2.d, d), (m2.R, R), (l2.p0, p0), (l2.pk, pk)]:
        assert a == pytest.approx(b, rel=1e-12, abs=1e-15)
    assert (m2.n_modes, l2.k) == (n, k)


@settings(max_examples=40, deadline=None)
@given(s=st.floats(0.5, 500), q=st.floats(1e-3, 2), kappa=st.floats(1, 2))
def test_round_trip_square_wave(s, q, kappa):
    h = ph.Hammer.from_dimensionless(BarModel(s=s, d=0.1, R=0.2, n_modes=3),
                                     SquareWaveLoad(q, kappa), BAR)
    assert isinstance(h.force, ph.HydraulicForce)
    back = h.load
    assert h.model.s == pytest.approx(s, rel=1e-12)
    if kappa < 2:
        assert isinstance(back, SquareWaveLoad)
        assert back.q == pytest.approx(q, rel=1e-12)
        assert back.kappa == pytest.approx(kappa, rel=1e-12)
    assert back.p0 == pytest.approx(q * (kappa - 1), rel=1e-12, abs=1e-15)


def test_round_trip_asymmetric_hydraulic():
    load = PiecewiseConstantLoad([0.0, 1.0], [0.05, -0.01])
    h = ph.Hammer.from_dimensionless(BarModel(s=30, d=0.0, R=0.1, n_modes=2), load, BAR)
    back = h.load
    assert isinstance(back, PiecewiseConstantLoad) and not isinstance(back, SquareWaveLoad)
    np.testing.assert_allclose(back.breaks, [0.0, 1.0], rtol=1e-14)
    np.testing.assert_allclose(back.levels, [0.05, -0.01], rtol=1e-12)


@pytest.mark.parametrize("name", sorted(ph.PRESETS))
def test_round_trip_si(name):
    h = ph.preset(name)
    back = ph.Hammer.from_dimensionless(h.model, h.load, h.bar, stop_area_m2=h.stop_area_m2)
    assert back.frequency_Hz == pytest.approx(h.frequency_Hz, rel=1e-13)
    assert back.damping_N_s_m2 == pytest.approx(h.damping_N_s_m2, rel=1e-13)
    assert back.R == pytest.approx(h.R, rel=1e-13)
    for f in ("mean_N", "amplitude_N", "high_N", "low_N", "fraction"):
        if hasattr(h.force, f):
            assert getattr(back.force, f) == pytest.approx(getattr(h.force, f), rel=1e-12)


def test_round_trip_refuses_inconsistent_stop():
    with pytest.raises(ValueError, match="not the model's R"):
        ph.Hammer.from_dimensionless(BarModel(s=30, d=0, R=0.5, n_modes=0), CosineLoad(0.1, 0.3),
                                     BAR, stop_area_m2=AREA)


# ------------------------------------------------------------------------------------------
# units
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("section", "key", "value", "match"),
    [
        ("bar", "length", 0.2, r"bar\.length needs a unit"),
        ("bar", "E", 210e9, r"bar\.E needs a unit"),
        ("bar", "length", "200 kg", r"bar\.length must be a length"),
        ("bar", "E", "210 GPx", r"bar\.E: cannot read"),
        ("bar", "length", "0.2", r"bar\.length needs a unit"),
        ("force", "mean", "0,8 kN", r"force\.mean: cannot read .* no thousands separators"),
        ("force", "mean", "400 N + 400 N", r"force\.mean: cannot read"),
        ("force", "mean", "800 N 2", r"force\.mean: cannot read the unit"),
        ("bar", "density", "7850 kg/m^2", r"bar\.density must be a density"),
        ("bar", "diameter", "-40 mm", r"bar\.diameter must be"),
        ("drive", "frequency", "251 rad/s", r"drive\.frequency must not be given in angular"),
        ("drive", "frequency", "2400 rpm", r"drive\.frequency must not be given in angular"),
        ("drive", "frequency", 40, r"drive\.frequency needs a unit"),
        ("force", "mean", "800 N*m", r"force\.mean must be a force"),
        ("force", "amplitude", "nan N", r"force\.amplitude must be finite"),
        ("stop", "restitution", "0.3 m", r"stop\.restitution must be"),
        ("stop", "restitution", 1.5, r"stop\.restitution must be in \[0, 1\]"),
    ],
)
def test_unit_errors(section, key, value, match):
    c = config()
    c[section][key] = value
    with pytest.raises(ValueError, match=match):
        ph.Hammer.from_config(c)


def test_units_accepted_in_any_form():
    import pint

    other = pint.UnitRegistry()  # a quantity of another registry is converted, not refused
    c = config(drive={"frequency": "2400 bpm"})
    c["bar"] = {"E": other.Quantity(210, "GPa"), "density": "7.85 g/cm^3", "length": "0.2 m",
                "area": f"{AREA * 1e4!r} cm^2"}
    c["stop"] = {"restitution": "30 percent"}
    c["force"] = {"kind": "pneumatic", "mean": "0.8 kN", "amplitude": "2150 kg*m/s^2"}
    h = ph.Hammer.from_config(c)
    ref = ph.Hammer.from_config(config())
    assert h.frequency_Hz == pytest.approx(40.0, rel=1e-14)
    assert h.R == pytest.approx(0.3)
    for a, b in [(h.s, ref.s), (h.load.p0, ref.load.p0), (h.load.pk, ref.load.pk)]:
        assert a == pytest.approx(b, rel=1e-12)


def test_core_does_not_import_pint():
    code = ("import sys, impactbar; import impactbar.loads, impactbar.model; "
            "impactbar.physical.PRESETS; assert 'pint' not in sys.modules, 'pint imported'")
    subprocess.run([sys.executable, "-c", code], check=True)


# ------------------------------------------------------------------------------------------
# configuration keys
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("mutate", "match"),
    [
        (lambda c: c.update(bars={}), r"unknown key 'bars'"),
        (lambda c: c["bar"].update(lenght="1 m"), r"unknown key bar\.lenght"),
        (lambda c: c["force"].update(fraction=0.5), r"force\.fraction does not apply"),
        (lambda c: c["force"].update(kind="electric"), r"force\.kind must be one of"),
        (lambda c: c["model"].update(modes=3), r"unknown key model\.modes"),
        (lambda c: c["bar"].pop("E"), r"missing key bar\.E"),
        (lambda c: c.pop("drive"), r"missing section \[drive\]"),
        (lambda c: c["bar"].update(area="12 cm^2"), r"exactly one of bar\.diameter and bar\.area"),
        (lambda c: c["stop"].update(area="20 cm^2"), r"exactly one of stop\.restitution and stop"),
        (lambda c: c.update(stop={"area": "10 cm^2"}), r"stop\.area must be at least"),
        (lambda c: c.update(damping={"ratio": 0.1, "coefficient": "1 N*s/m"}), r"at most one"),
        (lambda c: c.update(damping={"coefficient": "1 N/m"}), r"damping\.coefficient must be"),
        (lambda c: c.update(damping={"coefficient": 2.0}), r"damping\.coefficient needs a unit"),
        (lambda c: c["model"].update(n_modes=2.5), r"model\.n_modes must be an integer"),
        (lambda c: c["force"].update(k=0), r"force\.k must be an integer in \[1, 4096\]"),
    ],
)
def test_config_errors_name_the_key(mutate, match):
    c = config()
    mutate(c)
    with pytest.raises(ValueError, match=match):
        ph.Hammer.from_config(c)


def test_hydraulic_config_and_levels():
    f = {"kind": "hydraulic", "high": "20 kN", "low": "-20 kN", "fraction": 0.6}
    h = ph.Hammer.from_config(config(force=f))
    assert isinstance(h.load, SquareWaveLoad) and h.load.kappa == pytest.approx(1.2)
    assert h.mean_force_N == pytest.approx(20e3 * 0.6 - 20e3 * 0.4)
    f = {"kind": "hydraulic", "high": "15 kN", "low": "-5 kN", "fraction": 0.4}
    h = ph.Hammer.from_config(config(force=f))
    assert type(h.load) is PiecewiseConstantLoad
    assert h.load.p0 * h.scales.force_N == pytest.approx(15e3 * 0.4 - 5e3 * 0.6, rel=1e-12)
    with pytest.raises(ValueError, match=r"force\.low must be"):
        ph.Hammer.from_config(config(force={**f, "low": "20 kN"}))


def test_damping_coefficient_and_ratio():
    total = ph.Hammer.from_config(config(damping={"coefficient": "2.4 N*s/m"}))
    per_length = ph.Hammer.from_config(config(damping={"coefficient": "12 N*s/m^2"}))
    assert total.damping_N_s_m2 == pytest.approx(12.0, rel=1e-14)
    assert per_length.d == pytest.approx(total.d, rel=1e-14)
    assert total.d == pytest.approx(2.4 / (MASS * 2 * math.pi * 40), rel=1e-13)  # d = c/(m Omega)
    zeta = 0.02
    h = ph.Hammer.from_config(config(damping={"ratio": zeta}))
    assert h.d == pytest.approx(2 * zeta * h.s * math.pi, rel=1e-13)
    assert h.damping_ratio == pytest.approx(zeta, rel=1e-13)


def test_stop_bar_and_peak_stress():
    a_s = 2 * AREA
    h = ph.Hammer.from_config(config(stop={"area": f"{a_s!r} m^2"}))
    assert h.R == pytest.approx((a_s - AREA) / (a_s + AREA), rel=1e-14)
    c = math.sqrt(E / RHO)
    assert h.peak_stress_Pa(10.0) == pytest.approx(RHO * c * 10.0 * a_s / (AREA + a_s), rel=1e-13)
    rigid = ph.Hammer.from_config(config(stop={"restitution": 1.0}))
    assert rigid.peak_stress_Pa(10.0) == pytest.approx(RHO * c * 10.0, rel=1e-14)


def test_contact_duration_warning():
    h = ph.Hammer.from_config(config())
    assert h.contact_duration_s == pytest.approx(2 * L / math.sqrt(E / RHO), rel=1e-14)
    assert h.contact_fraction == pytest.approx(1 / (math.pi * h.s), rel=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert h.check_short_impacts()
    long_bar = config()
    long_bar["bar"] = {**BASE["bar"], "length": "3 m"}
    long_bar["drive"] = {"frequency": "200 Hz"}
    with pytest.warns(ph.ImpactDurationWarning, match="contact duration"):
        assert not ph.Hammer.from_config(long_bar).check_short_impacts()


# ------------------------------------------------------------------------------------------
# measured force
# ------------------------------------------------------------------------------------------
def write_csv(path, t, f, header="time_s,force_N"):
    lines = ([header] if header else []) + [f"{float(a)!r},{float(b)!r}"
                                            for a, b in zip(t, f, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return path


def measured_config(path, **force):
    return config(force={"kind": "measured", "csv": str(path), **force})


@pytest.mark.parametrize("n", [64, 200])
def test_measured_curve_reproduces_cosine(tmp_path, n):
    f = 40.0
    t = np.arange(n) / (n * f)
    F = 800.0 + 2150.0 * np.cos(2 * np.pi * f * t)
    h = ph.Hammer.from_config(measured_config(write_csv(tmp_path / "c.csv", t, F)))
    ref = ph.Hammer.from_config(config()).load
    load = h.load
    assert isinstance(load, FourierLoad)
    fit = h.fourier_fit
    assert fit.n_harmonics == 1 and fit.relative_error <= fit.tolerance
    assert load.p0 == pytest.approx(ref.p0, rel=1e-12)
    # the piecewise-linear curve's first harmonic is the cosine's, times sinc^2(pi / n)
    assert load.harmonics()[0] == pytest.approx(ref.pk * np.sinc(1 / n) ** 2, rel=1e-10)
    assert abs(load.harmonics()[0] - ref.pk) < 5.0 / n**2 * abs(ref.pk)
    assert h.rigid_impact_velocity_m_s == pytest.approx(800.0 / (f * MASS * 1.3), rel=1e-12)


def test_measured_curve_units_and_closing_sample(tmp_path):
    f = 40.0
    t = np.linspace(0.0, 1 / f, 101)  # the last sample closes the period
    F = 800.0 + 2150.0 * np.cos(2 * np.pi * f * t)
    a = ph.Hammer.from_config(measured_config(write_csv(tmp_path / "a.csv", t, F)))
    b = ph.Hammer.from_config(measured_config(write_csv(tmp_path / "b.csv", t * 1e3, F / 1e3,
                                                       header="time [ms],force [kN]")))
    c = ph.Hammer.from_config(measured_config(write_csv(tmp_path / "c.csv", t, F, header="")))
    np.testing.assert_allclose(b.load.harmonics(), a.load.harmonics(), rtol=1e-12)
    np.testing.assert_allclose(c.load.harmonics(), a.load.harmonics(), rtol=1e-12)
    assert a.mean_force_N == pytest.approx(800.0, rel=1e-12)


def test_measured_curve_sharp_needs_more_harmonics(tmp_path):
    f = 40.0
    t = np.arange(400) / (400 * f)
    # a hydraulic-like trapezoid: +-20 kN, ramps of 5 % of the period
    F = 20e3 * np.clip(np.minimum(t * f / 0.025 - 1, (0.625 - t * f) / 0.025), -1, 1)
    h = ph.Hammer.from_config(measured_config(write_csv(tmp_path / "sq.csv", t, F),
                                              tolerance=0.02))
    fit = h.fourier_fit
    assert 20 < fit.n_harmonics <= 256
    assert fit.relative_error <= 0.02
    assert h.mean_force_N == pytest.approx(4000.0, rel=1e-12)
    # independent check of the series: the dimensionless load against the curve, on a fine grid
    tt = np.linspace(0, 1 / f, 20001)
    series = h.load(tt / h.scales.time_s) * h.scales.force_N
    curve = np.interp(tt, np.append(t, 1 / f), np.append(F, F[0]))
    assert np.max(np.abs(series - curve)) <= 0.02 * 40e3 * (1 + 1e-9)
    assert np.max(np.abs(series - curve)) == pytest.approx(fit.max_error_N, rel=0.02)
    with pytest.raises(ValueError, match=r"force\.tolerance: 8 harmonics .* raise force"):
        ph.Hammer.from_config(measured_config(tmp_path / "sq.csv", tolerance=0.01,
                                              max_harmonics=8))


@pytest.mark.parametrize(
    ("t", "header", "match"),
    [
        (np.arange(50) / (50 * 80.0), "time_s,force_N", r"cover .* but one period"),
        (np.arange(50) / (25 * 40.0), "time_s,force_N", r"more than one period"),
        (np.arange(50) / (50 * 40.0), "time [kg],force [N]", r"time column must be"),
        (np.arange(50) / (50 * 40.0), "time_s,force_m", r"force column must be"),
    ],
)
def test_measured_curve_errors(tmp_path, t, header, match):
    path = write_csv(tmp_path / "bad.csv", t, np.cos(2 * np.pi * 40.0 * t), header=header)
    with pytest.raises(ValueError, match=match):
        ph.Hammer.from_config(measured_config(path))


def test_measured_curve_bad_file(tmp_path):
    with pytest.raises(ValueError, match="cannot read"):
        ph.Hammer.from_config(measured_config(tmp_path / "missing.csv"))
    (tmp_path / "x.csv").write_text("0,1\n0.01,abc\n")
    with pytest.raises(ValueError, match="data row 2"):
        ph.Hammer.from_config(measured_config(tmp_path / "x.csv"))


@needs_orbits
def test_measured_cosine_gives_the_cosine_orbits(tmp_path):
    f = 40.0
    t = np.arange(400) / (400 * f)
    F = 800.0 + 2150.0 * np.cos(2 * np.pi * f * t)
    c = measured_config(write_csv(tmp_path / "c.csv", t, F))
    c["model"] = {"n_modes": 4}
    measured = ph.orbits(ph.Hammer.from_config(c))
    c = config(model={"n_modes": 4})
    exact = ph.orbits(ph.Hammer.from_config(c))
    assert len(measured) == len(exact) > 0
    for a, b in zip(measured, exact, strict=True):
        assert a.phase_rad == pytest.approx(b.phase_rad, abs=1e-3)
        assert a.impact_velocity_m_s == pytest.approx(b.impact_velocity_m_s, rel=1e-3)
        assert a.stable == b.stable


# ------------------------------------------------------------------------------------------
# presets and examples
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(ph.PRESETS))
def test_presets_are_realistic(name):
    h = ph.preset(name)
    assert 1.0 <= h.mass_kg <= 10.0
    assert 0.1 <= h.bar.length_m <= 0.5
    assert 30.0 <= h.frequency_Hz <= 70.0
    assert 5.0 <= h.rigid_impact_velocity_m_s <= 12.0
    assert 0.0 < h.R < 1.0
    assert h.contact_fraction < ph.SHORT_IMPACT_LIMIT
    assert 2 * math.pi * h.d == pytest.approx(0.03, rel=0.05)  # the paper's damped case


def test_unknown_preset():
    with pytest.raises(ValueError, match="unknown preset 'x'; available: hydraulic-drill"):
        ph.preset("x")


@pytest.mark.parametrize("name", sorted(ph.PRESETS))
def test_examples_match_presets(name):
    assert ph.load_config(EXAMPLES / f"{name.replace('-', '_')}.toml") == ph.preset(name)


def test_measured_example():
    h = ph.load_config(EXAMPLES / "measured_drill.toml")
    fit = h.fourier_fit
    assert fit.relative_error <= fit.tolerance == 0.01
    assert h.mean_force_N == pytest.approx(800.0, rel=1e-6)
    assert abs(h.load.harmonics()[0]) * h.scales.force_N == pytest.approx(2150.0, rel=1e-3)


@needs_orbits
def test_measured_example_has_the_presets_stable_blow():
    h = ph.load_config(EXAMPLES / "measured_drill.toml")
    good = [o for o in ph.orbits(h) if o.stable]
    assert len(good) == 1
    assert good[0].impact_velocity_m_s == pytest.approx(h.rigid_impact_velocity_m_s, rel=1e-2)


def test_bad_toml(tmp_path):
    (tmp_path / "x.toml").write_text("[bar\n")
    with pytest.raises(ValueError, match="not valid TOML"):
        ph.load_config(tmp_path / "x.toml")
    with pytest.raises(ValueError, match="cannot read the configuration"):
        ph.load_config(tmp_path / "none.toml")


@needs_orbits
def test_pneumatic_preset_has_a_stable_orbit():
    found = ph.orbits(ph.preset("pneumatic-drill"))
    good = [o for o in found if o.admissible and o.stable]
    assert len(good) == 1
    o = good[0]
    assert 5.0 <= o.impact_velocity_m_s <= 12.0
    assert 20.0 <= o.impact_energy_J <= 200.0
    assert 100e6 <= o.peak_piston_stress_Pa <= 400e6


@needs_orbits
def test_hydraulic_preset_orbits_are_unstable():
    found = ph.orbits(ph.preset("hydraulic-drill"))
    assert any(o.admissible for o in found)
    assert not any(o.stable for o in found)  # the paper's conclusion (eq. 41)


# ------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------
def parse(argv):
    p = argparse.ArgumentParser()
    add_physical_arguments(p)
    p.add_argument("--json", action="store_true")
    return p.parse_args(argv)


def test_cli_needs_exactly_one_source():
    with pytest.raises(ValueError, match="give one of CONFIG.toml and --preset"):
        run_physical_orbits(parse([]))
    with pytest.raises(ValueError, match="CONFIG.toml and --preset cannot be used together"):
        run_physical_orbits(parse([str(EXAMPLES / "pneumatic_drill.toml"), "--preset",
                                   "hydraulic-drill"]))
    with pytest.raises(SystemExit):
        parse(["--preset", "nope"])


@needs_orbits
def test_cli_json(capsys):
    assert run_physical_orbits(parse(["--preset", "pneumatic-drill", "--json"])) == 0
    out = json.loads(capsys.readouterr().out)
    h = ph.preset("pneumatic-drill")
    assert out["mass_kg"] == pytest.approx(h.mass_kg)
    assert out["mean_force_N"] == 800.0
    assert out["frequency_Hz"] == 40.0
    assert out["restitution"] == pytest.approx(h.R)
    assert out["orbits"]
    keys = {"impact_velocity_m_s", "impact_energy_J", "impact_power_kW", "admissible", "stable",
            "max_abs_multiplier"}
    for o in out["orbits"]:
        assert keys <= set(o)
        assert o["impact_power_kW"] == pytest.approx(o["impact_energy_J"] * 40.0 / 1e3)


@needs_orbits
def test_cli_table(capsys):
    assert run_physical_orbits(parse([str(EXAMPLES / "measured_drill.toml")])) == 0
    out = capsys.readouterr().out
    assert "measured force: " in out and "v/(m/s)" in out


class FakeTrajectory:
    """A rigid bar bouncing at a fixed rate: enough to exercise the plots and files."""

    def __init__(self, t_end):
        self.impact_times = np.arange(1, int(t_end / (2 * np.pi)) + 1) * 2 * np.pi
        self.impact_velocities = np.full(self.impact_times.size, 0.2)

    def end_displacement(self, t):
        tau = np.mod(np.asarray(t, dtype=float), 2 * np.pi)
        return -0.01 * np.sin(tau / 2)


def test_cli_simulate_outputs(tmp_path, monkeypatch):
    from impactbar import cli

    calls = {}

    class FakeInitialState:
        @staticmethod
        def rigid(end_displacement, velocity):
            calls["initial"] = (end_displacement, velocity)
            return "initial"

    def fake_simulate(model, load, initial, t_end, *, t0=0.0, max_impacts=None):
        calls["t_end"] = t_end
        return FakeTrajectory(t_end)

    from impactbar.physical import results

    monkeypatch.setattr(results, "run_simulation", fake_simulate)
    monkeypatch.setattr(results, "InitialState", FakeInitialState)
    out = tmp_path / "run"
    rc = cli.main(["simulate", "--preset", "pneumatic-drill", "--out", str(out), "--periods", "5",
                   "--gap", "2 mm"])
    assert rc == 0
    assert calls["t_end"] == pytest.approx(10 * np.pi)
    assert calls["initial"] == (pytest.approx(-0.002 / 0.2), 0.0)
    for name in ("motion.png", "blows.png", "impacts.csv", "summary.json"):
        assert (out / name).stat().st_size > 0
    summary = json.loads((out / "summary.json").read_text())
    h = ph.preset("pneumatic-drill")
    v = 0.2 * h.scales.velocity_m_s
    assert summary["n_impacts"] == 5
    assert summary["last_impact_velocity_m_s"] == pytest.approx(v)
    assert summary["mean_impact_energy_J"] == pytest.approx(0.5 * h.mass_kg * v * v)
    assert summary["mean_blow_interval_s"] == pytest.approx(1 / 40)
    assert summary["mean_impact_power_kW"] == pytest.approx(0.5 * h.mass_kg * v * v * 40 / 1e3)
    rows = (out / "impacts.csv").read_text().splitlines()
    assert rows[0] == "impact,time_s,impact_velocity_m_s,impact_energy_J" and len(rows) == 6


def test_cli_simulate_bad_gap(tmp_path):
    from impactbar import cli

    assert cli.main(["simulate", "--preset", "pneumatic-drill", "--out", str(tmp_path),
                     "--gap", "2"]) == 2


@needs_sim
def test_simulate_pneumatic_preset_settles():
    # paper Section 5: below the upper curve of Fig. 5 the pneumatic hammer settles into its
    # stable one-impact motion
    h = ph.preset("pneumatic-drill")
    r = ph.simulate(h, periods=30, gap_m=0.002)
    stable = [o for o in ph.orbits(h) if o.stable]
    assert r.impact_times_s.size > 10
    np.testing.assert_allclose(r.impact_velocities_m_s[-5:], stable[0].impact_velocity_m_s,
                               rtol=1e-3)
    np.testing.assert_allclose(np.diff(r.impact_times_s[-5:]), 1 / 40, rtol=1e-6)
    ts = np.linspace(0, r.t_end_s, 50)
    assert np.all(r.end_displacement_m(ts) <= 1e-12)


def test_simulation_result_takes_scalar_only_trajectories():
    class Scalar(FakeTrajectory):
        def end_displacement(self, t):
            return float(super().end_displacement(float(t)))

    h = ph.preset("pneumatic-drill")
    r = ph.SimulationResult(h, Scalar(4 * np.pi), 2.0 / 40, np.zeros(0), np.zeros(0), np.zeros(0))
    ts = np.linspace(0, 1 / 40, 7)
    u = r.end_displacement_m(ts)
    expect = -0.01 * np.sin(ts / h.scales.time_s / 2) * h.bar.length_m
    np.testing.assert_allclose(u, expect, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(r.end_velocity_m_s(ts[1:-1]),
                               -0.005 * np.cos(ts[1:-1] / h.scales.time_s / 2)
                               * h.scales.velocity_m_s, rtol=1e-5, atol=1e-9)


def test_orbits_subcommand_takes_presets_and_configs(capsys):
    """Runs once the lead's ``impactbar orbits`` calls add_physical_arguments/run_physical_orbits."""
    from impactbar import cli

    pytest.importorskip("impactbar.cli.orbits")
    try:
        args = cli.build_parser().parse_args(["orbits", "--preset", "pneumatic-drill", "--json"])
    except SystemExit:
        pytest.skip("impactbar orbits does not take --preset yet")
    assert args.preset == "pneumatic-drill"
    assert cli.main(["orbits", "--preset", "pneumatic-drill", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["mean_force_N"] == 800.0 and out["frequency_Hz"] == 40.0
    assert any(o["stable"] for o in out["orbits"])
    assert cli.main(["orbits", str(EXAMPLES / "hydraulic_drill.toml")]) == 0
    assert "v/(m/s)" in capsys.readouterr().out
