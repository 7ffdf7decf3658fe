"""Impact laws as objects, looked up in one table (theory §4, §4b).

``LAWS`` maps each law's name to its class, in the style of scipy's ``METHODS``;
:func:`get_law` turns a name or a law object into a law object. A law (:class:`ContactLaw`) owns
everything that differs between laws: its contact window, the impact map with its Jacobian, the
one-impact phase equation and orbits, the simulator's contact step and the per-blow outputs.
Adding a law is one module with a :class:`ContactLaw` subclass and one entry in ``LAWS``
(see the developer page of the documentation).
"""

from __future__ import annotations

from .base import ContactLaw as ContactLaw
from .paper import InstantImpact as InstantImpact
from .paper import PaperLaw as PaperLaw
from .wave import WaveLaw as WaveLaw

__all__ = ["ContactLaw", "PaperLaw", "WaveLaw", "InstantImpact", "LAWS", "get_law"]

#: The impact laws by name: ``"paper"`` (eq. 10) and ``"wave"`` (the long rod, theory §4b).
LAWS: dict[str, type[ContactLaw]] = {"paper": PaperLaw, "wave": WaveLaw}


def get_law(spec) -> ContactLaw:
    """The law object for a name in :data:`LAWS` or a :class:`ContactLaw` instance.

    Parameters
    ----------
    spec : str or ContactLaw
        A key of :data:`LAWS` (``"paper"``, ``"wave"``), or a law object (returned as it is).

    Returns
    -------
    ContactLaw

    Raises
    ------
    ValueError
        For an unknown name or another type; the message lists the names.
    """
    if isinstance(spec, ContactLaw):
        return spec
    if isinstance(spec, str) and spec in LAWS:
        return LAWS[spec]()
    raise ValueError(f"impact must be one of {list(LAWS)} or a ContactLaw; got impact={spec!r}")
