"""A circuit drifter's one-impact orbit checked by a restart, and found from a second start: the
piston at rest at the valve's switch point (:meth:`~impactbar.physical.CircuitDrifter.orbit` with
``switch_start=True``; theory §11, "Optimising a drifter").

The default chain of :meth:`~impactbar.physical.CircuitDrifter.orbit` has one start, the piston at
rest on the stop, its motion followed until its impacts settle. A design may have a one-impact
orbit whose basin does not hold that start: on a design the optimiser's restarted searches met (a
front annulus of 0.39 mm^2, the blows ended at the law's window) the piston from rest on the stop
strikes twice, then buzzes on the shank, never reaching the switch point again, while from rest at
the switch point its blows are the orbit's from the first (8.9 m/s, 50 Hz, the relief valve open
twice a period, stable) when the supply starts at the relief's setting, and reach it from the
pre-charge. Newton's start from rest on the stop never comes near that orbit. The orbit so found
is refused unless :func:`impactbar.simulate`, restarted from it, repeats it (:func:`check_repeats`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

__all__ = ["REPEAT_TOL", "SWITCH_RUN_IMPACTS", "SWITCH_RUN_S", "check_repeats", "switch_start_orbit"]

#: How closely an orbit restarted in :func:`impactbar.simulate` must repeat itself (relative, over
#: two periods: the impact times and velocities).
REPEAT_TOL = 1e-6
#: The impacts of the run from rest at the switch point handed to Newton as its guess (its motion
#: then followed to Newton's start as from any run: ``find_orbit(guess=run)``)
SWITCH_RUN_IMPACTS = 2
#: The longest that run (s of the drill's time): a piston that has not struck twice by then has no
#: orbit from there
SWITCH_RUN_S = 1.0


def check_repeats(orbit, first: float | None = None) -> None:
    """Refuse a one-impact orbit of the circuit that :func:`impactbar.simulate`, restarted from its
    state after the impact (the pressures and the valve's opening as ``start_pressures``, the drive's
    discrete state from them), does not repeat over two periods to :data:`REPEAT_TOL`: the orbit's
    discrete state (the valve, the accumulator's and the relief valve's flags) would disagree with
    its continuous state, a solution of the equations that is not the machine's motion (theory §10).

    Parameters
    ----------
    orbit : DrivenOrbit
        The circuit's orbit (model units); one with more impacts a period is not checked.
    first : float, optional
        When the restarted run's first impact is due (model time from the state after the impact):
        default the period (an impact that takes no time); on rod and rock the orbit's arrival,
        ``orbit.impact_times[0]`` (its state is where the blow ends).

    Raises
    ------
    ValueError
        The run's impacts (times, velocities) off the orbit's by more than :data:`REPEAT_TOL`.
    """
    from ..simulation import InitialState, simulate

    if orbit.impacts != 1:
        return
    M = orbit.model.n_modes + 1
    y = np.asarray(orbit.states_after_impact[0], dtype=float)
    drive = dataclasses.replace(orbit.drive, start_pressures=tuple(orbit.drive_states[0]))
    T = orbit.period
    if first is None:
        due, span = T * np.arange(1, 3), 2.0 * T * (1.0 + 1e-3)
    else:
        due = first + T * np.arange(2)
        span = due[-1] + 2e-3 * T
    run = simulate(orbit.model, drive, InitialState(y[:M], y[M:]), span, max_impacts=2)
    times, speeds = np.asarray(run.impact_times), np.asarray(run.impact_velocities)
    v = orbit.impact_velocity
    if times.size < 2 or np.max(np.abs(times - due)) > REPEAT_TOL * T * 2 \
            or np.max(np.abs(speeds - v)) > REPEAT_TOL * abs(v):
        t1 = times.min() if times.size else math.nan  # (the first impact's time)
        said = f"{t1 / T:.6g}" if times.size else "none"
        rest = [b - a for a, b in np.asarray(run.contact_intervals).reshape(-1, 2)
                if times.size and abs(a - t1) <= REPEAT_TOL * T and b > a]
        if orbit.model.R == 0.0 and rest:  # (theory: at R = 0 the load must pull the end away at once)
            raise ValueError(f"find_orbit's orbit (period {T:.6g}) leaves the stop at once after its "
                             "plastic impact (stop.restitution = 0), but the net force then pushes the "
                             f"piston on the stop: simulate rests it there {rest[0] / T:.3g} periods, so the "
                             "orbit passes through the stop, not a motion of the circuit (an orbit with a "
                             "rest on the stop is not solved: give stop.restitution > 0)")
        raise ValueError(f"find_orbit's orbit (period {T:.6g}) does not repeat when simulate restarts it "
                         f"from its state after the impact (the first interval {said} periods): not a "
                         "motion of the circuit")


def switch_start_orbit(drifter, model=None, drive=None):
    """The one-impact orbit found from the piston at rest at the valve's switch point: a run of
    :func:`impactbar.simulate` from there (the circuit at its start pressures, the valve on the
    stroke) to its :data:`SWITCH_RUN_IMPACTS`-th impact, at most :data:`SWITCH_RUN_S` long, handed
    to :func:`impactbar.find_orbit` as its guess; the orbit checked by a restart
    (:func:`check_repeats`, from its arrival). Theory §10 (the drive's orbit and its guesses), §11.

    Parameters
    ----------
    drifter : CircuitDrifter
    model : BarModel, optional
        ``drifter.model()`` (default: built here).
    drive : HydraulicCircuitDrive, optional
        ``drifter.drive()`` (default: built here).

    Returns
    -------
    DrivenOrbit
        In the model's units, stable or not (its ``stable`` and ``multipliers`` say).

    Raises
    ------
    ValueError
        Where the run fails (a chamber empties, the oil would cavitate, a flight without an end),
        strikes fewer times than :data:`SWITCH_RUN_IMPACTS`, Newton finds no orbit from it, or the
        orbit does not repeat when restarted.
    """
    from ..orbits import find_orbit
    from ..simulation import InitialState, simulate

    model = drifter.model() if model is None else model
    drive = drifter.drive() if drive is None else drive
    start = InitialState.rigid(-drive.valve.switch_out, 0.0, model.n_modes)
    run = simulate(model, drive, start, SWITCH_RUN_S * drifter.omega_rad_s, histories=False,
                   max_impacts=SWITCH_RUN_IMPACTS)
    if run.n_impacts < SWITCH_RUN_IMPACTS:
        raise ValueError(f"the run from rest at the valve's switch point struck {run.n_impacts} times in "
                         f"{SWITCH_RUN_S:g} s")
    orbit = find_orbit(model, drive, guess=run)
    check_repeats(orbit, float(orbit.impact_times[0]))
    return orbit
