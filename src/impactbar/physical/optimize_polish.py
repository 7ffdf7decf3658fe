r"""The polish of a search's best design: an active-set step with the implicit function theorem's
gradients, so that the design reported can be certified to first order.

A derivative-free search (COBYLA) ends within its last step of a local optimum, or at its budget; its
design's projected gradient (:mod:`~impactbar.physical.optimality`) is then of the order of that step
over the problem's curvature, often above :data:`~impactbar.physical.optimality.KKT_TOLERANCE`.
:func:`polish` starts SLSQP from it, with the objective's and the constraints' gradients in the scaled
variables (:func:`~impactbar.physical.optimize_problem._refined_gradient`, four flights a variable and step):
SLSQP's quadratic subproblem identifies the active constraints and bounds and steps onto them, its
quasi-Newton Hessian along them, so that a few iterations take the projected gradient from the
search's resolution to the gradients' accuracy. Its designs are evaluated as the search's are, and
a design without an orbit is scored as the search scores it, by the border model
(:mod:`~impactbar.physical.optimize_border`: its nearest success's first-order extrapolation, with
that model's gradients, and the constraint "the one-impact orbit exists" with its gradient), not by
a penalty (objective 1, every constraint -1, and no gradient), which SLSQP's quadratic model cannot
follow back across the border. The design it returns is the best feasible design it visited, and
only where it is better than the start (a design without an orbit, or one that misses a constraint,
is never returned), so a polish that fails, as at a border of the operating point where its line
search backtracks, leaves the start.

The polish stops where it has what it is for: at an iterate that is the best feasible design so far
and whose gradients (those SLSQP asks for there) meet the first-order conditions to
:data:`~impactbar.physical.optimality.KKT_TOLERANCE` (:func:`~impactbar.physical.optimality.certify`,
the search's active set at its resolution 0). SLSQP's own stop (its ``ftol`` on the objective) can
come many designs later, or never within the budget, and a budget that ends the polish elsewhere
leaves the design's certificate to where the budget happened to fall: the same search on another
platform's floating point (other last bits in SLSQP's iterates) then ended "stopped at a budget".
:func:`~impactbar.physical.optimize_drifter` then reports it only where a fresh orbit confirms it
feasible and no worse than the search's best (its ranking of the designs evaluated).
"""

from __future__ import annotations

import numpy as np

from .._shared.threads import single_threaded_blas
from .._shared.validate import check_real

__all__ = ["polish", "polish_search"]


class _Spent(Exception):
    """The polish's budget of designs used up (SLSQP cannot be stopped by its callbacks)."""


class _Stationary(Exception):
    """The best design so far meets the first-order conditions (the polish is done); ``residual`` its
    KKT residual."""

    def __init__(self, residual: float):
        super().__init__(residual)
        self.residual = float(residual)


def polish(objective, margins, gradients, u, *, designs: int, ftol: float = 1e-10,
           feasibility: float = 1e-8, border=None, existence=None, d_existence=None, stationary=None):
    r"""SLSQP from the design ``u``, the objective maximised under the margins, with given gradients;
    the best feasible design it visits if better than ``u``.

    Parameters
    ----------
    objective : callable
        ``u -> float``, maximised; ``None`` where the design has no value (no orbit).
    margins : callable
        ``u -> array of shape (m,)``, the constraints' scaled margins (met where :math:`\ge 0`).
    gradients : callable
        ``u -> (objective_gradient (n,), margin_gradients (m, n))`` in the scaled variables (at a
        design without an orbit, those of ``border``'s model where it scores one).
    u : array_like, shape (n,)
        The start, in ``[0, 1]``: the search's best feasible design.
    designs : int
        The most designs the polish evaluates (at least 1; SLSQP stops there).
    ftol : float
        SLSQP's tolerance on the objective scaled by the start's (positive).
    feasibility : float
        How far (scaled) a margin may miss and still count as met (not negative).
    border : callable, optional
        ``u -> (objective, margins (m,))`` or ``None``: a design without an orbit (``objective``
        ``None``) scored by the search's border model (:mod:`~impactbar.physical.optimize_border`);
        SLSQP sees those scores there. ``None`` (or a design it does not score): the penalty,
        objective 1 in SLSQP's scaled terms and every margin -1.
    existence, d_existence : callable, optional
        ``u -> float`` and ``u -> array of shape (n,)``: the constraint "the one-impact orbit exists"
        and its gradient (:func:`~impactbar.physical.optimize_border.existence_gradient`), given to
        SLSQP after the margins (met where :math:`\ge 0`; not counted in the returned design's
        feasibility, as it is met at every design with an orbit); both or neither.
    stationary : callable, optional
        ``(u, objective_gradient (n,), margin_gradients (m, n)) -> float or None``: the design's KKT
        residual (:func:`~impactbar.physical.optimality.certify`) where it is at most the tolerance,
        ``None`` otherwise. Asked at each of SLSQP's iterates that is the best feasible design so far,
        with the gradients SLSQP asks for there; the polish stops at the first one it certifies.
        ``None``: the polish stops where SLSQP does, or at ``designs``.

    Returns
    -------
    scipy.optimize.OptimizeResult
        ``x`` the design returned (``u`` where no design visited is better), ``fun`` its objective,
        ``improved`` whether it is not ``u``, ``nfev`` the designs evaluated, ``nit`` SLSQP's
        iterations, ``message`` SLSQP's (or that the budget was spent, or that the design returned is
        stationary), ``success`` SLSQP's (true where ``stationary`` stopped it), ``residual`` the KKT
        residual ``stationary`` gave (``None`` where it did not stop the polish).

    Raises
    ------
    ValueError
        ``designs`` or ``ftol`` out of range, or a start without a value.

    Examples
    --------
    The largest :math:`u_0 + 2u_1` in the unit disc (closed form :math:`(1, 2)/\sqrt 5`), from a
    point of it:

    >>> res = polish(lambda u: u[0] + 2 * u[1], lambda u: np.array([1 - u @ u]),
    ...              lambda u: (np.array([1.0, 2.0]), -2 * u[None, :]), [0.4, 0.8], designs=40)
    >>> bool(res.improved), np.round(res.x * np.sqrt(5), 6).tolist()
    (True, [1.0, 2.0])
    """
    from scipy.optimize import OptimizeResult, minimize

    if not (isinstance(designs, int) and not isinstance(designs, bool) and designs >= 1):
        raise ValueError(f"designs must be an integer >= 1 (the polish's most designs); got {designs!r}")
    if not (isinstance(ftol, float) and 0.0 < ftol < 1.0):
        raise ValueError(f"ftol must be a number in (0, 1) (SLSQP's on the scaled objective); got {ftol!r}")
    u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    f0 = objective(u)
    if f0 is None:
        raise ValueError("u: the start has no value (no orbit); the polish starts from a feasible design")
    if (existence is None) != (d_existence is None):
        raise ValueError("existence and d_existence: give both (the constraint and its gradient) or neither")
    ref = abs(f0) or 1.0
    best = {"x": u, "fun": f0, "improved": False}
    seen = {u.tobytes()}
    m = len(margins(u))

    def visit(v):
        v = np.clip(np.asarray(v, dtype=float), 0.0, 1.0)
        if v.tobytes() not in seen:
            if len(seen) > designs:  # (the start among them)
                raise _Spent
            seen.add(v.tobytes())
        value = objective(v)
        if value is not None and value > best["fun"] and np.all(np.asarray(margins(v)) >= -feasibility):
            best.update(x=v, fun=value, improved=True)
        return v, value

    def modelled(v):
        """A design without an orbit: the border model's objective and margins, else the penalty's
        (objective ``-ref``: 1 as SLSQP sees it, every margin -1)."""
        scores = None if border is None else border(v)
        if scores is None:
            return -ref, -np.ones(m)
        value, by_model = scores
        return value, np.asarray(by_model, dtype=float)

    def f(v):
        v, value = visit(v)
        if value is None:
            value, _ = modelled(v)
        return -value / ref

    def g(v):
        v, value = visit(v)
        if value is None:
            _, out = modelled(v)
        else:
            out = np.asarray(margins(v), dtype=float)
        return out if existence is None else np.append(out, existence(v))

    def df(v):  # the objective's gradient, scaled as f
        point, _ = visit(v)
        d_objective, d_margins = gradients(point)
        if (stationary is not None and best["improved"] and point.tobytes() == best["x"].tobytes()
                and (residual := stationary(point, d_objective, d_margins)) is not None):
            raise _Stationary(residual)  # (SLSQP asks for the gradients at each new iterate)
        return -d_objective / ref

    def dg(v):
        point, _ = visit(v)
        _, d_margins = gradients(point)
        return d_margins if existence is None else np.vstack([d_margins, d_existence(point)])

    try:
        # SLSQP's arithmetic on one BLAS thread: its iterates' last bits depend on OpenBLAS's threads
        # (1 where a dask cluster was started before scipy loaded its OpenBLAS, as distributed sets
        # OPENBLAS_NUM_THREADS=1 for its workers in this process's environment; the cores otherwise),
        # and a polish that ends at its budget lands on other designs from them
        with single_threaded_blas():
            res = minimize(f, u, jac=df, method="SLSQP", constraints=[{"type": "ineq", "fun": g, "jac": dg}],
                           bounds=[(0.0, 1.0)] * u.size, options={"ftol": ftol, "maxiter": 10 * designs})
        message, success, nit, residual = str(res.message), bool(res.success), int(res.nit), None
    except _Spent:
        message, success, nit, residual = f"the polish's limit reached ({designs} designs)", False, -1, None
    except _Stationary as done:
        residual = done.residual
        message, success, nit = f"stationary: the best design's KKT residual {residual:.3g}", True, -1
    return OptimizeResult(x=best["x"], fun=best["fun"], improved=best["improved"], nfev=len(seen) - 1,
                          nit=nit, message=message, success=success, residual=residual)


def polish_search(evaluate, margins, gradients, history: list, points: dict, fkey: str, *, designs: int,
                  ftol: float, border=None, existence=None, d_existence=None, tolerance: float | None = None):
    """:func:`polish` from the best feasible design of a search
    (:func:`~impactbar.physical.optimize_drifter`'s), stopped at the first iterate whose record and
    gradients :func:`~impactbar.physical.optimality.certify` finds stationary (the reported design's
    certificate, at the search's resolution 0).

    Parameters
    ----------
    evaluate : callable
        ``u -> record`` (a design's, ``ok`` false without an orbit).
    margins, gradients : callable
        As :func:`polish`'s (the search's own).
    history : list of dict
        The search's records; the best feasible one (``fkey`` largest) is the start.
    points : dict
        Each record's id to its scaled variables.
    fkey : str
        The objective's figure in a record's ``objectives`` (maximised).
    designs : int
        The polish's most designs.
    ftol : float
        SLSQP's tolerance (:func:`polish`).
    border, existence, d_existence : callable, optional
        The search's border model and existence constraint (:func:`polish`'s).
    tolerance : float, optional
        The largest KKT residual at which the polish stops (default
        :data:`~impactbar.physical.optimality.KKT_TOLERANCE`, the certificate's); 0: never before SLSQP
        or the budget does.

    Returns
    -------
    scipy.optimize.OptimizeResult
        :func:`polish`'s, with ``summary``: a line for the search's message.

    Raises
    ------
    ValueError
        ``tolerance`` negative or not finite, or as :func:`polish`.
    """
    from .optimality import KKT_TOLERANCE, certify

    tolerance = KKT_TOLERANCE if tolerance is None else check_real("tolerance", tolerance, lo=0.0)
    top = max((r for r in history if r.get("feasible")), key=lambda r: r["objectives"][fkey])

    def objective(v):
        rec = evaluate(v)
        return rec["objectives"][fkey] if rec["ok"] else None

    def stationary(v, d_objective, d_margins):  # (the reported design's certificate, its verdict aside)
        rec = evaluate(v)
        residual = certify(d_objective, d_margins, rec, v, [str(i) for i in range(v.size)],
                           method="polish").residual
        return residual if residual <= tolerance else None

    res = polish(objective, margins, gradients, points[top["id"]], designs=designs, ftol=ftol, border=border,
                 existence=existence, d_existence=d_existence, stationary=stationary if tolerance else None)
    gain = f"{fkey} {top['objectives'][fkey]:.6g} -> {res.fun:.6g}" if res.improved else "no better design"
    res.summary = (f"polished from the best design (SLSQP, the implicit function theorem's gradients): "
                   f"{res.nfev} designs, {gain} ({res.message})")
    return res
