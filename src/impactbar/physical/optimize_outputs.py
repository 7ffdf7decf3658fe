"""What a design's record of the whole-drifter optimiser reports: the output each constraint limits
(:mod:`~impactbar.physical.outputs`), and besides its figures the piston's shape and the orbit's
Floquet multipliers, and the stress wave the blow sends into the shank
(:func:`~impactbar.physical.optimize_drifter`)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .outputs import OUTPUTS, current_name

__all__ = ["constraint_output", "piston_and_multipliers", "shank_stress"]

#: Each constraint: the output it limits (:mod:`~impactbar.physical.outputs`, its unit the
#: constraint's), its sense (+1: the value at most the limit; -1: at least) and the scale of its
#: normalised margin for the search (``None``: the limit's size). Each is named by its output: its
#: name or key, ``min_<name>`` for at least (a least over the period, ``minimum_pressure`` and
#: ``min_chamber_volume``, at least by its own name). Any other output is a constraint too: by its
#: name at most the limit, ``min_<name>`` at least; an output that is itself a least value over the
#: period (its name ``min_...`` or ``minimum_...``: ``min_rear_pressure``) at least by its own name,
#: as ``minimum_pressure`` (:func:`constraint_output`).
_CONSTRAINTS = {"peak_rod_stress": ("peak_rod_stress", 1, None),
                "max_multiplier": ("max_abs_multiplier", 1, 1.0),
                "minimum_pressure": ("minimum_pressure", -1, 1e6),
                "mean_supply_pressure": ("mean_supply_pressure", 1, None),
                "peak_supply_pressure": ("peak_supply_pressure", 1, None),
                "min_chamber_volume": ("min_chamber_volume", -1, 1e-4),
                "min_drilling_rate": ("drilling_rate", -1, None), "piston_mass": ("piston_mass", 1, None)}


#: The prefixes of an output that is a least value over the period: constrained by its own name,
#: its value at least the limit.
_LEAST = ("min_", "minimum_")


class _Constrained(NamedTuple):
    """What a constraint limits: the output, the sense (+1: at most the limit; -1: at least), the
    scale of its margin (``None``: the limit's) and its unit."""

    output: object
    sense: int
    scale: float | None
    unit: str


def constraint_output(name: str, kind: str = "circuit") -> _Constrained | None:
    """The output a constraint limits, its sense (+1: at most the limit; -1: at least), the scale of
    its margin (``None``: the limit's) and its unit; ``None`` for no constraint of that name that a
    machine of ``kind`` (``"circuit"``: the drifter with its oil circuit, ``"drifter"``: the valve
    drifter; :mod:`~impactbar.physical.outputs`) has.

    Examples
    --------
    >>> from impactbar.physical.optimize_outputs import constraint_output
    >>> o, sense, scale, unit = constraint_output("min_drilling_rate")
    >>> o.name, sense, unit
    ('drilling_rate', -1, 'm/min')
    >>> constraint_output("min_impact_velocity").output.name, constraint_output("speed")
    ('impact_velocity', None)
    >>> constraint_output("minimum_pressure", "drifter") is None  # (no oil)
    True
    >>> constraint_output("min_rear_pressure").sense  # (a least value: at least the limit)
    -1
    """
    name = current_name(name, "constraint")  # (an old name: a DeprecationWarning)
    if name in _CONSTRAINTS:
        out, sense, scale = _CONSTRAINTS[name]
    else:
        out, sense, scale = (name, 1, None) if name in OUTPUTS or not name.startswith("min_") else \
            (name[4:], -1, None)
        if out == name and name.startswith(_LEAST):  # (a least value over the period: at least)
            sense = -1
    o = OUTPUTS.get(out)
    if o is None or o.of is None or kind not in o.machines or o.dtype != "f8":
        return None
    return _Constrained(o, sense, scale, "" if o.unit == "1" else o.unit)


def piston_and_multipliers(drifter, orbit) -> dict:
    """A design record's piston (its segments' lengths and diameters, its mass and chamber areas, SI)
    and its orbit's Floquet multipliers (real and imaginary parts; none without an orbit).

    Parameters
    ----------
    drifter : CircuitDrifter or Drifter
    orbit : CircuitDrifterOrbit or DrifterOrbit or None

    Returns
    -------
    dict
        ``{"piston": {...}, "multipliers_re": [...], "multipliers_im": [...]}``; a valve drifter's
        piston has its ``stroke_area_m2`` and ``return_area_m2`` for the chambers' areas.
    """
    bar = drifter.bar
    lengths = list(getattr(bar, "lengths_m", [bar.length_m]))
    diameters = list(getattr(bar, "diameters_m", [bar.diameter_m]))
    mu = np.asarray([] if orbit is None else orbit.multipliers, dtype=complex)
    return {"piston": {"lengths_m": [float(x) for x in lengths], "diameters_m": [float(x) for x in diameters],
                       "mass_kg": bar.mass_kg, **_areas(drifter)},
            "multipliers_re": mu.real.tolist(), "multipliers_im": mu.imag.tolist()}


def _areas(drifter) -> dict:
    """The areas the oil drives the piston on (m^2): the chambers', or the valve drifter's."""
    if hasattr(drifter, "si"):
        return {"rear_area_m2": drifter.si["rear_area_m2"], "front_area_m2": drifter.si["front_area_m2"]}
    return {"stroke_area_m2": drifter.stroke_area_m2, "return_area_m2": drifter.return_area_m2}


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
