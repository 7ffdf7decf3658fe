"""The bar's motion between and at impacts, on plain dimensionless arrays.

Layout: ``modal`` (the closed-form fundamental matrix of each damped mode and the integrals of a
constant load over a step, paper eqs. 5-9), ``certified`` (certified enclosure of the zeros of a
function with a Lipschitz or derivative bound), ``impact`` (the wave-resolved contact with a long
rod, solved by characteristics, theory §4b), ``_kernel`` (the numba-compiled flight, impact
search and event loop behind :func:`impactbar.simulate`). The bottom of the core: imports only
numpy, scipy and numba, never another impactbar subpackage.
"""

from .impact import WaveImpact as WaveImpact
from .impact import wave_impact as wave_impact

__all__ = ["WaveImpact", "wave_impact"]
