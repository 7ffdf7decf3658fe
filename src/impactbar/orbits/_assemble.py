"""The periodic orbit at a converged solution of the segment problem of
:mod:`impactbar.orbits.multi_impact` (theory §5, §7): its multipliers (the monodromy's eigenvalues),
the law's record of each contact, and its admissibility."""

from __future__ import annotations

import math

import numpy as np

from .._shared.status import Admissibility
from ..laws.abilities import BlowRecords
from .admissibility import _admissibility, _window_departure
from .orbit import PeriodicOrbit
from .stability import sort_multipliers, stable_verdict

TWO_PI = 2.0 * math.pi


def _sorted_multipliers(P):
    return sort_multipliers(np.linalg.eigvals(P))


def _build(problem, u, *, admissibility: bool = True, evaluated=None) -> PeriodicOrbit:
    """The orbit at a converged solution ``u`` of the segment problem (``evaluated``: the problem's
    evaluation at ``u`` with its Jacobian, where the caller has it)."""
    model, load = problem.model, problem.load
    M, m = problem.M, problem.m
    _, _, info = problem.evaluate(u) if evaluated is None else evaluated
    t, _ = problem.split(u)
    c = problem.c
    v_imp = info["y_minus"][:, M:] @ c
    mu = _sorted_multipliers(problem.monodromy(info["maps"]))
    if not np.all(np.isfinite(mu)):
        mu = np.full(2 * M, np.inf + 0j)
    Tw = problem.T
    arrivals = np.append(t[1:], t[0] + TWO_PI * problem.n)  # flight j ends at arrivals[j]
    contacts, blows = None, model.law.ability(BlowRecords)
    if Tw > 0.0 and blows is not None and np.all(v_imp > 0.0) and admissibility:
        contacts = tuple(blows.blow(model, load, float(ta), ym)  # contact j starts flight j
                         for ta, ym in zip(t, np.roll(info["y_minus"], 1, axis=0), strict=True))
    statuses, clear, cerr = [], -math.inf, 0.0
    if admissibility:
        for j in range(m):
            T = arrivals[j] - t[j] - Tw
            y0 = info["y_plus"][j]
            at_rest = None
            if Tw > 0.0:  # the wave law: the end leaves the rod end when the window closes
                v_dep = float(c @ y0[M:])
                at_rest = abs(v_dep) <= 1e-12 * max(abs(float(v_imp[j - 1])), load.sup_abs, 1e-300)
            st, cl, ce = _admissibility(model, load, float(t[j] + Tw), y0, float(v_imp[j]),
                                        horizon=float(T), at_rest=at_rest)
            if Tw > 0.0:
                st = _window_departure(st, at_rest, v_dep,
                                       contacts is not None and bool(contacts[j].separations))
            statuses.append(st)
            if cl > clear:
                clear, cerr = cl, ce
        status = min(statuses, key=lambda a: a.rank)
    else:
        status = Admissibility.UNCHECKED
    admissible = status == Admissibility.ADMISSIBLE
    return PeriodicOrbit(
        model=model, load=load, impacts=m, periods=problem.n,
        impact_times=t.copy(), phases=np.mod(t, TWO_PI), impact_velocities=np.roll(v_imp, 1),
        admissible=admissible, admissibility=status, clearance=float(clear),
        clearance_error=float(cerr), multipliers=mu,
        stable=stable_verdict(admissible, mu),
        states_after_impact=info["y_plus"], states_before_impact=np.roll(info["y_minus"], 1, axis=0),
        contacts=contacts,
    )
