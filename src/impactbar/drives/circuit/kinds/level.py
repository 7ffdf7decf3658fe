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
import numpy as np

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


@nb.njit(**JIT)
def _off_level(g, above, level):
    """An event function ``p - level`` exactly 0 moved by one unit in the last place of ``level`` to
    the side the mode's flag says the pressure is on (``above`` 1: at or above the level, watched
    for falling through it): the level is crossed where the pressure passes it, not where it
    touches it. A flight starts on the level where its event ended the last flight, and over the
    first steps the pressure's change can be below the rounding of the level: CVODE leaves an event
    function that is 0 at the start unwatched until it moves off 0 (a pressure that turns back
    through the level at once was missed, and CVODE warned that a root function stayed identically
    0), and takes a 0 after a step for a root (the accumulator would empty at once where the pump
    fills it). Every watched level's (this kind's, a spool's stop, the preset's accumulator and
    relief)."""
    if g != 0.0:
        return g
    u = np.spacing(abs(level))
    return u if above > 0.5 else -u
