"""How a SI value of a config key is shown to a person: in the unit the config wrote the key in, else in
the key table's display unit (MPa, mm, L, L/min, ...), one function for every message, repr and line of
text. Machine outputs (JSON, stores, dicts of results) stay in SI.
"""

from __future__ import annotations

import math
import re

__all__ = ["display_unit", "written_unit", "format_si", "format_key", "config_quantity", "written_quantity"]

#: The key table's display unit of each SI unit: ``SI unit -> (factor from SI, display unit)``.
DISPLAY_UNITS = {"m": (1e3, "mm"), "Pa": (1e-6, "MPa"), "m**3": (1e3, "L"), "m**3/s": (6e4, "L/min"),
                 "m**2": (1e4, "cm^2"), "s": (1e3, "ms"), "W": (1e-3, "kW")}

_UNIT = re.compile(r"^\s*[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|nan|inf)\s*(.*?)\s*$", re.IGNORECASE)


def display_unit(unit: str) -> tuple[float, str]:
    """The factor from SI and the name of the display unit of the SI ``unit``.

    Examples
    --------
    >>> from impactbar.physical.display_units import display_unit
    >>> display_unit("m**3/s"), display_unit("N")
    ((60000.0, 'L/min'), (1.0, 'N'))
    """
    return DISPLAY_UNITS.get(unit, (1.0, unit.replace("**", "^")))


def written_unit(value) -> str | None:
    """The unit part of a config value written as a string (``"80 L/min"`` -> ``"L/min"``), ``None``
    for a number or a string without a unit."""
    if not isinstance(value, str):
        return None
    m = _UNIT.match(value)
    return m.group(1) or None if m else None


def _factor(si_unit: str, unit: str) -> float | None:
    """The factor from ``si_unit`` to ``unit``, ``None`` where pint cannot convert."""
    from .units import registry

    try:
        return float(registry().Quantity(1.0, si_unit).to(unit).magnitude)
    except Exception:  # pint: an undefined unit or another dimension
        return None


def format_si(value: float, unit: str, written=None, digits: int = 6) -> str:
    """A SI ``value`` of a key as a person reads it: in the unit of ``written`` (the config's own value
    of the key, e.g. ``"80 L/min"``) where it has one that is not the SI unit itself, else in the
    key table's display unit.

    Parameters
    ----------
    value : float
        The value in ``unit``.
    unit : str
        Its SI unit (``"m**3/s"``; ``""`` for a dimensionless key).
    written : str or float, optional
        The config's value of the key; its unit is the one shown.
    digits : int
        Significant digits.

    Returns
    -------
    str

    Examples
    --------
    >>> from impactbar.physical.display_units import format_si
    >>> format_si(0.0015545502243099316, "m**3/s", "80 L/min"), format_si(-0.00010000000000000003, "m**3")
    ('93.273 L/min', '-0.1 L')
    >>> format_si(0.02, "m", "0.03 m"), format_si(0.5, "")
    ('20 mm', '0.5')
    """
    if unit == "":
        return f"{value:.{digits}g}"
    wrote = written_unit(written)
    factor = _factor(unit, wrote) if wrote and wrote.replace("^", "**") != unit else None
    if factor is None:
        factor, wrote = display_unit(unit)
    return f"{value * factor:.{digits}g} {wrote}"


def format_key(value: float, unit: str, config: dict, key: str, digits: int = 6) -> str:
    """A SI ``value`` of the dotted ``key`` as a person reads it: :func:`format_si` in the unit the
    ``config`` writes the key in, in the key table's display unit where the config leaves it out.

    Examples
    --------
    >>> from impactbar.physical.display_units import format_key
    >>> config = {"chambers": {}, "supply": {"pump_flow": "1.2 L/s", "relief_pressure": "250 bar"}}
    >>> format_key(0.00125, "m**3/s", config, "supply.pump_flow")
    '1.25 L/s'
    >>> format_key(2.4e7, "Pa", config, "supply.relief_pressure")
    '240 bar'
    >>> format_key(5e-4, "m**3", config, "accumulator.volume")  # left out: the display unit
    '0.5 L'
    """
    written = config
    for part in key.split("."):  # (the dotted key's value as written; None where the config leaves it out)
        if isinstance(written, dict):
            written = written.get(part)
        elif isinstance(written, list) and part.isdigit() and int(part) < len(written):
            written = written[int(part)]
        else:
            written = None
    return format_si(value, unit, written if isinstance(written, str | int | float) else None, digits)


def config_quantity(x: float, unit: str):
    """An SI value as a config takes it: the float's repr with its unit (exact), a bare float for a
    dimensionless key.

    Examples
    --------
    >>> from impactbar.physical.display_units import config_quantity
    >>> config_quantity(0.0215, "m"), config_quantity(0.2, "")
    ('0.0215 m', 0.2)
    """
    return float(x) if unit == "" else f"{float(x)!r} {unit}"


def written_quantity(value: float, unit: str, written):
    """A SI ``value`` as a config value in the unit of ``written`` (the config's own value of the key),
    written so that reading it back gives ``value`` exactly; else its SI repr
    (:func:`~impactbar.physical.design_keys.config_quantity`).

    Examples
    --------
    >>> from impactbar.physical.display_units import written_quantity
    >>> written_quantity(0.0015545502243099316, "m**3/s", "80 L/min")
    '93.27301345859587 L/min'
    >>> written_quantity(0.0215, "m", 0.02)  # a config without a unit of its own: SI
    '0.0215 m'

    A value that no string in the written unit reads back to exactly (rare) stays in SI.
    """
    from .units import to_si

    wrote = written_unit(written)
    factor = _factor(unit, wrote) if unit and wrote and wrote.replace("^", "**") != unit else None
    if factor is not None:
        import numpy as np

        y = value * factor
        # the shortest that reads back exactly, then the floats a few ulps either side
        texts = [f"{y:.{digits}g} {wrote}" for digits in range(6, 18)]
        lo = hi = y
        near = [y]
        for _ in range(4):
            lo, hi = float(np.nextafter(lo, -math.inf)), float(np.nextafter(hi, math.inf))
            near = [lo, *near, hi]
        texts += [f"{v!r} {wrote}" for v in near]
        for text in texts:
            if to_si("value", text, unit, "") == value:
                return text
    return config_quantity(value, unit)
