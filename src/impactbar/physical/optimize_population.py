r"""A population search over a drifter's design (differential evolution) whose designs of each
generation are evaluated in parallel, on a dask cluster or one after another in this process.

:func:`~impactbar.physical.optimize_drifter` with ``method="differential_evolution"`` runs
:func:`scipy.optimize.differential_evolution` over the variables scaled to :math:`[0, 1]`, the start
one member of the first population, with ``updating="deferred"``: each generation's trial designs
are known before any is evaluated, and :func:`population_search`'s map computes their records
together. Each record is a fresh operating point (the default chain of ``orbit()``, no guess), by a
module-level function the workers unpickle, so a run on a cluster and one in this process give the
same records bit for bit and the search the same path. scipy would evaluate a
``NonlinearConstraint`` serially in the driver, so the constraints enter the objective instead: the
objective over the start's, negated, plus :data:`PENALTY` times the sum of the constraints' scaled
margins missed (a design without an operating point scores :data:`FAILED`). The reported optimum is
the best feasible design evaluated, as for the other methods.
"""

from __future__ import annotations

import contextlib
import math

import numpy as np

__all__ = ["PENALTY", "FAILED", "check_population", "compute_new", "penalised", "population_search",
           "record_map"]

#: The weight of the constraints' scaled margins missed, added to the objective over the start's.
PENALTY = 10.0
#: The score of a design without an operating point (or a non-finite objective).
FAILED = 1.0e3


def check_population(workers, popsize, seed, max_evaluations: int, n_variables: int) -> int:
    """The population search's arguments checked; its generations after the first.

    Parameters
    ----------
    workers : None, int or distributed.Client
        ``None``: this process; an integer (at least 1): a local cluster of that many processes; a client.
    popsize : int
        Members per variable (at least 2; the population ``max(5, popsize * n_variables)``).
    seed : int
        The search's random seed (at least 0).
    max_evaluations : int
        The most designs evaluated: at least two generations' (``2 * population``).
    n_variables : int
        The variables' number.

    Returns
    -------
    int
        ``maxiter`` for :func:`scipy.optimize.differential_evolution`: the generations after the
        first that ``max_evaluations`` allows.

    Raises
    ------
    ValueError
        Each argument out of its range, in one line.

    Examples
    --------
    >>> check_population(None, 3, 0, 18, 2)
    2
    >>> check_population(0, 3, 0, 18, 2)
    Traceback (most recent call last):
    ...
    ValueError: workers must be None, an integer >= 1 or a distributed.Client; got 0
    """
    if workers is not None and not _is_client(workers) and not (
            isinstance(workers, int) and not isinstance(workers, bool) and workers >= 1):
        raise ValueError(f"workers must be None, an integer >= 1 or a distributed.Client; got {workers!r}")
    if not (isinstance(popsize, int) and not isinstance(popsize, bool) and popsize >= 2):
        raise ValueError(f"popsize must be an integer >= 2 (members per variable); got {popsize!r}")
    if not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise ValueError(f"seed must be an integer >= 0; got {seed!r}")
    members = max(5, popsize * n_variables)
    if max_evaluations < 2 * members:
        raise ValueError(f"max_evaluations must be at least two generations of the population "
                         f"({2 * members} = 2 x {members}) with method='differential_evolution'; got "
                         f"{max_evaluations}")
    return max_evaluations // members - 1


def _is_client(workers) -> bool:
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - distributed is a dependency
        return False
    return isinstance(workers, Client)


def penalised(rec: dict, fkey: str, ref: float) -> float:
    r"""A design's score for the population search (minimised): :math:`-f / f_0 + w \sum_i
    \max(0, -g_i)`, :math:`g_i` the constraints' scaled margins, :math:`w` :data:`PENALTY`.

    Parameters
    ----------
    rec : dict
        The design's record (:func:`~impactbar.physical.optimize_drifter.evaluate_design`'s).
    fkey : str
        The objective's figure in ``rec["objectives"]``.
    ref : float
        The start's objective (its unit), ``!= 0``.

    Returns
    -------
    float
        :data:`FAILED` for a design without an operating point or a non-finite objective.

    Examples
    --------
    >>> rec = {"ok": True, "objectives": {"p": 2.0}, "constraints": {"c": {"scaled": -0.1}}}
    >>> round(penalised(rec, "p", 1.0), 12)
    -1.0
    """
    if not rec.get("ok"):
        return FAILED
    value = rec["objectives"][fkey]
    if not math.isfinite(value):
        return FAILED
    miss = sum(max(0.0, -c["scaled"]) for c in rec["constraints"].values())
    return -value / ref + PENALTY * miss


@contextlib.contextmanager
def record_map(workers):
    """A map of a module-level function over designs: ``run(fn, items, **common)`` is the list of
    ``fn(item, **common)``, in the order of ``items``.

    Parameters
    ----------
    workers : None, int or distributed.Client
        ``None``: in this process, one after another; an integer: a local cluster of that many
        worker processes (one thread each, on the loopback interface, no dashboard), started here and
        closed on exit; a client: its cluster (left open).

    Yields
    ------
    callable
    """
    if workers is None:
        yield lambda fn, items, **common: [fn(item, **common) for item in items]
        return
    if _is_client(workers):
        yield _client_map(workers)
        return
    import logging

    import dask
    from distributed import Client, LocalCluster

    with (dask.config.set({"distributed.scheduler.http.routes": [], "distributed.worker.http.routes": []}),
          LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                       dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": False},
                       worker_dashboard_address=None, silence_logs=logging.ERROR) as cluster,
          Client(cluster) as client):
        yield _client_map(client)


def _client_map(client):
    def run(fn, items, **common):
        items = list(items)
        if not items:
            return []
        # the shared arguments sent to each worker once, not with each task (an orbit is megabytes)
        shared = dict(zip(common, client.scatter(list(common.values()), broadcast=True, hash=False),
                          strict=True)) if common else {}
        return client.gather(client.map(fn, items, pure=False, **shared))

    return run


def compute_new(run, points, design_of, stored, add, record, common: dict) -> int:
    """The records of the designs among ``points`` not yet ``stored``, computed together by ``run``
    (:func:`record_map`'s) and stored by ``add(u, rec)`` in the order of ``points``; a design twice
    among them computed once.

    Parameters
    ----------
    run : callable
        ``run(record, items, **common)``: the records of ``items``.
    points : iterable of numpy.ndarray, each of shape (n,)
        The designs' scaled variables.
    design_of, stored, add, record, common
        As :func:`population_search`'s.

    Returns
    -------
    int
        The designs computed.
    """
    todo = {}
    for u in points:
        u = np.asarray(u, dtype=float)
        rid, changes = design_of(u)
        if rid not in stored and rid not in todo:
            todo[rid] = (u, changes)
    for (u, _), rec in zip(todo.values(), run(record, [c for _, c in todo.values()], **common), strict=True):
        add(u, rec)
    return len(todo)


def population_search(score, design_of, stored, add, record, common: dict, u0, *, popsize: int,
                      maxiter: int, seed: int, workers, atol: float = 0.0):
    """Differential evolution over the scaled variables, each generation's new designs computed
    together by ``record`` (on ``workers``), then stored by ``add`` before they are scored.

    Parameters
    ----------
    score : callable
        ``score(u)``: a stored design's score (minimised), ``u`` the scaled variables, shape ``(n,)``.
    design_of : callable
        ``design_of(u)``: ``(id, changes)``, the design's key and its config changes.
    stored : container
        The ids of the designs already evaluated (the run's, the cache's).
    add : callable
        ``add(u, rec)``: stores a new design's record.
    record : callable
        A module-level function, ``record(changes, **common)``: the design's record.
    common : dict
        Keyword arguments of ``record`` shared by all designs (the config, its folder, the limits).
    u0 : numpy.ndarray, shape (n,)
        The start, a member of the first population.
    popsize, maxiter, seed : int
        :func:`scipy.optimize.differential_evolution`'s.
    atol : float
        The search stops once the population's scores spread (standard deviation) below it, or after
        ``maxiter`` generations (scipy's relative ``tol`` is 0: the scores, the objective over the
        start's near -1, would spread below its default within a generation or two).
    workers : None, int or distributed.Client
        Where the records are computed (:func:`record_map`).

    Returns
    -------
    scipy.optimize.OptimizeResult
    """
    from scipy.optimize import differential_evolution

    with record_map(workers) as run:
        def generation(func, population):
            population = [np.asarray(u, dtype=float) for u in population]
            compute_new(run, population, design_of, stored, add, record, common)
            return [func(u) for u in population]

        return differential_evolution(score, [(0.0, 1.0)] * len(u0), popsize=popsize, maxiter=maxiter,
                                      seed=seed, x0=np.asarray(u0, dtype=float), polish=False,
                                      updating="deferred", workers=generation, init="latinhypercube",
                                      tol=0.0, atol=atol)
