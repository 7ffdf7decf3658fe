"""Continuation results: branches (stable solid, unstable dashed, events marked) and bifurcation curves."""

from __future__ import annotations

import numpy as np

from ._common import axes as _axes

__all__ = ["plot_branch", "plot_bifurcation_curve", "plot_bifurcation_curves", "plot_bifurcation_diagram"]


def plot_branch(branch, ax=None, *, y: str = "phase", color=None, label=None, events=True):
    """Plot a continuation branch (:class:`~impactbar.continuation.Branch`): stable stretches solid,
    unstable or inadmissible dashed, events marked.

    Parameters
    ----------
    branch : Branch
    ax : matplotlib.axes.Axes, optional
        Drawn on a new figure's axes if omitted.
    y : str
        What to plot against the parameter: a number of the orbits' tables along a branch (the
        fields of :data:`impactbar.orbits.orbit.ORBIT_FIELDS` in the view ``"branch"``:
        ``"phase"``, ``"impact_velocity"``, ``"impact_time"``, ``"clearance"``,
        ``"max_abs_multiplier"``); per-impact quantities give one curve per impact (phases
        unwrapped along the branch, so a curve does not jump at ``2 pi``). The default, the phase,
        separates the two sides of a fold and a branch that returns; the impact velocity does not
        on one-impact orbits (``2 pi p0/(1 + R)`` on each, theory §4).
    color, label : optional
        Line colour and legend label.
    events : bool
        Mark and name the events.

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib.pyplot as plt

    fields = branch.point_fields
    f = _ordinate(fields, y)
    if ax is None:
        _, ax = plt.subplots()
    x = branch.values
    Y = fields.stack(branch.orbits, f.name).reshape(len(x), -1)
    if f.units == "rad":
        Y = np.unwrap(Y, axis=0)
    stable = branch.stable
    color = color or ax._get_lines.get_next_color()
    first = True
    for j in range(Y.shape[1]):
        start = 0
        for i in range(1, len(x) + 1):
            if i == len(x) or stable[i] != stable[start]:
                sl = slice(start, min(i + 1, len(x)))
                ax.plot(x[sl], Y[sl, j], color=color, ls="-" if stable[start] else "--",
                        label=label if first else None)
                first = False
                start = i
    if events:
        marks = {"fold": "o", "branch-point": "s", "period-doubling": "D", "neimark-sacker": "^",
                 "grazing": "x", "admissibility": "+"}
        for e in branch.events:
            yy = np.atleast_1d(f.get(e.orbit))
            ax.plot([e.value] * len(yy), yy, ls="none", marker=marks.get(e.kind, "*"), color="k",
                    mfc="none")
            ax.annotate(e.kind.replace("period-doubling", "PD").replace("neimark-sacker", "NS"),
                        (e.value, yy[0]), textcoords="offset points", xytext=(4, 4), fontsize=7)
    ax.set_xlabel(branch.parameter)
    ax.set_ylabel(f.item.replace("_", " ") + (f" ({f.units})" if f.units not in ("", "1") else ""))
    return ax


def _ordinate(fields, y: str):
    """The orbit's field plotted as ``y`` along a branch (by its name, or the name of one value),
    of the branch's ``fields`` (:attr:`~impactbar.continuation.Branch.point_fields`)."""
    numbers = [f for f in fields if f.dtype == "f8"]
    for f in numbers:
        if y == f.item:
            return f
    raise ValueError(f"y must be one of {[f.item for f in numbers]}; got {y!r}")


def plot_bifurcation_curve(curve, ax=None, *, swap: bool = False, **kwargs):
    """Draw a two-parameter :class:`~impactbar.continuation.BifurcationCurve`, second parameter on
    the abscissa (``swap`` to exchange the axes).

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots()
    i, j = (0, 1) if swap else (1, 0)
    kwargs.setdefault("label", curve.kind)
    ax.plot(curve.values[:, i], curve.values[:, j], **kwargs)
    ax.set_xlabel(curve.parameters[i])
    ax.set_ylabel(curve.parameters[j])
    return ax


#: line style of each kind of two-parameter curve
CURVE_STYLES = {"fold": "-", "period-doubling": "--", "grazing": ":"}


def plot_bifurcation_curves(curves, ax=None):
    """Several two-parameter curves on one axes, a line style per kind (fold solid, period doubling
    dashed, grazing dotted), each labelled with its kind and its motion's impacts per periods.

    Parameters
    ----------
    curves : sequence of BifurcationCurve
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax, figsize=(6, 4.5))
    for c in curves:
        plot_bifurcation_curve(c, ax, ls=CURVE_STYLES.get(c.kind, "-."),
                               label=f"{c.kind} ({c.orbits[0].impacts} per {c.orbits[0].periods})")
    ax.legend(fontsize=8)
    return ax


def plot_bifurcation_diagram(branches, diagram=None, ax=None, *, y: str = "phase"):
    """Continued branches over a brute-force bifurcation diagram (grey dots, e.g. from
    :func:`impactbar.continuation.diagram.simulated_diagram`): stable solid, unstable dashed,
    events marked.

    Parameters
    ----------
    branches : sequence of Branch
        All continued in the same parameter.
    diagram : mapping, optional
        ``diagram["parameter"]`` and ``diagram[y]``, arrays of equal shape ``(n,)``.
    ax : matplotlib.axes.Axes, optional
    y : str
        The branches' ordinate (see :func:`plot_branch`; the phase, the default, separates the two
        sides of a fold).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax, figsize=(7, 4.5))
    if diagram is not None and np.size(diagram["parameter"]):
        ax.plot(diagram["parameter"], diagram[y], ".", ms=2, color="0.55", ls="none", zorder=0,
                label="simulation (brute force)")
    for b in branches:
        plot_branch(b, ax, y=y, label=f"{b.impacts} per {b.periods}")
    ax.legend(fontsize=8)
    if branches:
        ax.set_title(f"continuation in {branches[0].parameter}: stable solid, unstable dashed", fontsize=9)
    return ax
