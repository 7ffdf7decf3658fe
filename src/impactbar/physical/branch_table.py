"""The columns of a drifter's continued branch as ``impactbar continue`` writes it (``branch.csv``,
``events.csv``), each read from a declaration: none is written by hand.

``branch.csv``, in order:

- for a continued config key, the key in the unit ``--to`` was given in (``supply.pump_flow
  (L/min)``; the parameter tree's key or a part's, :func:`~impactbar.physical.tree.is_config_key`);
- the dimensionless continuation parameter by its own name (``delay``, ``pump_flow``,
  ``precharge``: theory §10, §11), as :meth:`~impactbar.Branch.to_dataframe` and a dimensionless
  sweep's axis name it;
- the dimensionless orbit's fields (:data:`~impactbar.orbits.orbit.ORBIT_FIELDS`: ``period``,
  ``impact_velocity``, ``max_abs_multiplier``, ``stable``; :data:`ORBIT_COLUMNS`);
- for a drifter with its oil circuit, the outputs of the view ``"branch"`` of the output registry
  (:mod:`~impactbar.physical.outputs`) by their keys with the display unit, in it
  (``mean_supply_pressure_MPa``).

One name, one unit: a field of the dimensionless orbit named as an output of the registry that has
a unit (the output ``impact_velocity`` is in m/s, ``period`` in s) is written with the suffix
:data:`DIMENSIONLESS` (``impact_velocity_dimensionless``); a pure number or a flag
(``max_abs_multiplier``, ``stable``) keeps its name, the same in both.

``events.csv``: the event's kind (with the border a border collision crosses), the parameter's value
by the same name as in ``branch.csv``, the critical multiplier's real and imaginary parts
(:attr:`~impactbar.BranchEvent.fields`, spread as :meth:`~impactbar.Branch.to_xarray` spreads a
complex field) and, for a config key, its value in the unit of ``--to``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from .._shared.schema import Field, Schema
from ..continuation.branch import BranchEvent
from ..orbits.orbit import ORBIT_FIELDS
from .outputs import OUTPUTS, Output, output_values, outputs

__all__ = ["DIMENSIONLESS", "ORBIT_COLUMNS", "EVENT_COLUMNS", "dimensionless_column", "branch_outputs",
           "branch_rows", "event_rows"]

#: The suffix of a dimensionless orbit's column whose name an output of another unit has.
DIMENSIONLESS = "_dimensionless"


def dimensionless_column(declared: Field) -> Field:
    """A field of the dimensionless orbit as a column beside the registry's outputs: its name, or
    with :data:`DIMENSIONLESS` where an output of that name has a unit (module docstring).

    Parameters
    ----------
    declared : Field
        A field of :data:`~impactbar.orbits.orbit.ORBIT_FIELDS` (dimensionless, units ``"1"``, or a
        flag).

    Returns
    -------
    Field
        The field, renamed where needed; its value still read from the orbit's attribute.
    """
    o = OUTPUTS.get(declared.name)
    if o is None or o.unit in ("", "1"):
        return declared
    return dataclasses.replace(declared, name=declared.name + DIMENSIONLESS,
                               attr=declared.attr or declared.name)


#: The dimensionless orbit's columns of ``branch.csv``, after the parameter (theory §10 and §11): its
#: fields in the view ``"drifter_branch"``.
ORBIT_COLUMNS = Schema(*(dimensionless_column(f) for f in ORBIT_FIELDS.select("drifter_branch")))

#: The declared fields of an event that ``events.csv`` writes, the parameter's value by the
#: parameter's name: the kind (with its surface), the value, the critical multiplier.
EVENT_COLUMNS = BranchEvent.fields.select(names=("kind", "value", "multiplier"))


def branch_outputs(circuit: bool) -> list[Output]:
    """The registry's outputs a drifter's ``branch.csv`` adds: those of the view ``"branch"`` for a
    drifter with its oil circuit (without the rock), none for the valve drifter."""
    return outputs("branch", "circuit", rock=False) if circuit else []


def _number(value) -> str:
    return str(bool(value)) if isinstance(value, bool | np.bool_) else f"{value:.12g}"


def branch_rows(branch, *, key: str | None = None, shown: Callable | None = None, points=(),
                columns=()) -> list[str]:
    """The lines of ``branch.csv``.

    Parameters
    ----------
    branch : Branch
        The dimensionless branch (:func:`~impactbar.continue_orbit`).
    key : str, optional
        The continued config key's column (``"supply.pump_flow (L/min)"``); none for a
        dimensionless parameter.
    shown : callable, optional
        ``shown(value)``: the dimensionless parameter's value in the key's column's unit (with
        ``key``).
    points : sequence of CircuitDrifterOrbit
        The operating point at each point of the branch (with ``columns``).
    columns : sequence of Output
        The registry's outputs written after the orbit's fields (:func:`branch_outputs`).

    Returns
    -------
    list of str
        The header, then a line per point (numbers to 12 significant digits).
    """
    head = ([key] if key else []) + [branch.parameter, *ORBIT_COLUMNS.names] + [o.shown_key for o in columns]
    rows = [",".join(head)]
    for i, (lam, orbit) in enumerate(zip(branch.values, branch.orbits, strict=True)):
        cells = ([shown(lam)] if key else []) + [lam] + [f.get(orbit) for f in ORBIT_COLUMNS]
        if columns:
            values = output_values(points[i], columns)
            cells += [o.shown(values[o.name]) for o in columns]
        rows.append(",".join(_number(c) for c in cells))
    return rows


def event_rows(branch, *, key: str | None = None, shown: Callable | None = None) -> list[str]:
    """The lines of ``events.csv``: the header, then one per event of ``branch`` (its kind and its
    surface, the parameter's value, the critical multiplier's parts, the value in the key's unit);
    parameters as :func:`branch_rows`'s."""
    kind, _, multiplier = EVENT_COLUMNS
    head = [kind.name, branch.parameter, f"{multiplier.item}_real", f"{multiplier.item}_imag"]
    rows = [",".join(head + ([key] if key else []))]
    for e in branch.events:
        mu = complex(multiplier.get(e))
        cells = [e.value, mu.real, mu.imag] + ([shown(e.value)] if key else [])
        rows.append(",".join([f"{e.kind}{' ' + e.surface if e.surface else ''}"]
                             + [_number(c) for c in cells]))
    return rows
