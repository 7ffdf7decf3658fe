"""The oil circuit's coupled blows (theory §11, "The coupled blow") against the blows with the force
held (the ideal valve's under the same law, theory §10), in the same run.

Run: ``python benchmarks/bench_circuit_laws.py`` (``--quick``: the blows only). On
``examples/circuit_drifter_rock.toml`` (the preset ``circuit-drifter`` on a drill string and rock, 8
cells per piston) at its operating point's arrival: one blow solved with the circuit's state
(``RodRock.driven_contact``: the lattice chunk by chunk, the circuit by CVODE step by step of the
lattice) against the same blow with the force held at the arrival's (``RodRock.contact``), and the
same under the wave law (the window with one integration of the circuit against the held window);
then ``find_orbit`` of the circuit on the rock against the ideal valve's at the circuit's mean supply
pressure on the same rock (``PositionSwitchedDrive``), and ``simulate`` over 20 blows of each. The
best of a few repetitions (the machine's other load only adds); compilation is done before the clock
starts.
"""

from __future__ import annotations

import argparse
import time
import tomllib
from pathlib import Path

import numpy as np

from impactbar import InitialState, PositionSwitchedDrive, find_orbit, simulate
from impactbar.loads import FourierLoad
from impactbar.physical import CircuitDrifter

EXAMPLE = Path(__file__).parents[1] / "examples" / "circuit_drifter_rock.toml"


def best(fn, reps):
    out = float("inf")
    for _ in range(reps):
        t = time.perf_counter()
        fn()
        out = min(out, time.perf_counter() - t)
    return out


def blows(model, drive, state, q, v, reps=3):
    """Seconds of one coupled blow and of the same blow with the force held."""
    law = model.law
    p0 = drive.force(state.mode, state.z, q, v)
    held = FourierLoad(p0, [])
    law.driven_contact(model, drive, state, 0.0, q, v)  # warm-up (compiling)
    law.contact(model, held, 0.0, q, v)
    return (best(lambda: law.driven_contact(model, drive, state, 0.0, q, v), reps),
            best(lambda: law.contact(model, held, 0.0, q, v), reps))


def main(quick=False):
    with open(EXAMPLE, "rb") as f:
        d = CircuitDrifter.from_config(tomllib.load(f))
    model, drive = d.model(), d.drive()
    point = d.orbit()
    o = point.orbit
    problem = o.problem
    tau, mode = problem.blocks[0]
    _, _, _, (_, q, v, state), _, _ = problem._flight(tau, mode, np.asarray(o._unknowns, dtype=float))
    rock = blows(model, drive, state, q, v)
    wave = model.with_(impact="wave", R=0.215)
    window = blows(wave, drive, state, q, v)
    print(f"{'one blow, s':>24} {'coupled':>9} {'held':>9}")
    print(f"{'rod-rock (8 cells)':>24} {rock[0]:>9.4f} {rock[1]:>9.4f}")
    print(f"{'wave law window':>24} {window[0]:>9.4f} {window[1]:>9.4f}")
    if quick:
        return
    ps = o.drive_states[0][2]
    a = drive.chambers.area_ratio
    ideal = PositionSwitchedDrive(stroke=ps * (1 - a), ret=a * ps - drive.supply.tank_pressure,
                                  switch_out=drive.valve.switch_out)
    oi = find_orbit(model, ideal)
    start = InitialState.rigid(-drive.valve.switch_out, 0.0)
    t_orbit = (best(lambda: find_orbit(model, drive), 1), best(lambda: find_orbit(model, ideal), 3))
    t_sim = (best(lambda: simulate(model, drive, start, 20.5 * o.period), 1),
             best(lambda: simulate(model, ideal, start, 20.5 * oi.period), 3))
    print(f"{'on the rock, s':>24} {'circuit':>9} {'ideal':>9}")
    print(f"{'find_orbit':>24} {t_orbit[0]:>9.3f} {t_orbit[1]:>9.3f}")
    print(f"{'simulate, 20 blows':>24} {t_sim[0]:>9.3f} {t_sim[1]:>9.3f}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="the blows only")
    main(**vars(parser.parse_args()))
