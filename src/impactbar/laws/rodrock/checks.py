"""The bounds a blow of the rod-and-rock law accepts (theory §4d) and the checks of
:func:`~impactbar.single_blow`'s arguments against them, made before any array is built: a
``ValueError`` naming the parameter and its range."""

from __future__ import annotations

import math

import numpy as np

from ..._shared.validate import check_int, check_real

#: The largest force scale (``s V``, the feed) and the smallest nonzero bit mass a blow accepts: the
#: wave energies are sums of squared forces, which beyond these would overflow or underflow.
MAX_FORCE = 1e100
MIN_BIT_MASS = 1e-100


def _check_force_scale(model, law, impact_velocity) -> float:
    """The checked impact velocity: its wave force ``s V`` and the feed within ``MAX_FORCE``, the
    bit's mass 0 or at least ``MIN_BIT_MASS``."""
    V = check_real("impact_velocity", impact_velocity, lo=0.0, lo_open=True)
    if not 1.0 / MAX_FORCE <= model.s * V <= MAX_FORCE:
        raise ValueError(f"impact_velocity must give a wave force s V in [{1 / MAX_FORCE:g}, {MAX_FORCE:g}] "
                         f"(s = {model.s:g}); got impact_velocity = {V:g}, whose wave energies would "
                         "overflow or underflow")
    if law.feed > MAX_FORCE:
        raise ValueError(f"feed must be in [0, {MAX_FORCE:g}] for a blow (its static energy would "
                         f"overflow); got feed = {law.feed:g}")
    if 0.0 < law.bit_mass < MIN_BIT_MASS:
        raise ValueError(f"bit_mass must be 0 (a massless bit) or in [{MIN_BIT_MASS:g}, inf) for a blow; "
                         f"got bit_mass = {law.bit_mass:g}")
    return V


def _check_blow_call(model, law, impact_velocity, t_max, cells_per_piston, record_field, piston=None):
    """The checked ``(V, t_max, cells_per_piston)`` of :func:`single_blow`, refused (``ValueError``
    naming the parameter and its range) before any array is built."""
    from ._piston import piston_segments
    from .grid import _check_blow_size, commensurate_cells

    p_len, _ = piston_segments(piston)
    s = model.s
    V = _check_force_scale(model, law, impact_velocity)
    travel = [g.travel_time(model) for g in law.segments]
    if not all(math.isfinite(T) for T in travel):  # a wave speed near 0: refused as the grid would be
        _check_blow_size(math.inf, math.inf, False)
    if t_max is None:
        t_max = 20.0 * (1.0 / s + sum(travel))
    else:
        t_max = check_real("t_max", t_max, lo=0.0, lo_open=True)
    if cells_per_piston is not None:
        cells_per_piston = check_int("cells_per_piston", cells_per_piston, lo=1)
        n_p = cells_per_piston
    else:  # the default grid of rod_rock_blow (at least 8 cells)
        n0 = commensurate_cells(np.concatenate(([1.0 / s], p_len / s, travel)))
        n_p = 64 if n0 is None else n0 * math.ceil(8 / n0)
    dt = 1.0 / (s * n_p)
    _check_blow_size(n_p + sum(travel) / dt, t_max / dt, record_field)
    m, Zb = law.bit_mass, s * law.segments[-1].impedance
    if m > 0.0:  # the lattice samples an underdamped bit's ringing on the rock within each step
        ring = math.sqrt(max(law.rock.k_u / m - (Zb / (2.0 * m)) ** 2, 0.0)) * dt
        if ring > MAX_BIT_RINGS:
            raise ValueError(f"bit_mass = {m:g} on k_u = {law.rock.k_u:g} rings {ring:.3g} radians a lattice "
                             f"step (more than {MAX_BIT_RINGS:g}): give a heavier bit, a bit_mass of 0, or "
                             "a finer grid (cells_per_piston)")
    return V, float(t_max), cells_per_piston


#: The most radians an underdamped bit may ring on the rock within one lattice step (its events are
#: sampled a quarter period apart there).
MAX_BIT_RINGS = 1e6

