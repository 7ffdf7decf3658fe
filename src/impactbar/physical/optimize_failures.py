"""A design of the whole-drifter optimiser without an operating point
(:func:`~impactbar.physical.optimize_drifter`): its record, with why it has none, what the
evaluation cost and, where it has no one-impact orbit, what the drill does there instead: its motion
from rest classified as a design map's ``settle`` task classifies it
(:func:`~impactbar.physical.settle.settle_point`: blows per cycle, chatter), and whether a one-impact
orbit exists all the same, one the rest on the stop does not reach (a circuit drifter's, from rest
at the valve's switch point: :func:`switch_orbit`).

"No one-impact orbit" in a record says what the default chain of ``orbit()`` found from its one start,
rest on the stop, not that the drill has none: a design the restarted searches met (its front
annulus 0.39 mm^2) has none from there (the piston buzzes on the shank) and a stable one from the
switch point.

A design without a one-impact orbit costs about what one with an orbit costs: Newton's method gives
up where its steps stall (:data:`~impactbar.drives.orbitproblem.STALL_STEPS`), so that the default
chain's starts fail in a few steps each rather than in their fifty; and the search does not classify
its motion (:data:`MOTION_MOST_BLOWS` blows from rest, several times the orbit's attempt): after the
search the designs the result lists (:func:`failures_table`, the first :data:`FAILED_ROWS`) are
classified (:func:`classify_listed`), the others' records say they are not
(:data:`NOT_CLASSIFIED`), and :func:`classify_failed` classifies any of them on demand.
"""

from __future__ import annotations

import math

__all__ = ["ERROR_CHARS", "MOTION_BLOWS", "MOTION_MOST_BLOWS", "FAILED_ROWS", "NOT_CLASSIFIED",
           "failed_record", "classify_failed", "classify_listed", "listed_failures", "motion_summary",
           "switch_orbit", "switch_summary",
           "design_text", "failures_table"]

#: The most characters of the error a failed design's record keeps (its first line): the default
#: chain's list of the starts it tried, each with why it failed.
ERROR_CHARS = 500
#: The blows a design without a one-impact orbit is simulated from rest to classify its motion (the
#: ``settle`` task's default; some 5 s of CPU on the example rock drifter)
MOTION_BLOWS = 40
#: The most blows the classification runs to where it cannot tell in :data:`MOTION_BLOWS`: a design
#: beside the documented optimum rises with its supply pressure for some 80 blows, then alternates
MOTION_MOST_BLOWS = 160
#: The most designs without an operating point a result's table lists (the others counted; all in
#: its JSON's ``history``)
FAILED_ROWS = 5
#: The ``motion_summary`` of a design without a one-impact orbit whose motion the search did not
#: classify (it is not among the :data:`FAILED_ROWS` a result lists): :func:`classify_failed` does
NOT_CLASSIFIED = "not classified: not reported (classify_failed classifies it)"


def failed_record(exc: BaseException, seconds: float, drifter=None, *, classify: bool = True) -> dict:
    r"""The record of a design without an operating point.

    Parameters
    ----------
    exc : BaseException
        Why it has none (the default chain's error, cavitation, a bad value).
    seconds : float
        The evaluation's wall time (s).
    drifter : CircuitDrifter, optional
        The design: where given and the error is that there is no periodic orbit, its motion from
        rest is classified (:func:`classify_failed`), or with ``classify=False`` the record says it
        is not (:data:`NOT_CLASSIFIED`).
    classify : bool
        Whether to classify the motion here (``False``: the optimiser's search, which classifies
        after it only the designs its result lists, :func:`classify_listed`).

    Returns
    -------
    dict
        ``ok`` and ``feasible`` ``False``, ``error`` (the first line of the message, at most
        :data:`ERROR_CHARS` characters) and ``seconds``; with the classification ``motion``,
        ``motion_summary`` and ``motion_seconds`` (:func:`classify_failed`), without it
        ``motion_summary`` :data:`NOT_CLASSIFIED`.

    Examples
    --------
    >>> from impactbar.physical.optimize_failures import failed_record
    >>> failed_record(ValueError("find_orbit: Newton stalled\nmore"), 1.25)
    {'ok': False, 'error': 'find_orbit: Newton stalled', 'feasible': False, 'seconds': 1.25}
    """
    lines = str(exc).splitlines() or [type(exc).__name__]
    rec = {"ok": False, "error": lines[0][:ERROR_CHARS], "feasible": False, "seconds": float(seconds)}
    if drifter is None or not _without_orbit(rec):
        return rec
    if not classify:
        rec["motion_summary"] = NOT_CLASSIFIED
        return rec
    return classify_failed(rec, drifter)


def _without_orbit(record: dict) -> bool:
    """Whether a record is a design's without a one-impact orbit (the only ones classified)."""
    return not record.get("ok") and "no periodic orbit" in record.get("error", "")


def classify_failed(record: dict, drifter) -> dict:
    r"""What the drill does at a design without a one-impact orbit: its motion from rest over
    :data:`MOTION_BLOWS` blows, up to :data:`MOTION_MOST_BLOWS` where that cannot tell, classified
    as a design map's ``settle`` task classifies it (:func:`~impactbar.physical.settle.settle_point`;
    theory §11, "Optimising a drifter"), written into its record; for a circuit drifter also the
    one-impact orbit from rest at the valve's switch point, where one exists (:func:`switch_orbit`).

    Parameters
    ----------
    record : dict
        The design's record (:func:`failed_record`'s, e.g. one of an optimiser result's ``history``
        whose ``motion_summary`` is :data:`NOT_CLASSIFIED`); updated in place.
    drifter : CircuitDrifter
        The design (``build(with_values(config, record["changes"]), folder)``).

    Returns
    -------
    dict
        ``record``, with ``motion`` (the ``settle`` task's figures in SI, or ``{"error": ...}`` where
        the run is refused: the oil cavitates), ``motion_summary`` (:func:`motion_summary`) and
        ``motion_seconds`` (the classification's wall time, s); a circuit drifter's also
        ``switch_orbit`` (:func:`switch_orbit`), ``switch_summary`` (:func:`switch_summary`) and
        ``switch_seconds``.

    Raises
    ------
    ValueError
        ``record`` not a design's without a one-impact orbit (its error not "no periodic orbit").
    """
    import time

    from .settle import settle_point

    if not (isinstance(record, dict) and _without_orbit(record)):
        raise ValueError("record must be a design's without a one-impact orbit (ok false, its error "
                         "'... no periodic orbit ...')")
    t0 = time.perf_counter()
    try:
        motion = settle_point(drifter, MOTION_BLOWS, most_blows=MOTION_MOST_BLOWS)
    except ValueError as err:  # (the oil cavitates during the run)
        motion = {"error": str(err).splitlines()[0][:ERROR_CHARS]}
    record.update(motion=motion, motion_summary=motion_summary(motion),
                  motion_seconds=time.perf_counter() - t0)
    from .circuit import CircuitDrifter

    if isinstance(drifter, CircuitDrifter):  # (whether an orbit exists that rest does not reach)
        t0 = time.perf_counter()
        found = switch_orbit(drifter)
        record.update(switch_orbit=found, switch_summary=switch_summary(found),
                      switch_seconds=time.perf_counter() - t0)
    return record


def switch_orbit(drifter) -> dict:
    """A circuit drifter's one-impact orbit from the piston at rest at the valve's switch point
    (:func:`~impactbar.physical.circuit_switch.switch_start_orbit`, checked by a restart), where the
    default chain's start, rest on the stop, finds none: its figures in SI, or why there is none
    (theory §11, "Optimising a drifter").

    Parameters
    ----------
    drifter : CircuitDrifter
        The design (its default chain already failed).

    Returns
    -------
    dict
        The orbit's outputs as a design map stores them (the view ``"store"`` of
        :mod:`~impactbar.physical.outputs` the machine has, the rock's where it has a drill string),
        by key in their units: ``stable``, ``max_multiplier`` (the largest multiplier's modulus),
        ``period_s``, ``blow_frequency_Hz``, ``impact_velocity_m_s``, ``cavitates``,
        ``relief_opens``, ``relief_margin_Pa``, ...; or ``{"error": ...}`` (its first line, at most
        :data:`ERROR_CHARS` characters).
    """
    from .circuit import CircuitDrifterOrbit
    from .circuit_switch import switch_start_orbit
    from .outputs import output_values, outputs

    try:
        point = CircuitDrifterOrbit(drifter, switch_start_orbit(drifter))
    except ValueError as err:
        return {"error": str(err).splitlines()[0][:ERROR_CHARS]}
    stored = outputs("store", "circuit", rock=drifter.drill is not None)
    values = output_values(point, stored)
    return {o.key: bool(values[o.name]) if o.dtype == "b1" else float(values[o.name]) for o in stored}


def switch_summary(found: dict) -> str:
    """One line saying whether a one-impact orbit exists from rest at the switch point
    (:func:`switch_orbit`'s figures; theory §11, "Optimising a drifter").

    Parameters
    ----------
    found : dict
        :func:`switch_orbit`'s figures, or its ``{"error": ...}``.

    Returns
    -------
    str
        The orbit's stability (the largest multiplier's modulus), blow frequency, impact velocity and
        whether the relief valve opens or the oil cavitates; else the error's first clause.

    Examples
    --------
    >>> from impactbar.physical.optimize_failures import switch_summary
    >>> switch_summary({"stable": True, "max_multiplier": 0.575, "blow_frequency_Hz": 50.26,
    ...                 "impact_velocity_m_s": 8.918, "cavitates": False, "relief_opens": True})
    'from rest at the switch point: a stable one-impact orbit (|mu| 0.575), 50.3 Hz, 8.92 m/s, relief open'
    >>> switch_summary({"error": "the rear chamber empties"})
    'from rest at the switch point: no one-impact orbit either (the rear chamber empties)'
    """
    head = "from rest at the switch point:"
    if "error" in found:
        why, _, _ = found["error"].partition("; ")
        return f"{head} no one-impact orbit either ({why})"
    said = [f"{head} a{' stable' if found['stable'] else 'n unstable'} one-impact orbit "
            f"(|mu| {found['max_multiplier']:.3g})", f"{found['blow_frequency_Hz']:.3g} Hz",
            f"{found['impact_velocity_m_s']:.3g} m/s"]
    if found.get("relief_opens"):
        said.append("relief open")
    if found["cavitates"]:
        said.append("cavitating")
    return ", ".join(said)


def listed_failures(history: list, most: int = FAILED_ROWS) -> list:
    """The designs without an operating point a result's table lists (:func:`failures_table`): the
    first ``most`` of ``history``'s.

    Parameters
    ----------
    history : list of dict
        The designs' records in the order evaluated.
    most : int
        The most designs listed, at least 0.

    Returns
    -------
    list of dict
        The records, in their order.

    Raises
    ------
    ValueError
        ``most`` not an integer at least 0.

    Examples
    --------
    >>> listed_failures([{"ok": True}, {"ok": False, "id": "a"}, {"ok": False, "id": "b"}], 1)
    [{'ok': False, 'id': 'a'}]
    """
    if not (isinstance(most, int) and most >= 0):
        raise ValueError(f"most must be an integer at least 0; got {most!r}")
    return [r for r in history if not r.get("ok")][:most]


def classify_listed(history: list, drifter_of, most: int = FAILED_ROWS) -> int:
    r"""The motions of the designs without a one-impact orbit that a result lists
    (:func:`listed_failures`) classified where the search left them unclassified
    (:data:`NOT_CLASSIFIED`; :func:`classify_failed`, theory §11).

    Parameters
    ----------
    history : list of dict
        The designs' records in the order evaluated; those classified are updated in place.
    drifter_of : callable
        ``drifter_of(record)``: the design of a record (its ``changes`` built).
    most : int
        The most designs listed, at least 0.

    Returns
    -------
    int
        How many were classified.

    Raises
    ------
    ValueError
        ``most`` negative.
    """
    todo = [r for r in listed_failures(history, most) if r.get("motion_summary") == NOT_CLASSIFIED]
    for r in todo:
        classify_failed(r, drifter_of(r))
    return len(todo)


def motion_summary(motion: dict) -> str:
    """One line saying what a drill does from rest (:func:`~impactbar.physical.settle.settle_point`'s
    figures).

    Examples
    --------
    >>> from impactbar.physical.optimize_failures import motion_summary
    >>> motion_summary({"period_blows": 3, "chatter_per_blow": 0.0, "blow_frequency": 51.4,
    ...                 "impact_velocity": 9.07, "impact_velocity_spread": 0.0068, "n_blows": 160})
    'settles into a period-3 motion (3 blows per cycle, 0.075 % spread), no chatter, 51.4 Hz, 9.07 m/s'
    >>> motion_summary({"period_blows": 0, "chatter_per_blow": 1.5, "blow_frequency": 40.0,
    ...                 "impact_velocity": 7.0, "n_blows": 40})
    'not settled in 40 blows, 1.5 chatter impacts per blow, 40 Hz, 7 m/s'
    >>> motion_summary({"period_blows": 0, "n_blows": 2, "n_impacts": 160, "simulated_time": 0.531,
    ...                 "blow_frequency": float("nan")})
    'stalls: 2 blows from rest, then 158 chatter impacts to 0.531 s, under two blows in its second half'
    """
    if "error" in motion:
        return f"no motion from rest: {motion['error']}"
    if math.isnan(motion["blow_frequency"]):  # (fewer than two blows in the run's second half)
        n = motion["n_blows"]
        return (f"stalls: {n or 'no'} blow{'' if n == 1 else 's'} from rest, then {motion['n_impacts'] - n} "
                f"chatter impacts to {motion['simulated_time']:.3g} s, under two blows in its second half")
    m = motion["period_blows"]
    # (the spread of the cycle's impact velocities: their standard deviation over their mean)
    spread = (f", {100.0 * motion['impact_velocity_spread'] / motion['impact_velocity']:.2g} % spread"
              if m > 1 else "")
    head = (f"settles into a period-{m} motion ({m} blow{'s' if m > 1 else ''} per cycle{spread})" if m
            else f"not settled in {motion['n_blows']} blows")
    chatter = motion["chatter_per_blow"]
    said = "no chatter" if chatter == 0 else f"{chatter:.3g} chatter impacts per blow"
    return f"{head}, {said}, {motion['blow_frequency']:.3g} Hz, {motion['impact_velocity']:.3g} m/s"


def design_text(values: dict, vary: dict) -> str:
    """A design's values of the varied keys in their display units, on one line.

    Parameters
    ----------
    values : dict
        Dotted key to value (SI).
    vary : dict
        Dotted key to ``low``, ``high`` and ``unit`` (:attr:`DrifterOptimum.vary
        <impactbar.physical.optimize_drifter.DrifterOptimum>`).

    Returns
    -------
    str

    Examples
    --------
    >>> design_text({"x": 0.021}, {"x": {"low": 0.02, "high": 0.023, "unit": "m"}})
    'x 21 mm'
    """
    from .display_units import display_unit

    parts = []
    for k in vary:
        scale, unit = display_unit(vary[k]["unit"])
        parts.append(f"{k} {values[k] * scale:.5g}{' ' + unit if unit else ''}")
    return ", ".join(parts)


def failures_table(history: list, vary: dict, most: int = FAILED_ROWS) -> str:
    """The designs without an operating point among ``history``: how many, what their evaluations
    and their motions' classification cost (s, against a design with one on average), and, one line
    each (at most ``most``, the first), the design, why it has none (its error's first clause),
    what the drill does there from rest (:func:`motion_summary`) and whether a one-impact orbit
    exists from rest at the switch point (:func:`switch_summary`).

    Parameters
    ----------
    history : list of dict
        The designs' records (:func:`failed_record`'s where without an operating point).
    vary : dict
        As :func:`design_text` takes it.
    most : int
        The most designs listed, at least 0.

    Returns
    -------
    str
        Empty where every design has an operating point.

    Raises
    ------
    ValueError
        ``most`` negative.

    Examples
    --------
    >>> vary = {"x": {"low": 0.02, "high": 0.023, "unit": "m"}}
    >>> rec = dict(failed_record(ValueError("find_orbit found no periodic orbit; tried this"), 0.5),
    ...            values={"x": 0.021}, motion_summary="settles into a period-2 motion", motion_seconds=1.0)
    >>> print(failures_table([{"ok": True, "seconds": 0.25}, rec], vary))
    1 of 2 designs without an operating point (0.5 s + 1 s classifying their motion; 0.25 s one with):
      x 21 mm: find_orbit found no periodic orbit; settles into a period-2 motion
    """
    listed = listed_failures(history, most)
    failed = [r for r in history if not r.get("ok")]
    if not failed:
        return ""
    ok = [r["seconds"] for r in history if r.get("ok") and "seconds" in r]
    cost = sum(r.get("seconds", 0.0) for r in failed)
    motion = sum(r.get("motion_seconds", 0.0) + r.get("switch_seconds", 0.0) for r in failed)
    against = f"; {sum(ok) / len(ok):.3g} s one with" if ok else ""
    rows = [f"{len(failed)} of {len(history)} designs without an operating point ({cost:.3g} s + "
            f"{motion:.3g} s classifying their motion{against}):"]
    for r in listed:
        why, _, _ = r["error"].partition("; ")
        said = "".join(f"; {r[k]}" for k in ("motion_summary", "switch_summary") if k in r)
        rows.append(f"  {design_text(r['values'], vary) if 'values' in r else 'a design'}: {why}{said}")
    if len(failed) > most:
        rows.append(f"  and {len(failed) - most} more (the JSON result's history)")
    return "\n".join(rows)
