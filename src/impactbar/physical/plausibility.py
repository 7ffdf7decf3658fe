"""Plausibility of a circuit's configuration: a value far outside the typical range of its key is
warned of (:class:`ImplausibleValueWarning`), not refused; the model runs it as given.

The typical ranges are those of the table of the circuit's keys in the documentation ("Every key of
the circuit, with its typical range": a hydraulic top-hammer drifter of a few kilograms at some
20 MPa). *Far* is more than a factor :data:`FAR` beyond the range: below ``low / FAR`` or above
``high * FAR`` (a key whose range starts at 0 is never too small). Only keys the configuration gives
are checked (a default is not the user's value), and an accumulator of no volume is none.
"""

from __future__ import annotations

import contextlib
import sys
import warnings

from .tree import typical_ranges
from .units import to_si

__all__ = ["ImplausibleValueWarning", "FAR", "TYPICAL", "implausible", "warn_implausible",
           "warnings_once"]

#: How far outside its typical range a value is implausible: by more than this factor.
FAR = 4.0

#: Key: (low, high, SI unit, shown unit, factor from SI to the shown unit): the typical ranges the
#: parameter tree declares (:func:`impactbar.physical.tree.typical_ranges`; the documentation's
#: table of the circuit's keys, the pre-charge 0.4 to 0.9 of a working pressure of 15 to 25 MPa).
TYPICAL = typical_ranges()


class ImplausibleValueWarning(UserWarning):
    """A configuration's value far outside its key's typical range (:data:`TYPICAL`, :data:`FAR`)."""


def implausible(config: dict) -> list[str]:
    """One line per value of ``config`` far outside its key's typical range.

    Parameters
    ----------
    config : dict
        A circuit's configuration (sections of keys with units), its values already checked.

    Returns
    -------
    list of str
        Each naming the key, the value as given (and in the range's unit) and the typical range.

    Examples
    --------
    >>> from impactbar.physical.plausibility import implausible
    >>> lines = implausible({"supply": {"pump_flow": "85 L/s", "tank_pressure": "0.3 MPa"}})
    >>> print(lines[0])
    supply.pump_flow = '85 L/s' (5100 L/min) is far outside its typical range 40-150 L/min (beyond a factor 4)
    """
    out = []
    for key, (low, high, unit, shown, factor) in TYPICAL.items():
        section, name = key.split(".")
        given = config.get(section, {}).get(name) if isinstance(config.get(section), dict) else None
        if given is None:
            continue
        v = to_si(key, given, unit, "")
        if key == "accumulator.volume" and v == 0.0:  # (no accumulator)
            continue
        if (low > 0.0 and v < low / FAR) or v > high * FAR:
            out.append(f"{key} = {given!r} ({v * factor:.4g} {shown}) is far outside its typical range "
                       f"{low * factor:.4g}-{high * factor:.4g} {shown} (beyond a factor {FAR:g})")
    return out


def warn_implausible(config: dict) -> None:
    """Warn (:class:`ImplausibleValueWarning`) of each line of :func:`implausible`."""
    for line in implausible(config):
        warnings.warn(line, ImplausibleValueWarning, stacklevel=3)


@contextlib.contextmanager
def warnings_once(prefix: str):
    """Within it, an :class:`ImplausibleValueWarning` is printed once per key (the first value: a
    sweep or an optimisation builds many), as one line on stderr (``"<prefix>: warning: ..."``);
    other warnings as Python shows them."""
    seen: set[str] = set()
    with warnings.catch_warnings():
        show = warnings.showwarning

        def one_line(message, category, filename, lineno, file=None, line=None):
            if not issubclass(category, ImplausibleValueWarning):
                return show(message, category, filename, lineno, file, line)
            key = str(message).split(" ", 1)[0]
            if key not in seen:
                seen.add(key)
                print(f"{prefix}: warning: {message}", file=sys.stderr)

        warnings.showwarning = one_line
        warnings.simplefilter("always", ImplausibleValueWarning)
        yield
