"""One reader for every configuration in SI units: a TOML file in; the hammer, the drifter or the
drifter with its oil circuit that it describes out, told apart by their sections
(:data:`~impactbar.physical.config.CONFIG_KINDS`)."""

from __future__ import annotations

import copy
import os
from pathlib import Path

from .circuit import _KEYS as _CIRCUIT_KEYS
from .circuit import CIRCUIT_PRESETS, CircuitDrifter
from .config import _SECTIONS as _HAMMER_KEYS
from .config import CONFIG_KINDS, PRESETS, config_kind, read_as, read_toml
from .drifter import _KEYS as _DRIFTER_KEYS
from .drifter import DRIFTER_PRESETS, Drifter
from .hammer import Hammer, _hammer_from_config
from .rock import _SEGMENT_KEYS, ROCK_SECTIONS

__all__ = ["load", "config_keys", "read_config", "build", "with_values", "config_value"]

_KEYS = {"circuit": _CIRCUIT_KEYS, "drifter": _DRIFTER_KEYS, "hammer": _HAMMER_KEYS}


def config_keys(kind: str) -> dict[str, list[str]]:
    """The sections of a configuration of one kind of machine and the keys each takes, from the
    tables its reader checks against (the drill string's and the rock's sections included, which
    every kind takes; ``rod.segments`` is the array of tables ``[[rod.segments]]``).

    Parameters
    ----------
    kind : {"hammer", "drifter", "circuit"}
        A hammer under a periodic force, a drifter whose valve switches on the piston's position, a
        drifter with its oil circuit (:data:`~impactbar.physical.config.CONFIG_KINDS`).

    Returns
    -------
    dict
        Section name to its keys, sorted; the top-level ``name`` is allowed besides.

    Raises
    ------
    ValueError
        An unknown kind.

    Examples
    --------
    >>> from impactbar.physical import config_keys
    >>> config_keys("circuit")["accumulator"]
    ['polytropic_exponent', 'precharge', 'volume']
    >>> config_keys("drifter")["rock"]
    ['cells_per_piston', 'contact_events', 'driven_end', 'feed', 'k', 'k_u', 'method']
    """
    if kind not in _KEYS:
        raise ValueError(f"kind must be one of {', '.join(CONFIG_KINDS)}; got {kind!r}")
    out = {name: sorted(keys) for name, keys in _KEYS[kind].items()}
    out.update({name: sorted(keys) for name, keys in ROCK_SECTIONS.items() if name != "rod"})
    out["rod.segments"] = sorted(_SEGMENT_KEYS)
    return out


def load(path) -> Hammer | Drifter | CircuitDrifter:
    """Read any machine in SI units from a TOML file: a hammer, a drifter or a drifter with its oil
    circuit, whichever the file describes.

    A file with a ``[chambers]`` section is a drifter with its oil circuit (theory §11,
    :meth:`CircuitDrifter.from_config`); else one with a ``[valve]`` section is a drifter whose valve
    switches on the piston's position (theory §10, :meth:`Drifter.from_config`); else it is a hammer
    under a periodic force (:func:`load_config`, whose keys are ``[drive]`` and ``[force]``). Each
    takes a drill string and the rock (``[[rod.segments]]``, ``[bit]``, ``[rock]``).

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file. A measured force's relative ``force.csv`` is taken from its folder.

    Returns
    -------
    Hammer, Drifter or CircuitDrifter

    Raises
    ------
    ValueError
        Not a path; a missing or malformed file; a sweep spec (``impactbar sweep`` reads those); an unknown or
        missing key or a value out of range, named, after the file and the kind of machine it was
        read as (a misspelt section can change the kind: the message says which keys were expected).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from impactbar.physical import load
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "drifter.toml"
    >>> text = '''
    ... [bar]
    ... E = "210 GPa"
    ... density = "7850 kg/m^3"
    ... length = "448.54236 mm"
    ... diameter = "45 mm"
    ... [stop]
    ... restitution = 0.215
    ... [valve]
    ... supply_pressure = "20 MPa"
    ... stroke_area = "2.8 cm^2"
    ... return_area = "2.8 cm^2"
    ... switch_out = "21.5 mm"
    ... '''
    >>> _ = path.write_text(text)
    >>> drifter = load(path)
    >>> type(drifter).__name__, round(drifter.orbit().blow_frequency_Hz, 2)
    ('Drifter', 47.19)
    >>> _ = path.write_text(text.replace("switch_out", "switch_at"))
    >>> load(path)
    Traceback (most recent call last):
    ...
    ValueError: ...drifter.toml: read as a drifter whose valve switches on the piston's position
    (it has a [valve] section and no [chambers]; theory §10): unknown key valve.switch_at; allowed in
    [valve]: delay, return_area, stroke_area, supply_pressure, switch_out
    """
    if not isinstance(path, str | os.PathLike):
        raise ValueError(f"path must be a TOML file's path (a str or os.PathLike); got {path!r} "
                         f"({type(path).__name__})")
    path = Path(path)
    return build(read_toml(path), path.parent, where=str(path))

def read_config(source) -> tuple[dict, Path | None]:
    """A machine's configuration from a TOML file, a preset's name or a nested dict.

    Parameters
    ----------
    source : str, os.PathLike or dict
        A path to a TOML file; the name of a preset (:data:`~impactbar.physical.PRESETS`,
        :data:`~impactbar.physical.DRIFTER_PRESETS`, :data:`~impactbar.physical.CIRCUIT_PRESETS`);
        or the configuration itself.

    Returns
    -------
    config : dict
        A deep copy (changing it changes nothing else).
    folder : pathlib.Path or None
        The file's folder (a measured force's relative ``force.csv`` is read from it), else None.

    Raises
    ------
    ValueError
        A source that is neither a readable TOML file, a preset nor a dict.

    Examples
    --------
    >>> from impactbar.physical.loader import read_config
    >>> config, folder = read_config("circuit-drifter")
    >>> config["supply"]["pump_flow"], folder
    ('70 L/min', None)
    """
    if isinstance(source, dict):
        return copy.deepcopy(source), None
    presets = {**PRESETS, **DRIFTER_PRESETS, **CIRCUIT_PRESETS}
    if isinstance(source, str) and source in presets:
        return copy.deepcopy(presets[source]), None
    if not isinstance(source, (str, Path)):
        raise ValueError("config must be a TOML file, a preset's name or a dict; got "
                         f"{type(source).__name__}")
    path = Path(source)
    if not path.exists() and not path.suffix:
        raise ValueError(f"config {str(source)!r} is neither a file nor a preset; presets: "
                         f"{', '.join(sorted(presets))}")
    return read_toml(path), path.parent


def build(config: dict, folder=None, *, where="config") -> Hammer | Drifter | CircuitDrifter:
    """The machine a configuration describes: a drifter with its oil circuit (it has
    ``[chambers]``), a drifter with a position-switched valve (``[valve]``) or a hammer.

    Parameters
    ----------
    config : dict
        Sections of keys with units, as in a TOML file.
    folder : path-like, optional
        Where a measured force's relative ``force.csv`` lies.
    where : str, optional
        What the config is called in a message (the file's path).

    Returns
    -------
    Hammer, Drifter or CircuitDrifter
        Built by the kind's own reader (its ``from_config``, or :func:`load_config`).

    Raises
    ------
    ValueError
        A key or value the machine's reader refuses (named, after the kind of machine).
    """
    kind = config_kind(config)
    try:
        if kind == "circuit":
            return CircuitDrifter.from_config(config)
        if kind == "drifter":
            return Drifter.from_config(config)
        return _hammer_from_config(config, folder)
    except ValueError as exc:
        raise read_as(kind, where, exc) from exc


def _locate(config: dict, key: str, *, create: bool):
    """The mapping (or list) holding the dotted ``key`` and the last part of the key."""
    if not isinstance(key, str) or not key or "." not in key:
        raise ValueError(f"a config key is 'section.key' (e.g. 'supply.pump_flow'); got {key!r}")
    kind = config_kind(config)
    sections = config_keys(kind)
    parts = key.split(".")
    if parts[0] == "rod" and len(parts) == 4 and parts[1] == "segments":
        allowed = sections["rod.segments"]
        segs = config.get("rod", {}).get("segments", [])
        if not parts[2].isdigit() or int(parts[2]) >= len(segs):
            raise ValueError(f"{key}: the rod has {len(segs)} segment(s), numbered from 0")
        if parts[3] not in allowed:
            raise ValueError(f"unknown key {key}; a rod segment takes {', '.join(allowed)}")
        return segs[int(parts[2])], parts[3]
    if parts[0] == "parts" and kind == "circuit":
        return _locate_part(config, key)
    if len(parts) != 2 or parts[0] not in sections:
        raise ValueError(f"unknown key {key!r} of {kind!r} config; sections: {', '.join(sorted(sections))}")
    section, name = parts
    if name not in sections[section]:
        raise ValueError(f"unknown key {key}; allowed in [{section}]: {', '.join(sections[section])}")
    if section not in config:
        if not create:
            raise ValueError(f"{key}: the config has no [{section}] section")
        config[section] = {}
    return config[section], name


def _locate_part(config: dict, key: str):
    """The table of a part added to the circuit (``parts.<name>.<key>``) and the key."""
    from .circuit_parts import part_keys, split_key

    (name, field), tables = split_key(key) or ("", ""), config.get("parts", {})
    if not name or not isinstance(tables, dict) or not isinstance(tables.get(name), dict):
        raise ValueError(f"{key}: a part's key is parts.<name>.<key>, of a part [parts.<name>] the config "
                         f"has ({', '.join(tables) if isinstance(tables, dict) and tables else 'none'})")
    allowed = part_keys(tables[name].get("kind"))[1:]  # (its kind is not changed)
    if field not in allowed:
        raise ValueError(f"unknown key {key}; allowed in [parts.{name}]: {', '.join(allowed)}")
    return tables[name], field


def config_value(config: dict, key: str):
    """The value of a dotted key as the config gives it (``"80 L/min"``, a number or a list).

    Raises
    ------
    ValueError
        An unknown key, or one the config leaves out.

    Examples
    --------
    >>> from impactbar.physical.loader import config_value, read_config
    >>> config_value(read_config("circuit-drifter")[0], "accumulator.precharge")
    '10 MPa'
    """
    holder, name = _locate(config, key, create=False)
    if name not in holder:
        raise ValueError(f"{key} is not given in the config (its default applies)")
    return holder[name]


def with_values(config: dict, changes: dict) -> dict:
    """A copy of a configuration with values changed by dotted key (the original unchanged).

    Parameters
    ----------
    config : dict
        Sections of keys with units.
    changes : dict
        Dotted key (``"section.key"``, ``"rod.segments.<i>.<key>"``, or a part's
        ``"parts.<name>.<key>"``) to its new value with its
        unit (``"80 L/min"``, a pint quantity, or a number where the key is dimensionless).

    Returns
    -------
    dict
        The changed configuration; :func:`build` checks its values.

    Raises
    ------
    ValueError
        A key the machine's configuration does not take (the allowed ones listed), or a rod
        segment it does not have.

    Examples
    --------
    >>> from impactbar.physical.loader import build, read_config, with_values
    >>> config = with_values(read_config("circuit-drifter")[0], {"supply.pump_flow": "90 L/min"})
    >>> build(config).si["pump_flow_m3_s"] * 60e3
    90.0
    """
    if not isinstance(changes, dict):
        raise ValueError(f"changes must be a dict of dotted keys to values; got {type(changes).__name__}")
    out = copy.deepcopy(config)
    for key, value in changes.items():
        holder, name = _locate(out, key, create=True)
        holder[name] = value
    return out
