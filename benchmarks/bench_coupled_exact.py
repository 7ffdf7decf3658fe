"""One exact blow under the oil circuit (the rod-rock law with ``method="exact"``, its drive's force
iterated: :func:`impactbar.laws.rodrock.coupled_exact.driven_exact_contact`), in CPU seconds.

On ``examples/circuit_drifter_rock.toml`` (its rod as given, not whole cells) at the second arrival
of a run on the lattice (16 cells per piston) from rest 0.05 behind the shank: one untimed blow
(compilation, caches), then the best of ``--reps`` timed ones (the machine's other load only adds).

Run: ``python benchmarks/bench_coupled_exact.py``. ``--against SRC`` times it in fresh processes on
the package tree ``SRC`` (e.g. ``git worktree add /tmp/old <commit>`` then ``--against /tmp/old/src``)
and on this one, alternately, and prints both side by side with the largest relative difference of
the blow's numbers (impact velocity after, work on the rock, the drive's state after, the piston's
modal state after) between the trees.
"""

from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path

import numpy as np
from _timing import against_parser, fresh_runs  # this folder's shared runner of two trees

import impactbar as ib
from impactbar.physical import build, read_config, with_values

EXAMPLE = Path(__file__).parents[1] / "examples" / "circuit_drifter_rock.toml"


def arrival(values=None):
    """The exact model, the drive and the second arrival's ``(state, t0, q, v)`` (the config's dotted
    keys ``values`` changed first, e.g. the rod's lengths; the first blow on the lattice ended at the
    law's window on every tree, where the law has ``driven_end``)."""
    cfg, _ = read_config(str(EXAMPLE))
    del cfg["rock"]["cells_per_piston"]
    cfg["rock"].pop("contact_events", None)  # (the lattice's plain events: the arrival as measured)
    if values:
        cfg = with_values(cfg, values)
    drifter = build(cfg)
    model, drive = drifter.model(), drifter.drive()
    exact = model.with_(impact=dataclasses.replace(model.law, method="exact"))
    named = {f.name for f in dataclasses.fields(model.law)}
    window = {"driven_end": "window"} if "driven_end" in named else {}
    lattice = model.with_(impact=dataclasses.replace(model.law, method="lattice", cells_per_piston=16,
                                                     **window))
    start = ib.InitialState.rigid(-0.05, 0.0, n_modes=model.n_modes)
    blow = ib.simulate(lattice, drive, start, 7.0).impacts[1]
    state = ib.simulate(lattice, drive, start, blow.t0 - 1e-12)._final_drive
    return exact, drive, state, blow.t0, blow.q_before, blow.v_before


def numbers(c):
    """The blow's numbers compared between trees, one flat list."""
    return [float(c.v_after[0]), float(c.record.work_on_rock), *map(float, c.drive_state.z),
            *map(float, c.q_after), *map(float, c.v_after)]


def measure(reps=2):
    """``{"cpu": best CPU seconds of one blow, "numbers": numbers(blow)}``."""
    args = arrival()
    law = args[0].law
    c = law.driven_contact(*args)  # untimed: compilation, caches
    best = float("inf")
    for _ in range(reps):
        t = time.process_time()
        c = law.driven_contact(*args)
        best = min(best, time.process_time() - t)
    return {"cpu": best, "numbers": numbers(c)}


def against(src, rounds=2, reps=2):
    """The blow on another package tree and on this one, in fresh processes, alternately."""
    runs = fresh_runs(__file__, src, rounds, args=("--reps", str(reps)))
    b = min(r["cpu"] for r in runs["baseline"])
    n = min(r["cpu"] for r in runs["new"])
    x, y = np.array(runs["baseline"][0]["numbers"]), np.array(runs["new"][0]["numbers"])
    diff = float(np.max(np.abs(x - y) / np.maximum(np.abs(x), 1e-300)))
    print(f"{'one exact blow under the circuit':34s} {'baseline CPU s':>14s} {'new CPU s':>10s} "
          f"{'ratio':>6s} "
          f"{'max rel. diff':>13s}")
    print(f"{'(best of ' + str(rounds) + ' processes)':34s} {b:14.3f} {n:10.3f} {b / n:6.2f} {diff:13.2e}")


def main(argv=None):
    args = against_parser(__doc__, "blows", rounds=2).parse_args(argv)
    if args.json:
        print(json.dumps(measure(args.reps)))
    elif args.against:
        against(args.against, args.rounds, args.reps)
    else:
        out = measure(args.reps)
        print(f"one exact blow under the circuit: {out['cpu']:.3f} CPU s (best of {args.reps})")


if __name__ == "__main__":
    main()
