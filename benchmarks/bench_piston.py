"""Benchmark of the stepped piston's exact free-free modes (64 of them, goal <= 10 ms),
side by side in the same process with the uniform piston's closed form (``BarModel.frequencies`` and
its cosine shapes) and with the same routine on one segment, and a finite-element solution of the
same stepped bar at the accuracy the exact one has (an independent method, for scale); and
``optimize_piston`` over two and three segments (goal <= 10 s for three), the gradient search beside
Nelder-Mead (derivative-free, the search before it) in the same run, and the baseline of one blow of
the uniform piston on the same rod and rock (one segment: nothing to optimise); one lattice blow with
its derivatives (the gradient search's unit) beside the plain blow;
and one blow of a stepped piston on a stepped rod with re-contacts by the exact solver (every wave
a delay line, the end certified) beside the uniform piston's exact blow and the lattice's (8 cells
per piston, first order) on the same rod.

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
        goal = "<= 10 ms" if name.startswith("stepped piston, 3") else ""
        print(f"{name:<80} {ms:>8.3f}   {goal}")
    blow_rows(max(1, args.repeat // 3))
    design_rows(max(1, args.repeat // 7))


def blow_rows(repeat):
    """``single_blow`` of a uniform and of stepped pistons on a two-segment rod (the tests' case)."""
    from impactbar import BilinearRock, RodRock, RodSegment, single_blow

    law = RodRock(segments=[RodSegment(0.75, 1.4), RodSegment(2.25, 0.7)], rock=BilinearRock(k=2.0, k_u=12.0))
    model = BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law)
    print(f"{'one blow on a stepped rod (median CPU time)':<80} {'ms':>8}")
    pistons = (("uniform piston", None),
               ("3 segments on a common grid", SteppedPiston([0.25, 0.5, 0.25], [1.0, 2.0, 1.3])),
               ("2 segments, arbitrary lengths", SteppedPiston([0.37, 0.63], [1.0, 1.6])),
               ("3 segments, arbitrary lengths", SteppedPiston([0.3, 0.45, 0.25], [1.0, 2.3, 1.4])))
    for label, piston in pistons:
        for method in ("exact", "lattice"):
            out = []
            ms = median_cpu(lambda p=piston, m=method, out=out: out.append(
                single_blow(model, 1.0, piston=p, method=m)), repeat) * 1e3
            b = out[-1]
            extra = f"ended {b.ended_by}" + (f", {b.exact.pieces} pieces" if method == "exact" else "")
            name = f"{label}, {method}: efficiency {b.efficiency:.6f} ({extra})"
            print(f"{name:<80} {ms:>8.2f}")


def design_rows(repeat):
    """optimize_piston on a matched 6 m rod, Lundberg's rock at alpha = 1.2564 and 3, stress limit 1.3
    times the uniform piston's (the tests' case): the gradient search (default) beside Nelder-Mead
    in the same run, over two and three segments; and one blow with its derivatives (the search's
    unit, two and four directions) beside the plain lattice blow of the same cells."""
    import math

    from impactbar.physical import optimize_piston
    from impactbar.physical.rock import RodPiece

    E, rho, m, L, V = 2.1e11, 7850.0, 2.355, 0.3, 10.0
    c = math.sqrt(E / rho)
    rod = [RodPiece(length_m=20 * L, area_m2=m / (rho * L), E_Pa=E, density_kg_m3=rho)]
    kw = dict(mass=m, length=L, max_stress=1.3 * rho * c * V / 2, impact_velocity=V)
    tangent_rows(repeat * 5, V / c)
    print(f"{'optimize_piston (median CPU time)':<80} {'s':>8}   goal")
    for alpha in (1.2564312, 3.0):
        K = alpha * (m * c / L) / (2 * L / c)
        for n, method in ((1, "slsqp"), (2, "slsqp"), (2, "nelder-mead"), (3, "slsqp"), (3, "nelder-mead")):
            best = []

            def run(n=n, method=method, best=best, K=K):
                best.append(optimize_piston(rod, (K, 1e12 * K), segments=n, method=method, **kw))

            s = median_cpu(run, repeat)
            b = best[-1]
            label = (f"alpha {alpha:.4g}, {n} segment(s), {method if n > 1 else 'uniform'}: {b.evaluations} "
                     f"blows, efficiency {b.efficiency:.7f}")
            goal = "<= 10 s" if n == 3 and method == "slsqp" else "baseline" if n == 1 else ""
            print(f"{label:<80} {s:>8.3f}   {goal}")


def tangent_rows(repeat, v):
    """One lattice blow of a 3-segment piston on whole cells (48 per piston, the tests' rod and rock
    at alpha = 3) with its derivatives in 2 and 4 directions, beside the plain blow."""
    from impactbar.laws.rodrock.blow import rod_rock_blow
    from impactbar.laws.rodrock.tangent import rod_rock_blow_tangent

    cells = np.repeat([0, 1, 2], [10, 13, 25])
    Z = 48 * np.array([0.4, 0.25, 0.35])[cells] / np.array([10, 13, 25])[cells]
    piston = SteppedPiston(np.ones(48), Z)
    rod, k = ([20.0], [1.0], [1.0]), 1.5
    print(f"{'one blow, 48 cells per piston, 1008 cells, 2112 steps (median CPU time)':<80} {'ms':>8}")
    rows = [("plain lattice blow (rod_rock_blow)", lambda: rod_rock_blow(
        1.0, v, *rod, k, 1e12 * k, 0.0, 0.0, cells_per_piston=48, t_max=44.0, piston=piston))]
    for nv in (2, 4):
        D = np.random.default_rng(0).standard_normal((48, nv))
        rows.append((f"with its derivatives in {nv} directions (rod_rock_blow_tangent)", lambda D=D:
                     rod_rock_blow_tangent(1.0, v, *rod, k, 1e12 * k, 0.0, 0.0, Z, D, t_max=44.0)))
    for name, fn in rows:
        print(f"{name:<80} {median_cpu(fn, repeat) * 1e3:>8.2f}")


if __name__ == "__main__":
    main()
