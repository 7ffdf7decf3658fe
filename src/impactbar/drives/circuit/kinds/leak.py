r"""Laminar leakage between two nodes (theory §11, *Parts of a drill's circuit*): a clearance's flow
:math:`q = G\,(p_\mathrm{source} - p_\mathrm{target})`, linear in the pressure drop (Hopsan's
``HydraulicLaminarOrifice``); ``G`` in the model's flow over its pressure (for an annular gap of
diameter ``D``, radial clearance ``c`` and length ``l`` in oil of viscosity ``mu``:
:math:`\pi D c^3 / (12 \mu l)`). Its loss :math:`q\,(p_\mathrm{source} - p_\mathrm{target}) =
G\,\Delta p^2` goes to its energy slot. No event: the law is smooth.

The record: ``source``, ``target`` (nodes), ``energy`` (slot, -1 none), ``conductance`` (:math:`G \ge 0`).
"""

from __future__ import annotations

import numba as nb

from ._flow import ENERGY, JIT, SOURCE, TARGET

CODE = 7
NAME = "leak"
CONDUCTANCE = 4
FIELDS = {"source": SOURCE, "target": TARGET, "energy": ENERGY, "conductance": CONDUCTANCE}
NODES = (SOURCE, TARGET)
ENERGIES = (ENERGY,)
EVENTS = ()


@nb.njit(**JIT)
def law(par, r, pa, pb, gap):
    """The flow from source to target, ``G (p_a - p_b)``, and its derivatives ``(q, dq/dp_a, dq/dp_b,
    dq/dy)``."""
    g = par[r + CONDUCTANCE]
    return g * (pa - pb), g, -g, 0.0
