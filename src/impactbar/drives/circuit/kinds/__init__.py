r"""Kinds of the circuit's network (:mod:`.._network`) written each in a module of its own, with its
equations: the parts of a drill's circuit beyond the preset's (theory §11, *Parts of a drill's
circuit*).

A kind's module declares ``CODE`` (its number in a record's ``KIND`` slot, after the network's
own kinds), ``NAME``, ``FIELDS`` (its fields' slots by name, for :func:`.._network.record`) and the
slots that name a node (``NODES``), an energy integrand (``ENERGIES``) and an event (``EVENTS``),
which :func:`.._network.compose` checks. A kind that passes a flow between two nodes (:data:`FLOWS`:
its fields ``source``, ``target`` and ``energy`` first) has the numba function ``law(par, r, p_a,
p_b, y)``: the flow from source to target (``r`` the record's offset in ``par``, ``y`` the piston's
gap) and its derivatives in ``p_a``, ``p_b`` and ``y``; the network adds the flow to its
nodes' balances, its loss ``q (p_a - p_b)`` to its energy slot and its derivatives to the Jacobian,
the same way for every such kind, in the interpreted network and in the code generated for a
topology (:mod:`.._netgen`, which calls these functions). A watched level (:mod:`.level`) is an
event of the gap or of a pressure drop.

- :mod:`.leak`: laminar leakage ``G (p_a - p_b)``;
- :mod:`.cushion`: a position-controlled orifice ``K g(y) phi(p_a - p_b)``;
- :mod:`.check`: a check valve ``K o(dp) phi(dp)``;
- :mod:`.level`: a watched level of the gap, of a pressure drop or of a spool's position;
- :mod:`.spool`: a pilot-operated spool's mechanics (the state of the part that replaces the valve);
- :mod:`.spool_port`: a spool valve's main port, ``K o(x) phi(p_a - p_b)`` (in :data:`SPOOL_FLOWS`:
  its opening a function of the spool's position ``x``, not of the gap).
"""

from __future__ import annotations

import numba as nb

from . import check, cushion, leak, level, spool, spool_port
from ._flow import JIT

__all__ = ["FLOWS", "SPOOL_FLOWS", "MODULES", "law", "check", "cushion", "leak", "level", "spool",
           "spool_port"]

#: the kinds that pass a flow between two nodes
FLOWS = (leak, cushion, check)
#: the kinds that pass a flow between two nodes through an opening set by the spool's position
SPOOL_FLOWS = (spool_port,)
#: every kind of this package by its code
MODULES = {m.CODE: m for m in (*FLOWS, level, spool, *SPOOL_FLOWS)}


@nb.njit(**JIT)
def law(kind, par, r, pa, pb, gap):
    """``(q, dq/dp_a, dq/dp_b, dq/dy)`` of the record at ``r`` of a kind of :data:`FLOWS` (its
    module's ``law``)."""
    if kind == leak.CODE:
        return leak.law(par, r, pa, pb, gap)
    if kind == cushion.CODE or kind == spool_port.CODE:  # (a spool's port: ``gap`` its position)
        return cushion.law(par, r, pa, pb, gap)
    return check.law(par, r, pa, pb, gap)
