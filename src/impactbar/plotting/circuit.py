"""The figures of a drifter's operating point with its oil circuit (theory §11): the pressures and
the valve over one period, each chamber's indicator (p-V) diagram, and the bifurcation diagram of
the operating point in one circuit parameter."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_circuit_branch", "plot_circuit_orbit", "plot_circuit_run"]


def plot_circuit_orbit(orbit, axes=None, points: int = 2000):
    """A drifter's operating point over one period, from the impact: the three pressures (front,
    rear and supply chamber) and the valve opening against time, and the indicator (p-V) diagram
    of the rear and of the front chamber with the work its loop encloses
    (:meth:`~impactbar.physical.circuit.CircuitDrifterOrbit.indicator_work_J`).

    Parameters
    ----------
    orbit : CircuitDrifterOrbit
        :meth:`~impactbar.physical.circuit.CircuitDrifter.orbit`'s result.
    axes : sequence of four matplotlib.axes.Axes, optional
        Pressures, valve opening, rear p-V, front p-V. Default: a new 2 x 2 figure.
    points : int
        Samples over the period, ``>= 2``.

    Returns
    -------
    numpy.ndarray of matplotlib.axes.Axes, shape (4,)

    Raises
    ------
    ValueError
        ``points`` below 2.
    """
    import matplotlib.pyplot as plt

    h = orbit.histories(points)
    if axes is None:
        _, axes = plt.subplots(2, 2, figsize=(9.0, 6.5), layout="constrained")
    ax_p, ax_v, ax_rear, ax_front = np.asarray(axes).ravel()
    t = h["t_s"] * 1e3
    for key, label in (("p_f_Pa", "front chamber"), ("p_r_Pa", "rear chamber"), ("p_s_Pa", "supply")):
        ax_p.plot(t, h[key] / 1e6, label=label)
    ax_p.set_xlabel("time from impact (ms)")
    ax_p.set_ylabel("pressure (MPa, absolute)")
    ax_p.set_title(f"{orbit.blow_frequency_Hz:.4g} Hz, {orbit.impact_energy_J:.4g} J a blow")
    ax_p.legend(loc="best", fontsize="small")
    ax_v.plot(t, h["x_v"], color="C3", label="valve (1: rear chamber to supply)")
    ax_v.set_xlabel("time from impact (ms)")
    ax_v.set_ylabel("valve opening")
    ax_gap = ax_v.twinx()
    ax_gap.plot(t, h["gap_m"] * 1e3, color="C7", ls="--", label="gap to the stop")
    ax_gap.set_ylabel("gap to the stop (mm)")
    lines = ax_v.get_lines() + ax_gap.get_lines()
    ax_v.legend(lines, [ln.get_label() for ln in lines], loc="best", fontsize="small")
    work = orbit.indicator_work_J(histories=h)
    for ax, p, V, name in ((ax_rear, "p_r_Pa", "V_r_m3", "rear"), (ax_front, "p_f_Pa", "V_f_m3", "front")):
        ax.plot(h[V] * 1e6, h[p] / 1e6, color="C1" if name == "rear" else "C0")
        ax.plot(h[V][0] * 1e6, h[p][0] / 1e6, "ko", ms=4, label="impact")
        ax.set_xlabel(f"{name} chamber volume (cm³)")
        ax.set_ylabel("pressure (MPa, absolute)")
        ax.set_title(f"{name} chamber: work on the piston {work[name]:.4g} J a period")
        ax.legend(loc="best", fontsize="small")
    return np.asarray([ax_p, ax_v, ax_rear, ax_front])


def plot_circuit_branch(branch, axes=None):
    """The bifurcation diagram of a drifter's operating point in one circuit parameter, in SI: the
    blow frequency above, the impact energy below, against the parameter; stable points solid,
    unstable ones dashed, every located event (fold, period doubling, Neimark-Sacker point,
    accumulator emptying, relief opening) a marked vertical line.

    Parameters
    ----------
    branch : CircuitBranch
        :func:`~impactbar.physical.circuit_branch.continue_circuit`'s result.
    axes : sequence of two matplotlib.axes.Axes, optional
        Default: a new figure with two rows sharing the parameter axis.

    Returns
    -------
    numpy.ndarray of matplotlib.axes.Axes, shape (2,)
    """
    import matplotlib.pyplot as plt

    if axes is None:
        _, axes = plt.subplots(2, 1, figsize=(7.0, 6.0), sharex=True, layout="constrained")
    ax_f, ax_e = np.asarray(axes).ravel()
    scale, unit = _shown_unit(branch.unit)
    x = branch.values * scale
    stable = branch.stable
    for ax, y, label in ((ax_f, branch.blow_frequency_Hz, "blow frequency (Hz)"),
                         (ax_e, branch.impact_energy_J, "impact energy (J)")):
        for flag, style, name in ((True, "-", "stable"), (False, "--", "unstable")):
            if np.any(stable == flag):
                ax.plot(x, np.where(stable == flag, y, np.nan), "C0" + style, label=name)
        for i, e in enumerate(branch.events):
            ax.axvline(e["value"] * scale, color=f"C{1 + i % 8}", lw=0.8, ls=":",
                       label=e["kind"] if ax is ax_f else None)
        ax.set_ylabel(label)
    ax_f.legend(loc="best", fontsize="small")
    ax_e.set_xlabel(f"{branch.parameter}" + (f" ({unit})" if unit else ""))
    return np.asarray([ax_f, ax_e])


def _shown_unit(unit: str):
    """The factor and unit a parameter in SI is drawn in (pressures in MPa, volumes in L, flows in
    L/min, times in ms)."""
    return {"Pa": (1e-6, "MPa"), "m**3": (1e3, "L"), "m**3/s": (6e4, "L/min"), "s": (1e3, "ms"),
            "m": (1e3, "mm")}.get(unit, (1.0, unit.replace("**", "^")))


def plot_circuit_run(run, axes=None, *, mass_kg: float | None = None):
    """A run of a drifter with its oil circuit against time: the three pressures above, the gap to
    the stop and the valve opening in the middle, and (with ``mass_kg``) the energy of every
    impact below.

    Parameters
    ----------
    run : dict
        :meth:`~impactbar.physical.circuit.CircuitDrifter.simulate`'s result.
    axes : sequence of matplotlib.axes.Axes, optional
        Three (two without ``mass_kg``) axes. Default: a new figure, one row each, sharing time.
    mass_kg : float, optional
        The piston's mass (kg), for the impact energies ``m v^2 / 2``.

    Returns
    -------
    numpy.ndarray of matplotlib.axes.Axes, shape (3,) or (2,)
    """
    import matplotlib.pyplot as plt

    rows = 3 if mass_kg is not None else 2
    if axes is None:
        _, axes = plt.subplots(rows, 1, figsize=(8.0, 2.6 * rows), sharex=True, layout="constrained")
    axes = np.asarray(axes).ravel()
    h = run["histories"]
    t = h["t_s"] * 1e3
    for key, label in (("p_f_Pa", "front chamber"), ("p_r_Pa", "rear chamber"), ("p_s_Pa", "supply")):
        axes[0].plot(t, h[key] / 1e6, lw=0.8, label=label)
    axes[0].set_ylabel("pressure (MPa)")
    axes[0].legend(loc="best", fontsize="small")
    axes[1].plot(t, h["gap_m"] * 1e3, color="C7", lw=0.8, label="gap to the stop")
    axes[1].plot(run["impact_times_s"] * 1e3, np.zeros(len(run["impact_times_s"])), "k|", ms=8,
                 label="impacts")
    axes[1].set_ylabel("gap (mm)")
    ax_v = axes[1].twinx()
    ax_v.plot(t, h["x_v"], color="C3", lw=0.6, alpha=0.6)
    ax_v.set_ylabel("valve opening", color="C3")
    axes[1].legend(loc="upper left", fontsize="small")
    if mass_kg is not None:
        v = np.asarray(run["impact_velocities_m_s"])
        axes[2].plot(run["impact_times_s"] * 1e3, 0.5 * mass_kg * v * v, "o", ms=3)
        axes[2].set_ylabel("impact energy (J)")
    axes[-1].set_xlabel("time (ms)")
    return axes
