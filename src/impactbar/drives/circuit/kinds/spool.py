r"""A pilot-operated spool (theory §11, *Parts of a drill's circuit*): the spool's mechanics, the
state of the part that replaces the preset's ramped valve (:class:`~impactbar.drives.circuit.SpoolValve`).

The spool's position ``x_s`` in ``[0, h_s]`` is kept as ``x = x_s / h_s`` in the network's ``x_v``
slot (the state the ramped valve's opening has), its velocity ``v_s`` as the "pressure" of a node of
its own of volume ``m_s`` and bulk modulus 1 (so that the node's capacitance is the mass, its net
inflow the force, its rate ``v_s'`` and its compression work ``m_s v_s v_s'``, the spool's kinetic
energy's rate; held, the spool rests at a stop):

- ``m_s v_s' = A_c p_c - A_0 p_s - b_s v_s`` (the control chamber's pressure on the large end opens
  it, the supply's on the small end closes it), ``x' = v_s / h_s``;
- the control chamber's volume is its node's ``V_c + A_c x_s``, its net inflow takes ``-A_c v_s``;
  the supply node's volume ``V_s - A_0 x_s``, its net inflow ``+A_0 v_s``;
- the damping's loss :math:`b_s v_s^2` into the record's energy slot;
- the stop's event: free, ``-x (1 - x)`` (rising through 0 at either stop); resting at a stop, the
  force into it (``-(A_c p_c - A_0 p_s)`` at 0, ``+`` at 1; falling through 0 where it turns strictly
  away).

The record: ``control``, ``supply``, ``velocity`` (nodes), ``large_area`` (``A_c``), ``small_area``
(``A_0``), ``stroke`` (``h_s``), ``damping`` (``b_s``), ``energy`` (the damping's loss slot), ``event``
(the stop's event slot). The mass is the velocity node's volume; whether the spool rests at a stop,
that node's ``held`` flag.
"""

from __future__ import annotations

import numba as nb

from ._flow import JIT
from .level import _off_level

CODE = 11
NAME = "spool"
CONTROL, SUPPLY, VELOCITY, LARGE, SMALL, STROKE, DAMPING, ENERGY, EVENT = range(1, 10)
FIELDS = {"control": CONTROL, "supply": SUPPLY, "velocity": VELOCITY, "large_area": LARGE,
          "small_area": SMALL, "stroke": STROKE, "damping": DAMPING, "energy": ENERGY, "event": EVENT}
NODES = (CONTROL, SUPPLY, VELOCITY)
ENERGIES = (ENERGY,)
EVENTS = (EVENT,)


@nb.njit(**JIT)
def force(par, r, pc, ps):
    """The oil's force on the spool, opening it: ``A_c p_c - A_0 p_s``."""
    return par[r + LARGE] * pc - par[r + SMALL] * ps


def stop_quantity(x, force_):
    r"""The stop's event quantity in Python: at a stop (:math:`x \le 0` or :math:`x \ge 1`) the force into it,
    else ``-x (1 - x)`` (so that it is at or above 0 exactly where the spool rests)."""
    if x <= 0.0:
        return -force_
    if x >= 1.0:
        return force_
    return -x * (1.0 - x)


@nb.njit(**JIT)
def value(par, r, held, x, pc, ps):
    """The stop's event function (moved off an exact 0 to the side of the flag ``held``)."""
    if held > 0.5:
        f = force(par, r, pc, ps)
        g = f if x >= 0.5 else -f
    else:
        g = -x * (1.0 - x)
    return _off_level(g, held, 1.0)
