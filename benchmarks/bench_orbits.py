"""Benchmark of ``periodic_orbits`` and the Fig. 5 boundary set, against the baseline a
user would otherwise write (``solve_ivp`` with impact events, run until the impact interval
settles).

Run: ``python benchmarks/bench_orbits.py [--quick]``. Prints a table; nothing is asserted.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy.integrate import solve_ivp

from impactbar import BarModel, CosineLoad, periodic_orbits
from impactbar.orbits.charts import pneumatic_existence_edge, pneumatic_stability_curve

TWO_PI = 2 * math.pi


def median_time(fn, repeat):
    fn()  # warm-up
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts)), float(np.min(ts))


def baseline_settle(model, load, *, tol=1e-8, max_periods=400, time_cap=None):
    """Simulate from rest at the stop with solve_ivp (DOP853, rtol 1e-10) and terminal impact events,
    restarting after each impact, until three impact intervals in a row are 2 pi to ``tol``.

    Returns (wall seconds, impacts, settled phase, settled flag)."""
    M = model.n_modes + 1
    w2 = model.frequencies**2
    c = model.end_weights
    d, R = model.d, model.R

    def rhs(t, y):
        return np.concatenate([y[M:], load(t) - d * y[M:] - w2 * y[:M]])

    def hit(t, y):
        return c @ y[:M]

    hit.terminal = True
    hit.direction = 1
    # start from the stable orbit's post-impact state, perturbed by 1e-3 (kind to the baseline:
    # a user starting far away waits longer, or meets chatter)
    orbit = next(o for o in periodic_orbits(model, load) if o.stable)
    rng = np.random.default_rng(1)
    y = orbit.state_after_impact * (1 + 1e-3 * rng.standard_normal(2 * M))
    y[0] -= c @ y[:M]
    t = orbit.phase
    times = []
    t_start = time.perf_counter()
    ok = False
    while t < max_periods * TWO_PI:
        sol = solve_ivp(rhs, (t, max_periods * TWO_PI), y, method="DOP853", rtol=1e-10, atol=1e-12,
                        events=hit)
        if not sol.t_events[0].size:
            break
        t = float(sol.t_events[0][0])
        y = sol.y_events[0][0].copy()
        y[M:] *= -R
        y[0] -= c @ y[:M]  # back onto the contact surface exactly
        times.append(t)
        if len(times) >= 4 and np.all(np.abs(np.diff(times[-4:]) - TWO_PI) < tol):
            ok = True
            break
        if time_cap and time.perf_counter() - t_start > time_cap:
            break
    return time.perf_counter() - t_start, len(times), (times[-1] % TWO_PI if times else math.nan), ok


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    rep = 5 if a.quick else 21
    load = CosineLoad(0.6, 1.0)
    print("impactbar benchmark: periodic_orbits with exact multipliers")
    print(f"{'case':<44} {'median ms':>10} {'min ms':>8}")
    for n in (0, 8, 64):
        model = BarModel(5.0, 0.1, 0.5, n)
        med, mn = median_time(lambda model=model: periodic_orbits(model, load), rep)
        print(f"{f'periodic_orbits, cosine, {n} modes':<44} {med * 1e3:10.2f} {mn * 1e3:8.2f}")
    from impactbar import SquareWaveLoad

    for n in (8, 64):
        model = BarModel(5.0, 0.1, 0.5, n)
        sq = SquareWaveLoad(1.0, 1.2)
        med, mn = median_time(lambda model=model, sq=sq: periodic_orbits(model, sq), max(3, rep // 4))
        print(f"{f'periodic_orbits, square wave, {n} modes':<44} {med * 1e3:10.2f} {mn * 1e3:8.2f}")

    R = np.linspace(0.0, 0.95, 40)

    def fig5():
        for d in (0.0, 0.03 / TWO_PI):
            pneumatic_existence_edge(R, d)
            pneumatic_stability_curve(BarModel(50.0, d, 0.0, 0), R)

    med, mn = median_time(fig5, 3)
    print(f"{'Fig. 5 boundary set (2 x 40 R, both edges)':<44} {med * 1e3:10.2f} {mn * 1e3:8.2f}")

    print("\nbaseline: solve_ivp (DOP853, rtol 1e-10) with impact events until the interval settles")
    print("(started 1e-3 off the stable orbit; where it has not settled within the time cap, the time")
    print(" is extrapolated: measured seconds per impact x the periods that max|mu| implies)")
    print(f"{'modes':>5} {'baseline s':>11} {'impacts':>8} {'settled':>8} {'impactbar ms':>13} {'ratio':>10}"
          f" {'phase diff':>11}")
    cap = 20 if a.quick else 120
    for n in (0, 8) if a.quick else (0, 8, 64):
        model = BarModel(5.0, 0.1, 0.5, n)
        tb, nimp, ph, ok = baseline_settle(model, load, time_cap=cap)
        med, _ = median_time(lambda model=model: periodic_orbits(model, load), rep)
        stable = [o for o in periodic_orbits(model, load) if o.stable]
        dph = abs(ph - stable[0].phase) if (stable and ok) else math.nan
        tag = ""
        if not ok and nimp:
            need = math.ceil(math.log(1e-8 / 1e-3) / math.log(stable[0].max_abs_multiplier)) + 3
            tb, tag = tb / nimp * need, " (est.)"
        print(f"{n:5d} {tb:11.2f}{tag:>7} {nimp:8d} {str(ok):>8} {med * 1e3:13.2f} {tb / med:10.0f}"
              f" {dph:11.1e}")


if __name__ == "__main__":
    main()
