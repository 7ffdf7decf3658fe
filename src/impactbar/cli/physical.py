"""Command-line pieces for hammers in SI units, shared by ``impactbar orbits`` and
``impactbar simulate``: a TOML config or a preset in, an SI table or JSON out."""

from __future__ import annotations

import dataclasses
import sys
import warnings

from .. import physical
from ..laws import LAWS
from ._common import UsageError, docs_page, json_ready, print_json

__all__ = ["add_physical_arguments", "add_impact_argument", "wants_physical", "hammer_from_args",
           "run_physical_orbits", "json_ready", "check_one_source"]


def add_physical_arguments(parser, config_help: str | None = None, *, hammers: bool = True) -> None:
    """Add an optional positional ``config`` (a TOML file; ``config_help`` its help, by default a
    hammer's keys) and ``--preset NAME`` to ``parser``; ``hammers``: whether the hammers' presets
    are among its choices (``impactbar drifter`` takes the drifters' only)."""
    hammer_presets = sorted(physical.PRESETS) if hammers else []
    hammer_help = f"a preset hammer in SI units: {', '.join(hammer_presets)}; or " if hammers else ""
    parser.add_argument(
        "config", nargs="?", default=None, metavar="CONFIG.toml",
        help=config_help or "a hammer in SI units (keys: [bar] E, density, length, diameter|area; "
             "[damping] coefficient|ratio; [stop] restitution|area; [drive] frequency; [force] kind = "
             "pneumatic|hydraulic|measured, ...; [model] n_modes); see "
             f"{docs_page('Real hammers in SI units')}")
    parser.add_argument(
        "--preset", default=None, metavar="NAME",
        choices=[*hammer_presets, *sorted(physical.DRIFTER_PRESETS), *sorted(physical.CIRCUIT_PRESETS)],
        help=f"{hammer_help}a drifter whose valve switches on the piston's position (theory section 10): "
             f"{', '.join(sorted(physical.DRIFTER_PRESETS))} (a config with a [valve] section is one too); "
             f"or a drifter with its oil circuit (theory section 11): "
             f"{', '.join(sorted(physical.CIRCUIT_PRESETS))} (a config with a [chambers] section)")


def add_impact_argument(parser) -> None:
    """Add ``--impact {paper,wave}`` (default: the config's ``[model] impact``, else ``paper``)."""
    parser.add_argument(
        "--impact", choices=tuple(LAWS), default=None,
        help="impact law: 'paper' (eq. 10, an instant velocity reversal) or 'wave' (the stop as a "
             "long rod, the contact solved by characteristics); default: a config's [model] "
             "impact, else 'paper'")


def wants_physical(args) -> bool:
    """Whether the command line named a config file or a preset (the SI path)."""
    return getattr(args, "config", None) is not None or getattr(args, "preset", None) is not None


def check_one_source(args) -> None:
    """Refuse a CONFIG.toml and ``--preset`` given together: each names a whole machine.

    Raises
    ------
    UsageError
    """
    if getattr(args, "config", None) is not None and getattr(args, "preset", None) is not None:
        raise UsageError("CONFIG.toml and --preset cannot be used together: each names the whole "
                         "machine; give one")


def hammer_from_args(args) -> physical.Hammer:
    """The hammer named by ``args.config`` or ``args.preset`` (exactly one).

    Raises
    ------
    ValueError
        Neither or both given, or an invalid config.
    """
    check_one_source(args)
    config, name = getattr(args, "config", None), getattr(args, "preset", None)
    if config is None and name is None:
        raise ValueError("give one of CONFIG.toml and --preset NAME")
    hammer = physical.preset(name) if name is not None else physical.load_config(config)
    impact = getattr(args, "impact", None)  # --impact overrides the config's [model] impact
    return hammer if impact is None else dataclasses.replace(hammer, impact=impact)


def run_physical_orbits(args) -> int:
    """``impactbar orbits CONFIG.toml | --preset NAME [--json]``: the one-impact periodic motions
    of a hammer with their SI figures, as a table or (with ``--json``) as JSON on stdout.

    The JSON echoes the inputs (``mass_kg``, ``mean_force_N``, ``frequency_Hz``,
    ``restitution``, ...) at the top level and lists the orbits under ``orbits``, each with
    ``impact_velocity_m_s``, ``impact_energy_J``, ``impact_power_kW``, ``admissible``, ``stable``,
    ``max_abs_multiplier`` and more. Warnings (long impacts) go to stderr and into ``warnings``.
    """
    hammer = hammer_from_args(args)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        found = physical.orbits(hammer)
    notes = [str(w.message) for w in caught]
    for note in notes:
        print(f"warning: {note}", file=sys.stderr)
    if getattr(args, "json", False):
        out = hammer.to_dict()
        out["warnings"] = notes
        out["orbits"] = [o.to_dict() for o in found]
        print_json(out)
        return 0
    print(format_table(hammer, found))
    return 0


def format_table(hammer: physical.Hammer, found) -> str:
    """A plain-text report: the hammer, then one row per orbit."""
    h = hammer
    lines = [
        f"hammer {h.name or '(unnamed)'}: piston {h.mass_kg:.3g} kg, {h.bar.describe()}",
        f"  drive {h.frequency_Hz:.4g} Hz, blows {h.blow_frequency_Hz:.4g} Hz, mean force "
        f"{h.mean_force_N:.4g} N, R = {h.R:.4g}, damping ratio {h.damping_ratio:.3g}",
        f"  dimensionless: s = {h.s:.5g}, d = {h.d:.5g}, R = {h.R:.5g}, N = {h.n_modes}, "
        f"p0 = {h.load.p0:.5g}",
        f"  contact 2L/c = {h.contact_duration_s * 1e6:.4g} us = {h.contact_fraction:.2%} of the "
        f"period; rigid-limit impact velocity {h.rigid_impact_velocity_m_s:.4g} m/s",
    ]
    fit = h.fourier_fit
    if fit is not None:
        lines.append(f"  measured force: {fit.n_harmonics} harmonics, max error "
                     f"{fit.max_error_N:.4g} N = {fit.relative_error:.2%} of the swing "
                     f"(tolerance {fit.tolerance:.2%})")
    if not found:
        lines.append("no one-impact periodic motion (one impact a drive period): the motion may chatter, "
                     "strike several times a period or settle into a longer cycle; `impactbar simulate "
                     "CONFIG` follows it from rest and names the cycle it settles into")
        return "\n".join(lines)
    lines.append(f"  impact law: {h.impact}")
    head, *rows = physical.PhysicalOrbit.fields.select("cli").table(found, width=2)  # declared columns
    lines += [head, "-" * len(head), *rows]
    if getattr(h, "drill", None) is not None:  # the rod-rock law: drilling per blow (theory §4d)
        head, *rows = physical.PhysicalOrbit.fields.select("cli_rock").table(found, width=2)
        lines += ["drilling per blow (work on rock, permanent penetration, rate at the blow "
                  "frequency, efficiency without and with the rebound)", head, "-" * len(head), *rows]
    return "\n".join(lines)
