"""The table of impact laws by name: :data:`LAWS` (and :data:`PARAMETERISED`, the laws a name alone
cannot build), :func:`get_law`, which turns a name or a law object into a law object, and
:func:`register_law`, which enters a new law class (theory §4, §4b, §4d)."""

from __future__ import annotations

import functools

from .._shared.registry import register
from .base import ContactLaw

__all__ = ["LAWS", "PARAMETERISED", "get_law", "register_law"]


#: The table of laws by name, in the style of scipy's ``METHODS``; its entries are made in
#: :mod:`impactbar.laws` (one line per law). Kept here, below the laws' implementations, so that
#: :class:`~impactbar.BarModel` resolves a name without importing the solvers.
LAWS: dict[str, type[ContactLaw]] = {}

#: Laws with required parameters, by name: not in :data:`LAWS` (a name alone cannot build them);
#: :func:`get_law` answers their name with how to build the object.
PARAMETERISED: dict[str, str] = {}


@functools.cache
def _default_law(cls: type[ContactLaw]) -> ContactLaw:
    """The one instance of a law without parameters (laws are frozen: every model may share it)."""
    return cls()


def get_law(spec) -> ContactLaw:
    """The law object for a name in :data:`LAWS` or a :class:`ContactLaw` instance.

    Parameters
    ----------
    spec : str or ContactLaw
        A key of :data:`LAWS` (``"paper"``, ``"wave"``), or a law object (returned as it is).

    Returns
    -------
    ContactLaw
        The law object given, or the one registered under the name.

    Raises
    ------
    ValueError
        For an unknown name or another type (the message lists the names), or the name of a law
        with required parameters (:data:`PARAMETERISED`; the message says how to build it).
    """
    if type(spec) is str and spec in LAWS:  # (the common case first: no ABC instance check)
        return _default_law(LAWS[spec])
    if isinstance(spec, ContactLaw):
        return spec
    if isinstance(spec, str) and spec in LAWS:
        return _default_law(LAWS[spec])
    if isinstance(spec, str) and spec in PARAMETERISED:
        raise ValueError(f"the impact law {spec!r} has required parameters: "
                         f"pass impact={PARAMETERISED[spec]}")
    raise ValueError(f"impact must be one of {list(LAWS)} or a ContactLaw; got impact={spec!r}")


def register_law(cls: type[ContactLaw]) -> type[ContactLaw]:
    """Enter a law class in the table :data:`LAWS` by its :attr:`~ContactLaw.name`, so that
    ``BarModel(impact=name)`` and a sweep spec's ``[law] kind`` know it (usable as a class
    decorator). Its fields (the dataclass's) are then the ``[law]`` table's other keys.

    Parameters
    ----------
    cls : type
        A subclass of :class:`ContactLaw` with a non-empty ``name`` whose fields all have defaults
        (the name alone builds it).

    Returns
    -------
    type
        The law class itself, as a decorator returns it.

    Raises
    ------
    ValueError
        For a class that is not a law, without a ``name``, whose ``name`` another class holds (or
        a law with required parameters, :data:`PARAMETERISED`), or that its name alone cannot build.

    Examples
    --------
    >>> from impactbar.laws import PaperLaw, register_law
    >>> register_law(PaperLaw) is PaperLaw  # already there: registering again changes nothing
    True
    """
    if isinstance(cls, type) and issubclass(cls, ContactLaw) and cls.name in PARAMETERISED:
        raise ValueError(f"name {cls.name!r} is already the impact law {PARAMETERISED[cls.name]}; choose "
                         "another name")
    if isinstance(cls, type) and issubclass(cls, ContactLaw) and cls.name not in LAWS:
        try:
            cls()
        except TypeError as exc:
            raise ValueError(f"the impact law {cls.__name__} must be built by its name alone (every "
                             f"field with a default): {exc}") from None
    return register(LAWS, cls, ContactLaw, "name", "impact law")

