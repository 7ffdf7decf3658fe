r"""The whole drifter optimised: piston shape, chambers, valve and circuit together, for drilling rate
per hydraulic kilowatt (or drilling rate, work on rock per blow, impact power) under the designer's
constraints (theory §11, "Optimising a drifter").

Each evaluation is the circuit's operating point on the rod and rock: :meth:`CircuitDrifter.orbit`
continued from the nearest design evaluated so far (Newton from its orbit) where that converges, else
the default chain. The search is derivative-free by default (COBYLA, :func:`scipy.optimize.minimize`)
over the variables scaled to :math:`[0, 1]` by their bounds: an operating point changes pattern (the
valve's switch before or after the impact, the relief opening or not) at borders where it is not
smooth, and an evaluation can fail (no orbit, cavitation). A design without an orbit is scored as the
far side of a border, not by a penalty (:mod:`~impactbar.physical.optimize_border`): by the first-order
extrapolation of the nearest design evaluated with one (its implicit-function-theorem gradients, one
per success, kept), and a constraint more, "the one-impact orbit exists", the existence margin (the
largest Floquet multiplier's modulus to the unit circle), negative there, its zero where that margin
extrapolates to zero, as a design map locates a border (else at a radius from the success); only in
the circuit's ideal limit, with no orbit to extrapolate, is a failed design objective 1 and every
constraint -1. The multistart's polish scores a failed design by the same model and is given the same
constraint, with their gradients (:mod:`~impactbar.physical.optimize_polish`). With
``method="slsqp"`` the search is SLSQP's with the gradients of the objective and of
the constraints by the implicit function theorem on each design's orbit
(:func:`~impactbar.physical.sensitivity.tangent_derivatives`: four flights per variable, no orbit
solved), a key across a border within the step by central differences of orbits continued from the
design's instead.
The reported optimum is the best feasible design evaluated, re-evaluated by a fresh ``orbit()``.
What the drill does at a design without a one-impact orbit (its motion from rest classified) is
found after the search, for the designs the result lists alone
(:func:`~impactbar.physical.optimize_failures.classify_listed`).

The circuit's ideal limit (``impact_velocity=``): each design is its piston's single blow on the rod
and rock at a given impact velocity, the circuit taken to deliver the piston at it and to cost
nothing, scored as :func:`~impactbar.physical.piston.optimize_piston` scores its designs
(:func:`~impactbar.physical.piston.piston_blow`); the objective the work on the rock per blow, the
constraints the peak incident stress and the piston's mass. Over the piston's diameters, its
lengths and mass held, the optimum is then :func:`~impactbar.physical.optimize_piston`'s (a check
of the search that does not trust it: ``tests/physical/test_optimize_drifter_checks.py``).

A valve drifter (``[valve]``, theory §10) is searched the same way at its operating point as a design
map finds it (:func:`~impactbar.physical.drifter.operating_point`), with the objectives and
constraints of its outputs (:func:`~impactbar.physical.optimize_problem.objectives`); a key that takes
integers is enumerated, each value a search over the other keys
(:mod:`~impactbar.physical.optimize_integers`).

This module is the search; the problem (the objectives, the constraints, a design's evaluation) is
:mod:`~impactbar.physical.optimize_problem`'s and the result :mod:`~impactbar.physical.optimize_result`'s,
their public names imported here as well.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import math
import time
from typing import NamedTuple

import numpy as np

from .circuit import CircuitDrifter
from .design_keys import INTEGER_KEYS, design_bounds
from .display_units import written_quantity
from .drifter import Drifter
from .loader import build, config_value, read_config, with_values
from .optimality import certify_search
from .optimize_border import EXISTENCE, BorderScore, border_score, existence_gradient, existence_margin
from .optimize_cache import DesignCache, OrbitChain
from .optimize_failures import classify_listed, failed_record
from .optimize_integers import integer_search
from .optimize_multistart import check_multistart, multistart_search
from .optimize_outputs import constraint_output, piston_and_multipliers, shank_stress
from .optimize_polish import polish_search
from .optimize_population import _is_client, check_population, penalised, population_search, record_map
from .optimize_problem import (
    DEFAULT_CONSTRAINTS,
    FEASIBILITY_TOLERANCE,
    IDEAL_CONSTRAINTS,
    OBJECTIVES,
    _design_gradient,
    _design_record,
    _Gradients,
    _limits,
    _operating_point,
    _refined_gradient,
    check_start,
    default_constraints,
    evaluate_blow,
    evaluate_design,
    least_margin,
    machine_kind,
    objectives,
)
from .optimize_progress import DesignProgress
from .optimize_result import DrifterOptimum, _better_missed
from .units import to_si

__all__ = ["OBJECTIVES", "DEFAULT_CONSTRAINTS", "IDEAL_CONSTRAINTS", "FEASIBILITY_TOLERANCE",
           "optimize_drifter", "evaluate_design", "evaluate_blow", "DrifterOptimum"]


class _Near(NamedTuple):
    """A design with an orbit, a guess for the designs after it: its scaled variables and id."""

    u: np.ndarray
    id: str


class _Design(NamedTuple):
    """A design: its id (its values' reprs), its values by key, its changes to the config."""

    id: str
    values: dict
    changes: dict


def _fingerprint(config: dict, vary: dict, objective: str, constraints: dict) -> str:
    text = json.dumps([config, {k: list(v) for k, v in vary.items()}, objective, constraints], sort_keys=True,
                      default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def optimize_drifter(config, vary: dict, objective: str = "drilling_rate_per_kW",
                     constraints: dict | None = None,
                     *, max_evaluations: int = 60, cache=None, progress: bool = True, rhobeg: float = 0.2,
                     tol: float = 2e-3, method: str = "cobyla", impact_velocity=None, workers=None,
                     popsize: int = 5, seed: int = 0, sample: int = 64,
                     local_starts: int = 3, start: str = "feasible", polish: int = 12) -> DrifterOptimum:
    r"""The design of a drifter with its oil circuit, or of a valve drifter, that maximises
    ``objective`` under ``constraints``, the variables any of its dotted config keys within bounds.

    Parameters
    ----------
    config : str, os.PathLike or dict
        A drifter with its oil circuit (``[chambers]``) or a valve drifter (``[valve]``: the machines
        a design map sweeps, a hammer not), on a drill string and the rock for the drilling
        objectives: a TOML file, a preset's name or the config itself
        (:func:`~impactbar.physical.read_config`).
    vary : dict
        Dotted key (``"piston.collar_diameter"``, ``"chambers.rear_volume"``, ``"valve.switch_out"``,
        ``"accumulator.precharge"``, ``"stop.restitution"``: any key the config gives that a design
        map sweeps, :func:`~impactbar.physical.design_keys.design_bounds`) to ``(low, high)`` with
        units (``("46 mm", "52 mm")``, a number for a dimensionless key); the config's own value,
        the start, must lie within. A key that takes integers (``"model.n_modes": (6, 8)``,
        :data:`~impactbar.physical.design_keys.INTEGER_KEYS`) has integer bounds and is
        enumerated: each combination of the integer keys' values (at most
        :data:`~impactbar.physical.optimize_integers.MAX_INTEGER_DESIGNS`) a search over the other
        keys by ``method``, or one fresh orbit without other keys; ``cache`` then one file per
        combination beside it.
    objective : str
        One of :data:`OBJECTIVES` (maximised): ``"drilling_rate_per_kW"`` (default),
        ``"drilling_rate"``, ``"work_on_rock_per_blow"``, ``"impact_power"``; a valve drifter has
        no pump: ``"impact_power"`` (its percussive power), ``"work_on_rock_per_blow"``,
        ``"drilling_rate"``.
    constraints : dict, optional
        Limits of :data:`DEFAULT_CONSTRAINTS` (with units or SI; ``None`` drops one), e.g.
        ``{"peak_rod_stress": "260 MPa"}``; a valve drifter's are those of its outputs
        (:func:`~impactbar.physical.optimize_problem.default_constraints`: no oil's).
    max_evaluations : int
        The most designs the search evaluates (besides the baseline's and the optimum's fresh
        re-evaluation); for SLSQP the most iterations, each its line search's designs (one where its
        full step is accepted; 252 designs for 30 on the example rock drifter).
    cache : str or os.PathLike, optional
        A file of the designs evaluated: read first (a run stopped part-way resumes from it, the
        search visiting the same designs), each design appended to it as one JSON line when it is
        evaluated (:class:`~impactbar.physical.optimize_cache.DesignCache`; a file of the format
        before, one JSON document, is read too). Keyed by the problem (the config, the variables and
        bounds, the objective, the constraints): a cache of another problem is not reused, and is
        overwritten. A resumed run visits the designs of a run never
        stopped, with the same figures to the bit: a design read from it carries its figures, not
        its orbit, and where a new design continues from one, that orbit is solved again as the first
        run solved it, along the designs' recorded guesses
        (:class:`~impactbar.physical.optimize_cache.OrbitChain`; the population search's designs are
        each a fresh orbit). The gradients computed (SLSQP's, the polish's) are kept in it too and
        read back, to the bit, where a run started again asks for them.
    progress : bool
        A progress bar (tqdm) on stderr where it is a terminal, none where it is not: the designs
        evaluated, the last one's seconds and the slowest one's
        (:class:`~impactbar.physical.optimize_progress.DesignProgress`).
    rhobeg, tol : float
        COBYLA's first and last step in the scaled variables (each bound's span is 1), ``rhobeg`` in
        ``(0, 1]``, ``tol`` in ``(0, rhobeg]`` (other methods: ``(0, 1]``); for SLSQP
        its ``ftol`` is ``tol ** 3`` (on the objective over the start's: 8e-9 by default, above
        the orbits' own accuracy, about 1e-9) and ``rhobeg`` is not used; a population stops once
        its scores spread below ``tol ** 2``.
    method : {"cobyla", "slsqp", "differential_evolution", "multistart"}
        The search: derivative-free (COBYLA), SLSQP with the implicit function theorem's
        gradients (module docstring; ``max_evaluations`` then bounds its iterations; where a border
        of the operating point lies along an active constraint, as the blow's on the example rock
        drifter, its line search backtracks at every step: there COBYLA), or a
        population's (:mod:`~impactbar.physical.optimize_population`: the constraints a penalty, each
        generation's designs evaluated together on ``workers``, each by a fresh ``orbit()``;
        ``max_evaluations`` bounds its designs, in whole generations, at least two), or COBYLA from
        the best feasible designs of a Sobol sample evaluated together
        (:mod:`~impactbar.physical.optimize_multistart`).
        A valve drifter: not SLSQP, and the multistart with ``polish=0`` (their gradients are the
        oil circuit's); its certificate's gradients central differences of fresh orbits.
    workers : None, int or distributed.Client
        Where a population's or a sample's designs are evaluated (those two methods only):
        ``None`` this process, an integer (at least 1) a local dask cluster of that many processes
        (started and closed by the call), or a client's cluster; the same records either way. The
        multistart's polish and its certificate compute their gradients' columns there too (two
        steps of :func:`~impactbar.physical.optimize_problem._refined_gradient` a round) on more
        than one worker or a client's cluster: the same gradients as in this process, to the bit.
    popsize, seed : int
        The population per variable (at least 2) and the random seed (at least 0) of
        ``method="differential_evolution"`` (``"multistart"``: the sample's seed).
    sample, local_starts : int
        ``method="multistart"``: the sample's designs (a power of two) and the local searches (in
        ``[1, sample]``), each ``(max_evaluations - sample) // local_starts`` designs at most.
    polish : int
        ``method="multistart"``: the most designs of the polish of the best feasible design found
        (:mod:`~impactbar.physical.optimize_polish`: SLSQP with the implicit function theorem's
        gradients from it), besides ``max_evaluations``; it stops earlier at its first iterate that
        is the best design so far and meets the first-order conditions (the certificate's
        :data:`~impactbar.physical.optimality.KKT_TOLERANCE`); its design is reported where a fresh
        orbit confirms it feasible and better, and certified as SLSQP's (the active set within 1e-4,
        no step of COBYLA's); 0: no polish.
    start : {"feasible", "any"}
        Whether the config's design, the search's start, must meet the constraints (``"feasible"``,
        else a ``ValueError``) or may miss them (``"any"``: COBYLA and SLSQP move towards the
        feasible region; the baseline is then an infeasible design, and where no design evaluated
        is feasible the reported one is the least infeasible, its certificate ``"infeasible"`` and
        the message saying so). A start without an operating point is refused either way.
    impact_velocity : float or str, optional
        The circuit's ideal limit (m/s, or with units, ``> 0``): each design is its piston's blow on
        the rod and rock at this impact velocity alone (:func:`evaluate_blow`), the circuit taken to
        deliver the piston at it; the objective ``"work_on_rock_per_blow"``, the constraints those of
        :data:`IDEAL_CONSTRAINTS` (the circuit's are not computed), the method COBYLA. Over the
        piston's diameters at held lengths and mass (``{"piston_mass": ...}``, active at the
        optimum: more mass, more work) its optimum is :func:`~impactbar.physical.optimize_piston`'s.

    Returns
    -------
    DrifterOptimum

    Raises
    ------
    ValueError
        A variable that is not a parameter or not in the config, bounds of the wrong unit or outside
        the key's range, a start outside its bounds, an unknown objective or constraint, an
        objective or constraint the machine does not have (no ``[rock]``, a valve drifter's no oil),
        a hammer, a method a valve drifter does not take, integer bounds not integers or too many, a
        start without an operating point or, with ``start="feasible"``, an infeasible start (the
        constraint named, with how far it is missed): each in one line.

    Examples
    --------
    >>> from impactbar.physical import optimize_drifter
    >>> optimize_drifter("circuit-drifter", {"valve.switch_out": ("20 mm", "23 mm")}, objective="speed")
    Traceback (most recent call last):
    ...
    ValueError: objective must be one of impact_power, work_on_rock_per_blow, drilling_rate,
    drilling_rate_per_kW; got 'speed'
    """
    from scipy.optimize import minimize

    t_start = time.perf_counter()
    if not isinstance(objective, str) or objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {', '.join(OBJECTIVES)}; got {objective!r}")
    cfg, folder = read_config(config)
    base = build(cfg, folder, where="config" if folder is None else str(config))  # (the file named)
    if not isinstance(base, CircuitDrifter | Drifter):
        raise ValueError("config must describe a drifter with its oil circuit (a [chambers] section) or a "
                         "valve drifter (a [valve] section), the machines a design map sweeps; got a "
                         f"{type(base).__name__}")
    kind = machine_kind(base)
    named = objectives(kind)
    if objective not in named:
        raise ValueError(f"objective {objective!r} is not a valve drifter's (no oil circuit); one of "
                         f"{', '.join(named)}")
    if kind == "drifter" and (method == "slsqp" or method == "multistart" and polish):
        raise ValueError(f"method {method!r}{' with polish' if polish and method == 'multistart' else ''}: "
                         "SLSQP's gradients are the oil circuit's orbit's; a valve drifter takes 'cobyla', "
                         "'differential_evolution' or 'multistart' with polish=0")
    if base.drill is None and objective != "impact_power":
        raise ValueError(f"objective {objective!r} needs the drill string and the rock ([rock] in the "
                         "config); "
                         "without them only 'impact_power'")
    if method not in ("cobyla", "slsqp", "differential_evolution", "multistart"):
        raise ValueError(f"method must be 'cobyla', 'slsqp', 'differential_evolution' or 'multistart'; got "
                         f"{method!r}")
    if not (isinstance(rhobeg, int | float) and not isinstance(rhobeg, bool) and 0.0 < rhobeg <= 1.0):
        raise ValueError(f"rhobeg must be a number in (0, 1] (COBYLA's first step in the variables scaled "
                         f"by their bounds); got {rhobeg!r}")
    top, name = (rhobeg, f"rhobeg] = (0, {rhobeg:g}]") if method in ("cobyla", "multistart") else (1.0, "1]")
    if not (isinstance(tol, int | float) and not isinstance(tol, bool) and 0.0 < tol <= top):
        raise ValueError(f"tol must be a number in (0, {name} (the search's last step in the scaled "
                         f"variables); got {tol!r}")
    if start not in ("feasible", "any"):
        raise ValueError(f"start must be 'feasible' or 'any'; got {start!r}")
    if not (isinstance(polish, int) and not isinstance(polish, bool) and polish >= 0):
        raise ValueError(f"polish must be an integer >= 0 (the polish's most designs); got {polish!r}")
    any_start = start == "any"  # (the name start is the start's values below)
    if workers is not None and method not in ("differential_evolution", "multistart"):
        raise ValueError(f"workers: only with method='differential_evolution'/'multistart', not {method!r}")
    ideal = impact_velocity is not None
    if ideal:
        V = (float(impact_velocity) if isinstance(impact_velocity, int | float)
             and not isinstance(impact_velocity, bool) else
             to_si("impact_velocity", impact_velocity, "m/s", "'10 m/s'"))
        if not (math.isfinite(V) and V > 0.0):
            raise ValueError(f"impact_velocity must be a positive speed, e.g. '10 m/s'; got "
                             f"{impact_velocity!r}")
        if objective != "work_on_rock_per_blow":
            raise ValueError(f"in the circuit's ideal limit (impact_velocity) the objective is "
                             f"'work_on_rock_per_blow'; got {objective!r}")
        if method != "cobyla":
            raise ValueError("in the circuit's ideal limit (impact_velocity) the method is 'cobyla' (SLSQP's "
                             f"gradients come from the circuit's orbits); got {method!r}")
    limits = _limits(constraints, base, ideal=ideal)
    kept = dict.fromkeys(default_constraints(kind)) | limits  # (evaluate_design's: a dropped one stays so)
    spec = design_bounds(cfg, vary, folder)
    keys = list(spec)
    if not (isinstance(max_evaluations, int) and max_evaluations >= len(keys) + 2):
        raise ValueError(f"max_evaluations must be an integer of at least the variables' number + 2 "
                         f"({len(keys) + 2}); got {max_evaluations!r}")
    if method == "differential_evolution":
        maxiter = check_population(workers, popsize, seed, max_evaluations, len(keys))
    elif method == "multistart":
        budget = check_multistart(workers, sample, local_starts, seed, max_evaluations, len(keys))

    def fresh_design(at: dict):
        """The design of changes ``at`` by a fresh ``orbit()`` (no continuation, no cache), or its blow
        in the ideal limit: the drifter, the record and the orbit (``None`` for a blow)."""
        drifter = build(with_values(cfg, at), folder)
        return (drifter, *((evaluate_blow(drifter, V, limits), None) if ideal else
                           evaluate_design(drifter, kept)))

    def fresh_record(at: dict, **given) -> dict:
        """:func:`fresh_design`'s record with its piston, multipliers and the shank's stress (``given``:
        its values, changes)."""
        drifter, out, orbit = fresh_design(at)
        out.update(piston_and_multipliers(drifter, orbit), **given,
                   shank_stress=None if ideal else shank_stress(drifter, orbit))
        return out

    if any(k in INTEGER_KEYS for k in keys):  # each integer design a search over the other keys
        def search(design, others, start_as, cache_file):
            return optimize_drifter(with_values(cfg, design), others, objective, constraints,
                                    max_evaluations=max_evaluations, cache=cache_file, progress=progress,
                                    rhobeg=rhobeg, tol=tol, method=method, impact_velocity=impact_velocity,
                                    workers=workers, popsize=popsize, seed=seed, sample=sample,
                                    local_starts=local_starts, start=start_as, polish=polish)

        return integer_search(cfg, spec, vary, objective, kind, search, fresh_record, any_start=any_start,
                              cache=cache)
    lo = np.array([spec[k]["low"] for k in keys])
    span = np.array([spec[k]["high"] - spec[k]["low"] for k in keys])
    fkey = named[objective].key
    tag = _fingerprint(cfg, {k: (spec[k]["low"], spec[k]["high"]) for k in keys}, objective,
                       dict(limits, impact_velocity=V) if ideal else limits)

    log = DesignCache(cache, tag)  # (a run started again: no design, no gradient computed twice)
    store, stored_gradients = log.designs, log.gradients
    n_cached = 0
    near: list[_Near] = []  # the designs with an orbit: their scaled variables, ids
    history: list[dict] = []
    counter = {"new": 0, "gradients": 0, "cached_gradients": 0}
    # each design's orbit by its id (a stored design's solved again along its guesses where needed)
    chain = OrbitChain(store, lambda c, g: _operating_point(build(with_values(cfg, c), folder), g).orbit)
    gradients: dict = {}  # by (id, "default") (SLSQP's), by (id, "refined") (the polish's)
    found: list = []  # the multistart's local searches
    points: dict[str, np.ndarray] = {}  # each design's scaled variables by its id
    polished = None  # the multistart's polish (its result)

    def changes_of(values: dict) -> dict:
        return {k: written_quantity(values[k], spec[k]["unit"], config_value(cfg, k)) for k in keys}

    def design_of(u: np.ndarray) -> _Design:
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        x = np.where(u == u0, start, lo + span * u)  # the start exactly as the config gives it
        values = {k: float(v) for k, v in zip(keys, x, strict=True)}
        changes = changes_of(values)
        changes.update({k: config_value(cfg, k) for k, at in zip(keys, u == u0, strict=True) if at})
        return _Design(json.dumps([repr(values[k]) for k in keys]), values, changes)

    def id_and_changes(u: np.ndarray) -> tuple[str, dict]:
        design = design_of(u)
        return design.id, design.changes

    def evaluate(u: np.ndarray, done: dict | None = None) -> dict:
        nonlocal n_cached
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        rid, values, changes = design_of(u)
        points.setdefault(rid, u)
        t0, drifter = time.perf_counter(), None
        if rid in store:
            rec = store[rid]
            if not any(r is rec for r in history):
                n_cached += 1
                history.append(rec)
                if rec.get("ok") and "u" in rec:  # a guess for the designs after it, as in the first run
                    near.append(_Near(np.asarray(rec["u"], dtype=float), rid))
            return rec
        try:
            if done is not None:  # computed by the population's map
                rec = done
            else:
                drifter = build(with_values(cfg, changes), folder)
                if ideal:
                    rec, orbit = evaluate_blow(drifter, V, limits), None
                else:
                    guess = min(near, key=lambda p: float(np.sum((p.u - u) ** 2))).id if near else None
                    rec, orbit = evaluate_design(drifter, kept, None if guess is None else chain.orbit(guess))
                    rec.update(guess=guess, u=u.tolist())
                    near.append(_Near(u.copy(), rid))
                    chain.add(rid, orbit)
                rec.update(piston_and_multipliers(drifter, orbit))
        except (ValueError, np.linalg.LinAlgError, ArithmeticError) as exc:
            rec = failed_record(exc, time.perf_counter() - t0, None if ideal else drifter, classify=False)
        rec.update(id=rid, values=values, changes=changes)
        log.add(rec)  # (store[rid])
        history.append(rec)
        counter["new"] += 1
        bar.design(rec["seconds"])
        return rec

    # COBYLA's budget counts its designs, the start among them; SLSQP's its iterations
    bar = DesignProgress(None if method == "slsqp" else max_evaluations, progress)
    start = np.array([spec[k]["start"] for k in keys])
    u0 = (start - lo) / span
    cluster = contextlib.ExitStack()  # (the multistart's workers, open through its polish and certificate)
    spread = None  # the multistart's map on its workers: the polish's, the certificate's gradient columns
    try:
        first = check_start(evaluate(u0), any_start)
        ref = abs(first["objectives"][fkey]) or 1.0

        # a design without an orbit scored by the border model (optimize_border): the nearest success's
        # first-order extrapolation, and the existence constraint negative there (a penalty, objective 1
        # and every constraint -1, only where no design has an orbit to extrapolate: the ideal limit)
        scale = constraint_output("max_multiplier", kind).scale or abs(limits.get("max_multiplier", 0.95))

        def border(rec: dict, which: str = "default") -> dict | None:
            """A failed design's scores by the border model, kept in its record (``None``: no design
            with an orbit, the ideal limit's): from the nearest design evaluated with an orbit (a
            sample's too, its gradient then from a fresh orbit), by its gradients of kind ``which``
            (``"default"``, the search's; ``"refined"``, the polish's), the record's ``gradient``."""
            if "border" not in rec and not ideal:
                u = points[rec["id"]]
                success = min((r for r in history if r["ok"]),
                              key=lambda r: float(np.sum((points[r["id"]] - u) ** 2)))
                nid, at = success["id"], points[success["id"]]
                grad, d_exists = exists_model(at, which)
                radius = min((r["border"]["radius"] for r in history if "radius" in r.get("border", {})
                              and r["border"]["nearest"] == nid), default=math.inf)
                s = border_score(u, at, success["objectives"][fkey], [c["scaled"] for c in success[
                    "constraints"].values()], existence_margin(success, scale), *grad, d_exists, radius)
                rec["border"] = {"nearest": nid, **s.as_record(),
                                 **({} if which == "default" else {"gradient": which})}
                log.changed(rec)  # (written again with the cache's next line)
            return rec.get("border")

        def exists_model(at, which: str):
            """A success's gradients of kind ``which`` and its existence margin's (``None``: not known);
            a valve drifter's figures have no such gradients: held (zeros)."""
            if kind != "circuit":
                return _Gradients(np.zeros(len(keys)), np.zeros((len(limits), len(keys)))), None
            grad = model_gradient(at, which)
            return grad, (grad.constraints[list(limits).index("max_multiplier")] if "max_multiplier" in limits
                          else None)

        def f(u):
            rec = evaluate(u)
            if rec["ok"]:
                return -rec["objectives"][fkey] / ref
            return 1.0 if border(rec) is None else -rec["border"]["objective"] / ref

        def g(u):
            rec = evaluate(u)
            if rec["ok"]:
                return np.array([c["scaled"] for c in rec["constraints"].values()])
            return -np.ones(len(limits)) if border(rec) is None else np.array(rec["border"]["margins"])

        def exists(u):  # the constraint "the one-impact orbit exists" (optimize_border)
            rec = evaluate(u)
            if rec["ok"]:  # (met: an orbit past the unit circle exists too, at 0)
                return max(existence_margin(rec, scale), 0.0)
            return -1.0 if border(rec) is None else rec["border"][EXISTENCE]

        def gradient_of(u, kind, compute):
            """A design's gradients: computed once per design and kind, kept in the cache file (a run
            started again reads them back, to the bit, where it would compute them again)."""
            rec = evaluate(u)
            key = (rec["id"], kind)
            if key not in gradients:
                kept = stored_gradients.get(key)
                if kept is not None:
                    gradients[key] = _Gradients(np.asarray(kept["objective"], dtype=float),
                                                np.asarray(kept["constraints"], dtype=float).reshape(
                                                    len(limits), len(keys)))
                    counter["cached_gradients"] += 1
                else:
                    orbit = chain.orbit(rec["id"]) if rec["ok"] and "u" in rec else None
                    gradients[key] = compute(cfg, folder, rec, orbit, spec, limits, fkey, span)
                    counter["gradients"] += 1
                    log.add_gradient(*key, gradients[key]._asdict())
            return gradients[key]

        def model_gradient(u, which: str = "default"):
            """A design's gradients of kind ``which`` (the polish's ``"refined"``: the step refined
            where it meets a border, _refined_gradient); a failed design's, its border model's: those
            of its nearest success, of the kind the model used."""
            rec = evaluate(u)
            if not rec["ok"] and border(rec, which) is not None:
                u, which = points[rec["border"]["nearest"]], rec["border"].get("gradient", "default")
            return gradient_of(u, which, _design_gradient if which == "default" else
                              functools.partial(_refined_gradient, run=spread))  # (on the workers: spread)

        def derivative(u):  # (SLSQP's and the border model's)
            return model_gradient(u)

        def refined(u):  # the polish's
            return model_gradient(u, "refined")

        def polish_border(u):  # the polish's scores of a failed design (optimize_polish.polish's border)
            b = border(evaluate(u), "refined")
            return None if b is None else (b["objective"], np.asarray(b["margins"], dtype=float))

        def polish_exists(u):  # the polish's constraint "the one-impact orbit exists" (its model's)
            rec = evaluate(u)
            if not rec["ok"]:
                border(rec, "refined")
            return exists(u)

        def d_existence(u):
            """The gradient of the polish's existence constraint: at a design with an orbit its
            existence margin's (0 where that is clipped at 0), at a failed design the border model's
            (optimize_border.existence_gradient)."""
            rec = evaluate(u)
            if rec["ok"]:
                _, d_e = exists_model(u, "refined")
                return np.zeros(len(keys)) if d_e is None or existence_margin(rec, scale) <= 0.0 else d_e
            b = border(rec, "refined")
            success = next(r for r in history if r["id"] == b["nearest"])
            _, d_e = exists_model(points[b["nearest"]], b.get("gradient", "default"))
            return existence_gradient(points[rec["id"]], points[b["nearest"]], BorderScore.from_record(b),
                                      existence_margin(success, scale), d_e)

        if method == "differential_evolution":
            res = population_search(lambda u: penalised(evaluate(u), fkey, ref),
                                    id_and_changes, store, evaluate, _design_record,
                                    {"config": cfg, "folder": folder, "limits": kept}, u0, popsize=popsize,
                                    maxiter=maxiter, seed=seed, workers=workers, atol=tol ** 2)
        elif method in ("cobyla", "multistart"):
            def cobyla(u, most=max_evaluations):
                return minimize(f, u, method="COBYLA", constraints=[{"type": "ineq", "fun": g}] + (
                    [] if ideal else [{"type": "ineq", "fun": exists}]), bounds=[(0.0, 1.0)] * len(keys),
                    options={"rhobeg": rhobeg, "tol": tol, "maxiter": most})
            if method == "multistart":
                run = cluster.enter_context(record_map(workers))
                # (one worker, or this process: each step where the one before asks for it)
                spread = run if _is_client(workers) or workers is not None and workers > 1 else None
            res, found = (cobyla(u0), []) if method == "cobyla" else multistart_search(
                evaluate, id_and_changes, store, _design_record,
                {"config": cfg, "folder": folder, "limits": kept}, lambda u: cobyla(u, budget), fkey,
                sample=sample, local_starts=local_starts, seed=seed, run=run, n_variables=len(keys))
            if found and polish:
                polished = polish_search(evaluate, g, refined, history, points, fkey, designs=polish,
                                         ftol=tol ** 3, border=None if ideal else polish_border,
                                         existence=None if ideal else polish_exists,
                                         d_existence=None if ideal else d_existence)
        else:
            res = minimize(f, u0, jac=lambda u: -derivative(u).objective / ref, method="SLSQP",
                           constraints=[{"type": "ineq", "fun": g,
                                         "jac": lambda u: derivative(u).constraints}],
                           bounds=[(0.0, 1.0)] * len(keys),
                           options={"ftol": tol ** 3, "maxiter": max_evaluations})
        message = str(res.message) + ("" if polished is None else f"; {polished.summary}")
        bar.finish()
    except BaseException:
        cluster.close()
        raise
    finally:
        bar.close()
        log.close()
    with cluster:  # (the multistart's workers, open through the certificate: its gradient's columns there)
        # what the drill does at the designs without a one-impact orbit that the result lists (the search
        # classified none: the motion from rest costs several evaluations)
        if classify_listed(history, lambda r: build(with_values(cfg, r["changes"]), folder)):
            log.rewrite()  # (their records changed: the file written anew, once)
        # the reported optimum (and the baseline) by a fresh orbit(): no continuation, no cache; the best
        # feasible design whose fresh orbit meets the constraints too (a continued orbit's figures can lie
        # some 1e-9 from the fresh one's, a design at an active limit on its other side)
        fresh = {}
        ranked = sorted((r for r in history if r.get("feasible")), key=lambda r: r["objectives"][fkey],
                        reverse=True)
        if not ranked:  # (a start="any" search that found no feasible design: the least infeasible reported)
            ranked = [max((r for r in history if r.get("ok")), key=least_margin)]
            message += (f"; no feasible design found: the design reported is the least infeasible (its "
                        f"smallest scaled margin {least_margin(ranked[0]):.3g})")
        for name, rec in [("baseline", first)] + [("optimum", r) for r in ranked]:
            if "optimum" in fresh and fresh["optimum"]["feasible"]:
                break
            best = rec
            out = fresh_record(rec["changes"], values=rec["values"], changes=rec["changes"])
            out["continued_vs_fresh"] = max(abs(out["objectives"][k] / rec["objectives"][k] - 1.0)
                                            for k in rec["objectives"] if rec["objectives"][k] != 0.0)
            if name == "optimum" and "optimum" in fresh:
                message += "; the best design's fresh orbit missed a constraint, the next best kept"
            fresh[name] = out
        message += _better_missed(history, best, fkey)
        # the polish's design reported: resolved by SLSQP (no step of COBYLA's), its stop SLSQP's
        by_polish = polished is not None and polished.improved and best["id"] == design_of(polished.x).id

        def fresh_of(v):  # a design's fresh record: the ideal limit's blow, a valve drifter's operating point
            _, record, _ = fresh_design(design_of(v).changes)
            return record

        # (a valve drifter has no implicit-function-theorem gradients: central differences, as the blow's)
        try:
            certificate = certify_search(fresh["optimum"], history, keys, (lo, span),
                                         polished if by_polish else res, tol, fkey,
                                         fresh_of if ideal or kind == "drifter" else None,
                                         lambda: _refined_gradient(cfg, folder, fresh["optimum"], None, spec,
                                                                   limits, fkey, span, run=spread),
                                         tol if method in ("cobyla", "multistart") and not by_polish else 0.0)
        except ValueError as exc:
            if kind == "circuit":
                raise
            certificate = None
            message += f"; no certificate: a neighbour has no operating point ({exc})"
    return DrifterOptimum(objective=objective,
                          vary={k: {"low": spec[k]["low"], "high": spec[k]["high"], "unit": spec[k]["unit"]}
                                for k in keys},
                          baseline=fresh["baseline"], optimum=fresh["optimum"], evaluations=counter["new"],
                          cached=n_cached, seconds=time.perf_counter() - t_start, history=history,
                          message=message, config=with_values(cfg, best["changes"]),
                          gradients=counter["gradients"], cached_gradients=counter["cached_gradients"],
                          certificate=certificate, found=found, kind=kind)
