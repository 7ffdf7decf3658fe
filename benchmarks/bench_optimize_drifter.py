"""Benchmark: ``optimize_drifter`` on the example rock drifter with its piston given by its shape
(examples/circuit_drifter_rock_piston.toml, the piston and circuit of examples/circuit_drifter_rock.toml)
over six variables (collar, front rod and rear rod diameters, rear chamber volume, switch point,
pre-charge) for drilling rate per hydraulic kilowatt, beside one baseline evaluation (a fresh ``orbit()``
of the start) in the same run.

Run: ``python benchmarks/bench_optimize_drifter.py [--max-evaluations N] [--out result.json]
[--cache cache.json] [--keys K1,K2,...] [--method cobyla|slsqp|differential_evolution|multistart]
[--sample N] [--local-starts K] [--workers W] [--quick]``; ``--keys four`` is the four variables of the
speed goal (the three diameters and the switch point). Prints the wall times, the number of
evaluations and the design table; nothing is asserted. A stopped run resumes from ``--cache``.

With ``--method multistart`` (a Sobol sample of ``--sample`` designs, COBYLA from the
``--local-starts`` best feasible ones) it prints too the designs evaluated, those without an operating
point and the seconds they cost, the certificate's verdict, the gain and each local search's best
design. ``--quick``: two variables (switch point, pre-charge), a sample of 8, one local search, 16
designs at most (a check that it runs, in minutes).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from impactbar.physical import build, optimize_drifter, read_config
from impactbar.physical.optimize_drifter import OBJECTIVES
from impactbar.physical.optimize_multistart import found_table

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "circuit_drifter_rock_piston.toml"

#: The problem of docs/optimising_a_drifter.md.
VARY = {
    "piston.collar_diameter": ("47 mm", "52 mm"),
    "piston.front_rod_diameter": ("43 mm", "47 mm"),
    "piston.rear_rod_diameter": ("38 mm", "43 mm"),
    "chambers.rear_volume": ("0.06 L", "0.2 L"),
    "valve.switch_out": ("18 mm", "25 mm"),
    "accumulator.precharge": ("8 MPa", "14 MPa"),
}
#: The four variables of the speed goal: the piston's three diameters and the switch point.
FOUR = ("piston.collar_diameter", "piston.front_rod_diameter", "piston.rear_rod_diameter", "valve.switch_out")
#: ``--quick``: the switch point and the pre-charge.
QUICK = ("valve.switch_out", "accumulator.precharge")
CONSTRAINTS = {"peak_incident_stress": "250 MPa", "min_drilling_rate": "2.5 m/min"}


def _multistart_summary(res) -> None:
    """The multistart's designs, its failures and their cost, the certificate, the gain, each local
    search's best design."""
    failed = [r for r in res.history if not r.get("ok")]
    cert, lost = res.certificate, sum(r.get("seconds", 0.0) for r in failed)
    print(f"multistart: {len(res.history)} designs evaluated ({res.evaluations} new, {res.cached} cached), "
          f"{len(failed)} without an operating point costing {lost:.1f} s of the designs' "
          f"{sum(r.get('seconds', 0.0) for r in res.history):.1f} s (each design's own time); certificate "
          f"{cert.verdict if cert is not None else 'none'}"
          f"{f' (KKT residual {cert.residual:.3g})' if cert is not None else ''}; gain {res.gain:+.2%}")
    print(found_table(res.found, res.vary, OBJECTIVES[res.objective][0]))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--max-evaluations", type=int, default=30)
    p.add_argument("--out", default=None)
    p.add_argument("--cache", default=None)
    p.add_argument("--any-rate", action="store_true",
                   help="drop the constraint on the drilling rate (the per-kW optimum then drills slower)")
    p.add_argument("--keys", default=None, help="a comma-separated subset of the variables, or 'four'")
    p.add_argument("--method", default="cobyla")
    p.add_argument("--popsize", type=int, default=5)
    p.add_argument("--sample", type=int, default=256)
    p.add_argument("--local-starts", type=int, default=3)
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--quick", action="store_true", help="multistart on two variables, a sample of 8")
    args = p.parse_args()
    if args.quick:
        args.method, args.keys, args.sample, args.local_starts = "multistart", ",".join(QUICK), 8, 1
        args.max_evaluations = 16
    keys = FOUR if args.keys == "four" else (args.keys.split(",") if args.keys else tuple(VARY))
    vary = {k: VARY[k] for k in keys}
    config, folder = read_config(EXAMPLE)
    drifter = build(config, folder)
    drifter.orbit()  # compiles (numba cache) outside the timing
    t = time.perf_counter()
    drifter.orbit()
    one = time.perf_counter() - t
    t = time.perf_counter()
    constraints = {**CONSTRAINTS, "min_drilling_rate": None} if args.any_rate else CONSTRAINTS
    c0 = time.process_time()
    res = optimize_drifter(EXAMPLE, vary, objective="drilling_rate_per_kW", constraints=constraints,
                           max_evaluations=args.max_evaluations, cache=args.cache, method=args.method,
                           popsize=args.popsize, progress=False, workers=args.workers,
                           **({"sample": args.sample, "local_starts": args.local_starts}
                              if args.method == "multistart" else {}))
    cpu = time.process_time() - c0
    wall = time.perf_counter() - t
    print(res.table())
    print(f"one baseline evaluation (fresh orbit): {one:.1f} s; optimize_drifter ({args.method}, "
          f"{len(vary)} variables): {wall:.0f} s wall, {cpu:.0f} s CPU, "
          f"{res.evaluations} evaluations ({res.cached} cached), {res.gradients} gradients, "
          f"{sum(r.get('continued', False) for r in res.history)} continued from a neighbour; {res.message}")
    if args.method == "multistart":
        _multistart_summary(res)
    if args.out:
        res.to_json(args.out)


if __name__ == "__main__":
    main()
