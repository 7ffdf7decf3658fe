r"""The integer keys of the whole-drifter optimiser (:func:`~impactbar.physical.optimize_drifter`): a
key that takes integers (:data:`~impactbar.physical.design_keys.INTEGER_KEYS`: ``model.n_modes``,
``rock.cells_per_piston``), varied by enumeration (theory §11, "Optimising a drifter").

Each integer design (each combination of the integer keys' values within their bounds, at most
:data:`MAX_INTEGER_DESIGNS`) is the config with those values, and the search runs over the other
keys from it, by the method asked for; without other keys it is evaluated by a fresh orbit. The
reported design is the best feasible one of all these searches' reported designs (each confirmed by
a fresh orbit), its certificate its own search's, over the other keys at its integer values. An
enumeration is exact over the integers, where a relaxation (a continuous search rounding them, or
:func:`scipy.optimize.differential_evolution`'s ``integrality``) would compare designs of different
model resolutions found by one search's path: the integers here are few (a model's modes, a rock's
cells), each changing the model, not a dimension of the machine.

A search from another integer design than the config's own starts from the config's other values,
which may miss a constraint there: it runs with ``start="any"``; one whose start has no operating
point is reported in the message and left out.
"""

from __future__ import annotations

import itertools
import math
import time
from pathlib import Path

from .design_keys import INTEGER_KEYS
from .loader import with_values
from .optimize_failures import failed_record
from .optimize_problem import check_start, least_margin, objectives
from .optimize_result import DrifterOptimum

__all__ = ["MAX_INTEGER_DESIGNS", "integer_designs", "integer_search"]

#: The most integer designs an optimisation enumerates (each a search over the other keys).
MAX_INTEGER_DESIGNS = 12


def integer_designs(spec: dict, keys: list) -> list[dict]:
    """Every combination of the integer keys' values within their bounds, the config's own first.

    Parameters
    ----------
    spec : dict
        The variables' bounds and starts (:func:`~impactbar.physical.design_keys.design_bounds`).
    keys : list of str
        The integer keys among them.

    Returns
    -------
    list of dict
        Key to an ``int``, each combination once.

    Raises
    ------
    ValueError
        More than :data:`MAX_INTEGER_DESIGNS` combinations, in one line.

    Examples
    --------
    >>> spec = {"model.n_modes": {"low": 2.0, "high": 4.0, "unit": "", "start": 3.0}}
    >>> integer_designs(spec, ["model.n_modes"])
    [{'model.n_modes': 3}, {'model.n_modes': 2}, {'model.n_modes': 4}]
    """
    ranges = [range(int(spec[k]["low"]), int(spec[k]["high"]) + 1) for k in keys]
    n = math.prod(len(r) for r in ranges)
    if n > MAX_INTEGER_DESIGNS:
        raise ValueError(f"vary: the integer keys {', '.join(keys)} take {n} values together within their "
                         f"bounds; at most {MAX_INTEGER_DESIGNS} (each a search over the others): narrow")
    own = tuple(int(spec[k]["start"]) for k in keys)
    combos = sorted(itertools.product(*ranges), key=lambda c: c != own)  # (stable: the own one first)
    return [dict(zip(keys, c, strict=True)) for c in combos]


def _named(design: dict) -> str:
    return ", ".join(f"{k} = {v}" for k, v in design.items())


def _with(rec: dict, design: dict) -> dict:
    """A record with the integer design's values and changes added (its own kept)."""
    return dict(rec, values={**{k: float(v) for k, v in design.items()}, **rec.get("values", {})},
                changes={**design, **rec.get("changes", {})})


def _cache_of(cache, design: dict):
    """An integer design's own cache file beside ``cache`` (``a.json``: ``a.model.n_modes=3.json``)."""
    if cache is None:
        return None
    path = Path(cache)
    return path.with_name(f"{path.stem}.{'.'.join(f'{k}={v}' for k, v in design.items())}{path.suffix}")


def integer_search(cfg: dict, spec: dict, vary: dict, objective: str, kind: str, search, fresh, *,
                   any_start: bool, cache=None) -> DrifterOptimum:
    """The best design over the integer keys' values, each a search over the other keys.

    Parameters
    ----------
    cfg : dict
        The config.
    spec : dict
        Every variable's bounds and start (:func:`~impactbar.physical.design_keys.design_bounds`).
    vary : dict
        The variables as given (dotted key to ``(low, high)``), the integer keys among them.
    objective : str
        The objective's name.
    kind : {"circuit", "drifter"}
        The machine (:func:`~impactbar.physical.optimize_problem.machine_kind`).
    search : callable
        ``search(design, others, start, cache)``: the :class:`DrifterOptimum` of the search over the
        other keys ``others`` (a ``vary`` dict) from the config with the integer ``design`` (key to
        ``int``), ``start`` ``"feasible"`` or ``"any"``.
    fresh : callable
        ``fresh(changes)``: a design's record by a fresh orbit (raises ``ValueError`` where it has
        none).
    any_start : bool
        Whether the config's own design may miss the constraints.
    cache : path-like, optional
        The cache file: each integer design's search has its own beside it.

    Returns
    -------
    DrifterOptimum
        Its variables all the keys, its history every search's designs (each record with its
        integer values), its evaluations their sum, its baseline the config's own design.

    Raises
    ------
    ValueError
        Too many integer designs; the config's own design without an operating point or, unless
        ``any_start``, infeasible.
    """
    t0 = time.perf_counter()
    integers = [k for k in spec if k in INTEGER_KEYS]
    others = {k: b for k, b in vary.items() if k not in integers}
    designs = integer_designs(spec, integers)
    runs, skipped = [], []
    for i, design in enumerate(designs):
        if not others:  # each integer design one fresh orbit
            t = time.perf_counter()
            try:
                rec = fresh(design)
            except ValueError as exc:
                rec = failed_record(exc, time.perf_counter() - t)
            rec = _with(rec, design)
            if i == 0:
                check_start(rec, any_start)
            runs.append((design, rec))
            continue
        try:
            res = search(design, others, "any" if i or any_start else "feasible", _cache_of(cache, design))
        except ValueError as exc:
            if i == 0:  # (the config's own: its refusal is the user's)
                raise
            skipped.append(f"{_named(design)} ({' '.join(str(exc).split())})")
            continue
        runs.append((design, res))
    fkey = objectives(kind)[objective].key
    if not others:
        history = [rec for _, rec in runs]
        ok = [r for r in history if r.get("feasible")]
        best = max(ok, key=lambda r: r["objectives"][fkey]) if ok else max(
            (r for r in history if r.get("ok")), key=least_margin)
        message = f"every integer design evaluated ({len(history)}), each by a fresh orbit: the best kept"
        return DrifterOptimum(objective=objective, vary=_bounds(spec), baseline=history[0], optimum=best,
                              evaluations=len(history), cached=0, seconds=time.perf_counter() - t0,
                              history=history, message=message, config=with_values(cfg, best["changes"]),
                              kind=kind)
    feasible = [(d, r) for d, r in runs if r.optimum.get("feasible")]
    def objective_of(run) -> float:
        _, result = run
        return result.optimum["objectives"][fkey]

    design, best = max(feasible, key=objective_of) if feasible else runs[0]
    history = [_with(rec, d) for d, r in runs for rec in r.history]
    message = (f"{len(runs)} integer designs searched over the other keys, the best at {_named(design)} "
               f"(its certificate over the other keys there): {best.message}")
    if skipped:
        message += f"; left out, no operating point at their start: {'; '.join(skipped)}"
    own, first = runs[0]
    return DrifterOptimum(objective=objective, vary=_bounds(spec), baseline=_with(first.baseline, own),
                          optimum=_with(best.optimum, design),
                          evaluations=sum(r.evaluations for _, r in runs),
                          cached=sum(r.cached for _, r in runs), seconds=time.perf_counter() - t0,
                          history=history, message=message, config=best.config,
                          gradients=sum(r.gradients for _, r in runs),
                          cached_gradients=sum(r.cached_gradients for _, r in runs),
                          certificate=best.certificate, found=best.found, kind=kind)


def _bounds(spec: dict) -> dict:
    """The result's variables: each key's bounds and unit, in the order given."""
    return {k: {"low": b["low"], "high": b["high"], "unit": b["unit"]} for k, b in spec.items()}
