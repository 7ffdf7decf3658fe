"""Results in SI units (:class:`~impactbar.physical.SimulationResult`): motion, energy per blow,
force waves."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_motion", "plot_blows", "plot_force_waves"]


def plot_motion(result, axes=None):
    """End displacement (mm) and velocity (m/s) against time (s), impacts marked.

    Parameters
    ----------
    result : SimulationResult
    axes : sequence of two matplotlib Axes, optional
        Created when not given.

    Returns
    -------
    the two Axes
    """
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(2, 1, sharex=True)
    ax_u, ax_v = axes
    n = int(min(200_000, max(2000, 400 * result.t_end_s * result.hammer.blow_frequency_Hz)))
    ts = np.linspace(0.0, result.t_end_s, n)
    ax_u.plot(ts, 1e3 * result.end_displacement_m(ts), lw=0.8)
    ax_u.axhline(0.0, color="k", lw=0.6)
    ax_u.set_ylabel("end displacement / mm")
    ax_u.set_title(result.hammer.name or "hammer")
    ax_v.plot(ts, result.end_velocity_m_s(ts), lw=0.8)
    ax_v.plot(result.impact_times_s, result.impact_velocities_m_s, "o", ms=3,
              label="impact velocity")
    ax_v.set_xlabel("time / s")
    ax_v.set_ylabel("end velocity / (m/s)")
    ax_v.legend(loc="best", fontsize="small")
    return ax_u, ax_v


def plot_blows(result, ax=None, blow_fraction: float = 0.25):
    """Energy per impact (J) against impact time (s): blows filled, chatter hollow
    (:meth:`~impactbar.physical.SimulationResult.is_blow` with ``blow_fraction``)."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots()
    blow = result.is_blow(blow_fraction)
    t, e = result.impact_times_s, result.blow_energies_J
    ax.plot(t[blow], e[blow], "o-", ms=3, lw=0.6, label="blows")
    if not np.all(blow):
        ax.plot(t[~blow], e[~blow], "o", ms=3, mfc="none", label="chatter")
        ax.legend(loc="best", fontsize="small")
    ax.set_xlabel("impact time / s")
    ax.set_ylabel("energy per blow / J")
    return ax


def plot_force_waves(result, ax=None, last: int = 8, blow_fraction: float = 0.25):
    """The force (kN) of the waves the last ``last`` blows sent into the rod, against the time from
    the start of each contact (us); wave law only.

    Chatter (impacts slower than ``blow_fraction`` of the run's largest, see
    :meth:`~impactbar.physical.SimulationResult.is_blow`) is left out; curves that agree to 1e-3
    of the largest force share one line and one legend entry, and the force axis has no offset.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots()
    blows = np.flatnonzero(result.is_blow(blow_fraction))[-last:]
    window = result.hammer.contact_duration_s  # 2 L / c
    t = np.linspace(0.0, window * (1.0 - 1e-9), 400)
    curves = [1e-3 * result.force_wave(int(i), t) for i in blows]
    scale = max((float(np.max(np.abs(c))) for c in curves), default=0.0)
    groups: list[tuple[np.ndarray, list[int]]] = []
    for i, c in zip(blows, curves, strict=True):
        for g, members in groups:
            if np.max(np.abs(c - g)) <= 1e-3 * scale:  # the same at the figure's resolution
                members.append(int(i))
                break
        else:
            groups.append((c, [int(i)]))
    for c, members in groups:
        name = "blow" if len(members) == 1 else "blows"
        ax.plot(1e6 * t, c, lw=0.9, label=f"{name} {', '.join(map(str, members))}")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_xlabel("time from contact / us")
    ax.set_ylabel("force into the rod / kN")
    if groups:
        ax.legend(loc="best", fontsize="x-small", ncol=2)
    return ax
