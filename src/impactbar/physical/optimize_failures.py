"""A design of the whole-drifter optimiser without an operating point
(:func:`~impactbar.physical.optimize_drifter`): its record, with why it has none and what the
evaluation cost.

A design without a one-impact orbit costs about what one with an orbit costs: Newton's method gives
up where its steps stall (:data:`~impactbar.drives.orbitproblem.STALL_STEPS`), so that the default
chain's starts fail in a few steps each rather than in their fifty.
"""

from __future__ import annotations

__all__ = ["ERROR_CHARS", "failed_record"]

#: The most characters of the error a failed design's record keeps (its first line): the default
#: chain's list of the starts it tried, each with why it failed.
ERROR_CHARS = 500


def failed_record(exc: BaseException, seconds: float) -> dict:
    """The record of a design without an operating point.

    Parameters
    ----------
    exc : BaseException
        Why it has none (the default chain's error, cavitation, a bad value).
    seconds : float
        The evaluation's wall time (s).

    Returns
    -------
    dict
        ``ok`` and ``feasible`` ``False``, ``error`` (the first line of the message, at most
        :data:`ERROR_CHARS` characters) and ``seconds``.

    Examples
    --------
    >>> from impactbar.physical.optimize_failures import failed_record
    >>> failed_record(ValueError("find_orbit: Newton stalled\\nmore"), 1.25)
    {'ok': False, 'error': 'find_orbit: Newton stalled', 'feasible': False, 'seconds': 1.25}
    """
    lines = str(exc).splitlines() or [type(exc).__name__]
    return {"ok": False, "error": lines[0][:ERROR_CHARS], "feasible": False, "seconds": float(seconds)}
