"""The rod-and-rock law (theory §4d): the piston strikes a finite, possibly stepped rod whose bit loads
a rock with Lundberg's bilinear force-penetration law, under a static feed force.

Layout: ``law`` (:class:`RodRock` and :func:`single_blow`), ``rod`` (its parts, :class:`RodSegment` and
:class:`BilinearRock`), ``checks`` (the bounds a blow accepts, checked before it runs), ``blow``
(:class:`Blow`: one blow by characteristics on the cell grid of piston and rod), ``contact`` (the
simulator's contact step and the orbits' blow map: the piston's modal state at impact through the blow to
its state after, :class:`~impactbar.laws.rodrock.contact.RockContact`), ``_rockloop`` (the blow's
compiled loop).
"""

import importlib

from .law import RodRock as RodRock
from .law import lundberg_efficiency as lundberg_efficiency
from .law import single_blow as single_blow
from .rod import BilinearRock as BilinearRock
from .rod import RodSegment as RodSegment

__all__ = ["RodRock", "RodSegment", "BilinearRock", "single_blow", "Blow"]


def __getattr__(name: str):
    # PEP 562: the blow's module (its dataclasses, the drawing hooks) loads on first use, so that
    # ``import impactbar`` (which builds the table of laws) stays as light as before
    if name == "Blow":
        value = importlib.import_module(".blow", __name__).Blow
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
