"""Benchmark: ``operating_point_sensitivities`` (the implicit function theorem on the orbit's shooting
system) against central differences of orbits at p +- h (h its own step): fresh ``orbit()`` calls (from
rest) and orbits continued from the design's (``orbit(guess=...)``), on the rigid circuit drifter
preset and, with ``--rock``, on the example drifter on the rock with its piston given by its shape.

Run: ``python benchmarks/bench_sensitivity.py [--rock]``. Prints per key the wall times and the largest
difference of the figures' derivatives, relative to the derivative and as an equivalent relative
error of the figures (``|dF_ift - dF_cd| h / |F|``, to set beside the orbits' own accuracy, about
1e-9); nothing is asserted.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from impactbar.physical import build, operating_point_sensitivities, read_config, with_values
from impactbar.physical.sensitivity import _figures

ROOT = Path(__file__).resolve().parents[1]
PROBLEMS = {
    "circuit-drifter": ("circuit-drifter", ["accumulator.precharge", "valve.switch_out",
                                            "chambers.rear_volume", "supply.pump_flow"]),
    "rock": (ROOT / "examples" / "circuit_drifter_rock_piston.toml", ["piston.collar_diameter",
                                                                     "valve.switch_out"]),
}


def _compare(name: str, source, keys: list[str], fresh: bool) -> None:
    cfg, folder = read_config(source)
    drifter = build(cfg, folder)
    drifter.orbit()  # compiles (numba cache) outside the timing
    t = time.perf_counter()
    orbit = drifter.orbit()
    t_orbit = time.perf_counter() - t
    print(f"{name}: the design's orbit {t_orbit:.2f} s")
    for multipliers in (True, False):
        t = time.perf_counter()
        s = operating_point_sensitivities(cfg, keys, orbit=orbit, multipliers=multipliers)
        print(f"  IFT, {len(keys)} keys, multipliers={multipliers}: {time.perf_counter() - t:.2f} s "
              f"({s.flights} flights)")
    s = operating_point_sensitivities(cfg, keys, orbit=orbit)
    for key in keys:
        p, unit = s.values[key], s.units[key]
        h = s.steps[key]
        ways = {"continued": lambda d: d.orbit(guess=orbit)}
        if fresh:
            ways["fresh"] = lambda d: d.orbit()
        for way, solve in ways.items():
            t = time.perf_counter()
            plus, minus = (_figures(solve(build(with_values(cfg, {key: f"{p + sign * h!r} {unit}"}), folder)))
                           for sign in (1.0, -1.0))
            wall = time.perf_counter() - t
            rel = eq = 0.0
            for fig, F in s.figures.items():
                cd = (plus[fig] - minus[fig]) / (2.0 * h)
                diff = abs(s.derivatives[fig][key] - cd)
                rel = max(rel, diff / abs(cd) if cd else 0.0)
                eq = max(eq, diff * h / abs(F) if F else 0.0)
            print(f"  {key:26s} CD of {way:9s} orbits {wall:6.2f} s; IFT vs CD: max rel {rel:.1e}, "
                  f"as a relative error of the figures {eq:.1e}")
    print(s.table())


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rock", action="store_true", help="also the example drifter on the rock (minutes)")
    args = p.parse_args()
    _compare("circuit-drifter", *PROBLEMS["circuit-drifter"], fresh=True)
    if args.rock:
        _compare("rock", *PROBLEMS["rock"], fresh=False)


if __name__ == "__main__":
    main()
