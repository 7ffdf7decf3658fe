r"""A multistart search over a drifter's design: a space-filling sample of the bounds, evaluated
together, then local searches from its best feasible designs.

:func:`~impactbar.physical.optimize_drifter` with ``method="multistart"`` draws a scrambled Sobol
sample (:class:`scipy.stats.qmc.Sobol`, seeded) of the variables scaled to :math:`[0, 1]`; its designs
are computed together by :func:`~impactbar.physical.optimize_population.record_map` (in this process
or on a dask cluster), each by a fresh ``orbit()``, as the population search's are. COBYLA then starts
from each of the ``local_starts`` best feasible designs of the sample (the objective largest; the
start's own design is the baseline, not a local start), each with an equal share of the budget left;
its designs are evaluated one after another, each continued from the nearest design evaluated with an
orbit. The reported optimum is the best feasible design evaluated, as for the other methods; each
local search's best design is listed in :attr:`~impactbar.physical.optimize_drifter.DrifterOptimum.found`.
"""

from __future__ import annotations

import numpy as np

from .optimize_population import _is_client, compute_new

__all__ = ["check_multistart", "found_table", "multistart_search", "sobol_sample"]


def check_multistart(workers, sample, local_starts, seed, max_evaluations: int, n_variables: int) -> int:
    """The multistart search's arguments checked; each local search's budget of designs.

    Parameters
    ----------
    workers : None, int or distributed.Client
        Where the sample is evaluated (:func:`~impactbar.physical.optimize_population.record_map`).
    sample : int
        The sample's designs: a power of two, at least 2 (a Sobol sample's balance needs it).
    local_starts : int
        The local searches, in ``[1, sample]``.
    seed : int
        The sample's scrambling seed (at least 0).
    max_evaluations : int
        The most designs evaluated: the sample's and at least ``n_variables + 2`` for each local search.
    n_variables : int
        The variables' number.

    Returns
    -------
    int
        ``(max_evaluations - sample) // local_starts``: each local search's most designs.

    Raises
    ------
    ValueError
        The first argument out of its range: its name and the range in one line.

    Examples
    --------
    >>> check_multistart(None, 8, 2, 0, 20, 2)
    6
    >>> check_multistart(None, 6, 2, 0, 20, 2)
    Traceback (most recent call last):
    ...
    ValueError: sample must be a power of two >= 2 (a Sobol sample's designs); got 6
    """
    if workers is not None and not _is_client(workers) and not (
            isinstance(workers, int) and not isinstance(workers, bool) and workers >= 1):
        raise ValueError(f"workers must be None, an integer >= 1 or a distributed.Client; got {workers!r}")
    if not (isinstance(sample, int) and not isinstance(sample, bool) and sample >= 2
            and sample & (sample - 1) == 0):
        raise ValueError(f"sample must be a power of two >= 2 (a Sobol sample's designs); got {sample!r}")
    if not (isinstance(local_starts, int) and not isinstance(local_starts, bool)
            and 1 <= local_starts <= sample):
        raise ValueError(f"local_starts must be an integer in [1, sample] = [1, {sample}]; got "
                         f"{local_starts!r}")
    if not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise ValueError(f"seed must be an integer >= 0; got {seed!r}")
    least = sample + local_starts * (n_variables + 2)
    if max_evaluations < least:
        raise ValueError(f"max_evaluations must be at least the sample and {n_variables + 2} designs per "
                         f"local search ({least} = {sample} + {local_starts} x {n_variables + 2}) with "
                         f"method='multistart'; got {max_evaluations}")
    return (max_evaluations - sample) // local_starts


def sobol_sample(n_variables: int, sample: int, seed: int) -> np.ndarray:
    """A scrambled Sobol sample of the unit cube.

    Parameters
    ----------
    n_variables : int
        The cube's dimension (at least 1).
    sample : int
        The points: a power of two.
    seed : int
        The scrambling's seed: the same seed, the same points.

    Returns
    -------
    numpy.ndarray, shape (sample, n_variables)
        In ``[0, 1)``.

    Examples
    --------
    >>> u = sobol_sample(2, 8, 0)
    >>> u.shape, bool(np.all((0.0 <= u) & (u < 1.0)))
    ((8, 2), True)
    >>> # balanced: each eighth of each axis holds one point
    >>> [sorted(np.floor(u[:, j] * 8).astype(int).tolist()) == list(range(8)) for j in range(2)]
    [True, True]
    """
    from scipy.stats import qmc

    return qmc.Sobol(d=n_variables, scramble=True, seed=seed).random_base2(int(sample).bit_length() - 1)


def multistart_search(evaluate, design_of, stored, record, common: dict, local, fkey: str, *, sample: int,
                      local_starts: int, seed: int, run, n_variables: int) -> tuple:
    """A Sobol sample of the scaled variables computed together, then ``local`` from its best feasible
    designs.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(u)``: a design's record (a stored one read); ``evaluate(u, rec)`` stores a new
        design's record computed elsewhere.
    design_of : callable
        ``design_of(u)``: ``(id, changes)``, the design's key and its config changes.
    stored : container
        The ids of the designs already evaluated (the run's, the cache's).
    record : callable
        A module-level function, ``record(changes, **common)``: the design's record.
    common : dict
        Keyword arguments of ``record`` shared by all designs.
    local : callable
        ``local(u)``: a local search (:class:`scipy.optimize.OptimizeResult`) from ``u``.
    fkey : str
        The objective's figure in a record's ``objectives`` (maximised).
    sample, local_starts, seed : int
        The sample's designs (a power of two), the local searches, the sample's seed.
    run : callable
        ``run(record, items, **common)``: the sample's records, computed together
        (:func:`~impactbar.physical.optimize_population.record_map`'s map, in this process or on a
        cluster's workers).
    n_variables : int
        The variables' number.

    Returns
    -------
    result : scipy.optimize.OptimizeResult
        The local search whose best design is best (without ``x`` where none ran), its message
        prefixed by the sample's.
    found : list of dict
        Each local search's ``start`` and ``values`` (dotted key to SI), ``objective``, ``feasible``,
        ``evaluations`` (COBYLA's) and ``message``, best first.
    """
    from scipy.optimize import OptimizeResult

    points = sobol_sample(n_variables, sample, seed)
    compute_new(run, points, design_of, stored, evaluate, record, common)
    recs = [evaluate(u) for u in points]
    ranked = sorted((i for i, r in enumerate(recs) if r.get("feasible")),
                    key=lambda i: recs[i]["objectives"][fkey], reverse=True)[:local_starts]
    found, results = [], []
    for i in ranked:
        res = local(points[i])
        best = evaluate(res.x)
        results.append(res)
        found.append({"start": recs[i]["values"], "values": best["values"],
                      "objective": best["objectives"][fkey] if best["ok"] else None,
                      "feasible": bool(best.get("feasible")), "evaluations": int(res.nfev),
                      "message": str(res.message)})
    order = sorted(range(len(found)), reverse=True, key=lambda j: (
        found[j]["feasible"], -np.inf if found[j]["objective"] is None else found[j]["objective"]))
    failed = sum(not r["ok"] for r in recs)
    head = f"{sample} sample designs ({failed} without an operating point), {len(found)} local search(es)"
    if not order:
        return OptimizeResult(message=f"{head}: no feasible design in the sample", nfev=0), []
    res = results[order[0]]
    res.message = f"{head}; the best's COBYLA: {res.message}"
    return res, [found[j] for j in order]


def found_table(found: list, vary: dict, fkey: str) -> str:
    """The local searches' best designs, one line each, best first.

    Parameters
    ----------
    found : list of dict
        :func:`multistart_search`'s.
    vary : dict
        Dotted key to ``low``, ``high`` and ``unit`` (:attr:`DrifterOptimum.vary
        <impactbar.physical.optimize_drifter.DrifterOptimum>`).
    fkey : str
        The objective's figure (its name carries its unit).

    Returns
    -------
    str

    Examples
    --------
    >>> print(found_table([{"start": {"x": 0.02}, "values": {"x": 0.021}, "objective": 13.0,
    ...                     "feasible": True, "evaluations": 8, "message": ""}],
    ...                   {"x": {"low": 0.02, "high": 0.023, "unit": "m"}}, "impact_power_kW"))
    local search 1 (8 designs) from x 20 mm: x 21 mm; impact_power_kW 13, feasible
    """
    from .optimize_failures import design_text

    return "\n".join(f"local search {i} ({f['evaluations']} designs) from {design_text(f['start'], vary)}: "
                     f"{design_text(f['values'], vary)}; {fkey} "
                     + ("none" if f["objective"] is None else f"{f['objective']:.5g}")
                     + (", feasible" if f["feasible"] else ", infeasible")
                     for i, f in enumerate(found, 1))
