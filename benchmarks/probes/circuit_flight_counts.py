r"""Probe: where a circuit's rigid orbit spends its integration, counted over one ``find_orbit`` from
the default guess (after a call that compiles): the flights (each a call of CVODE from Python) and
CVODE's counters summed after each (:meth:`._cvode.Workspace.statistics`: steps, right-hand sides,
error-test failures, Newton iterations and failures, Jacobians, set-ups, event evaluations), by
wrapping ``flight._integrate_compiled``; then the CPU time of ``find_orbit`` (best of ``--rounds``)
and the orbit's numbers to the last digit (period, impact velocity, state at impact, multipliers), to
compare two trees run the same way.

Run: ``PYTHONPATH=<tree>/src python benchmarks/probes/circuit_flight_counts.py spool`` (``spool``:
``examples/circuit_drill_spool.toml``; ``parts``: ``circuit_drill_parts.toml``; ``preset``: the preset
``circuit-drifter``). Library behaviour is not changed.
"""

from __future__ import annotations

import argparse
import collections
import time
from pathlib import Path

import numpy as np

import impactbar.drives.circuit.flight as FL
from impactbar import find_orbit
from impactbar.drives.circuit import _cvode as CV
from impactbar.physical import circuit_preset, load

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def counted(model, drive) -> tuple:
    """``(orbit, CPU s, flights, CVODE's counters summed)`` of one ``find_orbit``."""
    total, flights = collections.Counter(), [0]
    plain = FL._integrate_compiled

    def counting(cv, *args, **kwargs):
        out = plain(cv, *args, **kwargs)
        flights[0] += 1
        total.update(CV.last_workspace().statistics())
        return out

    FL._integrate_compiled = counting
    try:
        t = time.process_time()
        orbit = find_orbit(model, drive)
        cpu = time.process_time() - t
    finally:
        FL._integrate_compiled = plain
    return orbit, cpu, flights[0], dict(total)


def drill(name: str) -> tuple:
    """``(model, drive)`` of the drill ``name``: ``"spool"``, ``"parts"``
    (``examples/circuit_drill_<name>.toml``) or ``"preset"`` (the preset ``circuit-drifter``)."""
    d = (circuit_preset("circuit-drifter") if name == "preset"
         else load(EXAMPLES / f"circuit_drill_{name}.toml"))
    return d.model(), d.drive()


def arguments(doc: str) -> argparse.Namespace:
    """The probes' command line: the drill and ``--rounds``."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("drill", choices=("spool", "parts", "preset"))
    parser.add_argument("--rounds", type=int, default=3)
    return parser.parse_args()


def main() -> None:
    a = arguments(__doc__)
    model, drive = drill(a.drill)
    find_orbit(model, drive)  # (compiles)
    orbit, _, flights, stats = counted(model, drive)
    print(f"{a.drill}: flights {flights}, " + ", ".join(f"{k} {v}" for k, v in stats.items()))
    best = float("inf")
    for _ in range(a.rounds):
        t = time.process_time()
        find_orbit(model, drive)
        best = min(best, time.process_time() - t)
    print(f"find_orbit CPU s, best of {a.rounds}: {best:.4f}")
    print(f"period {orbit.period!r}, impact velocity {orbit.impact_velocity!r}")
    print("state", np.array2string(np.asarray(orbit.drive_states[0]), precision=17))
    print("multipliers", np.array2string(np.sort_complex(np.asarray(orbit.multipliers)), precision=17))


if __name__ == "__main__":
    main()
