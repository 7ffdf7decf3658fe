"""The drifter's oil circuit (theory §11) against the ideal valve it tends to (theory §10), in the
same run.

Run: ``python benchmarks/bench_circuit.py`` (``--quick``: the rigid piston only). On the preset
``circuit-drifter`` (dimensionless, ``impactbar.physical.circuit_preset``) and on the ideal valve
with the preset's forces at its mean supply pressure (``PositionSwitchedDrive``): the time of
``find_orbit`` from the default guess (rest on the stop, followed until the impacts repeat to 1e-6,
then Newton with the variational equations' Jacobian), of ``simulate`` over 100 blows, and of one
continuation point in the accumulator's pre-charge; the rigid piston and 8 modes. Issue 38's goals on
this 2-core machine: the rigid orbit <= 0.5 s, with 8 modes <= 2 s, 100 blows <= 1 s rigid, a
continuation point <= 0.2 s. The best of a few repetitions (the machine's other load only adds);
compilation is done before the clock starts.
"""

from __future__ import annotations

import argparse
import time

from impactbar import InitialState, PositionSwitchedDrive, continue_orbit, find_orbit, simulate
from impactbar.physical import circuit_preset


def best(fn, reps):
    out = float("inf")
    for _ in range(reps):
        t = time.perf_counter()
        fn()
        out = min(out, time.perf_counter() - t)
    return out


def row(d, drive, n):
    """The timings of the circuit and of the ideal valve at its mean supply pressure, ``n`` modes."""
    model = d.model().with_(n_modes=n)
    o = find_orbit(model, drive)
    ps = o.drive_states[0][2]
    a = drive.chambers.area_ratio
    ideal = PositionSwitchedDrive(stroke=ps * (1 - a), ret=a * ps - drive.supply.tank_pressure,
                                  switch_out=drive.valve.switch_out)
    oi = find_orbit(model, ideal)
    reps = 2 if n else 3
    start = InitialState.rigid(0.0, 0.0, n)
    out = {}
    out["orbit"] = (best(lambda: find_orbit(model, drive), reps),
                    best(lambda: find_orbit(model, ideal), reps))
    out["sim"] = (best(lambda: simulate(model, drive, start, 100.5 * o.period), reps),
                  best(lambda: simulate(model, ideal, start, 100.5 * oi.period), reps))
    t = time.perf_counter()
    b = continue_orbit(o, "precharge", to=drive.accumulator.precharge * 1.05, max_points=6, events=False)
    tc = (time.perf_counter() - t) / max(1, len(b.orbits) - 1)
    t = time.perf_counter()
    bi = continue_orbit(oi, "switch_out", to=ideal.switch_out * 1.05, max_points=6, events=False)
    out["cont"] = (tc, (time.perf_counter() - t) / max(1, len(bi.orbits) - 1))
    return out


def main(quick=False):
    d = circuit_preset("circuit-drifter")
    drive = d.drive()
    print(f"{'modes':>5} {'':>8} {'orbit s':>9} {'100 blows s':>12} {'cont. point s':>14}")
    for n in (0,) if quick else (0, 8):
        r = row(d, drive, n)
        for j, name in enumerate(("circuit", "ideal")):
            print(f"{n:>5} {name:>8} {r['orbit'][j]:>9.4f} {r['sim'][j]:>12.4f} {r['cont'][j]:>14.4f}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    main(parser.parse_args().quick)
