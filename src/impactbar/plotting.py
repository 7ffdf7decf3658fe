"""Plots of computed results (matplotlib imported lazily; every function takes an optional ``ax``)."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["plot_orbit", "plot_orbit_field", "plot_multipliers", "plot_experiment",
           "plot_end_displacement", "plot_impact_map", "plot_intervals"]

TWO_PI = 2.0 * math.pi


def _axes(ax):
    if ax is None:
        import matplotlib.pyplot as plt  # noqa: PLC0415

        _, ax = plt.subplots(figsize=(6, 3.6))
    return ax


def plot_orbit(orbit, ax=None, n: int = 2000):
    """End displacement ``u(1, t)`` over one period of a one-impact orbit (the stop at ``u = 0``).

    Parameters
    ----------
    orbit : PeriodicOrbit
    ax : matplotlib.axes.Axes, optional
    n : int
        Number of time samples (for drawing only; admissibility is decided rigorously elsewhere).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    t = np.linspace(0.0, TWO_PI, n)
    q, _ = orbit._state_in_period(t)
    u = orbit.model.end_weights @ q
    ax.axhline(0.0, color="k", lw=2, label="stop")
    ax.plot(t, u, color="tab:blue" if orbit.admissible else "tab:red",
            label=f"u(1, t), {orbit.admissibility}")
    ax.fill_between(t, u, 0, where=u > 0, color="tab:red", alpha=0.3)
    ax.set_xlabel("time since impact t")
    ax.set_ylabel("end displacement u(1, t)")
    ax.set_title(f"phase {orbit.phase:.4f}, impact velocity {orbit.impact_velocity:.4f}, "
                 f"max|mu| {orbit.max_abs_multiplier:.3f}", fontsize=9)
    ax.legend(fontsize=8)
    return ax


def plot_orbit_field(orbit, ax=None, nx: int = 101, nt: int = 400):
    """The displacement field ``u(x, t)`` over one period as an image (x along the bar).

    Returns
    -------
    matplotlib.image.AxesImage
    """
    ax = _axes(ax)
    x = np.linspace(0.0, 1.0, nx)
    t = np.linspace(0.0, TWO_PI, nt)
    q, _ = orbit._state_in_period(t)
    u = orbit.model.shape_functions(x) @ q  # (nx, nt)
    im = ax.imshow(u, origin="lower", aspect="auto", extent=(0, TWO_PI, 0, 1), cmap="viridis")
    ax.set_xlabel("time since impact t")
    ax.set_ylabel("x (driven end 0, struck end 1)")
    ax.figure.colorbar(im, ax=ax, label="u(x, t)")
    return im


def plot_multipliers(orbit, ax=None):
    """Exact Floquet multipliers and the paper's Schur roots in the complex plane, with the unit
    circle.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    th = np.linspace(0, TWO_PI, 400)
    ax.plot(np.cos(th), np.sin(th), "k-", lw=0.8)
    mu, sr = orbit.multipliers, orbit.schur_roots
    ax.plot(mu.real, mu.imag, "o", mfc="none", label="exact multipliers")
    ax.plot(sr.real, sr.imag, "x", label="paper (Schur blocks)")
    ax.set_aspect("equal")
    ax.set_xlabel("Re")
    ax.set_ylabel("Im")
    ax.legend(fontsize=8)
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
    from .simulation.experiments import load_period

    T = load_period(result.load)
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
        ax.plot(pairs[:, 0], pairs[:, 1], ".", ms=3)
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
