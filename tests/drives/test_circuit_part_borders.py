"""The border collisions of a drill's parts (theory §11, *Parts of a drill's circuit*): each watched
level (a check valve's cracking and full opening, a cushion's kinks, a spool's ports) and each
spool's stop has border-collision tests, and continuation locates where the orbit's crossings of one
change.

- On the spool drill (``examples/circuit_drill_spool.toml``) each level's ``.max`` and ``.min`` are the
  greatest and the least of the watched quantity less its level, checked against the watch's own
  quantity (``Watch.quantity``, the events' Python twin) on a dense sampling of the period's flights;
  each stop's ``.high`` and ``.low`` say the spool rests at both ends of its stroke, as its position
  history does.
- The check valve's tests read as its flow does: with its cracking pressure above every pressure
  drop over the period its ``.max`` is below 0 and no oil passes it; at the example's it is above 0
  and oil passes.
- Continued in the valve's switch point, the drill on the ramped valve
  (``examples/circuit_drill_parts.toml``) meets the cushion's last kink (45 mm): the piston's
  greatest gap over the period, from fresh orbits' histories on either side, crosses the kink where
  the branch's border collision says.
- Continued in the check valve's cracking pressure, the same drill meets the valve's full opening: the
  front chamber's greatest pressure drop to the supply, at the impact, falls below the full opening's
  level. A block's flight from a state past that level, in the mode of an orbit before it (the
  corrector's first iterate), starts with the flag the state says and passes; the branch reaches its
  end, and fresh orbits' pressure histories on either side cross the level where its border
  collision says.
- Continued in the spool's damping, the spool drill meets its spool's low stop's border: slowed, the
  spool reaches the stop no longer pushed into it and leaves it at once; the greatest push into the
  stop while the spool is at it, read from fresh orbits' dense states on either side, crosses 0 where
  the branch's border collision says.
"""

from pathlib import Path

import numpy as np
import pytest

from impactbar import BranchStatus, physical
from impactbar.continuation.driven import border_tests
from impactbar.drives.circuit import _network as NW
from impactbar.orbits import find_orbit
from impactbar.orbits.driven import orbit_problem

pytest.importorskip("pint")

ROOT = Path(__file__).resolve().parents[2] / "examples"


def _changed(path, values):
    """The drifter of the config at ``path`` with ``values`` (dotted keys, SI quantities) set."""
    return physical.build(physical.with_values(physical.read_config(str(path))[0], values))


@pytest.fixture(scope="module")
def spool_orbit():
    d = physical.load(ROOT / "circuit_drill_spool.toml")
    return find_orbit(d.model(), d.drive())


def _dense(orbit, per_flight=400):
    """The watched quantities' inputs ``(q, z)`` at ``per_flight`` points of each of the period's
    flights (their cubic Hermite interpolants)."""
    problem = orbit.problem
    out = []
    for p in problem.flights(problem.unknowns(orbit)):
        Y = p._at(np.linspace(p.t0, p.t_end, per_flight))
        nz = len(p.layout.state_names)
        out.extend((Y[:p.M, i], Y[2 * p.M:2 * p.M + nz, i]) for i in range(Y.shape[1]))
    return out


def test_each_level_and_stop_has_its_tests_and_they_are_the_quantitys_extremes(spool_orbit):
    tests = border_tests(spool_orbit)
    watches = spool_orbit.drive._watched
    samples = _dense(spool_orbit)
    levels = [w for w in watches if w.kind == NW.LEVEL]
    stops = [w for w in watches if w.kind == NW.SPOOL]
    assert len(levels) == 11 and len(stops) == 1  # (the spool's 6, the cushion's 3, the check's 2)
    for w in levels:
        x = np.array([w.quantity(q, z) for q, z in samples])
        span = x.max() - x.min()
        assert tests[f"{w.name}.max"] == pytest.approx(x.max() - w.level, abs=1e-4 * span), w.name
        assert tests[f"{w.name}.min"] == pytest.approx(x.min() - w.level, abs=1e-4 * span), w.name
        assert tests[f"{w.name}.max"] >= x.max() - w.level - 1e-12 * span  # (the interpolants' own)
    (stop,) = stops
    x = np.array([z[stop.form[0][0][1]] for _, z in samples])  # (the spool's position)
    g = np.array([stop.quantity(q, z) for q, z in samples])
    assert abs(x.min()) < 1e-12 and abs(x.max() - 1.0) < 1e-12  # (it rests at both ends of its stroke)
    for name, at in ((".high", x >= 1.0 - 1e-12), (".low", x <= 1e-12)):
        assert tests[stop.name + name] > 0.0
        assert tests[stop.name + name] == pytest.approx(g[at].max(), rel=1e-2)


@pytest.mark.parametrize("crack, opens", [("0.05 MPa", True), ("0.5 MPa", False)])
def test_the_check_valves_test_reads_as_its_flow(crack, opens):
    point = _changed(ROOT / "circuit_drill_parts.toml", {"parts.check.cracking_pressure": crack}).orbit()
    flow = point.histories(4000)["q_check_m3_s"]
    test = border_tests(point.orbit)["check_crack.max"]
    assert (test > 0.0) == opens
    assert (np.abs(flow).max() > 0.0) == opens


@pytest.fixture(scope="module")
def cushion_branch():
    d = physical.load(ROOT / "circuit_drill_parts.toml")
    return d, physical.continue_circuit(d, "valve.switch_out", "18 mm")


def test_continuation_locates_where_the_piston_stops_reaching_the_cushions_last_kink(cushion_branch):
    d, branch = cushion_branch
    (event,) = [e for e in branch.branch.events if e.surface == "cushion_kink2.max"]
    assert abs(border_tests(event.orbit)["cushion_kink2.max"]) < 1e-8
    (si,) = [e for e in branch.events if e["kind"] == "border-collision cushion_kink2.max"]
    at_mm = si["value"] * 1e3  # (the drifter's branch says it in the key's SI unit, m)
    assert at_mm == pytest.approx(20.72, abs=0.005)  # (theory §11 quotes it)
    # the greatest gap over the period from fresh orbits on either side
    kink, sides = 45e-3, []
    for factor in (0.99, 1.01):
        point = _changed(ROOT / "circuit_drill_parts.toml",
                         {"valve.switch_out": f"{at_mm * factor} mm"}).orbit()
        sides.append((at_mm * factor, point.histories(20000)["gap_m"].max() - kink))
    (s0, g0), (s1, g1) = sides
    assert g0 < 0.0 < g1  # (a later switch, a longer return stroke)
    crossing = s0 - g0 * (s1 - s0) / (g1 - g0)
    assert crossing == pytest.approx(at_mm, rel=1e-3)


def test_a_blocks_flight_past_the_check_valves_full_opening_starts_in_the_mode_its_state_says():
    # the orbit at 0.0922 MPa: the drop at the impact above the full opening's level (its flag set)
    before = _changed(ROOT / "circuit_drill_parts.toml",
                      {"parts.check.cracking_pressure": "0.0922 MPa"}).orbit()
    after = _changed(ROOT / "circuit_drill_parts.toml", {"parts.check.cracking_pressure": "0.0944 MPa"})
    ob = before.orbit
    X = ob.problem.unknowns(ob)
    (w,) = [w for w in ob.drive._watched if w.name == "check_open"]
    M = ob.model.n_modes + 1
    ((_, mode),) = ob.problem.blocks
    assert mode[1 + w.slot] == 1 and w.quantity(X[:M], X[2 * M:]) > w.level
    # that orbit's start flown at 0.0944 MPa, whose full opening lies above the drop at the start (the
    # corrector's first iterate): the flight once went on with the flag set and failed in CVODE
    problem = orbit_problem(ob.model, after.drive(), 1, ob.problem.settings).adopt(ob.problem)
    (w2,) = [w for w in after.drive()._watched if w.name == "check_open"]
    assert w2.quantity(X[:M], X[2 * M:]) < w2.level
    r = problem.root_value(X)
    assert np.all(np.isfinite(r)) and np.abs(r).max() < 1e-2 * np.abs(X).max()
    # the period's events: no full opening crossed, the cracking level passed once each way
    names = [e for e, _ in problem.event_pattern(X)[1:]]
    assert "check_open" not in names and names.count("check_crack") == 2


@pytest.fixture(scope="module")
def check_branch():
    d = physical.load(ROOT / "circuit_drill_parts.toml")
    return physical.continue_circuit(d, "parts.check.cracking_pressure", "0.2 MPa")


def test_continuation_passes_where_the_check_valve_stops_opening_fully(check_branch):
    branch = check_branch
    assert branch.branch.status == BranchStatus.REACHED
    assert branch.branch.values[-1] == pytest.approx(0.02, rel=1e-12)  # (0.2 MPa in 10 MPa)
    assert [e.surface for e in branch.branch.events] == ["check_open.max"]
    (event,) = branch.branch.events
    assert abs(border_tests(event.orbit)["check_open.max"]) < 1e-8
    (si,) = [e for e in branch.events if e["kind"] == "border-collision check_open.max"]
    at = si["value"]  # (Pa)
    assert at == pytest.approx(92368.7, abs=0.5)  # (benchmarks/HISTORY.md quotes it)
    assert round(at * 1e-6, 5) == 0.09237  # (theory §11 quotes it, MPa)
    # the greatest drop less the full opening's level (0.05 MPa above cracking) from fresh orbits'
    # pressure histories on either side: it is the drop at the impact, and it crosses 0 there
    sides = []
    for factor in (0.999, 1.001):
        point = _changed(ROOT / "circuit_drill_parts.toml",
                         {"parts.check.cracking_pressure": f"{at * factor} Pa"}).orbit()
        h = point.histories(20000)
        drop = h["p_f_Pa"] - h["p_s_Pa"] - (at * factor + 0.05e6)
        assert drop.max() == pytest.approx(drop[0], abs=1e-9 * 0.05e6)  # (at the impact)
        sides.append((at * factor, drop.max()))
    (s0, g0), (s1, g1) = sides
    assert g0 > 0.0 > g1  # (a higher cracking pressure, the full opening no longer reached)
    crossing = s0 - g0 * (s1 - s0) / (g1 - g0)
    assert crossing == pytest.approx(at, rel=1e-3)


def test_continuation_locates_where_the_spool_stops_resting_on_its_low_stop():
    # the spool's damping raised from the example's 50 N*s/m: past some 248 N*s/m the spool, slowed,
    # reaches its low stop no longer pushed into it and leaves it at once (its rest there ends)
    d = physical.load(ROOT / "circuit_drill_spool.toml")
    branch = physical.continue_circuit(d, "parts.main_spool.damping", "300 N*s/m")
    assert branch.branch.status == BranchStatus.REACHED
    assert [e.surface for e in branch.branch.events] == ["main_spool_stop.low"]
    (event,) = branch.branch.events
    assert abs(border_tests(event.orbit)["main_spool_stop.low"]) < 1e-8
    (si,) = [e for e in branch.events if e["kind"] == "border-collision main_spool_stop.low"]
    at = si["value"]  # (N*s/m)
    assert at == pytest.approx(247.934, abs=0.01)  # (benchmarks/HISTORY.md quotes it)
    # from fresh orbits on either side, the greatest push into the low stop while the spool is at it,
    # read from the dense states (the stop's force along the flights), not from the border test
    sides = []
    for factor in (0.999, 1.001):
        dd = _changed(ROOT / "circuit_drill_spool.toml", {"parts.main_spool.damping": f"{at * factor} N*s/m"})
        orbit = find_orbit(dd.model(), dd.drive())
        (stop,) = [w for w in orbit.drive._watched if w.kind == NW.SPOOL]
        samples = _dense(orbit)
        x = np.array([z[stop.form[0][0][1]] for _, z in samples])
        push = np.array([stop.quantity(q, z) for q, z in samples])
        assert x.min() == pytest.approx(0.0, abs=1e-12)  # (it reaches the stop on both sides)
        sides.append((at * factor, push[x <= 1e-12].max()))
    (s0, g0), (s1, g1) = sides
    assert g0 > 0.0 > g1  # (more damping: no longer pushed into the stop where it arrives)
    crossing = s0 - g0 * (s1 - s0) / (g1 - g0)
    assert crossing == pytest.approx(at, rel=1e-3)
