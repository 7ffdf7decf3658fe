"""What the rock's first calls compile, counted: the circuit on rock's ``orbit()``
(``examples/circuit_drifter_rock.toml``, the lattice's blows) and the README's first exact blow,
each in a fresh process with a new, empty numba cache, on this tree and optionally another.

Run: ``python benchmarks/probes/rock_first_compiles.py [--rows rock blow] [--against SRC] [--kernels]``.

Per row and tree: the call's CPU seconds; numba's compiles (``numba:compile`` events: one a kernel
and signature, numba's own overloads among them); those of the rod and rock's kernels
(``impactbar.laws.rodrock``), how many of them made machine code and wrappers of their own (the
others are link-only: their callers hold their machine code), and their own CPU seconds (each
kernel's compile less its callees'); impactbar's kernels compiled for more than one signature; and a digest
of the call's numbers (the same on both trees: the same bits). ``--kernels`` lists every kernel.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

_CHILD = r"""
import json, sys, time
from collections import defaultdict
from numba.core import event

row, root = sys.argv[1], sys.argv[2]
own, count, sigs, machine, stack = defaultdict(float), defaultdict(int), defaultdict(list), {}, []


class Listener(event.Listener):
    def on_start(self, ev):
        stack.append([time.process_time(), 0.0])  # (its start, its callees' compiles)

    def on_end(self, ev):
        disp = ev.data["dispatcher"]
        fn = disp.py_func
        name = fn.__module__ + "." + fn.__qualname__
        start, callees = stack.pop()
        dt = time.process_time() - start
        own[name] += dt - callees
        count[name] += 1
        sigs[name].append(str(ev.data["args"]))
        machine[name] = disp._compiler.pipeline_class.__name__ != "LinkOnlyCompiler"
        if stack:
            stack[-1][1] += dt


event.register("numba:compile", Listener())
if row == "rock":
    from impactbar import physical as ph
    cfg, _ = ph.read_config(root + "/examples/circuit_drifter_rock.toml")
    t = time.process_time()
    orbit = ph.build(cfg).orbit()
    digest = repr((orbit.blow_frequency_Hz, orbit.impact_velocity_m_s))
else:
    from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow
    law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
    t = time.process_time()
    blow = single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, t_max=39.0)
    digest = repr(blow.efficiency)
cpu = time.process_time() - t
print(json.dumps(dict(cpu=cpu, digest=digest, own=own, count=count, machine=machine,
                      sigs={k: v for k, v in sigs.items() if len(v) > 1 and not k.startswith("numba.")})))
"""


def run(src: str, row: str) -> dict:
    """The row's first call in a fresh process on the package tree ``src`` with an empty numba cache."""
    cache = tempfile.mkdtemp(prefix="impactbar-rockprobe-")
    try:
        env = dict(os.environ, PYTHONPATH=src, NUMBA_CACHE_DIR=cache, OMP_NUM_THREADS="1",
                   OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
        env.pop("NUMBA_OPT", None)
        env.pop("IMPACTBAR_TIERED", None)
        done = subprocess.run([sys.executable, "-c", _CHILD, row, str(ROOT)], env=env, capture_output=True,
                              text=True)
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    if done.returncode:
        raise RuntimeError(f"{row} on {src} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def summary(r: dict) -> dict:
    """The counts of one run."""
    rock = [k for k in r["count"] if k.startswith("impactbar.laws.rodrock.")]
    return {"CPU s": r["cpu"], "compiles": sum(r["count"].values()),
            "numba overloads": sum(v for k, v in r["count"].items() if k.startswith("numba.")),
            "rodrock compiles": sum(r["count"][k] for k in rock),
            "with machine code": sum(r["count"][k] for k in rock if r["machine"][k]),
            "rodrock own CPU s": sum(r["own"][k] for k in rock)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", nargs="+", choices=("rock", "blow"), default=("rock", "blow"))
    ap.add_argument("--against", metavar="SRC", help="also run the package tree SRC (first)")
    ap.add_argument("--kernels", action="store_true", help="list every kernel's compiles and own CPU s")
    a = ap.parse_args(argv)
    trees = ([("baseline", a.against)] if a.against else []) + [("now", str(ROOT / "src"))]
    for row in a.rows:
        results = {label: run(src, row) for label, src in trees}
        print(f"{row}:")
        for label, r in results.items():
            print(f"  {label:<9} " + ", ".join(f"{k} {v:.2f}" if isinstance(v, float) else f"{k} {v}"
                                               for k, v in summary(r).items()))
            for k, v in sorted(r["sigs"].items()):
                print(f"    {k} compiled {len(v)} times: " + " | ".join(v))
            if a.kernels:
                for k, v in sorted(r["own"].items(), key=lambda kv: -kv[1]):
                    print(f"    {k:<64} {v:6.2f} s {r['count'][k]:>3}"
                          + ("" if r["machine"][k] else "  link-only"))
        if len(results) == 2:
            same = results["baseline"]["digest"] == results["now"]["digest"]
            print("  results " + ("the same to the bit" if same else "DIFFERENT"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
