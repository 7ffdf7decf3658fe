"""The drifter's oil circuit (theory §11): its flights by CVODE driven from compiled code against the
same CVODE through scikit-sundae's Python interface (the way before), and against the ideal valve it
tends to (theory §10), in the same run.

Run: ``python benchmarks/bench_circuit.py`` (``--quick``: the rigid piston only). On the preset
``circuit-drifter`` (dimensionless, ``impactbar.physical.circuit_preset``) and on the ideal valve
with the preset's forces at its mean supply pressure (``PositionSwitchedDrive``): the time of
``find_orbit`` from the default guess, of ``simulate`` over 100 blows and of one continuation point in
the accumulator's pre-charge; beside each, the same call with the settings ``compiled=False``
(:class:`~impactbar.drives.circuit.CircuitFlightSettings`: every call of the vector field, its Jacobian
and the events through Python, as before). One stroke flight by
CVODE both ways and by scipy's Radau on the same compiled right-hand side and Jacobian, with CVODE's
own counters for it. Without ``--quick``, ``find_orbit`` with flexible pistons: 1 mode both ways,
8 modes with the variational flights' band solver against the dense one (the settings' ``band=False``,
the way before; about four minutes). The goals on this 2-core machine: the rigid orbit
<= 0.5 s, with 8 modes <= 2 s, 100 blows <= 1 s rigid, a continuation point <= 0.2 s. The best of a
few repetitions (the machine's other load only adds); compilation is done before the clock starts.
Under the table, the example drill with all the parts a drifter has (``examples/circuit_drill_spool.toml``:
the return line's accumulator, leakage, a cushion, a check valve and a pilot-operated spool valve; rigid
piston) and the same drill with the preset's ramped valve (``examples/circuit_drill_parts.toml``): each
orbit's CPU time against the preset's in the same run, the goal at most 3x: met or missed
(``--drill``: those rows only; ``--drill --against REF`` beside those of the git ref ``REF``, or
of a package tree's ``src`` folder, each tree in fresh processes, ``--rounds`` each).

``--goals REF`` instead runs, one after the other, the benchmarks that measure each goal of the
elastic piston's circuit work against the git ref ``REF`` (e.g. ``main``), each in fresh processes
on both trees in the same run, and prints each goal above its script's table: the circuit's orbits
rigid and with 4, 8 and 16 modes and a continuation point with 8 modes
(``bench_circuit_modes.py``), the circuit on rock (``bench_circuit_laws.py``), the exact blow under
the circuit (``bench_coupled_exact.py``), the wave law's blow under the circuit
(``bench_wave_states.py``), the first exact blow and the first rock orbit with an empty numba cache
(``bench_first_call.py``) and the rigid bar's fixed cost against a compiled minimal loop
(``bench_fast_paths.py``); under each table, each goal's number on this tree against the goal: met,
or missed and why (measured: :data:`WHY_CONTINUATION`, :data:`WHY_ROCK_COMPILE`). Some half an hour
on the 2-core machine; ``--only TEXT`` runs the goals whose text holds ``TEXT`` (e.g. ``--only "the
circuit on rock"``).
"""

from __future__ import annotations

import argparse
import functools
import sys
import time
from pathlib import Path

import impactbar.drives.circuit.flight as FL
from impactbar import InitialState, PositionSwitchedDrive, continue_orbit, find_orbit, simulate
from impactbar.drives.circuit import CircuitFlightSettings
from impactbar.physical import circuit_preset, load


def best(fn, reps, clock=time.perf_counter):
    out = float("inf")
    for _ in range(reps):
        t = clock()
        fn()
        out = min(out, clock() - t)
    return out


def before(**options):
    """The settings of the flights integrated the way before (``compiled=False``: through
    scikit-sundae's Python interface; ``band=False``: the dense solver), the drive the same."""
    return CircuitFlightSettings(**options)


def rigid_rows(d, drive):
    """``{task: (compiled, through scikit-sundae, ideal valve)}`` seconds on the rigid preset."""
    model = d.model()
    o = find_orbit(model, drive)
    ps = o.drive_states[0][2]
    a = drive.chambers.area_ratio
    ideal = PositionSwitchedDrive(stroke=ps * (1 - a), ret=a * ps - drive.supply.tank_pressure,
                                  switch_out=drive.valve.switch_out)
    oi = find_orbit(model, ideal)
    start = InitialState.rigid(0.0, 0.0, 0)
    slow = before(compiled=False)
    tasks = {
        "find_orbit from the default guess": (lambda s: find_orbit(model, drive, settings=s),
                                              lambda: find_orbit(model, ideal)),
        "simulate, 100 blows": (lambda s: simulate(model, drive, start, 100.5 * o.period, settings=s),
                                lambda: simulate(model, ideal, start, 100.5 * oi.period)),
    }
    out = {}
    for name, (circuit, ideal_fn) in tasks.items():
        out[name] = (best(functools.partial(circuit, None), 3), best(functools.partial(circuit, slow), 2),
                     best(ideal_fn, 3))
    o_slow = find_orbit(model, drive, settings=slow)  # (its continuation keeps its settings)
    now = min(_cont_point(o, "precharge", drive.accumulator.precharge) for _ in range(3))
    then = min(_cont_point(o_slow, "precharge", drive.accumulator.precharge) for _ in range(2))
    ideal_point = min(_cont_point(oi, "switch_out", ideal.switch_out) for _ in range(3))
    out["a continuation point (pre-charge)"] = (now, then, ideal_point)
    return out


def _cont_point(o, name, value):
    """Seconds per point of a continuation in ``name`` over 5 % (at most 5 points)."""
    t = time.perf_counter()
    b = continue_orbit(o, name, to=value * 1.05, max_points=6, events=False)
    return (time.perf_counter() - t) / max(1, len(b.orbits) - 1)


def flexible_rows(d, drive):
    """``find_orbit`` with 1 mode compiled and through scikit-sundae, 8 modes with the band solver and
    the dense one (both compiled; one repetition each)."""
    out = []
    m1 = d.model().with_(n_modes=1)
    find_orbit(m1, drive)
    now = best(lambda: find_orbit(m1, drive), 2)
    then = best(lambda: find_orbit(m1, drive, settings=before(compiled=False)), 1)
    out.append((1, "through scikit-sundae", now, then))
    m8 = d.model().with_(n_modes=8)
    now = best(lambda: find_orbit(m8, drive), 1)
    then = best(lambda: find_orbit(m8, drive, settings=before(band=False)), 1)
    out.append((8, "dense solver", now, then))
    return out


def integrators(d, drive):
    """One stroke flight of the rigid preset (from rest 60 mm out, the supply at 22 MPa, to the
    impact) by CVODE compiled, through scikit-sundae and by scipy's Radau on the same compiled
    right-hand side and Jacobian, all at rtol 1e-10: seconds, steps, and CVODE's counters."""
    import numpy as np
    from scipy.integrate import solve_ivp

    from impactbar.drives import DriveState
    from impactbar.drives.circuit import _cvode

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    import circuit_field_reference as K  # (the preset's kernel written by hand: the tests' reference)

    model = d.model()
    q, v = np.array([-0.06 / d.bar.length_m]), np.array([0.0])
    state = DriveState((1, 0, 1, 0), np.array([2.2, 2.2, 2.2, 1.0]))
    par = K.preset_par(drive, model, state.mode)
    n = 6 + K.N_ENERGY
    calls = [0]

    def f(t, y):
        calls[0] += 1
        out = np.empty(n)
        K.rhs(t, y, out, par)
        return out

    def jac(t, y):
        JJ = np.empty((n, n))
        K.jac(t, y, None, JJ, par)
        return JJ

    def arrival(t, y):
        return y[0]

    arrival.terminal, arrival.direction = True, 1
    y0 = np.concatenate((q, v, state.z, np.zeros(K.N_ENERGY)))

    def one(compiled=True):
        return FL.circuit_flight(drive, model, state, 0.0, q, v, 50.0, before(compiled=compiled))

    one()  # warm-up
    t_cv = best(one, 5)
    fl = one()
    stats = _cvode.last_workspace().statistics()
    t_py = best(lambda: one(compiled=False), 3)
    f(0.0, y0), jac(0.0, y0)  # (compiled before the clock starts)
    calls[0] = 0
    t = time.perf_counter()
    ref = solve_ivp(f, (0.0, 50.0), y0, method="Radau", rtol=1e-10, atol=1e-12, jac=jac, events=arrival)
    t_ra = time.perf_counter() - t
    gap = abs(ref.t_events[0][0] - fl.t) / fl.t
    return t_cv, t_py, fl.piece.t.size, stats, t_ra, ref.t.size, calls[0], gap


#: the drill with the parts a drifter has (a return accumulator, two clearances, a cushion, a check
#: valve) on the preset's ramped valve
DRILL = Path(__file__).resolve().parents[1] / "examples" / "circuit_drill_parts.toml"
#: the example drill with all the parts: the same drill with its main valve a pilot-operated spool
SPOOL_DRILL = DRILL.with_name("circuit_drill_spool.toml")
#: the drill's rigid orbit at most this many times the preset's, same run
DRILL_GOAL = 3.0


def drill_rows(reps=3):
    """CPU seconds of ``find_orbit`` from the default guess on the rigid preset, the drill on the
    ramped valve (:data:`DRILL`) and the example drill with all the parts, its valve a spool
    (:data:`SPOOL_DRILL`), the best of ``reps`` each after one
    call that compiles, and the drills' ratios to the preset's."""
    out = {}
    for name, d in (("preset", circuit_preset("circuit-drifter")), ("drill", load(DRILL)),
                    ("spool", load(SPOOL_DRILL))):
        model, drive = d.model(), d.drive()
        find_orbit(model, drive)
        out[name] = best(lambda m=model, dr=drive: find_orbit(m, dr), reps, clock=time.process_time)
    p = out["preset"]
    return p, out["drill"], out["spool"], out["drill"] / p, out["spool"] / p


#: the drills' rows: (label, index in :func:`drill_rows`' numbers)
DRILL_ROWS = (("rigid orbit CPU s, preset", 0), ("rigid orbit CPU s, ramped-valve drill", 1),
              ("rigid orbit CPU s, spool drill", 2), ("ramped-valve drill / preset (x)", 3),
              ("spool drill / preset rigid orbit (x)", 4))


def print_drill(reps=3, against=None, rounds=2):
    """The drills' rows: the orbits' CPU seconds, then each ratio against :data:`DRILL_GOAL`; with
    ``against`` (a git ref, or a package tree's ``src`` folder) the same rows of that tree beside
    this one's, each tree in fresh processes (``rounds`` each, alternately; the best of them, and the
    ratios of the best times)."""
    if against is None:
        columns = [drill_rows(reps)]
        print(f"{'case':38s} {'this tree':>10s}")
    else:
        from _timing import fresh_runs, ref_tree

        src = against if Path(against).is_dir() else ref_tree(against)
        runs = fresh_runs(__file__, src, rounds, ["--drill"])
        # each tree's best times, and the ratios of those bests (not the best of the processes' ratios,
        # which pairs one process's fast preset with another's fast drill)
        columns = []
        for name in ("baseline", "new"):
            p, drill, spool = (min(r[k] for r in runs[name]) for k in range(3))
            columns.append([p, drill, spool, drill / p, spool / p])
        name = "before" if Path(against).is_dir() else against[:10]
        print(f"{'case (best of ' + str(rounds) + ' processes)':38s} {name:>10s} {'this tree':>10s}")
    for label, k in DRILL_ROWS:
        print(f"{label:38s} " + " ".join(f"{c[k]:10.4f}" for c in columns))
        if k >= 3:
            r = columns[-1][k]
            print(f"   the goal, at most {DRILL_GOAL:g}x: {'met' if r <= DRILL_GOAL else 'missed'}")


def main(quick=False):
    d = circuit_preset("circuit-drifter")
    drive = d.drive()
    t_cv, t_py, s_cv, stats, t_ra, s_ra, c_ra, gap = integrators(d, drive)
    print(f"one stroke flight, rtol 1e-10: CVODE compiled {t_cv * 1e3:.2f} ms, through scikit-sundae "
          f"{t_py * 1e3:.2f} ms ({s_cv} points); scipy Radau {t_ra:.3f} s ({s_ra} steps, {c_ra} "
          f"evaluations); impact times {gap:.1e} apart")
    print("  CVODE's counters: " + ", ".join(f"{k} {v}" for k, v in stats.items()))
    print(f"{'modes':>5} {'task':<36} {'circuit s':>10} {'before s':>10} {'ideal s':>9}   (before: through "
          "scikit-sundae's Python interface)")
    for name, (now, before, ideal) in rigid_rows(d, drive).items():
        print(f"{0:>5} {name:<36} {now:>10.4f} {before:>10.4f} {ideal:>9.4f}")
    print_drill()
    if not quick:
        for n, what, now, before in flexible_rows(d, drive):
            print(f"{n:>5} {'find_orbit from the default guess':<36} {now:>10.3f} {before:>10.3f}   "
                  f"(before: {what})")


#: why a goal is missed where it is (measured; theory §11 and benchmarks/HISTORY.md have the traces)
WHY_CONTINUATION = (
    "each point takes the chord's plain periods at the variational flights' state tolerance (some "
    "50 ms each, one to three) and the orbit's variational period (some 165 ms: its state at rtol "
    "1e-13, 50 ms, and Magnus' 10,000 steps of 11 us); the steps are set by the balanced Jacobian's "
    "norm (9,068 with 8 modes: the oil's stiffness, in the rows that vary along the flight, so a "
    "propagator of the constant modal block would not lengthen them). Under 0.1 s a point needs a "
    "sensitivity method other than the variational equations' integration")
WHY_ROCK_COMPILE = (
    "some 170 kernels typed, lowered and compiled once each (numba's own passes, typing and "
    "lowering among them, about half, LLVM's the other half); the first exact blow's own compile is "
    "most of 15 s, and the "
    "orbit's kernels (flights, admissibility search, tangents) add the rest. What is left is compiling "
    "each kernel once: smaller kernels cost more compiles, inlining more typing (HISTORY.md)")

WHY_LATTICE = (
    "   exact blows are not the circuit on rock's default: its orbit with them takes 6 to 6.6 s "
    "of CPU against the lattice's 0.16 s (the goal 0.3 s), 16 exact blows of some 0.35 s, 11 of "
    "them the multipliers' central differences; the lattice's blow's work dissipated in the rock "
    "is 1.6e-6 off the exact blow's (theory §11). A tangent of the coupled exact blow through its "
    "force's iteration would replace those differences")

WHY_EXACT_COST = (
    "the exact orbit is found on the lattice (8 then 64 cells, its blows ended where the exact ones "
    "end: some 0.55 s of lattice blows, 10 of them at 64 cells) and polished on 4 exact blows (some "
    "0.37 s of CPU each, 7 rounds of the drive's force: 2 the chord's, 1 the closing step's, 1 the "
    "orbit's own) and the last one's tangent (0.31 s, on the last round's switch log: its blow not "
    "solved again); a blow's record is no longer sampled in the orbit (0.06 s a blow). Each blow's "
    "solver runs 28 windows for its own 13 (0.27 s against 0.17 s solved once): each round solves "
    "the travel time past where its force is right again in the next, which only the driven end's "
    "wave re-sent in the solver's pool would spare (HISTORY.md)")
WHY_DEFAULT_DISTANCE = (
    "the default's blows are the example's slot lattice at 8 cells a piston (contact_events='slots': "
    "every event at its own instant inside its step, the rod's segments exact, the drive meeting the "
    "arriving wave's slots), ended at the exact blows' instant: 2.0e-6 from the exact orbit, 3.1e-7 on "
    "16 cells; on the plain lattice (contact_events='step') 1.4e-3 on 8 cells, 2.0e-5 on 64 "
    "(benchmarks/HISTORY.md)")

WHY_SLOTS_COST = (
    "the example names the slot lattice (contact_events='slots', within 2.0e-6 of the exact orbit "
    "where the plain lattice is 1.4e-3 off): its blows' merges and cuts some 8 times a plain blow's "
    "cost, and the circuit's flights take the arriving wave's slots as breaks; the plain lattice's "
    "orbit (contact_events='step') meets the goal, 0.26 s (benchmarks/HISTORY.md)")

WHY_DRILL = (
    "(the same drill on the preset's ramped valve, beside the goal's spool drill) the drill's circuit "
    "has two more nodes with a pressure state (the cushion's, the return line's), "
    "five more flows and six more events (the cushion's three kinks, the check valve's two, the return "
    "line's gas) than the preset's; each event crossed ends a flight and starts another")

WHY_SPOOL = (
    "the spool drill's orbit takes 415 flights against the preset's 59 (27 to 29 a period against 4: "
    "the spool's stops, its main ports' two kinks and its pilot ports' four, the cushion's and the "
    "check valve's each end one), each with some 0.3 ms of Python around CVODE's call, and 41,600 of "
    "CVODE's steps against 18,000, each dearer (10 states against 6). Taking the spool's six kinks "
    "inside the flights (the openings clipped in the laws, no events) was measured and not kept: 237 "
    "flights, but 48,700 steps, twice the error-test failures and four times the Newton failures "
    "where CVODE steps across a kink, the same CPU time; and a light fast spool's flights failed at "
    "its pilot kinks. Left: restarting CVODE at a kink inside the compiled flight loop, without "
    "Python (benchmarks/HISTORY.md)")

#: (goal, script, its arguments (``{ref}`` the git ref, ``{src}`` its exported package tree),
#: the rows that hold the goal's numbers: ``(label, bound, why)``, this tree's number on the row
#: that starts with ``label`` at most ``bound``, and why it is missed where it is; or a line to print)
GOALS = (
    ("the circuit's orbit: rigid <= 0.5 s, 4 modes <= 0.2 s, 8 modes <= 0.5 s, 16 modes <= 2 s; a "
     "continuation point with 8 modes <= 0.1 s (CPU s)", "bench_circuit_modes.py",
     ("--against", "{ref}", "--rounds", "2"),
     (("rigid orbit", 0.5, ""), ("4 modes orbit", 0.2, ""), ("8 modes orbit", 0.5, ""),
      ("16 modes orbit", 2.0, ""), ("8 modes continuation point", 0.1, WHY_CONTINUATION),
      ("8 modes continuation, 8 points", 0.1, WHY_CONTINUATION))),
    ("an orbit of the example drill with all the parts (examples/circuit_drill_spool.toml, rigid "
     "piston) within 3x the preset's rigid circuit orbit, same run (beside it the same drill on the "
     "preset's ramped valve, examples/circuit_drill_parts.toml)", "bench_circuit.py",
     ("--drill", "--against", "{ref}"),
     (("spool drill / preset rigid orbit (x)", DRILL_GOAL, WHY_SPOOL),
      ("ramped-valve drill / preset (x)", DRILL_GOAL, WHY_DRILL))),
    ("the circuit on rock (examples/circuit_drifter_rock.toml) <= 0.3 s an orbit (CPU s)",
     "bench_circuit_laws.py", ("--against", "{ref}", "--rounds", "2"),
     (("find_orbit circuit", 0.3, WHY_SLOTS_COST),)),
    ("the exact blow under the circuit (method='exact'; the lattice's orbit some 65 times cheaper a blow)",
     "bench_coupled_exact.py", ("--against", "{src}"), (WHY_LATTICE,)),
    ("the circuit on rock: the exact orbit at most 10x the default's cost, the default within 1e-5 of "
     "the exact orbit (frequency, impact velocity, work on rock, penetration, mean supply pressure)",
     "bench_exact_orbit.py", ("--against", "{src}", "--reps", "1"),
     (("exact / default cost (x)", 10.0, WHY_EXACT_COST),
      ("default's distance from the exact orbit", 1e-5, WHY_DEFAULT_DISTANCE))),
    ("the wave law's blow under the circuit >= 5x faster (met at an earlier stop, against d617828: a "
     "blow and 300 states through it 13x, a run of 4 blows and the circuit's histories 6.8x; "
     "HISTORY.md)", "bench_wave_states.py", ("--against", "{src}"), ()),
    ("the first exact blow with an empty numba cache <= 15 s of CPU", "bench_first_call.py",
     ("--against", "{src}", "--rounds", "2"),
     (("CPU time (s)", 15.0, "its compile is typing and lowering each of its kernels once (HISTORY.md); "
       "the spread of the machine is some 10 %"),)),
    ("the first rock orbit with an empty numba cache <= 15 s of CPU", "bench_first_call.py",
     ("--rock-orbit", "--against", "{src}", "--rounds", "1"),
     (("CPU time (s)", 15.0, WHY_ROCK_COMPILE),)),
    ("the rigid bar's short run <= 2x a compiled minimal loop", "bench_fast_paths.py",
     ("--quick", "--against", "{src}"),
     (("simulate / peer, rigid, one load period by t_end (x)", 2.0, ""),)),
)


def verdicts(table: str, rows) -> list[str]:
    """For each ``(label, bound, why)`` of ``rows``: the row of ``table`` that starts with ``label``,
    this tree's number on it against ``bound``: met, or missed and why (a string in ``rows``:
    printed as it is)."""
    import re

    out = []
    for row in rows:
        if isinstance(row, str):  # (a goal without a number to check: why it stands as it does)
            out.append(row)
            continue
        label, bound, why = row
        line = next((ln.strip() for ln in table.splitlines() if ln.strip().startswith(label)), "")
        # (the row's numbers: the baseline's, this tree's, then any goal; a ratio "1.2x" is not one)
        values = [float(x) for x in re.findall(r"(?<![\w.])-?\d+\.?\d*(?:e-?\d+)?(?![\w.])",
                                               line[len(label):])]
        if not values:
            out.append(f"   {label}: no number found")
            continue
        new = values[1] if len(values) > 1 else values[0]
        if new <= bound:
            out.append(f"   {label}: {new:g} <= {bound:g}, met")
        else:
            out.append(f"   {label}: {new:g} > {bound:g}, missed: {why}")
    return out


def goals(ref: str, only: str | None = None) -> None:
    """Each goal (those whose text holds ``only``, where given), then its script's table against the
    git ref ``ref`` (module docstring), then each of its numbers against the goal: met, or missed and
    why."""
    import subprocess
    import sys
    from pathlib import Path

    from _timing import ref_tree

    here = Path(__file__).resolve().parent
    src = ref_tree(ref)
    for goal, script, args, rows in GOALS:
        if only is not None and only not in goal:
            continue
        shown = " ".join(args).format(ref=ref, src=f"<{ref}>/src")
        print(f"\n## {goal}\n   python benchmarks/{script} {shown}", flush=True)
        argv = [a.format(ref=ref, src=src) for a in args]
        run = subprocess.run([sys.executable, str(here / script), *argv], capture_output=True, text=True)
        table = run.stdout.rstrip()
        print(table or run.stderr.rstrip()[-2000:], flush=True)
        for line in verdicts(table, rows):
            print(line, flush=True)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--goals", metavar="REF", help="every goal's benchmark against the git ref REF")
    parser.add_argument("--only", metavar="TEXT", help="with --goals: the goals whose text holds TEXT")
    parser.add_argument("--drill", action="store_true",
                        help="only the example drills' rigid orbits against the preset's")
    parser.add_argument("--against", metavar="REF_OR_SRC",
                        help="with --drill: the same rows on a git ref or a package tree's src folder")
    parser.add_argument("--rounds", type=int, default=2, help="processes each tree with --against")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # (--against's child)
    a = parser.parse_args()
    if a.json and a.drill:
        import json

        print(json.dumps(list(drill_rows())))
    elif a.drill:
        print_drill(against=a.against, rounds=a.rounds)
    elif a.goals:
        goals(a.goals, a.only)
    else:
        main(a.quick)
