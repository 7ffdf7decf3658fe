"""Impact laws as objects, looked up in one table (theory §4, §4b).

``LAWS`` maps each law's name to its class, in the style of scipy's ``METHODS``;
:func:`get_law` turns a name or a law object into a law object. A law (:class:`ContactLaw`) owns
everything that differs between laws: its contact window, the impact map with its Jacobian, the
one-impact phase equation and orbits, the simulator's contact step and the per-blow outputs.
Adding a law is one module with a :class:`ContactLaw` subclass and one entry in ``LAWS``
(see the developer page of the documentation).
"""

from __future__ import annotations

from .base import LAWS as LAWS
from .base import PARAMETERISED as PARAMETERISED
from .base import ContactLaw as ContactLaw
from .base import get_law as get_law
from .paper import InstantImpact as InstantImpact
from .paper import PaperLaw as PaperLaw
from .rodrock import BilinearRock as BilinearRock
from .rodrock import RodRock as RodRock
from .rodrock import RodSegment as RodSegment
from .rodrock import rock_periodic_orbits as rock_periodic_orbits
from .rodrock import single_blow as single_blow
from .wave import PressedContact as PressedContact
from .wave import WaveLaw as WaveLaw

__all__ = ["ContactLaw", "PaperLaw", "WaveLaw", "PressedContact", "InstantImpact", "LAWS", "get_law",
           "RodRock",
           "RodSegment", "BilinearRock", "single_blow", "rock_periodic_orbits"]

#: The impact laws by name: ``"paper"`` (eq. 10) and ``"wave"`` (the long rod, theory §4b). The rod
#: and the rock (``"rodrock"``, theory §4d) has required parameters: only a ``RodRock(...)`` object
#: builds it, so its name is in ``PARAMETERISED`` (``get_law("rodrock")`` says how), not in ``LAWS``.
#: The table itself lives in :mod:`impactbar.laws.base`, below the laws' implementations, so that
#: :class:`~impactbar.BarModel` can resolve a name without importing the solvers the laws drive.
LAWS.update({"paper": PaperLaw, "wave": WaveLaw})
PARAMETERISED.update({"rodrock": "RodRock(segments=[RodSegment(length=..., impedance=...), ...], "
                                 "rock=BilinearRock(k=..., k_u=...))"})
