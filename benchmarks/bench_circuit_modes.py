"""The oil circuit's orbit with a flexible piston: ``find_orbit`` on the preset ``circuit-drifter``
(``impactbar.physical.circuit_preset``) rigid and with 4, 8 and 16 modes, and one point of a
continuation in the accumulator's pre-charge with 8 modes (the mean of the two points after the
start of a short branch, and of the seven of a branch of eight, the pre-charge 20 % up), each beside
its goal on this 2-core machine (8 modes <= 0.5 s, 4 modes <= 0.2 s, 16 modes <= 2 s, a
continuation point with 8 modes <= 0.1 s; the rigid orbit <= 0.5 s).

CPU seconds of one call each (the variational flights take seconds; the machine's other sessions
move wall time more than CPU time), after an untimed rigid and 1-mode orbit (numba's compilation,
the caches). Run: ``python benchmarks/bench_circuit_modes.py`` (``--modes 4 8`` for fewer).
``--against REF`` runs the same script's cases on the git ref ``REF`` too (its ``src`` exported by
``git archive`` to a temporary folder), in fresh processes, alternately, and prints both side by side
(the best of ``--rounds`` processes each).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from _timing import fresh_runs, ref_tree  # this folder's shared runner

GOALS = {"rigid orbit": 0.5, "4 modes orbit": 0.2, "8 modes orbit": 0.5, "16 modes orbit": 2.0,
         "8 modes continuation point": 0.1, "8 modes continuation, 8 points": 0.1}


def cpu(fn) -> float:
    t = time.process_time()
    fn()
    return time.process_time() - t


def cases(modes=(4, 8, 16)) -> dict:
    """``{case: CPU seconds}``."""
    from impactbar import continue_orbit, find_orbit
    from impactbar.physical import circuit_preset

    d = circuit_preset("circuit-drifter")
    drive = d.drive()
    model = d.model()
    find_orbit(model, drive)
    find_orbit(model.with_(n_modes=1), drive)  # (compiled, warm)
    out = {"rigid orbit": min(cpu(lambda: find_orbit(model, drive)) for _ in range(3))}
    orbits = {}
    for n in modes:
        m = model.with_(n_modes=n)
        t = time.process_time()
        try:
            orbits[n] = find_orbit(m, drive)
        except ValueError as err:  # (a failure is a row, not the end of the run)
            print(f"{n} modes: {err}", file=sys.stderr)
            out[f"{n} modes orbit"] = float("nan")
            continue
        out[f"{n} modes orbit"] = time.process_time() - t
    if 8 in orbits:
        o = orbits[8]
        t = time.process_time()
        b = continue_orbit(o, "precharge", to=drive.accumulator.precharge * 1.05, max_points=3, events=False)
        out["8 modes continuation point"] = (time.process_time() - t) / max(1, len(b.orbits) - 1)
        # (a longer branch, the pre-charge 20 % up: the points as a design map's row meets them)
        t = time.process_time()
        b = continue_orbit(o, "precharge", to=drive.accumulator.precharge * 1.2, max_points=8, events=False)
        out["8 modes continuation, 8 points"] = (time.process_time() - t) / max(1, len(b.orbits) - 1)
    return out


def _row(case, secs) -> str:
    goal = GOALS.get(case)
    cells = " ".join(f"{s:10.3f}" for s in secs)
    verdict = "" if goal is None else f"<= {goal:g} s {'met' if secs[-1] <= goal else 'missed'}"
    return f"{case:28s} {cells}   {verdict}"


def against(ref: str, rounds: int, modes) -> None:
    runs = fresh_runs(__file__, ref_tree(ref), rounds, ["--modes", *(str(m) for m in modes)])
    print(f"{'case (CPU s, best of ' + str(rounds) + ')':28s} {ref[:10]:>10s} {'this tree':>10s}   goal")
    for case in runs["new"][0]:
        b = min(r[case] for r in runs["baseline"])
        n = min(r[case] for r in runs["new"])
        print(_row(case, (b, n)) + f"   ({b / n:.1f}x)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", metavar="REF", help="compare with the git ref REF (e.g. main)")
    parser.add_argument("--rounds", type=int, default=1, help="processes each with --against")
    parser.add_argument("--modes", type=int, nargs="+", default=[4, 8, 16])
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # (--against's child)
    args = parser.parse_args(argv)
    if args.json:
        print(json.dumps(cases(tuple(args.modes))))
        return
    if args.against:
        against(args.against, args.rounds, args.modes)
        return
    for case, sec in cases(tuple(args.modes)).items():
        print(_row(case, (sec,)))


if __name__ == "__main__":
    sys.exit(main())
