"""What every drawing function shares: axes made on demand, matplotlib imported lazily."""

from __future__ import annotations


def axes(ax, figsize=(6, 3.6)):
    """``ax``, or the axes of a new figure of ``figsize`` inches when ``ax`` is None."""
    if ax is None:
        import matplotlib.pyplot as plt  # noqa: PLC0415

        _, ax = plt.subplots(figsize=figsize)
    return ax
