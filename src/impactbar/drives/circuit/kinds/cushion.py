r"""A position-controlled orifice (theory §11, *Parts of a drill's circuit*): a port that the piston
opens and shuts, a cushion, ``q = K_max g(y) phi(p_source - p_target)`` with ``g`` piecewise linear in
the piston's gap ``y`` (Hopsan's ``HydraulicTurbulentOrifice`` with its area a function of the
piston's position). A record holds the piece of ``g`` the mode says the gap is on,
``g = intercept + slope y`` (the part writes it from its flags: the kinks are events,
:mod:`.level`), so that the vector field is smooth between events. Its loss ``q (p_source -
p_target)`` goes to its energy slot.

The record (:data:`._flow.PIECEWISE`): ``source``, ``target`` (nodes), ``energy`` (slot, -1 none),
``coefficient`` (``K_max``), ``ptr2`` (the transition pressure squared), ``intercept``, ``slope``.
"""

from __future__ import annotations

import numba as nb

from ._flow import COEFFICIENT, ENERGY, INTERCEPT, JIT, PIECEWISE, PTR2, SLOPE, SOURCE, TARGET, dphi, phi

CODE = 8
NAME = "cushion"
FIELDS = PIECEWISE
NODES = (SOURCE, TARGET)
ENERGIES = (ENERGY,)
EVENTS = ()


@nb.njit(**JIT)
def law(par, r, pa, pb, gap):
    """The flow from source to target, ``K (g_0 + g_1 y) phi(p_a - p_b)``, and its derivatives
    ``(q, dq/dp_a, dq/dp_b, dq/dy)``."""
    k, ptr2 = par[r + COEFFICIENT], par[r + PTR2]
    g = par[r + INTERCEPT] + par[r + SLOPE] * gap
    f = phi(pa - pb, ptr2)
    d = k * g * dphi(pa - pb, ptr2)
    return k * g * f, d, -d, k * par[r + SLOPE] * f
