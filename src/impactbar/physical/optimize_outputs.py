"""What a design's record of the whole-drifter optimiser reports besides its figures: the piston's
shape and the orbit's Floquet multipliers, and the stress wave the blow sends into the shank
(:func:`~impactbar.physical.optimize_drifter`)."""

from __future__ import annotations

import numpy as np

__all__ = ["piston_and_multipliers", "shank_stress"]


def piston_and_multipliers(drifter, orbit) -> dict:
    """A design record's piston (its segments' lengths and diameters, its mass and chamber areas, SI)
    and its orbit's Floquet multipliers (real and imaginary parts; none without an orbit).

    Parameters
    ----------
    drifter : CircuitDrifter
    orbit : CircuitDrifterOrbit or None

    Returns
    -------
    dict
        ``{"piston": {...}, "multipliers_re": [...], "multipliers_im": [...]}``.
    """
    bar = drifter.bar
    lengths = list(getattr(bar, "lengths_m", [bar.length_m]))
    diameters = list(getattr(bar, "diameters_m", [bar.diameter_m]))
    mu = np.asarray([] if orbit is None else orbit.multipliers, dtype=complex)
    return {"piston": {"lengths_m": [float(x) for x in lengths], "diameters_m": [float(x) for x in diameters],
                       "mass_kg": bar.mass_kg, "rear_area_m2": drifter.si["rear_area_m2"],
                       "front_area_m2": drifter.si["front_area_m2"]},
            "multipliers_re": mu.real.tolist(), "multipliers_im": mu.imag.tolist()}


def shank_stress(drifter, orbit) -> dict | None:
    """The stress in the shank adapter over the first blow: the incident wave, whose peak the peak
    incident stress is, and what the rod and rock return (theory §4d).

    Parameters
    ----------
    drifter : CircuitDrifter
    orbit : CircuitDrifterOrbit

    Returns
    -------
    dict or None
        ``{"t_s": [...], "stress_Pa": [...]}`` (s, Pa); ``None`` without a rock.
    """
    if drifter.drill is None:
        return None
    blow = orbit.orbit.contacts[0]
    sc = drifter.scales
    return {"t_s": (np.asarray(blow.times[:-1], dtype=float) * sc.time_s).tolist(),
            "stress_Pa": (np.asarray(blow.shank_forces, dtype=float) * sc.force_N
                          / drifter.drill.segments[0].area_m2).tolist()}
