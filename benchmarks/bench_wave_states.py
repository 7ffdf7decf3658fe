"""The wave law's blow under the oil circuit and the piston's states through it (``state_at``, what a
run's histories sample at each of the circuit's steps in a blow).

On the pump-fed drifter of theory §11 (70 L/min, 20 MPa, a 5.6 kg piston; one flexible mode, the
stop's ``R = 0.215``): one coupled blow (``driven_contact``: the circuit integrated over the window,
the window solved by characteristics), the same blow with its state sampled at 300 times through
the window (each sample the fields' projection on the modes), and a run of 4 blows from rest under
the circuit with the circuit's histories (``HydraulicCircuitDrive.histories``: pressures, valve,
gap, at every step of the integrator, 1,200 states inside the blows). CPU seconds, the best of 3
after one untimed call (numba's compilation, caches).

Run: ``python benchmarks/bench_wave_states.py``. ``--against SRC`` instead runs the same in fresh
processes on the package tree ``SRC`` (e.g. ``git archive <commit> src | tar -x -C /tmp/old`` then
``--against /tmp/old/src``) and on this one, alternately, and prints both side by side (the best
of three processes each).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from _timing import fresh_runs  # this folder's shared runner

from impactbar import BarModel, InitialState, simulate
from impactbar.drives import DriveState
from impactbar.drives.circuit import Accumulator, Chambers, HydraulicCircuitDrive, Oil, Supply, Valve

S = 52.0
SAMPLES = 300


def drifter():
    """The wave law's model and the pump-fed circuit (units of theory §11)."""
    model = BarModel(s=S, d=0.0, R=0.215, n_modes=1, impact="wave")
    drive = HydraulicCircuitDrive(
        Chambers(area_ratio=0.5, rear_volume=0.4, front_volume=0.2),
        Valve(switch_out=0.048, coefficient=2.0, switching_time=0.05),
        Supply(pump_flow=0.07, hose_volume=1.0, front_coefficient=2.0, tank_pressure=0.03),
        Oil(bulk_modulus=70.0, transition_pressure=0.01),
        Accumulator(precharge=0.5, volume=2.0))
    return model, drive


def best_cpu(fn, reps=3):
    """The least CPU time of ``reps`` calls of ``fn()`` (seconds), after one untimed call."""
    fn()
    out = float("inf")
    for _ in range(reps):
        t = time.process_time()
        fn()
        out = min(out, time.process_time() - t)
    return out


def cases():
    """``{case: CPU seconds}``."""
    model, drive = drifter()
    q, v = np.zeros(2), np.array([0.34, 0.0])
    state = DriveState((1, 0, 1, 0), np.array([1.15, 1.15, 1.15, 1.0]))
    law = model.law

    def blow():
        return law.driven_contact(model, drive, state, 0.0, q, v)

    def sampled():
        rec = blow().record
        for t in np.linspace(0.0, rec.duration, SAMPLES):
            rec.state_at(t)

    def run():
        traj = simulate(model, drive, InitialState.rigid(-0.06, 0.0), 20.0, max_impacts=4)
        drive.histories(traj)

    return {"one blow": best_cpu(blow), f"blow + {SAMPLES} states": best_cpu(sampled),
            "run of 4 blows + histories": best_cpu(run, 1)}


def against(src, rounds=3):
    """The cases on another package tree and on this one, in fresh processes, alternately."""
    runs = fresh_runs(__file__, src, rounds)
    print(f"{'case (CPU s, best of ' + str(rounds) + ' processes)':40s} {'baseline':>9s} {'new':>9s} "
          f"{'ratio':>7s}")
    for case in runs["new"][0]:
        b = min(r[case] for r in runs["baseline"])
        n = min(r[case] for r in runs["new"])
        print(f"{case:40s} {b:9.4f} {n:9.4f} {b / n:7.1f}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", metavar="SRC", help="compare with the package tree SRC instead")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # (--against's child)
    args = parser.parse_args(argv)
    if args.json:
        print(json.dumps(cases()))
        return
    if args.against:
        against(args.against)
        return
    for case, sec in cases().items():
        print(f"{case:40s} {sec:9.4f} s")


if __name__ == "__main__":
    main()
