"""The bar's motion between and at impacts, on plain dimensionless arrays: the building blocks every
impact law and every solver shares.

Layout: ``modal`` (the closed-form fundamental matrix of each damped mode and the integrals of a
constant load over a step, paper eqs. 5-9), ``certified`` (certified enclosure of the zeros of a
function with a Lipschitz or derivative bound, and the zeros of one harmonic in closed form),
``monodromy`` (a flight's linearisation with the saltation term at its arrival, the order of the
Floquet multipliers and their structured eigenvalue method, theory §7), ``invariants`` (the piston's
fields as Riemann invariants, where the laws that follow a blow along characteristics start,
theory §4c), ``_event_loop`` (the numba-compiled flight, impact search and event loop behind
:func:`impactbar.simulate`), ``_load_flow`` (compiled flows of the loads), ``_aberth`` (the
compiled Aberth-Ehrlich iteration), ``compiled`` (what the other packages use of those kernels, by
public names: the interface), ``compiled_views`` (the one view of a load, and of a modal basis,
that compiled code reads), ``implementations`` (the registry that chooses between fast and reference
implementations). The contact laws' own numerics are in :mod:`impactbar.laws`. The bottom of the
core: imports only numpy, scipy and numba, never another impactbar subpackage."""

#: names that moved to the wave law's package (the laws sit above the shared building blocks)
_MOVED = {"WaveImpact": "impactbar.WaveImpact", "wave_impact": "impactbar.wave_impact"}


def __getattr__(name: str):
    if name in _MOVED:
        raise AttributeError(f"impactbar.dynamics.{name} moved to {_MOVED[name]} (impactbar.laws.wave)")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
