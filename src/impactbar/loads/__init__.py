"""Periodic loads of period ``2 pi`` at the driven end (theory §3, paper eqs. 7, 33, 34).

A load is ``p(t) = Re sum_{k>=0} p_k exp(i k t)`` in its own time frame; an impact at phase ``phase``
sees ``p(t + phase)`` (eq. 7). Each load also knows the exact motion of a modal oscillator
``q'' + d q' + w2 q = p(t)`` that it drives (eq. 8), which is all the rest of the package needs.
"""

from __future__ import annotations

from .abilities import LoadAbilities, LoadKernel, LoadTraits
from .base import LOADS, Load, load_from_record, register_load
from .fourier import CosineLoad, FourierLoad
from .piecewise import PiecewiseConstantLoad, SquareWaveLoad

__all__ = ["Load", "FourierLoad", "CosineLoad", "PiecewiseConstantLoad", "SquareWaveLoad", "LOADS",
           "register_load", "load_from_record", "LoadTraits", "LoadAbilities", "LoadKernel"]


# the table of loads (kind -> class), in the order the CLI and the sweep spec list them
LOADS.update({cls.traits.kind: cls
              for cls in (CosineLoad, SquareWaveLoad, FourierLoad, PiecewiseConstantLoad)})
