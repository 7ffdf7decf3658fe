"""The oil circuit's continuation parameters, declared once (theory §11): each one's dimensionless
name, the part and the field that hold it, its range and its description.

The drive's tables are views of :data:`DECLARED`: :data:`~impactbar.drives.circuit.drive.PARAMETERS`
(name to part and field, what ``with_`` changes), the ranges its records state
(``drive.params.parameter_table()``) and its ``parameters``; the tree of SI parameters
(:mod:`impactbar.physical.tree`) names these parameters as the ones its fields set.

Examples
--------
>>> from impactbar.drives.circuit.parameters import DECLARED
>>> p = next(p for p in DECLARED if p.name == "area_ratio")
>>> p.part, p.field, p.ranges["high"], p.ranges["high_open"]
('chambers', 'area_ratio', 1.0, True)
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["CircuitParameter", "DECLARED"]


class CircuitParameter(NamedTuple):
    """One continuation parameter of the oil circuit (theory §11), dimensionless.

    Parameters
    ----------
    name : str
        Its name (``"pump_flow"``): the keyword of the drive's ``with_``.
    part : str
        The drive's part that holds it (``"supply"``, ``"accumulator"``, ``"valve"``, ``"chambers"``,
        ``"oil"``).
    field : str
        The part's field (``"pump_flow"``; the valve's ``"coefficient"`` for ``valve_coefficient``).
    description : str
        A short description (its record's).
    low : float
        Its lower bound (pressure-scaled values: 0 for every one but the gas's exponent, 1).
    low_open : bool
        Whether ``low`` is excluded.
    high : float or None
        Its upper bound; ``None``: none.
    high_open : bool
        Whether ``high`` is excluded; without ``high``, whether infinity is (a finite value required:
        every one but the relief pressure, whose infinity means no relief valve).
    """

    name: str
    part: str
    field: str
    description: str
    low: float = 0.0
    low_open: bool = False
    high: float | None = None
    high_open: bool = True

    @property
    def ranges(self) -> dict:
        """The keyword arguments of its :class:`~impactbar.parameters.Parameter` record (``low``,
        ``high``, ``low_open`` and ``high_open`` where true, ``description``)."""
        out: dict = {"low": self.low}
        if self.high is not None:
            out["high"] = self.high
        if self.low_open:
            out["low_open"] = True
        if self.high_open:
            out["high_open"] = True
        out["description"] = self.description
        return out


_P = CircuitParameter

#: The circuit's continuation parameters, in the order the drive lists them (its ``parameters``); the
#: parts' constructors check them again, with the ranges that depend on another parameter (a held
#: supply pressure above the tank's, ``switch_in`` below ``switch_out``, the pre-charge below the
#: relief pressure).
DECLARED: tuple[CircuitParameter, ...] = (
    _P("pump_flow", "supply", "pump_flow", "the pump's flow", low_open=True),
    _P("supply_pressure", "supply", "pressure", "pressure of a supply held at a pressure"),
    _P("hose_volume", "supply", "hose_volume", "the supply hose's oil volume", low_open=True),
    _P("front_coefficient", "supply", "front_coefficient",
       "flow coefficient of the supply to the front chamber", low_open=True),
    _P("tank_pressure", "supply", "tank_pressure", "the tank's pressure"),
    _P("relief_pressure", "supply", "relief_pressure",
       "the relief valve's cracking pressure (inf: no relief valve)", low_open=True, high_open=False),
    _P("relief_coefficient", "supply", "relief_coefficient", "the relief valve's flow coefficient"),
    _P("precharge", "accumulator", "precharge", "the accumulator's gas pre-charge", low_open=True),
    _P("accumulator_volume", "accumulator", "volume", "the accumulator's gas volume"),
    _P("polytropic_exponent", "accumulator", "polytropic_exponent", "the gas's polytropic exponent", low=1.0,
       high=2.0, high_open=False),
    _P("switch_out", "valve", "switch_out", "gap whose rising crossing opens the valve", low_open=True),
    _P("switch_in", "valve", "switch_in", "gap whose falling crossing closes the valve", low_open=True),
    _P("switching_time", "valve", "switching_time", "a full stroke of the valve's spool"),
    _P("valve_coefficient", "valve", "coefficient", "the valve's flow coefficient", low_open=True),
    _P("area_ratio", "chambers", "area_ratio", "area of the front annulus over the rear's", low_open=True,
       high=1.0),
    _P("rear_volume", "chambers", "rear_volume", "the rear chamber's dead volume", low_open=True),
    _P("front_volume", "chambers", "front_volume", "the front chamber's dead volume", low_open=True),
    _P("bulk_modulus", "oil", "bulk_modulus", "the oil's bulk modulus", low_open=True),
    _P("transition_pressure", "oil", "transition_pressure",
       "transition pressure of the orifices' smoothed law", low_open=True),
)

