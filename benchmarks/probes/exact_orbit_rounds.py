r"""Probe: where the exact orbit's coupled blows spend their exact solver, counted over one warm
``find_orbit`` of ``examples/circuit_drifter_rock.toml`` with ``RodRock(method="exact")``.

Counted (deterministic) by wrapping the solver's runs (``exact._run``) and the coupled blow
(:func:`~impactbar.laws.rodrock.coupled_exact.driven_exact_contact`): for each exact coupled blow
the runs of its rounds of the drive's force (a round whose pool filled runs again, larger), each
run's start (the impact, or the snapshot it goes on from), its horizon and the solver's windows it
ran (``h``, the shortest travel time, long each), the wave pieces at its end, and the windows run
over all its runs against the blow's own; the arriving wave's splines made and taken again.

Then, timed (CPU s, best of ``--reps`` after one call): the last blow solved again from the impact
with its last force, to the end of each window (fixed horizon, no certificate), and to its
certified end, and its runs' windows priced at those costs; and the plain iteration of the force
(every round the whole blow) started from the force of the Newton iterate before (the previous
exact blow's, time from the impact), each round's change of the force (of its size) and its
solver's CPU, and its last force's distance from the march's.

Run: ``PYTHONPATH=<tree>/src python benchmarks/probes/exact_orbit_rounds.py [--reps N]``. Library
behaviour is not changed.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

import impactbar.laws.rodrock.coupled_exact as CE
import impactbar.laws.rodrock.exact as EXM
import impactbar.laws.rodrock.exactrecord as ER
from impactbar import find_orbit
from impactbar.laws.rodrock import _records as S
from impactbar.laws.rodrock.exactmap import ExactBlowMap, initial_waves
from impactbar.loads import FourierLoad
from impactbar.physical import CircuitDrifter

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _timing import best_cpu  # noqa: E402  (benchmarks/_timing.py)

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter_rock.toml"


def _setup():
    """The example's drifter and its model with exact blows."""
    with open(EXAMPLE, "rb") as f:
        drifter = CircuitDrifter.from_config(tomllib.load(f))
    model = drifter.model()
    return drifter, model.with_(impact=dataclasses.replace(model.law, method="exact"))


def counted(drifter, exact) -> list:
    """One warm orbit's exact coupled blows: ``(arrival, rounds, final force, record)`` each, a round
    ``(start, horizon, windows, pieces)`` (``start`` None: from the impact), and the splines made, taken
    and the records sampled."""
    find_orbit(exact, drifter.drive())  # (untimed: compilation, caches)
    blows, runs, made = [], [], [0, 0, 0]
    plain_run, plain_contact, plain_init = EXM._run, CE.driven_exact_contact, CE._Force.__init__
    plain_spline, plain_sampled = CE._spline_callable, ER.blow_from_exact
    forces = []

    def run(ws, t_max, stops, h, snaps, scale):
        CI, CT = ws[S.WS_CI], ws[S.WS_CT]
        w0, t0 = int(CI[S.CI_WIN]), float(CT[S.CT_T])
        out = plain_run(ws, t_max, stops, h, snaps, scale)
        runs.append((t0 if w0 else None, t_max, int(CI[S.CI_WIN]) - w0, int(ws[S.WS_CNT][S.CNT_PIECES])))
        return out

    def contact(model, drive, state, t0, q, v, *args, **kwargs):
        del runs[:], forces[:]
        out = plain_contact(model, drive, state, t0, q, v, *args, **kwargs)
        arrival = (model, drive, state, t0, np.array(q), np.array(v))
        blows.append((arrival, list(runs), forces[-2], out.record))
        return out

    def init(self, *args, **kwargs):
        plain_init(self, *args, **kwargs)
        forces.append(self)

    def spline(*args):
        made[0] += 1
        return plain_spline(*args)

    def callables(self, breaks, memo=None):
        out = plain_callables(self, breaks, memo)
        made[1] += len(out)
        return out

    def sampled(*args, **kwargs):
        made[2] += 1
        return plain_sampled(*args, **kwargs)

    plain_callables = CE._Incoming.callables
    EXM._run, CE.driven_exact_contact, CE._Force.__init__ = run, contact, init
    CE._spline_callable, CE._Incoming.callables, ER.blow_from_exact = spline, callables, sampled
    try:
        find_orbit(exact, drifter.drive())
    finally:
        EXM._run, CE.driven_exact_contact, CE._Force.__init__ = plain_run, plain_contact, plain_init
        CE._spline_callable, CE._Incoming.callables = plain_spline, plain_callables
        ER.blow_from_exact = plain_sampled
    return blows, made


def window_costs(blow, reps) -> tuple:
    """The last blow's force, solved again from the impact: CPU s to the end of each window (fixed
    horizon), and to the certified end."""
    (model, drive, state, t0, q, v), _, force, rec = blow
    bmap = rec._map
    bmap.drive = force.pieces(float(bmap.basis.travel[0]), float(rec.duration))
    h = float(min(bmap.basis.travel.min(), bmap.rod_times.min()))
    n = int(np.ceil(rec.duration / h - 1e-9))
    cum = [best_cpu(lambda w=w: bmap.solve(q, v, t_max=min(w * h, rec.duration), lean=True), reps)
           for w in range(1, n + 1)]
    cap = CE.HORIZONS * float(model.law.window(model))
    whole = best_cpu(lambda: bmap.solve(q, v, t_max=cap, lean=True, certified=True), reps)
    return h, cum, whole


def warm_rounds(blow, start, rounds=6) -> tuple:
    """The plain iteration of ``blow``'s force from the force ``start``: ``(change, solver CPU s)`` a
    round, and the last force's distance from the march's (of its size)."""
    (model, drive, state, t0, q, v), _, march, _ = blow
    p0 = float(drive.force(state.mode, state.z, q, v))
    bmap = ExactBlowMap(model, FourierLoad(p0, []), t0)
    T0, Z0 = float(bmap.basis.travel[0]), float(bmap.basis.impedance[0])
    cap = CE.HORIZONS * bmap.duration
    waves = initial_waves(bmap.basis, q, v, p0)
    w0 = -float(model.drive_weights @ q)
    force, out, scale = start, [], abs(p0)
    for _ in range(rounds):
        bmap.drive = force.pieces(T0, cap)
        t = time.process_time()
        ex = bmap.solve(q, v, record=True, t_max=cap, certified=True)
        cpu = time.process_time() - t
        breaks = CE._breaks(ex, T0, float(ex.duration), t0)
        a = CE._Incoming(ex, waves, force, T0, Z0, t0).callables(breaks)
        fl = drive.abilities.end_flight(model, state, breaks, w0, a, Z0, None)
        new = CE._Force(p0, fl.pieces, t0)
        grid = np.union1d(new.starts, np.linspace(0.0, float(ex.duration), 257))
        scale = max(scale, float(np.max(np.abs(new(grid)))))
        out.append((float(np.max(np.abs(new(grid) - force(grid)))) / scale, cpu))
        force = new
        if out[-1][0] < 1e-12:
            break
    grid = np.linspace(0.0, float(ex.duration), 4097)
    return out, float(np.max(np.abs(force(grid) - march(grid)))) / scale


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reps", type=int, default=3, help="best of this many timings")
    args = parser.parse_args(argv)
    drifter, exact = _setup()
    blows, made = counted(drifter, exact)
    T0 = float(blows[0][3]._map.basis.travel[0])
    print(f"{len(blows)} exact coupled blows, {sum(len(b[1]) for b in blows)} solver runs; T0 = "
          f"{T0:.6g} (model time); splines made {made[0]} of {made[1]}; records sampled {made[2]}")
    for i, (_, runs, _, rec) in enumerate(blows):
        print(f"blow {i + 1}: ends at {rec.duration / T0:.4f} T0 ({rec.exact.ended_by}), "
              f"{rec.exact.windows} windows, {rec.exact.pieces} pieces")
        for k, (start, horizon, windows, pieces) in enumerate(runs):
            where = "impact" if start is None else f"{start / T0:.3f} T0"
            print(f"  run {k + 1}: from {where:>9s} to {min(horizon, rec.duration) / T0:7.3f} T0, "
                  f"{windows:2d} windows, {pieces:6d} pieces")
        print(f"  windows run over its runs {sum(r[2] for r in runs)} (the blow's own {rec.exact.windows})")
    h, cum, whole = window_costs(blows[-1], args.reps)
    print(f"the last blow from the impact with its last force (CPU s, best of {args.reps}; windows of "
          f"{h / T0:.4f} T0):")
    print("  to window " + ", ".join(f"{w + 1}: {c:.3f}" for w, c in enumerate(cum)))
    print(f"  to its certified end: {whole:.3f}")
    # (each round's windows priced at these costs: what the march's rounds cost against the blow once)
    runs, D = blows[-1][1], float(blows[-1][3].duration)
    at = np.minimum(np.concatenate(([0.0], h * np.arange(1, len(cum) + 1))), D)
    price = np.concatenate(([0.0], cum))
    rounds = sum(float(np.interp(min(hz, D), at, price) - np.interp(0.0 if t is None else t, at, price))
                 for t, hz, _, _ in runs)
    print(f"  its runs' windows at these costs {rounds:.3f} s against the blow once {cum[-1]:.3f} s "
          f"(without the certificate's end)")
    for i in range(1, len(blows)):
        rows, dist = warm_rounds(blows[i], blows[i - 1][2])
        print(f"blow {i + 1}, the plain iteration from blow {i}'s force: changes "
              + ", ".join(f"{c:.2e} ({t:.3f} s)" for c, t in rows) + f"; from the march's force {dist:.2e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
