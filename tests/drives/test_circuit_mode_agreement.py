"""The circuit's discrete state agrees with its continuous state (theory §11, *Parts of a drill's
circuit*): an orbit returned is a solution, each of its modes the one its state says, and a run
restarted from it repeats it.

- A block's mode is fixed from the guess, and its flight starts in the mode its state says
  (``start_mode``). Continued from the drill's orbit at a cracking pressure of 0.0922 MPa
  (``examples/circuit_drill_parts.toml``), whose check valve is fully open at the impact, to 0.0944
  MPa, where the drop at the impact is below the full opening's level, the guess's mode says "open";
  the problem's event pattern starts with the mode the state says (``consistent_mode``'s), and the
  orbit found from that guess returns that mode in its blocks, starts its event pattern with it and
  repeats when ``simulate`` restarts it from its state.
- An arrival at the stop on the same root as a level's crossing turns the level's flag. On the preset
  drifter with a check valve that passes no oil (its flights the drive's own on either side of its
  levels), from the front chamber to the supply, the drop is greatest over a flight at its arrival; a
  cracking level one rounding below the drop there is crossed on the arrival's root (the flights the
  same, no flight ended by the crossing). The flag is set after the flight, as the drop is past the
  level, in the orbit's flights and in a run of ``simulate``, and a run restarted from the state
  handed on starts in the mode handed on and repeats the next flight.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from impactbar import InitialState, physical, simulate
from impactbar.drives.circuit import CheckValve
from impactbar.drives.circuit.watch import consistent_mode
from impactbar.orbits import find_orbit
from impactbar.orbits.driven import orbit_problem
from impactbar.orbits.shooting import ShootingProblem

pytest.importorskip("pint")

ROOT = Path(__file__).resolve().parents[2] / "examples"


def _watch(drive, name):
    (w,) = [w for w in drive._watched if w.name == name]
    return w


def _repeats(orbit, mode):
    """``simulate`` restarted from the orbit's state after its impact (its flags from that state)
    starts in ``mode`` and repeats the orbit over two periods."""
    M = orbit.model.n_modes + 1
    y = np.asarray(orbit.states_after_impact[0], dtype=float)
    restart = dataclasses.replace(orbit.drive, start_pressures=tuple(orbit.drive_states[0]))
    assert restart.start(orbit.model, y[:M], y[M:]).mode == mode
    T = orbit.period
    run = simulate(orbit.model, restart, InitialState(y[:M], y[M:]), 2.0 * T * (1.0 + 1e-3), max_impacts=2)
    assert np.allclose(run.impact_times, T * np.arange(1, 3), rtol=1e-6, atol=0.0)
    assert np.allclose(run.impact_velocities, orbit.impact_velocity, rtol=1e-6, atol=0.0)


def test_an_orbits_start_mode_is_the_one_its_flight_starts_in():
    cfg = physical.read_config(str(ROOT / "circuit_drill_parts.toml"))[0]

    def drill(crack):
        return physical.build(physical.with_values(cfg, {"parts.check.cracking_pressure": crack}))

    ob = drill("0.0922 MPa").orbit().orbit
    drive = drill("0.0944 MPa").drive()
    M = ob.model.n_modes + 1
    w = _watch(drive, "check_open")
    X = ob.problem.unknowns(ob)
    problem = orbit_problem(ob.model, drive, 1, ob.problem.settings).adopt(ob.problem)
    ((_, guess),) = problem.blocks
    says = consistent_mode(drive._watched, guess, X[:M], X[2 * M:])
    assert guess[1 + w.slot] == 1 and says[1 + w.slot] == 0 == w.flag(X[:M], X[2 * M:])
    assert problem.start_modes(X) == [says]
    assert problem.event_pattern(X)[0] == ("start", says)
    # the orbit found from that guess: its blocks' mode the one its state says, its pattern's too
    found = find_orbit(ob.model, drive, guess=ob)
    Xf = found.problem.unknowns(found)
    ((_, mode),) = found.problem.blocks
    assert mode[1 + w.slot] == 0 == w.flag(Xf[:M], Xf[2 * M:])
    assert consistent_mode(drive._watched, mode, Xf[:M], Xf[2 * M:]) == mode
    pattern = found.problem.event_pattern(Xf)
    assert pattern[0] == ("start", mode) and "check_open" not in [name for name, _ in pattern]
    _repeats(found, mode)


def _inert(drive, level):
    """``drive`` with a check valve from the front chamber to the supply that passes no oil
    (coefficient 0), cracking at ``level``."""
    valve = CheckValve("front", "supply", coefficient=0.0, cracking_pressure=level, opening_span=1.0)
    return dataclasses.replace(drive, extra_parts=(valve,))


@pytest.fixture(scope="module")
def start(preset):
    """``(tau, mode, X)``: the preset orbit's block with its front chamber's pressure 1e-3 lower, so
    that the drop to the supply, below the level at the start, rises to its greatest at the arrival;
    the mode that of the drive with the inert valve (its flags 0: no level reached)."""
    model, drive, orbit = preset
    ((tau, mode),) = orbit.problem.blocks
    X = orbit.problem.unknowns(orbit).copy()
    X[2 * (model.n_modes + 1) + drive.layout["front"]] -= 1e-3
    return tau, (*mode, 0, 0), X


def _coincident(drive, arrival_drop):
    """The level one rounding below the drop at the arrival of the flights of ``_inert(drive, .)``
    (``arrival_drop(inert drive)``: a level never reached, 50): crossed on the arrival's root."""
    x = arrival_drop(_inert(drive, 50.0))
    return x - np.spacing(x)


def test_an_arrival_on_a_levels_root_turns_its_flag_in_the_orbits_flights(preset, start):
    model, drive, orbit = preset
    tau, mode, X = start
    M = model.n_modes + 1
    first = {}

    def arrival_drop(d):
        out = first["far"] = ShootingProblem(model, d)._flight(tau, mode, X, keep=True)
        _, _, _, (_, qa, _, sa), pieces, events = out
        w = _watch(d, "check_crack")
        drops = [w.quantity(*y) for p in pieces for t in [np.linspace(p.t0, p.t_end, 500)]
                 for y in zip(p.modal(t)[0].T, p.drive_state(t).T, strict=True)]
        x = w.quantity(qa, sa.z)
        assert max(drops) <= x and drops[0] < x - 1e-4 and events  # (greatest at the arrival)
        return x

    dr = _inert(drive, _coincident(drive, arrival_drop))
    w = _watch(dr, "check_crack")
    problem = ShootingProblem(model, dr)
    y, t_after, after, (t_arr, _, _, _), _, events = problem._flight(tau, mode, X, keep=True)
    far = first["far"]
    assert t_arr == far[3][0] and len(events) == len(far[5]) + 1  # (the same flights)
    te, e, _, _ = events[-1]
    assert e.name == "check_crack" and te == t_arr  # (on the arrival's root)
    q, z = y[:M], y[2 * M:]
    assert w.quantity(q, z) >= w.level and after[1 + w.slot] == 1 == w.flag(q, z)
    assert consistent_mode(dr._watched, after, q, z) == after
    # restarted from the state handed on (its flags from it), the run starts in the mode handed on and
    # repeats the next flight
    restart = dataclasses.replace(dr, start_pressures=tuple(z))
    assert restart.start(model, q, y[M:2 * M]).mode == after
    _, _, _, (t_next, _, _, _), _, later = problem._flight(t_after, after, y, keep=True)
    assert later[0][1].name == "check_crack" and later[0][2][1 + w.slot] == 0  # (the drop falls back)
    run = simulate(model, restart, InitialState(q, y[M:2 * M]), 2.0 * orbit.period, max_impacts=1)
    assert run.impact_times[0] == pytest.approx(t_next - t_after, rel=1e-9)


def test_an_arrival_on_a_levels_root_turns_its_flag_in_a_run(preset, start):
    model, drive, _ = preset
    _, _, X = start
    M = model.n_modes + 1
    first = {}

    def run_of(d):  # (to the first impact: the drive's state there, before the impact's map)
        d = dataclasses.replace(d, start_pressures=tuple(X[2 * M:]))
        return simulate(model, d, InitialState(X[:M], X[M:2 * M]), 3.0, max_impacts=1)

    def arrival_drop(d):
        run = first["far"] = run_of(d)
        return _watch(d, "check_crack").quantity(np.asarray(run.final_state.modal_displacement),
                                                 run._final_drive.z)

    dr = _inert(drive, _coincident(drive, arrival_drop))
    w = _watch(dr, "check_crack")
    run, far = run_of(dr), first["far"]
    assert np.array_equal(run.impact_times, far.impact_times)
    assert len(run.pieces) == len(far.pieces)  # (no flight ended by the crossing: on the arrival's root)
    q, (mode, z) = np.asarray(run.final_state.modal_displacement), run._final_drive
    assert w.quantity(q, z) >= w.level and mode[1 + w.slot] == 1 == w.flag(q, z)
    assert consistent_mode(dr._watched, mode, q, z) == mode
