"""Results in SI units (:class:`~impactbar.physical.SimulationResult`): motion, energy per blow,
force waves."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_motion", "plot_blows", "plot_force_waves", "plot_drifter_motion", "plot_drifter_blows",
           "plot_blow_forces", "plot_rod_stress"]


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
    n = int(min(200_000, max(2000, 400 * result.t_end_s * result.hammer.blow_frequency_Hz)))
    ts = np.linspace(0.0, result.t_end_s, n)
    return _end_motion(axes, ts, 1e3 * result.end_displacement_m(ts), result.end_velocity_m_s(ts),
                       result.impact_times_s, result.impact_velocities_m_s,
                       result.hammer.name or "hammer")


def _end_motion(axes, ts, u_mm, v, t_impacts, v_impacts, title):
    """The two panels of an SI run: end displacement (mm) and velocity (m/s), impacts marked."""
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(2, 1, sharex=True)
    ax_u, ax_v = axes
    ax_u.plot(ts, u_mm, lw=0.8)
    ax_u.axhline(0.0, color="k", lw=0.6)
    ax_u.set_ylabel("end displacement / mm")
    ax_u.set_title(title)
    ax_v.plot(ts, v, lw=0.8)
    ax_v.plot(t_impacts, v_impacts, "o", ms=3, label="impact velocity")
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
    t, e = result.impact_times_s, result.impact_energies_J
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


def _drifter_impacts(drifter, run):
    """Impact times (s) and velocities (m/s) of a drifter's simulated run."""
    om, L = drifter.omega_rad_s, drifter.bar.length_m
    return run.impact_times / om, run.impact_velocities * L * om


def plot_drifter_motion(drifter, run, axes=None):
    """A drifter's simulated run (:meth:`~impactbar.physical.Drifter.simulate`): end displacement
    (mm) and velocity (m/s) against time (s), impacts marked.

    Parameters
    ----------
    drifter : Drifter
    run : DrivenTrajectory
        Its dimensionless run.
    axes : sequence of two matplotlib Axes, optional
        Created when not given.

    Returns
    -------
    the two Axes
    """
    om, L = drifter.omega_rad_s, drifter.bar.length_m
    t = np.linspace(run.t0, run.t_end, int(min(200_000, max(2000, 400 * max(run.n_impacts, 1)))))
    return _end_motion(axes, t / om, 1e3 * L * run.end_displacement(t), L * om * run.end_velocity(t),
                       *_drifter_impacts(drifter, run), drifter.name or "drifter")


def plot_drifter_blows(drifter, run, ax=None):
    """Energy per impact ``m v^2 / 2`` (J) of a drifter's simulated run against impact time (s)."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots()
    ti, vi = _drifter_impacts(drifter, run)
    ax.plot(ti, 0.5 * drifter.bar.mass_kg * vi * vi, "o-", ms=3, lw=0.6)
    ax.set_xlabel("impact time / s")
    ax.set_ylabel("energy per blow / J")
    return ax


def _boundaries(drifter):
    """Names, positions along the rod (m, from the shank) and areas (m^2) of the segment boundaries
    (the shank first) and of the bit."""
    segs = drifter.drill.segments
    x = np.concatenate([[0.0], np.cumsum([g.length_m for g in segs])])
    names = ["shank"] + [f"joint {i}" for i in range(1, len(segs))] + ["bit"]
    areas = [g.area_m2 for g in segs] + [segs[-1].area_m2]
    return names, x, np.array(areas)


def plot_blow_forces(drifter, record, ax=None):
    """The force history of one blow on a drill string (a record of ``run.pieces[i].impacts``
    under the rod-rock law, theory §4d): the force (kN) at every segment boundary, the shank first,
    and on the rock, against the time since impact (us).

    Parameters
    ----------
    drifter : Drifter
        With a drill string.
    record : RockContact
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots()
    sc = drifter.scales
    b = record.blow
    t_us = np.asarray(b.times, dtype=float) * sc.time_s * 1e6
    names, _, _ = _boundaries(drifter)
    jf = np.asarray(b.junction_forces, dtype=float) * sc.force_N / 1e3
    for j in range(jf.shape[1]):
        ax.stairs(jf[:, j], t_us, label=names[j])
    ax.plot(t_us, np.asarray(b.bit_forces, dtype=float) * sc.force_N / 1e3, lw=1.0, label="on the rock")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("time since impact / us")
    ax.set_ylabel("force / kN (compression > 0)")
    ax.set_title(f"a blow: {record.work_on_rock * sc.force_N * sc.length_m:.4g} J on rock, "
                 f"efficiency {record.efficiency:.3f}")
    ax.legend(loc="best", fontsize="small")
    return ax


def plot_rod_stress(drifter, record, ax=None):
    """The stress along the drill string in one blow: the largest compressive and tensile stress
    (MPa) at every segment boundary and at the bit, against the position along the rod (m, from
    the shank), each boundary's force over the area of the segment after it."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots()
    sc = drifter.scales
    b = record.blow
    names, x, area = _boundaries(drifter)
    forces = np.column_stack([np.asarray(b.junction_forces, dtype=float),
                              np.asarray(b.bit_forces, dtype=float)[1:]]) * sc.force_N
    stress = forces / area / 1e6
    ax.plot(x, stress.max(axis=0), "o-", label="largest compression")
    ax.plot(x, np.minimum(stress.min(axis=0), 0.0), "s--", label="largest tension")
    for xi, name in zip(x, names, strict=True):
        ax.annotate(name, (xi, 0.0), textcoords="offset points", xytext=(2, 4), fontsize="x-small")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("position along the rod / m (shank at 0)")
    ax.set_ylabel("stress / MPa")
    ax.set_title("stress along the rod in a blow")
    ax.legend(loc="best", fontsize="small")
    return ax
