"""The pseudo-arclength engine that every continuation runs on (theory §7), and its settings.

A continuation follows the solutions ``U = (u, ..., lambda)`` of an *augmented problem* ``G(U) = 0``
with one more unknown than equations, the continued parameter ``lambda`` last: for
:func:`continue_orbit` ``G`` is the segment problem of :func:`impactbar.find_orbit` in ``(u,
lambda)``; for :func:`continue_bifurcation` the same problem in ``(u, lambda_1, lambda_2)``
bordered by one scalar test function (a minimally augmented system, as in MATCONT and
BifurcationKit). The engine knows nothing else of the problem: it predicts along the tangent (the
null vector of ``DG``), corrects by Newton's method on the hyperplane normal to it (the arclength
condition), controls the step and stops at the target, at the point limit, when the corrector fails
or where the problem says so (its events).

An augmented problem provides ``W`` (the weights of the arclength norm), ``FJ(U, frozen)``
(residual, Jacobian, and the columns it may reuse within one correction), ``orbit(U)``,
``acceptable(U)``, ``after_point(engine, points, tangents, orbits)`` (events, and a status to stop
with) and ``corner(engine, U, index)`` (an event explaining a failed step, or ``None``); and may
provide ``corrector``, ``None`` or a corrector of its own in place of Newton's
(``corrector(engine, U_pred, normal, anchor, max_iter) -> (U or None, iterations, Jacobian at U)``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._shared.status import BranchStatus
from .._shared.validate import check_int, check_real

__all__ = ["ContinuationSettings"]


@dataclass(frozen=True)
class ContinuationSettings:
    """Step control, point limit and tolerance of a pseudo-arclength continuation, shared by
    :func:`continue_orbit` and :func:`continue_bifurcation` (validated once, here).

    Attributes
    ----------
    step : float or None
        Initial arclength step (> 0), in the weighted norm: the squared norm of the unknowns
        (impact times, reduced modal states) averaged over their number, plus each parameter's
        square (as AUTO weighs a state against the parameter). ``None``: ``|to - start| / 50``.
    max_step : float or None
        Largest step (> 0). ``None``: ``|to - start| / 10``.
    min_step : float or None
        Smallest step (> 0): the continuation stops (``"step too small"``) when the corrector
        fails below it. ``None``: ``1e-9 |to - start|``.
    max_points : int
        Largest number of points, ``>= 2``. Default 2000.
    tol : float
        Relative tolerance of Newton's corrector, in ``(0, 1e-3]``. Default ``1e-11``.

    Raises
    ------
    ValueError
        Naming the setting and its allowed range.

    Examples
    --------
    >>> from impactbar.continuation import ContinuationSettings
    >>> ContinuationSettings(max_step=0.05).max_points
    2000
    """

    step: float | None = None
    max_step: float | None = None
    min_step: float | None = None
    max_points: int = 2000
    tol: float = 1e-11

    #: the defaults of ``step``, ``max_step`` and ``min_step`` as fractions of ``|to - start|``
    FRACTIONS = (1 / 50, 1 / 10, 1e-9)

    def __post_init__(self):
        for name in ("step", "max_step", "min_step"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, check_real(name, value, lo=0.0, lo_open=True))
        if self.min_step is not None and self.max_step is not None and self.min_step > self.max_step:
            raise ValueError(f"min_step must be <= max_step = {self.max_step}; got {self.min_step}")
        object.__setattr__(self, "max_points", check_int("max_points", self.max_points, lo=2))
        object.__setattr__(self, "tol", check_real("tol", self.tol, lo=0.0, lo_open=True, hi=1e-3))

    def steps(self, span: float) -> tuple[float, float, float]:
        """``(step, max_step, min_step)`` for a continuation over ``span = |to - start|``, the
        defaults filled in and the initial step at most the largest."""
        f_step, f_max, f_min = self.FRACTIONS
        step = span * f_step if self.step is None else self.step
        max_step = span * f_max if self.max_step is None else self.max_step
        min_step = span * f_min if self.min_step is None else self.min_step
        return min(step, max_step), max_step, min_step


def _settings(settings: ContinuationSettings | None, **given) -> ContinuationSettings:
    """``settings`` (default: the defaults) with the keyword arguments given (not ``None``) in
    place of its fields."""
    if settings is None:
        settings = ContinuationSettings()
    elif not isinstance(settings, ContinuationSettings):
        raise ValueError(f"settings must be a ContinuationSettings; got {type(settings).__name__}")
    given = {k: v for k, v in given.items() if v is not None}
    if not given:
        return settings
    fields = {k: getattr(settings, k) for k in ("step", "max_step", "min_step", "max_points", "tol")}
    return ContinuationSettings(**dict(fields, **given))


class _Engine:
    """Pseudo-arclength continuation of an augmented problem (see the module's docstring)."""

    def __init__(self, problem, tol: float):
        self.problem, self.tol = problem, tol
        self.W = problem.W
        self.last_J = None

    def orbit(self, U, **kwargs):
        """The problem's orbit at ``U``."""
        return self.problem.orbit(U, **kwargs)

    def dot(self, a, b):
        return float(a @ (self.W * b))

    def norm(self, a):
        return math.sqrt(self.dot(a, a))

    def tangent(self, U, t_prev, J=None):
        """Unit tangent (weighted norm) at ``U``: the null vector of ``DG``, oriented along
        ``t_prev``; ``J`` is that Jacobian if already at hand."""
        if J is None:
            _, J, _ = self.problem.FJ(U)
        A = np.vstack((J, self.W * t_prev))
        rhs = np.zeros(A.shape[0])
        rhs[-1] = 1.0
        t = np.linalg.solve(A, rhs)
        t /= self.norm(t)
        if self.dot(t, t_prev) < 0:
            t = -t
        return t

    def correct(self, U_pred, normal, anchor, *, max_iter=10):
        """Newton on ``G(U) = 0``, ``<normal, U - anchor> = 0`` (weighted). Returns
        ``(U, iterations)`` or ``(None, iterations)``; the last Jacobian is kept in ``last_J`` (for
        the tangent at the new point: the last step is below the tolerance)."""
        own = getattr(self.problem, "corrector", None)
        if own is not None:  # the problem's own corrector (its Jacobian kept in last_J all the same)
            U, it, self.last_J = own(self, U_pred, normal, anchor, max_iter)
            return U, it
        U = np.array(U_pred, dtype=float)
        self.last_J = None
        normal = self.W * normal
        frozen = prev = None
        for it in range(1, max_iter + 1):
            try:
                F, J, frozen = self.problem.FJ(U, frozen)
            except ValueError:
                return None, it
            if not (np.all(np.isfinite(F)) and np.all(np.isfinite(J))):
                return None, it
            G = np.append(F, normal @ (U - anchor))
            A = np.vstack((J, normal))
            try:
                dU = np.linalg.solve(A, G)
            except np.linalg.LinAlgError:
                return None, it
            U = U - dU
            step, scale = float(np.max(np.abs(dU))), max(1.0, float(np.max(np.abs(U))))
            # converged when this step, or the next one predicted from the rate of the last two,
            # is below the tolerance (saves the evaluation that would only confirm it)
            if step <= self.tol * scale or (prev is not None and step < 1e-6 * scale
                                            and step * step / prev <= 0.1 * self.tol * scale):
                self.last_J = J
                return U, it
            prev = step
        return None, max_iter

    def march(self, U0, t0, to, direction, lo, hi, steps, max_points, first=None):
        """Follow the curve from ``U0`` (tangent ``t0``) towards ``lambda = to``.

        Parameters
        ----------
        U0 : numpy.ndarray
            A solution of ``G = 0``.
        t0 : numpy.ndarray or None
            Its unit tangent, pointing towards ``to`` (``None`` with ``first``).
        to, direction : float
            The target of the last unknown and the sign of ``to - U0[-1]``.
        lo, hi : float
            The range the last unknown may take (``"turned back"`` outside it).
        steps : tuple of float
            ``(step, max_step, min_step)``.
        max_points : int
        first : tuple or None
            ``(U1, t1)``: the second point and its tangent, already found (branch switching).

        Returns
        -------
        points : numpy.ndarray, shape (P, U.size)
        orbits : tuple, length P
        events : list
        status : BranchStatus
        """
        problem = self.problem
        h, max_step, min_step = steps
        points, tangents, orbits, found = [U0], [t0], [problem.orbit(U0)], []
        status = BranchStatus.MAX_POINTS
        e_last = np.eye(U0.size)[-1]
        pending = first
        stalled = 0
        while len(points) < max_points:
            Ua, ta = points[-1], tangents[-1]
            if pending is not None:
                (Ub, tb), pending, it = pending, None, 1
            else:
                Ub = None
                while h >= min_step:
                    pred = Ua + h * ta
                    final = (pred[-1] - to) * direction > 0 and (Ua[-1] - to) * direction < 0
                    if final:  # onto the target's hyperplane
                        Ub, it = self.correct(Ua + ta * (to - Ua[-1]) / ta[-1], e_last,
                                              np.append(Ua[:-1], to))
                    else:
                        Ub, it = self.correct(pred, ta, pred)
                        if Ub is not None and (Ub[-1] - to) * direction > 0 and (Ua[-1] - to) * direction < 0:
                            final = True  # corrected past the target: onto the target's hyperplane instead
                            Ub, it = self.correct(Ua + ta * (to - Ua[-1]) / ta[-1], e_last,
                                                  np.append(Ua[:-1], to))
                    if Ub is not None:
                        tb = self.tangent(Ub, ta, self.last_J) if not final else ta
                        turned = not final and self.dot(tb, ta) < 0.8
                        if not turned and self.norm(Ub - Ua) < 3 * h + 1e-12 and problem.acceptable(Ub):
                            break
                    Ub = None
                    h *= 0.5
                if Ub is None:
                    status = BranchStatus.STEP_TOO_SMALL
                    corner = problem.corner(self, Ua, len(points) - 1)
                    if corner is not None:
                        found.append(corner)
                        status = BranchStatus.LOAD_JUMP
                    break
            try:
                ob = problem.orbit(Ub)
            except ValueError:
                status = BranchStatus.PARAMETER_RANGE
                break
            points.append(Ub)
            orbits.append(ob)
            tangents.append(tb)
            new, stop = problem.after_point(self, points, tangents, orbits)
            found.extend(new)
            if stop is not None:
                status = stop
                break
            if abs(Ub[-1] - to) <= 1e-14 * max(1.0, abs(to)):
                status = BranchStatus.REACHED
                break
            if Ub[-1] < lo - 1e-12 * max(1.0, abs(lo)) or Ub[-1] > hi + 1e-12 * max(1.0, abs(hi)):
                status = BranchStatus.TURNED_BACK
                break
            if it <= 3:
                h = min(h * 1.6, max_step)
            elif it >= 6:
                h = max(h * 0.6, min_step)
            stalled = stalled + 1 if h < 1e-4 * max_step else 0
            if stalled >= 8:  # steps stay tiny: the problem may know the corner (a load jump)
                corner = problem.corner(self, Ub, len(points) - 1)
                if corner is not None:
                    found.append(corner)
                    status = BranchStatus.LOAD_JUMP
                    break
        return np.array(points), tuple(orbits), found, status
