"""The keys of a hammer configuration (TOML file or nested dict), their checks, and the presets' data.

Nothing here builds a :class:`~impactbar.physical.Hammer`: :meth:`Hammer.from_config`,
:func:`~impactbar.physical.load_config` and :func:`~impactbar.physical.preset` (in
:mod:`impactbar.physical.hammer`) do, with these parsers, so the two modules do not import each other.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from .._shared.validate import check_real
from . import tree
from .forces import Force, HydraulicForce, MeasuredForce, PneumaticForce
from .units import to_si

# --------------------------------------------------------------------------------------------
# configuration
# --------------------------------------------------------------------------------------------
# a hammer's sections and the keys of each, as the parameter tree declares them (the drill string's
# sections checked by its own reader, impactbar.physical.rock), and the force's keys of each kind
_SECTIONS = {name: keys for name, keys in tree.config_sections("hammer").items()
             if name not in ("rod", "rod.segments", "bit", "rock")}
_FORCE_KEYS = {kind: {f.name for f in tree.MACHINES["hammer"].values()
                      if f.section == "force" and f.needs == kind}
               for kind in ("pneumatic", "hydraulic", "measured")}
_REQUIRED = {"bar", "stop", "drive", "force"}


class _ConfigKind(NamedTuple):
    """A kind of configuration: the section that only it has, and how a message names it."""

    section: str | None
    what: str


#: The kinds of configuration in SI units, each told apart by a section that only it has (the first
#: found decides; a configuration with neither is a hammer's), with how a message names each.
CONFIG_KINDS = {
    "circuit": _ConfigKind("chambers", "a drifter with its oil circuit (it has a [chambers] section; "
                                       "theory §11)"),
    "drifter": _ConfigKind("valve", "a drifter whose valve switches on the piston's position (it has a "
                                    "[valve] section and no [chambers]; theory §10)"),
    "hammer": _ConfigKind(None, "a hammer under a periodic force (it has no [valve] or [chambers] section)"),
}


def config_kind(config: dict) -> str:
    """Which machine a configuration describes: ``"circuit"``, ``"drifter"`` or ``"hammer"``
    (:data:`CONFIG_KINDS`).

    Raises
    ------
    ValueError
        Not a mapping of sections, or a sweep spec (its top-level ``task``).
    """
    if not isinstance(config, dict):
        raise ValueError(f"a configuration must be a mapping of sections; got {type(config).__name__}")
    if "task" in config:
        raise ValueError("this is a sweep spec (it has a top-level 'task'), not a machine in SI units: "
                         "run it with 'impactbar sweep'")
    return next(kind for kind, k in CONFIG_KINDS.items() if k.section is None or k.section in config)


def read_as(kind: str, path, exc: ValueError) -> ValueError:
    """``exc`` with the file and the kind of machine it was read as in front: what was wrong is
    then read against the right keys (a misspelt ``[chambers]`` makes a hammer of a circuit)."""
    return ValueError(f"{path}: read as {CONFIG_KINDS[kind].what}: {exc}")


def read_toml(path) -> dict:
    """The TOML file at ``path`` as a nested dict.

    Raises
    ------
    ValueError
        A missing or unreadable file, invalid TOML, or nesting too deep to read.
    """
    import tomllib

    path = Path(path)
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except OSError as exc:
        raise ValueError(f"cannot read the configuration {str(path)!r}: {exc.strerror}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{str(path)!r} is not valid TOML: {exc}") from exc
    except RecursionError as exc:  # tomllib recurses into nested arrays and inline tables
        raise ValueError(f"{str(path)!r}: arrays or tables nested too deeply for a configuration"
                         ) from exc


def _section(config: dict, name: str, allowed: set | None = None) -> dict:
    """The table ``[name]`` of ``config`` (empty if absent), refused unless a table whose keys are
    among ``allowed`` (default: the hammer's keys of that section), naming the first unknown key."""
    allowed = _SECTIONS[name] if allowed is None else allowed
    sec = config.get(name, {})
    if not isinstance(sec, dict):
        raise ValueError(f"[{name}] must be a table of keys; got {sec!r}")
    unknown = sorted(set(sec) - allowed)
    if unknown:
        raise ValueError(f"unknown key {name}.{unknown[0]}; allowed in [{name}]: "
                         f"{', '.join(sorted(allowed))}")
    return sec


def _need(sec: dict, section: str, key: str):
    if key not in sec:
        raise ValueError(f"missing key {section}.{key}")
    return sec[key]


def _dimensionless(name: str, value, **rng) -> float:
    return check_real(name, to_si(name, value, "", "0.3"), **rng)


def _force_from_config(sec: dict, base_dir) -> Force:
    kind = _need(sec, "force", "kind")
    if kind not in _FORCE_KEYS:
        raise ValueError(f"force.kind must be one of {', '.join(sorted(_FORCE_KEYS))}; "
                         f"got {kind!r}")
    extra = sorted(set(sec) - _FORCE_KEYS[kind] - {"kind"})
    if extra:
        raise ValueError(f"key force.{extra[0]} does not apply to force.kind = {kind!r}; allowed: "
                         f"{', '.join(sorted(_FORCE_KEYS[kind]))}")

    def force(key):
        return tree.read_si(f"force.{key}", _need(sec, "force", key), "hammer")

    if kind == "pneumatic":
        return PneumaticForce(force("mean"), force("amplitude"), sec.get("k", 1))
    if kind == "hydraulic":
        return HydraulicForce(force("high"), force("low"),
                              _dimensionless("force.fraction", _need(sec, "force", "fraction")))
    path = _need(sec, "force", "csv")
    if not isinstance(path, str):
        raise ValueError(f"force.csv must be a file path; got {path!r}")
    p = Path(path)
    if not p.is_absolute() and base_dir is not None:
        p = Path(base_dir) / p
    return MeasuredForce.from_csv(p, tolerance=_dimensionless("force.tolerance",
                                                              sec.get("tolerance", 0.01)),
                                  max_harmonics=sec.get("max_harmonics", 256))


# --------------------------------------------------------------------------------------------
# presets
# --------------------------------------------------------------------------------------------
# Both presets use a steel piston: E = 210 GPa and rho = 7850 kg/m^3 are the textbook values of
# carbon and low-alloy steel (e.g. EN 1993-1-1, section 3.2.6: E = 210 000 N/mm^2). Their rod,
# the stop, is a long steel bar (the shank adapter / drill steel), so R follows from its area.
# The forces are chosen from the rigid-limit identity v = F_mean / (f m (1 + R)) (theory §4) to
# give a typical impact velocity, and checked to give an admissible orbit.
PRESETS: dict[str, dict] = {
    # A pneumatic top-hammer rock drill (the class of a heavy hand-held drill or a light drifter).
    "pneumatic-drill": {
        "name": "pneumatic-drill",
        "bar": {
            "E": "210 GPa",  # steel, see above
            "density": "7850 kg/m^3",  # steel
            # 200 mm x 40 mm: m = 7850 * pi/4 * 0.04^2 * 0.2 = 1.97 kg, a piston of "a few kg"
            # (pistons of hand-held and light pneumatic drills weigh about 1-3 kg)
            "length": "200 mm",
            "diameter": "40 mm",
        },
        # A 45 mm shank against the 40 mm piston: R = (45^2 - 40^2)/(45^2 + 40^2) = 0.117.
        "stop": {"area": "15.904 cm^2"},  # pi/4 * 4.5^2 cm^2
        # 40 Hz = 2400 blows per minute, inside the 2000-3000 bpm of pneumatic drills; a jackhammer
        # strikes about 25 times a second (ritchiewiki.com, "Pneumatic Drill").
        "drive": {"frequency": "40 Hz"},
        # Mean force 800 N: about 0.63 MPa (the usual 6-7 bar shop air) on the 12.6 cm^2 piston
        # face. It gives v = 800 / (40 * 1.97 * 1.117) = 9.1 m/s (energy 81 J, power 3.2 kW),
        # inside the 5-12 m/s of air hammers. Amplitude 2150 N puts p0/p1 = 0.372 inside the
        # paper's stable band (theory §6: 0.337 < p0/p1 < 0.403 at R = 0.117).
        "force": {"kind": "pneumatic", "mean": "800 N", "amplitude": "2150 N"},
        # Viscous friction of the guided piston, unknown in practice: 2.4 N s/m makes
        # 2 pi d = 0.03, the damped case of the paper's Fig. 5.
        "damping": {"coefficient": "2.4 N*s/m"},
        "model": {"n_modes": 16},
    },
    # A hydraulic top-hammer rock drill (drifter) with a differential piston.
    "hydraulic-drill": {
        "name": "hydraulic-drill",
        "bar": {
            "E": "210 GPa",
            "density": "7850 kg/m^3",
            # A long slender piston, 450 mm x 45 mm: m = 5.6 kg. Hydraulic drifter pistons are
            # longer and heavier than pneumatic ones (a few kg up to about 10 kg).
            "length": "450 mm",
            "diameter": "45 mm",
        },
        # A 56 mm shank: R = (56^2 - 45^2)/(56^2 + 45^2) = 0.215. (With a 52 or 57 mm shank the
        # struck end's ringing after the jumps of the square wave grazes the stop between impacts
        # and the one-impact orbits are inadmissible: see theory §5.)
        "stop": {"area": "24.630 cm^2"},  # pi/4 * 5.6^2 cm^2
        # 55 Hz: hydraulic drills strike at 40-70 Hz; a stress-wave bench study measured up to
        # 62 Hz and up to 346 J per blow at 18-23 MPa ("Influence of piston mass and working
        # pressure on the impact performance of a hydraulic rock drill using the stress wave
        # method"; see also Ma et al., Adv. Mech. Eng. 11(4), 2019, doi:10.1177/1687814019841486).
        "drive": {"frequency": "55 Hz"},
        # Differential piston: the front annulus A_f is always at supply pressure p, the rear area
        # A_r = 2 A_f is switched between p and tank, so the net force is +p A_f (forward stroke)
        # and -p A_f (return): the paper's symmetric square wave (eq. 34). p = 20 MPa on
        # A_f = 10 cm^2 gives +-20 kN. A fraction 0.58 of the period forward (kappa = 1.16) gives
        # a mean of 3.2 kN and a rigid-limit v = 3200 / (55 * 5.62 * 1.215) = 8.5 m/s (204 J,
        # 11 kW); the flexible piston's struck end arrives at 9.3 m/s in the admissible orbit.
        # That orbit is unstable, as every hydraulic one-impact orbit (paper eq. 41): simulated
        # from rest the motion does not settle (paper Section 5). A real drifter switches its
        # valve on the piston's position, which this time-periodic load does not represent.
        "force": {"kind": "hydraulic", "high": "20 kN", "low": "-20 kN", "fraction": 0.58},
        # Oil-film damping of the piston guides, unknown in practice: 9 N s/m makes 2 pi d = 0.03,
        # the damped case of the paper's Fig. 8.
        "damping": {"coefficient": "9 N*s/m"},
        "model": {"n_modes": 16},
    },
}
