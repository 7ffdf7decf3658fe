"""The figure of a piston design (theory §12): the stepped piston's shape and its incident stress
wave against the uniform piston's of the same mass and length."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_piston_design"]


def plot_piston_design(design, axes=None):
    """The best shape of :func:`~impactbar.physical.piston.optimize_piston` (its radius along the
    piston, the struck end on the right) above, its incident force in the rod against time below,
    each beside the uniform piston's.

    Parameters
    ----------
    design : OptimalPiston
    axes : sequence of two matplotlib.axes.Axes, optional
        Default: a new figure with two rows.

    Returns
    -------
    numpy.ndarray of matplotlib.axes.Axes, shape (2,)
    """
    import matplotlib.pyplot as plt

    if axes is None:
        _, axes = plt.subplots(2, 1, figsize=(6.5, 6.0), layout="constrained")
    ax_shape, ax_wave = axes
    x = np.concatenate(([0.0], np.cumsum(design.lengths_m))) * 1e3
    r = np.append(design.diameters_m, design.diameters_m[-1]) * 500.0
    volume = float(np.sum(design.areas_m2 * design.lengths_m))
    r_u = float(np.sqrt(4.0 * volume / design.length_m / np.pi)) * 500.0  # the same mass and length
    ax_shape.fill_between(x, -r, r, step="post", color="C0", alpha=0.35, label="best shape")
    for sign in (1.0, -1.0):
        ax_shape.plot([x[0], x[-1]], [sign * r_u] * 2, color="C1", ls="--",
                      label="uniform piston" if sign > 0 else None)
    ax_shape.set_xlabel("position from the driven end (mm); struck end on the right")
    ax_shape.set_ylabel("radius (mm)")
    ax_shape.set_title(f"work on rock {design.work_on_rock_J:.4g} J "
                       f"(uniform {design.uniform_work_on_rock_J:.4g} J)")
    ax_shape.legend(loc="best", fontsize="small")
    top = max(float(np.max(np.abs(design.incident_force_N))), float(np.max(design.uniform_incident_force_N)))
    pressing = np.flatnonzero(np.maximum(np.abs(design.incident_force_N),
                                         np.abs(design.uniform_incident_force_N)) > 1e-3 * top)
    n = min(design.incident_force_N.size, int(1.25 * (pressing[-1] + 1)) if pressing.size else 1)
    t = design.times_s[:n + 1] * 1e6
    ax_wave.stairs(design.incident_force_N[:n] / 1e3, t, color="C0", label="best shape")
    ax_wave.stairs(design.uniform_incident_force_N[:n] / 1e3, t, color="C1", ls="--", label="uniform piston")
    ax_wave.set_xlabel("time from impact (µs)")
    ax_wave.set_ylabel("piston-shank force (kN)")
    ax_wave.legend(loc="best", fontsize="small")
    return np.asarray(axes)
