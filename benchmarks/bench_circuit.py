"""The drifter's oil circuit (theory §11) against the ideal valve it tends to (theory §10), in the
same run.

Run: ``python benchmarks/bench_circuit.py`` (``--quick``: the rigid piston only). On the preset
``circuit-drifter`` (dimensionless, ``impactbar.physical.circuit_preset``) and on the ideal valve
with the preset's forces at its mean supply pressure (``PositionSwitchedDrive``): the time of
``find_orbit`` from the default guess (rest on the stop, followed at a loose tolerance with the slow
supply mode extrapolated away, then Newton with the variational equations' Jacobian; beside it the
start of before, every impact followed at the drive's tolerance until they repeat to 1e-4), of
``simulate`` over 100 blows, and of one continuation point in the accumulator's pre-charge (beside it
the point of before: the parameter's column of the Jacobian by a central difference, full Newton
steps); the rigid
piston and 8 modes. Issue 38's goals on this 2-core machine: the rigid orbit <= 0.5 s, with 8 modes
<= 2 s, 100 blows <= 1 s rigid, a continuation point <= 0.2 s. The best of a few repetitions (the
machine's other load only adds); compilation is done before the clock starts.
"""

from __future__ import annotations

import argparse
import time

import impactbar.orbits._settling as settling
import impactbar.orbits.switched as S
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
    out["before"] = best(lambda: _plain_start(model, drive), reps)
    out["sim"] = (best(lambda: simulate(model, drive, start, 100.5 * o.period), reps),
                  best(lambda: simulate(model, ideal, start, 100.5 * oi.period), reps))
    out["cont before"] = min(_cont_point(o, drive, forward=False) for _ in range(reps))
    tc = min(_cont_point(o, drive, forward=True) for _ in range(reps))
    t = time.perf_counter()
    bi = continue_orbit(oi, "switch_out", to=ideal.switch_out * 1.05, max_points=6, events=False)
    out["cont"] = (tc, (time.perf_counter() - t) / max(1, len(bi.orbits) - 1))
    return out


def _cont_point(o, drive, forward):
    """Seconds per point of a continuation in the pre-charge (5 points): now, the parameter's column
    of the Jacobian by a forward difference and each corrector's first step a chord step with the
    last orbit's Jacobian; before, a central difference and full Newton steps."""
    import impactbar.continuation.switched as CS

    keep = CS.FORWARD_LAMBDA, CS.CHORD
    CS.FORWARD_LAMBDA = CS.CHORD = forward
    try:
        t = time.perf_counter()
        b = continue_orbit(o, "precharge", to=drive.accumulator.precharge * 1.05, max_points=6, events=False)
        return (time.perf_counter() - t) / max(1, len(b.orbits) - 1)
    finally:
        CS.FORWARD_LAMBDA, CS.CHORD = keep


def _plain_start(model, drive):
    """``find_orbit`` with the start of before the settling's acceleration: every impact followed at the
    drive's tolerance until the impact velocities agree to 1e-4, no extrapolation."""
    fit, rtol = settling.DOMINANT_FIT, S.SETTLE_RTOL
    settling.DOMINANT_FIT, S.SETTLE_RTOL = 0.0, drive.integrator.rtol
    try:
        return find_orbit(model, drive)
    finally:
        settling.DOMINANT_FIT, S.SETTLE_RTOL = fit, rtol


def integrators(d, drive):
    """One stroke flight of the rigid preset (from rest 60 mm out, the supply at 22 MPa, to the
    impact) by CVODE and by scipy's Radau on the same compiled right-hand side and Jacobian, both at
    rtol 1e-10: seconds and right-hand-side evaluations of each."""
    import numpy as np
    from scipy.integrate import solve_ivp

    from impactbar.drives import DriveState
    from impactbar.drives.circuit import _kernel as K
    from impactbar.drives.circuit.flight import circuit_flight

    model = d.model()
    q, v = np.array([-0.06 / d.bar.length_m]), np.array([0.0])
    state = DriveState((1, 0, 1, 0), np.array([2.2, 2.2, 2.2, 1.0]))
    par = drive._par(model, state.mode)
    n = 6 + K.N_ENERGY
    calls = [0]

    def f(t, y):
        calls[0] += 1
        out = np.empty(n)
        K.rhs(t, y, out, par)
        return out

    def jac(t, y):
        JJ = np.empty((n, n))
        K.jac(t, y, None, JJ, par)
        return JJ

    def arrival(t, y):
        return y[0]

    arrival.terminal, arrival.direction = True, 1
    y0 = np.concatenate((q, v, state.z, np.zeros(K.N_ENERGY)))
    circuit_flight(drive, model, state, 0.0, q, v, 50.0)  # warm-up
    t_cv = best(lambda: circuit_flight(drive, model, state, 0.0, q, v, 50.0), 3)
    t = time.perf_counter()
    ref = solve_ivp(f, (0.0, 50.0), y0, method="Radau", rtol=1e-10, atol=1e-12, jac=jac, events=arrival)
    t_ra = time.perf_counter() - t
    fl = circuit_flight(drive, model, state, 0.0, q, v, 50.0)
    return t_cv, fl.piece.t.size, t_ra, ref.t.size, calls[0], abs(ref.t_events[0][0] - fl.t) / fl.t


def main(quick=False):
    d = circuit_preset("circuit-drifter")
    drive = d.drive()
    t_cv, s_cv, t_ra, s_ra, c_ra, gap = integrators(d, drive)
    print(f"one stroke flight, rtol 1e-10: CVODE {t_cv:.4f} s ({s_cv} steps), scipy Radau {t_ra:.3f} s "
          f"({s_ra} steps, {c_ra} evaluations): {t_ra / t_cv:.0f} times; impact times {gap:.1e} apart")
    print(f"{'modes':>5} {'':>8} {'orbit s':>9} {'100 blows s':>12} {'cont. point s':>14}")
    for n in (0,) if quick else (0, 8):
        r = row(d, drive, n)
        for j, name in enumerate(("circuit", "ideal")):
            print(f"{n:>5} {name:>8} {r['orbit'][j]:>9.4f} {r['sim'][j]:>12.4f} {r['cont'][j]:>14.4f}")
        print(f"{n:>5} {'before':>8} {r['before']:>9.4f} {'':>12} {r['cont before']:>14.4f}   (the circuit's "
              "orbit from the start of before; its continuation point with a central difference in "
              "the parameter and full Newton steps)")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    main(parser.parse_args().quick)
