"""Impact laws as objects, looked up in one table (theory §4, §4b, §4d).

``LAWS`` maps each law's name to its class, in the style of scipy's ``METHODS``;
:func:`get_law` turns a name or a law object into a law object. A law (:class:`ContactLaw`) owns
everything that differs between laws: its contact window, the impact map with its Jacobian, the
simulator's contact step, its declarations (:class:`LawTraits`), its own continuation parameters;
and, where it has them, its abilities (:mod:`impactbar.laws.abilities`, looked up by
``law.ability(kind)``): the one-impact phase equation and the orbits' states
(:class:`PhaseEquation`, :class:`OrbitState`), the per-blow records (:class:`BlowRecords`), the blow
coupled to a drive (:class:`CoupledBlow`), Newton's starts (:class:`NewtonStart`).

Each law is one subpackage holding its numerics: ``paper`` (eq. 10, theory §4), ``wave`` (the long
rod, theory §4b), ``rodrock`` (the finite rod and the rock, theory §4d). The laws sit below the
solvers (orbits, simulation, continuation), which reach them as ``model.law``; a law imports only
the core below it (``dynamics``, ``loads``, ``_shared``) and returns plain data that the solvers
build their results from. Adding a law is one :class:`ContactLaw` subclass and one entry in ``LAWS``
(see the developer page of the documentation).
"""

from __future__ import annotations

from .abilities import BlowRecords as BlowRecords
from .abilities import CoupledBlow as CoupledBlow
from .abilities import NewtonStart as NewtonStart
from .abilities import PhaseEquation as PhaseEquation
from .base import ContactLaw as ContactLaw
from .base import LawNotSupported as LawNotSupported
from .base import LawTraits as LawTraits
from .base import OrbitState as OrbitState
from .paper import InstantImpact as InstantImpact
from .paper import PaperLaw as PaperLaw
from .registry import LAWS as LAWS
from .registry import PARAMETERISED as PARAMETERISED
from .registry import get_law as get_law
from .registry import register_law as register_law
from .rodrock import BilinearRock as BilinearRock
from .rodrock import RodRock as RodRock
from .rodrock import RodSegment as RodSegment
from .rodrock import single_blow as single_blow
from .rodrock.longrod import SteppedLongRod as SteppedLongRod
from .wave import PressedContact as PressedContact
from .wave import WaveLaw as WaveLaw

__all__ = ["ContactLaw", "LawTraits", "PhaseEquation", "BlowRecords", "CoupledBlow", "NewtonStart",
           "OrbitState", "LawNotSupported", "PaperLaw", "WaveLaw", "PressedContact",
           "InstantImpact", "LAWS", "get_law", "register_law", "RodRock", "RodSegment", "BilinearRock",
           "single_blow", "SteppedLongRod", "piston_law"]


def piston_law(law: ContactLaw, stepped: bool) -> ContactLaw:
    """The law a model under ``law`` takes with a stepped (``stepped``) or a uniform piston: the wave
    law's long rod struck by a stepped piston is :class:`SteppedLongRod` (its contact the exact blow,
    theory §4b, §12), and back; every other law takes itself (and takes a stepped piston, or refuses
    it, by its traits' ``stepped_piston``).

    Parameters
    ----------
    law : ContactLaw
    stepped : bool

    Returns
    -------
    ContactLaw
    """
    if stepped and isinstance(law, WaveLaw):
        return SteppedLongRod()
    if not stepped and isinstance(law, SteppedLongRod):
        return WaveLaw()
    return law

#: The impact laws by name: ``"paper"`` (eq. 10) and ``"wave"`` (the long rod, theory §4b). The rod
#: and the rock (``"rodrock"``, theory §4d) has required parameters: only a ``RodRock(...)`` object
#: builds it, so its name is in ``PARAMETERISED`` (``get_law("rodrock")`` says how), not in ``LAWS``.
#: The table itself lives in :mod:`impactbar.laws.base`, below the laws' implementations.
LAWS.update({"paper": PaperLaw, "wave": WaveLaw})
PARAMETERISED.update({"rodrock": "RodRock(segments=[RodSegment(length=..., impedance=...), ...], "
                                 "rock=BilinearRock(k=..., k_u=...))"})

#: names that moved up to the solvers (a law imports no solver): where each is now
_MOVED = {"rock_periodic_orbits": "impactbar.orbits.rock_periodic_orbits"}


def __getattr__(name: str):
    if name in _MOVED:
        raise AttributeError(f"impactbar.laws.{name} moved to {_MOVED[name]} (the laws sit below the "
                             "orbit solvers)")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
