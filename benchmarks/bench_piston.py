"""Benchmark for issue 44: the stepped piston's exact free-free modes (64 of them, goal <= 10 ms),
side by side in the same process with the uniform piston's closed form (``BarModel.frequencies`` and
its cosine shapes) and with the same routine on one segment, and a finite-element solution of the
same stepped bar at the accuracy the exact one has (an independent method, for scale).

Run: ``python benchmarks/bench_piston.py [--repeat N]``. Prints a table of median CPU times;
nothing is asserted.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.linalg import eigh_tridiagonal

from impactbar import BarModel, SteppedPiston


def median_cpu(fn, repeat):
    fn()
    ts = []
    for _ in range(repeat):
        t = time.process_time()
        fn()
        ts.append(time.process_time() - t)
    return float(np.median(ts))


def fe_modes(lengths, impedances, elements, count):
    """Linear finite elements with lumped masses, nodes on the steps (error O(h^2))."""
    per = np.rint(np.asarray(lengths) / np.sum(lengths) * elements).astype(int)
    h = np.repeat(np.asarray(lengths) / np.sum(lengths) / per, per)
    z = np.repeat(impedances, per)
    stiff = z / h
    dk = np.zeros(h.size + 1)
    dk[:-1] += stiff
    dk[1:] += stiff
    m = np.zeros(h.size + 1)
    m[:-1] += z * h / 2
    m[1:] += z * h / 2
    w = 1.0 / np.sqrt(m)
    return eigh_tridiagonal(dk * w * w, -stiff * w[:-1] * w[1:], eigvals_only=True, select="i",
                            select_range=(1, count))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=21)
    args = ap.parse_args()
    three = ([0.2, 0.3, 0.5], [3.0, 1.0, 2.0])
    x = np.linspace(0.0, 1.0, 257)
    model = BarModel(10.0, 0.0, 0.5, 64)
    rows = [
        ("stepped piston, 3 segments, 64 modes (exact)", lambda: SteppedPiston(*three).modes(64)),
        ("stepped piston, 1 segment, 64 modes (exact)", lambda: SteppedPiston([1.0], [1.0]).modes(64)),
        ("uniform bar, 64 modes (closed form + shapes on 257 points)",
         lambda: (model.frequencies, model.shape_functions(x))),
        ("3 segments, 64 modes by finite elements, 20,000 elements (O(h^2): ~1e-5 at mode 64)",
         lambda: fe_modes(*three, 20000, 64)),
    ]
    print(f"{'task (median CPU time)':<80} {'ms':>8}   goal")
    for name, fn in rows:
        ms = median_cpu(fn, args.repeat) * 1e3
        goal = "<= 10 ms (issue 44)" if name.startswith("stepped piston, 3") else ""
        print(f"{name:<80} {ms:>8.3f}   {goal}")


if __name__ == "__main__":
    main()
