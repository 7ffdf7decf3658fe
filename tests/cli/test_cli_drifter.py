"""``impactbar orbits|simulate|continue`` with a hydraulic drifter (theory §10): the preset of the
theory's worked example and a TOML config with a [valve] section give the SI figures of the closed
form."""

import json
import math
import re

import pytest

from impactbar import physical
from impactbar.cli import main

CONFIG = """
name = "my-drifter"
[bar]
E = "210 GPa"
density = "7850 kg/m^3"
length = "448.54236 mm"
diameter = "45 mm"
[stop]
restitution = 0.215
[valve]
supply_pressure = "14 MPa"
stroke_area = "4 cm^2"
return_area = "4 cm^2"
switch_out = "2.15 cm"
"""


def _expected():
    """Theory §10's worked example in SI by hand: 5.6 kg, 5.6 kN each way, 21.5 mm, R = 0.215."""
    a, x1, R = 5600.0 / 5.6, 0.0215, 0.215
    v = math.sqrt(2 * x1 * 2 * a / (1 - R * R))
    u1 = math.sqrt(R * R * v * v + 2 * a * x1)
    return v, 1 / ((u1 - R * v) / a + (u1 + v) / a)


@pytest.mark.parametrize("source", ["preset", "config"])
def test_orbits_json_of_a_drifter(source, tmp_path, capsys):
    if source == "preset":
        argv = ["orbits", "--preset", "hydraulic-drifter", "--json"]
    else:
        (tmp_path / "d.toml").write_text(CONFIG)
        argv = ["orbits", str(tmp_path / "d.toml"), "--json"]
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    v, f = _expected()
    assert doc["orbit"]["impact_velocity_m_s"] == pytest.approx(v, rel=1e-7)
    assert doc["orbit"]["blow_frequency_Hz"] == pytest.approx(f, rel=1e-7)
    assert doc["orbit"]["impact_power_kW"] == pytest.approx(0.5 * 5.6 * v * v * f / 1e3, rel=1e-6)


def test_simulate_and_continue_a_drifter(tmp_path, capsys):
    assert main(["simulate", "--preset", "hydraulic-drifter", "--out", str(tmp_path / "s"), "--periods", "30",
                 "--gap", "30 mm"]) == 0
    summary = json.loads((tmp_path / "s" / "summary.json").read_text())
    v, f = _expected()
    assert summary["blow_frequency_Hz"] == pytest.approx(f, rel=1e-7)
    assert summary["impact_velocity_m_s"] == pytest.approx(v, rel=1e-7)
    rows = (tmp_path / "s" / "impacts.csv").read_text().splitlines()
    assert rows[0] == "time_s,impact_velocity_m_s" and len(rows) == summary["n_impacts"] + 1
    # the figures a hammer's run gets; no rod, so no force history nor stress along it
    assert {p.name for p in (tmp_path / "s").glob("*.png")} == {"motion.png", "blows.png"}
    capsys.readouterr()
    assert main(["continue", "--preset", "hydraulic-drifter", "--parameter", "delay", "--to", "1.0",
                 "--out", str(tmp_path / "c"), "--brute", "0", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["status"] == "reached" and doc["events"][0]["kind"] == "admissibility"
    # the delay (dimensionless) past which the piston grazes the stop on its way out: it leaves at
    # R v under the stroke force (a_s = 1) for tau, then the return force (a_r = 1) stops its inward
    # motion w = tau - R v within w^2 / 2, which at the event equals the gap R v tau - tau^2 / 2
    # (rigid, d = 0, theory §10)
    from impactbar import find_orbit
    from impactbar.physical import drifter_preset

    tau = doc["events"][0]["value"]
    d = drifter_preset("hydraulic-drifter")
    o = find_orbit(d.model(), d.drive().__class__(1.0, 1.0, d.drive().switch_out, tau))
    rv = 0.215 * o.impact_velocity
    assert rv * tau - tau * tau / 2 == pytest.approx((tau - rv) ** 2 / 2, abs=1e-8)
    events = (tmp_path / "c" / "events.csv").read_text().splitlines()
    assert events[0] == "kind,delay,multiplier_real,multiplier_imag"
    assert any(e.startswith("admissibility,") for e in events[1:])
    branch = (tmp_path / "c" / "branch.csv").read_text().splitlines()
    assert len(branch) > 5 and float(branch[-1].split(",")[0]) == pytest.approx(1.0)


@pytest.mark.parametrize("source", ["preset", "config"])
def test_drifter_command_prints_the_operating_point(source, tmp_path, capsys):
    """``impactbar drifter``: the ideal valve's operating point is the closed form."""
    if source == "preset":
        argv = ["drifter", "--preset", "hydraulic-drifter"]
    else:
        (tmp_path / "d.toml").write_text(CONFIG)
        argv = ["drifter", str(tmp_path / "d.toml")]
    assert main([*argv, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    v, f = _expected()
    assert doc["orbit"]["impact_velocity_m_s"] == pytest.approx(v, rel=1e-7)
    assert doc["orbit"]["blow_frequency_Hz"] == pytest.approx(f, rel=1e-7)
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert f"blow frequency {f:.4g} Hz" in text and f"impact velocity {v:.4g} m/s" in text


def test_drifter_command_takes_only_the_documented_presets(capsys):
    """An undocumented preset name (an old one, say) is not a choice of ``--preset``."""
    with pytest.raises(SystemExit) as exc:
        main(["drifter", "--preset", "drifter-old"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'drifter-old'" in err and "hydraulic-drifter" in err


def _help(capsys) -> str:
    with pytest.raises(SystemExit) as exc:
        main(["drifter", "--help"])
    assert exc.value.code == 0
    return " ".join(capsys.readouterr().out.split())


def test_drifter_help_lists_both_drifters_sections_and_keys(capsys):
    """Every section and key the two readers check (their own tables), each under its drifter; none
    of the hammer's ([drive], [force])."""
    from impactbar.physical import circuit, drifter, rock

    text = _help(capsys)
    valve, rest = text.split("configuration keys of a drifter with its oil circuit")
    valve = valve.split("configuration keys of a drifter whose valve switches")[1]
    circ, drill = rest.split("either drifter on a drill string and the rock")
    for block, table in ((valve, drifter._KEYS), (circ, circuit._KEYS)):
        for section, keys in table.items():
            assert f"[{section}] {', '.join(sorted(keys))}" in block, (section, block)
        assert re.findall(r"\[([\w.]+)\]", block.split("): ", 1)[1]) == list(table)  # those only
    for section, keys in rock.ROCK_SECTIONS.items():
        if section != "rod":
            assert f"[{section}] {', '.join(sorted(keys))}" in drill
    assert f"[rod.segments] {', '.join(sorted(rock._SEGMENT_KEYS))}" in drill
    assert "[drive]" not in text and "[force]" not in text


def test_drifter_help_follows_the_tables(capsys, monkeypatch):
    """The help is generated from the readers' tables: a key added to a table shows."""
    from impactbar.physical import circuit

    monkeypatch.setitem(circuit._KEYS, "accumulator", {*circuit._KEYS["accumulator"], "zz_new_key"})
    assert "[accumulator] polytropic_exponent, precharge, volume, zz_new_key" in _help(capsys)


def test_drifter_command_refuses_a_hammer(capsys):
    """A hammer's file is refused in one line that says what the file is; the hammers' presets are
    not offered (the help lists the drifters' only, and argparse refuses the others)."""
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "examples" / "pneumatic_drill.toml"
    assert main(["drifter", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "needs a drifter" in err and "circuit-drifter" in err and "\n" not in err
    assert "pneumatic_drill.toml is a hammer under a periodic force" in err
    for hammer in ("pneumatic-drill", "hydraulic-drill"):
        with pytest.raises(SystemExit) as exit_:
            main(["drifter", "--preset", hammer])
        err = capsys.readouterr().err
        assert exit_.value.code == 2 and "invalid choice" in err and err.count("\n") == 1
    assert "hydraulic-drill" not in _help(capsys) and "pneumatic-drill" not in _help(capsys)


def test_circuit_si_parameters_are_the_drive_parameters():
    """Every config key of ``SI_PARAMETERS`` converts the preset's own config value to the value
    its dimensionless drive holds (two paths: the drive's builder and the SI table)."""
    from impactbar.physical import tree
    from impactbar.physical.circuit import CIRCUIT_PRESETS, SI_PARAMETERS, circuit_preset

    d = circuit_preset("circuit-drifter")
    drive, config = d.drive(), CIRCUIT_PRESETS["circuit-drifter"]
    checked = 0
    for key, (param, _, _) in SI_PARAMETERS.items():
        section, name = key.split(".")
        if name not in config.get(section, {}):
            continue
        got, value = d.to_dimensionless(key, config[section][name])
        assert got == param
        assert value == drive.value(param)  # (the config's conversion: the same to the bit)
        assert d.from_dimensionless(key, value) == pytest.approx(
            tree.read_si(key, config[section][name]), rel=1e-12)
        checked += 1
    assert checked >= 14
    with pytest.raises(ValueError, match="parameter must be one of accumulator.precharge"):
        d.to_dimensionless("accumulator.pressure", "1 MPa")
    with pytest.raises(ValueError, match="accumulator.precharge"):
        d.to_dimensionless("accumulator.precharge", 12.0)  # a bare number: its unit is needed


def test_continue_a_circuit_in_si(tmp_path, capsys):
    """``impactbar continue CONFIG --parameter accumulator.precharge --to '10.2 MPa'``: the branch in
    the pre-charge in the unit of ``--to`` (MPa) beside its dimensionless value (10 MPa units), with
    what a designer reads at each point in SI (blow frequency, impact energy, mean supply pressure,
    pump power, hydraulic efficiency), the start's equal to the operating point's."""
    assert main(["continue", "--preset", "circuit-drifter", "--parameter", "accumulator.precharge",
                 "--to", "10.2 MPa", "--out", str(tmp_path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["status"] == "reached" and doc["to"] == "10.2 MPa"
    assert str(tmp_path / "diagram.png") in doc["files"] and (tmp_path / "diagram.png").stat().st_size > 0
    rows = (tmp_path / "branch.csv").read_text().splitlines()
    assert rows[0] == ("accumulator.precharge (MPa),precharge,period_dimensionless,"
                       "impact_velocity_dimensionless,stable,max_abs_multiplier,blow_frequency_Hz,"
                       "impact_energy_J,mean_supply_pressure_MPa,pump_power_kW,hydraulic_efficiency")
    values = [[float(x) for x in r.split(",")[:2]] for r in rows[1:]]
    assert values[0][0] == pytest.approx(10.0) and values[-1][0] == pytest.approx(10.2, rel=1e-9)
    for si, dimensionless in values:
        assert si == pytest.approx(dimensionless * 10.0, rel=1e-12)
    first = dict(zip(rows[0].split(","), rows[1].split(","), strict=True))
    op = physical.circuit_preset("circuit-drifter").orbit()
    assert float(first["blow_frequency_Hz"]) == pytest.approx(op.blow_frequency_Hz, rel=1e-9)
    assert float(first["impact_energy_J"]) == pytest.approx(op.impact_energy_J, rel=1e-9)
    p_s = float(first["mean_supply_pressure_MPa"])
    assert p_s == pytest.approx(op.mean_supply_pressure_Pa / 1e6, rel=1e-9)
    assert 0.0 < float(first["hydraulic_efficiency"]) < 1.0
    # refusals: a unit for a dimensionless parameter, a config key for a drifter without a circuit
    assert main(["continue", "--preset", "circuit-drifter", "--parameter", "precharge", "--to", "12 MPa",
                 "--out", str(tmp_path)]) == 2
    assert "--to must be a number" in capsys.readouterr().err
    assert main(["continue", "--preset", "hydraulic-drifter", "--parameter", "supply.pump_flow", "--to",
                 "80 L/min", "--out", str(tmp_path)]) == 2
    assert "oil circuit" in capsys.readouterr().err


def test_continue_reports_in_the_unit_of_to(tmp_path, capsys):
    """``--to '76 L/min'``: the branch and the relief's border collision (the relief valve starting to
    open) in L/min, each the SI value of its dimensionless parameter converted."""
    assert main(["continue", "--preset", "circuit-drifter", "--parameter", "supply.pump_flow",
                 "--to", "76 L/min", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    d = physical.circuit_preset("circuit-drifter")
    rows = [r.split(",") for r in (tmp_path / "events.csv").read_text().splitlines()]
    assert rows[0][-1] == "supply.pump_flow (L/min)"
    relief = [r for r in rows[1:] if r[0] == "border-collision relief"]
    assert len(relief) == 1
    si = d.from_dimensionless("supply.pump_flow", float(relief[0][1]))  # m^3/s
    assert float(relief[0][-1]) == pytest.approx(si * 6e4, rel=1e-10) and 70 < float(relief[0][-1]) < 76
    assert f"supply.pump_flow = {si * 6e4:.6g} L/min" in out
    branch = (tmp_path / "branch.csv").read_text().splitlines()
    assert branch[0].startswith("supply.pump_flow (L/min),") and float(branch[-1].split(",")[0]) == \
        pytest.approx(76.0, rel=1e-9)


def test_simulate_a_circuit_drifter_from_rest(tmp_path, capsys):
    """``impactbar simulate --preset circuit-drifter``: impacts.csv's energies are m v^2 / 2 with the
    piston's mass from its geometry; from rest the accumulator charges, so every blow is faster than
    the one before and slower than the operating point's; pressures.csv holds the absolute
    pressures and the valve's opening in [0, 1]."""
    assert main(["simulate", "--preset", "circuit-drifter", "--periods", "8", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "wrote" in out and "operating point's 10.02 m/s" in out
    rows = [[float(x) for x in r.split(",")] for r in (tmp_path / "impacts.csv").read_text().splitlines()[1:]]
    m = 7850 * math.pi / 4 * 0.045 ** 2 * 0.44854236
    assert len(rows) >= 5
    for _, v, e in rows:
        assert e == pytest.approx(0.5 * m * v * v, rel=1e-8)
    v = [r[1] for r in rows]
    assert all(b > a for a, b in zip(v, v[1:], strict=False)) and v[-1] < 10.02
    assert all(b > a for a, b in zip([r[0] for r in rows], [r[0] for r in rows][1:], strict=False))
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["n_impacts"] == len(rows) and summary["operating_point"]["stable"]
    p = (tmp_path / "pressures.csv").read_text().splitlines()
    assert p[0] == "t_s,p_f_Pa,p_r_Pa,p_s_Pa,x_v,gap_m"
    cols = list(zip(*([float(x) for x in r.split(",")] for r in p[1:]), strict=True))
    assert min(cols[4]) >= 0.0 and max(cols[4]) <= 1.0 and min(min(c) for c in cols[1:4]) > 0.0
    assert (tmp_path / "motion.png").stat().st_size > 0
    assert main(["simulate", "--preset", "circuit-drifter", "--periods", "0", "--out", str(tmp_path)]) == 2
    assert "--periods must be > 0" in capsys.readouterr().err


def test_the_readme_quotes_the_drifter_command_as_it_prints(capsys):
    """README.md's ``impactbar drifter --preset hydraulic-drifter`` block is the command's output now
    (its numbers the closed form of theory §10, checked above)."""
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    quoted = re.search(r"```console\n\$ impactbar drifter --preset hydraulic-drifter\n(.*?)```", readme,
                       flags=re.S)
    assert quoted is not None, "the README's drifter example is gone; update this test with it"
    assert main(["drifter", "--preset", "hydraulic-drifter"]) == 0
    assert capsys.readouterr().out == quoted.group(1)


def test_drifter_text_says_the_impact_power_and_the_circuits_borders(capsys):
    """The text has what the JSON has: the impact power, and the relief valve and the accumulator
    over the period, checked against the orbit's pressure history sampled apart (its extremes
    against the relief's 25 MPa and the pre-charge's 10 MPa), and the efficiency says what it is."""
    assert main(["drifter", "--preset", "circuit-drifter"]) == 0
    text = capsys.readouterr().out
    point = physical.circuit_preset("circuit-drifter").orbit()
    v, f = point.impact_velocity_m_s, point.blow_frequency_Hz
    shown = float(re.search(r"impact power ([0-9.]+) kW", text).group(1))
    assert shown == pytest.approx(0.5 * 5.6 * v * v * f / 1e3, rel=1e-3)
    p_s = point.histories(4000)["p_s_Pa"] / 1e6
    relief = float(re.search(r"relief valve stays shut \(the supply pressure peaks ([0-9.]+) MPa below", text)
                   .group(1))
    acc = float(re.search(r"accumulator never empties \(the supply pressure stays ([0-9.]+) MPa above",
                          text).group(1))
    assert relief == pytest.approx(25.0 - p_s.max(), rel=1e-3, abs=1e-3)  # (four digits shown)
    assert acc == pytest.approx(p_s.min() - 10.0, rel=1e-3, abs=1e-3)
    eta = f"hydraulic efficiency {point.hydraulic_efficiency:.3f} (the energy the blows deliver"
    assert eta in text


def test_drifter_text_says_the_relief_opens_and_the_accumulator_empties(tmp_path, capsys):
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter.toml").read_text()
    opens = tmp_path / "opens.toml"
    opens.write_text(text.replace('pump_flow = "70 L/min"', 'pump_flow = "100 L/min"')
                     .replace('volume = "0.5 L"', 'volume = "0 L"'))
    assert main(["drifter", str(opens)]) == 0
    out = capsys.readouterr().out
    assert "the relief valve opens (the supply pressure reaches" in out and "; no accumulator" in out
    empties = tmp_path / "empties.toml"
    empties.write_text(text.replace('precharge = "10 MPa"', 'precharge = "24 MPa"'))
    assert main(["drifter", str(empties)]) == 0
    assert "the accumulator empties (the supply pressure falls" in capsys.readouterr().out


def test_the_circuit_header_speaks_the_units_the_config_wrote(tmp_path, capsys):
    """The pump's flow, the accumulator's volume and its pre-charge in the header are in the units the
    config wrote them in (bar, L/s), not in MPa and L/min whatever the config said."""
    from pathlib import Path

    text = (Path(__file__).parents[2] / "examples" / "circuit_drifter.toml").read_text()
    mine = text.replace('precharge = "10 MPa"', 'precharge = "100 bar"').replace(
        'pump_flow = "70 L/min"', 'pump_flow = "1.2 L/s"')
    assert mine != text
    config = tmp_path / "my.toml"
    config.write_text(mine)
    assert main(["drifter", str(config)]) == 0
    header = capsys.readouterr().out.splitlines()[0]
    assert "pump 1.2 L/s, accumulator 0.5 L at 100 bar," in header, header
