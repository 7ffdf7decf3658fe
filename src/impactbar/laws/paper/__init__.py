"""The paper's impact law (eq. 10, theory §4): :class:`PaperLaw` and its per-impact record
:class:`InstantImpact` (``law``); the phase equation, eq. 14, with the existence edge of eq. 38
(``phase``); the one-impact orbits' states (``periodic``) and their exact multipliers
(``stability``). Only ``law`` is imported with the package: the numerics load on first use."""

from .law import InstantImpact as InstantImpact
from .law import PaperLaw as PaperLaw

__all__ = ["PaperLaw", "InstantImpact"]
