r"""Probe: the circuit's plain flights by the compiled DOP853 (``_dop853``, the generated ``dop853_fly``)
against CVODE's Adams-Moulton (``_cvode.fly``), on one period of the preset ``circuit-drifter``'s orbit.

For each number of modes the orbit is found (by CVODE's flights, ``multistep="cvode"``), then its
period's "state" flights (``ShootingProblem._flight`` at the drive's variational-state tolerance,
``rtol = 1e-13``, ``atol = 1e-15``: the plain flights under Magnus' ``Phi``) are captured (their code,
parameters, start, end and event directions, by wrapping ``flight._integrate_compiled``) and each
flown again:

* CVODE at ``rtol = 1e-13`` (today's state flights: every step kept);
* DOP853 at ``rtol = 1e-12`` and ``1e-13`` (``atol`` a hundredth of ``rtol``), its kept points at
  most ``flight.keep_spacing`` apart at CVODE's (first) tolerance (dense-output samples inside its
  steps);

other tolerances by ``--cvode`` and ``--dop853``.

Per method, summed over the period: CPU time (best of ``--rounds``), steps, right-hand sides, kept
points; and per piece the worst of (a) the error at the piece's end against a reference (scipy's
DOP853 at ``rtol = 2.3e-14``, ``atol = 1e-17``, its dense output at each method's own end time), as
``max |y - ref| / (|ref| + 1e-3)``, (b) the difference of the end times from CVODE's, (c) the kept
points' error (the same norm, at every kept point), (d) the cubic Hermite interpolant of the kept
points (rates by the generated ``field_at``, as ``CircuitPiece``) at the middle of each kept
interval against the reference's dense output, same norm.

With ``--stiffer K ...``: instead, the CPU time of 3 periods of ``simulate`` from rest with the oil's
bulk modulus times each ``K``, Adams-Moulton, DOP853 and BDF (``multistep``), beside the stiffness
ratio (``flight.EXPLICIT_STIFFNESS``'s measurement).

Run: ``python benchmarks/probes/explicit_flight.py --modes 4 8 16 --rounds 3`` and
``... --modes 4 8 16 --rounds 2 --stiffer 1 3 10 30 100``. Library behaviour is not changed.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from impactbar import find_orbit
from impactbar.drives.circuit import CircuitFlightSettings, _cvode
from impactbar.drives.circuit import flight as F
from impactbar.physical import circuit_preset

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _timing import best_cpu  # noqa: E402  (benchmarks/_timing.py)


def _capture(n_modes):
    """The orbit's period of state flights: ``(drive, model, flights)``, each flight
    ``(code, par, y0, end, directions, keep, n_energy, t_end, y_end)`` as CVODE flew it."""
    d = circuit_preset("circuit-drifter")
    drive, model = d.drive(), d.model().with_(n_modes=n_modes)
    # (the flights captured are CVODE's, as before DOP853)
    orbit = find_orbit(model, drive, settings=CircuitFlightSettings(multistep="cvode"))
    p = orbit._problem
    X = np.asarray(orbit._unknowns, dtype=float)
    tau, mode = p.blocks[0]
    settings = F.magnus_state_settings(p.settings)
    cap = []
    orig = F._integrate_compiled

    def wrap(cv, band, blocks, adams, n_energy, code, par, s, directions, y0, t, end, keep):
        out = orig(cv, band, blocks, adams, n_energy, code, par, s, directions, y0, t, end, keep)
        cap.append((code, par.copy(), y0.copy(), float(end), np.asarray(directions, dtype=np.int32), keep,
                    n_energy, adams, float(out[2][-1]), out[4].copy()))
        return out

    F._integrate_compiled = wrap
    try:
        p._last = None
        p._flight(tau, mode, X, settings=settings)
    finally:
        F._integrate_compiled = orig
    return drive, model, settings, cap


def _best(call, rounds):
    """``(best CPU s of rounds calls, the result of one more)``."""
    return best_cpu(call, rounds), call()


def _hermite_error(code, par, ts, Y, ref):
    """The cubic Hermite interpolant of ``(ts, Y)`` at the middle of each interval against ``ref``."""
    if ts.size < 2:
        return 0.0
    f = np.empty_like(Y)
    code.field_at(np.ascontiguousarray(Y), par, f)
    h = np.diff(ts)[:, None]
    mid = 0.5 * (Y[:-1] + Y[1:]) + 0.125 * h * (f[:-1] - f[1:])
    r = ref(0.5 * (ts[:-1] + ts[1:])).T[:, :Y.shape[1]]
    return float(np.max(np.abs(mid - r) / (np.abs(r) + 1e-3)))


def _fly(method, flight, settings, spacing, rounds):
    """One captured flight by ``method`` (``"cvode 1e-13"``, ``"dop853 1e-12"``, ...): ``(CPU s, kept
    times, kept states, end state, steps, right-hand sides)``."""
    code, par, y0, end, directions, keep, n_energy, adams = flight[:8]
    rtol = float(method.split()[1])
    s = dataclasses.replace(settings, rtol=rtol, atol=rtol * 1e-2)
    if method.startswith("cvode"):
        cpu, out = _best(lambda: F._integrate_compiled(_cvode, True, True, adams, n_energy, code, par, s,
                                                       directions, y0, 0.0, end, keep), rounds)
        st = _cvode.last_workspace().statistics()
        return cpu, out[2], out[3], out[4], st["steps"], st["rhs"]
    cpu, out = _best(lambda: code.dop853_fly(0.0, y0, end, s.rtol, s.atol, directions, par, keep,
                                             F._MAX_STEPS, spacing), rounds)
    return cpu, out[1], out[2], out[3], int(out[5][0]), int(out[5][2])


def _reference(flight):
    """scipy's DOP853 at ``rtol = 2.3e-14`` over the flight (a hair past CVODE's end), its dense
    output."""
    code, par, y0, t1 = flight[0], flight[1], flight[2], flight[8]

    def f(t, y):
        yp = np.empty_like(y)
        code.flight_rhs(t, y, yp, par)
        return yp

    return solve_ivp(f, (0.0, t1 * (1 + 1e-9) + 1e-12), y0, method="DOP853", rtol=2.3e-14, atol=1e-17,
                     dense_output=True).sol


def run(n_modes, rounds, cvode=(1e-13,), dop853=(1e-12, 1e-13)):
    drive, model, settings, cap = _capture(n_modes)
    spacing = F.keep_spacing(drive, model, *cvode[:1])
    methods = [f"cvode {r:g}" for r in cvode] + [f"dop853 {r:g}" for r in dop853]
    tot = {m: dict(cpu=0.0, steps=0, rhs=0, kept=0, err=0.0, dt=0.0, pts=0.0, herm=0.0) for m in methods}
    for flight in cap:
        code, par, keep, t1 = flight[0], flight[1], flight[5], flight[8]
        ref = _reference(flight)
        for m in methods:
            cpu, ts, Y, yend, steps, rhs = _fly(m, flight, settings, spacing, rounds)
            te = float(ts[-1])
            r = ref(te)
            T = tot[m]
            T["cpu"] += cpu
            T["steps"] += steps
            T["rhs"] += rhs
            T["kept"] += ts.size
            T["err"] = max(T["err"], float(np.max(np.abs(yend - r) / (np.abs(r) + 1e-3))))
            T["dt"] = max(T["dt"], abs(te - t1))
            R = ref(ts).T[:, :keep]
            T["pts"] = max(T["pts"], float(np.max(np.abs(Y - R) / (np.abs(R) + 1e-3))))
            T["herm"] = max(T["herm"], _hermite_error(code, par, ts, Y, ref))
    print(f"\n{n_modes} modes: {len(cap)} flights, period {sum(c[8] for c in cap):.4f}, kept spacing "
          f"{spacing:.3g}")
    print(f"{'method':<14}{'CPU ms':>9}{'steps':>9}{'rhs':>9}{'kept':>9}{'end err':>10}{'|dt_end|':>10}"
          f"{'points':>10}{'Hermite':>10}")
    for m in methods:
        T = tot[m]
        print(f"{m:<14}{T['cpu'] * 1e3:9.1f}{T['steps']:9d}{T['rhs']:9d}{T['kept']:9d}{T['err']:10.1e}"
              f"{T['dt']:10.1e}{T['pts']:10.1e}{T['herm']:10.1e}")


def stiffness(n_modes, ks, rounds, periods=3.0):
    """CPU s of ``periods`` periods of ``simulate`` from rest on the stop with the oil's bulk modulus
    times each ``k``: the plain flights by Adams-Moulton, DOP853 and BDF (``multistep``), beside the
    stiffness ratio (how :data:`flight.EXPLICIT_STIFFNESS` was chosen, as ``ADAMS_STIFFNESS`` was),
    and the largest difference of the impact velocities from Adams'."""
    from impactbar import InitialState, simulate

    d = circuit_preset("circuit-drifter")
    base, model = d.drive(), d.model().with_(n_modes=n_modes)
    names = ("adams", "dop853", "bdf")
    print(f"\n{n_modes} modes, {periods:g} periods of simulate, CPU s (best of {rounds})")
    print(f"{'k':>6}{'ratio':>8}" + "".join(f"{m:>9}" for m in names) + f"{'adams/dop':>11}{'impacts':>9}"
          f"{'dv dop':>10}{'dv bdf':>10}")
    for k in ks:
        oil = dataclasses.replace(base.oil, bulk_modulus=k * base.oil.bulk_modulus)
        row, v = [], []
        drive = dataclasses.replace(base, oil=oil)
        for method in names:
            s = CircuitFlightSettings(multistep=method)
            start = InitialState.rigid(0.0, 0.0, n_modes)
            simulate(model, drive, start, 0.05, settings=s)  # (the network's code, compiled or loaded)
            cpu, tr = _best(lambda d=drive, s=s, start=start: simulate(model, d, start, periods, settings=s),
                            rounds)
            row.append(cpu)
            v.append(np.asarray(tr.impact_velocities, dtype=float))

        def dv(a, b):
            return float(np.nanmax(np.abs(a - b))) if a.size == b.size and a.size else float("nan")

        ratio = F.stiffness_ratio(drive, model)
        print(f"{k:6g}{ratio:8.2f}" + "".join(f"{c:9.3f}" for c in row) + f"{row[0] / row[1]:11.2f}"
              f"{v[0].size:9d}{dv(v[1], v[0]):10.1e}{dv(v[2], v[0]):10.1e}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--modes", type=int, nargs="+", default=[4, 8, 16])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--cvode", type=float, nargs="+", default=[1e-13], help="CVODE's rtol (Adams)")
    ap.add_argument("--dop853", type=float, nargs="+", default=[1e-12, 1e-13], help="DOP853's rtol")
    ap.add_argument("--stiffer", type=float, nargs="*", default=None,
                    help="instead: simulate CPU, the bulk modulus times each value")
    args = ap.parse_args()
    for n in args.modes:
        if args.stiffer is not None:
            stiffness(n, args.stiffer, args.rounds)
        else:
            run(n, args.rounds, args.cvode, args.dop853)


if __name__ == "__main__":
    main()
