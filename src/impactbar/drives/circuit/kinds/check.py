r"""A check valve (theory §11, *Parts of a drill's circuit*): ``q = K_cv o(dp) phi(dp)``,
``dp = p_source - p_target``, its opening ``o = clip((dp - p_crack) / dp_open, 0, 1)`` (Hopsan's
``HydraulicCheckValvePreLoaded``, a check valve with a cracking pressure, its opening rising over a
span as its ``HydraulicPressureControlledValve``'s). A record holds the piece of ``o`` the mode says
the drop is on, ``o = intercept + slope dp`` (the part writes it from its flags: the kinks at
``p_crack`` and ``p_crack + dp_open`` are events, :mod:`.level`), so that the vector field is smooth
between events. Its loss ``q dp`` goes to its energy slot.

The record: as a cushion's (:data:`._flow.PIECEWISE`), ``K_cv`` its coefficient.
"""

from __future__ import annotations

import numba as nb

from ._flow import COEFFICIENT, INTERCEPT, JIT, PTR2, SLOPE, dphi, phi
from .cushion import ENERGIES as ENERGIES  # (a cushion's record and slots)
from .cushion import EVENTS as EVENTS
from .cushion import FIELDS as FIELDS
from .cushion import NODES as NODES

CODE = 9
NAME = "check"


@nb.njit(**JIT)
def law(par, r, pa, pb, gap):
    """The flow from source to target, ``K (o_0 + o_1 dp) phi(dp)``, and its derivatives ``(q,
    dq/dp_a, dq/dp_b, dq/dy)``."""
    dp = pa - pb
    k, ptr2 = par[r + COEFFICIENT], par[r + PTR2]
    o = par[r + INTERCEPT] + par[r + SLOPE] * dp
    f = phi(dp, ptr2)
    d = k * (par[r + SLOPE] * f + o * dphi(dp, ptr2))
    return k * o * f, d, -d, 0.0
