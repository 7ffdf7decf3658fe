"""The one rule of the tables of parts by name (the loads' ``LOADS``, the laws' ``LAWS``, the drives'
``DRIVES``): a class enters its table by the name it declares, and a name another class holds is
refused."""

from __future__ import annotations

from operator import attrgetter


def register(table: dict, cls, base: type, attr: str, what: str):
    """Enter ``cls`` in ``table`` by its class attribute ``attr`` (``kind`` or ``name``).

    Parameters
    ----------
    table : dict of str to type
        The table (changed in place).
    cls : type
        A subclass of ``base``.
    base : type
        The parts' base class (:class:`~impactbar.Load`, :class:`~impactbar.laws.ContactLaw`,
        :class:`~impactbar.Drive`).
    attr : str
        The class attribute that holds the name (dotted for one of its attributes:
        ``"traits.kind"``).
    what : str
        What a part is called in the messages (``"load"``, ``"impact law"``, ``"drive"``).

    Returns
    -------
    type
        ``cls`` (so that a register function serves as a class decorator).

    Raises
    ------
    ValueError
        For a class that is not a subclass of ``base``, without a name, or whose name another class
        holds.

    Examples
    --------
    >>> table = {}
    >>> class Part:
    ...     kind = "a"
    >>> register(table, Part, Part, "kind", "part") is Part and table == {"a": Part}
    True
    """
    if not (isinstance(cls, type) and issubclass(cls, base)):
        raise ValueError(f"cls must be a subclass of {base.__name__}; got {cls!r}")
    key = attrgetter(attr)(cls)
    if not isinstance(key, str) or not key:
        raise ValueError(f"cls.{attr} must be a non-empty string (the {what}'s name in its table); "
                         f"got {key!r}")
    held = table.get(key)
    if held is not None and held is not cls:
        raise ValueError(f"{attr} {key!r} is already the {what} {held.__name__}; choose another {attr}")
    table[key] = cls
    return cls
