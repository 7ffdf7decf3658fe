"""The figures of a drifter's operating point with its oil circuit (theory §11): the pressures and
the valve over one period, each chamber's indicator (p-V) diagram, and the bifurcation diagram of
the operating point in one circuit parameter."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_circuit_branch", "plot_circuit_orbit", "plot_circuit_run", "plot_circuit_schematic"]


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
                ax.plot(x, np.where(stable == flag, y, np.nan), "C0" + style, marker="o", ms=3,
                        label=name)  # the branch's points marked
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
    # the valve as a shaded band under the gap (a line over many periods fills the panel), the
    # legend above the panel, outside the data
    ax_v = axes[1].twinx()
    ax_v.fill_between(t, 0.0, h["x_v"], color="C3", alpha=0.2, lw=0, label="valve opening")
    ax_v.set_ylim(0.0, max(1.0, float(np.max(h["x_v"], initial=0.0))) * 1.05)
    ax_v.set_ylabel("valve opening", color="C3")
    axes[1].set_zorder(ax_v.get_zorder() + 1)  # the gap drawn over the band
    axes[1].patch.set_visible(False)
    gap_handles, _ = axes[1].get_legend_handles_labels()
    band_handles, _ = ax_v.get_legend_handles_labels()
    handles = gap_handles + band_handles
    axes[1].legend(handles=handles, loc="lower left", bbox_to_anchor=(0.0, 1.0), ncols=3,
                   fontsize="small", frameon=False)
    if mass_kg is not None:
        v = np.asarray(run["impact_velocities_m_s"])
        axes[2].plot(run["impact_times_s"] * 1e3, 0.5 * mass_kg * v * v, "o", ms=3)
        axes[2].set_ylabel("impact energy (J)")
    axes[-1].set_xlabel("time (ms)")
    return axes


#: The SI values a drifter must carry (its ``si`` dict) for :func:`plot_circuit_schematic`.
_SCHEMATIC_KEYS = ("rear_area_m2", "front_area_m2", "rear_volume_m3", "front_volume_m3", "switch_out_m",
                   "switch_in_m", "switching_time_s", "valve_coefficient", "pump_flow_m3_s",
                   "hose_volume_m3", "front_coefficient", "tank_pressure_Pa", "relief_pressure_Pa",
                   "relief_coefficient", "precharge_Pa", "accumulator_volume_m3", "polytropic_exponent")


def _schematic_labels(drifter) -> dict:
    """Each part's label: its symbols, and with a drifter its SI values (theory §11's names)."""
    if drifter is None:
        return {
            "pump": "pump\n$Q_p$", "supply": "supply node: hose volume $V_s$, pressure $p_s$",
            "accumulator": "gas accumulator\n$p_0$, $V_0$, $n$",
            "relief": "relief valve\n$p_{rel}$, $K_{rel}$",
            "tank": "tank, $p_t$", "front_orifice": "front orifice\n$K_f$",
            "valve": "main valve\n$K_v$, " r"$\tau_v$", "rear": "rear (stroke)\nchamber\n$A_r$, $V_{r0}$",
            "front": "front (return)\nchamber\n$A_f$, $V_{f0}$", "piston": "piston",
            "switch_out": "switch_out", "switch_in": "switch_in", "impact": "impact position\n(stop / shank)"}
    si = getattr(drifter, "si", None)
    missing = [k for k in _SCHEMATIC_KEYS if not isinstance(si, dict) or k not in si]
    if missing:
        raise ValueError(f"drifter must be a CircuitDrifter (impactbar.physical.CircuitDrifter) or None; "
                         f"got {type(drifter).__name__} without the SI value {missing[0]!r}")

    def g(x):
        return f"{x:.3g}"

    acc = (f"gas accumulator\n$p_0$ = {g(si['precharge_Pa'] / 1e6)} MPa\n$V_0$ = "
           f"{g(si['accumulator_volume_m3'] * 1e3)} L, $n$ = {g(si['polytropic_exponent'])}"
           if si["accumulator_volume_m3"] > 0 else "gas accumulator\n(none)")
    relief = (f"relief valve\n$p_{{rel}}$ = {g(si['relief_pressure_Pa'] / 1e6)} MPa\n$K_{{rel}}$ = "
              f"{g(si['relief_coefficient'] * 6e10)} L/min/MPa"
              if np.isfinite(si["relief_pressure_Pa"]) else "relief valve\n(none)")
    s_in = si["switch_in_m"]
    mass = getattr(getattr(drifter, "bar", None), "mass_kg", None)
    stand_in = getattr(drifter, "valve_stand_in", None)
    valve = (f"main valve: {stand_in}\n(pilot-operated spool,\nswitched by its pilot ports)" if stand_in
             else f"main valve\n$K_v$ = {g(si['valve_coefficient'])}\nm³/s/Pa$^{{1/2}}$\n"
                  rf"$\tau_v$ = {g(si['switching_time_s'] * 1e3)} ms")
    return {
        "pump": f"pump\n$Q_p$ = {g(si['pump_flow_m3_s'] * 6e4)} L/min",
        "supply": f"supply node: hose volume $V_s$ = {g(si['hose_volume_m3'] * 1e3)} L, pressure $p_s$",
        "accumulator": acc, "relief": relief,
        "tank": f"tank, $p_t$ = {g(si['tank_pressure_Pa'] / 1e6)} MPa",
        "front_orifice": f"front orifice\n$K_f$ = {g(si['front_coefficient'])}\nm³/s/Pa$^{{1/2}}$",
        "valve": valve,
        "rear": (f"rear (stroke)\nchamber\n$A_r$ = {g(si['rear_area_m2'] * 1e4)} cm²\n"
                 f"$V_{{r0}}$ = {g(si['rear_volume_m3'] * 1e3)} L"),
        "front": (f"front (return) chamber\n$A_f$ = {g(si['front_area_m2'] * 1e4)} cm²\n"
                  f"$V_{{f0}}$ = {g(si['front_volume_m3'] * 1e3)} L"),
        "piston": "piston" + (f"\n{g(mass)} kg" if mass is not None else ""),
        "switch_out": f"switch_out\n{g(si['switch_out_m'] * 1e3)} mm",
        "switch_in": ("switch_in\n(none: the valve\nreturns at impact)" if s_in is None
                      else f"switch_in\n{g(s_in * 1e3)} mm"),
        "impact": "impact position\n(stop / shank)\ngap 0"}


def plot_circuit_schematic(drifter=None, ax=None):
    """A schematic of a drifter's oil circuit (theory §11; the parts of
    :mod:`impactbar.drives.circuit`): the pump feeding the supply node (the hose's volume) with the
    gas accumulator and the relief valve to the tank on it; the front (return) chamber fed from the
    supply through the front orifice; the main valve connecting the rear (stroke) chamber to the
    supply (``x_v = 1``) or to the tank (``x_v = 0``); the piston with its rear area and its front
    annulus; and below it the stroke axis, the gap from the impact position, with the valve's
    switch points ``switch_out`` (on the way out the valve starts to the stroke) and ``switch_in``
    (on the way in it starts back; without it, at the impact).

    Parameters
    ----------
    drifter : CircuitDrifter, optional
        With a :class:`~impactbar.physical.CircuitDrifter` (e.g. ``impactbar.physical.circuit_preset(
        "circuit-drifter")``) each part is labelled with its SI values (areas in cm², volumes in L,
        pressures in MPa absolute, flows in L/min, switch points in mm); ``None`` (default): with
        the symbols of theory §11 only. The switch points are drawn to scale along the stroke axis
        only with a drifter.
    ax : matplotlib.axes.Axes, optional
        Default: a new figure, 11 x 5.4 inches.

    Returns
    -------
    matplotlib.axes.Axes
        The axes the diagram is drawn on.

    Raises
    ------
    ValueError
        ``drifter`` neither ``None`` nor a drifter with its oil circuit (no ``si`` dict of its SI
        values).
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, FancyBboxPatch, Rectangle

    lab = _schematic_labels(drifter)
    if ax is None:
        _, ax = plt.subplots(figsize=(11.0, 5.4), layout="constrained")
    line = {"color": "k", "lw": 1.4, "solid_capstyle": "butt"}
    txt = {"fontsize": 8.5, "va": "center"}
    rail, tank = 7.0, 0.6                  # the supply node's and the tank's lines
    x_pump, x_acc, x_rel, x_val = 1.0, 3.0, 5.2, 7.6
    cyl0, head0, head1, cyl1, rod1 = 9.0, 10.9, 11.4, 13.4, 14.6   # cylinder, piston head, rod tip
    y0, y1, r0, r1 = 3.0, 4.6, 3.5, 4.1    # the cylinder's bore and the rod's section

    def box(x, y, w, h, **kw):
        ax.add_patch(FancyBboxPatch((x - w / 2, y - h / 2), w, h, boxstyle="round,pad=0.05",
                                    fc=kw.pop("fc", "white"), ec="k", lw=1.2, zorder=3, **kw))

    def arrow(x0, y0_, x1, y1_):
        ax.annotate("", (x1, y1_), (x0, y0_), arrowprops={"arrowstyle": "-|>", "color": "k", "lw": 1.2})

    # supply node and tank lines
    ax.plot([x_pump, 12.2], [rail, rail], **line)
    ax.plot([x_pump, x_val], [tank, tank], **line)
    ax.text(6.6, rail + 0.3, lab["supply"], ha="center", **txt)
    ax.text(x_pump + 0.2, tank - 0.3, lab["tank"], ha="left", **txt)
    # pump: from the tank up into the supply node
    ax.plot([x_pump, x_pump], [tank, rail], **line, zorder=1)
    ax.add_patch(Circle((x_pump, 3.6), 0.45, fc="white", ec="k", lw=1.2, zorder=3))
    ax.add_patch(plt.Polygon([(x_pump - 0.25, 3.4), (x_pump + 0.25, 3.4), (x_pump, 3.95)], fc="k", zorder=4))
    arrow(x_pump, 5.2, x_pump, 6.2)
    ax.text(x_pump - 0.6, 3.6, lab["pump"], ha="right", **txt)
    # gas accumulator on the supply node
    ax.plot([x_acc, x_acc], [5.6, rail], **line, zorder=1)
    ax.add_patch(FancyBboxPatch((x_acc - 0.4, 4.3), 0.8, 1.3, boxstyle="round,pad=0,rounding_size=0.4",
                                fc="#dde8f4", ec="k", lw=1.2, zorder=3))
    ax.plot([x_acc - 0.4, x_acc + 0.4], [5.0, 5.0], color="k", lw=0.8, zorder=4)   # the membrane
    ax.text(x_acc, 4.6, "gas", ha="center", fontsize=7, va="center", zorder=5)
    ax.text(x_acc, 3.95, lab["accumulator"], ha="center", fontsize=8.5, va="top")
    # relief valve: supply node to tank
    ax.plot([x_rel, x_rel], [tank, rail], **line, zorder=1)
    box(x_rel, 5.5, 0.9, 0.7)
    ax.plot([x_rel - 0.3, x_rel + 0.3], [5.25, 5.75], color="k", lw=1.0, zorder=4)  # its spring
    arrow(x_rel, 4.9, x_rel, 4.3)
    ax.text(x_rel + 0.15, 2.4, lab["relief"], ha="left", **txt)
    # main valve: the rear chamber to the supply (x_v = 1) or to the tank (x_v = 0)
    ax.plot([x_val, x_val], [tank, rail], **line, zorder=1)
    box(x_val, 3.8, 1.3, 1.0)
    ax.text(x_val, 3.8, "P ↔ A ↔ T", ha="center", fontsize=7.5, va="center", zorder=5)
    ax.plot([x_val + 0.7, cyl0], [3.8, 3.8], **line)
    ax.text(x_val - 0.8, 3.8, lab["valve"], ha="right", **txt)
    ax.text(x_val + 0.12, 5.4, "P: supply\n($x_v$ = 1)", ha="left", fontsize=7, va="center")
    ax.text(x_val + 0.12, 2.0, "T: tank\n($x_v$ = 0)", ha="left", fontsize=7, va="center")
    # the cylinder: rear chamber | piston head | front annulus, the rod through the front wall
    ax.add_patch(Rectangle((cyl0, y0), cyl1 - cyl0, y1 - y0, fc="none", ec="k", lw=1.6, zorder=2))
    ax.add_patch(Rectangle((cyl0, y0), head0 - cyl0, y1 - y0, fc="#f6d8b8", ec="none", zorder=1))
    ax.add_patch(Rectangle((head1, y0), cyl1 - head1, y1 - y0, fc="#cfe3cf", ec="none", zorder=1))
    ax.add_patch(Rectangle((head0, y0), head1 - head0, y1 - y0, fc="0.55", ec="k", zorder=3))
    ax.add_patch(Rectangle((head1, r0), rod1 - head1, r1 - r0, fc="0.55", ec="k", zorder=3))
    ax.text(0.5 * (cyl0 + head0), y1 + 0.15, lab["rear"], ha="center", fontsize=8.5, va="bottom")
    ax.text(0.5 * (head1 + cyl1), y0 - 0.15, lab["front"], ha="center", fontsize=8.5, va="top")
    ax.text(0.5 * (head0 + head1), y1 + 0.15, lab["piston"], ha="center", fontsize=8.5, va="bottom")
    # front orifice: supply node to the front chamber
    x_fo = 12.2
    ax.plot([x_fo, x_fo], [y1, rail], **line, zorder=1)
    box(x_fo, 5.8, 0.5, 0.5)
    ax.plot([x_fo - 0.2, x_fo + 0.2], [5.65, 5.95], color="k", lw=1.0, zorder=4)
    ax.text(x_fo + 0.45, 5.8, lab["front_orifice"], ha="left", **txt)
    # the stop (shank) the piston strikes, at the impact position
    ax.add_patch(Rectangle((rod1, 2.9), 0.7, 1.8, fc="0.8", ec="k", hatch="//", zorder=3))
    ax.text(0.5 * (head1 + cyl1), 0.5 * (r1 + y1), "stroke →", ha="center", fontsize=7, va="center")
    # the stroke axis: the gap from the impact position, growing away from the stop
    ya = 1.0
    ax.plot([cyl0 + 0.4, rod1], [ya, ya], color="k", lw=0.8)
    arrow(rod1 - 0.3, ya - 0.3, cyl0 + 0.6, ya - 0.3)
    ax.text(cyl0 + 0.6, ya - 0.45, "gap from the impact position", ha="left", fontsize=8, va="top")
    span = rod1 - cyl0 - 1.2
    if getattr(drifter, "valve_stand_in", None):  # (a spool in the valve's place: no switch points)
        x_out = x_in = None
    elif drifter is not None:
        s_out, s_in = drifter.si["switch_out_m"], drifter.si["switch_in_m"]
        x_out = rod1 - span / 1.25
        x_in = rod1 - span / 1.25 * s_in / s_out if s_in is not None else None
    else:
        x_out, x_in = rod1 - span / 1.25, rod1 - 0.45 * span / 1.25
    marks = (("impact", rod1, "k"), ("switch_out", x_out, "C3"), ("switch_in", x_in, "C0"))
    for name, x, color in marks:
        if x is None:
            continue
        ax.plot([x, x], [ya - 0.15, ya + 0.15], color=color, lw=2.0, gid=name)
    ax.text(rod1 + 0.1, ya + 0.25, lab["impact"], ha="left", fontsize=8, va="bottom")
    if x_out is not None:  # (the ramped valve's switch points; a spool has its pilot ports instead)
        ax.text(x_out, ya + 0.25, lab["switch_out"], ha="center", fontsize=8, va="bottom", color="C3")
        if x_in is not None:
            ax.text(x_in, ya + 0.25, lab["switch_in"], ha="center", fontsize=8, va="bottom", color="C0")
        else:
            ax.text(rod1 + 0.1, ya - 0.2, lab["switch_in"], ha="left", fontsize=8, va="top", color="C0")
    name = getattr(drifter, "name", "") if drifter is not None else ""
    ax.set_title("A drifter's oil circuit" + (f": {name}" if name else ""))
    ax.set_xlim(-1.9, 17.0)
    ax.set_ylim(-0.6, 7.8)
    ax.set_aspect("equal")
    ax.set_axis_off()
    return ax
