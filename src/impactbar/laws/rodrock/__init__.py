"""The rod-and-rock law (theory §4d): the piston strikes a finite, possibly stepped rod whose bit loads
a rock with Lundberg's bilinear force-penetration law, under a static feed force.

Layout: ``law`` (:class:`RodRock` with its :class:`RodSegment` and :class:`BilinearRock`, and
:func:`single_blow`), ``blow`` (:class:`Blow`: one blow by characteristics on the cell grid of piston
and rod), ``contact`` (the simulator's contact step and the orbits' blow map: the piston's modal state
at impact through the blow to its state after, :class:`~impactbar.laws.rodrock.contact.RockContact`),
``_rockkernel`` (the blow's compiled loop).
"""

from .blow import Blow as Blow
from .law import BilinearRock as BilinearRock
from .law import RodRock as RodRock
from .law import RodSegment as RodSegment
from .law import lundberg_efficiency as lundberg_efficiency
from .law import single_blow as single_blow

__all__ = ["RodRock", "RodSegment", "BilinearRock", "single_blow", "Blow"]
