"""Parsing of inputs written with units (``"210 GPa"``, ``"45 mm"``) into SI floats, through pint.

pint is imported lazily, on the first input that needs it, so the dimensionless core never needs it.
Every failure is a ``ValueError`` that names the input, the dimension it needs and an example.
"""

from __future__ import annotations

import functools
import math
import numbers
import re

import numpy as np

__all__ = ["to_si", "to_si_any", "registry"]


@functools.cache
def registry():
    """The package's pint ``UnitRegistry`` (created once), with ``bpm`` (blows per minute) added."""
    try:
        import pint
    except ImportError as exc:  # pragma: no cover - pint is in the test environment
        raise ImportError(
            "inputs with units need pint: pip install 'impactbar[units]'"
        ) from exc
    ureg = pint.UnitRegistry()
    # rock drills are rated in blows per minute; pint's own "rpm" is an angular speed (2 pi rad/min)
    ureg.define("blows_per_minute = 1 / minute = bpm")
    return ureg


_QUANTITY = re.compile(
    # the unit: names, powers, products and quotients only (no "#" comment, ";", "," or "+")
    r"^\s*([+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|nan|inf))\s*([\w\s*/^().°%-]*?)\s*$",
    re.IGNORECASE)


def _parse(name: str, value):
    """``value`` as a quantity of our registry; a bare real number becomes a dimensionless one."""
    ureg = registry()
    if isinstance(value, bool) or value is None:
        raise ValueError(f"{name} must be a number or a quantity with a unit; got {value!r}")
    if isinstance(value, numbers.Real | np.floating | np.integer):
        try:
            return ureg.Quantity(float(value), ""), True
        except OverflowError:  # an int past the floats' range
            raise ValueError(f"{name} must be a number within the floats' range; got {value!r}") from None
    if hasattr(value, "magnitude") and hasattr(value, "units"):  # pint, maybe another registry
        try:
            return ureg.Quantity(float(value.magnitude), str(value.units)), False
        except Exception as exc:
            raise ValueError(f"{name}: cannot read the quantity {value!r}: {exc}") from exc
    if isinstance(value, str):
        # one number, then a unit expression: no arithmetic, and no commas (pint would read the
        # decimal comma of "2,5 kN" as a thousands separator: 25 kN)
        m = _QUANTITY.match(value)
        if m is None:
            raise ValueError(
                f"{name}: cannot read {value!r}: write one number (decimal point, no thousands "
                "separators) followed by a unit, e.g. '2.5 kN'")
        number, unit = m.groups()
        try:
            q = ureg.Quantity(float(number), unit)
        except Exception as exc:  # pint raises several kinds (undefined unit, syntax)
            raise ValueError(f"{name}: cannot read the unit {unit!r} of {value!r}: {exc}") from exc
        return q, unit == ""
    raise ValueError(
        f"{name} must be a number or a string with a unit such as '45 mm'; got {value!r} "
        f"({type(value).__name__})"
    )


def _angle_free(name: str, q, value) -> None:
    units = dict(q.to_root_units().unit_items())
    if "radian" in units or "steradian" in units:
        raise ValueError(
            f"{name} must not be given in angular units (rad, rpm, ...): they hide a factor 2 pi; "
            f"got {value!r}. Write a frequency in Hz or bpm (blows per minute)"
        )


def to_si(name: str, value, unit: str, example: str, *, what: str | None = None) -> float:
    """Convert ``value`` to a float in ``unit``.

    Parameters
    ----------
    name : str
        Name of the input, for the error message (e.g. ``"bar.length"``).
    value : str, pint.Quantity or float
        ``"45 mm"``, a pint quantity, or a bare number; a bare number is accepted only when
        ``unit`` is dimensionless (``""``).
    unit : str
        Target unit, e.g. ``"m"``, ``"Pa"``, ``""`` for a dimensionless input.
    example : str
        An example value for the error message, e.g. ``"'45 mm'"``.
    what : str, optional
        The dimension in words (``"a length"``), for the error message.

    Returns
    -------
    float
        The magnitude in ``unit``, finite.

    Raises
    ------
    ValueError
        A bare number where a unit is needed, an unknown unit, the wrong dimension, an angular unit,
        or a value that is not finite. The message names ``name``.
    """
    q, bare = _parse(name, value)
    what = what or f"a quantity in {unit}"
    if bare and unit != "":
        raise ValueError(
            f"{name} needs a unit: it must be {what}, e.g. {example}; got the bare number {value!r}"
        )
    _angle_free(name, q, value)
    try:
        mag = q.to(unit).magnitude
    except Exception as exc:  # pint.DimensionalityError
        raise ValueError(
            f"{name} must be {what} (e.g. {example}); got {value!r}, of dimension "
            f"{q.dimensionality}"
        ) from exc
    try:
        v = float(mag)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a single value; got {value!r}") from exc
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite; got {value!r}")
    return v


def to_si_any(name: str, value, choices, example: str, what: str) -> tuple[float, str]:
    """Convert ``value`` to the first of several units whose dimension fits.

    Parameters
    ----------
    choices : sequence of str
        Candidate target units of different dimensions, e.g. ``("N*s/m", "N*s/m^2")``.

    Returns
    -------
    (float, str)
        The magnitude and the unit it was converted to.
    """
    q, bare = _parse(name, value)
    if bare:
        raise ValueError(f"{name} needs a unit: it must be {what}, e.g. {example}; got {value!r}")
    for unit in choices:
        try:
            return to_si(name, q, unit, example, what=what), unit
        except ValueError:
            continue
    raise ValueError(f"{name} must be {what} (e.g. {example}); got {value!r}, of dimension "
                     f"{q.dimensionality}")
