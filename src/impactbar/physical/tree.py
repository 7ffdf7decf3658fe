r"""One tree of parameters: each part of a drifter with its oil circuit declares its fields once, by
their dotted SI name (``supply.pump_flow``, ``rock.k``, ``chambers.rear_area``), with the SI unit,
an example, the scale that makes the field dimensionless (theory §11, eq. 2), the dimensionless
parameter it sets, its typical range, its own bound in SI, and whether it can be continued (and why
not). The dimensionless parameters are their holders' own declarations (the circuit drive's
:mod:`impactbar.drives.circuit.parameters`, the rod-rock law's, the bar model's): the tree names them.

Every tool reads this one declaration: the configuration's reader (the sections' keys, the required
ones, the values it converts), the circuit drive (:func:`drive_values`: each field's SI value by its
scale into the drive's part and field of its parameter),
:meth:`~impactbar.physical.CircuitDrifter.to_dimensionless`,
:func:`~impactbar.physical.continue_circuit`, the design maps' and the optimiser's units and integer
keys, the sensitivities, the plausibility warnings and the command line. A field declared here is
therefore set, swept, continued and optimised by its dotted name with no line elsewhere; the old
tables (``SI_PARAMETERS``, ``TYPICAL``, ``INTEGER_KEYS``, the circuit's ``_KEYS``, the SI checks'
bounds) are views of it.

Scales (theory §11, eq. 2): :math:`P` = 10 MPa, :math:`A_r` the rear area, :math:`L` and :math:`m`
the piston's length and mass, :math:`\Omega = \sqrt{P A_r / (m L)}`, volumes in :math:`A_r L`, flows
in :math:`A_r L \Omega`, forces in :math:`P A_r` (:data:`SCALE_STEPS`: each scale as the divisions
and multiplications that take an SI value to its dimensionless one, so that each rounds as written;
:data:`SCALES`: their factors).

Examples
--------
>>> from impactbar.physical.tree import field
>>> f = field("supply.pump_flow")
>>> f.unit, f.scale, f.parameter, f.continuable
('m**3/s', 'flow', 'pump_flow', True)
>>> field("model.n_modes").why_not
'takes integers: a design map takes it as an axis, continuation and the optimiser vary real values'
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["Field", "FIELDS", "MACHINES", "SCALES", "field", "fields", "declared", "read_si",
           "config_sections", "section_keys", "required_keys", "integer_keys", "continuable_keys",
           "real_keys", "in_sections", "typical_ranges", "continued", "refuse_continuation",
           "markdown_table", "SCALE_STEPS", "convert", "convert_back", "has", "drive_values",
           "part_key", "is_config_key"]

#: The pressure scale ``P`` of the dimensionless circuit (Pa).
PRESSURE_SCALE = 1.0e7

#: Why a key that sets the model's scales is not continued (a design map and the optimiser vary it).
SCALE_REASON = ("sets the model's scales (the piston's mass, length or rear area), so every dimensionless "
                "parameter moves with it: a design map, the optimiser and the sensitivities vary it, "
                "continuation follows one dimensionless parameter")
#: Why an integer key is not continued.
INTEGER_REASON = ("takes integers: a design map takes it as an axis, continuation and the optimiser vary "
                  "real values")


@dataclass(frozen=True)
class Field:
    """One field of a part, declared once.

    Parameters
    ----------
    key : str
        Its dotted SI name (``"supply.pump_flow"``): the TOML section and key.
    unit : str
        Its SI unit in pint's spelling (``"m**3/s"``; ``""`` for a bare number).
    example : str
        An example value as a config writes it (``"'80 L/min'"``), shown in messages.
    scale : str or callable, optional
        The name of its scale in :data:`SCALES` (or a function of the drifter giving the factor
        from SI to dimensionless); ``""`` where it sets no dimensionless parameter.
    parameter : str, optional
        The dimensionless parameter it sets (a drive's, the impact law's or the bar model's), ``""``
        for none.
    holder : {"drive", "law", "model", ""}
        Which part of the dimensionless problem holds ``parameter``.
    si : str, optional
        Its name in :attr:`CircuitDrifter.si <impactbar.physical.CircuitDrifter>` (``""``: not there).
    required : bool
        Whether the section must give it.
    default : str or float or None
        The value of an optional field left out (read as the config's; ``None``: none).
    typical : tuple, optional
        ``(low, high, shown unit, factor from SI to the shown unit)``: its typical range.
    integer : bool
        Whether it takes integers.
    needs : str, optional
        What the drifter must have for it to count: ``"rock"`` (a ``[rock]`` section),
        ``"accumulator"``, ``"stop"`` (no ``[rock]``).
    reason : str, optional
        Why it is not continued (``""``: it is, where it sets a parameter).
    many : bool
        Whether it is a list of values (the piston's ``end_lengths``) or a field of each table of
        an array (``rod.segments.length``, the key ``rod.segments.<i>.length``): a tool varies a
        list's element by its index, never the list.
    text : bool
        Whether it is a word or a file's path (``force.kind``, ``rock.method``), not a quantity.
    bound : {"", "positive", "non_negative"}
        Its own bound in SI, checked before the conversion (theory §11): ``"positive"`` (above 0),
        ``"non_negative"`` (0 or above); ``""``: none of its own (or one that depends on another
        field, checked with it: ``valve.switch_in`` below ``valve.switch_out``).
    zero : str, optional
        What 0 means for a ``"non_negative"`` field (``"0: no accumulator"``), shown in the message.
    """

    key: str
    unit: str
    example: str
    scale: str | Callable = ""
    parameter: str = ""
    holder: str = ""
    si: str = ""
    required: bool = False
    default: str | float | None = None
    typical: tuple = ()
    integer: bool = False
    needs: str = ""
    reason: str = ""
    many: bool = False
    text: bool = False
    bound: str = ""
    zero: str = ""

    @property
    def section(self) -> str:
        """The section (``"supply"``)."""
        return self.key.rsplit(".", 1)[0]

    @property
    def name(self) -> str:
        """The key within its section (``"pump_flow"``)."""
        return self.key.rsplit(".", 1)[1]

    @property
    def written(self) -> str:
        """The key as a tool takes it (``rod.segments.<i>.length`` for a field of each segment)."""
        return f"{self.section}.<i>.{self.name}" if self.section == "rod.segments" else self.key

    @property
    def continuable(self) -> bool:
        """Whether a branch of orbits can be followed in it: it sets one dimensionless parameter."""
        return bool(self.parameter) and not self.reason and not self.integer

    @property
    def why_not(self) -> str:
        """Why it is not continued (``""`` where it is)."""
        if self.continuable:
            return ""
        if self.text:
            return "is a word or a file's path, not a quantity"
        return self.reason or (INTEGER_REASON if self.integer else
                               "sets no dimensionless parameter of the circuit (none is declared for it)")


def _declare(*parts: tuple[Field, ...]) -> dict[str, Field]:
    out = {}
    for part in parts:
        for f in part:
            if f.key in out:
                raise ValueError(f"{f.key} is declared twice")
            out[f.key] = f
    return out


_MPA, _L, _ORIFICE, _RELIEF = ("MPa", 1e-6), ("L", 1e3), "m**3/s/Pa**0.5", "m**3/s/Pa"
#: a field's own bound in SI (``bound``): above 0, or 0 or above with what 0 means
_POSITIVE = {"bound": "positive"}


def _zero(means: str) -> dict:
    return {"bound": "non_negative", "zero": means}


# -- the parts ----------------------------------------------------------------------------------------
_BAR = (Field("bar.E", "Pa", "'210 GPa'", required=True, reason=SCALE_REASON),
        Field("bar.density", "kg/m**3", "'7850 kg/m^3'", required=True, reason=SCALE_REASON),
        Field("bar.length", "m", "'0.6 m'", required=True, reason=SCALE_REASON),
        Field("bar.diameter", "m", "'60 mm'", reason=SCALE_REASON),
        Field("bar.area", "m**2", "'28 cm^2'", reason=SCALE_REASON))
# the piston's shape, in place of [bar] and the chamber areas (impactbar.physical.geometry)
_LIST_REASON = "is a list of values: vary its elements' lengths and diameters one by one in the config"
_PISTON = (Field("piston.E", "Pa", "'210 GPa'", required=True, reason=SCALE_REASON),
           Field("piston.density", "kg/m**3", "'7850 kg/m^3'", required=True, reason=SCALE_REASON),
           *(Field(f"piston.{part}_{what}", "m", "'50 mm'", required=True, reason=SCALE_REASON)
             for part in ("rear_rod", "collar", "front_rod") for what in ("diameter", "length")),
           Field("piston.end_diameters", "m", "['40 mm']", reason=_LIST_REASON, many=True),
           Field("piston.end_lengths", "m", "['50 mm']", reason=_LIST_REASON, many=True))
_STOP = (Field("stop.restitution", "", "0.215", "one", "R", "model", needs="stop"),
         Field("stop.area", "m**2", "'30 cm^2'",
               reason="sets the restitution through the impedances (eq. 10): continue stop.restitution"))
_DAMPING = (Field("damping.coefficient", "N*s/m", "'9 N*s/m'", typical=(0.0, 50.0, "N s/m", 1.0)),)
_MODEL = (Field("model.n_modes", "", "4", integer=True),)
_CHAMBERS = (
    Field("chambers.rear_area", "m**2", "'5.6 cm^2'", si="rear_area_m2", required=True, reason=SCALE_REASON,
          typical=(4e-4, 15e-4, "cm^2", 1e4), **_POSITIVE),
    Field("chambers.front_area", "m**2", "'5.6 cm^2'", "area", "area_ratio", "drive", "front_area_m2", True,
          **_POSITIVE),
    Field("chambers.rear_volume", "m**3", "'0.15 L'", "volume", "rear_volume", "drive", "rear_volume_m3",
          True, **_POSITIVE),
    Field("chambers.front_volume", "m**3", "'0.1 L'", "volume", "front_volume", "drive", "front_volume_m3",
          True, **_POSITIVE))
_VALVE = (
    Field("valve.switch_out", "m", "'21.5 mm'", "length", "switch_out", "drive", "switch_out_m", True,
          typical=(15e-3, 60e-3, "mm", 1e3), **_POSITIVE),
    Field("valve.switch_in", "m", "'10 mm'", "length", "switch_in", "drive", "switch_in_m"),
    Field("valve.switching_time", "s", "'1 ms'", "time", "switching_time", "drive", "switching_time_s", True,
          typical=(0.5e-3, 3e-3, "ms", 1e3), **_zero("0: an instant switch")),
    Field("valve.flow_coefficient", _ORIFICE, "'7.5e-6 m^3/s/Pa^0.5'", "orifice", "valve_coefficient",
          "drive", "valve_coefficient", True, typical=(3e-6, 2e-5, "m^3/s/Pa^0.5", 1.0), **_POSITIVE))
_SUPPLY = (
    Field("supply.pump_flow", "m**3/s", "'80 L/min'", "flow", "pump_flow", "drive", "pump_flow_m3_s", True,
          typical=(40.0 / 6e4, 150.0 / 6e4, "L/min", 6e4), **_POSITIVE),
    Field("supply.hose_volume", "m**3", "'1 L'", "volume", "hose_volume", "drive", "hose_volume_m3", True,
          typical=(0.1e-3, 2e-3, *_L), **_POSITIVE),
    Field("supply.front_flow_coefficient", _ORIFICE, "'7.5e-6 m^3/s/Pa^0.5'", "orifice", "front_coefficient",
          "drive", "front_coefficient", True, typical=(3e-6, 2e-5, "m^3/s/Pa^0.5", 1.0), **_POSITIVE),
    Field("supply.tank_pressure", "Pa", "'0.3 MPa'", "pressure", "tank_pressure", "drive", "tank_pressure_Pa",
          True, typical=(0.2e6, 1e6, *_MPA), **_zero("pressures are absolute")),
    Field("supply.relief_pressure", "Pa", "'25 MPa'", "pressure", "relief_pressure", "drive",
          "relief_pressure_Pa", default=math.inf, typical=(17e6, 30e6, *_MPA)),
    Field("supply.relief_coefficient", _RELIEF, "'5e-10 m^3/s/Pa'", "relief", "relief_coefficient", "drive",
          "relief_coefficient", default="0 m**3/s/Pa", typical=(1e-10, 1e-9, "m^3/s/Pa", 1.0),
          **_zero("0: no relief flow")))
_ACCUMULATOR = (
    Field("accumulator.precharge", "Pa", "'12 MPa'", "pressure", "precharge", "drive", "precharge_Pa",
          default=PRESSURE_SCALE, typical=(6e6, 22.5e6, *_MPA), needs="accumulator", **_POSITIVE),
    Field("accumulator.volume", "m**3", "'0.5 L'", "volume", "accumulator_volume", "drive",
          "accumulator_volume_m3", default=0.0, typical=(0.2e-3, 1e-3, *_L), needs="accumulator",
          **_zero("0: no accumulator")),
    Field("accumulator.polytropic_exponent", "", "1.4", "one", "polytropic_exponent", "drive",
          "polytropic_exponent", default=1.4, needs="accumulator"))
_OIL = (
    Field("oil.bulk_modulus", "Pa", "'1.4 GPa'", "pressure", "bulk_modulus", "drive", "bulk_modulus_Pa", True,
          typical=(0.8e9, 1.8e9, "GPa", 1e-9), **_POSITIVE),
    Field("oil.transition_pressure", "Pa", "'0.5 MPa'", "pressure", "transition_pressure", "drive",
          "transition_pressure_Pa", True, typical=(0.05e6, 0.5e6, *_MPA), **_POSITIVE))
# a drifter on the drill string and the rock: the rod-rock law's own (theory §4d)
_ROCK = (Field("rock.k", "N/m", "'250 kN/mm'", "stiffness", "rock.k", "law", needs="rock"),
         Field("rock.k_u", "N/m", "'2500 kN/mm'", "stiffness", "rock.k_u", "law", needs="rock"),
         Field("rock.feed", "N", "'5 kN'", "force", "feed", "law", needs="rock"),
         Field("rock.cells_per_piston", "", "64", integer=True),
         Field("rock.method", "", "'auto'", text=True),
         Field("rock.driven_end", "", "'free'", text=True),
         Field("rock.contact_events", "", "'step'", text=True))
_BIT = (Field("bit.mass", "kg", "'1.5 kg'", "mass", "bit_mass", "law", needs="rock"),)
# each table of the drill string's array [[rod.segments]] (the key rod.segments.<i>.<name>; E and
# density default to the piston's)
_SEGMENT_REASON = "is a field of each rod segment: vary it by the segment's index (rod.segments.<i>.<key>)"
_ROD = (Field("rod.segments.length", "m", "'1.2 m'", required=True, reason=_SEGMENT_REASON, many=True),
        Field("rod.segments.diameter", "m", "'32 mm'", reason=_SEGMENT_REASON, many=True),
        Field("rod.segments.area", "m**2", "'8 cm^2'", reason=_SEGMENT_REASON, many=True),
        Field("rod.segments.E", "Pa", "'210 GPa'", reason=_SEGMENT_REASON, many=True),
        Field("rod.segments.density", "kg/m**3", "'7850 kg/m^3'", reason=_SEGMENT_REASON, many=True))
# a hammer's periodic force (impactbar.physical.config): its integer keys
_FORCE = (Field("force.k", "", "1", integer=True), Field("force.max_harmonics", "", "40", integer=True))

#: Every declared field of a drifter with its oil circuit by its dotted SI name, in the order the
#: parts are declared (then the drill string's and a hammer's integer keys).
FIELDS: dict[str, Field] = _declare(_ACCUMULATOR, _SUPPLY, _VALVE, _CHAMBERS, _OIL, _ROCK, _BIT, _BAR,
                                    _PISTON, _STOP, _DAMPING, _MODEL, _FORCE, _ROD)

# -- the other machines (theory §10 and §5): the drifter whose valve switches on the piston's
# position, and the hammer under a periodic force; the bar's, the stop's and the drill string's
# fields are the same declarations as above
_DRIFTER_VALVE = (
    Field("valve.supply_pressure", "Pa", "'20 MPa'", required=True),
    Field("valve.stroke_area", "m**2", "'2.8 cm^2'", required=True),
    Field("valve.return_area", "m**2", "'2.8 cm^2'", required=True),
    Field("valve.switch_out", "m", "'21.5 mm'", required=True),
    Field("valve.delay", "s", "'1 ms'", default="0 ms"))
_PIECE = (*_BAR, *_STOP, *_DAMPING, *_MODEL, *_ROCK, *_BIT, *_ROD)
_HAMMER = (
    Field("drive.frequency", "Hz", "'40 Hz'", required=True),
    Field("force.kind", "", "'pneumatic'", required=True, text=True),
    *(Field(f"force.{name}", "N", "'2.5 kN'", needs=kind)
      for name, kind in (("mean", "pneumatic"), ("amplitude", "pneumatic"), ("high", "hydraulic"),
                         ("low", "hydraulic"))),
    Field("force.k", "", "1", integer=True, needs="pneumatic"),
    Field("force.fraction", "", "0.3", needs="hydraulic"),
    Field("force.csv", "", "'force.csv'", text=True, needs="measured"),
    Field("force.tolerance", "", "1e-3", needs="measured"),
    Field("force.max_harmonics", "", "40", integer=True, needs="measured"),
    Field("damping.ratio", "", "0.02"),
    Field("model.impact", "", "'paper'", text=True))

#: Each kind of machine's declared fields by dotted SI name (a drifter with its oil circuit's are
#: :data:`FIELDS`; ``"drifter"``: the valve switched on the piston's position; ``"hammer"``: a
#: periodic force); the configuration's reader of each kind takes these keys and no other.
MACHINES: dict[str, dict[str, Field]] = {
    "circuit": FIELDS,
    "drifter": _declare(_DRIFTER_VALVE, _PIECE),
    "hammer": _declare(_HAMMER, _PIECE),
}

#: The sections of a drifter with its oil circuit whose keys the tree declares in full.
CIRCUIT_SECTIONS = ("bar", "stop", "damping", "model", "chambers", "valve", "supply", "accumulator", "oil")

#: A unit in words, for a message (``"a pressure"``).
WORDS = {"m**2": "an area", "m**3": "a volume", "Pa": "a pressure", "m": "a length", "s": "a time",
         "m**3/s": "a flow", _ORIFICE: "a flow coefficient (m^3/s/Pa^0.5)",
         _RELIEF: "a flow coefficient (m^3/s/Pa)", "N/m": "a stiffness", "N": "a force", "kg": "a mass",
         "Hz": "a frequency", "kg/m**3": "a density", "N*s/m": "a damping coefficient"}

#: Each scale as the steps that take an SI value to its dimensionless one (theory §11, eq. 2), in
#: order: ``("/", f)`` divides by ``f(drifter)``, ``("*", f)`` multiplies by it. The steps are the
#: declaration, not one factor: ``x / P`` and ``x * (1 / P)`` may differ in the last bit, and the
#: circuit drive (:func:`drive_values`) converts each field exactly as its scale's steps say.
SCALE_STEPS: dict[str, tuple] = {
    "pressure": (("/", lambda d: PRESSURE_SCALE),),
    "volume": (("/", lambda d: d.volume_scale_m3),),
    "flow": (("/", lambda d: d.flow_scale_m3_s),),
    "orifice": (("*", lambda d: math.sqrt(PRESSURE_SCALE) / d.flow_scale_m3_s),),
    "relief": (("*", lambda d: PRESSURE_SCALE), ("/", lambda d: d.flow_scale_m3_s)),
    "length": (("/", lambda d: d.bar.length_m),),
    "time": (("*", lambda d: d.omega_rad_s),),
    "one": (),
    "area": (("/", lambda d: d.si["rear_area_m2"]),),
    "stiffness": (("/", lambda d: d.bar.mass_kg * d.omega_rad_s ** 2),),  # K / (m Omega^2): the law reads it
    "force": (("/", lambda d: d.scales.force_N),),
    "mass": (("/", lambda d: d.bar.mass_kg),),
    "damping": (("/", lambda d: d.bar.mass_kg * d.omega_rad_s),),
}
_STEP = {"*": operator.mul, "/": operator.truediv}
_UNDO = {"*": operator.truediv, "/": operator.mul}


def convert(scale: str | Callable, drifter, value: float) -> float:
    r"""An SI value in its scale's units (theory §11, eq. 2): the scale's :data:`SCALE_STEPS` applied
    to ``value`` in turn (a scale given as a function: ``value`` times its factor).

    Parameters
    ----------
    scale : str or callable
        A name in :data:`SCALE_STEPS`, or a function of the drifter giving the factor from SI.
    drifter : CircuitDrifter
        Whose scales (the piston's length and mass, the rear area, :math:`\Omega`).
    value : float
        The value in SI (its field's unit).

    Returns
    -------
    float
        Dimensionless.

    Examples
    --------
    >>> convert("pressure", None, 12e6), convert("one", None, 1.4)
    (1.2, 1.4)
    """
    if callable(scale):
        return value * scale(drifter)
    for step, of in SCALE_STEPS[scale]:
        value = _STEP[step](value, of(drifter))
    return value


def convert_back(scale: str | Callable, drifter, value: float) -> float:
    r"""The SI value of a dimensionless ``value`` (theory §11, eq. 2): the inverse of :func:`convert`,
    its scale's :data:`SCALE_STEPS` undone in reverse order (a division by ``f`` undone as a
    multiplication by ``f``, not by a factor ``1 / f``; a scale given as a function: ``value``
    divided by its factor).

    Parameters
    ----------
    scale : str or callable
        The field's scale, as :func:`convert` takes it.
    drifter : CircuitDrifter
        Whose scales.
    value : float
        Dimensionless.

    Returns
    -------
    float
        The value in SI (its field's unit).

    Examples
    --------
    >>> convert_back("pressure", None, 1.2), convert_back("one", None, 1.4)
    (12000000.0, 1.4)
    """
    if callable(scale):
        return value / scale(drifter)
    for step, of in reversed(SCALE_STEPS[scale]):
        value = _UNDO[step](value, of(drifter))
    return value


#: Each scale's factor from SI to dimensionless, a function of the drifter (theory §11, eq. 2): its
#: steps applied to 1, to show or compare; a value is converted by the steps (:func:`convert`), which
#: a product by this factor may round apart in the last bit.
SCALES: dict[str, Callable] = {name: (lambda d, name=name: convert(name, d, 1.0)) for name in SCALE_STEPS}


def fields() -> dict[str, Field]:
    """Every declared field by its dotted SI name (:data:`FIELDS`)."""
    return FIELDS


def field(key: str) -> Field:
    """The declaration of a dotted SI name.

    Raises
    ------
    ValueError
        A name the tree does not declare (the declared ones listed).
    """
    f = FIELDS.get(key) if isinstance(key, str) else None
    if f is None:
        raise ValueError(f"parameter must be one of {', '.join(FIELDS)} (a config key); got {key!r}")
    return f


def declared(key: str, kind: str = "circuit") -> Field | None:
    """The declaration of a dotted config key of a kind of machine (``None``: not declared); a rod
    segment's key ``rod.segments.<i>.<name>`` is declared once as ``rod.segments.<name>``.

    Examples
    --------
    >>> declared("rod.segments.1.diameter").unit, declared("valve.delay", "drifter").unit
    ('m', 's')
    """
    if not isinstance(key, str):
        return None
    parts = key.split(".")
    if len(parts) == 4 and parts[:2] == ["rod", "segments"] and parts[2].isdigit():
        key = f"rod.segments.{parts[3]}"
    return MACHINES.get(kind, {}).get(key)


def part_key(key) -> tuple[str, str] | None:
    """``(name, field)`` of a config's own part's key ``parts.<name>.<field>`` (the field declared
    by the part's kind, :mod:`~impactbar.physical.circuit_parts`); ``None`` for a key of another
    form.

    Examples
    --------
    >>> part_key("parts.damper.volume"), part_key("supply.pump_flow")
    (('damper', 'volume'), None)
    """
    head, _, rest = key.partition(".") if isinstance(key, str) else ("", "", "")
    name, dot, field = rest.partition(".")
    return (name, field) if head == "parts" and dot and name and field and "." not in field else None


def is_config_key(key) -> bool:
    """Whether ``key`` is a dotted SI config key: one that a kind of machine declares
    (:func:`declared`, a rod segment's by its index too), or a field of a config's own part
    (:func:`part_key`), rather than a dimensionless parameter's name (``delay``, ``precharge``).

    Examples
    --------
    >>> is_config_key("supply.pump_flow"), is_config_key("valve.delay"), is_config_key("parts.damper.volume")
    (True, True, True)
    >>> is_config_key("precharge"), is_config_key("supply.pumpflow")
    (False, False)
    """
    return part_key(key) is not None or any(declared(key, kind) is not None for kind in MACHINES)


def read_si(key: str, value, kind: str = "circuit", name: str | None = None) -> float:
    """A config value in its declared SI unit (:func:`~impactbar.physical.units.to_si` with the
    field's unit, example and dimension in words), the message naming ``name`` (default ``key``).

    Raises
    ------
    ValueError
        An undeclared key; a value of another dimension, a bare number for a key with a unit, one
        not finite (the message naming ``name``).

    Examples
    --------
    >>> read_si("rod.segments.0.length", "1.2 m"), read_si("valve.delay", "2 ms", "drifter")
    (1.2, 0.002)
    """
    from .units import to_si

    f = declared(key, kind)
    if f is None or f.text:
        raise ValueError(f"{key} is not a quantity the {kind} config declares")
    return to_si(name or key, value, f.unit, f.example, what=WORDS.get(f.unit))


def config_sections(kind: str) -> dict[str, set]:
    """Each section of a kind of machine's configuration and the keys it takes (the drill
    string's sections ``rod`` (its array ``segments``), ``bit``, ``rock`` included; the
    segments' own keys under ``"rod.segments"``)."""
    out: dict[str, set] = {}
    for f in MACHINES[kind].values():
        out.setdefault(f.section, set()).add(f.name)
    out.setdefault("rod", set()).add("segments")
    return out


def in_sections(sections=CIRCUIT_SECTIONS) -> tuple[Field, ...]:
    """The declared fields of ``sections``, section by section in their order."""
    return tuple(f for s in sections for f in FIELDS.values() if f.section == s)


def section_keys(sections=CIRCUIT_SECTIONS) -> dict[str, set]:
    """Each section's keys (a drifter with its oil circuit's by default)."""
    return {s: {f.name for f in FIELDS.values() if f.section == s} for s in sections}


def required_keys(sections=CIRCUIT_SECTIONS) -> dict[str, tuple]:
    """Each section's required keys, in declaration order (sections with none left out)."""
    out = {s: tuple(f.name for f in FIELDS.values() if f.section == s and f.required) for s in sections}
    return {s: keys for s, keys in out.items() if keys}


def real_keys() -> tuple[str, ...]:
    """The keys of one real value (not an integer, not a list): what a tool differentiates."""
    return tuple(k for k, f in FIELDS.items() if not f.integer and not f.many and not f.text)


def integer_keys() -> tuple[str, ...]:
    """The keys that take integers."""
    return tuple(k for k, f in FIELDS.items() if f.integer)


def continuable_keys() -> tuple[str, ...]:
    """The keys a branch of orbits can be followed in."""
    return tuple(k for k, f in FIELDS.items() if f.continuable)


def typical_ranges() -> dict[str, tuple]:
    """Key to ``(low, high, SI unit, shown unit, factor)`` for the fields with a typical range."""
    return {k: (low, high, f.unit, shown, factor) for k, f in FIELDS.items() if f.typical
            for low, high, shown, factor in (f.typical,)}


def markdown_table(extra=()) -> str:
    """The declared fields as a Markdown table (the documentation's list of keys is this text).

    Parameters
    ----------
    extra : tuple of Field, optional
        Fields to list after the tree's (the library's part kinds':
        :func:`impactbar.physical.circuit_parts.markdown_table`).

    Returns
    -------
    str
        One row per field: the dotted name, its SI unit, its scale, the dimensionless parameter
        it sets, and whether it is continued (or why not); then those of ``extra``.
    """
    rows = ["| key | SI unit | scale | dimensionless parameter | continued |",
            "| --- | --- | --- | --- | --- |"]
    for f in (*FIELDS.values(), *extra):
        scale = f.scale if isinstance(f.scale, str) else "(a function)"
        parameter = f"`{f.parameter}`" if f.parameter else "-"
        rows.append(f"| `{f.written}` | {f.unit.replace('**', '^') or '1'} | {scale or '-'} | {parameter} | "
                    f"{'yes' if f.continuable else 'no: ' + f.why_not} |")
    return "\n".join(rows) + "\n"


def refuse_continuation(key: str) -> Field:
    """The declaration of ``key``, refused with its reason where it cannot be continued.

    Raises
    ------
    ValueError
        An undeclared key, or one whose declaration says why it is not continued.

    Examples
    --------
    >>> refuse_continuation("bar.diameter")
    Traceback (most recent call last):
    ...
    ValueError: parameter bar.diameter cannot be continued: it sets the model's scales (the piston's mass, ...
    """
    f = field(key)
    if not f.continuable:
        raise ValueError(f"parameter {key} cannot be continued: it {f.why_not}")
    return f


def continued(drifter, key: str) -> Field:
    """The declaration of ``key`` for a continuation of ``drifter``: its value in SI converted to the
    continued parameter by its scale (:func:`convert`, as the config's values are) and back
    (:func:`convert_back`).

    Raises
    ------
    ValueError
        As :func:`refuse_continuation`; a key whose part the drifter lacks (a rock's without a
        ``[rock]`` section, an accumulator's without an accumulator, the stop's on the rock).
    """
    f = refuse_continuation(key)
    if not has(drifter, f.needs):
        raise ValueError(f"parameter {key} is {_LACKING[f.needs]}")
    return f


#: What a drifter with its oil circuit must have for a field of each ``needs`` to count.
_NEEDS = {"": lambda d: True, "rock": lambda d: d.drill is not None, "stop": lambda d: d.drill is None,
          "accumulator": lambda d: d.si["accumulator_volume_m3"] > 0.0}
#: Why a field of each ``needs`` does not count for a drifter that lacks it.
_LACKING = {"rock": "the drill string's and the rock's: the drifter has no [rock] section",
            "accumulator": "the accumulator's: the drifter has none (no [accumulator] section, or its "
                           "volume 0)",
            "stop": "the stop's: on the rock the rod-rock law sets the impact"}


def has(drifter, needs: str) -> bool:
    """Whether ``drifter`` (a drifter with its oil circuit) has what a field's ``needs`` names: a
    drill string and the rock (``"rock"``), the stop (``"stop"``: no rock), an accumulator of a
    volume above 0 (``"accumulator"``); always for ``""``.

    Raises
    ------
    ValueError
        A ``needs`` of another kind of machine's (a hammer's force).
    """
    if needs not in _NEEDS:
        raise ValueError(f"needs must be one of {', '.join(map(repr, _NEEDS))} (a circuit's); got {needs!r}")
    return bool(_NEEDS[needs](drifter))


def drive_values(drifter) -> dict[str, dict]:
    """The circuit drive's parts' dimensionless values for ``drifter`` (theory §11, eq. 2), from the
    declarations alone: each field the drive holds (``holder="drive"``), its SI value
    (``drifter.si[f.si]``) converted by its scale's steps (:func:`convert`; ``None`` stays ``None``:
    no ``switch_in``) into the part and field that the drive's declaration
    (:data:`impactbar.drives.circuit.parameters.DECLARED`) gives its parameter. A field whose part the
    drifter lacks (``needs``: an accumulator of no volume) is left out, and so is a part left with
    none.

    Parameters
    ----------
    drifter : CircuitDrifter

    Returns
    -------
    dict
        Part (``"chambers"``, ``"valve"``, ``"supply"``, ``"oil"``, ``"accumulator"``) to its fields'
        values by the part's field names (the valve's ``coefficient``).
    """
    from ..drives.circuit.drive import PARAMETERS  # (the declaration's part and field of each parameter)

    out: dict[str, dict] = {}
    for f in FIELDS.values():
        if f.holder == "drive" and has(drifter, f.needs):
            part, name = PARAMETERS[f.parameter]
            x = drifter.si[f.si]
            out.setdefault(part, {})[name] = None if x is None else convert(f.scale, drifter, x)
    return out
