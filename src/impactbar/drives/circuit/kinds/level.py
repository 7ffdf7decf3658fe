r"""A watched level (theory §11, *Parts of a drill's circuit*): an event of a part where the piston's
gap ``y`` (``gap`` 1), a spool's position ``x`` (``gap`` :data:`SPOOL`, 2: the network's ``x_v`` slot,
:mod:`.spool`) or a pressure drop ``p_source - p_target`` (``gap`` 0) passes ``level`` (a kink of a
cushion's opening, of a check valve's, of a spool valve's port), with a flag of the drive's mode
(``on``: at or above the level, watched falling; else watched rising). No flow, no energy. The
callers hand the spool's position as ``gap`` to a level of :data:`SPOOL`.

The record: ``source``, ``target`` (nodes), ``gap`` (1 or 0), ``level``, ``on`` (the flag), ``event``
(the network's event slot).
"""

from __future__ import annotations

import numba as nb

from .._field import _off_level
from ._flow import JIT, SOURCE, TARGET

CODE = 10
NAME = "level"
GAP, LEVEL, ON, EVENT = range(3, 7)
#: the ``gap`` of a level of the spool's position
SPOOL = 2
FIELDS = {"source": SOURCE, "target": TARGET, "gap": GAP, "level": LEVEL, "on": ON, "event": EVENT}
NODES = (SOURCE, TARGET)
ENERGIES = ()
EVENTS = (EVENT,)


def quantity(record, pressures, gap):
    """The watched quantity (the gap, or the pressure drop from ``pressures(node)``), in Python."""
    if record[GAP] > 0.5:
        return gap
    return pressures(int(record[SOURCE])) - pressures(int(record[TARGET]))


@nb.njit(**JIT)
def value(par, r, pa, pb, gap):
    """The event function: the quantity less the level, moved off an exact 0 to the flag's side."""
    x = gap if par[r + GAP] > 0.5 else pa - pb
    return _off_level(x - par[r + LEVEL], par[r + ON], par[r + LEVEL])
