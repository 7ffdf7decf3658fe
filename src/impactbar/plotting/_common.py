"""What every drawing function shares: axes made on demand, matplotlib imported lazily."""

from __future__ import annotations


def axes(ax, figsize=(6, 3.6)):
    """``ax``, or the axes of a new figure of ``figsize`` inches when ``ax`` is None."""
    if ax is None:
        import matplotlib.pyplot as plt  # noqa: PLC0415

        _, ax = plt.subplots(figsize=figsize)
    return ax


def label_contours(ax, contours, unit: str = ""):
    """Label contour lines so that a reader can tell them apart: the format's decimals chosen from
    the levels' spacing (no two labels read the same), labels upright, and none cut by the axes' frame.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes the lines are drawn on.
    contours : matplotlib.contour.ContourSet
        The lines (``ax.contour(...)``).
    unit : str
        Written after each number (``"Hz"``); none when empty.

    Returns
    -------
    list of matplotlib.text.Text
        The labels kept.
    """
    import numpy as np

    levels = np.asarray(contours.levels, dtype=float)
    steps = np.diff(levels)
    step = float(np.min(np.abs(steps[steps != 0]))) if np.any(steps != 0) else 1.0
    decimals = max(0, -int(np.floor(np.log10(step))))
    while len({f"{v:.{decimals}f}" for v in levels}) < len(levels) and decimals < 12:
        decimals += 1
    suffix = f" {unit}" if unit else ""
    texts = ax.clabel(contours, fmt=lambda v: f"{v:.{decimals}f}{suffix}", inline=True, rightside_up=True)
    renderer = ax.figure.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    for t in list(texts):
        box = t.get_window_extent(renderer)
        if not (frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1):
            t.remove()  # a label the frame would cut
            texts.remove(t)
    return texts
