"""Plots of computed results (matplotlib imported lazily; every function takes an optional ``ax``)."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["plot_orbit", "plot_orbit_field", "plot_multipliers", "plot_experiment"]

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


def plot_experiment(result, directory, *, prefix: str = "") -> list:
    """Write three PNG figures of an :class:`~impactbar.simulation.experiments.ExperimentResult`
    into ``directory``: end displacement against time (the kept
    runs), the impact map ``v_{i+1}`` against ``v_i``, and a histogram of impact intervals.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    from .simulation.experiments import load_period

    T = load_period(result.load)
    files = []

    rows = max(1, len(result.trajectories))
    fig, axes = plt.subplots(rows, 1, figsize=(9, 2.2 * rows), squeeze=False)
    for ax, tr in zip(axes[:, 0], result.trajectories, strict=False):
        t1 = tr.t_end
        t0 = max(tr.t0, t1 - 20 * T)
        t = np.linspace(t0, t1, 4000)
        ax.plot(t / T, tr.end_displacement(t), lw=0.8)
        ax.set_ylabel("u(1, t)")
    axes[-1, 0].set_xlabel("t / load period (last 20 periods)")
    fig.suptitle("end displacement")
    fig.tight_layout()
    files.append(out / f"{prefix}end_displacement.png")
    fig.savefig(files[-1], dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5, 5))
    if result.impact_pairs.size:
        ax.plot(result.impact_pairs[:, 0], result.impact_pairs[:, 1], ".", ms=2)
        lim = float(np.max(result.impact_pairs)) * 1.05
        ax.plot([0, lim], [0, lim], "k:", lw=0.5)
    ax.set_xlabel("v_i")
    ax.set_ylabel("v_{i+1}")
    ax.set_title("impact map (main impacts, classified windows)")
    fig.tight_layout()
    files.append(out / f"{prefix}impact_map.png")
    fig.savefig(files[-1], dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6, 4))
    if result.intervals.size:
        ax.hist(result.intervals, bins=80)
    ax.set_xlabel("impact interval / load period")
    ax.set_ylabel("count")
    ax.set_title(f"mean {result.interval_mean:.4f}, std {result.interval_std:.4f}")
    fig.tight_layout()
    files.append(out / f"{prefix}interval_histogram.png")
    fig.savefig(files[-1], dpi=120)
    plt.close(fig)
    return files
