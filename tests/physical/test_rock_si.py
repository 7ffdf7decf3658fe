"""The drill string and the rock in SI units (theory §4d): ``[rod]``, ``[bit]``, ``[rock]`` in a
configuration, the dimensionless law they define, the per-blow outputs in SI, and the command line."""

import copy
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from impactbar import physical
from impactbar.physical.outputs import OUTPUTS
from impactbar.physical.rock import rock_blows, rock_from_config, rock_summary

CONFIG = {
    "name": "drill-on-rock",
    "bar": {"E": "210 GPa", "density": "7850 kg/m^3", "length": "450 mm", "diameter": "45 mm"},
    "stop": {"restitution": 0.0},
    "drive": {"frequency": "55 Hz"},
    "force": {"kind": "pneumatic", "mean": "3 kN", "amplitude": "8 kN"},
    "damping": {"ratio": 0.01},
    "model": {"n_modes": 4},
    "rod": {"segments": [{"length": "0.4 m", "diameter": "45 mm"},
                         {"length": "1.2 m", "diameter": "32 mm", "E": "200 GPa"}]},
    "bit": {"mass": "1.5 kg"},
    "rock": {"k": "600 kN/mm", "k_u": "6000 kN/mm", "feed": "5 kN"},
}


def test_the_law_in_model_units():
    """Lengths in piston lengths, impedances ``E A / c`` and wave speeds relative to the piston's,
    ``k = K / (m Omega^2)``, the bit in piston masses, the feed in ``m L Omega^2``; Lundberg's
    ``alpha = K (2 L / c) / Z`` computed in SI is the law's."""
    h = physical.Hammer.from_config(CONFIG)
    law = h.model.law
    assert h.impact == "rodrock" and h.model.impact == "rodrock"
    b, sc = h.bar, h.scales
    Z = b.density_kg_m3 * b.wave_speed_m_s * b.area_m2
    alpha_si = 600e6 * (2 * b.length_m / b.wave_speed_m_s) / Z
    assert law.alpha(h.model) == pytest.approx(alpha_si, rel=1e-12)
    g0, g1 = law.segments
    assert g0.length == pytest.approx(0.4 / 0.45, rel=1e-14) and g0.impedance == pytest.approx(1.0, rel=1e-14)
    c1 = math.sqrt(200e9 / 7850)
    assert g1.wave_speed == pytest.approx(c1 / b.wave_speed_m_s, rel=1e-14)
    assert g1.impedance == pytest.approx(200e9 * math.pi / 4 * 0.032**2 / c1 / Z, rel=1e-12)
    assert law.rock.gamma == pytest.approx(10.0, rel=1e-14)
    assert law.bit_mass == pytest.approx(1.5 / b.mass_kg, rel=1e-14)
    assert law.feed * sc.force_N == pytest.approx(5e3, rel=1e-14)
    assert h.to_dict()["drill"]["rock_k_N_m"] == pytest.approx(600e6)


def test_per_blow_outputs_in_si():
    """Work on rock in J (model energy times ``m L^2 Omega^2``), penetration per blow in mm, the
    drilling rate at the blow frequency in m/min, efficiencies; the second half's summary."""
    h = physical.Hammer.from_config(CONFIG)
    r = physical.simulate(h, periods=12)
    out = rock_blows(h, r.trajectory)
    blows = r.trajectory.impacts
    assert len(blows) == out["work_on_rock_J"].size == r.impact_times_s.size > 2
    sc = h.scales
    j = int(np.argmax(out["work_on_rock_J"]))
    joules = blows[j].work_on_rock * h.bar.mass_kg * sc.velocity_m_s**2
    assert out["work_on_rock_J"][j] == pytest.approx(joules, rel=1e-12)
    np.testing.assert_allclose(out["rock_dissipated_J"] + out["rock_stored_J"], out["work_on_rock_J"],
                               rtol=1e-12)
    assert out["rock_dissipated_J"][j] == pytest.approx(
        blows[j].rock_dissipated * h.bar.mass_kg * sc.velocity_m_s**2, rel=1e-12)
    mm = blows[j].permanent_penetration * h.bar.length_m * 1e3
    assert out["penetration_mm"][j] == pytest.approx(mm, rel=1e-12)
    assert out["drilling_rate_m_min"][j] == pytest.approx(mm * 1e-3 * 55.0 * 60.0, rel=1e-12)
    assert np.all((out["efficiency"] > 0) & (out["efficiency"] <= out["efficiency_with_rebound"])
                  & (out["efficiency_with_rebound"] <= 1))
    s = rock_summary(r)
    assert s["n_blows"] >= 2 and s["mean_work_on_rock_J"] > 0 and 0 < s["mean_efficiency"] <= 1
    # the power into the rock, the registry's output: the work of the second half's impacts from its
    # first blow to (not with) its last over the time between those blows
    power = OUTPUTS["rock_power"]
    assert (power.key, power.unit) == ("rock_power_W", "W") and power.key in s
    t, blow = r.impact_times_s, r.is_blow()
    late = t[blow & (t >= 0.5 * r.t_end_s)]
    window = (t >= late[0]) & (t < late[-1])
    work = np.sum(out["work_on_rock_J"][window])
    assert s[power.key] == pytest.approx(work / (late[-1] - late[0]), rel=1e-12)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda c: c["rock"].pop("k_u"), r"missing key rock\.k_u"),
    (lambda c: c["rock"].update(k="600 kN"), r"rock\.k must be a stiffness"),
    (lambda c: c["rod"]["segments"][0].pop("diameter"), r"exactly one of rod\.segments\[0\]\.diameter"),
    (lambda c: c["rod"]["segments"][1].update(width="1 m"), r"unknown key rod\.segments\[1\]\.width"),
    (lambda c: c["bit"].update(size="1 m"), r"unknown key bit\.size"),
    (lambda c: c.pop("rock"), r"\[rod\] and \[bit\] need a \[rock\] section"),
    (lambda c: c["rock"].update(k_u="100 kN/mm"), r"rock\.k_u"),
])
def test_configuration_errors_name_the_key(edit, message):
    config = copy.deepcopy(CONFIG)
    edit(config)
    with pytest.raises(ValueError, match=message):
        physical.Hammer.from_config(config)


def test_no_rock_section_no_drill():
    config = {k: v for k, v in CONFIG.items() if k not in ("rod", "bit", "rock")}
    assert rock_from_config(config, None) is None
    assert physical.Hammer.from_config(config).drill is None


def test_cli_simulate_prints_the_drilling_outputs(tmp_path):
    """``impactbar simulate examples/rock_drill.toml`` (a ``[rock]`` section) prints the work on rock, the
    penetration per blow, the drilling rate and the efficiencies, and writes them to summary.json."""
    import json

    toml = Path(__file__).parents[2] / "examples" / "rock_drill.toml"
    assert physical.load_config(toml).drill.rock_k_N_m == pytest.approx(830e6)
    res = subprocess.run([sys.executable, "-m", "impactbar", "simulate", str(toml),
                          "--out", str(tmp_path / "o"), "--periods", "8"],
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert "J on rock" in res.stdout and "mm per blow" in res.stdout and "m/min" in res.stdout
    rock = json.loads((tmp_path / "o" / "summary.json").read_text())["rock"]
    assert rock["mean_work_on_rock_J"] > 0 and rock["drilling_rate_m_min"] > 0
    # blows and chatter apart, and the blow frequency measured, not the drive's
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert rock["n_blows"] == summary["n_blows_second_half"]
    assert rock["blow_frequency_Hz"] == pytest.approx(summary["blow_frequency_Hz"], rel=1e-12)
    assert f"second half, {rock['n_blows']} blows, {rock['n_chatter']} chatter" in res.stdout


#: the hydraulic drill's piston under a +-12 kN square wave on a drill string and rock: its motion
#: does not settle, but it has one-impact periodic orbits for ``impactbar orbits`` to list
ORBITS_TOML = """name = "hydraulic-drill on rock"

[bar]
E = "210 GPa"
density = "7850 kg/m^3"
length = "450 mm"
diameter = "45 mm"

[stop]                     # not used by the rod-rock law (the rod replaces the stop)
restitution = 0.0

[drive]
frequency = "55 Hz"

[force]                    # +12 kN for 58 % of the period, -12 kN for the rest
kind = "hydraulic"
high = "12 kN"
low = "-12 kN"
fraction = 0.58

[damping]
coefficient = "9 N*s/m"

[model]
n_modes = 8

[[rod.segments]]           # shank adapter
length = "0.4 m"
diameter = "45 mm"

[[rod.segments]]           # drill rod
length = "1.2 m"
diameter = "32 mm"

[bit]
mass = "1.5 kg"

[rock]
k = "470 kN/mm"
k_u = "4700 kN/mm"
feed = "5 kN"
"""


def test_the_docs_example_rock_sits_at_lundbergs_optimum():
    """docs/physical.md: ``k = 470 kN/mm`` under a 450 mm x 45 mm steel piston gives
    ``alpha = 1.27`` (Lundberg's optimum 1.2564312 to two digits: theory §4d)."""
    config = copy.deepcopy(CONFIG)
    config["rock"] = {"k": "470 kN/mm", "k_u": "4700 kN/mm", "feed": "5 kN"}
    h = physical.Hammer.from_config(config)
    assert round(h.model.law.alpha(h.model), 2) == 1.27
    assert h.model.law.rock.gamma == pytest.approx(10.0)


def test_cli_orbits_prints_the_drilling_outputs_per_blow(tmp_path):
    """``impactbar orbits CONFIG --json`` on a drill string and rock: the one-impact orbits under the rod-rock
    law (periodic_orbits by Newton from guesses) with each blow's work on rock (J), penetration (mm),
    drilling rate (m/min) and efficiencies; the same figures as a run of the simulator started on
    the orbit, converted by :func:`rock_blows` (to 1e-8), and the table prints them."""
    import json

    import impactbar as ib

    toml = tmp_path / "rock.toml"
    toml.write_text(ORBITS_TOML)
    res = subprocess.run([sys.executable, "-m", "impactbar", "orbits", str(toml), "--json"],
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    found = json.loads(res.stdout)["orbits"]
    assert found
    from impactbar.cli.physical import format_table

    hammer = physical.load_config(toml)
    model, load = hammer.model, hammer.load
    si = physical.orbits(hammer)
    orbits = [o.orbit for o in si]
    assert [o["phase_rad"] for o in found] == pytest.approx([o.phase for o in orbits], abs=1e-9)
    T = model.law.window(model)
    M = model.n_modes + 1
    for row, o in zip(found, orbits, strict=True):
        y = o.states_after_impact[0]
        t0 = o.impact_times[0] + T
        run = ib.simulate(model, load, ib.InitialState(modal_displacement=y[:M], modal_velocity=y[M:]),
                          t0 + 2 * math.pi, t0=t0)
        blows = rock_blows(hammer, run)
        for key in ("work_on_rock_J", "penetration_mm", "drilling_rate_m_min", "efficiency",
                    "efficiency_with_rebound"):
            assert row[key] == pytest.approx(blows[key][0], rel=1e-8), key
        assert 0.0 <= row["efficiency"] <= row["efficiency_with_rebound"] <= 1.0
    table = format_table(hammer, si)  # what ``impactbar orbits`` prints
    assert "drilling per blow" in table and f"{found[0]['work_on_rock_J']:8.2f}" in table


def test_the_blows_method_and_grid_in_a_config():
    """``[rock] method`` and ``cells_per_piston`` set the simulator's blows: exact by default; a
    ``cells_per_piston`` (at 4 times the commensurate count here) puts them on the lattice, whose
    work on rock per blow lies off the exact blows' by more than rounding and less than 10 % (the
    lattice's error); ``method = "lattice"`` takes the commensurate count; bad values are refused by
    name."""
    from impactbar.laws.rodrock.contact import BlowMap

    h = physical.Hammer.from_config(CONFIG)
    assert h.model.law.cells_per_piston is None and h.model.law.blow_method(h.model) == "exact"
    default = BlowMap(h.model, h.load, 0.0).grid.piston_cells
    cfg = copy.deepcopy(CONFIG)
    cfg["rock"]["cells_per_piston"] = 4 * default
    fine = physical.Hammer.from_config(cfg)
    assert fine.model.law.cells_per_piston == 4 * default
    assert fine.model.law.blow_method(fine.model) == "lattice"
    assert fine.to_dict()["drill"]["cells_per_piston"] == 4 * default
    w0 = rock_blows(h, physical.simulate(h, periods=4).trajectory)["work_on_rock_J"]
    w1 = rock_blows(fine, physical.simulate(fine, periods=4).trajectory)["work_on_rock_J"]
    assert w0.size == w1.size > 0
    assert 1e-12 < np.max(np.abs(w1 - w0) / w0) < 0.1
    lattice = copy.deepcopy(CONFIG)
    lattice["rock"]["method"] = "lattice"
    lat = physical.Hammer.from_config(lattice)
    assert lat.model.law.blow_method(lat.model) == "lattice" and lat.to_dict()["drill"]["method"] == "lattice"
    lattice["rock"]["method"] = "cells"
    with pytest.raises(ValueError, match="rock.method"):
        physical.Hammer.from_config(lattice)
    lattice["rock"].update(method="lattice", driven_end="window", contact_events="inside")
    named = physical.Hammer.from_config(lattice)
    assert (named.model.law.driven_end, named.model.law.contact_events) == ("window", "inside")
    assert named.to_dict()["drill"]["driven_end"] == "window"
    assert (lat.model.law.driven_end, lat.model.law.contact_events) == ("free", "step")  # (defaults)
    for key, bad in (("driven_end", "fixed"), ("contact_events", "steps")):
        wrong = copy.deepcopy(lattice)
        wrong["rock"][key] = bad
        with pytest.raises(ValueError, match=f"rock.{key} must be"):
            physical.Hammer.from_config(wrong)
    for bad in (0, "16", 1.5):
        cfg["rock"]["cells_per_piston"] = bad
        with pytest.raises(ValueError, match="rock.cells_per_piston"):
            physical.Hammer.from_config(cfg)
