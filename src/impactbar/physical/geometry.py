r"""A drifter's piston given by its shape: the segments' lengths and diameters, from which the chamber
areas, the mass and the stepped piston follow (theory §11, "The piston's shape and the chambers").

A differential piston runs in a bore of the collar's diameter :math:`D_c`; its rear rod
(:math:`d_r`, the driven end) and its front rod (:math:`d_f`, towards the struck end) pass through the
seals at each end of the bore, so the oil presses on the annuli

.. math::

    A_r = \tfrac{\pi}{4}\,(D_c^2 - d_r^2), \qquad A_f = \tfrac{\pi}{4}\,(D_c^2 - d_f^2),

the rear chamber's and the front chamber's areas (the stroke needs :math:`A_r > A_f`, so
:math:`d_r < d_f`). The piston is the stepped bar of the rear rod, the collar, the front rod and any
further steps of the striking end, driven end first (:class:`~impactbar.physical.SteppedBar`), its
mass :math:`\rho \sum_j A_j L_j`.

Configuration (a ``[piston]`` section of a drifter with its oil circuit, in place of ``[bar]`` and
of ``chambers.rear_area`` / ``chambers.front_area``)::

    [piston]  E, density,
              rear_rod_diameter, rear_rod_length, collar_diameter, collar_length,
              front_rod_diameter, front_rod_length,
              end_diameters, end_lengths            # optional lists: the striking end's steps
"""

from __future__ import annotations

import copy
import math

from .tree import required_keys, section_keys

__all__ = ["PISTON_KEYS", "piston_geometry", "expand_piston"]

#: The keys of a ``[piston]`` section (declared in :mod:`impactbar.physical.tree`).
PISTON_KEYS = section_keys(("piston",))["piston"]

_REQUIRED = required_keys(("piston",))["piston"]


def _length(key: str, value) -> float:
    from .units import to_si

    x = to_si(key, value, "m", "'45 mm'", what="a length")
    if not (math.isfinite(x) and x > 0.0):
        raise ValueError(f"{key} must be a positive length, e.g. '45 mm'; got {value!r}")
    return x


def piston_geometry(section: dict) -> dict:
    r"""The piston's segments and chamber areas from a ``[piston]`` section (SI).

    Parameters
    ----------
    section : dict
        The keys of :data:`PISTON_KEYS` with units (``"45 mm"``); ``end_diameters`` and
        ``end_lengths`` lists of the same length (the striking end's steps, in order towards it).

    Returns
    -------
    dict
        ``lengths_m`` and ``diameters_m`` (lists, driven end first: rear rod, collar, front rod,
        the steps), ``rear_area_m2`` :math:`\pi (D_c^2 - d_r^2)/4`, ``front_area_m2``
        :math:`\pi (D_c^2 - d_f^2)/4` and ``mass_kg``.

    Raises
    ------
    ValueError
        An unknown or missing key, a length not positive or without its unit, lists of
        different lengths, or a chamber area that would be zero or negative (the keys named).

    Examples
    --------
    >>> from impactbar.physical.geometry import piston_geometry
    >>> g = piston_geometry({"E": "210 GPa", "density": "7850 kg/m^3", "rear_rod_diameter": "40 mm",
    ...     "rear_rod_length": "100 mm", "collar_diameter": "50 mm", "collar_length": "100 mm",
    ...     "front_rod_diameter": "45 mm", "front_rod_length": "250 mm"})
    >>> round(g["rear_area_m2"] * 1e4, 4), round(g["front_area_m2"] * 1e4, 4)
    (7.0686, 3.7306)
    >>> piston_geometry({**{"E": "210 GPa", "density": "7850 kg/m^3", "rear_rod_diameter": "40 mm",
    ...     "rear_rod_length": "100 mm", "collar_diameter": "40 mm", "collar_length": "100 mm",
    ...     "front_rod_diameter": "45 mm", "front_rod_length": "250 mm"}})
    Traceback (most recent call last):
    ...
    ValueError: piston: the rear chamber's area pi/4 (collar_diameter^2 - rear_rod_diameter^2) must be
    above 0; got 0 cm^2 (piston.collar_diameter 40 mm, piston.rear_rod_diameter 40 mm)
    """
    from .bar import _positive_si
    from .config import _section

    section = _section({"piston": section}, "piston", PISTON_KEYS)  # a table, its keys known
    for key in _REQUIRED:
        if key not in section:
            raise ValueError(f"missing key piston.{key}")
    end_lengths, end_diameters = section.get("end_lengths", []), section.get("end_diameters", [])
    if not (isinstance(end_lengths, list) and isinstance(end_diameters, list)) \
            or len(end_lengths) != len(end_diameters):
        raise ValueError("piston.end_lengths and piston.end_diameters must be lists of the same length; got "
                         f"{end_lengths!r} and {end_diameters!r}")
    d = {k: _length(f"piston.{k}", section[k]) for k in _REQUIRED[2:]}
    lengths = [d["rear_rod_length"], d["collar_length"], d["front_rod_length"]]
    lengths += [_length(f"piston.end_lengths[{j}]", x) for j, x in enumerate(end_lengths)]
    diameters = [d["rear_rod_diameter"], d["collar_diameter"], d["front_rod_diameter"]]
    diameters += [_length(f"piston.end_diameters[{j}]", x) for j, x in enumerate(end_diameters)]
    areas = {}
    for side, rod in (("rear", "rear_rod_diameter"), ("front", "front_rod_diameter")):
        a = math.pi / 4.0 * (d["collar_diameter"] ** 2 - d[rod] ** 2)
        if not a > 0.0:
            raise ValueError(f"piston: the {side} chamber's area pi/4 (collar_diameter^2 - {rod}^2) must be "
                             f"above 0; got {a * 1e4:.4g} cm^2 (piston.collar_diameter "
                             f"{d['collar_diameter'] * 1e3:.4g} mm, piston.{rod} {d[rod] * 1e3:.4g} mm)")
        areas[side] = a
    if not areas["front"] < areas["rear"]:
        raise ValueError("piston.front_rod_diameter must be above piston.rear_rod_diameter (the rear area "
                         "above the front one, for the stroke to push toward the rod); got "
                         f"{d['front_rod_diameter'] * 1e3:.4g} mm and {d['rear_rod_diameter'] * 1e3:.4g} mm")
    # (named here: the [bar] that expand_piston writes would name bar.E, bar.density)
    _positive_si("piston.E", section["E"], "Pa", "'210 GPa'", "a pressure")
    rho = _positive_si("piston.density", section["density"], "kg/m**3", "'7850 kg/m^3'", "a density")
    mass = rho * sum(math.pi / 4.0 * dia ** 2 * le for dia, le in zip(diameters, lengths, strict=True))
    return {"lengths_m": lengths, "diameters_m": diameters, "rear_area_m2": areas["rear"],
            "front_area_m2": areas["front"], "mass_kg": mass}


def expand_piston(config: dict) -> dict:
    """A copy of a circuit drifter's configuration with its ``[piston]`` written out as the stepped
    ``[bar]`` and the chamber areas it implies (:func:`piston_geometry`), in SI: what
    :meth:`~impactbar.physical.CircuitDrifter.from_config` reads.

    Raises
    ------
    ValueError
        A ``[piston]`` beside a ``[bar]`` or beside ``chambers.rear_area`` / ``chambers.front_area``
        (give the shape or the areas, not both), or what :func:`piston_geometry` refuses.
    """
    if "bar" in config:
        raise ValueError("give the piston either as [piston] (its shape) or as [bar], not both")
    chambers = config.get("chambers", {})
    given = sorted({"rear_area", "front_area"} & set(chambers if isinstance(chambers, dict) else {}))
    if given:
        raise ValueError(f"chambers.{given[0]}: with a [piston] the chamber areas follow from its diameters "
                         "(leave rear_area and front_area out)")
    g = piston_geometry(config["piston"])
    out = copy.deepcopy(config)
    sec = out.pop("piston")
    out["bar"] = {"E": sec["E"], "density": sec["density"],
                  "length": [f"{x!r} m" for x in g["lengths_m"]],
                  "diameter": [f"{x!r} m" for x in g["diameters_m"]]}
    out.setdefault("chambers", {})
    out["chambers"]["rear_area"] = f"{g['rear_area_m2']!r} m**2"
    out["chambers"]["front_area"] = f"{g['front_area_m2']!r} m**2"
    return out
