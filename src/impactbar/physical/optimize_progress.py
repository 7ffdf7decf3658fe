"""The optimiser's progress (:func:`~impactbar.physical.optimize_drifter`): a tqdm bar of the designs a
run evaluates, on stderr and only where stderr is a terminal (a redirected log gets no bar lines),
its postfix the last design's seconds and the slowest design's, so that a design that takes many
times the others shows while it is the run's cost."""

from __future__ import annotations

import sys

__all__ = ["DesignProgress"]


class DesignProgress:
    """A bar counting the designs evaluated.

    Parameters
    ----------
    total : int or None
        The most designs the search can evaluate (``None`` where its budget bounds something else,
        SLSQP's iterations); at the end of a finished run the total becomes the count.
    enabled : bool
        ``False``: no bar. ``True``: a bar where stderr is a terminal (tqdm's ``disable=None``).

    Attributes
    ----------
    count : int
        Designs counted (whether or not a bar shows).
    slowest : tuple of (float, int)
        The slowest design's seconds and its number (from 1), ``(0.0, 0)`` before any.

    Examples
    --------
    >>> from impactbar.physical.optimize_progress import DesignProgress
    >>> p = DesignProgress(3, enabled=False)
    >>> p.design(1.5); p.design(29.0)
    >>> p.count, p.slowest, p.postfix()
    (2, (29.0, 2), 'last 29.0 s, slowest 29.0 s (design 2)')
    >>> p.finish(); p.close()
    """

    def __init__(self, total: int | None, enabled: bool) -> None:
        from tqdm import tqdm

        self.count = 0
        self.last = 0.0
        self.slowest = (0.0, 0)
        self.bar = tqdm(total=total, desc="optimize_drifter", unit="design", file=sys.stderr,
                        disable=None if enabled else True)

    def postfix(self) -> str:
        """The bar's postfix: the last design's seconds and the slowest one's."""
        seconds, design = self.slowest
        return f"last {self.last:.1f} s, slowest {seconds:.1f} s (design {design})"

    def design(self, seconds: float) -> None:
        """Count a design that took ``seconds``."""
        self.count += 1
        self.last = float(seconds)
        slowest_s, _ = self.slowest
        if seconds > slowest_s:
            self.slowest = (float(seconds), self.count)
        self.bar.set_postfix_str(self.postfix(), refresh=False)
        self.bar.update(1)

    def finish(self) -> None:
        """The run finished: the total becomes the count (a search that stops before its budget)."""
        if not self.bar.disable:
            self.bar.total = self.bar.n
            self.bar.refresh()

    def close(self) -> None:
        self.bar.close()
