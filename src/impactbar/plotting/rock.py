"""Figures of a blow on the rod and the rock (theory §4d): the Lagrange (x-t) diagram of force in
piston and rod, and the bit's force-penetration loop."""

from __future__ import annotations

import numpy as np

from ._common import axes

__all__ = ["plot_force_penetration", "plot_lagrange"]


def plot_lagrange(blow, ax=None, cmap="RdBu_r", **kwargs):
    """The force in every cell of piston and rod against position and time (compression red).

    Parameters
    ----------
    blow : Blow
        Solved with ``record_field=True`` (:func:`impactbar.single_blow`).
    ax : matplotlib.axes.Axes, optional
    cmap : str
        Diverging colour map, centred on zero force.
    **kwargs
        Passed to ``pcolormesh``.

    Returns
    -------
    matplotlib.axes.Axes
        Position (piston lengths, the shank at 0) across, time (model units) up.
    """
    if blow.field is None:
        raise ValueError("blow.field is None: solve the blow with single_blow(..., record_field=True)")
    ax = axes(ax, figsize=(7, 4.5))
    top = float(np.max(np.abs(blow.field))) or 1.0
    mesh = ax.pcolormesh(blow.cell_edges, blow.times, blow.field, cmap=cmap, vmin=-top, vmax=top,
                         shading="flat", **kwargs)
    ax.figure.colorbar(mesh, ax=ax, label="force (compression > 0)")
    for x in blow.cell_edges[np.cumsum((blow.piston_cells,) + tuple(blow.segment_cells)) [:-1]]:
        ax.axvline(x, color="0.3", lw=0.6)
    ax.set_xlabel("position x (piston lengths; shank at 0)")
    ax.set_ylabel("time t")
    ax.set_title("Lagrange diagram of force")
    return ax


def plot_force_penetration(blow, ax=None, **kwargs):
    """The bit's force against the penetration: loading along ``k``, unloading along ``k_u``.

    Parameters
    ----------
    blow : Blow
    ax : matplotlib.axes.Axes, optional
    **kwargs
        Passed to ``plot``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes(ax)
    ax.plot(blow.penetrations, blow.bit_forces, **kwargs)
    ax.axvline(blow.permanent_penetration, color="0.5", ls=":", lw=0.8)
    ax.set_xlabel("penetration p")
    ax.set_ylabel("rock force R")
    ax.set_title(f"work on rock {blow.work_on_rock:.4g}, efficiency {blow.efficiency:.3f}")
    return ax
