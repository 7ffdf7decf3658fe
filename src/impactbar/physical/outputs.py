"""The outputs of a drifter, each declared once: its name, the unit its value comes in, its long name,
how it is read from an operating point (an orbit in SI, :class:`~impactbar.physical.DrifterOrbit`)
or from a blow (:func:`~impactbar.physical.piston.piston_blow`'s figures), and where it is shown.

Every tool reads this registry: the summaries of an operating point
(:meth:`~impactbar.physical.CircuitDrifterOrbit.summary`, the CLI's ``impactbar drifter``), the
stored variables of a design map (:func:`~impactbar.sweeps.map_spec.map_variables`), the
sensitivities (:data:`~impactbar.physical.sensitivity.FIGURE_UNITS`), the optimiser's objectives and
constraints (:mod:`~impactbar.physical.optimize_drifter`) and the continuation's ``branch.csv``. An
output added by :func:`register_output` appears in each of them.

Names. An output's :attr:`Output.name` is its stored variable's; its :attr:`Output.key`, the name
with the unit its value comes in (``pump_power_kW``, ``mean_supply_pressure_Pa``), is the key of the
sensitivities' and the optimiser's figures; its :attr:`Output.shown_key`, the name with its display
unit (``mean_supply_pressure_MPa``, :func:`~impactbar.physical.display_units.display_unit`), the key
of the summaries. A store holds the SI value (:attr:`Output.si_unit`: kW as W, mm as m, m/min as
m/s).

One name per quantity: an output's name (with its unit as a key) is the only one any view uses,
and :attr:`Output.long_name` the only long name. A name an output had before is in
:data:`RENAMED_OUTPUTS`: given to a tool (a constraint, a design map's or a store's variable, a key of a
stored record) it still reads the output, with a ``DeprecationWarning`` naming the new one
(:func:`current_name`, :func:`current_keys`).

Views (:attr:`Output.views`): ``"store"`` a design map's variable, ``"summary"`` the operating
point's summary and the CLI, ``"figure"`` a figure the sensitivities differentiate and the
optimiser's records carry (``"record"`` those its records carry), ``"branch"`` a column of a
circuit's ``branch.csv``; :attr:`Output.objective` names one the optimiser can maximise. Any
output of a number can be a constraint of the optimiser (its value at most the limit;
``min_<name>`` at least).
"""

from __future__ import annotations

import math
import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .._shared.renamed import renamed
from .._shared.schema import Field
from ..orbits.orbit import ORBIT_FIELDS
from .display_units import display_unit

__all__ = ["Output", "OUTPUTS", "RENAMED_OUTPUTS", "register_output", "unregister_output", "outputs",
           "added_outputs", "Reading", "output_values", "output_by_key", "current_name", "current_keys",
           "renamed_key"]

#: The unit an output's value comes in that is not SI, to the SI unit a store holds and the factor
#: (the value times it).
_TO_SI = {"kW": ("W", 1e3), "mm": ("m", 1e-3), "m/min": ("m/s", 1.0 / 60.0)}

VIEWS = frozenset({"store", "summary", "figure", "record", "branch"})
MACHINES = frozenset({"drifter", "circuit"})


def _suffix(unit: str) -> str:
    """A unit as a key's suffix (``"m/s"`` -> ``"m_s"``, ``"m**3"`` -> ``"m3"``), ``""`` for none."""
    return "" if unit in ("", "1") else unit.replace("**", "").replace("/", "_").replace("^", "")


def _named(name: str, unit: str) -> str:
    s = _suffix(unit)
    return f"{name}_{s}" if s else name


@dataclass(frozen=True)
class Output:
    """One output of a drifter.

    Attributes
    ----------
    name : str
        Its name (a design map's variable).
    unit : str
        The unit :attr:`of` gives its value in (``"Pa"``, ``"kW"``, ``"m/min"``; ``"1"`` for a
        dimensionless number, ``""`` for a flag).
    long_name : str
        What it is, in words (a stored variable's ``long_name``).
    of : callable, optional
        ``of(reading)``: its value at an operating point (:class:`Reading`), in :attr:`unit`.
    blow : callable, optional
        ``blow(figures)``: its value from a single blow's figures
        (:func:`~impactbar.physical.piston.piston_blow`), in :attr:`unit`.
    views : frozenset of str
        Where it is shown (module docstring).
    machines : frozenset of str
        ``"drifter"`` (the valve drifter) and/or ``"circuit"`` (with its oil circuit).
    rock : bool
        Whether it needs the drill string and the rock.
    dtype : str
        ``"f8"``, ``"b1"`` (a flag) or ``"U"`` (text, not stored).
    key : str, optional
        Its figures' key; the name with :attr:`unit` by default.
    optional : bool
        Left out of the figures where its value is NaN (not computed).
    objective : str, optional
        The name the optimiser maximises it by (:data:`~impactbar.physical.optimize_drifter.OBJECTIVES`,
        :func:`~impactbar.physical.optimize_problem.objectives`): one output per name and machine.
    edge : bool
        A flag whose change between neighbouring points of a design map is an edge
        (:func:`~impactbar.sweeps.map_task.find_edges`).
    """

    name: str
    unit: str
    long_name: str
    of: Callable | None = field(default=None, compare=False)
    blow: Callable | None = field(default=None, compare=False)
    views: frozenset = frozenset()
    machines: frozenset = frozenset({"circuit"})
    rock: bool = False
    dtype: str = "f8"
    key: str | None = None
    optional: bool = False
    objective: str | None = None
    edge: bool = False

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name.isidentifier()):
            raise ValueError(f"Output name must be an identifier; got {self.name!r}")
        object.__setattr__(self, "views", frozenset(self.views))
        object.__setattr__(self, "machines", frozenset(self.machines))
        if not self.views <= VIEWS:
            raise ValueError(f"Output {self.name}: views must be among {sorted(VIEWS)}; got "
                             f"{sorted(self.views)}")
        if not self.machines or not self.machines <= MACHINES:
            raise ValueError(f"Output {self.name}: machines must be among {sorted(MACHINES)}; got "
                             f"{sorted(self.machines)}")
        if self.of is None and self.views - {"record"}:
            raise ValueError(f"Output {self.name}: views {sorted(self.views - {'record'})} read it from an "
                             "operating point; give of=")
        if self.dtype not in ("f8", "b1", "U") or ("store" in self.views and self.dtype == "U"):
            raise ValueError(f"Output {self.name}: dtype must be 'f8', 'b1' or 'U' (text, not stored); got "
                             f"{self.dtype!r}")
        if self.key is None:
            object.__setattr__(self, "key", _named(self.name, self.unit))

    @property
    def si_unit(self) -> str:
        """The SI unit a store holds it in (CF spelling: ``"1"`` dimensionless, ``""`` a flag)."""
        si_unit, _ = _TO_SI.get(self.unit, (self.unit, 1.0))
        return si_unit

    def to_si(self, value):
        """A value in :attr:`unit` in :attr:`si_unit`."""
        _, factor = _TO_SI.get(self.unit, (self.unit, 1.0))
        return value * factor if factor != 1.0 else value

    @property
    def shown_unit(self) -> str:
        """The unit a person reads it in (:func:`~impactbar.physical.display_units.display_unit`)."""
        if self.unit in ("", "1"):
            return self.unit
        _, shown = display_unit(self.unit)
        return shown

    @property
    def shown_key(self) -> str:
        """Its key in the summaries: the name with :attr:`shown_unit`."""
        return _named(self.name, self.shown_unit) if self.key == _named(self.name, self.unit) else self.key

    def shown(self, value):
        """A value in :attr:`unit` in :attr:`shown_unit` (a factor below 1 as a division by its
        inverse: ``Pa / 1e6``)."""
        if self.unit in ("", "1") or self.dtype != "f8":
            return value
        factor, _ = display_unit(self.unit)
        if factor == 1.0:
            return value
        return value * factor if factor > 1.0 else value / round(1.0 / factor)

    @classmethod
    def from_field(cls, declared: Field, of: Callable | None = None, **kwargs) -> Output:
        """The output of a quantity a result type declares already (a field of
        :data:`~impactbar.orbits.orbit.ORBIT_FIELDS`): its name, long name, unit, key and dtype read
        from the field (its SI column's unit and key where it has one), not written again.

        Parameters
        ----------
        declared : Field
            The declared field: the output's name is its name; its unit and key its SI column's
            (:class:`~impactbar._shared.schema.SI`) where it has one, else its own units.
        of : callable, optional
            ``of(reading)``, as :class:`Output`'s.
        **kwargs
            The other attributes of :class:`Output`.

        Returns
        -------
        Output
        """
        si = declared.si
        unit = declared.units if si is None else si.units
        kwargs.setdefault("key", None if si is None else si.name)
        return cls(declared.name, unit, declared.long_name, of, dtype=declared.dtype, **kwargs)

    def column(self, **presentation) -> Field:
        """The output as a declared field of an SI result type (a column of
        :data:`~impactbar.physical.results.PHYSICAL_ORBIT_FIELDS`): named by its :attr:`key`, in
        :attr:`unit`, of its dtype, with its :attr:`long_name`; the name, unit and long name are the
        registry's, not written again.

        Parameters
        ----------
        **presentation
            The other attributes of :class:`~impactbar._shared.schema.Field` (``views``, ``label``,
            ``fmt``).

        Returns
        -------
        Field
        """
        return Field(self.key, self.long_name, self.unit, self.dtype, **presentation)

    def applies(self, kind: str, rock: bool) -> bool:
        """Whether a machine of ``kind`` (with the rock or not) has it."""
        return kind in self.machines and (rock or not self.rock)


class Reading:
    """An operating point read for its outputs: what several outputs use computed once.

    Attributes
    ----------
    point : DrifterOrbit or CircuitDrifterOrbit
    """

    def __init__(self, point) -> None:
        self.point = point

    @cached_property
    def rock(self) -> dict:
        """The point's rock figures (:meth:`~impactbar.physical.DrifterOrbit.rock`)."""
        return self.point.rock()

    @cached_property
    def histories(self) -> dict:
        """The circuit's histories at 200 points over the period."""
        return self.point.histories(200)

    @cached_property
    def borders(self) -> dict:
        """The circuit's border margins (Pa)."""
        return self.point.border_margins_Pa

    @cached_property
    def least(self) -> dict:
        """The least absolute pressure of each oil volume (Pa)."""
        return self.point.minimum_pressures_Pa

    @cached_property
    def max_multiplier(self) -> float:
        mult = np.abs(np.asarray(self.point.multipliers))
        return float(mult.max()) if mult.size else 0.0


def relief_open_fraction(point) -> float:
    """Fraction of the period in which the supply pressure is above the relief's setting (the
    integrator's steps, linear between them)."""
    sup = point.orbit.drive.supply
    if not sup.has_relief or sup.held:
        return 0.0
    p_rel, total, open_ = sup.relief_pressure, 0.0, 0.0
    supply = point.orbit.drive.layout.supply
    for p in point._pieces:
        if not hasattr(p, "drive_state") or not hasattr(p, "t"):
            continue
        t = np.asarray(p.t, dtype=float)
        if t.size < 2:
            continue
        ps = np.asarray(p.drive_state(t)[supply], dtype=float) - p_rel  # (a flight's or a blow's steps)
        total += t[-1] - t[0]
        dt = np.diff(t)
        a, b = ps[:-1], ps[1:]
        both = (a > 0) & (b > 0)
        open_ += float(np.sum(dt[both]))
        cross = (a > 0) != (b > 0)
        frac = np.where(cross, np.where(a > 0, a, b) / np.where(cross, np.abs(a - b), 1.0), 0.0)
        open_ += float(np.sum(dt[cross] * frac[cross]))
    return open_ / total if total > 0 else 0.0


def _rebound(r: Reading) -> float:
    o = r.point.orbit
    M = o.model.n_modes + 1
    after = np.asarray(o.states_after_impact[0], dtype=float)
    return -float(o.model.end_weights @ after[M:]) * r.point.drifter.scales.velocity_m_s


def _at_impact(name: str) -> Callable:
    return lambda r: r.point.pressures_at_impact_Pa[name]


def _least(volume: str) -> Callable:
    return lambda r: r.least.get(volume, math.nan)


def _rock(key: str) -> Callable:
    return lambda r: r.rock.get(key, math.nan)


_BOTH = frozenset(MACHINES)

#: The outputs by name, in the order every view lists them. An output that is a field of the orbit
#: (:data:`~impactbar.orbits.orbit.ORBIT_FIELDS`, or that field's SI column) reads its name and unit
#: there (:meth:`Output.from_field`); the SI results read the others' here (:meth:`Output.column`).
OUTPUTS: dict[str, Output] = {o.name: o for o in (
    Output("blow_frequency", "Hz", "blow frequency", lambda r: r.point.blow_frequency_Hz,
           views={"store", "summary", "figure", "record", "branch"}, machines=_BOTH),
    Output("period", "s", "period of the operating point", lambda r: r.point.period_s,
           views={"store", "summary"}, machines=_BOTH),
    Output.from_field(ORBIT_FIELDS["impact_velocity"], of=lambda r: r.point.impact_velocity_m_s,
                      views={"store", "summary", "figure"}, machines=_BOTH),
    Output("impact_energy", "J", "piston kinetic energy at impact", lambda r: r.point.impact_energy_J,
           blow=lambda b: b["impact_energy_J"], views={"store", "summary", "figure", "record", "branch"},
           machines=_BOTH),
    Output.from_field(ORBIT_FIELDS["max_abs_multiplier"], of=lambda r: r.max_multiplier,
                      views={"store", "figure"}, machines=_BOTH, key="max_multiplier", optional=True),
    Output("mean_supply_pressure", "Pa", "absolute supply pressure averaged over the period",
           lambda r: r.point.mean_supply_pressure_Pa, views={"store", "summary", "figure", "branch"}),
    Output("pump_power", "kW", "pump power, the flow Q_p times p_s - p_t, over the period",
           lambda r: r.point.pump_power_kW, views={"store", "summary", "figure", "record", "branch"}),
    Output("impact_power", "kW", "kinetic energy at impact times the blow frequency",
           lambda r: r.point.impact_power_kW, views={"summary", "figure", "record"}, machines=_BOTH,
           objective="impact_power"),
    Output("hydraulic_efficiency", "1", "energy the blows deliver over the pump's work",
           lambda r: r.point.hydraulic_efficiency, views={"store", "summary", "figure", "record", "branch"}),
    Output.from_field(ORBIT_FIELDS["stable"], of=lambda r: r.point.stable, views={"store", "summary"},
                      machines=_BOTH, edge=True),
    *(Output(f"min_{v}_pressure", "Pa", f"least absolute {what} pressure over the period",
             _least(v), views={"store"})
      for v, what in (("rear", "rear chamber"), ("front", "front chamber"), ("supply", "supply"))),
    Output("minimum_pressure", "Pa", "least absolute pressure of the oil over the period",
           lambda r: min(r.least.values()), views={"summary"}),
    Output("cavitates", "", "an absolute pressure falls below 0 during the period",
           lambda r: bool(min(r.least.values()) < 0.0) if r.least else False, views={"store", "summary"},
           dtype="b1", edge=True),
    Output.from_field(ORBIT_FIELDS["admissibility"], of=lambda r: str(r.point.orbit.admissibility),
                      views={"summary"}, machines={"drifter"}),
    Output("multiplier", "1", "modulus of the first non-trivial Floquet multiplier",
           lambda r: abs(complex(r.point.multipliers[0])) if r.point.multipliers.size else 0.0,
           views={"summary"}, machines=_BOTH),
    Output("relief_open_fraction", "1", "fraction of the period the relief valve is open",
           lambda r: relief_open_fraction(r.point), views={"store"}),
    Output("relief_opens", "", "the relief valve opens during the period",
           lambda r: bool(r.borders.get("relief", math.inf) < 0.0), views={"store"}, dtype="b1",
           edge=True),
    Output("relief_margin", "Pa", "relief pressure less the greatest supply pressure",
           lambda r: r.borders.get("relief", math.inf), views={"store", "summary"}),
    Output("accumulator_empties", "", "the accumulator empties: the supply pressure falls below the "
                                      "pre-charge during the period",
           lambda r: bool(r.borders.get("accumulator", math.inf) < 0.0), views={"store"}, dtype="b1",
           edge=True),
    Output("accumulator_margin", "Pa", "least supply pressure less the accumulator pre-charge",
           lambda r: r.borders.get("accumulator", math.inf), views={"store", "summary"}),
    Output("rebound_velocity", "m/s", "the struck end's velocity leaving the stop", _rebound,
           views={"figure"}),
    *(Output(f"{v}_pressure_at_impact", "Pa", f"{v} pressure at the impact", _at_impact(v), views={"figure"})
      for v in ("front", "rear", "supply")),
    Output("work_on_rock", "J", "work done on the rock per blow", _rock("work_on_rock_J"),
           blow=lambda b: b["work_on_rock_J"], views={"store", "figure", "record"}, machines=_BOTH,
           rock=True, objective="work_on_rock_per_blow"),
    Output("penetration", "mm", "permanent penetration per blow", _rock("penetration_mm"),
           views={"store"}, machines=_BOTH, rock=True),
    Output("drilling_rate", "m/min", "drilling rate: the penetration per blow times the blow frequency",
           _rock("drilling_rate_m_min"),
           views={"store", "figure", "record"}, machines=_BOTH, rock=True, objective="drilling_rate"),
    # (an operating point's: the work per blow times the blow frequency, as the drilling rate; a run's,
    # impactbar.physical.rock.rock_summary: the work of the blows and their chatter over their span)
    Output("rock_power", "W", "power into the rock: the work done on the rock per unit time",
           lambda r: r.rock["work_on_rock_J"] * r.point.blow_frequency_Hz, machines=_BOTH, rock=True),
    Output("peak_rod_stress", "Pa", "peak compressive stress of the incident wave in the rod",
           _rock("peak_rod_stress_Pa"), blow=lambda b: b["peak_rod_stress_Pa"], views={"store"},
           machines=_BOTH, rock=True),
    Output("rod_energy", "J", "energy carried into the rod per blow", _rock("rod_energy_J"),
           views={"store"}, machines=_BOTH, rock=True),
    Output.from_field(ORBIT_FIELDS["efficiency"], of=_rock("efficiency"), blow=lambda b: b["efficiency"],
                      views={"store", "record"}, machines=_BOTH, rock=True),
    Output("drilling_rate_per_kW", "m/min/kW", "drilling rate over the pump's power",
           lambda r: r.rock["drilling_rate_m_min"] / r.point.pump_power_kW, views={"figure", "record"},
           rock=True, key="drilling_rate_per_kW", objective="drilling_rate_per_kW"),
    Output("peak_supply_pressure", "Pa", "greatest supply pressure over the period (absolute)",
           lambda r: float(np.max(r.histories["p_s_Pa"]))),
    Output("min_chamber_volume", "m**3", "smallest volume of either chamber over the period",
           lambda r: float(min(np.min(r.histories["V_f_m3"]), np.min(r.histories["V_r_m3"])))),
    Output("piston_mass", "kg", "the piston's mass", lambda r: r.point.drifter.bar.mass_kg,
           blow=lambda b: b["piston_mass_kg"], machines=_BOTH),
)}

_BUILTIN = frozenset(OUTPUTS)

#: The names outputs had before, to their names now (one quantity, one name): the map stores and the
#: optimiser's constraints said ``peak_incident_stress`` for the orbit's and the rock figures'
#: ``peak_rod_stress``, and ``rock_efficiency`` (an operating point's) and ``blow_efficiency`` (an
#: ideal blow's) for the blow's ``efficiency``; the valve drifter's summaries said ``percussive_power``
#: for ``impact_power`` (the kinetic energy at impact times the blow frequency, both machines'); the
#: optimiser's constraint ``min_pressure`` limited ``minimum_pressure`` (the least pressure of the oil),
#: a constraint now named by it; the hammer's one-impact orbit and its simulation said ``blow_energy``
#: for ``impact_energy`` (``blow_energy_J``, ``mean_blow_energy_J``) and ``power`` for
#: ``impact_power`` (``power_W`` and ``mean_power_W``, in W: :func:`renamed_key`).
RENAMED_OUTPUTS = {"peak_incident_stress": "peak_rod_stress", "rock_efficiency": "efficiency",
                   "blow_efficiency": "efficiency", "percussive_power": "impact_power",
                   "min_pressure": "minimum_pressure", "blow_energy": "impact_energy",
                   "power": "impact_power"}


def current_name(name: str, what: str = "output") -> str:
    """An output's name now: ``name`` itself, or the name that replaced it (:data:`RENAMED_OUTPUTS`, its key
    with the unit too: ``peak_incident_stress_Pa``), with a ``DeprecationWarning`` naming it.

    Parameters
    ----------
    name : str
        A name or key as a user wrote it (a constraint's ``min_<name>`` too).
    what : str
        What the name is, for the warning (``"constraint"``, ``"variable"``).

    Returns
    -------
    str
        The name with the old output name replaced (its ``min_`` prefix and unit suffix kept).

    Examples
    --------
    >>> import warnings
    >>> from impactbar.physical.outputs import current_name
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     current_name("min_rock_efficiency", "constraint"), str(caught[0].message)
    ('min_efficiency', "constraint 'min_rock_efficiency' is now called 'min_efficiency'")
    """
    stem = _old_stem(name)
    if stem is None:
        return name
    new = _OLD_KEYS[stem]
    renamed = name[:len(name) - len(stem)] + new
    warnings.warn(f"{what} {name!r} is now called {renamed!r}", DeprecationWarning, stacklevel=3)
    return renamed


def current_keys(record: dict, what: str = "key") -> dict:
    """A record read back with the outputs' names now.

    Parameters
    ----------
    record : dict
        Figures or limits by name or key (a stored record's, a user's constraints).
    what : str
        What the keys are, for the warning.

    Returns
    -------
    dict
        ``record`` with each old name or key (:data:`RENAMED_OUTPUTS`) replaced by the name now
        (:func:`current_name`: a ``DeprecationWarning`` each), in its order; ``record`` itself where
        none is old.
    """
    if not any(_old_stem(k) for k in record):
        return record
    return {current_name(k, what): v for k, v in record.items()}


def _old_keys() -> dict:
    """Each old name of :data:`RENAMED_OUTPUTS` and its key with the unit, to the name or key now."""
    out = {}
    for old, new in RENAMED_OUTPUTS.items():
        o = OUTPUTS[new]
        out[old] = new
        if o.key != new:
            out[_named(old, o.unit)] = o.key
        if o.shown_key != o.key:
            out[_named(old, o.shown_unit)] = o.shown_key
    return out


_OLD_KEYS = _old_keys()


def renamed_key(key: str) -> tuple[str, float]:
    """The key now of a value stored under an old name (:data:`RENAMED_OUTPUTS`), and the factor its value
    is divided by: an old name or key of :func:`current_name` (factor 1), or an old name with the SI
    unit where the output's key has another (``power_W``, in W, is ``impact_power_kW``: 1000). No
    warning: for tools that compare a record of an older version with one of this (source:
    docs/developers.md, one name per output).

    Parameters
    ----------
    key : str
        A key as an older version stored it.

    Returns
    -------
    tuple of (str, float)
        The key now and the factor (``key`` itself and 1.0 where it is not an old one).

    Examples
    --------
    >>> from impactbar.physical.outputs import renamed_key
    >>> renamed_key("blow_energy_J"), renamed_key("power_W"), renamed_key("stable")
    (('impact_energy_J', 1.0), ('impact_power_kW', 1000.0), ('stable', 1.0))
    """
    stem = _old_stem(key)
    if stem is not None:
        return key[:len(key) - len(stem)] + _OLD_KEYS[stem], 1.0
    for old, new in RENAMED_OUTPUTS.items():
        o = OUTPUTS[new]
        si_unit, factor = _TO_SI.get(o.unit, (o.unit, 1.0))
        if factor != 1.0 and key == _named(old, si_unit):
            return o.key, factor
    return key, 1.0


def _old_stem(name) -> str | None:
    """The old name or key in ``name`` (itself, or after ``min_``), ``None`` for none."""
    if not isinstance(name, str):
        return None
    for stem in (name, name[4:] if name.startswith("min_") else None):
        if stem in _OLD_KEYS:
            return stem
    return None


def register_output(output: Output) -> Output:
    """Add an output to :data:`OUTPUTS`: the summaries, design maps, sensitivities and optimiser show
    it as the views it names say.

    Parameters
    ----------
    output : Output

    Returns
    -------
    Output

    Raises
    ------
    ValueError
        An output of that name or key already registered.

    Examples
    --------
    >>> from impactbar.physical.outputs import Output, register_output, unregister_output
    >>> o = register_output(Output("stroke", "m", "the piston's travel from the stop, at most",
    ...                            lambda r: max(r.point.histories()["gap_m"]), views={"summary"}))
    >>> o.key, o.shown_key, o.shown(0.0215)
    ('stroke_m', 'stroke_mm', 21.5)
    >>> unregister_output("stroke")
    """
    if not isinstance(output, Output):
        raise ValueError(f"output must be an Output; got {type(output).__name__}")
    taken = {n for o in OUTPUTS.values() for n in (o.name, o.key)}
    if output.name in taken or output.key in taken:
        raise ValueError(f"output {output.name!r} (key {output.key!r}): the name or key is registered "
                         "already")
    OUTPUTS[output.name] = output
    return output


def unregister_output(name: str) -> None:
    """Remove an output added by :func:`register_output` (the library's own stay).

    Raises
    ------
    ValueError
        An unknown name, or one of the library's outputs.
    """
    if name in _BUILTIN or name not in OUTPUTS:
        raise ValueError(f"unregister_output: {name!r} is not an output added by register_output")
    del OUTPUTS[name]


def outputs(view: str | None = None, kind: str | None = None, rock: bool = True) -> list[Output]:
    """The registered outputs in order, those of ``view`` (all where ``None``) that a machine of
    ``kind`` (any where ``None``) has, with or without the rock."""
    return [o for o in OUTPUTS.values() if (view is None or view in o.views)
            and (kind is None or o.applies(kind, rock))]


def added_outputs(view: str | None = None) -> list[Output]:
    """The outputs added by :func:`register_output`, of ``view``."""
    return [o for o in outputs(view) if o.name not in _BUILTIN]


def output_by_key(key: str) -> Output:
    """The output whose name or :attr:`~Output.key` is ``key``.

    Raises
    ------
    ValueError
        No such output.
    """
    key = current_name(key)
    for o in OUTPUTS.values():
        if key in (o.name, o.key):
            return o
    raise ValueError(f"unknown output {key!r}; one of {', '.join(OUTPUTS)}")


def output_values(point, selected, reading: Reading | None = None) -> dict:
    """The values of the ``selected`` outputs at an operating point, by name, in their units.

    Parameters
    ----------
    point : DrifterOrbit or CircuitDrifterOrbit
    selected : iterable of Output
    reading : Reading, optional
        A reading of ``point`` to share (its rock figures and histories computed once).

    Returns
    -------
    dict
    """
    r = Reading(point) if reading is None else reading
    return {o.name: o.of(r) for o in selected}


def __getattr__(name: str):
    # (an old name of a table here, :data:`~impactbar._shared.renamed.RENAMED_PUBLIC_NAMES`: the new
    # one's value, with a DeprecationWarning)
    if (value := renamed(sys.modules[__name__], name)) is not None:
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
