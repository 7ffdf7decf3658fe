"""The wave impact law (theory §4b, §4c): the stop is a long rod, the contact lasts ``2/s`` and is
solved by characteristics with the drive acting.

Layout: ``law`` (:class:`WaveLaw`, the contact step and its records :class:`PressedContact`),
``impact`` (:class:`WaveImpact` and :func:`wave_impact`: the characteristics solution of one
window, with the drive's part :func:`~impactbar.laws.wave.impact.window_drive`), ``_characteristics``
and ``_jumps`` (the solver on characteristics, the fields' jumps located exactly), ``sustained``
(the piston pressed on the rod after a window), ``periodic`` (the phase equation, the orbits'
states, the impact map's Jacobian and multipliers, the existence edge), ``_window`` and
``_separation`` (the compiled windows and the square wave's phase residual). ``law`` is imported with
the package; the numerics (scipy.optimize, numba) load on first use.
"""

import importlib

from .law import PressedContact as PressedContact
from .law import WaveLaw as WaveLaw

__all__ = ["WaveLaw", "PressedContact", "WaveImpact", "wave_impact"]


def __getattr__(name: str):
    # PEP 562: the characteristics solver loads numba; imported when first asked for
    if name in ("WaveImpact", "wave_impact"):
        value = getattr(importlib.import_module(".impact", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
