"""A design of the whole-drifter optimiser without an operating point
(:func:`~impactbar.physical.optimize_drifter`): its record, with why it has none, what the
evaluation cost and, where it has no one-impact orbit, what the drill does there instead: its motion
from rest classified as a design map's ``settle`` task classifies it
(:func:`~impactbar.physical.settle.settle_point`: blows per cycle, chatter).

A design without a one-impact orbit costs about what one with an orbit costs: Newton's method gives
up where its steps stall (:data:`~impactbar.drives.orbitproblem.STALL_STEPS`), so that the default
chain's starts fail in a few steps each rather than in their fifty.
"""

from __future__ import annotations

__all__ = ["ERROR_CHARS", "MOTION_BLOWS", "failed_record", "motion_summary"]

#: The most characters of the error a failed design's record keeps (its first line): the default
#: chain's list of the starts it tried, each with why it failed.
ERROR_CHARS = 500
#: The blows a design without a one-impact orbit is simulated from rest to classify its motion (the
#: ``settle`` task's default; some 5 s of CPU on the example rock drifter)
MOTION_BLOWS = 40


def failed_record(exc: BaseException, seconds: float, drifter=None) -> dict:
    r"""The record of a design without an operating point.

    Parameters
    ----------
    exc : BaseException
        Why it has none (the default chain's error, cavitation, a bad value).
    seconds : float
        The evaluation's wall time (s).
    drifter : CircuitDrifter, optional
        The design: where given and the error is that there is no periodic orbit, its motion from
        rest is classified (:data:`MOTION_BLOWS` blows, :func:`~impactbar.physical.settle.settle_point`).

    Returns
    -------
    dict
        ``ok`` and ``feasible`` ``False``, ``error`` (the first line of the message, at most
        :data:`ERROR_CHARS` characters) and ``seconds``; with the classification ``motion`` (the
        ``settle`` task's figures in SI, or ``{"error": ...}`` where the run is refused),
        ``motion_summary`` (:func:`motion_summary`) and ``motion_seconds`` (its cost, s).

    Examples
    --------
    >>> from impactbar.physical.optimize_failures import failed_record
    >>> failed_record(ValueError("find_orbit: Newton stalled\nmore"), 1.25)
    {'ok': False, 'error': 'find_orbit: Newton stalled', 'feasible': False, 'seconds': 1.25}
    """
    import time

    lines = str(exc).splitlines() or [type(exc).__name__]
    rec = {"ok": False, "error": lines[0][:ERROR_CHARS], "feasible": False, "seconds": float(seconds)}
    if drifter is None or "no periodic orbit" not in rec["error"]:
        return rec
    from .settle import settle_point

    t0 = time.perf_counter()
    try:
        motion = settle_point(drifter, MOTION_BLOWS)
    except ValueError as err:  # (the oil cavitates during the run)
        motion = {"error": str(err).splitlines()[0][:ERROR_CHARS]}
    rec.update(motion=motion, motion_summary=motion_summary(motion), motion_seconds=time.perf_counter() - t0)
    return rec


def motion_summary(motion: dict) -> str:
    """One line saying what a drill does from rest (:func:`~impactbar.physical.settle.settle_point`'s
    figures).

    Examples
    --------
    >>> from impactbar.physical.optimize_failures import motion_summary
    >>> motion_summary({"period_blows": 3, "chatter_per_blow": 0.0, "blow_frequency": 51.4,
    ...                 "impact_velocity": 9.07, "n_blows": 40})
    'settles into a period-3 motion (3 blows per cycle), no chatter, 51.4 Hz, 9.07 m/s'
    >>> motion_summary({"period_blows": 0, "chatter_per_blow": 1.5, "blow_frequency": 40.0,
    ...                 "impact_velocity": 7.0, "n_blows": 40})
    'not settled in 40 blows, 1.5 chatter impacts per blow, 40 Hz, 7 m/s'
    """
    if "error" in motion:
        return f"no motion from rest: {motion['error']}"
    m = motion["period_blows"]
    head = (f"settles into a period-{m} motion ({m} blow{'s' if m > 1 else ''} per cycle)" if m
            else f"not settled in {motion['n_blows']} blows")
    chatter = motion["chatter_per_blow"]
    said = "no chatter" if chatter == 0 else f"{chatter:.3g} chatter impacts per blow"
    return f"{head}, {said}, {motion['blow_frequency']:.3g} Hz, {motion['impact_velocity']:.3g} m/s"
