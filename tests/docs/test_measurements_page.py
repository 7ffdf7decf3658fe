"""The measurements page: its console output is what ``impactbar measure`` prints, its Python runs,
and every number its prose quotes from the PMMA-13 test is recomputed."""

import contextlib
import io
import os
import re
from pathlib import Path

import numpy as np
import pytest

from impactbar.cli import main
from impactbar.measure import run_spec

ROOT = Path(__file__).resolve().parents[2]
PAGE = (ROOT / "docs" / "measurements.md").read_text()
TEXT = re.sub(r"\s+", " ", PAGE)


@pytest.fixture(scope="module")
def report():
    return run_spec(ROOT / "examples" / "shpb_pmma13.toml").report


@pytest.mark.parametrize("spec", ["examples/shpb_pmma13.toml", "examples/drill_rod.toml"])
def test_the_console_block_is_what_the_command_prints(spec):
    blocks = dict(re.findall(r"```console\n\$ impactbar measure (\S+)\n(.*?)```", PAGE, re.S))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["measure", str(ROOT / spec)]) == 0
    assert out.getvalue() == blocks[spec]


def test_the_drill_rods_prose_numbers():
    """The exact blow's numbers the page quotes, and its noise, from the script that made the data."""
    import runpy

    from impactbar.physical.piston import piston_blow

    make = runpy.run_path(str(ROOT / "examples" / "data" / "make_drill_rod_blow.py"))
    true = make["TRUE"]
    b = piston_blow(make["ROD"], (true["rock.k"], true["rock.k_u"]), lengths=[0.3], areas=[1.0e-3],
                    impact_velocity=true["impact_velocity"])
    assert _quoted(r"penetration of ([0-9.]+) mm and does") == round(1e3 * b["blow"].max_penetration
                                                                      * b["length_m"], 3)
    assert _quoted(r"does ([0-9.]+) J of work on the rock") == round(b["work_on_rock_J"], 2)
    assert _quoted(r"\(of the piston's ([0-9]+) J\)") == round(b["impact_energy_J"])
    test = run_spec(ROOT / "examples" / "drill_rod.toml")
    from impactbar.physical.piston import _model_units

    _, force_N, *_ = _model_units(make["ROD"], true["rock.k"], true["rock.k_u"], b["mass_kg"], b["length_m"],
                                  2.0e11, 8000.0, None)
    peak = float(b["blow"].bit_force(test.waves.time / (b["length_m"] / 5000.0)).max()) * force_N
    assert _quoted(r"peak force of ([0-9.]+) kN at the bit") == round(peak / 1e3, 1)
    k_u = test.report["rock_from_curve"]["k_u"]
    assert _quoted(r"the unloading one ([0-9]+) % low") == round(100 * (1 - k_u / true["rock.k_u"]))
    from impactbar.measure.waves import lowpass

    t = test.waves.time
    exact = b["blow"].bit_force(t / (b["length_m"] / 5000.0)) * force_N
    alike = np.max(np.abs(test.bit.force - lowpass(exact, t[1] - t[0], 40e3))) / peak
    assert alike < _quoted(r"low-passed alike they agree within ([0-9.]+) %") / 100
    from impactbar.measure import gauge_strains

    length = sum(p.length_m for p in make["ROD"])
    t = make["T0"] + make["DT"] * np.arange(make["N"])
    eps = gauge_strains(make["ROD"], **make["PISTON"], values=true, time=t,
                        stations=[length - x for x in make["STATIONS"].values()])
    peak = max(float(np.max(np.abs(e))) for e in eps.values())
    noise = 1e6 * make["NOISE"] * peak
    assert _quoted(r"0.2 % of the peak strain \(([0-9.]+) microstrain\)") == round(noise, 1)


def test_the_python_blocks_run(monkeypatch):
    monkeypatch.chdir(ROOT)
    for code in re.findall(r"```python\n(.*?)```", PAGE, re.S):
        with contextlib.redirect_stdout(io.StringIO()):
            exec(compile(code, "measurements.md", "exec"), {})


def _quoted(pattern: str) -> float:
    m = re.search(pattern, TEXT)
    assert m is not None, f"the quote {pattern!r} is gone from the page; update this test with the text"
    return float(m.group(1))


def test_the_prose_numbers(report):
    w, a, v, e = report["windows"], report["arrivals"], report["impact_velocity"], report["energies_J"]
    assert _quoted(r"The incident window lasts ([0-9.]+) us") == round(
        w["incident"]["stop_us"] - w["incident"]["start_us"], 1)
    assert _quoted(r"one's foot \(([0-9.]+) us with") == round(a["reflected_computed_us"], 2)
    assert _quoted(r"its foot comes ([0-9.]+) us earlier") == round(a["reflected_early_us"], 2)
    assert _quoted(r"that would be ([0-9]+) m/s") == round(a["incident_bar_wave_speed_from_reflection"])
    assert _quoted(r"plateau's scatter \(([0-9.]+) m/s\)") == round(v["velocity_std"], 2)
    assert _quoted(r"two gauges' difference \(([0-9.]+) m/s\)") == round(
        0.5 * (max(v["per_gauge"]) - min(v["per_gauge"])), 2)
    assert _quoted(r"kinetic energy \$[^$]+\$ is ([0-9.]+) mJ") == round(1e3 * e["striker_kinetic"], 2)
    assert _quoted(r"the incident wave carries ([0-9.]+) mJ") == round(1e3 * e["incident"], 2)
    assert _quoted(r"mJ \(([0-9]+) %\)") == round(100 * e["incident"] / e["striker_kinetic"])
    into = e["force_velocity_at_specimen"]
    assert _quoted(r"\(([0-9.]+) mJ into the specimen's face") == round(1e3 * into, 2)
    g = report["diagnostics"]["gauges"]
    assert _quoted(r"they differ by ([0-9.]+) %") == round(100 * (g["incident"]["scale"] - 1), 1)
    second = round(100 * (g["transmitted"]["scale"] - 1), 1)
    assert _quoted(r"they differ by [0-9.]+ % and ([0-9.]+) %") == second
    for bar in g.values():
        assert _quoted(r"in scale, ([0-9]+) % of the peak") == round(100 * bar["rms_difference"])
    balance = report["diagnostics"]["force_balance"]["median_abs"]
    assert _quoted(r"peak: ([0-9]+) % at the median") == round(100 * balance)
    s = report["stress_strain"]
    assert _quoted(r"two-wave stresses \(([0-9]+) and") == round(s["1"]["peak_stress_MPa"])
    assert _quoted(r"two-wave stresses \([0-9]+ and ([0-9]+) MPa\)") == round(s["2"]["peak_stress_MPa"])
    assert min(s["1"]["peak_stress_MPa"], s["2"]["peak_stress_MPa"]) < s["3"]["peak_stress_MPa"] \
        < max(s["1"]["peak_stress_MPa"], s["2"]["peak_stress_MPa"])
    lines = {n["frequency_MHz"] for n in report["diagnostics"]["noise_lines"].values()}
    assert lines == {_quoted(r"one line, at ([0-9.]+) MHz on every channel")}
    size = os.path.getsize(ROOT / "examples" / "data" / "shpb_pmma13.npz")
    assert size // 1000 == _quoted(r"\(`examples/data/shpb_pmma13.npz`, ([0-9]+) kB\)")


def test_the_fit_blocks_output_is_what_it_prints():
    code = re.search(r"## The model beside the measurement.*?```python\n(.*?)```", PAGE, re.S).group(1)
    shown = re.search(r"## The model beside the measurement.*?```text\n(.*?)```", PAGE, re.S).group(1)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code.replace("fit.comparisons[1.0].plot()", ""), "measurements.md", "exec"), {})
    assert out.getvalue() == shown


def test_the_dispersion_corrections_numbers():
    """PMMA-13 with the bars' Poisson ratio: the three-wave peak stress the page quotes, and the
    first mode's speed at the pickup's frequency."""
    import math

    from impactbar.measure import Bar, phase_velocity, read_spec

    spec = read_spec(ROOT / "examples" / "shpb_pmma13.toml")
    spec["dispersion"] = {"poisson": 0.33}
    corrected = run_spec(spec).report["stress_strain"]["3"]["peak_stress_MPa"]
    assert _quoted(r"three-wave peak stress from [0-9.]+ to ([0-9.]+) MPa") == round(corrected, 1)
    plain = run_spec(ROOT / "examples" / "shpb_pmma13.toml").report["stress_strain"]["3"]["peak_stress_MPa"]
    assert _quoted(r"three-wave peak stress from ([0-9.]+) to") == round(plain, 1)
    bar = Bar(71.7e9, 2810.0, 4.4521e-6)
    radius = math.sqrt(bar.area / math.pi)
    assert _quoted(r"a radius of ([0-9.]+) mm") == round(1e3 * radius, 2)
    c = phase_velocity([0.732e6], radius, bar, 0.33)[0]
    assert _quoted(r"carries at ([0-9.]+) of") == round(c / bar.wave_speed, 2)


def test_the_reflection_fits_numbers(report):
    """The reflection's delay fitted on PMMA-13: the delay, the wave speed and its standard error,
    the ratio and the misfit the page quotes."""
    f = report["arrivals"]["reflection_fit"]
    assert _quoted(r"the fitted delay, ([0-9.]+) us") == round(f["delay_us"], 3)
    assert _quoted(r"us, gives ([0-9]+) m/s with") == round(f["wave_speed_m_s"])
    assert _quoted(r"a standard error of ([0-9]+) m/s") == round(f["wave_speed_std_m_s"])
    assert _quoted(r"\(\$r = (-[0-9.]+)\$\)") == round(f["ratio"], 3)
    assert _quoted(r"a misfit of ([0-9]+) %") == round(100 * f["misfit"])
