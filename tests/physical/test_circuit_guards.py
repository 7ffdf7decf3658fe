"""The drifter with its oil circuit off its happy path (``impactbar.physical.circuit``): a stop that
keeps the piston (``restitution = 0``, a rest phase on the stop), the config's values checked in SI
with the user's key, and orbits that are no motion at all refused."""

import numpy as np
import pytest

from impactbar.physical.circuit import CIRCUIT_PRESETS, circuit_preset


def test_a_run_with_restitution_zero_rests_on_the_stop_and_its_energy_account_closes():
    """With ``R = 0`` every arrival ends the piston's motion: it rests on the stop while the oil
    presses it there (the circuit's state integrated alone), then leaves when the force turns. The
    rest phase was integrated with the circuit's CVODE name handed to scipy (refused); now the rest
    carries the circuit's energy terms, so that the account closes over the whole run."""
    from impactbar.drives.flight import QuadratureRestPiece

    d = circuit_preset("circuit-drifter", stop={"restitution": 0})
    out = d.simulate(0.04)
    run = out["run"]
    assert out["impact_times_s"].size >= 1 and run.contact_intervals.shape[0] >= 1
    rests = [p for p in run.pieces if isinstance(p, QuadratureRestPiece)]
    assert len(rests) == run.contact_intervals.shape[0]
    alpha = run.drive.chambers.area_ratio
    for p in rests:
        assert p.t_end > p.t0
        t = np.linspace(p.t0, p.t_end, 201)
        z = p.drive_state(t)
        force = z[1] - alpha * z[0]
        assert np.all(force > -1e-9)  # the oil presses the piston onto the stop throughout
        assert abs(force[-1]) < 1e-8  # and it leaves where the force turns
        q, v = run.modal_state(t)
        assert np.all(q == 0.0) and np.all(v == 0.0)
        assert p.energies()[0] > 0.0 and p.energies()[1] == 0.0  # the pump works, the piston does not
    acc = run.drive.energy(run)
    assert abs(acc["relative_residual"]) < 1e-9
    # the account without the rests' terms would be off by the pump's work during them
    assert sum(p.energies()[0] for p in rests) > 1e-4 * acc["pump"]


_PRESET = CIRCUIT_PRESETS["circuit-drifter"]
#: every key of the circuit's sections with a value to turn negative (the preset's, or one in range)
_KEYS = [(sec, key, value) for sec in ("chambers", "valve", "supply", "accumulator", "oil")
         for key, value in _PRESET[sec].items()] + [("valve", "switch_in", "10 mm")]


def _negative(value):
    if isinstance(value, str):
        number, unit = value.split(" ", 1)
        return f"-{number} {unit}", unit
    return -value, ""


def _refused(**changes) -> str:
    with pytest.raises(ValueError) as info:
        circuit_preset("circuit-drifter", **changes)
    message = str(info.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize(("sec", "key", "value"), _KEYS, ids=[f"{s}.{k}" for s, k, _ in _KEYS])
def test_a_key_given_none_is_refused_naming_it_and_its_unit(sec, key, value):
    """``None`` reached the arithmetic (a TypeError) or read as the key left out."""
    message = _refused(**{sec: {key: None}})
    assert message.startswith(f"{sec}.{key} must be ") and "got None" in message
    if isinstance(value, str):  # the unit it needs, with an example
        assert "e.g. '" in message and any(u in message for u in ("m^2", "m^3", "m^3/s", "Pa", "m", "s"))


@pytest.mark.parametrize(("sec", "key", "value"), _KEYS, ids=[f"{s}.{k}" for s, k, _ in _KEYS])
def test_a_negative_value_is_refused_in_si_naming_the_key_and_quoting_the_value(sec, key, value):
    """Each refused before the conversion to the dimensionless circuit: the key as ``section.key``
    and the value as the user wrote it, with its unit (not a bare name and a dimensionless number),
    ``accumulator.volume = "-0.5 L"`` among them (it read as no accumulator)."""
    negative, unit = _negative(value)
    message = _refused(**{sec: {key: negative}})
    assert message.startswith(f"{sec}.{key} must be ")
    assert message.endswith(f"; got {negative}".rstrip()) and (unit == "" or unit in message)


@pytest.mark.parametrize(("changes", "expected"), [
    ({"supply": {"relief_pressure": "0.2 MPa"}},
     "supply.relief_pressure must be above supply.tank_pressure (0.3 MPa); got 0.2 MPa"),
    ({"chambers": {"rear_volume": "-0.1 L"}}, "chambers.rear_volume must be positive; got -0.1 L"),
    ({"accumulator": {"volume": "-0.5 L"}},
     "accumulator.volume must be 0 or above (0: no accumulator); got -0.5 L"),
    ({"accumulator": {"precharge": "30 MPa"}},
     "accumulator.precharge must be below supply.relief_pressure (25 MPa): the accumulator would never take "
     "oil; got 30 MPa"),
    ({"chambers": {"front_area": "6 cm^2"}},
     "chambers.front_area must be below chambers.rear_area (5.6 cm^2) for the stroke to push toward the "
     "stop; got 6 cm^2"),
    ({"valve": {"switch_in": "30 mm"}},
     "valve.switch_in must be above 0 and below valve.switch_out (21.5 mm); got 30 mm"),
    ({"accumulator": {"polytropic_exponent": 2.5}},
     "accumulator.polytropic_exponent must be in [1, 2] (1 isothermal, 1.4 adiabatic nitrogen); got 2.5"),
    ({"stop": {"restitution": 1.0}}, "stop.restitution must be in [0, 1); got 1"),
    ({"supply": {"relief_coefficient": "0 m^3/s/Pa"}},
     "supply.relief_coefficient must be positive with a supply.relief_pressure; got 0 m^3/s/Pa"),
])
def test_range_errors_speak_si(changes, expected):
    assert _refused(**changes) == expected


_BEYOND = "below the rear chamber's length, chambers.rear_volume / chambers.rear_area ({vol} / 5.6 " \
    "cm^2), where the piston, still retracting, empties the rear chamber before it reaches the switch " \
    "point; got {got}"


@pytest.mark.parametrize(("switch_out", "rear_volume", "limit", "got"), [
    ("24 m", "0.1 L", "178.571 mm", "24000 mm"),  # meant mm: SI is shown in the display unit
    ("20 cm", "0.1 L", "17.8571 cm", "20 cm"),  # the unit the config wrote
    ("21.5 mm", "0.012 L", "21.4286 mm", "21.5 mm"),  # a rear chamber too short for the preset's switch
])
def test_a_switch_point_beyond_the_rear_chamber_is_refused_naming_the_cause(switch_out, rear_volume, limit,
                                                                           got):
    """``switch_out = "24 m"`` (meant mm) was taken, then the run from rest failed with "the rear
    chamber empties (V <= 0) near t = 1.64831 ... give a larger rear_volume (now 0.398115)": numbers
    in the model's units and not the cause, a switch point the piston cannot reach before its
    retraction empties the rear chamber (at ``rear_volume / rear_area``: 0.1 L / 5.6 cm^2 = 178.571 mm)."""
    message = _refused(valve={"switch_out": switch_out}, chambers={"rear_volume": rear_volume})
    assert message == (f"valve.switch_out must be in (0, {limit}): "
                       + _BEYOND.format(vol=rear_volume, got=got))
    # the limit itself: the rear chamber's volume over its area
    assert float(limit.split()[0]) == pytest.approx(
        float(rear_volume.split()[0]) * 1e-3 / 5.6e-4 * {"mm": 1e3, "cm": 1e2}[limit.split()[1]], rel=1e-5)


def test_a_switch_point_just_inside_the_rear_chamber_is_taken():
    d = circuit_preset("circuit-drifter", chambers={"rear_volume": "0.0121 L"})
    assert d.si["switch_out_m"] == pytest.approx(0.0215, rel=1e-15)


def test_an_accumulator_of_no_volume_is_still_none():
    d = circuit_preset("circuit-drifter", accumulator={"volume": "0 L"})
    assert d.drive().accumulator is None


_DEGENERATE = [("valve", "switch_out", "21.5 mm", "0.0215 mm"),
               ("supply", "pump_flow", "70 L/min", "70000 L/min")]


@pytest.mark.parametrize(("sec", "key", "was", "value"), _DEGENERATE,
                         ids=[f"{s}.{k}" for s, k, _, _ in _DEGENERATE])
def test_no_orbit_of_period_zero(sec, key, was, value, tmp_path, capsys):
    """From the example's config the run from rest settles onto the piston resting on the stop (its
    bounces dying away): Newton's fixed point there was returned as an orbit of period 0 and impact
    velocity 1e-27 (``blow_frequency_Hz`` a ZeroDivisionError, the command line a traceback)."""
    from pathlib import Path

    from impactbar.cli import main

    with pytest.raises(ValueError, match=r"degenerate solution \(period 0, impact velocity .*e-2\d\): the "
                                         "piston resting on the stop"):
        circuit_preset("circuit-drifter", **{sec: {key: value}}).orbit()
    example = (Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter.toml").read_text()
    line = f'{key} = "{was}"'
    assert line in example
    config = tmp_path / "circuit.toml"
    config.write_text(example.replace(line, f'{key} = "{value}"'))
    assert main(["orbits", str(config)]) == 2
    err = capsys.readouterr().err
    # the implausible value is warned of in a line of its own, then the error in one line
    warning, error = err.splitlines()
    assert warning.startswith(f"impactbar orbits: warning: {sec}.{key} = '{value}'")
    assert "Traceback" not in err and "period 0" in error
    assert error.startswith("impactbar orbits: error: find_orbit found no periodic orbit")


def test_an_orbit_past_the_relief_pressure_opens_the_relief_and_repeats_in_simulate(monkeypatch):
    """At ``oil.transition_pressure = 50 MPa`` the settling of the motion from rest extrapolated the
    supply pressure (Aitken's step) past the relief pressure without the relief valve's event, and
    Newton converged with the relief closed at 29.6 MPa against its 25 MPa: a stable "orbit" of period
    0.866 that simulate, restarted from its state (the relief then open), did not repeat (its first
    interval 1.036 periods). The extrapolation no longer jumps a switching surface; an orbit whose
    mode its state contradicts is refused, and so is one that simulate does not repeat."""
    import dataclasses

    from impactbar import InitialState, simulate
    from impactbar.orbits import driven_search, shooting

    d = circuit_preset("circuit-drifter", oil={"transition_pressure": "50 MPa"})
    o = d.orbit().orbit
    (_, mode), = o.problem.blocks
    p_s, p_rel = o.drive_states[0][2], o.drive.supply.relief_pressure
    assert (p_s > p_rel) == bool(mode[3])  # the relief valve's flag as its pressure says
    restart = dataclasses.replace(o.drive, start_pressures=tuple(o.drive_states[0]))
    run = simulate(o.model, restart, InitialState.rigid(0.0, o.states_after_impact[0][1]), 3.5 * o.period)
    assert np.allclose(np.diff(np.concatenate(([0.0], run.impact_times))), o.period, rtol=1e-6, atol=0)
    assert np.allclose(run.impact_velocities, o.impact_velocity, rtol=1e-6, atol=0)
    # the extrapolation allowed to jump the surface again (and a growing drift not carried to the surface
    # first, which now reaches the relief before the extrapolation would): each guard refuses what it gives
    monkeypatch.setattr(shooting, "expanding_to_surface", lambda *a, **k: None)
    monkeypatch.setattr(shooting, "surfaces_ahead", lambda *a, **k: True)
    with pytest.raises(ValueError, match="drive's mode at an impact is not the one its state gives"):
        d.orbit()
    monkeypatch.setattr(driven_search, "surfaces_ahead", lambda *a, **k: True)
    with pytest.raises(ValueError, match=r"does not repeat when simulate restarts it .*\(the first interval "
                                         r"1\.03\d+ periods\)"):
        d.orbit()


def test_a_branch_ends_on_its_target_where_the_corrector_would_pass_it():
    """The preset's circuit with ``switch_in = 8 mm`` and a front feed of 250 L/min at 5 bar, followed
    in the pump flow to 75 L/min in steps of 0.02: past the relief valve's border collision (72.49
    L/min) the corrector carried the next point to 76.6 L/min, beyond the target (status 'turned
    back'); the step is now corrected onto the target instead."""
    from impactbar import physical

    front = f"{physical.flow_coefficient('250 L/min', '5 bar')} m^3/s/Pa^0.5"
    valve = {**_PRESET["valve"], "switch_in": "8 mm"}
    supply = {**_PRESET["supply"], "front_flow_coefficient": front}
    d = physical.CircuitDrifter.from_config({**_PRESET, "valve": valve, "supply": supply})
    b = physical.continue_circuit(d, "supply.pump_flow", "75 L/min", step=0.02, max_step=0.02)
    assert b.branch.status == "reached"
    assert b.values[-1] * 6e4 == pytest.approx(75.0, rel=1e-12)
    assert np.all(b.values * 6e4 <= 75.0 * (1 + 1e-12))
    assert [e["kind"] for e in b.events] == ["border-collision relief"]


def test_a_plastic_impact_orbit_that_leaves_the_stop_at_once_is_refused_saying_why(monkeypatch):
    """At ``stop.restitution = 0`` find_orbit's one-impact orbit leaves the stop at once after the
    impact, but there the oil presses the piston on the stop (the rear force above the front's:
    MODEL's admissibility at R = 0 needs the load to pull the end away), so the orbit passes through
    the stop: its own flight goes past the stop, while simulate restarted from its state rests the
    piston there, whether the state puts it on the stop exactly or a rounding before it (a start on
    the stop at rest, pressed, used to fly through it). The restart check refuses it, and says so
    (it said the orbit did not repeat, its first interval 1 period)."""
    import dataclasses

    from impactbar import InitialState, simulate
    from impactbar.physical import circuit, load

    drifter = load("examples/circuit_drifter.toml")
    drifter = dataclasses.replace(drifter, restitution=0.0)
    seen = []
    check = circuit._check_repeats
    monkeypatch.setattr(circuit, "_check_repeats", lambda orbit: (seen.append(orbit), check(orbit)))
    with pytest.raises(ValueError, match=r"leaves the stop at once after its plastic impact .*simulate rests "
                                         r"it there 0\.0\d+ periods, so the orbit passes through the stop"):
        drifter.orbit()
    o = seen[0]
    z = o.drive_states[0]
    assert z[1] - o.drive.chambers.area_ratio * z[0] > 0.0  # the oil presses the piston on the stop
    y = np.asarray(o.states_after_impact[0], dtype=float)
    M = o.model.n_modes + 1
    times = np.linspace(0.005, 0.02, 4)
    assert np.all(o.modal_state(times)[0][0] > 1e-6)  # the orbit's own flight: past the stop
    restart = dataclasses.replace(o.drive, start_pressures=tuple(z))
    assert abs(y[0]) < 1e-20  # (on the stop to rounding, either side)
    for q0 in (y[0], 0.0):  # (as the impact map gave it, and on the stop exactly)
        run = simulate(o.model, restart, InitialState(np.array([q0]), y[M:]), 0.02)
        assert np.all(run.displacement(1.0, times) == 0.0)  # at rest on the stop
