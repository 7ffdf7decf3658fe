r"""Probe: does ``BUZZING`` (``tests/physical/drifter_optimum.py``: a front annulus of 0.39 mm^2, the
blows ended at the law's window, ``drifter_optimum.window_end``) have a one-impact orbit, and what
does the start from rest at the valve's switch point (``orbit(switch_start=True)``,
:mod:`impactbar.physical.circuit_switch`) cost against the default chain?

For BUZZING it prints: the default chain's error and cost (coupled blows, seconds); the orbit
continued along its collar from 47.3 mm down to its own 47 mm (as ``existence_borders.py``), its
period, impact velocity, largest multiplier, relief margin and event pattern (the drive's discrete
states in order); the orbit ``orbit(switch_start=True)`` finds, its cost and its distance from the
continued one; ``simulate`` restarted from that orbit (30 periods: its impacts against the orbit's);
runs of ``simulate`` from rest on the stop and from rest at the switch point, each with the supply at
its start pressure and at the relief's setting (their last impacts). Then the
same start on the documented multistart's designs without a one-impact orbit
(``drifter_optimum.DOCUMENTED_NO_ORBIT``, the example's own settings) and on the lattice band's
``collar(1.01)`` and ``SEARCHED``.

Run: ``python benchmarks/probes/switch_start.py`` (a minute or two). Measured on s21-buzz,
2026-11-30 (benchmarks/HISTORY.md, "A one-impact orbit that rest does not reach").
"""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "physical"))
from drifter_optimum import BUZZING, DOCUMENTED_NO_ORBIT, EXAMPLE, SEARCHED, collar, window_end  # noqa: E402

from impactbar import InitialState, simulate  # noqa: E402
from impactbar.orbits import coupled  # noqa: E402
from impactbar.physical import build, read_config, with_values  # noqa: E402
from impactbar.physical.optimize_failures import switch_orbit, switch_summary  # noqa: E402

_COUNT = [0]
_SOLVE = coupled.blow_state


def _counted(*args, **kwargs):
    _COUNT[0] += 1
    return _SOLVE(*args, **kwargs)


def _timed(fn):
    """``fn()``'s result (or its ValueError), its coupled blows and seconds."""
    _COUNT[0], t0 = 0, time.perf_counter()
    try:
        out = fn()
    except ValueError as err:
        out = err
    return out, _COUNT[0], time.perf_counter() - t0


def _said(point) -> str:
    o = point.orbit
    mu = float(np.abs(o.multipliers).max())
    return (f"period {point.period_s * 1e3:.6f} ms, {point.impact_velocity_m_s:.6f} m/s, |mu|max {mu:.6f} "
            f"({'stable' if o.stable else 'unstable'}), relief margin "
            f"{point.border_margins_Pa['relief'] / 1e6:+.4f} MPa")


def _runs(drifter) -> None:
    drive, model = drifter.drive(), drifter.model()
    L, om = drifter.bar.length_m, drifter.omega_rad_s
    p_rel, tank = drive.supply.relief_pressure, drive.supply.tank_pressure
    top = drive.valve.switch_out
    for name, gap, start in (("rest on the stop", 0.0, None),
                             ("rest on the stop, the supply at the relief's setting", 0.0,
                              (p_rel, tank, p_rel, 0.0)),
                             ("rest at the switch point", top, None),
                             ("the switch point, the supply at the relief's setting", top,
                              (p_rel, tank, p_rel, 1.0))):
        d = drive if start is None else dataclasses.replace(drive, start_pressures=start)
        run = simulate(model, d, InitialState.rigid(-gap, 0.0, drifter.n_modes), 0.4 * om, histories=False,
                       max_impacts=200)
        t, v = np.asarray(run.impact_times) / om, np.asarray(run.impact_velocities) * L * om
        print(f"  simulate 0.4 s from {name}: {t.size} impacts, {int(np.sum(v > 1.0))} above 1 m/s; the last "
              f"{np.round(v[-3:], 4)} m/s, {np.round(np.diff(t[-4:]) * 1e3, 3)} ms apart", flush=True)


def main() -> None:
    coupled.blow_state = _counted
    cfg, folder = read_config(EXAMPLE)
    mp = pytest.MonkeyPatch()
    window_end(mp)
    print("-- BUZZING, the blows ended at the law's window")
    err, n, s = _timed(lambda: build(with_values(cfg, BUZZING), folder).orbit())
    print(f"default chain: {n} coupled blows, {s:.2f} s: {str(err)[:240]}", flush=True)
    guess = None
    for c in (47.3, 47.2, 47.15, 47.1, 47.05, 47.0):
        guess = build(with_values(cfg, dict(BUZZING, **{"piston.collar_diameter": f"{c!r} mm"})),
                      folder).orbit(guess)
    print(f"continued along the collar from 47.3 mm: {_said(guess)}")
    print(f"  its events: {guess.orbit.problem.event_pattern(guess.orbit._unknowns)}")
    point, n, s = _timed(lambda: build(with_values(cfg, BUZZING), folder).orbit(switch_start=True))
    print(f"orbit(switch_start=True): {n} coupled blows, {s:.2f} s: {_said(point)}")
    X, Y = point.orbit._unknowns, guess.orbit._unknowns
    print(f"  against the continued orbit: unknowns {np.max(np.abs(X - Y)) / np.max(np.abs(Y)):.2g} "
          f"relative, multipliers {np.max(np.abs(point.orbit.multipliers - guess.orbit.multipliers)):.2g}")
    o = point.orbit
    M = o.model.n_modes + 1
    y = np.asarray(o.states_after_impact[0], dtype=float)
    run = simulate(o.model, dataclasses.replace(o.drive, start_pressures=tuple(o.drive_states[0])),
                   InitialState(y[:M], y[M:]), 30.5 * o.period, histories=False)
    t, v = np.asarray(run.impact_times), np.asarray(run.impact_velocities)
    k = np.arange(t.size)
    print(f"  simulate restarted from it, 30 periods: {t.size} impacts, arrivals off the orbit's by "
          f"{np.max(np.abs(t - o.impact_times[0] - k * o.period)) / o.period:.2g} periods, velocities by "
          f"{np.max(np.abs(v / o.impact_velocity - 1.0)):.2g} relative")
    _runs(build(with_values(cfg, BUZZING), folder))
    for name, changes in (("collar(1.01)", collar(1.01)), ("SEARCHED", SEARCHED)):
        found, n, s = _timed(lambda changes=changes: switch_orbit(build(with_values(cfg, changes), folder)))
        print(f"{name}: {n} coupled blows, {s:.2f} s: {switch_summary(found)}", flush=True)
    mp.undo()
    print("-- the documented multistart's designs without a one-impact orbit (the example's own settings)")
    for i, changes in enumerate(DOCUMENTED_NO_ORBIT):
        err, n0, s0 = _timed(lambda changes=changes: build(with_values(cfg, changes), folder).orbit())
        found, n, s = _timed(lambda changes=changes: switch_orbit(build(with_values(cfg, changes), folder)))
        print(f"design {i}: default chain {n0} coupled blows, {s0:.2f} s ({str(err)[:120]}); from the switch "
              f"point {n} coupled blows, {s:.2f} s: {switch_summary(found)}", flush=True)
    coupled.blow_state = _SOLVE


if __name__ == "__main__":
    main()
