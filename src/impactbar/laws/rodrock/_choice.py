"""The choices between the exact blow and the lattice that depend on the model's geometry alone
(theory §4d): whether the exact solver's cost is bounded, and whether a bit's mass is negligible.
:func:`~impactbar.single_blow` and the simulator's blows (:meth:`~impactbar.RodRock.blow_method`,
:mod:`impactbar.laws.rodrock.exactmap`) make them alike."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MAX_EXACT_LOADING_EXPONENT", "MAX_EXACT_PASS_WINDOWS", "NEGLIGIBLE_BIT"]


#: The most windows (of the shortest travel time in piston and rod) one round trip of a wave through
#: them may take for ``method="auto"`` to choose the exact solver: beyond, its cost grows with them
#: and the lattice, whose cost is bounded up front, is used.
MAX_EXACT_PASS_WINDOWS = 2e3

#: A bit is negligible (taken as massless by the exact solver) when its time constant ``m / Z_b``
#: against the last rod segment's impedance is at most this fraction of the shortest travel time and
#: it is overdamped on the rock (``4 m k_u <= Z_b^2``): its effect on every result is of that
#: relative order, far below the exact blow's accuracy, while its fast branch would make the exact
#: solver's series long (a bit of 1e-8 asked for more than 20 GB).
NEGLIGIBLE_BIT = 1e-10


#: The largest loading exponent ``k / Z_b`` times the shortest travel time for ``method="auto"`` to
#: choose the exact solver: a rock that stiff against the rod (a rod of impedance 1e-12 of the
#: piston's gave 2e8) makes its pieces overflow, where the lattice still answers.
MAX_EXACT_LOADING_EXPONENT = 1e6


def _exact_is_cheap(model, law, piston=None) -> bool:
    """Whether a round trip through piston (its segments, if stepped) and rod takes at most
    ``MAX_EXACT_PASS_WINDOWS`` windows and the rock's loading exponent over the shortest of them is
    at most ``MAX_EXACT_LOADING_EXPONENT``."""
    from ._piston import piston_segments

    s = model.s
    with np.errstate(over="ignore", divide="ignore"):  # (the array's methods: a call's fixed cost)
        if piston is None:
            own = [1.0 / s]
        else:
            lengths, _ = piston_segments(piston)
            own = list(lengths / s)
        travel = np.array(own + [g.travel_time(model) for g in law.segments])
        shortest = float(travel.min())
        rate = law.rock.k / (s * law.segments[-1].impedance) * shortest
    if not shortest > 0.0:  # (a travel time that underflowed: no window to count in)
        return False
    ratio = 2.0 * float(travel.sum()) / shortest
    return (bool(np.isfinite(travel).all()) and ratio <= MAX_EXACT_PASS_WINDOWS
            and rate <= MAX_EXACT_LOADING_EXPONENT)


def _bit_is_negligible(model, law) -> bool:
    """Whether the bit's mass is negligible (``NEGLIGIBLE_BIT``)."""
    m = law.bit_mass
    Zb = model.s * law.segments[-1].impedance
    with np.errstate(over="ignore", divide="ignore"):
        travel = [1.0 / model.s] + [g.travel_time(model) for g in law.segments]
    shortest = min(travel)
    return bool(0.0 < m and math.isfinite(Zb) and shortest > 0.0 and m <= NEGLIGIBLE_BIT * Zb * shortest
                and 4.0 * m * law.rock.k_u <= Zb * Zb)
