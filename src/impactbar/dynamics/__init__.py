"""The bar's motion between and at impacts, on plain dimensionless arrays.

Layout: ``modal`` (the closed-form fundamental matrix of each damped mode and the integrals of a
constant load over a step, paper eqs. 5-9), ``certified`` (certified enclosure of the zeros of a
function with a Lipschitz or derivative bound), ``impact`` (the wave-resolved contact with a long
rod, solved by characteristics, theory §4b), ``_kernel`` (the numba-compiled flight, impact search
and event loop behind :func:`impactbar.simulate`), ``sustained`` (the wave law's sustained contact:
the struck end against the rod's impedance, theory §4b), ``_wavekernel`` and ``_flowkernel``
(compiled contact windows of the wave law, compiled flows of the loads), ``kernelview`` (the one
view of a load, and of a modal basis, that compiled code reads), ``implementations`` (the registry
that chooses between fast and reference implementations). The bottom of the core: imports only
numpy, scipy and numba, never another impactbar subpackage."""

import importlib

__all__ = ["WaveImpact", "wave_impact"]


def __getattr__(name: str):
    # PEP 562: ``impactbar.loads`` imports ``dynamics.modal``; the contact solver (scipy.optimize,
    # numba) is imported only when it is used, so ``import impactbar`` stays light
    if name in __all__:
        value = getattr(importlib.import_module(".impact", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
