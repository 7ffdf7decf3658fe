"""Benchmark: the optimiser's cache file written as a search writes it, by this tree's writer (a log,
one line a design or gradient: :class:`~impactbar.physical.optimize_cache.DesignCache`) and by
another tree's ``optimize_cache.write_cache`` (loaded from ``--against REF``: before the log, the
whole file rewritten after every design and every gradient), side by side in the same process.

A synthetic store of ``--designs`` designs (records of the size and shape of the documented search's,
six variables and its constraints), each written as the search writes it: after each design, and a
gradient's after every ``--gradient-every`` designs. Prints for each writer and size the seconds and
CPU seconds of all the writes, the bytes written (a counter: the old writer's grow with the square
of the designs), the final file's size and the seconds to read it back; and whether both files read
back the same designs and gradients, to the bit (the old file by this tree's reader too: the format
before the log is read). Nothing is asserted.

Run: ``python benchmarks/bench_optimize_cache_writes.py --against REF [--designs 400 1600]
[--gradient-every 10]`` (``PYTHONPATH`` this tree's ``src``).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from impactbar.physical.optimize_cache import DesignCache

KEYS = ["piston.collar_diameter", "piston.front_rod_diameter", "piston.rear_rod_diameter",
        "chambers.rear_volume", "valve.switch_out", "accumulator.precharge"]
CONSTRAINTS = ["max_multiplier", "min_pressure", "mean_supply_pressure", "peak_rod_stress",
               "min_drilling_rate"]
FIGURES = ["drilling_rate_per_kW", "drilling_rate", "work_on_rock_per_blow", "impact_power", "efficiency",
           "blow_frequency", "impact_velocity", "flow", "hydraulic_power", "max_multiplier"]


def _old_module(ref: str):
    """``optimize_cache`` of the git ref ``ref`` (its writer needs nothing else of the package)."""
    root = Path(__file__).resolve().parents[1]
    text = subprocess.run(["git", "-C", str(root), "show", f"{ref}:src/impactbar/physical/optimize_cache.py"],
                          capture_output=True, text=True, check=True).stdout
    path = Path(tempfile.mkdtemp(prefix="impactbar-old-cache-")) / "old_optimize_cache.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("impactbar.physical.old_optimize_cache", path)
    module = importlib.util.module_from_spec(spec)
    module.__package__ = "impactbar.physical"  # (its reader's names now: this tree's outputs)
    spec.loader.exec_module(module)
    return module


def _record(i: int, rng) -> dict:
    """A design's record of the documented search's shape: its values and changes, guess, figures,
    constraints, piston and multipliers (every third one failed, with an error and border scores)."""
    values = {k: float(v) for k, v in zip(KEYS, rng.random(len(KEYS)), strict=True)}
    ok = i % 3 != 0
    rec = {"id": json.dumps([repr(v) for v in values.values()]), "ok": ok, "seconds": float(rng.random()),
           "continued": bool(i), "objectives": {f"{k}_x": float(rng.random()) for k in FIGURES},
           "constraints": {c: {"value": float(rng.random()), "limit": 0.95, "scaled": float(rng.random()),
                               "met": True} for c in CONSTRAINTS},
           "feasible": ok, "piston": {"mass_kg": float(rng.random()), "areas_m2": rng.random(3).tolist()},
           "multipliers": rng.random(8).tolist(), "shank_stress": {"peak_Pa": float(rng.random())},
           "guess": None if i == 0 else f"design {i - 1}", "u": rng.random(len(KEYS)).tolist(),
           "values": values, "changes": {k: f"{v:.17g} mm" for k, v in values.items()}}
    if not ok:
        rec.update(error="no one-impact orbit: " + "Newton did not converge; " * 6,
                   border={"nearest": f"design {i - 1}", "objective": float(rng.random()),
                           "margins": rng.random(len(CONSTRAINTS)).tolist(), "radius": float(rng.random())})
    return rec


def _gradient(rng) -> dict:
    return {"objective": rng.random(len(KEYS)), "constraints": rng.random((len(CONSTRAINTS), len(KEYS)))}


def _search(n: int, every: int, write, seed: int = 1) -> None:
    """The writes of a search of ``n`` designs: ``write(store, gradients)`` after each design and
    each gradient (a gradient after every ``every`` designs)."""
    rng = np.random.default_rng(seed)
    store, gradients = {}, {}
    for i in range(n):
        rec = _record(i, rng)
        store[rec["id"]] = rec
        write(store, gradients, rec=rec)
        if i % every == every - 1:
            gradients[(rec["id"], "default")] = g = _gradient(rng)
            write(store, gradients, gradient=(rec["id"], "default", g))


def _measure(n: int, every: int, old, folder: Path) -> dict:
    rows = {}
    written = {"old": 0}
    old_path, new_path = folder / f"old{n}.json", folder / f"new{n}.json"

    def old_write(store, gradients, **_):
        old.write_cache(old_path, "problem", store, gradients)
        written["old"] += old_path.stat().st_size

    cache = DesignCache(new_path, "problem")

    def new_write(store, gradients, rec=None, gradient=None):
        cache.add(rec) if gradient is None else cache.add_gradient(*gradient)

    for name, write in (("baseline", old_write), ("new", new_write)):
        t, c = time.perf_counter(), time.process_time()
        _search(n, every, write)
        cache.close()
        wall, cpu = time.perf_counter() - t, time.process_time() - c
        path = old_path if name == "baseline" else new_path
        t = time.perf_counter()
        read = DesignCache(path, "problem")
        rows[name] = {"writes_s": wall, "writes_cpu_s": cpu, "bytes_written": written.get("old", 0)
                      if name == "baseline" else path.stat().st_size, "file_bytes": path.stat().st_size,
                      "read_s": time.perf_counter() - t, "designs": len(read.designs),
                      "gradients": len(read.gradients)}
        rows[name]["digest"] = json.dumps(old._plain([list(read.designs.values()),
                                                      [[*k, g] for k, g in sorted(read.gradients.items())]]))
    same = rows["baseline"].pop("digest") == rows["new"].pop("digest")
    old_read = old.read_cache(old_path, "problem")
    return {"rows": rows, "same_designs_and_gradients": same,
            "old_reader_on_old_file_same_as_new_reader": old_read == DesignCache(old_path, "problem").designs}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", metavar="REF", required=True, help="the baseline's git ref")
    parser.add_argument("--designs", type=int, nargs="+", default=[400, 1600])
    parser.add_argument("--gradient-every", type=int, default=10)
    args = parser.parse_args(argv)
    old = _old_module(args.against)
    with tempfile.TemporaryDirectory() as folder:
        for n in args.designs:
            out = _measure(n, args.gradient_every, old, Path(folder))
            print(f"\n{n} designs, {n // args.gradient_every} gradients "
                  f"(read back the same to the bit: {out['same_designs_and_gradients']}; "
                  f"the old file read by the old reader and this one alike: "
                  f"{out['old_reader_on_old_file_same_as_new_reader']})")
            print(f"{'':24}{'baseline (' + args.against + ')':>24}{'new':>14}{'ratio':>10}")
            for key in ("writes_s", "writes_cpu_s", "bytes_written", "file_bytes", "read_s"):
                a, b = out["rows"]["baseline"][key], out["rows"]["new"][key]
                print(f"{key:24}{a:24.4g}{b:14.4g}{a / b if b else float('nan'):10.1f}")
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
