"""A design map of the rigid oil-circuit drifter (preset ``circuit-drifter``) over the pump flow and the
accumulator's pre-charge: ``impactbar.sweeps.run_map`` (each point continued from its neighbour, the
chunks stored in zarr) against the same points as a loop of fresh ``orbit()`` calls, in the same run.

Run: ``python benchmarks/bench_drifter_map.py`` (21 x 21 points: 3-15 MPa x 50-150 L/min, the grid of
``examples/sweep_map_circuit_drifter.toml``) or ``--quick`` (7 x 7); ``--figure PNG`` draws the map.
``--workers N`` runs the map on a local dask cluster of N processes (default: one thread of this
process, the same single core as the loop). Reported: wall and CPU seconds of each, the points per
second, how many map points were continued from a neighbour, and the largest relative difference
between the map and the loop over the stored variables (the continued points differ by the
integrator's accuracy, about 1e-9). The kernels are compiled (or loaded) before the clock starts.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from impactbar.physical.loader import build, read_config, with_values
from impactbar.sweeps import open_sweep, parse_spec, run_map
from impactbar.sweeps.map_task import point_values


def clocks(fn):
    """``(result, wall seconds, CPU seconds of this process)`` of ``fn()``."""
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="7 x 7 points instead of 21 x 21")
    ap.add_argument("--workers", type=int, default=None, help="dask workers for the map (default: one "
                    "thread of this process)")
    ap.add_argument("--config", default="circuit-drifter", help="the drifter: a preset or a TOML file "
                    "(e.g. examples/circuit_drifter_rock.toml: the map on rock)")
    ap.add_argument("--grid", type=int, default=None, help="n x n points (default 21, --quick 7)")
    ap.add_argument("--no-loop", action="store_true", help="time the map alone (no loop of orbit() calls)")
    ap.add_argument("--json", action="store_true", help="print the figures as one JSON line last")
    ap.add_argument("--figure", default=None, metavar="PNG", help="also draw the map's hydraulic "
                    "efficiency with its edges into this file (impactbar plot)")
    args = ap.parse_args()
    n = args.grid or (7 if args.quick else 21)
    config_name = str(Path(args.config).resolve()) if args.config.endswith(".toml") else args.config
    doc = {"task": "operating_point", "config": config_name,
           "axes": {"accumulator.precharge": {"start": "3 MPa", "stop": "15 MPa", "num": n},
                    "supply.pump_flow": {"start": "50 L/min", "stop": "150 L/min", "num": n}}}
    spec = parse_spec(doc)
    config = read_config(config_name)[0]
    build(config).orbit()  # compile or load the kernels before the clocks start

    def loop():
        out = {}
        for i, p in enumerate(spec.axes[0].values):
            for j, q in enumerate(spec.axes[1].values):
                cfg = with_values(config, {"supply.pump_flow": f"{q!r} m**3/s",
                                           "accumulator.precharge": f"{p!r} Pa"})
                try:
                    out[i, j] = point_values(build(cfg).orbit(allow_cavitation=True), "circuit", False)
                except ValueError:
                    out[i, j] = None
        return out

    with tempfile.TemporaryDirectory() as tmp:
        store = Path(tmp) / "map.zarr"
        kw = {"executor": "threads", "n_workers": 1} if args.workers is None else {"n_workers": args.workers}
        _, map_wall, map_cpu = clocks(lambda: run_map(spec, store, progress=False, refine=False, **kw))
        ds = open_sweep(store).load()
        if args.figure:
            from impactbar.sweeps import plot_sweep

            plot_sweep(store, args.figure, variable="hydraulic_efficiency", dpi=110)
    ref, loop_wall, loop_cpu = clocks(loop) if not args.no_loop else ({}, float("nan"), float("nan"))
    worst, where, by_name = 0.0, "", {}
    for (i, j), want in ref.items():
        if want is None:
            continue
        for name, w in want.items():
            if isinstance(w, bool) or name.endswith("_margin") or not np.isfinite(w) or w == 0:
                continue
            d = abs(float(ds[name].values[i, j]) / w - 1.0)
            by_name[name] = max(by_name.get(name, 0.0), d)
            if d > worst:
                worst, where = d, f"{name} at {(i, j)}, origin {int(ds['origin'].values[i, j])}"
    fig = {"points": spec.n_points, "map_wall_s": round(map_wall, 2), "map_cpu_s": round(map_cpu, 2),
           "loop_wall_s": round(loop_wall, 2), "loop_cpu_s": round(loop_cpu, 2),
           "continued": int(np.count_nonzero(ds["origin"].values)),
           "no_orbit": int(np.count_nonzero(ds["status"].values)),
           "loop_no_orbit": sum(v is None for v in ref.values()),
           "edges": int(ds.sizes.get("edge", 0)), "max_rel_diff": float(f"{worst:.3g}"),
           "workers": args.workers or "1 thread"}
    print(f"{n} x {n} map of {args.config} (pump flow x pre-charge), {spec.n_points} points")
    print(f"  run_map (continued):   {map_wall:7.2f} s wall, {map_cpu:7.2f} s CPU (this process), "
          f"{spec.n_points / map_wall:5.2f} points/s; {fig['continued']} points continued, "
          f"{fig['no_orbit']} without an orbit, {fig['edges']} edges")
    print(f"  loop of fresh orbit(): {loop_wall:7.2f} s wall, {loop_cpu:7.2f} s CPU, "
          f"{spec.n_points / loop_wall:5.2f} points/s; {fig['loop_no_orbit']} without an orbit")
    print(f"  largest relative difference map vs loop: {worst:.2g} ({where}); by variable: "
          + ", ".join(f"{k} {v:.1g}" for k, v in sorted(by_name.items())))
    if args.json:
        print(json.dumps(fig))


if __name__ == "__main__":
    main()
