"""A drill rod's blow from two gauges by ``impactbar measure`` (examples/drill_rod.toml): its
recording is the library's own exact blow with 0.2 % noise, so the waves, the bit's force, the
energy and the rock come out against the blow that made them."""

import json
import runpy
from pathlib import Path

import numpy as np
import pytest

from impactbar.cli import main
from impactbar.measure import run_spec
from impactbar.measure.waves import lowpass

ROOT = Path(__file__).resolve().parents[2]
SPEC = ROOT / "examples" / "drill_rod.toml"
MAKE = runpy.run_path(str(ROOT / "examples" / "data" / "make_drill_rod_blow.py"))


@pytest.fixture(scope="module")
def rod():
    return run_spec(SPEC)


@pytest.fixture(scope="module")
def truth():
    """The blow that made the recording: its bit force (N) and penetration (m) as functions of the
    time from the impact (s), and its work on the rock (J)."""
    from impactbar.physical.piston import _model_units, piston_blow

    true = MAKE["TRUE"]
    b = piston_blow(MAKE["ROD"], (true["rock.k"], true["rock.k_u"]), lengths=[0.3], areas=[1.0e-3],
                    impact_velocity=true["impact_velocity"])
    _, force_N, _, time_s, *_ = _model_units(MAKE["ROD"], true["rock.k"], true["rock.k_u"], b["mass_kg"],
                                             b["length_m"], 2.0e11, 8000.0, None)
    blow = b["blow"]
    return (lambda t: blow.bit_force(t / time_s) * force_N,
            lambda t: blow.exact.penetration(t / time_s) * b["length_m"], b["work_on_rock_J"])


def test_the_stored_recording_is_what_its_script_writes():
    with np.load(ROOT / "examples" / "data" / "drill_rod_blow.npz") as stored:
        made = MAKE["make"]()
        assert set(stored.files) == set(made)
        for key, value in made.items():
            np.testing.assert_array_equal(stored[key], value)


def test_the_bits_force_is_the_blows_low_passed_alike(rod, truth):
    """The waves overlap at both gauges (the pulse, 0.12 ms, is 0.6 m long against the gauges' 0.15 m
    and 0.2 m from the bit); separated, low-passed at 40 kHz, the bit's force is the exact blow's
    force low-passed alike within 1 % of its peak (0.4 % here), its peak within 1 %, the energy into
    the bit within 2 % of the blow's work on the rock and the penetration's peak within 2 %."""
    force, penetration, work = truth
    t = rod.waves.time
    exact = force(t)
    assert np.max(np.abs(rod.bit.force - lowpass(exact, t[1] - t[0], 40e3))) < 0.01 * exact.max()
    bit = rod.report["bit"]
    assert bit["peak_force_kN"] * 1e3 == pytest.approx(exact.max(), rel=0.01)
    assert bit["energy_fv_J"] == pytest.approx(work, rel=0.02)
    assert bit["max_penetration_mm"] * 1e-3 == pytest.approx(penetration(t).max(), rel=0.02)
    # the force-squared form counts the wave coming back as well: it is the incident wave's energy
    assert bit["energy_f2_J"] == pytest.approx(bit["incident_energy_J"], rel=0.01)


def test_the_rock_from_the_curve_and_from_the_models_blow(rod):
    """From the force-penetration curve k comes back within its standard error's 3, k_u 9 % low (the
    low-pass rounds the short unloading: a bias its standard error does not count); the model's blow
    fitted to the gauges gives the impact velocity, k and k_u within 3 standard errors."""
    true = MAKE["TRUE"]
    curve = rod.report["rock_from_curve"]
    assert abs(curve["k"] - true["rock.k"]) < 3 * curve["k_std"]
    assert 0.85 < curve["k_u"] / true["rock.k_u"] < 0.95
    fit = rod.report["model_fit"]
    for name, value in true.items():
        assert abs(fit["values"][name] - value) < 3 * fit["errors"][name], name
    assert fit["misfit"] == pytest.approx(0.01, rel=0.1)  # the noise's share: 0.2 % of the peak


OLD = {  # the older spelling: the gauges' bar as [bars.rod], the model's rod as two lists
    "rod": """[bars.rod]
young_modulus = 2.0e11
density = 8000.0
area = 0.8e-3
""",
    "model": "[model]\nrod_lengths = [0.5, 3.0]\nrod_areas = [1.2e-3, 0.8e-3]\n",
}


def _older(text: str) -> str:
    start = text.index("[[rod.segments]]")
    end = text.index("[channels.near]")
    return (text[:start] + OLD["rod"] + "\n" + text[end:]).replace("[model]\n", OLD["model"])


def test_the_rod_is_the_models_rod_read_by_its_reader():
    """The spec's [[rod.segments]] are a drifter's [rod]: with a [rock] beside them, the model's
    configuration reader (rock_from_config) reads the same pieces the measurement does, and they
    are the rod that made the recording; the gauges' bar is the last segment."""
    import tomllib

    from impactbar.measure.spec import _drill_rod, read_spec
    from impactbar.physical import Bar as Piston
    from impactbar.physical.rock import rock_from_config

    spec = read_spec(SPEC)
    bar, pieces = _drill_rod(spec)
    config = {"rod": tomllib.loads(SPEC.read_text())["rod"], "rock": {"k": "300 kN/mm", "k_u": "3000 kN/mm"}}
    piston = Piston(E_Pa=2.1e11, density_kg_m3=7850.0, length_m=0.3, area_m2=1.0e-3)
    assert rock_from_config(config, piston).segments == pieces == tuple(MAKE["ROD"])
    assert (bar.young_modulus, bar.density, bar.area) == (2.0e11, 8000.0, 0.8e-3)


def test_the_older_spelling_gives_the_same_report(rod, tmp_path):
    """[bars.rod] and model.rod_lengths/rod_areas, the spelling before [rod], still read: the report
    is the same to the last bit."""
    text = SPEC.read_text().replace('file = "data/', f'file = "{ROOT / "examples" / "data"}/')
    (tmp_path / "old.toml").write_text(_older(text))
    assert "[[rod.segments]]" not in _older(text) and "rod_areas" in _older(text)
    assert run_spec(tmp_path / "old.toml").report == rod.report


def test_the_cli_prints_the_report_as_json_and_writes_the_bits_histories(tmp_path, capsys):
    assert main(["measure", str(SPEC), "--json", "--out", str(tmp_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert set(report) == {"separation", "bit", "rock_from_curve", "model_fit"}
    assert report["separation"]["first_failing_Hz"] == pytest.approx(5000.0 / (2 * 0.05))
    bit = np.loadtxt(tmp_path / "bit.csv", delimiter=",", skiprows=1)
    assert bit.shape[1] == 7 and bit[:, 3].max() == pytest.approx(1e3 * report["bit"]["peak_force_kN"])
    assert (tmp_path / "drill_rod.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("edit, message", [
    (lambda s: s.replace("station = 0.20", "station = 0.15"),
     "channels 'near' and 'far' sit at one station (0.15 m)"),
    (lambda s: s.replace("cutoff_hz = 40.0e3", "cutoff_hz = 60.0e3"), "cutoff must lie in (0, 50000) Hz"),
    (lambda s: s.replace("[channels.far]", "[channels.far2]"), "channel 'far2' is not in the recording"),
    (lambda s: s.replace("[bit]\ncutoff_hz = 40.0e3\n", ""), "[specimen] or a drill rod's [bit] is needed"),
    (lambda s: s.replace('bar = "rod"', 'bar = "drill"', 1), "channel 'near' sits on bar 'drill'"),
    (lambda s: s.replace("station = 0.20\n", ""), "channels.far.station is missing"),
    (lambda s: s + '\n[specimen]\nlength = 1e-3\narea = 1e-6\n', "[specimen] or a drill rod's [bit]"),
    # the rod in the model's keys, refused by the model's reader
    (lambda s: s.replace('E = "200 GPa"\n', "", 1), "missing key rod.segments[0].E"),
    (lambda s: s.replace('area = "0.8e-3 m^2"', 'area = "-0.8e-3 m^2"'), "rod.segments[1].area"),
    (lambda s: s.replace('area = "0.8e-3 m^2"', 'area = "0.8e-3 m"'), "rod.segments[1].area must be an area"),
    (lambda s: s.replace('area = "0.8e-3 m^2"', 'area = "0.8e-3 m^2"\ndiameter = "32 mm"'),
     "give exactly one of rod.segments[1].diameter and rod.segments[1].area"),
    (lambda s: s.replace('length = "3.0 m"', 'length = "3.0 m"\nlenght = "1 m"'),
     "unknown key rod.segments[1].lenght"),
    (lambda s: s.replace('length = "3.0 m"', 'length = "0.18 m"'),
     "channels.far.station must lie on the rod's last segment, 0 <= x < 0.18 m"),
    (lambda s: s.replace("[model]\n", "[model]\nrod_lengths = [0.5, 3.0]\n"),
     "model.rod_lengths: the model's rod is [rod]'s segments"),
    (lambda s: s + '\n[bars.rod]\nyoung_modulus = 2e11\ndensity = 8000.0\narea = 0.8e-3\n',
     "[rod] (its [[rod.segments]], the model's keys) or the older [bars.rod], not both"),
])
def test_bad_specs_are_refused_in_one_line(tmp_path, capsys, edit, message):
    text = SPEC.read_text().replace('file = "data/', f'file = "{ROOT / "examples" / "data"}/')
    (tmp_path / "spec.toml").write_text(edit(text))
    assert main(["measure", str(tmp_path / "spec.toml")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
