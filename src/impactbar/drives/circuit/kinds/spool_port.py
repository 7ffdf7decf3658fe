r"""A main port of a spool valve (theory §11, *Parts of a drill's circuit*): ``q = K_v o(x)
phi(p_source - p_target)``, its opening ``o`` piecewise linear in the spool's position ``x`` (the
network's ``x_v`` slot, :mod:`.spool`): ``o_P`` from the supply to the work port, ``o_T`` from the
work port to the return. A record holds the piece of ``o`` the mode says the spool is on,
``o = intercept + slope x`` (the part writes it from its flags: the kinks are events, levels of ``x``,
:mod:`.level`), so that the vector field is smooth between events. Its loss goes to its energy slot.

The record: as a cushion's (:data:`._flow.PIECEWISE`), its opening a function of ``x`` instead of the
piston's gap.
"""

from __future__ import annotations

import numba as nb

from ._flow import JIT
from .cushion import ENERGIES as ENERGIES  # (a cushion's record and slots)
from .cushion import EVENTS as EVENTS
from .cushion import FIELDS as FIELDS
from .cushion import NODES as NODES
from .cushion import law as _cushion_law

CODE = 12
NAME = "spool_port"


@nb.njit(**JIT)
def law(par, r, pa, pb, x):
    """The flow from source to target, ``K (o_0 + o_1 x) phi(p_a - p_b)``, and its derivatives ``(q,
    dq/dp_a, dq/dp_b, dq/dx)`` (a cushion's law with the spool's position for the gap)."""
    return _cushion_law(par, r, pa, pb, x)
