"""Benchmark: ``optimize_drifter`` with ``method="slsqp"`` (gradients by the implicit function theorem,
:func:`impactbar.physical.sensitivity.tangent_derivatives`) against the derivative-free COBYLA on a
small problem: the rigid circuit drifter preset, impact power over the switch point, the rear
chamber's volume and the accumulator's pre-charge (default constraints), in the same run.

Run: ``python benchmarks/bench_optimize_slsqp.py``. Prints per method the designs evaluated (orbits
solved), the gradients, the wall time, the gain and the optimum; nothing is asserted.
"""

from __future__ import annotations

import time

from impactbar.physical import build, optimize_drifter, read_config

VARY = {"valve.switch_out": ("20 mm", "23 mm"), "chambers.rear_volume": ("0.06 L", "0.2 L"),
        "accumulator.precharge": ("8 MPa", "14 MPa")}


def main() -> None:
    build(read_config("circuit-drifter")[0]).orbit()  # compiles (numba cache) outside the timing
    for vary in ({k: VARY[k] for k in ("valve.switch_out", "chambers.rear_volume")}, VARY):
        print(f"variables: {', '.join(vary)}")
        for method in ("cobyla", "slsqp"):
            t = time.perf_counter()
            res = optimize_drifter("circuit-drifter", vary, objective="impact_power", method=method,
                                   progress=False)
            wall = time.perf_counter() - t
            values = ", ".join(f"{k} {v:.6g}" for k, v in res.optimum["values"].items())
            print(f"  {method:6s}: {res.evaluations:3d} designs, {res.gradients:2d} gradients, {wall:5.1f} s;"
                  f" gain {res.gain * 100:+.4f} %; optimum {values}; {res.message}")


if __name__ == "__main__":
    main()
