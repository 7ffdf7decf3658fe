"""A drifter with its oil circuit on a drill string and rock: the SI figures of its blow,
solved with the circuit's state (theory §11, "The coupled blow"), and the drilling rate
(``examples/circuit_drifter_rock.toml``)."""

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from impactbar import InitialState, simulate
from impactbar.drives.circuit import HydraulicCircuitDrive
from impactbar.loads import FourierLoad
from impactbar.physical import CircuitDrifter
from impactbar.physical.circuit import PRESSURE_SCALE

EXAMPLE = Path(__file__).parents[2] / "examples" / "circuit_drifter_rock.toml"


def load_config(path=EXAMPLE):
    with open(path, "rb") as f:
        return tomllib.load(f)


@pytest.fixture(scope="module")
def point():
    return CircuitDrifter.from_config(load_config()).orbit()


def test_the_drilling_rate_is_the_penetration_times_the_blow_frequency(point):
    """The orbit's figures in SI from its blow's record (the scales: force ``P A_r``, length ``L``),
    the drilling rate the penetration times the blow frequency; a run restarted on the orbit (the
    simulator's loop, not the shooting problem's) strikes one period later with the same blow (its
    penetration to 1e-9, its impact velocity to 1e-8). The numbers quoted in docs/physical.md and
    theory §11: 45.66 Hz, 10.39 m/s, 302.0 J, 218.4 J on the rock, 0.9145 mm, 2.505 m/min."""
    d, o = point.drifter, point.orbit
    assert d.model().impact == "rodrock" and d.restitution == 0.0 and o.stable and o.admissible
    sc = d.scales
    L = d.bar.length_m
    assert sc.force_N == pytest.approx(PRESSURE_SCALE * d.si["rear_area_m2"], rel=1e-15)
    assert sc.force_N * L == pytest.approx(d.energy_scale_J, rel=1e-12)
    r = point.rock()
    (rec,) = o.contacts
    pen_m = float(rec.permanent_penetration) * L
    assert r["penetration_mm"] == pytest.approx(pen_m * 1e3, rel=1e-12)
    assert r["work_on_rock_J"] == pytest.approx(float(rec.work_on_rock) * sc.force_N * L, rel=1e-12)
    assert r["drilling_rate_m_min"] == pytest.approx(pen_m * point.blow_frequency_Hz * 60.0, rel=1e-12)
    assert 0.0 < r["efficiency"] <= r["efficiency_with_rebound"] <= 1.0
    assert point.summary()["rock"] == r
    y, z = o.states_after_impact[0], o.drive_states[0]
    drive = o.drive
    restart = HydraulicCircuitDrive(drive.chambers, drive.valve, drive.supply, drive.oil, drive.accumulator,
                                    start_pressures=tuple(z))
    run = simulate(o.model, restart, InitialState(y[:1], y[1:]), 1.5 * o.period)
    (blow,) = run.impacts
    assert run.impact_times[0] == pytest.approx(o.period - o.contact_time, rel=1e-8)
    assert run.impact_velocities[0] == pytest.approx(o.impact_velocity, rel=1e-8)
    assert blow.permanent_penetration == pytest.approx(rec.permanent_penetration, rel=1e-9)
    quoted = (round(point.blow_frequency_Hz, 2), round(point.impact_velocity_m_s, 2),
              round(point.impact_energy_J, 1), round(r["work_on_rock_J"], 1), round(r["penetration_mm"], 4),
              round(r["drilling_rate_m_min"], 3))
    assert quoted == (45.66, 10.39, 302.0, 218.4, 0.9145, 2.505)


def test_the_blow_on_the_rock_moves_the_pressures(point):
    """The operating point's blow (1.01 ms, to where the piston is free for good) with the circuit's
    state: the rear chamber's pressure rises 1.2 MPa (21.67 to 22.87 MPa) as the piston stops and its
    demand for oil with it, the front chamber's falls 0.29 MPa, where the force held at the arrival's
    would keep them; the piston leaves at 3.638 m/s against 3.727 m/s under the frozen force (its
    blow ended at the law's window, 0.98 ms), the work on rock 2e-5 apart (the rock takes the blow's
    first wave, which the drive barely touches); a closed front chamber would have taken 12 MPa from
    the piston's 1.5 mm of travel, 0.85 % of its volume. Figures of theory §11."""
    d, o = point.drifter, point.orbit
    problem = o.problem
    tau, mode = problem.blocks[0]
    X = np.asarray(o._unknowns, dtype=float)
    _, _, _, (_, q, v, state), pieces, _ = problem._flight(tau, mode, X, keep=True)
    (blow,) = [p for p in pieces if hasattr(p, "record")]
    z0, z1 = blow.drive_pieces[0].y[0, 1:5], blow.drive_pieces[-1].y[-1, 1:5]
    MPa = PRESSURE_SCALE / 1e6
    assert (round(z0[1] * MPa, 2), round(z1[1] * MPa, 2)) == (21.67, 22.87)
    assert round((z0[0] - z1[0]) * MPa, 2) == 0.29
    model, drive = o.model, o.drive
    L, om = d.bar.length_m, d.omega_rad_s
    p0 = drive.force(state.mode, state.z, q, v)
    _, v_frozen, _, frozen = model.law.contact(model, FourierLoad(p0, []), 0.0, q, v)
    assert round(blow.record.duration / om * 1e3, 2) == 1.01
    assert round(frozen.duration / om * 1e3, 2) == 0.98
    rebound = (round(-o.states_after_impact[0][1] * L * om, 3), round(-v_frozen[0] * L * om, 3))
    assert rebound == (3.638, 3.727)
    assert abs(blow.record.work_on_rock / frozen.work_on_rock - 1.0) == pytest.approx(2.3e-5, rel=0.1)
    # a closed front chamber: the piston's travel in the blow, its share of the chamber, the pressure
    w = np.concatenate([p.y[:, 0] for p in blow.drive_pieces])
    travel = float(np.max(w) - np.min(w))
    share = drive.chambers.area_ratio * travel / drive.chambers.front_volume
    assert (round(travel * L * 1e3, 1), round(100 * share, 2)) == (1.5, 0.85)
    assert round(drive.oil.bulk_modulus * share * MPa) == 12


def test_a_circuit_drifter_config_takes_the_drill_string_sections():
    cfg = load_config()
    del cfg["rock"]
    with pytest.raises(ValueError, match=r"\[rod\] and \[bit\] need a \[rock\]"):
        CircuitDrifter.from_config(cfg)
    cfg = load_config()
    cfg["drill"] = {}
    with pytest.raises(ValueError, match=r"unknown section \[drill\]"):
        CircuitDrifter.from_config(cfg)
    cfg = load_config()
    cfg["stop"] = {"restitution": 0.3}  # a stop beside the drill string: its R plays no part
    assert CircuitDrifter.from_config(cfg).model().impact == "rodrock"
    plain = load_config(EXAMPLE.with_name("circuit_drifter.toml"))
    d = CircuitDrifter.from_config(plain)
    assert d.drill is None and d.model().impact == "paper"


def test_the_command_line_prints_the_blow_on_the_rock(point, monkeypatch, capsys):
    """``impactbar orbits examples/circuit_drifter_rock.toml``: the drill string in the header and the
    blow's figures on their own line (the orbit the fixture's: the same configuration)."""
    from types import SimpleNamespace

    from impactbar.cli.drifter import run_circuit_orbits

    monkeypatch.setattr(CircuitDrifter, "orbit", lambda self, guess=None: point)
    assert run_circuit_orbits(SimpleNamespace(json=False), point.drifter) == 0
    out = capsys.readouterr().out
    assert "a drill string of 2 segment(s) on rock (k = 470 kN/mm)" in out
    assert "per blow: work on rock 218.4 J, penetration 0.9145 mm" in out and "2.505 m/min" in out


def test_the_indicator_work_is_the_oils_work_through_the_blows(point):
    """The chambers' p-V loops over the period, the volumes inside the blow following the driven end
    as the circuit integrated it: their sum is the energy account's work of the oil on the piston at
    second order in the sampling (measured 3.4e-3 J at 4000 points and 1.0e-3 J at 8000, of 271 J;
    the blow's end re-measures positions from the advanced stop, a step the open path does not
    integrate)."""
    acc = point.energy_account["piston"]
    errors = [abs(point.indicator_work_J(n)["piston"] - acc) for n in (4000, 8000)]
    assert errors[1] < 2e-5 * acc and 2.5 < errors[0] / errors[1] < 5.0


@pytest.mark.parametrize("key, value, si, name", [("rock.k", "470 kN/mm", 4.7e8, "rock.k"),
                                                  ("rock.k_u", "4700 kN/mm", 4.7e9, "rock.k_u"),
                                                  ("rock.feed", "2 kN", 2e3, "feed"),
                                                  ("bit.mass", "1.5 kg", 1.5, "bit_mass")])
def test_the_rocks_config_keys_are_the_laws_parameters(key, value, si, name):
    """A drifter on rock takes the drill string's and the rock's config keys as continuation
    parameters: the config's own values give the law's dimensionless ones (its rod-rock law built
    from the config, theory §4d), and back."""
    drifter = CircuitDrifter.from_config(load_config())
    parameter, x = drifter.to_dimensionless(key, value)
    assert parameter == name
    assert x == pytest.approx(drifter.model().law.parameter_value(name), rel=1e-14)
    assert drifter.from_dimensionless(key, x) == pytest.approx(si, rel=1e-14)


def test_a_rock_parameter_needs_a_rock():
    """Without a ``[rock]`` section the rock's keys are refused in one line."""
    config = load_config()
    for section in ("rock", "rod", "bit"):
        config.pop(section, None)
    config["stop"] = {"restitution": 0.3}
    with pytest.raises(ValueError, match=r"rock\.k is the drill string's and the rock's: the drifter has no"):
        CircuitDrifter.from_config(config).to_dimensionless("rock.k", "400 kN/mm")


def test_the_operating_point_is_followed_in_the_rocks_stiffness(point):
    """``continue_circuit`` in ``rock.k`` (SI): the branch starts at the config's stiffness, in N/m,
    and each point is an orbit of the circuit on the rock of its stiffness (the residual of the
    problem built there at the integrator's accuracy)."""
    from impactbar.physical import continue_circuit

    branch = continue_circuit(point.drifter, "rock.k", "460 kN/mm", max_points=2)
    assert branch.unit == "N/m" and branch.values[0] == pytest.approx(4.7e8, rel=1e-12)
    assert branch.values[1] < branch.values[0]
    for o in branch.branch.orbits:
        X = np.asarray(o._unknowns, dtype=float)
        assert np.max(np.abs(o.problem.value(X))) < 1e-9
    assert branch.blow_frequency_Hz[0] == pytest.approx(point.blow_frequency_Hz, rel=1e-9)


def test_the_examples_lattice_error_at_four_times_the_cells(point):
    """The example's figures are the slot lattice's at 8 cells per piston (the coupled blow, theory
    §11): at 32 cells the same 45.66 Hz and 218.4 J on the rock (README, docs/physical.md), the blow
    frequency 1e-6 apart (measured 8e-7)."""
    config = load_config()
    config["rock"]["cells_per_piston"] = 32
    fine = CircuitDrifter.from_config(config).orbit()
    assert (round(fine.blow_frequency_Hz, 2), round(fine.rock()["work_on_rock_J"], 1)) == (45.66, 218.4)
    assert abs(point.blow_frequency_Hz / fine.blow_frequency_Hz - 1.0) < 1e-6


def test_the_command_line_simulation_writes_the_work_on_rock_and_the_penetration(point, monkeypatch,
                                                                                 tmp_path, capsys):
    """``impactbar simulate examples/circuit_drifter_rock.toml``: impacts.csv holds each blow's work on
    rock (J) and permanent penetration (m) beside its time, velocity and energy, those that
    ``CircuitDrifter.simulate`` returns for the same run (3 periods of the operating point from rest;
    the orbit the fixture's: the same configuration)."""
    from impactbar.cli import main

    monkeypatch.setattr(CircuitDrifter, "orbit", lambda self, guess=None: point)
    assert main(["simulate", str(EXAMPLE), "--periods", "3", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    head, *rows = (tmp_path / "impacts.csv").read_text().splitlines()
    assert head == "time_s,impact_velocity_m_s,impact_energy_J,work_on_rock_J,penetration_m"
    got = np.array([[float(x) for x in r.split(",")] for r in rows])
    run = point.drifter.simulate(3 * point.period_s)
    assert got.shape == (run["impact_times_s"].size, 5) and got.shape[0] >= 2
    np.testing.assert_allclose(got[:, 0], run["impact_times_s"], rtol=1e-8)
    np.testing.assert_allclose(got[:, 3], run["work_on_rock_J"], rtol=1e-8)
    np.testing.assert_allclose(got[:, 4], run["penetration_mm"] / 1e3, rtol=1e-8)
    # each blow puts into the rock part of the piston's energy at impact (the feed's work is small)
    assert np.all((got[:, 3] > 0) & (got[:, 3] < got[:, 2])) and np.all(got[:, 4] > 0)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["mean_work_on_rock_J_second_half"] == pytest.approx(got[got.shape[0] // 2:, 3].mean())
