"""Benchmark: ``optimize_drifter(method="differential_evolution")``, each generation's designs evaluated
in this process (``workers=None``) and on a local dask cluster of 1 and 2 worker processes, in the same
run: the rigid circuit drifter preset, impact power over the switch point and the accumulator's
pre-charge (default constraints).

With ``--rock``: the drifter on the rod and rock (``examples/circuit_drifter_rock_piston.toml``, its
flexible piston's blows by the rod-rock law, several seconds an orbit), drilling rate per kW over the
collar's diameter under a peak incident stress of 260 MPa, ``workers`` None and 2 (about 3 minutes).

Run: ``python benchmarks/bench_optimize_population.py [--popsize 5] [--max-evaluations 40] [--rock]``.
Prints per
``workers`` the designs evaluated, the wall time of the whole call (the cluster's start and close
included) and the best objective; nothing is asserted. The runs visit the same designs (the records are
the same bit for bit), so only the time differs.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from impactbar.physical import build, optimize_drifter, read_config

VARY = {"valve.switch_out": ("20 mm", "23 mm"), "accumulator.precharge": ("8 MPa", "12 MPa")}
ROCK = Path(__file__).resolve().parents[1] / "examples" / "circuit_drifter_rock_piston.toml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--popsize", type=int, default=5)
    ap.add_argument("--max-evaluations", type=int, default=40)
    ap.add_argument("--rock", action="store_true")
    args = ap.parse_args()
    if args.rock:
        config, vary, objective, workers_list = ROCK, {"piston.collar_diameter": ("48 mm", "50 mm")}, \
            "drilling_rate_per_kW", (None, 2)
        constraints = {"peak_rod_stress": "260 MPa"}
    else:
        config, vary, objective, constraints, workers_list = "circuit-drifter", VARY, "impact_power", None, \
            (None, 1, 2)
    fkey = {"impact_power": "impact_power_kW", "drilling_rate_per_kW": "drilling_rate_per_kW"}[objective]
    build(read_config(config)[0]).orbit()  # compiles (numba cache) outside the timing
    print(f"{config}: {objective} over {', '.join(vary)}; popsize {args.popsize}, max_evaluations "
          f"{args.max_evaluations}")
    for workers in workers_list:
        t = time.perf_counter()
        res = optimize_drifter(config, vary, objective=objective, constraints=constraints,
                               method="differential_evolution", workers=workers, popsize=args.popsize,
                               max_evaluations=args.max_evaluations, progress=False)
        wall = time.perf_counter() - t
        orbits = sum(r.get("seconds", 0.0) for r in res.history)
        values = ", ".join(f"{k} {v:.6g}" for k, v in res.optimum["values"].items())
        print(f"  workers={workers!s:4s}: {res.evaluations:3d} designs, {wall:5.1f} s wall "
              f"({orbits:5.1f} s of orbits summed); best {objective} "
              f"{res.optimum['objectives'][fkey]:.6g}, gain {res.gain * 100:+.4f} %; "
              f"optimum {values}")


if __name__ == "__main__":
    main()
