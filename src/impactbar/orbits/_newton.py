"""Newton's method and its relatives on a segment problem (:class:`~.multi_impact._Segments`, or
continuation's with the same ``evaluate``, ``newton``, ``scale``, ``m``, ``n``, ``B`` and ``T``):
the normalisation of a solution's impact times, the detection of an undoubled orbit found again on a
doubled problem, and the chord method that polishes a coarse model's orbit (theory §5, §10)."""

from __future__ import annotations

import math

import numpy as np

from ._assemble import _build
from .multi_impact import Z_TIME

TWO_PI = 2.0 * math.pi

#: Newton iterations that polish a coarse model's orbit into the law's own (:func:`find_orbit`)
POLISH_ITERATIONS = 15


def _normalise(problem, u):
    """Shift the impact times so that the first lies in ``[0, 2 pi)``; check they increase."""
    z = np.array(u, dtype=float).reshape(problem.m, problem.B)
    z[:, Z_TIME] -= TWO_PI * math.floor(z[0, Z_TIME] / TWO_PI)
    t = z[:, Z_TIME]
    if problem.m > 1 and not np.all(np.diff(t) > 0.0):
        return None
    if not t[-1] - t[0] < TWO_PI * problem.n:
        return None
    if problem.T > 0.0 and not np.all(np.diff(np.append(t, t[0] + TWO_PI * problem.n)) > problem.T):
        return None  # a flight shorter than the contact window
    return z.ravel()


def _converge(problem, u0, avoid, tol, max_iter):
    """Newton's method on ``problem`` from ``u0``: the normalised solution, or ``None`` where it does
    not converge or only finds ``avoid`` (the undoubled orbit)."""
    u, _ = problem.newton(u0, tol=tol, max_iter=max_iter)
    if u is None or (avoid is not None and _same_orbit(u, avoid, problem)):
        return None
    return _normalise(problem, u)


def _converge_built(problem, u0, avoid, tol, max_iter):
    """:func:`_converge`, then the orbit (:func:`_build`) from one evaluation with the Jacobian at
    the normalised solution (the check of its residual and the multipliers'); ``None`` where Newton
    does not converge."""
    u, _ = problem.newton(u0, tol=tol, max_iter=max_iter, check=False)
    if u is None or (avoid is not None and _same_orbit(u, avoid, problem)):
        return None
    u = _normalise(problem, u)
    if u is None:
        return None
    evaluated = problem.evaluate(u)
    F, _, _ = evaluated
    if not np.all(np.isfinite(F)):
        return None
    return _build(problem, u, evaluated=evaluated)


def _chord(problem, u0, DF, avoid, tol, max_iter=POLISH_ITERATIONS):
    """The chord method on ``problem`` from ``u0`` with the fixed Jacobian ``DF`` (the coarse model's
    at its orbit, within that model's error of this one's): each step one evaluation of the residual,
    no Jacobian; it converges at the rate of the Jacobians' difference. The normalised solution, or
    ``None`` where the residual stops halving (then Newton's method)."""
    u = np.array(u0, dtype=float)
    last = math.inf
    for _ in range(max_iter):
        F, _, _ = problem.evaluate(u, jacobian=False)
        size = float(np.max(np.abs(F)))
        if not (np.all(np.isfinite(F)) and size <= 0.5 * last):
            return None
        last = size
        try:
            du = np.linalg.solve(DF, F)
        except np.linalg.LinAlgError:
            return None
        u = u - du
        if float(np.max(np.abs(du))) <= tol * problem.scale(u):
            F, _, _ = problem.evaluate(u, jacobian=False)
            if not np.all(np.isfinite(F)) or (avoid is not None and _same_orbit(u, avoid, problem)):
                return None
            return _normalise(problem, u)
    return None


def _same_orbit(u, v, problem):
    """Whether ``u`` is the undoubled orbit ``v`` again: its two halves coincide (up to the
    half-period shift of the times)."""
    return _halves_gap(u, problem) <= 1e-7 * problem.scale(v)


def _halves_gap(u, problem) -> float:
    """The largest difference between the two halves of the unknowns ``u`` of a doubled problem
    (``2 m`` impacts in ``2 n`` periods), the second half's times shifted back by ``2 pi n``: zero
    on an orbit of ``m`` impacts in ``n`` periods traversed twice."""
    z = np.array(u, dtype=float).reshape(2, -1)
    z[1, ::problem.B] -= TWO_PI * problem.n / 2
    return float(np.max(np.abs(z[0] - z[1])))
