r"""The problem the whole-drifter optimiser (:func:`~impactbar.physical.optimize_drifter`) solves:
its objectives and constraints, and a design's evaluation against them.

A design is evaluated at the circuit's operating point on the rod and rock (:func:`evaluate_design`:
:meth:`CircuitDrifter.orbit` by Newton from a nearby design's orbit where that converges, else the
default chain; a valve drifter's as a design map finds it,
:func:`~impactbar.physical.drifter.operating_point`), or in the circuit's ideal limit as its
piston's single blow at a given impact velocity (:func:`evaluate_blow`). Its record gives every
objective (:data:`OBJECTIVES`) and every constraint's value, limit and margin, positive where met; a
margin missed by less than :data:`FEASIBILITY_TOLERANCE` of its scale counts as met. A design
without an operating point has the record of
:func:`~impactbar.physical.optimize_failures.failed_record`. The gradients of a design's figures
in the scaled variables are the implicit function theorem's
(:func:`~impactbar.physical.sensitivity.tangent_derivatives`). A valve drifter (no oil circuit) has
the objectives and constraints of its outputs (:func:`objectives`, :func:`default_constraints`).
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

import numpy as np

from .circuit import CircuitDrifter
from .display_units import config_quantity, display_unit
from .loader import build, with_values
from .optimize_failures import failed_record
from .optimize_outputs import constraint_output, piston_and_multipliers
from .outputs import Reading, current_keys, outputs
from .sensitivity import default_step, tangent_derivatives
from .units import to_si

__all__ = ["OBJECTIVES", "DEFAULT_CONSTRAINTS", "IDEAL_CONSTRAINTS", "FEASIBILITY_TOLERANCE", "least_margin",
           "evaluate_design", "evaluate_blow", "objectives", "default_constraints", "machine_kind"]


class _Objective(NamedTuple):
    """An objective: the record's figure maximised, its unit, what it is."""

    key: str
    unit: str
    long_name: str


def objectives(kind: str = "circuit", rock: bool = True) -> dict:
    """The objectives of a machine (all maximised): name to (the figure, its unit, what it is), the
    outputs of the view ``"record"`` it has that name an objective
    (:attr:`~impactbar.physical.outputs.Output.objective`; theory §11, "Optimising a drifter").

    Parameters
    ----------
    kind : {"circuit", "drifter"}
        The drifter with its oil circuit, or the valve drifter.
    rock : bool
        Whether it has the drill string and the rock.

    Returns
    -------
    dict of str to _Objective

    Examples
    --------
    >>> from impactbar.physical.optimize_problem import objectives
    >>> [(k, o.key) for k, o in objectives("drifter").items()]  # doctest: +NORMALIZE_WHITESPACE
    [('impact_power', 'impact_power_kW'), ('work_on_rock_per_blow', 'work_on_rock_J'),
     ('drilling_rate', 'drilling_rate_m_min')]
    """
    return {o.objective: _Objective(o.key, o.unit, o.long_name) for o in outputs("record", kind, rock)
            if o.objective}


#: The objectives of a drifter with its oil circuit (:func:`objectives`).
OBJECTIVES = objectives()

#: The constraints and their default limits (SI): ``peak_rod_stress`` (Pa, the largest stress in
#: the shank adapter before the rock's first reflection is back at it, or over the piston's first
#: contact where that lasts longer: the peak of the incident wave; ``None``: not constrained),
#: ``max_multiplier`` (the largest Floquet multiplier's modulus), ``minimum_pressure`` (Pa absolute,
#: the least pressure of the oil at least: no cavitation at 0),
#: ``mean_supply_pressure`` (Pa; ``"relief"``: the relief valve's setting), ``peak_supply_pressure``
#: (Pa; ``None``: not constrained), ``min_chamber_volume`` (m^3, the smallest volume of either chamber
#: over the period must lie above it), ``min_drilling_rate`` (m/min; ``None``: not constrained; a
#: design that drills per kilowatt more by drilling slower is then kept from the optimum),
#: ``piston_mass`` (kg, the piston's mass at most; ``None``: not constrained).
DEFAULT_CONSTRAINTS = {"peak_rod_stress": None, "max_multiplier": 0.95, "minimum_pressure": 0.0,
                       "mean_supply_pressure": "relief", "peak_supply_pressure": None,
                       "min_chamber_volume": 0.0, "min_drilling_rate": None, "piston_mass": None}

#: The constraints of the circuit's ideal limit (``optimize_drifter(..., impact_velocity=...)``): the
#: blow's and the piston's.
IDEAL_CONSTRAINTS = ("peak_rod_stress", "piston_mass")

#: How far a constraint may be missed and count as met, relative to its scale (the limit, or where
#: the limit is 0 the margin's fixed scale: 1 MPa of pressure, 0.1 L of volume): the operating
#: point's own accuracy, its periodic orbit to 1e-8 (the circuit's flights at ``rtol = 1e-10``,
#: :mod:`impactbar.drives.circuit.flight`). A continued and a fresh orbit of one design differ by
#: some 1e-9 (the mean supply pressure on the preset by up to 4e-9); SLSQP walks along an active
#: limit at about that distance from it. The reported optimum's fresh orbit meets it too.
FEASIBILITY_TOLERANCE = 1e-8


def machine_kind(drifter) -> str:
    """``"circuit"`` for a drifter with its oil circuit, ``"drifter"`` for a valve drifter (the
    machines of :mod:`~impactbar.physical.outputs`)."""
    return "circuit" if isinstance(drifter, CircuitDrifter) else "drifter"


def default_constraints(kind: str = "circuit") -> dict:
    """The constraints of :data:`DEFAULT_CONSTRAINTS` that a machine of ``kind`` has (a valve
    drifter's: those of its outputs, none of the oil's), with their default limits.

    Examples
    --------
    >>> from impactbar.physical.optimize_problem import default_constraints
    >>> default_constraints("drifter")
    {'peak_rod_stress': None, 'max_multiplier': 0.95, 'min_drilling_rate': None, 'piston_mass': None}
    """
    return {k: v for k, v in DEFAULT_CONSTRAINTS.items() if constraint_output(k, kind) is not None}


def evaluate_design(drifter: CircuitDrifter, constraints: dict | None = None,
                    guess=None) -> tuple[dict, object]:
    """A design's figures: its operating point's objectives and constraints with their margins.

    Parameters
    ----------
    drifter : CircuitDrifter or Drifter
        With a drill string and the rock (``[rock]``) for the drilling figures; a valve drifter has
        the objectives and constraints of :func:`objectives` and :func:`default_constraints`.
    constraints : dict, optional
        Limits by name (:data:`DEFAULT_CONSTRAINTS`, SI or with units); the defaults where left out.
    guess : CircuitDrifterOrbit or DrifterOrbit, optional
        The operating point of a nearby design: Newton starts there; where it does not converge the
        default chain (``orbit()``) is used.

    Returns
    -------
    record : dict
        ``objectives`` (:data:`OBJECTIVES`' figures), ``constraints`` (name to ``value``, ``limit``,
        ``margin`` in the value's unit, positive where met, and ``scaled`` margin), ``feasible``,
        ``continued`` (whether Newton from ``guess`` converged), ``seconds``.
    orbit : CircuitDrifterOrbit

    Raises
    ------
    ValueError
        No operating point (the default chain's reason).
    """
    limits = _limits(constraints, drifter)
    t0 = time.perf_counter()
    orbit, continued = _operating_point(drifter, guess)
    rec = _figures(orbit, limits)
    rec["continued"] = continued
    rec["seconds"] = time.perf_counter() - t0
    return rec, orbit


class _OperatingPoint(NamedTuple):
    """A design's orbit, and whether it was continued from a guess."""

    orbit: object
    continued: bool


class _Gradients(NamedTuple):
    """The gradients of a design's objective, shape ``(n,)``, and of its constraints' scaled
    margins, shape ``(m, n)``, in the ``n`` scaled variables."""

    objective: np.ndarray
    constraints: np.ndarray


def _operating_point(drifter: CircuitDrifter, guess) -> _OperatingPoint:
    """The design's orbit: Newton from ``guess`` where given and it converges, else the default
    chain; and whether it was continued (a valve drifter's as a design map's,
    :func:`~impactbar.physical.drifter.operating_point`)."""
    from .drifter import operating_point

    solve = drifter.orbit if isinstance(drifter, CircuitDrifter) else \
        (lambda guess=None: operating_point(drifter, guess))
    if guess is not None:
        try:
            return _OperatingPoint(solve(guess=guess), True)
        except (ValueError, np.linalg.LinAlgError, ArithmeticError):
            pass
    return _OperatingPoint(solve(), False)


def evaluate_blow(drifter: CircuitDrifter, impact_velocity: float, constraints: dict | None = None) -> dict:
    """A design in the circuit's ideal limit: its piston's blow on the rod and rock at
    ``impact_velocity`` (:func:`~impactbar.physical.piston.piston_blow`), the circuit taken to
    deliver the piston at it and to cost nothing.

    Parameters
    ----------
    drifter : CircuitDrifter
        With a drill string and the rock (``[rock]``).
    impact_velocity : float
        The piston's velocity at impact (m/s), ``> 0``.
    constraints : dict, optional
        Limits of :data:`IDEAL_CONSTRAINTS` (SI or with units); the others are the circuit's.

    Returns
    -------
    dict
        As :func:`evaluate_design`'s: ``objectives`` (``work_on_rock_J``, ``impact_energy_J``,
        ``efficiency``), ``constraints``, ``feasible``, ``seconds``.

    Raises
    ------
    ValueError
        No drill string, a constraint of the circuit, ``impact_velocity`` not positive.

    Examples
    --------
    >>> from impactbar.physical import build, read_config
    >>> from impactbar.physical.optimize_drifter import evaluate_blow
    >>> evaluate_blow(build(read_config("circuit-drifter")[0]), 10.0)
    Traceback (most recent call last):
    ...
    ValueError: the ideal limit (impact_velocity) needs the drill string and the rock ([rock] in the config)
    """
    from .piston import piston_blow

    if drifter.drill is None:
        raise ValueError("the ideal limit (impact_velocity) needs the drill string and the rock ([rock] in "
                         "the config)")
    limits = _limits(constraints, drifter, ideal=True)
    t0 = time.perf_counter()
    bar, drill = drifter.bar, drifter.drill
    blow = piston_blow(drill.segments, (drill.rock_k_N_m, drill.rock_k_u_N_m),
                       lengths=list(getattr(bar, "lengths_m", [bar.length_m])),
                       areas=list(getattr(bar, "areas_m2", [bar.area_m2])), impact_velocity=impact_velocity,
                       E=bar.E_Pa, density=bar.density_kg_m3, bit_mass=drill.bit_mass_kg, feed=drill.feed_N)
    blow = dict(blow, piston_mass_kg=bar.mass_kg)
    obj = {o.key: o.blow(blow) for o in outputs("record") if o.blow is not None}
    values = {name: constraint_output(name).output.blow(blow) for name in IDEAL_CONSTRAINTS}
    rec = _constrained(obj, values, limits)
    rec["seconds"] = time.perf_counter() - t0
    return rec


def _limits(constraints, drifter, ideal: bool = False) -> dict:
    if constraints is not None and not isinstance(constraints, dict):
        raise ValueError(f"constraints must be a dict of limits or None; got {constraints!r}")
    given = current_keys(dict(constraints or {}), "constraint")  # (an old name: a DeprecationWarning)
    kind = machine_kind(drifter)
    defaults = default_constraints(kind)
    unknown = sorted(k for k in given if not isinstance(k, str) or constraint_output(k, kind) is None)
    if unknown:
        what = "" if kind == "circuit" else " of a valve drifter (no oil circuit)"
        raise ValueError(f"constraints: unknown constraint {unknown[0]!r}{what}; one of "
                         f"{', '.join(defaults)}, or an output's name (at most the limit; "
                         "min_<name>, or a least value's own name, min_... or minimum_...: at least)")
    circuit = sorted(set(given) - set(IDEAL_CONSTRAINTS)) if ideal else []
    if circuit:
        raise ValueError(f"constraints: {circuit[0]!r} is the circuit's; in its ideal limit "
                         f"(impact_velocity) only {', '.join(IDEAL_CONSTRAINTS)}")
    out = {}
    for name, default in {**defaults, **given}.items():
        if ideal and name not in IDEAL_CONSTRAINTS:
            continue
        v = given.get(name, default)
        if v is None:
            continue
        if constraint_output(name, kind).output.rock and drifter.drill is None:
            raise ValueError(f"constraints: {name!r} needs the drill string and the rock ([rock] in the "
                             "config)")
        if v == "relief":
            v = drifter.si["relief_pressure_Pa"]
            if not math.isfinite(v):
                continue
        unit = constraint_output(name, kind).unit
        if isinstance(v, int | float) and not isinstance(v, bool):  # a bare number: SI
            out[name] = float(v)
            continue
        example = {"Pa": "'400 MPa'", "kg": "'5.6 kg'", "m**3": "'0.01 L'",
                   "m/min": "'2 m/min'"}.get(unit, "0.95")
        out[name] = to_si(f"constraints[{name!r}]", v, unit, example)
    return out


def _figures(orbit, limits: dict) -> dict:
    """An operating point's record: the outputs of the view ``"record"`` (by key) and the value of
    every constraint, the defaults' and those of ``limits`` (those the machine has)."""
    r, kind = Reading(orbit), orbit._kind
    obj = {o.key: o.of(r) for o in outputs("record", kind, rock=orbit.drifter.drill is not None)
           if o.of is not None}
    values = {name: float(constraint_output(name, kind).output.of(r))
              for name in {**default_constraints(kind), **limits}}
    return _constrained(obj, values, limits, kind)


def _constrained(obj: dict, values: dict, limits: dict, kind: str = "circuit") -> dict:
    """A design's record: its objectives ``obj`` and the constraints' ``values`` against ``limits``."""
    cons = {}
    for name, limit in limits.items():
        _, sense, scale, unit = constraint_output(name, kind)
        value = values[name]
        margin = (limit - value) if sense > 0 else (value - limit)
        scale = scale if scale is not None else abs(limit) or 1.0
        cons[name] = {"value": value, "limit": limit, "margin": margin, "unit": unit,
                      "scaled": margin / scale if math.isfinite(margin) else -1.0}
    feasible = all(c["scaled"] >= -FEASIBILITY_TOLERANCE for c in cons.values())
    return {"ok": True, "objectives": obj, "constraints": cons, "feasible": feasible,
            "figures": {k: v for k, v in values.items()}}


def least_margin(record: dict) -> float:
    """A design's smallest scaled margin over its constraints: negative where it misses one, the
    most missed one's miss over its scale (``inf`` where there is no constraint).

    Parameters
    ----------
    record : dict
        A design's record with an operating point (:func:`evaluate_design`, :func:`evaluate_blow`).

    Returns
    -------
    float

    Examples
    --------
    >>> least_margin({"constraints": {"a": {"scaled": 0.2}, "b": {"scaled": -0.05}}})
    -0.05
    """
    return min((c["scaled"] for c in record["constraints"].values()), default=math.inf)


def check_start(record: dict, any_start: bool) -> dict:
    """The search's start, refused where it has no operating point or, unless ``any_start``, where
    it misses a constraint (theory §11, "Optimising a drifter").

    Parameters
    ----------
    record : dict
        The start's record (:func:`evaluate_design`, :func:`evaluate_blow`, or a failed one).
    any_start : bool
        Whether an infeasible start is taken (``optimize_drifter(start="any")``).

    Returns
    -------
    dict
        ``record``.

    Raises
    ------
    ValueError
        No operating point (its error), or an infeasible start: the constraint missed most, its value,
        limit and how far it is missed, in one line.

    Examples
    --------
    >>> check_start({"ok": True, "feasible": False, "constraints": {"max_multiplier": {
    ...     "value": 0.99, "limit": 0.95, "margin": -0.04, "unit": "", "scaled": -0.04}}}, False)
    Traceback (most recent call last):
    ...
    ValueError: infeasible start: constraint max_multiplier = 0.99 misses its limit 0.95 by 0.04
    """
    if not record["ok"]:
        raise ValueError(f"the start has no operating point: {record['error']}")
    if not record["feasible"] and not any_start:
        name, c = min(record["constraints"].items(), key=lambda kv: kv[1]["scaled"])
        scale, unit = display_unit(c["unit"])
        u = f" {unit}" if unit else ""
        raise ValueError(f"infeasible start: constraint {name} = {c['value'] * scale:.6g}{u} misses its "
                         f"limit {c['limit'] * scale:.6g}{u} by {-c['margin'] * scale:.4g}{u}")
    return record


def _design_record(changes: dict, config: dict, folder, limits: dict) -> dict:
    """A design's record by a fresh ``orbit()`` (a worker's task in the population search); a design
    without a one-impact orbit not classified (the search classifies those its result lists)."""
    t0, drifter = time.perf_counter(), None
    try:
        drifter = build(with_values(config, changes), folder)
        rec, orbit = evaluate_design(drifter, limits)
        rec.update(piston_and_multipliers(drifter, orbit))
    except (ValueError, np.linalg.LinAlgError, ArithmeticError) as exc:
        rec = failed_record(exc, time.perf_counter() - t0, drifter, classify=False)
    return rec


def _gradient_column(j: int, cfg: dict, folder, rec: dict, orbit, spec: dict, limits: dict, fkey: str,
                     span: np.ndarray, step: float):
    """Column ``j`` of :func:`_design_gradient` (a module-level function: a worker's task): the
    objective's derivative and the margins' in the scaled variable ``j``, or ``None`` where neither
    the linearised orbit nor the secant of two continued orbits gives one (the column left zero)."""
    keys, names = list(spec), list(limits)
    design = with_values(cfg, rec["changes"])
    values, units = rec["values"], {k: spec[k]["unit"] for k in keys}
    key = keys[j]

    def read(point) -> dict:
        r = _figures(point, limits)
        return {"objective": r["objectives"][fkey], **{n: r["constraints"][n]["scaled"] for n in names}}

    try:
        _, _, derivatives = tangent_derivatives(design, folder, orbit, [key], values, units, step,
                                                "max_multiplier" in limits, read)
        col = {n: d[key] for n, d in derivatives.items()}
    except ValueError:  # a border within the step: the secant of two continued orbits
        h = step * abs(values[key])
        try:
            above, below = [read(build(with_values(design, {key: config_quantity(values[key] + s * h,
                                                                                 units[key])}),
                                       folder).orbit(guess=orbit)) for s in (1.0, -1.0)]
        except (ValueError, np.linalg.LinAlgError, ArithmeticError):
            return None
        col = {n: (above[n] - below[n]) / (2.0 * h) for n in above}
    return col["objective"] * span[j], [col[n] * span[j] for n in names]


def _design_gradient(cfg: dict, folder, rec: dict, orbit, spec: dict, limits: dict, fkey: str,
                     span: np.ndarray, step: float | None = None, columns=None) -> _Gradients:
    """The gradients of a design's objective and of its constraints' scaled margins in the scaled
    variables: per variable by :func:`~impactbar.physical.sensitivity.tangent_derivatives` from the
    design's orbit, or where its step meets a border (or a design read from the cache, without its
    orbit) by central differences of orbits continued from the design's; zeros for a design
    without an orbit. ``step``: the differences' relative step (``None``: :func:`default_step`'s);
    ``columns``: the columns already computed (:func:`_gradient_column`'s, by variable), else
    computed here one after another."""
    dobj, dcon = np.zeros(len(spec)), np.zeros((len(limits), len(spec)))
    if not rec["ok"]:
        return _Gradients(dobj, dcon)
    if orbit is None:
        orbit = build(with_values(cfg, rec["changes"]), folder).orbit()
    step = default_step(orbit.drifter) if step is None else step
    for j in range(len(spec)):
        col = (columns[j] if columns is not None else
               _gradient_column(j, cfg, folder, rec, orbit, spec, limits, fkey, span, step))
        if col is not None:
            dobj[j], dcon[:, j] = col
    return _Gradients(dobj, dcon)


#: The refined gradient's steps: the default one, then each a tenth of the one before.
REFINEMENTS = 3


def _refined_gradient(cfg: dict, folder, rec: dict, orbit, spec: dict, limits: dict, fkey: str,
                      span: np.ndarray, rtol: float = 1e-2, run=None) -> _Gradients:
    """:func:`_design_gradient` at the default step where it agrees with a step ten times smaller (the
    objective's and the margins' gradients together, to ``rtol`` of their norm), else at the smaller
    step where that agrees with the next (down to a thousandth of the default): near a border of the
    operating point (a design without an orbit within the default step, as at the whole drifter's best
    designs) the differences of the linearised orbit straddle it and are wrong (by up to a factor 50
    on the example rock drifter's), while those of a smaller step agree with central differences of
    fresh orbits. ``run``: a map (:func:`~impactbar.physical.optimize_population.record_map`'s, on a
    cluster's workers) that computes the columns of two steps together (the default and the next,
    then the last two where asked), the same numbers as one after another (each column the same
    function of the same orbit), compared here alike; ``None``: one step after another in this
    process, each where the one before asks for it."""
    if rec["ok"] and orbit is None:
        orbit = build(with_values(cfg, rec["changes"]), folder).orbit()
    step = default_step(orbit.drifter) if rec["ok"] else 0.0
    steps = []
    for _ in range(1 + (REFINEMENTS if rec["ok"] else 0)):  # (each a tenth of the one before, as divided)
        steps.append(step)
        step /= 10.0
    n, done = len(spec), {}

    def level(i):
        if run is not None and rec["ok"] and i not in done:  # (two steps a round: the first two always
            pair = [i, i + 1][:len(steps) - i]  # asked, the last two mostly, on the example's designs)
            flat = run(_step_column, [(steps[k], j) for k in pair for j in range(n)], cfg=cfg, folder=folder,
                       rec=rec, orbit=orbit, spec=spec, limits=limits, fkey=fkey, span=span)
            done.update({k: flat[m * n:(m + 1) * n] for m, k in enumerate(pair)})
        return _design_gradient(cfg, folder, rec, orbit, spec, limits, fkey, span, steps[i], done.get(i))

    prev = level(0)
    for i in range(1, len(steps)):
        cur = level(i)
        a, b = np.vstack([*prev]), np.vstack([*cur])
        if np.linalg.norm(a - b) <= rtol * max(np.linalg.norm(a), np.linalg.norm(b)):
            break
        prev = cur
    return prev


def _step_column(item: tuple, **common):
    """:func:`_gradient_column` of ``item = (step, j)`` (a worker's task of :func:`_refined_gradient`)."""
    step, j = item
    return _gradient_column(j, step=step, **common)
