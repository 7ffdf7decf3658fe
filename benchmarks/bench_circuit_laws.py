"""The oil circuit's coupled blows (theory §11, "The coupled blow") against the blows with the force
held (the ideal valve's under the same law, theory §10), in the same run.

Run: ``python benchmarks/bench_circuit_laws.py`` (``--quick``: the blows only). On
``examples/circuit_drifter_rock.toml`` (the preset ``circuit-drifter`` on a drill string and rock, 8
cells per piston) at its operating point's arrival: one blow solved with the circuit's state
(``RodRock.driven_contact``: the lattice chunk by chunk, the circuit by CVODE step by step of the
lattice) against the same blow with the force held at the arrival's (``RodRock.contact``), and the
same under the wave law (the window with one integration of the circuit against the held window);
then ``find_orbit`` of the circuit on the rock against the ideal valve's at the circuit's mean supply
pressure on the same rock (``PositionSwitchedDrive``), and ``simulate`` over 20 blows of each. CPU
seconds, the best of a few repetitions (the machine's other load only adds); compilation is done
before the clock starts. The circuit's ``find_orbit`` on the rock has the goal <= 0.3 s.

``--against REF`` runs the same cases on the git ref ``REF`` too (its ``src`` exported by ``git
archive`` to a temporary folder; or ``REF`` a tree's ``src`` folder, e.g. of a worktree of ``main``,
whose compiled kernels are kept between runs), in fresh processes, alternately, and prints both side
by side (the best of ``--rounds`` processes each). ``find_orbit`` of the circuit: the least and the
median CPU time of 5 calls.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from _timing import example_drifter, fresh_runs, ref_tree  # this folder's shared runner

from impactbar import InitialState, PositionSwitchedDrive, find_orbit, simulate
from impactbar.loads import FourierLoad

EXAMPLE = Path(__file__).parents[1] / "examples" / "circuit_drifter_rock.toml"


def best(fn, reps):
    """The least CPU seconds of ``reps`` calls of ``fn()``."""
    out = float("inf")
    for _ in range(reps):
        t = time.process_time()
        fn()
        out = min(out, time.process_time() - t)
    return out


def blows(model, drive, state, q, v, reps=3):
    """Seconds of one coupled blow and of the same blow with the force held."""
    law = model.law
    p0 = drive.force(state.mode, state.z, q, v)
    held = FourierLoad(p0, [])
    law.driven_contact(model, drive, state, 0.0, q, v)  # warm-up (compiling)
    law.contact(model, held, 0.0, q, v)
    return (best(lambda: law.driven_contact(model, drive, state, 0.0, q, v), reps),
            best(lambda: law.contact(model, held, 0.0, q, v), reps))


def cases(quick=False) -> dict:
    """``{case: CPU seconds}`` (module docstring)."""
    d = example_drifter(EXAMPLE)
    model, drive = d.model(), d.drive()
    point = d.orbit()
    o = point.orbit
    problem = o.problem
    tau, mode = problem.blocks[0]
    _, _, _, (_, q, v, state), _, _ = problem._flight(tau, mode, np.asarray(o._unknowns, dtype=float))
    rock = blows(model, drive, state, q, v)
    wave = model.with_(impact="wave", R=0.215)
    window = blows(wave, drive, state, q, v)
    out = {"blow rod-rock coupled": rock[0], "blow rod-rock held": rock[1],
           "blow wave window coupled": window[0], "blow wave window held": window[1]}
    if quick:
        return out
    ps = o.drive_states[0][2]
    a = drive.chambers.area_ratio
    ideal = PositionSwitchedDrive(stroke=ps * (1 - a), ret=a * ps - drive.supply.tank_pressure,
                                  switch_out=drive.valve.switch_out)
    oi = find_orbit(model, ideal)
    start = InitialState.rigid(-drive.valve.switch_out, 0.0)
    runs = []
    for _ in range(5):
        t = time.process_time()
        find_orbit(model, drive)
        runs.append(time.process_time() - t)
    out["find_orbit circuit"] = min(runs)
    out["find_orbit circuit (median)"] = float(np.median(runs))
    out["find_orbit ideal"] = best(lambda: find_orbit(model, ideal), 3)
    out["simulate 20 blows circuit"] = best(lambda: simulate(model, drive, start, 20.5 * o.period), 1)
    out["simulate 20 blows ideal"] = best(lambda: simulate(model, ideal, start, 20.5 * oi.period), 3)
    return out


def against(ref: str, rounds: int, quick: bool) -> None:
    src = ref if Path(ref).is_dir() else ref_tree(ref)  # (a tree's src folder, its kernels compiled)
    runs = fresh_runs(__file__, src, rounds, ["--quick"] if quick else [])
    print(f"{'case (CPU s, best of ' + str(rounds) + ')':30s} {ref[:10]:>10s} {'this tree':>10s}")
    for case in runs["new"][0]:
        b = min(r[case] for r in runs["baseline"])
        n = min(r[case] for r in runs["new"])
        print(f"{case:30s} {b:10.4f} {n:10.4f}   ({b / n:.2f}x)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="the blows only")
    parser.add_argument("--against", metavar="REF",
                        help="compare with the git ref REF (e.g. main) or a tree's src folder (its numba "
                        "caches kept between runs)")
    parser.add_argument("--rounds", type=int, default=1, help="processes each with --against")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # (--against's child)
    args = parser.parse_args(argv)
    if args.json:
        print(json.dumps(cases(args.quick)))
        return
    if args.against:
        against(args.against, args.rounds, args.quick)
        return
    for case, sec in cases(args.quick).items():
        print(f"{case:30s} {sec:10.4f}")


if __name__ == "__main__":
    sys.exit(main())
