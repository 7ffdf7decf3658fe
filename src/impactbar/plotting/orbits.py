"""Orbits: the end's motion over a period, the field, the Floquet multipliers."""

from __future__ import annotations

import math

import numpy as np

from ._common import axes as _axes

__all__ = ["plot_orbit", "plot_orbit_field", "plot_multipliers"]

TWO_PI = 2.0 * math.pi


def plot_orbit(orbit, ax=None, n: int = 2000):
    """End displacement ``u(1, t)`` over one period of an orbit (the stop at ``u = 0``), from its
    first impact; impacts of an orbit with several are marked.

    Parameters
    ----------
    orbit : PeriodicOrbit
        Any orbit of :func:`~impactbar.periodic_orbits` or :func:`~impactbar.find_orbit`.
    ax : matplotlib.axes.Axes, optional
    n : int
        Number of time samples (for drawing only; admissibility is decided rigorously elsewhere).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax)
    t = np.linspace(0.0, getattr(orbit, "period", TWO_PI), n)
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
    # below the axes: inside, it covered the multipliers near the unit circle
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)
    return ax
