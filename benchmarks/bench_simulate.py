"""Impacts per second: impactbar's event-driven simulator against the baseline users write today,
scipy ``solve_ivp`` (DOP853, rtol 1e-10) restarted at each terminal impact event.

Run: ``python benchmarks/bench_simulate.py`` (add ``--quick`` for a short run). Prints one table:
for 0, 8 and 64 flexible modes and 1 and 64 load harmonics, impacts per second of both, their
ratio, and the largest difference of the impact times they find. Compilation (numba warm-up) is
done before the clock starts. Then a batch of 1000 rigid-bar runs of 1000 impacts on 2 threads.

Every case starts close to the stable one-impact orbit of ``periodic_orbits`` (pneumatic hammer,
``p0/p1 = 1.2``, ``R = 0.8``, ``d = 0.02``, ``s = 1.37``), so both methods follow the same long
sequence of impacts, with no chatter the baseline could not follow.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy.integrate import solve_ivp

from impactbar import BarModel, FourierLoad, InitialState, periodic_orbits, simulate


def baseline(model, load, t0, q0, v0, n_impacts, rtol=1e-10):
    """solve_ivp (DOP853) restarted at each terminal impact event; impact law applied by hand."""
    M = model.n_modes + 1
    w2 = model.frequencies**2
    c = model.end_weights
    d = model.d
    R = model.R

    def rhs(t, y):
        return np.concatenate((y[M:], load(t) - d * y[M:] - w2 * y[:M]))

    def hit(t, y):
        return c @ y[:M]

    hit.terminal = True
    hit.direction = 1
    t, y = t0, np.concatenate((q0, v0))
    times = []
    while len(times) < n_impacts:
        sol = solve_ivp(rhs, (t, t + 1e4), y, method="DOP853", rtol=rtol, atol=1e-12, events=hit)
        if sol.status != 1:
            break
        t, y = sol.t_events[0][-1], sol.y_events[0][-1].copy()
        times.append(t)
        y[M:] *= -R
    return np.array(times)


def setup(n_modes, n_harmonics):
    model = BarModel(s=1.37, d=0.02, R=0.8, n_modes=n_modes)
    coef = np.zeros(n_harmonics, dtype=complex)
    coef[0] = 1.0
    if n_harmonics > 1:
        k = np.arange(2, n_harmonics + 1)
        coef[1:] = 0.02 * np.exp(1j * k) / k  # a small, rich ripple on the main harmonic
    load = FourierLoad(1.2, coef)
    orbit = next(o for o in periodic_orbits(model, load) if o.stable)
    q, v = orbit.modal_state_after_impact
    q = q.copy()
    q[0] -= 1e-3  # a small step back from the stop: the run starts off the orbit
    return model, load, orbit.phase, q, v


def rate_impactbar(model, load, t0, q, v, n):
    st = InitialState(q, v)
    simulate(model, load, st, t0 + 1e7, t0=t0, max_impacts=5)  # compile outside the clock
    t = time.perf_counter()
    tr = simulate(model, load, st, t0 + 1e7, t0=t0, max_impacts=n)
    return tr, n / (time.perf_counter() - t)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer impacts")
    args = ap.parse_args(argv)
    n_base = 10 if args.quick else 40
    n_fast = 2000 if args.quick else 20000
    rows = []
    for n_modes in (0, 8, 64):
        for n_harm in (1, 64):
            model, load, t0, q, v = setup(n_modes, n_harm)
            tr, fast = rate_impactbar(model, load, t0, q, v, n_fast)
            nb = n_base if n_modes <= 8 else max(3, n_base // 4)
            t = time.perf_counter()
            ref = baseline(model, load, t0, q, v, nb)
            slow = ref.size / (time.perf_counter() - t)
            dt = float(np.max(np.abs(ref - tr.impact_times[:ref.size])))
            rows.append((n_modes, n_harm, slow, fast, fast / slow, dt, ref.size))
    print(f"{'modes':>5} {'harmonics':>9} | {'solve_ivp imp/s':>15} {'impactbar imp/s':>15} "
          f"{'ratio':>8} | {'max |dt|':>9} over")
    print("-" * 80)
    for n_modes, n_harm, slow, fast, ratio, dt, nb in rows:
        print(f"{n_modes:>5} {n_harm:>9} | {slow:>15.1f} {fast:>15.0f} {ratio:>8.0f} | "
              f"{dt:>9.1e} {nb:>4} impacts")

    # batch: 1000 rigid-bar runs of 1000 impacts each, 2 threads (the core releases the GIL)
    model, load, t0, q, v = setup(0, 1)
    rng = np.random.default_rng(0)
    starts = [InitialState(q - [1e-3 * rng.uniform()], v * rng.uniform(0.95, 1.05))
              for _ in range(1000)]
    simulate(model, load, starts[0], t0 + 1e7, t0=t0, max_impacts=5)
    t = time.perf_counter()
    with ThreadPoolExecutor(2) as pool:
        runs = list(pool.map(
            lambda st: simulate(model, load, st, t0 + 1e7, t0=t0, max_impacts=1000), starts))
    wall = time.perf_counter() - t
    total = sum(r.n_impacts for r in runs)
    print(f"\nbatch: {len(runs)} rigid-bar runs, {total} impacts in {wall:.2f} s on 2 threads "
          f"({total / wall:.0f} impacts/s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
