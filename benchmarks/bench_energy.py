"""Benchmark of the energy account of a run under the wave law with a pressing load
(s = 50, 40 modes, two load periods), side by side in the same process with the simulation itself
and with the quadrature the account used before (Gauss-Legendre, 16 nodes a panel, panels doubling
from the fastest decay up to the fastest oscillation's scale, then on the load's), which the
sustained contact's integrals now replace by their closed form.

Run: ``python benchmarks/bench_energy.py [--repeat N]``. Prints median wall times; asserts nothing.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from impactbar import BarModel, CosineLoad, InitialState, simulate
from impactbar.laws.wave.law import PressedContact

X, W = np.polynomial.legendre.leggauss(16)


def old_integrals(sc, tau):
    """The sustained contact's ``(work, rod, damping, advance)`` as main computed them before."""
    t_end = sc.t0 + float(tau)
    out = np.zeros(4)
    lam_max, decay = float(np.max(np.abs(sc.lam))), float(np.min(-sc.lam.real))
    osc = float(np.max(np.abs(sc.lam.imag)))
    h_osc = 1.5 / osc if osc > 0.0 else math.inf
    kmax = float(np.max(sc._data.ks)) if sc._data.kind == 0 and sc._data.ks.size else 0.0
    for p in sc._pieces:
        a, b = p.ta, min(p.tb, t_end)
        if b <= a:
            break
        t_tr = min(b, a + 40.0 / decay)
        grow, w = [a], 1.0 / lam_max
        while grow[-1] < t_tr and w < h_osc:
            grow.append(min(grow[-1] + w, t_tr))
            w *= 2.0
        x = grow[-1]
        n_osc = math.ceil((t_tr - x) / h_osc) if t_tr > x else 0
        n_rest = math.ceil((b - t_tr) * (kmax + 1.0) / 1.5) if b > t_tr else 0
        parts = [np.asarray(grow)]
        if n_osc:
            parts.append(np.linspace(x, t_tr, n_osc + 1)[1:])
        if n_rest:
            parts.append(np.linspace(t_tr, b, n_rest + 1)[1:])
        e = np.concatenate(parts)
        for i in range(0, e.size - 1, 1024):
            ee = e[i:i + 1025]
            half = 0.5 * np.diff(ee)
            t = (half[:, None] * (X + 1.0) + ee[:-1, None]).ravel()
            wt = (half[:, None] * W).ravel()
            v = p.states(t)[sc.N:]
            ut1 = sc.c @ v
            pn = sc.load(t) if p.level is None else p.level
            out += [np.sum(wt * pn * (sc.kappa @ v)), sc.impedance * np.sum(wt * ut1 * ut1),
                    sc.model.d * np.sum(wt * (sc.kappa @ (v * v))), np.sum(wt * ut1)]
    return out


def median_wall(fn, repeat):
    ts = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return float(np.median(ts))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    model = BarModel(50.0, 0.1, 0.5, 40, impact="wave")
    load, start = CosineLoad(2.0, 1.0), InitialState.rigid(-0.5, 0.0, n_modes=40)

    def run():
        return simulate(model, load, start, 4 * math.pi)

    run()  # compile
    t_sim = median_wall(run, args.repeat)
    runs = [run() for _ in range(args.repeat)]
    t_acc = median_wall(lambda: runs.pop().energy, args.repeat)
    tr = run()
    windows = [seg.frozen for seg in tr._segments if isinstance(seg.frozen, PressedContact)]
    sustained = [(w.sustained, w.duration - w.window.duration) for w in windows]

    def closed():
        for sc, tau in sustained:
            sc.__dict__.pop("_integral_memo", None)
            sc._integrals(tau)

    def quadrature():
        for sc, tau in sustained:
            old_integrals(sc, tau)

    t_closed, t_quad = median_wall(closed, args.repeat), median_wall(quadrature, 1)
    diff = max(float(np.max(np.abs(np.array(sc._integrals(tau)) - old_integrals(sc, tau))))
               for sc, tau in sustained)
    print(f"s = 50, 40 modes, CosineLoad(2, 1), 2 load periods, {len(sustained)} sustained contacts")
    print(f"{'simulate':<44s} {t_sim:8.3f} s")
    print(f"{'Trajectory.energy (closed-form integrals)':<44s} {t_acc:8.3f} s")
    print(f"{'  its sustained contacts, closed form':<44s} {t_closed:8.4f} s")
    print(f"{'  the same by the former quadrature':<44s} {t_quad:8.3f} s   (max difference {diff:.1e})")


if __name__ == "__main__":
    main()
