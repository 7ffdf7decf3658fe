r"""A first-order (KKT) certificate of a design reported by
:func:`~impactbar.physical.optimize_drifter`: whether it is a local optimum, or where the search stopped.

The search maximises the objective :math:`f(u)` over the variables scaled to :math:`u \in [0, 1]^n` by
their bounds, under the constraints' scaled margins :math:`c_i(u) \ge 0`. At a local optimum (a regular
point) there are multipliers :math:`\lambda_i \ge 0` of the active constraints and :math:`\mu_j \ge 0`
of the active bounds with

.. math:: -\nabla f = \sum_i \lambda_i \nabla c_i \pm \sum_j \mu_j e_j ,

(:math:`+e_j` for a variable at its lower bound, :math:`-e_j` at its upper one). The multipliers are
the non-negative least-squares solution (:func:`scipy.optimize.nnls`) on the active gradients; the
residual of that fit over :math:`\lVert\nabla f\rVert` is the KKT residual, zero at a stationary
point, 1 where no active gradient helps (no constraint and no bound active: the projected gradient is
the whole gradient).

A search resolves the design only to its last step :math:`\rho` in the scaled variables (COBYLA's
final trust radius, ``tol``): a constraint whose margin is within what one such step changes,
:math:`c_i(u) \le \rho\,\lVert\nabla c_i\rVert`, is one the search cannot tell from active, and
counts as active (as does a variable within :math:`\rho` of a bound), besides the fixed band
:data:`ACTIVE_TOLERANCE`.

A search stopped next to a border where a design of it within twice its last step has no orbit, or
where the figures of one with an orbit jump: the objective or a scaled margin departs from the
gradient's prediction :math:`\nabla h \cdot \delta` by more than :data:`JUMP_RATIO` times the
most the gradient lets it change over that step, :math:`\lVert\nabla h\rVert\,\lVert\delta\rVert`
(a smooth figure would need its gradient to change by several times its own size within the step:
another branch of the orbit, the designs beyond it missing a constraint the gradient says they meet).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["KKT_TOLERANCE", "ACTIVE_TOLERANCE", "DIFFERENCE_STEP", "JUMP_RATIO", "JUMP_FLOOR",
           "OptimalityCertificate", "certify", "central_gradients", "stopped_at_budget", "certify_search"]

#: The largest relative KKT residual of a design certified ``"converged"``: the search's own last step
#: (COBYLA's ``tol``, 2e-3 by default, in the scaled variables) leaves the gradient's projection some
#: 1e-3 of its size on a smooth problem; 1e-2 leaves a factor of ten for it.
KKT_TOLERANCE = 1e-2

#: A constraint is active where its scaled margin (the margin over the limit, or the fixed scale where
#: the limit is 0) is at most this, or at most the search's resolution times its gradient's norm
#: where that is larger (:func:`certify`); a variable sits at a bound within this of 0 or 1 (scaled),
#: or within the resolution.
ACTIVE_TOLERANCE = 1e-4

#: The step of the central differences in the scaled variables (the truncation error of order
#: ``step ** 2``; one-sided, of order ``step``, at a bound).
DIFFERENCE_STEP = 1e-4

#: A figure of a neighbouring design (within the search's reach) jumps where it departs from its
#: gradient's prediction by more than this times the gradient's norm times the distance (module
#: docstring).
JUMP_RATIO = 3.0

#: ... and by more than this times the larger of the two figures' sizes: far above the orbits'
#: accuracy (a continued and a fresh orbit of one design differ by some 1e-9 relative).
JUMP_FLOOR = 1e-6

_VERDICTS = ("converged", "stopped at a budget", "stopped at a border", "not stationary", "infeasible")


@dataclass(frozen=True)
class OptimalityCertificate:
    r"""The first-order (KKT) certificate of a reported design.

    Attributes
    ----------
    verdict : str
        ``"converged"`` (the KKT residual below :data:`KKT_TOLERANCE`, the multipliers non-negative
        by construction), else ``"stopped at a budget"`` (the search ran out of evaluations or
        iterations), ``"stopped at a border"`` (a design of the search next to it had no orbit, or
        its figures jump: ``border`` says which), or ``"not stationary"``; ``"infeasible"`` where
        the design misses a constraint (``record["feasible"]`` false: a search that found no
        feasible design), whatever its residual.
    residual : float
        The KKT residual: the projected gradient's norm over the objective's gradient's (module
        docstring).
    objective_gradient : list of float, shape (n,)
        The objective's gradient in the scaled variables (the objective's unit).
    constraint_gradients : dict
        Constraint name to its scaled margin's gradient, a list of shape (n,).
    active : list of str
        The constraints within :data:`ACTIVE_TOLERANCE` of their limit, or within the search's
        resolution times their gradient's norm (:func:`certify`).
    bounds : dict
        Variable (dotted key) at a bound (within :data:`ACTIVE_TOLERANCE` or the resolution) to
        ``"low"`` or ``"high"``.
    multipliers : dict
        Name (an active constraint, or ``"<key> low"``/``"<key> high"`` of a bound) to its Lagrange
        multiplier (the objective's unit per unit scaled margin), each :math:`\ge 0`.
    method : str
        How the gradients were computed.
    budget : bool
        Whether the search stopped at its budget of evaluations or iterations.
    border : str
        The error of the nearest design without an orbit within twice the search's last step, else
        the largest jump of a figure to a design with one there (:data:`JUMP_RATIO`; ``""`` where
        neither).
    tolerance : float
        :data:`KKT_TOLERANCE`.
    """

    verdict: str
    residual: float
    objective_gradient: list
    constraint_gradients: dict
    active: list
    bounds: dict
    multipliers: dict
    method: str
    budget: bool = False
    border: str = ""
    tolerance: float = KKT_TOLERANCE

    def __post_init__(self):
        if self.verdict not in _VERDICTS:
            raise ValueError(f"verdict must be one of {', '.join(_VERDICTS)}; got {self.verdict!r}")

    @property
    def converged(self) -> bool:
        """Whether the design is a certified (first-order) local optimum."""
        return self.verdict == "converged"

    def to_dict(self) -> dict:
        """The certificate as plain data (JSON-ready)."""
        return asdict(self)

    def __str__(self) -> str:
        active = ", ".join(list(self.active) + [f"{k} at its {s} bound" for k, s in self.bounds.items()])
        lam = ", ".join(f"{k} {v:.3g}" for k, v in self.multipliers.items())
        text = (f"{self.verdict}: KKT residual {self.residual:.2g} (tolerance {self.tolerance:g}); active: "
                f"{active or 'none'}" + (f"; multipliers {lam}" if lam else ""))
        beyond = "figures jump" if self.border.startswith(_JUMP) else "no orbit"
        return text + (f"; {beyond} beyond: {self.border}" if self.border else "")


def stopped_at_budget(result) -> bool:
    """Whether a :func:`scipy.optimize.minimize` (or ``differential_evolution``) result stopped at its
    budget: its message says so (COBYLA's ``MAXFUN``, SLSQP's iteration limit)."""
    text = str(getattr(result, "message", "")).lower()
    return any(w in text for w in ("maxfun", "maximum number", "iteration limit", "limit reached"))


def central_gradients(point, u, step: float = DIFFERENCE_STEP) -> tuple:
    """The gradients of a design's figures by central differences of fresh evaluations in the scaled
    variables (one-sided at a bound).

    Parameters
    ----------
    point : callable
        ``u -> [objective, margin_1, ...]`` (the scaled margins), an array of shape (1 + m,).
    u : array_like, shape (n,)
        The design in the scaled variables, in ``[0, 1]``.
    step : float
        The difference step in the scaled variables, in ``(0, 0.1]``.

    Returns
    -------
    objective_gradient : numpy.ndarray, shape (n,)
    constraint_gradients : numpy.ndarray, shape (m, n)
    method : str

    Examples
    --------
    >>> g, G, how = central_gradients(lambda u: np.array([u[0] ** 2 + u[1], 1 - u[0]]), [0.5, 0.5])
    >>> np.round(g, 8).tolist(), np.round(G, 8).tolist()
    ([1.0, 1.0], [[-1.0, 0.0]])
    """
    if not (isinstance(step, float) and 0.0 < step <= 0.1):
        raise ValueError(f"step must be a number in (0, 0.1] (scaled variables); got {step!r}")
    u = np.asarray(u, dtype=float)
    cols = []
    for j in range(u.size):
        up, down = u.copy(), u.copy()
        up[j], down[j] = min(u[j] + step, 1.0), max(u[j] - step, 0.0)
        cols.append((np.asarray(point(up), dtype=float) - np.asarray(point(down), dtype=float))
                    / (up[j] - down[j]))
    objective, *constraints = np.array(cols).T
    method = (f"central differences of fresh evaluations, step {step:g} in the scaled variables (error "
              "O(step**2); one-sided O(step) at a bound)")
    return objective, np.array(constraints).reshape(-1, u.size), method


_JUMP = "a jump: "


def _jump(u, own, gradients, neighbours, names: list, reach: float) -> str:
    """The largest jump of a figure (``own``, shape (1 + m,): the objective, the scaled margins, with
    their ``gradients``, shape (1 + m, n)) to a design of ``neighbours`` ((scaled variables, figures))
    within ``reach``: text naming it, ``""`` where none (module docstring)."""
    worst, text = 0.0, ""
    slopes = JUMP_RATIO * np.linalg.norm(gradients, axis=1)  # (each figure's, the same for every neighbour)
    for v, figures in neighbours:
        delta = np.asarray(v, dtype=float) - u
        d = float(np.linalg.norm(delta))
        if not 0.0 < d <= reach:
            continue
        figures = np.asarray(figures, dtype=float)
        change = figures - own
        predicted = gradients @ delta
        off = np.abs(change - predicted)
        bound = np.maximum(slopes * d, JUMP_FLOOR * np.maximum(np.abs(own), np.abs(figures)))
        for i in np.flatnonzero(off > bound):
            ratio = off[i] / bound[i]
            if ratio > worst:
                worst = ratio
                text = (f"{_JUMP}{names[i]} changes by {change[i]:.3g} over {d:.3g} (scaled) where its "
                        f"gradient predicts {predicted[i]:.3g}")
    return text


def certify(objective_gradient, constraint_gradients, record: dict, u, keys, *, method: str,
            budget: bool = False, failed=(), reach: float = 0.0,
            resolution: float = 0.0, neighbours=(), objective: float | None = None) -> OptimalityCertificate:
    """The first-order certificate of a design (module docstring).

    Parameters
    ----------
    objective_gradient : array_like, shape (n,)
        The objective's gradient in the scaled variables (maximised).
    constraint_gradients : array_like, shape (m, n)
        The scaled margins' gradients, in the order of ``record["constraints"]``.
    record : dict
        The design's record (:func:`~impactbar.physical.optimize_drifter.evaluate_design`).
    u : array_like, shape (n,)
        The design in the scaled variables.
    keys : list of str
        The variables' dotted keys.
    method : str
        How the gradients were computed.
    budget : bool
        Whether the search stopped at its budget (:func:`stopped_at_budget`).
    failed : sequence of (array_like, str)
        The designs of the search without an orbit: scaled variables and error.
    reach : float
        How near (scaled, Euclidean) a failed design, or one whose figures jump, counts as a border
        next to this one.
    resolution : float
        The search's last step in the scaled variables (not negative; 0: the fixed band alone): a
        constraint whose scaled margin is at most ``resolution`` times its gradient's norm is active,
        and a variable within ``resolution`` of a bound at it (module docstring).
    neighbours : sequence of (array_like, array_like)
        The designs of the search with an orbit: scaled variables, shape (n,), and figures, shape
        (1 + m,): the objective and the scaled margins in the order of ``record["constraints"]``;
        one within ``reach`` whose figure jumps (:data:`JUMP_RATIO`) marks a border.
    objective : float, optional
        The design's objective (with ``neighbours``, where they are given).

    Returns
    -------
    OptimalityCertificate

    Raises
    ------
    ValueError
        ``resolution`` negative or not finite, a gradient not finite, or ``neighbours`` without
        ``objective``.

    Examples
    --------
    >>> rec = {"constraints": {"mass": {"scaled": 0.0}}}
    >>> c = certify([1.0, 1.0], [[-1.0, -1.0]], rec, [0.5, 0.5], ["a", "b"], method="exact")
    >>> c.verdict, c.active, round(c.multipliers["mass"], 12), c.residual < 1e-12  # (its least squares')
    ('converged', ['mass'], 1.0, True)
    """
    g = np.asarray(objective_gradient, dtype=float)
    names = list(record["constraints"])
    G = np.asarray(constraint_gradients, dtype=float).reshape(len(names), g.size)
    u = np.asarray(u, dtype=float)
    if not (isinstance(resolution, int | float) and math.isfinite(resolution) and resolution >= 0.0):
        raise ValueError(f"resolution must be a finite number >= 0 (scaled variables); got {resolution!r}")
    near = max(ACTIVE_TOLERANCE, float(resolution))
    active = [n for i, n in enumerate(names) if record["constraints"][n]["scaled"] <= max(
        ACTIVE_TOLERANCE, resolution * float(np.linalg.norm(G[i])))]
    bounds = {k: ("low" if x <= near else "high") for k, x in zip(keys, u, strict=True)
              if x <= near or x >= 1.0 - near}
    cols, labels = [G[names.index(n)] for n in active], list(active)
    for k, side in bounds.items():
        cols.append(np.eye(g.size)[keys.index(k)] * (1.0 if side == "low" else -1.0))
        labels.append(f"{k} {side}")
    norm = float(np.linalg.norm(g))
    if not (math.isfinite(norm) and np.all(np.isfinite(G))):
        raise ValueError("objective_gradient, constraint_gradients: must be finite")
    if cols and norm > 0.0:
        from scipy.optimize import nnls  # scipy.optimize loads on first use, not on import

        lam, rnorm = nnls(np.array(cols).T, -g)
    else:
        lam, rnorm = np.zeros(len(cols)), norm
    residual = rnorm / norm if norm > 0.0 else 0.0
    distance, error = min(((float(np.linalg.norm(np.asarray(v) - u)), e) for v, e in failed),
                          default=(math.inf, ""))
    border = error if distance <= reach else ""
    if not border and len(neighbours):
        if objective is None:
            raise ValueError("objective: the design's objective must be given with neighbours")
        own = np.array([objective, *(record["constraints"][n]["scaled"] for n in names)], dtype=float)
        border = _jump(u, own, np.vstack([g, G]), neighbours, ["the objective", *names], reach)
    verdict = ("infeasible" if not record.get("feasible", True) else
               "converged" if residual <= KKT_TOLERANCE else "stopped at a budget" if budget
               else "stopped at a border" if border else "not stationary")
    return OptimalityCertificate(verdict=verdict, residual=float(residual), objective_gradient=g.tolist(),
                                 constraint_gradients={n: G[i].tolist() for i, n in enumerate(names)},
                                 active=active, bounds=bounds,
                                 multipliers={n: float(x) for n, x in zip(labels, lam, strict=True)},
                                 method=method, budget=budget, border=border)


def certify_search(record: dict, history: list, keys: list, scaling: tuple, result, tol: float, fkey: str,
                   blow, design_gradient, resolution: float | None = None) -> OptimalityCertificate:
    """The certificate of :func:`~impactbar.physical.optimize_drifter`'s reported design ``record``.

    Parameters
    ----------
    record : dict
        The reported design's fresh record (``values`` in SI by dotted key).
    history : list of dict
        The search's designs (those without an orbit, ``ok`` false, mark a border, as do those with
        one whose figures jump: :func:`certify`'s ``neighbours``).
    keys : list of str
        The variables.
    scaling : tuple of numpy.ndarray
        The bounds' lows and spans (SI), each of shape (n,).
    result : scipy.optimize.OptimizeResult
        The search's (:func:`stopped_at_budget`).
    tol : float
        The search's last step (scaled): a failed design within twice it is a border.
    fkey : str
        The objective's figure.
    blow : callable or None
        ``u -> record`` of a fresh evaluation in the circuit's ideal limit: the gradients by
        :func:`central_gradients`; ``None``: by ``design_gradient``.
    design_gradient : callable
        ``() -> (objective_gradient, constraint_gradients)`` of the orbit's implicit-function-theorem
        sensitivities.
    resolution : float, optional
        The search's resolution in the scaled variables (:func:`certify`): ``tol`` where not given
        (COBYLA's last trust radius); :func:`~impactbar.physical.optimize_drifter` gives 0 for SLSQP
        and the population, whose ``tol`` is no step.

    Returns
    -------
    OptimalityCertificate
    """
    lo, span = scaling
    u = (np.array([record["values"][k] for k in keys]) - lo) / span
    if blow is not None:
        g, G, method = central_gradients(lambda v: [(r := blow(v))["objectives"][fkey],
                                                    *(c["scaled"] for c in r["constraints"].values())], u)
    else:
        (g, G), method = design_gradient(), ("implicit-function-theorem sensitivities of the orbit "
                                             "(tangent_derivatives, the step refined till two agree; central "
                                             "differences of continued orbits across a border)")
    def scaled(r):
        return (np.array([r["values"][k] for k in keys]) - lo) / span

    failed = [(scaled(r), r["error"]) for r in history if not r.get("ok") and "values" in r]
    names = list(record["constraints"])
    neighbours = [(scaled(r), [r["objectives"][fkey], *(r["constraints"][n]["scaled"] for n in names)])
                  for r in history if r.get("ok") and "values" in r]
    return certify(g, G, record, u, keys, method=method, budget=stopped_at_budget(result), failed=failed,
                   reach=2.0 * tol, resolution=tol if resolution is None else resolution,
                   neighbours=neighbours, objective=record["objectives"][fkey])
