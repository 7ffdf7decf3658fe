"""One reader for every configuration in SI units: a TOML file in; the hammer, the drifter or the
drifter with its oil circuit that it describes out, told apart by their sections
(:data:`~impactbar.physical.config.CONFIG_KINDS`)."""

from __future__ import annotations

from pathlib import Path

from .circuit import _KEYS as _CIRCUIT_KEYS
from .circuit import CircuitDrifter
from .config import _SECTIONS as _HAMMER_KEYS
from .config import CONFIG_KINDS, config_kind, read_as, read_toml
from .drifter import _KEYS as _DRIFTER_KEYS
from .drifter import Drifter
from .hammer import Hammer, _hammer_from_config
from .rock import _SEGMENT_KEYS, ROCK_SECTIONS

__all__ = ["load", "config_keys"]

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
    ['cells_per_piston', 'feed', 'k', 'k_u', 'method']
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
        A missing or malformed file; a sweep spec (``impactbar sweep`` reads those); an unknown or
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
    path = Path(path)
    config = read_toml(path)
    kind = config_kind(config)
    try:
        if kind == "circuit":
            return CircuitDrifter.from_config(config)
        if kind == "drifter":
            return Drifter.from_config(config)
        return _hammer_from_config(config, path.parent)
    except ValueError as exc:
        raise read_as(kind, path, exc) from exc
