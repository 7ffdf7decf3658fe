"""Benchmark: what a design without an operating point costs the whole-drifter optimiser against a
design with one, on this tree and on another, in the same session.

The designs are the documented optimum of examples/circuit_drifter_rock_piston.toml on the lattice's
contact events at its step ends (``rock.contact_events`` left at the lattice's ``"step"``, where they
were met; the example now takes ``"inside"``) with its collar's diameter times each of
``--factors``: from about 1.0095 to 1.0125 lies a band without a one-impact orbit; and a design the
optimiser's search met without one (``searched``: its motion followed from rest to Newton's start
alternates, two impacts a period; ``--no-searched`` leaves it out). Each is evaluated as the
optimiser's workers evaluate a design (``_design_record``: the build, the operating point, and for a
design without one its record; on a tree where the search leaves its motion unclassified, that
classification timed apart, as the result classifies the designs it lists,
``optimize_failures.classify_failed`` on the design built again), one process, after one untimed
design (numba's caches). Prints per tree the median and the largest CPU seconds of the designs with
and without an operating point (the latter as the search pays them, and with the motion classified
as for a reported design), the failed ones' split (the orbit's attempt, the motion's classification)
and whether the two trees' records (every figure but the seconds, the motion classified) agree to
the bit. Nothing is asserted.

Run: ``python benchmarks/bench_failed_evaluation.py [--against REF] [--rounds N] [--factors F1,F2,...]
[--no-searched]`` (``REF`` a git ref or a tree's ``src`` folder; the least of ``--rounds`` fresh
processes per design).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from _timing import fresh_runs, ref_tree  # this folder's shared timer

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "physical"))
from drifter_optimum import EXAMPLE, SEARCHED, collar  # noqa: E402  (the tests': the documented optimum, its collar varied)

FACTORS = "1.0,1.003,1.009,1.01,1.0105,1.011,1.0115,1.012,1.013,1.03"


def _figures(rec: dict) -> str:
    """A record without its timings, as text (to compare two trees' to the bit)."""
    kept = {k: v for k, v in rec.items() if k not in ("seconds", "motion_seconds", "switch_seconds")}
    return json.dumps(kept, sort_keys=True, default=repr)


def _designs(factors: list, searched: bool) -> list:
    """``(label, changes)`` of each design: the collars' factors, then the searched design."""
    return [(f"collar x {f:g}", collar(f)) for f in factors] + ([("searched", SEARCHED)] if searched else [])


def _run(factors: list, searched: bool = True) -> dict:
    """Each design's CPU seconds (its evaluation, and its motion's classification where the
    evaluation leaves it), whether it has an operating point, its motion's seconds, its record."""
    from impactbar.physical import build, read_config, with_values
    from impactbar.physical import optimize_failures as failures
    from impactbar.physical.optimize_drifter import DEFAULT_CONSTRAINTS, _design_record

    cfg, folder = read_config(EXAMPLE)
    cfg["rock"].pop("contact_events", None)  # (step ends, where the designs were met: on any tree)
    limits = dict(DEFAULT_CONSTRAINTS, mean_supply_pressure=None)

    _design_record(collar(factors[0]), cfg, folder, limits)  # (numba's caches)
    out = []
    for label, changes in _designs(factors, searched):
        t = time.process_time()
        rec = _design_record(changes, cfg, folder, limits)
        cpu = time.process_time() - t
        t = time.process_time()
        if hasattr(failures, "classify_failed") and rec.get("motion_summary") == failures.NOT_CLASSIFIED:
            failures.classify_failed(rec, build(with_values(cfg, changes), folder))  # (as when reported)
        out.append({"design": label, "cpu_s": cpu, "classify_cpu_s": time.process_time() - t, "ok": rec["ok"],
                    "motion_s": rec.get("motion_seconds", 0.0), "record": _figures(rec)})
    return {"designs": out}


def _summary(designs: list) -> dict:
    """The medians and the largest CPU seconds of the designs with and without an operating point."""
    ok = [d["cpu_s"] for d in designs if d["ok"]]
    failed = [d for d in designs if not d["ok"]]
    cpu = [d["cpu_s"] for d in failed]
    listed = [d["cpu_s"] + d.get("classify_cpu_s", 0.0) for d in failed]
    motion = [d["motion_s"] for d in failed]
    return {"with one: median CPU s": float(np.median(ok)) if ok else None,
            "without: median CPU s": float(np.median(cpu)) if cpu else None,
            "without: largest CPU s": max(cpu, default=None),
            "without, classified: median CPU s": float(np.median(listed)) if listed else None,
            "without: median motion s (wall)": float(np.median(motion)) if motion else None,
            "ratio of the medians": (float(np.median(cpu)) / float(np.median(ok))) if ok and cpu else None,
            "designs with / without": f"{len(ok)} / {len(failed)}"}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", metavar="REF", help="the baseline's git ref or src folder")
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--factors", default=FACTORS)
    parser.add_argument("--no-searched", action="store_true", help="without the searched design")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # (--against's child)
    args = parser.parse_args(argv)
    factors = [float(f) for f in args.factors.split(",")]
    searched = not args.no_searched
    if args.json:
        print(json.dumps(_run(factors, searched)))
        return 0
    if args.against is None:
        designs = _run(factors, searched)["designs"]
        for d in designs:
            print(f"{d['design']:16s} {'ok' if d['ok'] else 'no orbit':9s} {d['cpu_s']:7.2f} s CPU")
        print(json.dumps(_summary(designs), indent=1))
        return 0
    src = args.against if Path(args.against).is_dir() else ref_tree(args.against)
    labels = [label for label, _ in _designs(factors, searched)]
    more = ("--factors", args.factors) + (() if searched else ("--no-searched",))
    runs = fresh_runs(__file__, src, args.rounds, more)
    # per design the least CPU of the rounds
    best = {k: [min((r["designs"][i] for r in runs[k]), key=lambda d: d["cpu_s"])
                for i in range(len(labels))] for k in runs}
    print(f"{'design':16s} {'baseline':>18s} {'new':>18s}")
    for i, label in enumerate(labels):
        cells = [f"{'ok' if d['ok'] else 'none'} {d['cpu_s']:7.2f} s"
                 for d in (best["baseline"][i], best["new"][i])]
        print(f"{label:16s} {cells[0]:>18s} {cells[1]:>18s}")
    a, b = _summary(best["baseline"]), _summary(best["new"])
    for key in a:
        cells = [f"{v:18.3g}" if isinstance(v, float) else f"{'-' if v is None else v!s:>18s}"
                 for v in (a[key], b[key])]
        print(f"{key:34s} {cells[0]} {cells[1]}")
    same, only = [], set()
    for x, y in zip(best["baseline"], best["new"], strict=True):
        old, new = json.loads(x["record"]), json.loads(y["record"])
        only |= {f"{k} (baseline)" for k in old.keys() - new.keys()}
        only |= {f"{k} (new)" for k in new.keys() - old.keys()}
        same.append(all(old[k] == new[k] for k in old.keys() & new.keys()))
    one = f"; written by one tree only: {', '.join(sorted(only))}" if only else ""
    print(f"the same records (every figure but the seconds, of the keys both trees write), to the bit: "
          f"{sum(same)} of {len(same)}{one}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
