"""The PMMA-13 Kolsky-bar test (HopPyBar's example, cropped in examples/data) from its raw channels,
and the refusals of bad recordings and specs."""

import json
from pathlib import Path

import numpy as np
import pytest

from impactbar.cli import main
from impactbar.measure import run_spec

ROOT = Path(__file__).resolve().parents[2]
SPEC = ROOT / "examples" / "shpb_pmma13.toml"
NPZ = ROOT / "examples" / "data" / "shpb_pmma13.npz"


@pytest.fixture(scope="module")
def pmma():
    return run_spec(SPEC)


def test_the_pulses_are_found_where_the_bars_predict(pmma):
    """The incident pulse lasts two striker transits (2 x 25.4 mm / 5051 m/s = 10.06 us between its
    ramps' middles); the reflected and transmitted ones come some 2 x 102 mm / c later; the
    reflected foot comes early, as the issue with this record says."""
    w, a = pmma.report["windows"], pmma.report["arrivals"]
    assert -1.5 < w["incident"]["start_us"] < 0 and w["incident"]["sign"] == -1
    assert 10.06 < w["incident"]["stop_us"] - w["incident"]["start_us"] < 10.06 + 3
    assert w["reflected"]["sign"] == 1 and w["transmitted"]["sign"] == -1
    assert 1.0 < a["reflected_early_us"] < 3.0
    assert 0 < a["transmitted_late_us"] < 3.0


def test_the_striker_velocity_and_its_energy(pmma):
    """V = 2 c |eps| (12.5 m/s, HopPyBar's relation); the striker's kinetic energy (rho A L V^2 / 2)
    against the incident wave's, which must not exceed it: the wave carries 92 % of it."""
    v, e = pmma.report["impact_velocity"], pmma.report["energies_J"]
    assert v["velocity"] == pytest.approx(2 * 5051.34 * abs(v["plateau_strain"]), rel=1e-5)
    assert 12.0 < v["velocity"] < 13.0 and 0.2 < v["uncertainty"] < 1.0
    assert min(v["per_gauge"]) < v["velocity"] < max(v["per_gauge"])
    assert 0.85 < e["incident"] / e["striker_kinetic"] < 1.0
    assert e["force_velocity_at_specimen"] == pytest.approx(e["incident"] - e["reflected"], rel=0.02)


def test_the_diagnostics_show_the_faults(pmma):
    """The two gauges of each bar differ by a few per cent; the pickup near 0.7 MHz stands out on
    every channel; the specimen's faces balance to some 10 %."""
    d = pmma.report["diagnostics"]
    for bar in ("incident", "transmitted"):
        assert 0.95 < d["gauges"][bar]["scale"] < 1.05 and 0.01 < d["gauges"][bar]["rms_difference"] < 0.06
    for line in d["noise_lines"].values():
        assert 0.6 < line["frequency_MHz"] < 0.8 and line["above_median"] > 100
    assert 0.02 < d["force_balance"]["median_abs"] < 0.2


def test_the_stress_strain_summary(pmma):
    """The three-wave stress is the mean of the two faces' (one- and two-wave) stresses."""
    s = pmma.specimen
    np.testing.assert_allclose(s.stress["3"], 0.5 * (s.stress["1"] + s.stress["2"]), rtol=1e-12)
    summary = pmma.report["stress_strain"]
    assert 150 < summary["3"]["peak_stress_MPa"] < 200
    assert 0.03 < summary["3"]["final_strain"] < 0.05 and 4000 < summary["3"]["mean_strain_rate"] < 7000


def test_the_cli_prints_the_report_as_json_and_writes_csv(tmp_path, capsys):
    assert main(["measure", str(SPEC), "--json", "--out", str(tmp_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert set(report) == {"windows", "arrivals", "impact_velocity", "energies_J", "stress_strain",
                           "diagnostics"}
    waves = np.loadtxt(tmp_path / "waves.csv", delimiter=",", skiprows=1)
    assert waves.shape[1] == 4 and (tmp_path / "stress_strain.csv").exists()
    assert (tmp_path / "kolsky.png").read_bytes()[:4] == b"\x89PNG"


def _spec(tmp_path, npz, edit=lambda s: s):
    text = SPEC.read_text().replace('file = "data/shpb_pmma13.npz"', f'file = "{npz}"')
    path = tmp_path / "spec.toml"
    path.write_text(edit(text))
    return path


def _npz(tmp_path, change):
    with np.load(NPZ) as data:
        arrays = {k: data[k] for k in data.files}
    change(arrays)
    np.savez(tmp_path / "rec.npz", **arrays)
    return tmp_path / "rec.npz"


@pytest.mark.parametrize("change, edit, message", [
    (lambda a: a.update(ch2=a["ch2"][:-5]), None, "channel 'ch2' has 16245 samples where the time has 16250"),
    (lambda a: a.update(ch3=np.clip(a["ch3"], -9000, 9000)), None, "channel 'ch3' is saturated"),
    (lambda a: a.update(ch3=np.random.default_rng(0).integers(-200, 200, 16250),
                        ch4=np.random.default_rng(1).integers(-200, 200, 16250)),
     None, "no pulse in the transmitted bar"),
    (lambda a: None, lambda s: s.replace('station = "0.10135 m"\n', "", 1),
     "channels.ch3.station is missing"),
    (lambda a: None, lambda s: s.replace('bar = "transmitted"', 'bar = "output"'),
     "channel 'ch3' sits on bar 'output', which the bars do not name"),
])
def test_bad_recordings_are_refused_in_one_line(tmp_path, capsys, change, edit, message):
    spec = _spec(tmp_path, _npz(tmp_path, change), edit or (lambda s: s))
    assert main(["measure", str(spec)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def _bare_si(text):
    """The example spec in the older spelling: every quantity a bare number in SI."""
    import re

    return re.sub(r'"([-+0-9.e]+) (?:Pa|kg/m\^3|m\^2|m|V)"', r"\1", text)


def test_quantities_with_units_and_the_older_bare_si_numbers_give_one_report(tmp_path, capsys):
    assert '"71.7e9 Pa"' in SPEC.read_text()  # (the example writes its quantities with units)
    bare = _spec(tmp_path, NPZ, _bare_si)
    assert '"' not in "".join(ln.split("#")[0] for ln in bare.read_text().splitlines()
                              if ln.split("=")[0].strip() in ("young_modulus", "density", "area", "station",
                                                                "excitation", "length"))
    outputs = []
    for spec in (SPEC, bare):
        assert main(["measure", str(spec), "--json"]) == 0
        outputs.append(json.loads(capsys.readouterr().out))
    assert outputs[0] == outputs[1]


def test_a_bar_takes_the_models_keys_e_and_a_round_bars_diameter(tmp_path):
    from impactbar.measure.spec import read_spec

    area = 4.4521e-6
    d = (4.0 * area / np.pi) ** 0.5
    round_bar = f'E = "71.7 GPa"\ndensity = "2.81 g/cm^3"\ndiameter = "{d * 1e3!r} mm"'
    text = _bare_si(SPEC.read_text()).replace("young_modulus = 71.7e9\ndensity = 2810\narea = 4.4521e-6",
                                              round_bar, 1)
    path = tmp_path / "round.toml"
    path.write_text(text.replace('file = "data/shpb_pmma13.npz"', f'file = "{NPZ}"'))
    spec = read_spec(path)
    from impactbar.measure.spec import _bar

    got, want = _bar(spec, "bars.incident"), _bar(spec, "bars.transmitted")
    assert got.young_modulus == pytest.approx(want.young_modulus, rel=1e-15)
    assert got.density == pytest.approx(want.density, rel=1e-14)
    assert got.area == pytest.approx(want.area, rel=1e-14)


@pytest.mark.parametrize("edit, message", [
    (lambda s: s.replace('density = "2810 kg/m^3"', 'density = "2810 kg"', 1), "bars.incident.density"),
    (lambda s: s.replace('station = "0.10202 m"', 'station = "102 V"', 1), "channels.ch1.station"),
    (lambda s: s.replace('area = "4.4521e-6 m^2"', 'area = "4.4521e-6 m^2"\ndiameter = "2 mm"', 1),
     "bars.incident: give area or diameter, not both"),
    (lambda s: s.replace('density = "2810 kg/m^3"\n', "", 1), "bars.incident.density is missing"),
    (lambda s: s.replace('young_modulus = "71.7e9 Pa"', "young_modulus = [1]", 1),
     "bars.incident.young_modulus"),
])
def test_a_wrong_unit_or_key_of_a_bar_or_channel_is_refused_in_one_line(tmp_path, capsys, edit, message):
    spec = _spec(tmp_path, NPZ, edit)
    assert main(["measure", str(spec)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err
