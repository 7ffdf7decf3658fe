"""The checks of a circuit drifter's config in SI (:meth:`impactbar.physical.CircuitDrifter.from_config`):
each value against its range before the conversion to the dimensionless circuit, the message in the
user's terms, the key as ``section.key`` and the value as given, with its unit
(``"supply.relief_pressure must be above supply.tank_pressure (0.3 MPa); got 0.2 MPa"``)."""

from __future__ import annotations

import math

from .display_units import display_unit, format_si, written_unit
from .tree import in_sections

#: The circuit's keys with a bound of their own, in the order they are checked: the SI value's name,
#: its unit and the rule (``"positive"``: above 0; ``"non_negative"``: 0 or above, with what 0 means),
#: a view of the tree's declarations (:attr:`~impactbar.physical.tree.Field.bound`).
_RANGES = tuple((f.key, f.si, f.unit.replace("**", "^"),
                 f.bound if f.bound == "positive" else (f.bound, f.zero)) for f in in_sections() if f.bound)

def shown(value, si: float, unit: str) -> str:
    """A config value as the user wrote it (a string in a unit of their own), else its SI value in the
    key table's display unit (a value the package wrote in SI, e.g. along a branch, reads in L, MPa)."""
    si_unit, wrote = unit.replace("^", "**"), written_unit(value)
    _, shown = display_unit(si_unit)
    if wrote is not None and (wrote.replace("^", "**") != si_unit or shown == unit):
        return value.strip()
    return format_si(si, si_unit)


def check_circuit_si(sec: dict, si: dict, restitution: float) -> None:
    """Refuse a value of the config out of its range, naming its key (``section.key``) and quoting
    it with its unit.

    Parameters
    ----------
    sec : dict
        The config's sections (``{"supply": {...}, ...}``), the values as given.
    si : dict
        Their SI values, by the names of :class:`~impactbar.physical.CircuitDrifter`'s ``si``.
    restitution : float
        ``R`` (checked where ``stop.restitution`` gives it).

    Raises
    ------
    ValueError
        The first value out of range, with its key, its value and unit, and the range.
    """
    def given(key):
        section, k = key.split(".")
        return k in sec[section]

    def fail(key, name, unit, must):
        section, k = key.split(".")
        raise ValueError(f"{key} must be {must}; got {shown(sec[section][k], si[name], unit)}")

    for key, name, unit, rule in _RANGES:
        if not given(key):
            continue
        v = si[name]
        if rule == "positive" and not v > 0.0:
            fail(key, name, unit, "positive")
        if isinstance(rule, tuple) and not v >= 0.0:
            _, why = rule  # ("non_negative", why)
            fail(key, name, unit, f"0 or above ({why})")
    ch, su = sec["chambers"], sec["supply"]
    if si["front_area_m2"] >= si["rear_area_m2"]:
        fail("chambers.front_area", "front_area_m2", "m^2",
             f"below chambers.rear_area ({shown(ch['rear_area'], si['rear_area_m2'], 'm^2')}) for the "
             "stroke to push toward the stop")
    stroke = si["rear_volume_m3"] / si["rear_area_m2"]  # where the retracting piston empties the rear chamber
    if given("valve.switch_out") and not si["switch_out_m"] < stroke:
        vol = shown(ch["rear_volume"], si["rear_volume_m3"], "m^3")
        area = shown(ch["rear_area"], si["rear_area_m2"], "m^2")
        fail("valve.switch_out", "switch_out_m", "m",
             f"in (0, {format_si(stroke, 'm', sec['valve']['switch_out'])}): below the rear chamber's "
             f"length, chambers.rear_volume / chambers.rear_area ({vol} / {area}), where the piston, still "
             "retracting, empties the rear chamber before it reaches the switch point")
    if given("valve.switch_in") and not 0.0 < si["switch_in_m"] < si["switch_out_m"]:
        out = shown(sec["valve"]["switch_out"], si["switch_out_m"], "m")
        fail("valve.switch_in", "switch_in_m", "m", f"above 0 and below valve.switch_out ({out})")
    tank = shown(su["tank_pressure"], si["tank_pressure_Pa"], "Pa")
    if given("supply.relief_pressure"):
        if not si["relief_pressure_Pa"] > si["tank_pressure_Pa"]:
            fail("supply.relief_pressure", "relief_pressure_Pa", "Pa",
                 f"above supply.tank_pressure ({tank})")
        if not si["relief_coefficient"] > 0.0:
            raise ValueError("supply.relief_coefficient must be positive with a supply.relief_pressure; got "
                             + shown(su.get("relief_coefficient", 0.0), si["relief_coefficient"], "m^3/s/Pa"))
    if given("accumulator.polytropic_exponent") and not 1.0 <= si["polytropic_exponent"] <= 2.0:
        fail("accumulator.polytropic_exponent", "polytropic_exponent", "",
             "in [1, 2] (1 isothermal, 1.4 adiabatic nitrogen)")
    if given("accumulator.precharge") and si["accumulator_volume_m3"] > 0.0 \
            and math.isfinite(si["relief_pressure_Pa"]) and si["precharge_Pa"] >= si["relief_pressure_Pa"]:
        rel = shown(su["relief_pressure"], si["relief_pressure_Pa"], "Pa")
        fail("accumulator.precharge", "precharge_Pa", "Pa",
             f"below supply.relief_pressure ({rel}): the accumulator would never take oil")
    st = sec["stop"]
    if "restitution" in st and not 0.0 <= restitution < 1.0:
        got = shown(st["restitution"], restitution, "")
        raise ValueError(f"stop.restitution must be in [0, 1); got {got}")
