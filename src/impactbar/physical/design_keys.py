"""A design key: one dotted config key of a machine, its SI unit and its values, read and set the one
way that every caller varying a config uses (the design maps of ``impactbar sweep``,
:mod:`impactbar.sweeps.map_spec`, and the optimiser, :func:`~impactbar.physical.optimize_drifter`).

A key is any one that :func:`~impactbar.physical.loader.config_value` finds in the config (its
sections' keys, ``rod.segments.<i>.<key>``); its SI unit is the one
:data:`~impactbar.physical.tree.FIELDS` declares, else the base units of the config's own
value (``""`` for a bare number); a value is written back as its float's repr with that unit
(:func:`~impactbar.physical.display_units.config_quantity`), and whether the machine takes it is what
:func:`~impactbar.physical.loader.build` of :func:`~impactbar.physical.loader.with_values` says.
No table of its own decides which keys may vary.
"""

from __future__ import annotations

from .config import config_kind
from .display_units import config_quantity
from .loader import config_value
from .tree import FIELDS, integer_keys
from .tree import declared as declared_field
from .units import to_si

__all__ = ["INTEGER_KEYS", "design_key", "key_unit", "key_value", "design_bounds"]

#: the config keys that take integers (declared so in :mod:`impactbar.physical.tree`): a design map's
#: axis over one takes integer values (stored as integers); the optimiser enumerates the integers
#: within their bounds (:mod:`~impactbar.physical.optimize_integers`)
INTEGER_KEYS = integer_keys()


def key_unit(key: str, base, declared: str | None = None) -> str:
    """The SI unit of a dotted key whose config value is ``base``: the one the parameter tree
    declares (:data:`~impactbar.physical.tree.FIELDS`) where the value has its dimension, else the
    value's own base units.

    Parameters
    ----------
    key : str
        The dotted key (``"supply.pump_flow"``, ``"stop.restitution"``).
    base : str, float or list
        The config's own value of the key (:func:`~impactbar.physical.loader.config_value`).
    declared : str, optional
        The unit declared for the key by its kind of machine (:func:`~impactbar.physical.tree.declared`)
        or by a part (:func:`~impactbar.physical.circuit_parts.declared_unit`); default: the
        parameter tree's declaration of a drifter with its oil circuit, if any.

    Returns
    -------
    str
        pint's spelling (``"m**3/s"``); ``""`` for a bare number.

    Raises
    ------
    ValueError
        A value that is not a quantity (``"<key>: the config's value ... is not a quantity: ..."``).

    Examples
    --------
    >>> from impactbar.physical.design_keys import key_unit
    >>> key_unit("chambers.rear_area", "5.6 cm^2"), key_unit("stop.restitution", 0.215)
    ('m**2', '')
    >>> key_unit("supply.pump_flow", "70 L/min")
    'm**3/s'
    >>> key_unit("damping.coefficient", "9 N*s/m"), key_unit("damping.coefficient", "20 N*s/m^2")
    ('N*s/m', 'kg/m/s')
    """
    from .units import registry

    if not isinstance(base, str):
        return ""
    try:
        q = registry().Quantity(base)
    except Exception as exc:  # pint raises several kinds
        raise ValueError(f"{key}: the config's value {base!r} is not a quantity: {exc}") from None
    if declared is None and declared_field(key) is not None:
        declared = declared_field(key).unit
    if declared and q.is_compatible_with(declared):
        return declared  # (a hammer's damping per unit length is another quantity: its own)
    return "" if q.dimensionless else f"{q.to_base_units().units:~}".replace(" ", "")


def key_value(name: str, value, unit: str, base) -> float:
    """``value`` (a quantity string, or a number for a dimensionless key) in the key's ``unit``,
    refused as the config's own value ``base`` shows it should be written.

    Parameters
    ----------
    name : str
        What the value is called in a message (``"[axes] supply.pump_flow"``).
    value : str or float
    unit : str
        The key's SI unit (:func:`key_unit`).
    base : str or float
        The config's own value of the key.

    Returns
    -------
    float
        The value in ``unit``.

    Raises
    ------
    ValueError
        A value of the wrong dimension, a bare number for a key with a unit, one not finite.

    Examples
    --------
    >>> from impactbar.physical.design_keys import key_value
    >>> round(key_value("supply.pump_flow", "90 L/min", "m**3/s", "70 L/min") * 6e4, 12)
    90.0
    """
    return to_si(name, value, unit, repr(base), what=f"in {unit or 'no unit'} as the config's {base!r}")


def design_key(config: dict, key: str) -> tuple[str, object]:
    """A key's SI unit and the config's own value of it (:func:`key_unit`).

    Raises
    ------
    ValueError
        An unknown key, one the config leaves out, or a value that is not a quantity.
    """
    from .circuit_parts import declared_unit

    base = config_value(config, key)
    f = declared_field(key, config_kind(config))
    return key_unit(key, base, f.unit if f is not None else declared_unit(config, key)), base


def design_bounds(config: dict, vary, folder=None) -> dict:
    """The variables of a search: each dotted key's SI unit, bounds and start, checked the way a
    design map checks its axes (:func:`design_key`, :func:`key_value`, the machine built at each
    bound).

    Parameters
    ----------
    config : dict
        The machine's configuration.
    vary : dict
        Dotted key to ``(low, high)``, each a quantity with a unit (a number for a dimensionless key).
    folder : path-like, optional
        The config's folder.

    Returns
    -------
    dict
        Key to ``{"low", "high", "unit", "start"}`` (SI; the start is the config's own value); a key of
        :data:`INTEGER_KEYS` has integer bounds.

    Raises
    ------
    ValueError
        One line: a key the config does not give, bounds not ``(low, high)``, of the wrong unit, not
        ordered or outside the key's range, a start outside the bounds, bounds of an integer key that
        are not integers.

    Examples
    --------
    >>> from impactbar.physical import read_config
    >>> from impactbar.physical.design_keys import design_bounds
    >>> design_bounds(read_config("circuit-drifter")[0], {"stop.restitution": (0.1, 0.3)})
    {'stop.restitution': {'low': 0.1, 'high': 0.3, 'unit': '', 'start': 0.215}}
    """
    from .loader import build, with_values

    if not isinstance(vary, dict) or not vary:
        raise ValueError("vary must be a non-empty dict of dotted key to (low, high)")
    out = {}
    for key, bounds in vary.items():
        try:
            unit, base = design_key(config, key)
        except ValueError as exc:
            raise ValueError(f"vary: {key!r} is not a parameter the optimiser varies: {exc}") from None
        if not isinstance(bounds, (tuple, list)) or len(bounds) != 2:
            raise ValueError(f"vary[{key!r}] must be (low, high); got {bounds!r}")
        integer = key in FIELDS and FIELDS[key].integer
        low, high = bounds
        lo, hi = (key_value(f"vary[{key!r}] {side}", b, unit, base)
                  for side, b in (("low", low), ("high", high)))
        if not lo < hi:
            raise ValueError(f"vary[{key!r}]: low must be below high; got {low!r} and {high!r}")
        if integer and not (lo.is_integer() and hi.is_integer()):
            raise ValueError(f"vary[{key!r}] takes integers (the config key is an integer); got {low!r} and "
                             f"{high!r}")
        for side, b, given in (("low", lo, low), ("high", hi, high)):
            try:
                build(with_values(config, {key: int(b) if integer else config_quantity(b, unit)}), folder)
            except ValueError as exc:
                raise ValueError(f"vary[{key!r}]: the {side} bound {given!r} is outside the key's range: "
                                 f"{' '.join(str(exc).split(': ', 2)[-1].split())}") from None
        start = key_value(key, base, unit, base)
        if not lo <= start <= hi:
            raise ValueError(f"vary[{key!r}]: the start {base!r} lies outside the bounds {low!r} to "
                             f"{high!r}")
        out[key] = {"low": lo, "high": hi, "unit": unit, "start": start}
    return out
