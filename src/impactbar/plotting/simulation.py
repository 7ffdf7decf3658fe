"""Simulations and the random-start experiments: end displacement, impact map, intervals."""

from __future__ import annotations

import numpy as np

from ._common import axes as _axes

__all__ = ["plot_trajectory", "plot_end_displacement", "plot_impact_map", "plot_intervals", "plot_experiment",
           "INTERVAL_RESOLUTION"]


def plot_trajectory(trajectory, ax=None, n: int = 4000):
    """The struck end's displacement ``u(1, t)`` over a :class:`~impactbar.Trajectory` of
    :func:`~impactbar.simulate`, the stop at ``u = 0`` and every impact marked.

    Parameters
    ----------
    trajectory : Trajectory
    ax : matplotlib.axes.Axes, optional
    n : int
        Time samples drawn (for drawing only: the impacts are the simulator's, refined to rounding).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax, figsize=(8, 3.6))
    t = np.linspace(trajectory.t0, trajectory.t_end, n)
    ax.plot(t, trajectory.end_displacement(t), lw=0.8, label="u(1, t)")
    ax.axhline(0.0, color="k", lw=1.5, label="stop")
    ti = np.asarray(trajectory.impact_times)
    if ti.size:
        ax.plot(ti, np.zeros_like(ti), "|", color="tab:red", ms=8, label=f"{ti.size} impacts")
    ax.set_xlabel("time t")
    ax.set_ylabel("end displacement u(1, t)")
    ax.legend(fontsize=8, loc="lower right")
    return ax


#: impact intervals closer than this (load periods) are one value: the tolerance to which
#: ``classify`` calls a motion periodic; a periodic motion's intervals differ by less (by about
#: 1e-12 once settled: the simulator refines impact times to rounding)
INTERVAL_RESOLUTION = 1e-4


def plot_end_displacement(result, axes=None, *, periods: float = 20.0):
    """The struck end's displacement ``u(1, t)`` over the last ``periods`` load periods of each
    run an :class:`~impactbar.simulation.experiments.ExperimentResult` kept.

    Parameters
    ----------
    result : ExperimentResult
    axes : sequence of matplotlib.axes.Axes, optional
        One per kept run; created when not given.
    periods : float, optional
        Load periods shown, at the end of each run. Default 20.

    Returns
    -------
    sequence of matplotlib.axes.Axes
    """
    T = result.load_period
    if axes is None:
        import matplotlib.pyplot as plt

        rows = max(1, len(result.trajectories))
        fig, grid = plt.subplots(rows, 1, figsize=(9, 1.9 * rows + 0.6), squeeze=False, sharex=False,
                                 layout="constrained")
        axes = list(grid[:, 0])
        fig.suptitle("end displacement of the first runs (last load periods)")
    for i, (ax, tr) in enumerate(zip(axes, result.trajectories, strict=False)):
        t1 = tr.t_end
        t0 = max(tr.t0, t1 - periods * T)
        t = np.linspace(t0, t1, 4000)
        ax.plot(t / T, tr.end_displacement(t), lw=0.8)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_ylabel("u(1, t)")
        ax.text(0.01, 0.05, f"run {i}: {result.classes[i].kind}", transform=ax.transAxes, fontsize=8.5)
    if len(axes):
        axes[-1].set_xlabel("t / load period")
    return axes


def plot_impact_map(result, ax=None):
    """The impact map of an experiment: each main impact's velocity ``v(i+1)`` against the previous
    one's ``v(i)``, over the classified windows of every run.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    pairs = result.impact_pairs
    if pairs.size:
        ax.plot(*pairs.T, ".", ms=3)  # (the velocity before an impact, the next one)
        lim = float(np.max(pairs)) * 1.05
        ax.plot([0, lim], [0, lim], "k:", lw=0.6, label="v(i+1) = v(i)")
        ax.legend(loc="upper left", fontsize=8.5)
    else:
        ax.text(0.5, 0.5, "no main impacts in the windows", ha="center", transform=ax.transAxes)
    ax.set_xlabel("impact velocity v(i)")
    ax.set_ylabel("next impact velocity v(i+1)")
    ax.set_title("impact map (main impacts, classified windows)", fontsize=9.5)
    return ax


def plot_intervals(result, ax=None):
    """The distribution of the intervals between main impacts of an experiment, in load periods.

    Intervals equal to within :data:`INTERVAL_RESOLUTION` are one value, so an exactly periodic
    motion shows as one bar at its period, not as a histogram of rounding noise.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    iv = np.asarray(result.intervals, dtype=float)
    if iv.size == 0:
        ax.text(0.5, 0.5, "no main impacts in the windows", ha="center", transform=ax.transAxes)
        ax.set_title("impact intervals", fontsize=9.5)
        return ax
    q = np.round(iv / INTERVAL_RESOLUTION) * INTERVAL_RESOLUTION
    values, counts = np.unique(q, return_counts=True)
    if values.size <= 12:  # a few distinct intervals: one bar each, no binning
        width = 0.02 * max(float(np.ptp(values)), 0.5)
        ax.bar(values, counts, width=width)
        for v, c in zip(values, counts, strict=True):
            ax.annotate(f"{v:.6g}", (v, c), ha="center", va="bottom", fontsize=8.5,
                        xytext=(0, 2), textcoords="offset points")
        ax.set_xlim(values.min() - 0.5, values.max() + 0.5)
    else:
        ax.hist(q, bins=min(80, max(10, int(np.sqrt(q.size)))))
    ax.ticklabel_format(axis="x", useOffset=False)
    ax.set_xlabel(f"interval between main impacts / load period (to {INTERVAL_RESOLUTION:g})")
    ax.set_ylabel("count")
    spread = 100 * result.interval_std / result.interval_mean if result.interval_mean else np.nan
    ax.set_title(f"mean {result.interval_mean:.4f}, std {result.interval_std:.4f} ({spread:.1f} %)",
                 fontsize=9.5)
    return ax


def plot_experiment(result, directory, *, prefix: str = "") -> list:
    """Write three PNG figures of an :class:`~impactbar.simulation.experiments.ExperimentResult`
    into ``directory``: :func:`plot_end_displacement` (the kept runs), :func:`plot_impact_map` and
    :func:`plot_intervals`.

    Returns
    -------
    list of pathlib.Path
        The files written: ``end_displacement.png``, ``impact_map.png``,
        ``interval_histogram.png`` (with ``prefix``).
    """
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    files = []
    axes = plot_end_displacement(result)
    files.append(out / f"{prefix}end_displacement.png")
    axes[0].figure.savefig(files[-1], dpi=120)
    plt.close(axes[0].figure)
    for name, draw in (("impact_map", plot_impact_map), ("interval_histogram", plot_intervals)):
        fig, ax = plt.subplots(figsize=(5.5, 4.5), layout="constrained")
        draw(result, ax)
        files.append(out / f"{prefix}{name}.png")
        fig.savefig(files[-1], dpi=120)
        plt.close(fig)
    return files
