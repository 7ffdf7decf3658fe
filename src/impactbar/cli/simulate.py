"""``impactbar simulate CONFIG.toml --out DIR``: simulate a hammer in SI units from rest and write
plots of the struck end's displacement and velocity, the impact times and the energy per blow."""

from __future__ import annotations

import json
import sys

import numpy as np

from .. import physical
from ..plotting.physical import plot_blows, plot_force_waves, plot_motion
from ._common import add_quiet_argument, output_folder, progress_bar, require
from .physical import add_impact_argument, add_physical_arguments, hammer_from_args, json_ready

__all__ = ["add_parser", "run", "summarize", "plot_motion", "plot_blows", "plot_force_waves"]

# the drawing lives in impactbar.plotting; re-exported here for the old import path


def add_parser(subparsers) -> None:
    """Register ``simulate``."""
    p = subparsers.add_parser(
        "simulate", help="simulate a hammer in SI units from rest; plots and impact table",
        description="Simulate a hammer given in SI units (a TOML config or a preset) from rest and "
                    "write motion.png (end displacement and velocity over time, impacts marked), "
                    "blows.png (energy per blow), impacts.csv and summary.json to DIR; with "
                    "--impact wave also forces.png (the force waves sent into the rod).")
    add_physical_arguments(p)
    add_impact_argument(p)
    p.add_argument("--out", default="out/simulate", metavar="DIR",
                   help="output folder (created; default out/simulate)")
    p.add_argument("--periods", type=float, default=40.0, metavar="N",
                   help="length of the run in load periods, one drive period 1/f_b each (the "
                        "dimensionless 2 pi; default 40)")
    p.add_argument("--blow-fraction", type=float, default=0.25, metavar="F",
                   help="an impact is a blow when its impact velocity is at least F times the run's "
                        "largest; slower ones are chatter, counted apart (default 0.25)")
    p.add_argument("--gap", default="0 mm", metavar="LENGTH",
                   help="initial distance of the struck end from the stop, with a unit; the "
                        "piston starts at rest (default '0 mm')")
    add_quiet_argument(p)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run the simulation and write the outputs; returns the exit status."""
    from ..physical.units import to_si
    from .drifter import drifter_from_args, run_drifter_simulate

    drifter = drifter_from_args(args)  # a valve switched on the piston's position (theory §10)
    if drifter is not None:
        gap = to_si("--gap", args.gap, "m", "'2 mm'", what="a length")
        return run_drifter_simulate(args, drifter, output_folder(args.out), gap)
    hammer = hammer_from_args(args)
    if not 0.0 < args.blow_fraction <= 1.0:
        print(f"impactbar simulate: error: --blow-fraction must be in (0, 1]; got "
              f"{args.blow_fraction}", file=sys.stderr)
        return 2
    gap = to_si("--gap", args.gap, "m", "'2 mm'", what="a length")
    require("matplotlib")
    out = output_folder(args.out)
    try:  # a bar with an estimate of the time left (stderr, a terminal, not --quiet)
        with progress_bar(args.periods, desc="simulate", unit="period", quiet=args.quiet) as bar:
            def progress(f):
                bar.update(f * args.periods - bar.n)

            result = physical.simulate(hammer, periods=args.periods, gap_m=gap,
                                       progress=None if bar.disable else progress)
    except RuntimeError as exc:
        print(f"impactbar simulate: error: {exc}", file=sys.stderr)
        return 1
    written, summary = _write_outputs(result, out, args)
    line = (f"{hammer.name or 'hammer'}: {summary['n_impacts']} impacts in {result.t_end_s:.4g} s "
            f"({summary['n_blows']} blows, {summary['n_chatter']} chatter)")
    if summary["n_blows_second_half"] >= 2:
        line += (f"; second half, {summary['n_blows_second_half']} blows: "
                 f"{summary['mean_impact_velocity_m_s']:.3f} m/s, "
                 f"{summary['mean_impact_energy_J']:.2f} J per blow, every "
                 f"{summary['mean_blow_interval_s'] * 1e3:.2f} ms "
                 f"(std {summary['blow_interval_std_s'] * 1e3:.2f} ms; "
                 f"{summary['blow_frequency_Hz']:.4g} Hz), "
                 f"{summary['mean_impact_power_kW']:.4g} kW")
        if np.isfinite(summary["mean_efficiency"]):
            line += f", efficiency {summary['mean_efficiency']:.3f}"
    print(line + f"; wrote {out}/{written}, impacts.csv, summary.json")
    rock = summary.get("rock", {})
    if "mean_work_on_rock_J" in rock:
        print(f"rock (second half, {rock['n_blows']} blows, {rock['n_chatter']} chatter): "
              f"{rock['mean_work_on_rock_J']:.4g} J on rock and {rock['mean_penetration_mm']:.4g} mm per "
              f"blow, {rock['drilling_rate_m_min']:.4g} m/min at the measured blow frequency "
              f"({rock['measured_rate_m_min']:.4g} m/min over the run, chatter included), efficiency "
              f"{rock['mean_efficiency']:.3f} ({rock['mean_efficiency_with_rebound']:.3f} with the rebound)")
    if summary["settled"]:
        print(summary["message"])
    else:
        print(f"impactbar simulate: warning: {summary['message']}", file=sys.stderr)
    return 0


def _write_outputs(result, out, args) -> tuple[str, dict]:
    """impacts.csv, summary.json and the figures; returns the figures' names and the summary."""
    write_impacts(result, out / "impacts.csv")
    summary = summarize(result, blow_fraction=args.blow_fraction)
    if result.hammer.drill is not None:  # the rod-rock law: drilling outputs (impactbar.physical.rock)
        from ..physical.rock import rock_summary

        summary["rock"] = rock_summary(result, blow_fraction=args.blow_fraction)
    (out / "summary.json").write_text(json.dumps(json_ready(summary), indent=2, allow_nan=False))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6), constrained_layout=True)
    plot_motion(result, axes)
    fig.savefig(out / "motion.png", dpi=120)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(8, 3.5), constrained_layout=True)
    plot_blows(result, ax, blow_fraction=args.blow_fraction)
    fig.savefig(out / "blows.png", dpi=120)
    plt.close(fig)
    written = "motion.png, blows.png"
    if np.any(np.isfinite(result.rod_energies_J)):
        fig, ax = plt.subplots(figsize=(8, 3.5), constrained_layout=True)
        plot_force_waves(result, ax, blow_fraction=args.blow_fraction)
        fig.savefig(out / "forces.png", dpi=120)
        plt.close(fig)
        written += ", forces.png"
    return written, summary


def write_impacts(result: physical.SimulationResult, path) -> None:
    """One row per impact: index, time (s), impact velocity (m/s), energy per blow (J), written
    through :meth:`~impactbar.physical.SimulationResult.to_dataframe` with 9 significant digits."""
    result.to_dataframe().to_csv(path, float_format="%.9g", lineterminator="\r\n")


def summarize(result: physical.SimulationResult, *, blow_fraction: float = 0.25) -> dict:
    """The hammer's inputs and the impact statistics, JSON-ready.

    The statistics are :meth:`~impactbar.physical.SimulationResult.blow_statistics`: over the
    blows of the second half of the run (past the start-up), an impact being a blow when its impact
    velocity is at least ``blow_fraction`` of the run's largest; slower ones are counted as chatter.
    ``settled`` and ``message`` say whether the blows repeat a cycle. ``blow_frequency_Hz`` is the
    blows' measured frequency (the inverse of their mean interval; NaN with fewer than two), the
    drive's imposed one ``f / k`` being ``drive_blow_frequency_Hz``.
    """
    t = result.impact_times_s
    v = result.impact_velocities_m_s
    e = result.impact_energies_J
    out = result.hammer.to_dict()
    out["drive_blow_frequency_Hz"] = out.pop("blow_frequency_Hz")  # f / k, imposed by the drive
    out.update({"t_end_s": result.t_end_s, "n_impacts": int(t.size)})
    if t.size:
        out.update({"last_impact_velocity_m_s": float(v[-1]), "last_impact_energy_J": float(e[-1])})
    stats = result.blow_statistics(blow_fraction=blow_fraction)
    out.update(stats.to_dict())
    out["blow_frequency_Hz"] = 1.0 / stats.mean_blow_interval_s  # measured; NaN below two blows
    return out
