"""Benchmark of ``periodic_orbits`` under the wave law against the paper's law at
``n_modes`` from 8 to 1024, side by side in the same process (goal: the wave law within 2x the
paper law at every ``n_modes``), and on the two presets.

Run: ``python benchmarks/bench_wave_modes.py [--quick] [--repeat N] [--modes 8 64 256 1024]``. Prints
a table (median wall time of fresh calls: the per-model caches are cleared between repeats); nothing
is asserted. The presets' calls take 2-4 ms, where a median of the default 5 moved the ratio by 0.5
between runs on a 2-core machine at load 1: ``--repeat 41`` for those.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from impactbar import BarModel, CosineLoad, periodic_orbits, physical


def _clear_caches():
    from impactbar.laws.wave import _characteristics, impact
    from impactbar.laws.wave import periodic as wave
    from impactbar.orbits import stability

    # (getattr: an older tree, timed for comparison, may lack some of these caches; the wave law's
    # Fourier moment tables too, which from 64 modes on were timed once per run, not per call)
    for f in (getattr(wave, "_phase_scan", None), getattr(wave, "_state_series", None),
              getattr(wave, "_flight_fundamental", None), stability.period_fundamental,
              getattr(_characteristics, "_held_scan_table", None),
              getattr(impact, "_fourier_moment_tables", None)):
        if f is not None:
            f.cache_clear()


def median_time(fn, repeat):
    fn()  # warm-up (numba compilation)
    ts = []
    for _ in range(repeat):
        _clear_caches()
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def cases(modes):
    load = CosineLoad(0.6, 1.0)
    for n in modes:
        yield f"s=3 d=0 R=0.5 N={n}", BarModel(3.0, 0.0, 0.5, n), load
    for name in ("pneumatic-drill", "hydraulic-drill"):
        h = physical.preset(name)
        yield name, h.model, h.load


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="fewer repeats")
    ap.add_argument("--repeat", type=int, help="fresh calls per case (default 5, or 3 with --quick)")
    ap.add_argument("--modes", type=int, nargs="+", default=[8, 32, 64, 128, 256, 512, 1024])
    args = ap.parse_args(argv)
    repeat = args.repeat or (3 if args.quick else 5)
    print(f"{'case':<26} {'paper law/s':>12} {'wave law/s':>11} {'ratio':>6} {'orbits p/w':>11}")
    for name, model, load in cases(args.modes):
        t, n = {}, {}
        for law in ("paper", "wave"):
            m = model.with_(impact=law)
            t[law] = median_time(lambda m=m, load=load: periodic_orbits(m, load), repeat)
            n[law] = len(periodic_orbits(m, load))
        print(f"{name:<26} {t['paper']:12.4f} {t['wave']:11.4f} {t['wave'] / t['paper']:6.2f} "
              f"{n['paper']:>5}/{n['wave']:<5}", flush=True)


if __name__ == "__main__":
    main()
