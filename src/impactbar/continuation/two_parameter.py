"""Two-parameter continuation of folds, period doublings and grazing (the chart edges of the paper's
Figs. 5, 6, 8 and their analogues for motions with several impacts; theory §5-§7).

A located :class:`BranchEvent` is followed in two parameters at once by the pseudo-arclength engine
of :func:`continue_orbit` (:mod:`impactbar.continuation.engine`) on a minimally augmented system:
the segment problem of :func:`find_orbit` plus one scalar condition, ``g = 0``. For a fold (period
doubling) ``g`` is the bordered determinant of ``I - P`` (``I + P``), ``P`` the monodromy matrix:
the last entry of the solution of ``[[I -+ P, b], [c^T, 0]] (v, g) = (0, 1)`` with ``b``, ``c``
the singular vectors at the start; for grazing ``g`` is the clearance (the largest ``u(1, t)``
between impacts, theory §5).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._shared.status import CurveKind
from .._shared.threads import single_threaded_blas
from ..orbits.segments import SegmentProblem, build_orbit, normalise, unknowns_from
from .branch import BranchEvent, orbit_columns
from .engine import ContinuationSettings, _Engine, _settings
from .parameters import _check_parameter, _target, parameter_value, with_parameter

__all__ = ["BifurcationCurve", "continue_bifurcation"]

#: Event kinds a two-parameter curve can follow.
CURVE_KINDS = tuple(CurveKind)


@dataclass(frozen=True, eq=False)
class BifurcationCurve:
    """A curve of folds, period doublings or grazing points in a plane of two parameters.

    Attributes
    ----------
    kind : CurveKind
        A string: ``"fold"``, ``"period-doubling"`` or ``"grazing"``.
    parameters : tuple of str
        ``(first, second)``: the parameter of the branch the event was found on, and the new one.
    values : numpy.ndarray, shape (P, 2)
        The two parameters at each point of the curve.
    orbits : tuple of MultiImpactOrbit, length P
        The critical orbit at each point.
    status : BranchStatus
        Why the continuation stopped (a string): ``"reached"``, ``"max_points"``,
        ``"step too small"``, ``"parameter range"`` or ``"turned back"``.

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, continue_bifurcation, continue_orbit, periodic_orbits
    >>> start = periodic_orbits(BarModel(s=3.0, d=0.0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))[1]
    >>> fold = continue_orbit(start, "p0", to=1.5).events[0]
    >>> curve = continue_bifurcation(fold, "R", to=0.7)
    >>> str(curve.kind), curve.parameters
    ('fold', ('p0', 'R'))
    >>> curve.values[-1].round(6)  # p0 = (1 + R)/(pi (1 - R)) at R = 0.7
    array([1.803756, 0.7     ])
    """

    kind: str
    parameters: tuple
    values: np.ndarray
    orbits: tuple = field(repr=False)
    status: str

    def __len__(self) -> int:
        return int(self.values.shape[0])

    def __repr__(self) -> str:
        """One line: the kind, the parameters, the ends, the points, the status."""
        a, b = self.parameters
        ends = (f"({a}, {b}) from {tuple(round(float(x), 6) for x in self.values[0])} to "
                f"{tuple(round(float(x), 6) for x in self.values[-1])}, " if len(self) else "")
        return (f"BifurcationCurve({str(self.kind)!r}, {ends}{len(self)} points, "
                f"status {str(self.status)!r})")

    def to_dataframe(self):
        """One row per point: both parameters, then the orbits' fields as a branch's table gives
        them (:func:`impactbar.continuation.branch.orbit_columns`); requires pandas."""
        import pandas as pd

        a, b = self.parameters
        first, second = self.values.T  # the two parameters' values
        df = pd.DataFrame({a: first, b: second, **orbit_columns(self.orbits)})
        df.index.name = "point"
        return df

    def plot(self, ax=None, *, swap: bool = False, **kwargs):
        """Draw the curve, second parameter on the abscissa (``swap`` to exchange the axes).

        Returns
        -------
        matplotlib.axes.Axes
        """
        from ..plotting.continuation import plot_bifurcation_curve

        return plot_bifurcation_curve(self, ax, swap=swap, **kwargs)


class _BifurcationProblem:
    """The augmented system ``G = (F, g)`` in ``U = (u, lambda_1, lambda_2)`` for the engine
    (:mod:`impactbar.continuation.engine`): the segment problem ``F`` of :func:`find_orbit` bordered
    by the test function ``g`` of the curve's kind, ``lambda_2`` (the continued one) last."""

    def __init__(self, model, load, names, m, n, kind):
        self.model0, self.load0, self.names, self.m, self.n = model, load, names, m, n
        self.kind = kind
        size = SegmentProblem(model, load, m, n).size  # (t, state) per impact
        self.W = np.concatenate((np.full(size, 1.0 / size), [1.0, 1.0]))
        self.b = self.c = None
        self._cache = {}

    def segments(self, l1, l2):
        key = (float(l1), float(l2))
        p = self._cache.get(key)
        if p is None:
            first, second = key
            model, load = with_parameter(self.model0, self.load0, self.names[0], first)
            model, load = with_parameter(model, load, self.names[1], second)
            p = SegmentProblem(model, load, self.m, self.n)
            if len(self._cache) > 64:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = p
        return p

    def matrix(self, problem, info):
        P = problem.monodromy(info["maps"])
        return np.eye(P.shape[0]) + (P if self.kind == CurveKind.PERIOD_DOUBLING else -P)

    def set_border(self, U):
        p = self.segments(U[-2], U[-1])
        _, _, info = p.evaluate(U[:-2])
        A = self.matrix(p, info)
        uu, _, vt = np.linalg.svd(A)
        self.b, self.c = uu[:, -1], vt[-1]

    def g(self, U):
        """The test function: minus the clearance (grazing), or the bordered determinant of
        ``I -+ P``: the last entry of the solution of ``[[I -+ P, b], [c^T, 0]] (v, g) = (0, 1)``."""
        p = self.segments(U[-2], U[-1])
        if self.kind == CurveKind.GRAZING:
            u = normalise(p, U[:-2])
            return -build_orbit(p, U[:-2] if u is None else u).clearance
        _, _, info = p.evaluate(U[:-2])
        A = self.matrix(p, info)
        k = A.shape[0]
        B = np.zeros((k + 1, k + 1))
        B[:k, :k] = A
        B[:k, k] = self.b
        B[k, :k] = self.c
        rhs = np.zeros(k + 1)
        rhs[k] = 1.0
        return float(np.linalg.solve(B, rhs)[k])

    def FJ(self, U, frozen=None):
        """``G``, its Jacobian (``F_u`` exact, the parameter columns and the gradient of ``g`` by
        central differences) and the parameter columns, which Newton's corrector reuses."""
        u, l1, l2 = U[:-2], U[-2], U[-1]
        F, DF, _ = self.segments(l1, l2).evaluate(u)
        g0 = self.g(U)
        if frozen is None:
            cols = []
            for i, lam in ((-2, l1), (-1, l2)):
                h = 1e-6 * max(1.0, abs(lam))
                e = np.zeros(U.size)
                e[i] = h
                try:
                    Fp, _, _ = self.segments(*(U + e)[-2:]).evaluate(u, jacobian=False)
                    Fm, _, _ = self.segments(*(U - e)[-2:]).evaluate(u, jacobian=False)
                    cols.append((Fp - Fm) / (2 * h))
                except ValueError:  # at the edge of a parameter's range: one-sided
                    Fp, _, _ = self.segments(*(U + e)[-2:]).evaluate(u, jacobian=False)
                    cols.append((Fp - F) / h)
            frozen = np.column_stack(cols)
        grad = np.empty(U.size)
        for i in range(U.size):
            h = 1e-7 * max(1.0, abs(U[i]))
            e = np.zeros(U.size)
            e[i] = h
            try:
                grad[i] = (self.g(U + e) - self.g(U - e)) / (2 * h)
            except ValueError:
                grad[i] = (self.g(U + e) - g0) / h
        J = np.vstack((np.column_stack((DF, frozen)), grad))
        return np.append(F, g0), J, frozen

    def orbit(self, U, admissibility=True):
        p = self.segments(U[-2], U[-1])
        u = normalise(p, U[:-2])
        return build_orbit(p, U[:-2] if u is None else u, admissibility=admissibility)

    def acceptable(self, U):
        return normalise(self.segments(U[-2], U[-1]), U[:-2]) is not None

    def after_point(self, engine, points, tangents, orbits):
        """No events on a curve; every 10 points the bordering vectors are renewed (near the
        current singular vectors)."""
        if self.kind != CurveKind.GRAZING and len(points) % 10 == 0:
            self.set_border(points[-1])
        return [], None

    def corner(self, engine, U, index):
        return None


def continue_bifurcation(event: BranchEvent, parameter: str, to: float, *,
                         settings: ContinuationSettings | None = None, step: float | None = None,
                         max_step: float | None = None, min_step: float | None = None,
                         max_points: int | None = None, tol: float | None = None) -> BifurcationCurve:
    """Follow a fold, period doubling or grazing point in two parameters (Figs. 5, 6, 8; theory
    §5-§7).

    The event's own parameter and ``parameter`` both vary; the orbit stays critical (a multiplier at
    ``+1`` or ``-1``, or zero clearance) along the curve, which is traced by pseudo-arclength
    continuation of the segment problem of :func:`find_orbit` augmented by one test function.

    Parameters
    ----------
    event : BranchEvent
        A ``"fold"``, ``"period-doubling"`` or ``"grazing"`` event of a :class:`Branch`.
    parameter : str
        The second parameter (one of ``"p0"``, ``"pk"``, ``"q"``, ``"kappa"``, ``"R"``, ``"d"``,
        ``"s"``, other than the branch's).
    to : float
        Target value of ``parameter``; the curve stops there, or where it leaves the range between
        the start and ``to``.
    settings : ContinuationSettings, optional
        Steps, point limit and Newton tolerance, as for :func:`continue_orbit` (the same defaults:
        ``|to - start| / 50``, ``/ 10`` and ``1e-9`` times that, 2000 points, ``1e-11``).
    step, max_step, min_step, max_points, tol : optional
        Override the fields of ``settings`` of the same names.

    Returns
    -------
    BifurcationCurve

    Raises
    ------
    ValueError
        For an event of another kind, a bad parameter (named), or ``to`` equal to the start value.

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, periodic_orbits, continue_orbit
    >>> from impactbar.continuation import continue_bifurcation
    >>> start = periodic_orbits(BarModel(s=3, d=0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))[1]
    >>> pd = continue_orbit(start, "p0", to=0.7).events[0]
    >>> curve = continue_bifurcation(pd, "R", to=0.7)
    >>> round(float(curve.values[-1, 0]), 8)  # p0 at R = 0.7: (1+R)^2 / sqrt(4 (1+R^2)^2 + ...)
    0.85416706
    """
    if not isinstance(event, BranchEvent):
        raise ValueError(f"event must be a BranchEvent; got {type(event).__name__}")
    if event.kind not in CURVE_KINDS:
        raise ValueError(f"event must be a fold, period doubling or grazing point; got {event.kind!r}")
    o = event.orbit
    model, load = o.model, o.load
    _check_parameter(model, load, parameter, continuation=True)
    if parameter == event.parameter:
        raise ValueError(f"parameter must differ from the branch's parameter {event.parameter!r}")
    l1 = float(event.value)
    l2 = parameter_value(model, load, parameter)
    to = _target(parameter, l2, to)
    settings = _settings(settings, step=step, max_step=max_step, min_step=min_step,
                         max_points=max_points, tol=tol)
    direction = 1.0 if to > l2 else -1.0
    problem = _BifurcationProblem(model, load, (event.parameter, parameter), o.impacts, o.periods,
                                  CurveKind(event.kind))
    engine = _Engine(problem, settings.tol)
    with single_threaded_blas():
        base = problem.segments(l1, l2)
        U0 = np.concatenate((unknowns_from(base, o.impact_times, o.states_after_impact), [l1, l2]))
        if event.kind != CurveKind.GRAZING:
            problem.set_border(U0)
        e2 = np.zeros(U0.size)
        e2[-1] = 1.0
        U0, _ = engine.correct(U0, e2, U0)  # back onto the curve at the start value
        if U0 is None:
            raise ValueError("event: Newton on the augmented system did not converge at the start")
        t0 = engine.tangent(U0, direction * e2, engine.last_J)
        P, orbits, _, status = engine.march(U0, t0, to, direction, min(l2, to), max(l2, to),
                                            settings.steps(abs(to - l2)), settings.max_points)
    return BifurcationCurve(kind=CurveKind(event.kind), parameters=(event.parameter, parameter),
                            values=P[:, -2:].copy(), orbits=orbits, status=status)
