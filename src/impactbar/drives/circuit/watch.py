"""The watched events of a circuit's extra parts, read from its network (:mod:`._network`): an
accumulator's pre-charge, a relief's setting (a node's pressure through a level), and the levels of
the kinds of :mod:`.kinds` (the piston's gap or a pressure drop through a level: a cushion's or a
check valve's kinks) or the spool's position (a spool valve's ports' kinks), and a spool's stop
(:mod:`.kinds.spool`), each a flag of the drive's mode."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import _network as NW
from .kinds import level as LV
from .kinds import spool as SP

__all__ = ["Watch", "watched"]


@dataclass(frozen=True)
class Watch:
    """One watched event of an extra part.

    Attributes
    ----------
    name : str
        The event's name (the part's).
    slot : int
        Its slot in the network's events (its flag is the mode's ``1 + slot``).
    level : float
        The level its quantity passes.
    kind : int
        The record's kind: :data:`._network.ACCUM`, :data:`._network.RELIEF`, :data:`._network.LEVEL`
        or :data:`._network.SPOOL` (its stop: the quantity is at or above 0 where it rests).
    node : int or None
        The node whose pressure is watched (an accumulator's, a relief's), else ``None``.
    quantity : callable
        ``quantity(q, z)``: the watched quantity at the modal displacements ``q`` and the circuit's
        state ``z``.
    """

    name: str
    slot: int
    level: float
    kind: int
    node: int | None
    quantity: Callable

    def flag(self, q, z) -> int:
        """The mode's flag at ``(q, z)``: at or above the level (above it for a relief)."""
        x = self.quantity(q, z)
        return int(x > self.level if self.kind == NW.RELIEF else x >= self.level)


def _level(record, pressure, ns):
    """A watched level's ``quantity(q, z)`` (the gap ``-q_0``, the spool's position ``z[ns]`` or a
    pressure drop)."""
    if record[LV.GAP] == LV.SPOOL:
        return lambda q, z: float(z[ns])
    return lambda q, z: LV.quantity(record, lambda j: pressure(z, j), -float(q[0]))


def _stop(record, pressure, ns):
    """A spool's stop's ``quantity(q, z)`` (:func:`.kinds.spool.stop_quantity`)."""
    ac, a0 = float(record[SP.LARGE]), float(record[SP.SMALL])
    c, s = int(record[SP.CONTROL]), int(record[SP.SUPPLY])
    return lambda q, z: SP.stop_quantity(float(z[ns]), ac * pressure(z, c) - a0 * pressure(z, s))


def watched(net, events, own=()) -> tuple:
    """The extra parts' :class:`Watch` es of the composed network ``net`` (:func:`._network.compose`),
    in slot order; ``events`` the network's event names (slot ``i``:
    :attr:`.composition.Composition.events`), those named in ``own`` (the drive's: the preset's
    accumulator and relief) left out."""
    head, recs = net[:NW.NW_SIZE], np.asarray(net[NW.NW_SIZE:]).reshape(-1, NW.REC_SIZE)
    ns = int(head[NW.NW_NSTATE])

    def pressure(z, j):
        return float(z[j]) if j < ns else float(recs[j][NW.N_P])

    out = []
    for r in recs:
        kind = int(r[NW.KIND])
        if kind == NW.ACCUM and r[NW.A_WATCH] > 0.5 and r[NW.A_EV] >= 0:
            node = int(r[NW.A_NODE])
            out.append((int(r[NW.A_EV]), float(r[NW.A_P0]), kind, node,
                        lambda q, z, j=node: pressure(z, j)))
        elif kind == NW.RELIEF and r[NW.R_WATCH] > 0.5 and r[NW.R_EV] >= 0:
            node = int(r[NW.R_FROM])
            out.append((int(r[NW.R_EV]), float(r[NW.R_SET]), kind, node,
                        lambda q, z, j=node: pressure(z, j)))
        elif kind == NW.LEVEL and r[NW.LV_EV] >= 0:
            out.append((int(r[NW.LV_EV]), float(r[LV.LEVEL]), kind, None, _level(r.copy(), pressure, ns)))
        elif kind == NW.SPOOL and r[SP.EVENT] >= 0:
            out.append((int(r[SP.EVENT]), 0.0, kind, None, _stop(r.copy(), pressure, ns)))
    watches = [Watch(events[slot], slot, level, kind, node, f) for slot, level, kind, node, f in out]
    return tuple(sorted((w for w in watches if w.name not in own), key=lambda w: w.slot))
