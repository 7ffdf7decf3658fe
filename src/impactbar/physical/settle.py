"""The motion of a machine from rest, classified: the ``settle`` task of a design map
(:mod:`impactbar.sweeps.map_spec`) at each point, and what the whole-drifter optimiser records of a
design without a one-impact orbit (:mod:`~impactbar.physical.optimize_failures`)."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["SETTLE_FIRST_HZ", "SETTLE_GROWTH", "SETTLE_RUNS", "SETTLE_LONGEST", "SETTLE_IMPACTS_PER_BLOW",
           "settle_run", "settle_point"]

#: a settle's first run lasts its blows at this blow frequency (Hz); a run holding fewer blows is
#: followed by a longer one, from rest again
SETTLE_FIRST_HZ = 40.0
#: a settle not settled in its blows and allowed more (``most_blows``) runs again from rest with this
#: many times more
SETTLE_GROWTH = 4
#: most runs a settle makes before it classifies what the last one holds
SETTLE_RUNS = 8
#: the longest run, in units of the first: its blows at a sixteenth of :data:`SETTLE_FIRST_HZ` (2.5 Hz),
#: below any percussive machine's rate. A machine with fewer blows by then is classified by what that
#: run holds (without the bound, a design whose piston never struck ran 4 times longer each time: a
#: drifter's 40 blows, 4096 s of its circuit in the seventh run)
SETTLE_LONGEST = 16.0
#: the most impacts a circuit drifter's run holds per blow wanted: the run ends at the last of them
#: (:func:`impactbar.simulate`'s ``max_impacts``) and is classified by what it holds, a motion with
#: more than ``SETTLE_IMPACTS_PER_BLOW - 1`` chatter impacts a blow. Each impact of a drifter on the
#: rock is a coupled contact (some 40 ms of CPU, chatter as dear as a blow); without the bound, a
#: design whose piston, after two blows, buzzes on the shank (700 impacts a second at 8 mm/s: a
#: front annulus of 0.4 mm^2) ran 16 s of it, then runs of up to 64 s for 160 blows: more than 16
#: minutes; bounded, 160 impacts, some 5 s
SETTLE_IMPACTS_PER_BLOW = 4


def _most_impacts(machine, blows: int) -> int | None:
    """The most impacts a run of ``machine`` for ``blows`` blows holds (:data:`SETTLE_IMPACTS_PER_BLOW`
    a blow for a circuit drifter; ``None``, no bound, for a valve drifter: its flights closed forms)."""
    from .circuit import CircuitDrifter

    return SETTLE_IMPACTS_PER_BLOW * blows if isinstance(machine, CircuitDrifter) else None


def _impacts(machine, duration_s: float, most: int | None):
    """The impact times (s) and velocities (m/s) of ``machine.simulate(duration_s)`` from rest (a
    circuit drifter's up to its ``most``-th impact)."""
    from .circuit import CircuitDrifter

    if isinstance(machine, CircuitDrifter):  # (the impacts alone: each blow summarised)
        run = machine.simulate(duration_s, histories=False, max_impacts=most)
        return np.asarray(run["impact_times_s"], float), np.asarray(run["impact_velocities_m_s"], float)
    tr, _ = machine.simulate(duration_s)
    om, length = machine.omega_rad_s, machine.bar.length_m
    return np.asarray(tr.impact_times, float) / om, np.asarray(tr.impact_velocities, float) * length * om


def settle_run(machine, blows: int, blow_fraction: float = 0.25, *, rate_hz: float = SETTLE_FIRST_HZ):
    """The impacts of the machine from rest up to its ``blows``-th blow.

    The first run lasts ``blows / rate_hz`` seconds; where it holds fewer blows (impacts at
    least ``blow_fraction`` of its hardest) a longer one follows, from rest again, up to
    :data:`SETTLE_RUNS` runs and at most :data:`SETTLE_LONGEST` times the first. A circuit drifter's
    run ends at its ``SETTLE_IMPACTS_PER_BLOW * blows``-th impact: where it holds fewer blows by then
    it is the last (another from rest would repeat it). The impacts after the ``blows``-th blow are
    dropped.

    Parameters
    ----------
    machine : Drifter or CircuitDrifter
    blows : int
        Blows wanted, at least 1.
    blow_fraction : float
        Threshold between blows and chatter (:meth:`impactbar.physical.SimulationResult.is_blow`).
    rate_hz : float
        The blow frequency (Hz) the first run's length assumes, above 0: default
        :data:`SETTLE_FIRST_HZ`; a shorter run's rate where a longer one follows it.

    Returns
    -------
    times_s, velocities_m_s : numpy.ndarray
        The impacts kept (s, m/s).
    t_end_s : float
        The ``blows``-th blow's time, or where no run held that many the last run's duration, or its
        last impact's time where it ended at its impacts' bound.

    Raises
    ------
    ValueError
        Where the machine's ``simulate`` refuses (a circuit's oil cavitates during the run), or
        ``rate_hz`` is not above 0.
    """
    if not rate_hz > 0.0:
        raise ValueError(f"rate_hz must be above 0 Hz; got {rate_hz!r}")
    ran, duration = 0.0, blows / rate_hz
    longest, most = SETTLE_LONGEST * duration, _most_impacts(machine, blows)
    for _ in range(SETTLE_RUNS):
        t, v = _impacts(machine, duration, most)
        ran = duration
        top = float(np.max(v)) if v.size else 0.0
        where = np.flatnonzero(v >= blow_fraction * top) if top > 0 else np.zeros(0, int)
        if where.size >= blows:
            end = float(t[where[blows - 1]])
            keep = t <= end
            return t[keep], v[keep], end
        if most is not None and t.size >= most:  # (at its impacts' bound: a longer run repeats it)
            return t, v, float(np.max(t))  # (its last impact)
        # long enough for the blows at the rate seen and a tenth more, at most the longest run
        grown = min(duration * (max(1.1, 1.1 * blows / where.size) if where.size else 4.0), longest)
        if grown <= duration:  # (the longest run done: another from rest would repeat it)
            break
        duration = grown
    return t, v, ran


def settle_point(machine, blows: int, blow_fraction: float = 0.25, settle_tolerance: float = 0.01, *,
                 most_blows: int | None = None) -> dict:
    r"""The motion of a machine from rest over ``blows`` blows (:func:`settle_run`), classified by
    :meth:`impactbar.physical.SimulationResult.blow_statistics`.

    Settled into a cycle of ``m`` blows, the figures are over its last cycle: the ``m`` last blows
    and the ``m`` intervals before them; not settled, over the blows of the run's second half.
    ``blow_frequency`` is the number of intervals over their sum (for ``m = 1`` the inverse period),
    its spread the standard deviation of the inverse intervals; ``chatter_per_blow`` counts the
    chatter impacts between those blows per interval.

    Parameters
    ----------
    machine : Drifter or CircuitDrifter
    blows : int
        Blows simulated from rest, at least 8.
    blow_fraction, settle_tolerance : float
        As :meth:`~impactbar.physical.SimulationResult.blow_statistics` takes them.
    most_blows : int, optional
        Where the motion has not settled in ``blows``, runs from rest of :data:`SETTLE_GROWTH`
        times more blows follow, up to ``most_blows`` (at least ``blows``): the classification run
        until it can tell (a drifter's blows rising with its supply pressure for some 80 blows
        before they alternate); not after a run that ended at its impacts' bound
        (:data:`SETTLE_IMPACTS_PER_BLOW`) with fewer blows than wanted: more blows wanted would buy
        more of its chatter. Default ``blows``: one run.

    Returns
    -------
    dict
        The ``settle`` task's variables in SI (:func:`impactbar.sweeps.map_spec.map_variables`,
        without ``status`` and ``failure``).

    Raises
    ------
    ValueError
        Where the machine's ``simulate`` refuses, or ``most_blows`` is below ``blows``.

    Examples
    --------
    >>> from impactbar.physical.loader import build, read_config
    >>> from impactbar.physical.settle import settle_point
    >>> s = settle_point(build(read_config("hydraulic-drifter")[0]), 20)
    >>> s["period_blows"], s["settled"], round(s["blow_frequency"], 2)
    (1, True, 47.19)
    """
    from .results import SimulationResult

    most = blows if most_blows is None else most_blows
    if not (isinstance(most, int) and most >= blows):
        raise ValueError(f"most_blows must be an integer at least blows ({blows}); got {most_blows!r}")
    rate = SETTLE_FIRST_HZ
    while True:
        t, v, end = settle_run(machine, blows, blow_fraction, rate_hz=rate)
        res = SimulationResult(hammer=None, trajectory=None, t_end_s=end, impact_times_s=t,
                               impact_velocities_m_s=v, impact_energies_J=0.5 * machine.bar.mass_kg * v * v)
        stats = res.blow_statistics(blow_fraction=blow_fraction, settle_tolerance=settle_tolerance)
        bound = _most_impacts(machine, blows)
        bounded = stats.n_blows < blows and bound is not None and t.size >= bound
        if stats.settled or blows >= most or bounded:
            break
        # (the next run's length at the rate seen: the blows come faster as a supply charges)
        rate = max(rate, stats.n_blows / end) if end > 0.0 else rate
        blows = min(SETTLE_GROWTH * blows, most)
    blow = res.is_blow(blow_fraction)
    idx = np.flatnonzero(blow & (t >= 0.5 * end))  # the second half's blows (as blow_statistics has them)
    m = stats.blows_per_cycle
    k = m if m else idx.size - 1  # intervals looked at
    out = {"period_blows": m, "settled": m > 0, "n_blows": stats.n_blows, "n_impacts": stats.n_impacts,
           "simulated_time": end}
    if k >= 1:
        last = idx[-k - 1:]
        dt = np.diff(t[last])
        vb = v[last[1:]]
        out.update(chatter_per_blow=float(last[-1] - last[0] - k) / k,
                   impact_velocity=float(np.mean(vb)), impact_velocity_spread=float(np.std(vb)),
                   blow_frequency=k / float(np.sum(dt)), blow_frequency_spread=float(np.std(1.0 / dt)))
    else:
        out.update(chatter_per_blow=math.nan, impact_velocity=math.nan, impact_velocity_spread=math.nan,
                   blow_frequency=math.nan, blow_frequency_spread=math.nan)
    return out
