"""The optional parts of a sweep spec beside ``[model]``: a registered impact law (``[law]``) and a
registered drive in place of the load (``[drive]``). Each table names its class by ``kind`` in its
registry (:data:`impactbar.laws.LAWS`, :func:`impactbar.laws.register_law`;
:data:`impactbar.drives.DRIVES`, :func:`impactbar.drives.register_drive`, a drive class or a factory
returning a drive) and gives the rest of the constructor's (the factory's) keyword arguments; the part
built is validated by its constructor, and an axis may then sweep any of its parameters
(:func:`impactbar.parameters.parameters`), with no case for any law or drive here.
"""

from __future__ import annotations

#: the length of the ``orbit`` dimension of an ``orbits`` sweep under a drive, unless ``[orbits]
#: max_orbits`` says (a drive's orbits have no bound of a load's phase equation)
DRIVE_MAX_ORBITS = 8


def _built(section: str, table, registry: dict, what: str, register: str, base: type):
    """The part a ``[law]`` or ``[drive]`` table builds (an instance of ``base``: a registered
    factory's result is checked), and the table with its values as the part holds them (JSON
    scalars) for the store's copy of the spec."""
    if not isinstance(table, dict):
        raise ValueError(f"[{section}] must be a table; got {table!r}")
    kind = table.get("kind")
    if not isinstance(kind, str) or kind not in registry:
        raise ValueError(f"[{section}] kind must be one of {sorted(registry)} ({register} adds one); "
                         f"got {kind!r}")
    args = {k: v for k, v in table.items() if k != "kind"}
    maker = registry[kind]
    name = getattr(maker, "__name__", repr(maker))
    try:
        part = maker(**args)
    except TypeError as exc:  # an unknown or missing keyword
        raise ValueError(f"[{section}] the {what} {kind!r} takes keys of {name}: {exc}") from None
    except ValueError as exc:
        raise ValueError(f"[{section}] {exc}") from None
    if not isinstance(part, base):
        raise ValueError(f"[{section}] kind {kind!r}: {name} must return a {base.__name__}; "
                         f"got {type(part).__name__}")
    out = {"kind": kind}
    for k, given in args.items():
        value = getattr(part, k, given)
        out[k] = value if isinstance(value, bool | int | float | str) or value is None else given
    return part, out


def law_table(table):
    """The impact law of a ``[law]`` table: ``kind`` a name in :data:`impactbar.laws.LAWS`, the
    other keys the law's fields.

    Parameters
    ----------
    table : dict
        ``{"kind": name, field: value, ...}`` as the spec's TOML gives it.

    Returns
    -------
    law : ContactLaw
    table : dict
        The table, its values as the law holds them.

    Raises
    ------
    ValueError
        One line naming ``[law]`` and the unknown kind (the registered ones listed) or the bad key.

    Examples
    --------
    >>> law_table({"kind": "paper"})
    (PaperLaw(), {'kind': 'paper'})
    """
    from ..laws import LAWS, ContactLaw

    return _built("law", table, LAWS, "impact law", "impactbar.laws.register_law", ContactLaw)


def drive_table(table):
    """The drive of a ``[drive]`` table: ``kind`` a key of :data:`impactbar.drives.DRIVES`, the
    other keys the drive's constructor's arguments (or, for a factory entered by
    ``register_drive(factory, kind=...)``, the factory's).

    Parameters
    ----------
    table : dict

    Returns
    -------
    drive : Drive
    table : dict
        The table, its values as the drive holds them.

    Raises
    ------
    ValueError
        One line naming ``[drive]`` and the unknown kind (the registered ones listed), the bad
        key, or a factory that returned no :class:`~impactbar.Drive`.

    Examples
    --------
    >>> drive_table({"kind": "position-switched", "stroke": 1, "ret": 0.5, "switch_out": 1.0})[1]
    {'kind': 'position-switched', 'stroke': 1.0, 'ret': 0.5, 'switch_out': 1.0}
    """
    from ..drives import DRIVES, Drive

    return _built("drive", table, DRIVES, "drive", "impactbar.drives.register_drive", Drive)
