"""Pseudo-arclength continuation of periodic impacting motions (theory §4, §5, §7).

A branch of ``m``-impact, ``n``-period motions is followed in one parameter of the model or the
load; along it, folds (a multiplier through ``+1``), period doublings (``-1``), Neimark-Sacker points
(a complex pair through the unit circle), grazing (the end touches the stop between impacts, or
strikes it with zero velocity), other losses of admissibility and impacts running into a jump of a
piecewise-constant load are detected by sign changes of test functions and located on the branch.
The unknowns and conditions are those of :func:`find_orbit` (one segment per flight, closed-form
flow, exact Jacobian), bordered by the pseudo-arclength condition, as in the segment-based
continuation of hybrid periodic orbits (COCO's ``hspo``).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from .._status import BranchStatus, EventKind
from .._threads import single_threaded_blas
from .._validate import check_real
from ..loads import PiecewiseConstantLoad
from ..orbits.multi_impact import (
    MultiImpactOrbit,
    _build,
    _normalise,
    _Segments,
    _unknowns_from,
    doubling_direction,
)
from ..orbits.one_impact import PeriodicOrbit
from .branch import Branch, BranchEvent
from .parameters import _check_parameter, _steps, parameter_value, with_parameter

__all__ = ["continue_orbit", "EVENT_KINDS"]

TWO_PI = 2.0 * math.pi

#: Event kinds, in the order they are reported.
EVENT_KINDS = tuple(EventKind)

# ------------------------------------------------------------------------------------------------
# the continuation engine
# ------------------------------------------------------------------------------------------------
class _Continuation:
    def __init__(self, model, load, name, m, n, tol):
        self.model0, self.load0, self.name, self.m, self.n, self.tol = model, load, name, m, n, tol
        self._cache = {}
        size = 2 * (model.n_modes + 1) * m
        # weighted arclength: the state's squared norm is averaged over its components (as AUTO
        # does), so the parameter keeps its share however many modes and impacts there are
        self.W = np.append(np.full(size, 1.0 / size), 1.0)

    def dot(self, a, b):
        return float(a @ (self.W * b))

    def norm(self, a):
        return math.sqrt(self.dot(a, a))

    def problem(self, lam):
        key = float(lam)
        p = self._cache.get(key)
        if p is None:
            model, load = with_parameter(self.model0, self.load0, self.name, key)
            p = _Segments(model, load, self.m, self.n)
            if len(self._cache) > 16:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = p
        return p

    def F(self, U):
        F, _, _ = self.problem(U[-1]).evaluate(U[:-1], jacobian=False)
        return F

    def FJ(self, U, F_lam=None):
        """Residual and the full Jacobian ``[F_u, F_lam]``, ``F_lam`` by central differences unless
        given (Newton's corrector reuses the one of its first iteration)."""
        u, lam = U[:-1], U[-1]
        F, DF, info = self.problem(lam).evaluate(u)
        if F_lam is not None:
            return F, np.column_stack((DF, F_lam)), info
        h = 1e-6 * max(1.0, abs(lam))
        try:
            Fp = self.problem(lam + h).evaluate(u, jacobian=False)[0]
            Fm = self.problem(lam - h).evaluate(u, jacobian=False)[0]
            Fl = (Fp - Fm) / (2 * h)
        except ValueError:  # at the edge of the parameter's range: one-sided
            try:
                Fl = (self.problem(lam + h).evaluate(u, jacobian=False)[0] - F) / h
            except ValueError:
                Fl = (F - self.problem(lam - h).evaluate(u, jacobian=False)[0]) / h
        return F, np.column_stack((DF, Fl)), info

    def tangent(self, U, t_prev, J=None):
        """Unit tangent (weighted norm) at ``U``: the null vector of ``[F_u, F_lam]``, oriented along
        ``t_prev``; ``J`` is that Jacobian if already at hand."""
        if J is None:
            _, J, _ = self.FJ(U)
        A = np.vstack((J, self.W * t_prev))
        rhs = np.zeros(A.shape[0])
        rhs[-1] = 1.0
        t = np.linalg.solve(A, rhs)
        t /= self.norm(t)
        if self.dot(t, t_prev) < 0:
            t = -t
        return t

    def correct(self, U_pred, normal, anchor, *, max_iter=10):
        """Newton on ``F(U) = 0``, ``<normal, U - anchor> = 0`` (weighted). Returns
        ``(U, iterations)`` or ``(None, iterations)``; the last Jacobian is kept in ``last_J`` (for
        the tangent at the new point: the last step is below the tolerance)."""
        U = np.array(U_pred, dtype=float)
        self.last_J = None
        normal = self.W * normal
        F_lam = prev = None
        for it in range(1, max_iter + 1):
            try:
                F, J, _ = self.FJ(U, F_lam)
            except ValueError:
                return None, it
            F_lam = J[:, -1]
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

    def orbit(self, U, admissibility=True):
        """The orbit at a branch point, its first impact time brought into ``[0, 2 pi)``."""
        p = self.problem(U[-1])
        u = _normalise(p, U[:-1])
        return _build(p, U[:-1] if u is None else u, admissibility=admissibility)


def _tests(orbit: MultiImpactOrbit):
    """Test functions at a point: ``det(I - P)``, ``det(I + P)``, the Neimark-Sacker function and its
    number of complex pairs, the clearance and the smallest impact velocity."""
    mu = orbit.multipliers
    fold = float(np.prod(1.0 - mu).real)
    pd = float(np.prod(1.0 + mu).real)
    cpx = mu[mu.imag > 1e-10 * np.maximum(1.0, np.abs(mu))]
    ns = float(np.prod(np.abs(cpx) ** 2 - 1.0)) if cpx.size else 1.0
    return {"fold": fold, "period-doubling": pd, "neimark-sacker": ns, "pairs": int(cpx.size),
            "grazing": -float(orbit.clearance), "impact": float(np.min(orbit.impact_velocities)),
            "admissible": orbit.admissible}


def continue_orbit(orbit, parameter: str, to: float, *, step: float | None = None,
                   max_step: float | None = None, min_step: float | None = None,
                   max_points: int = 2000, events: bool = True, stop_on=(), tol: float = 1e-11,
                   xtol: float = 1e-10) -> Branch:
    """Follow a periodic motion as one parameter changes, by pseudo-arclength continuation.

    Each step predicts along the branch's tangent (the null vector of ``[F_u, F_lambda]`` of the
    segment problem of :func:`find_orbit`, eqs. 8, 10, 11) and corrects by Newton's method on the
    hyperplane normal to it; the step grows after quick convergence and is halved after a failure.
    Between consecutive points the test functions ``det(I - P)`` (fold, multiplier ``+1``),
    ``det(I + P)`` (period doubling, ``-1``), ``prod(|mu|^2 - 1)`` over complex pairs
    (Neimark-Sacker), the clearance (grazing between impacts, theory §5), the smallest impact
    velocity (grazing impact) and the admissibility flag are compared; a change of sign is located
    on the branch by Brent's method along the chord between the two points (theory §7).

    Parameters
    ----------
    orbit : PeriodicOrbit, MultiImpactOrbit or BranchEvent
        The start. A ``"period-doubling"`` :class:`BranchEvent` starts the doubled branch (``2 m``
        impacts in ``2 n`` periods) from the event, along the bifurcating direction (branch
        switching).
    parameter : str
        One of ``"p0"``, ``"pk"`` (a :class:`CosineLoad`), ``"q"``, ``"kappa"`` (a
        :class:`SquareWaveLoad`), ``"R"``, ``"d"``, ``"s"`` (the :class:`BarModel`).
    to : float
        Target value; the branch stops there, or where it leaves the range between the start and
        ``to`` after a fold. A branch started at a period doubling may bifurcate to either side:
        it is followed while the parameter stays within ``|to - start|`` of the doubling.
    step, max_step, min_step : float, optional
        Initial, largest and smallest arclength steps, in a weighted norm: the squared norm of the
        unknowns (impact times, reduced modal states) averaged over their number, plus the
        parameter's square (as AUTO weighs a state against the parameter); defaults
        ``|to - start| / 50``, ``/ 10`` and ``1e-9`` times that.
    max_points : int
        Largest number of branch points.
    events : bool
        Detect and locate events.
    stop_on : iterable of str
        Event kinds at which to stop (e.g. ``("grazing",)``).
    tol : float
        Relative Newton tolerance at each point.
    xtol : float
        Tolerance of the event location in the chord's arclength (the parameter is then located to
        about the same).

    Returns
    -------
    Branch

    Raises
    ------
    ValueError
        For a bad argument (named), a parameter the load does not have, a start that is not a
        solution, or ``to`` equal to the start value.

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, periodic_orbits, continue_orbit
    >>> start = periodic_orbits(BarModel(s=3, d=0, R=0.6, n_modes=0), CosineLoad(0.3, 1.0))[1]
    >>> b = continue_orbit(start, "p0", to=1.3)
    >>> [(e.kind, round(e.value, 6)) for e in b.events], b.status
    ([('period-doubling', 0.756847), ('fold', 1.27324), ('grazing', 0.401966)], 'turned back')
    """
    switch = None
    if isinstance(orbit, BranchEvent):
        if orbit.kind != "period-doubling":
            raise ValueError(f"a BranchEvent start must be a period doubling; got {orbit.kind!r}")
        switch = orbit
        base = orbit.orbit
    elif isinstance(orbit, PeriodicOrbit | MultiImpactOrbit):
        base = orbit
    else:
        raise ValueError(f"orbit must be a PeriodicOrbit, MultiImpactOrbit or BranchEvent; got "
                         f"{type(orbit).__name__}")
    model, load = base.model, base.load
    _check_parameter(model, load, parameter)
    lam0 = parameter_value(model, load, parameter)
    to, step, max_step, min_step, max_points = _steps(parameter, lam0, to, step, max_step, min_step,
                                                       max_points, (1 / 50, 1 / 10, 1e-9))
    tol = check_real("tol", tol, lo=0.0, lo_open=True, hi=1e-3)
    xtol = check_real("xtol", xtol, lo=0.0, lo_open=True, hi=1e-2)
    stop_on = tuple(stop_on)
    for k in stop_on:
        if k not in EVENT_KINDS:
            raise ValueError(f"stop_on must hold event kinds from {EVENT_KINDS}; got {k!r}")
    direction = 1.0 if to > lam0 else -1.0

    if isinstance(base, PeriodicOrbit):
        times, states, m, n = np.array([base.phase]), base.state_after_impact[None, :], 1, 1
    else:
        times, states, m, n = base.impact_times, base.states_after_impact, base.impacts, base.periods
    with single_threaded_blas():
        if switch is not None:
            return _run_switch(switch, parameter, lam0, to, direction, step, max_step, min_step,
                               max_points, events, stop_on, tol, xtol)
        cont = _Continuation(model, load, parameter, m, n, tol)
        u0 = _unknowns_from(cont.problem(lam0), times, states)
        U0 = np.append(u0, lam0)
        F0, J0, _ = cont.FJ(U0)
        if float(np.max(np.abs(F0))) <= 1e-11 * max(1.0, float(np.max(np.abs(U0)))):
            cont.last_J = J0  # already a solution (at a fold, Newton at fixed parameter is singular)
        else:
            U0, _ = cont.correct(U0, np.eye(U0.size)[-1], U0)
            if U0 is None:
                raise ValueError("orbit: Newton at the start value did not converge; is it a solution?")
        # the tangent: the null vector of [F_u, F_lam] (by SVD: also at a fold), towards `to`
        t0 = np.linalg.svd(cont.last_J)[2][-1]
        t0 /= cont.norm(t0)
        if t0[-1] * direction < 0:
            t0 = -t0
        return _run(cont, U0, t0, lam0, to, direction, step, max_step, min_step, max_points, events,
                    stop_on, xtol)


def _run_switch(ev, parameter, lam0, to, direction, step, max_step, min_step, max_points, events,
                stop_on, tol, xtol):
    """Branch switching at a period doubling: the doubled orbit's branch, started along the null
    vector ``(e, P_1 e, ..., -e, -P_1 e, ...)`` built from the eigenvector ``e`` of the multiplier
    ``-1``."""
    o = ev.orbit
    m0, n0 = o.impacts, o.periods
    cont = _Continuation(o.model, o.load, parameter, 2 * m0, 2 * n0, tol)
    z, w = doubling_direction(o)
    U0 = np.append(z, lam0)
    w = np.append(w, 0.0)
    w /= cont.norm(w)
    h = step
    while h >= min_step:
        U1, _ = cont.correct(U0 + h * w, w, U0 + h * w)
        if U1 is not None and float(np.max(np.abs(U1[:-1] - U0[:-1]))) > 1e-3 * h:
            break
        h *= 0.5
    else:
        raise ValueError("branch switching at the period doubling failed: no doubled orbit found")
    t1 = cont.tangent(U1, (U1 - U0) / cont.norm(U1 - U0))
    return _run(cont, U0, None, lam0, to, direction, step, max_step, min_step, max_points, events,
                stop_on, xtol, first=(U1, t1))


def _run(cont, U0, t0, lam0, to, direction, step, max_step, min_step, max_points, events, stop_on,
         xtol, first=None):
    lo, hi = min(lam0, to), max(lam0, to)
    if first is not None:  # a branch born at a period doubling may leave on either side
        lo, hi = lam0 - abs(to - lam0), lam0 + abs(to - lam0)
    points = [U0]
    orbits = [cont.orbit(U0)]
    tests = [_tests(orbits[0])]
    tangents = [t0]
    found: list[BranchEvent] = []
    status = BranchStatus.MAX_POINTS
    h = step
    pending_first = first
    stalled = 0
    while len(points) < max_points:
        Ua, ta = points[-1], tangents[-1]
        if pending_first is not None:
            Ub, tb = pending_first
            pending_first = None
            it = 1
        else:
            Ub = None
            while h >= min_step:
                pred = Ua + h * ta
                final = (pred[-1] - to) * direction > 0 and (Ua[-1] - to) * direction < 0
                if final:
                    Ub, it = cont.correct(Ua + ta * (to - Ua[-1]) / ta[-1], np.eye(Ua.size)[-1],
                                          np.append(Ua[:-1], to))
                else:
                    Ub, it = cont.correct(pred, ta, pred)
                if Ub is not None:
                    ok_dir = True
                    tb = cont.tangent(Ub, ta, cont.last_J) if not final else ta
                    if not final and cont.dot(tb, ta) < 0.8:
                        ok_dir = False
                    dist = cont.norm(Ub - Ua)
                    if ok_dir and dist < 3 * h + 1e-12 and _normalise(cont.problem(Ub[-1]), Ub[:-1]) \
                            is not None:
                        break
                Ub = None
                h *= 0.5
            if Ub is None:
                status = BranchStatus.STEP_TOO_SMALL
                corner = _load_jump(cont, Ua, len(points) - 1)
                if corner is not None:
                    found.append(corner)
                    status = BranchStatus.LOAD_JUMP
                break
        try:
            ob = cont.orbit(Ub)
        except ValueError:
            status = BranchStatus.PARAMETER_RANGE
            break
        points.append(Ub)
        orbits.append(ob)
        tests.append(_tests(ob))
        tangents.append(tb)
        if events:
            new = _detect(cont, points, tangents, tests, orbits, xtol)
            found.extend(new)
            hit = [e for e in new if e.kind in stop_on]
            if hit:
                status = BranchStatus.stopped_at(hit[0].kind)
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
        if stalled >= 8:  # steps stay tiny: an impact running into a jump of the load is a corner
            corner = _load_jump(cont, Ub, len(points) - 1)
            if corner is not None:
                found.append(corner)
                status = BranchStatus.LOAD_JUMP
                break
    P = np.array(points)
    return Branch(parameter=cont.name, values=P[:, -1].copy(), orbits=tuple(orbits),
                  events=tuple(found), status=status, impacts=cont.m, periods=cont.n, _points=P)


def _detect(cont, points, tangents, tests, orbits, xtol):
    """Events between the last two points, located in order along the chord."""
    Ua, Ub = points[-2], points[-1]
    ta = tangents[-2] if tangents[-2] is not None else (Ub - Ua) / cont.norm(Ub - Ua)
    A, B = tests[-2], tests[-1]
    hb = cont.dot(ta, Ub - Ua)
    idx = len(points) - 1
    out = []

    def at(hh):
        if hh == 0.0:
            return Ua
        if hh == hb:
            return Ub
        pred = Ua + hh * ta
        U, _ = cont.correct(pred, ta, pred)
        return U

    def locate(fn):
        def g(hh):
            U = at(hh)
            if U is None:
                raise _LocateError
            return fn(cont.orbit(U, admissibility=fn is _clear or fn is _vmin or fn is _adm))

        try:
            hh = brentq(g, 0.0, hb, xtol=xtol, rtol=4 * np.finfo(float).eps, maxiter=200)
        except (_LocateError, ValueError, RuntimeError):
            return None
        return hh

    def add(kind, hh, crit_fn):
        U = at(hh)
        if U is None:
            return
        o = cont.orbit(U)
        out.append(BranchEvent(kind=kind, parameter=cont.name, value=float(U[-1]), index=idx,
                               orbit=o, multiplier=crit_fn(o), _point=U))

    if A["fold"] * B["fold"] < 0:
        hh = locate(_fold)
        if hh is not None:
            turned = (tangents[-2] is not None and tangents[-1] is not None
                      and tangents[-2][-1] * tangents[-1][-1] < 0)
            add(EventKind.FOLD if turned else EventKind.BRANCH_POINT, hh, lambda o: _nearest(o, 1.0))
    if A["period-doubling"] * B["period-doubling"] < 0:
        hh = locate(_pd)
        if hh is not None:
            add(EventKind.PERIOD_DOUBLING, hh, lambda o: _nearest(o, -1.0))
    if A["pairs"] == B["pairs"] and A["pairs"] and A["neimark-sacker"] * B["neimark-sacker"] < 0:
        hh = locate(_ns)
        if hh is not None:
            U = at(hh)
            o = cont.orbit(U, admissibility=False)
            cpx = o.multipliers[np.abs(o.multipliers.imag) > 1e-8]
            if cpx.size and np.min(np.abs(np.abs(cpx) - 1.0)) < 1e-6:
                add(EventKind.NEIMARK_SACKER, hh, lambda o: _nearest_circle(o))
    grazes = []  # chord positions of the located grazing points
    if np.isfinite(A["grazing"]) and np.isfinite(B["grazing"]) and A["grazing"] * B["grazing"] < 0:
        hh = locate(_clear)
        if hh is not None:
            add(EventKind.GRAZING, hh, lambda o: complex(math.nan, math.nan))
            grazes.append(hh)
    if A["impact"] * B["impact"] < 0:
        hh = locate(_vmin)
        if hh is not None:
            add(EventKind.GRAZING, hh, lambda o: complex(math.nan, math.nan))
            grazes.append(hh)
    if A["admissible"] != B["admissible"] and not _explained(at, cont, hb, grazes, A["admissible"]):
        # e.g. sticking at R = 0, or a grazing the clearance did not show
        hh = _bisect_flag(at, cont, hb, xtol)
        if hh is not None:
            add(EventKind.ADMISSIBILITY, hh, lambda o: complex(math.nan, math.nan))
    out.sort(key=lambda e: cont.dot(ta, e._point - Ua))
    return out


def _load_jump(cont, U, index):
    """Where an impact of the branch reaches a jump of a piecewise-constant load (the flow is not
    differentiable there, and the branch has a corner, e.g. the hydraulic existence edge, Fig. 8):
    Newton on ``F(u, lambda) = 0`` with the impact time nearest a jump pinned to it. Returns a
    ``"load-jump"`` event, or None when no impact is near a jump or Newton fails."""
    load = cont.problem(U[-1]).load
    if not isinstance(load, PiecewiseConstantLoad):
        return None
    K = 2 * (cont.model0.n_modes + 1)
    t = U[:-1].reshape(cont.m, K)[:, 0]

    br = load.breaks
    rel = np.mod(t[:, None] - br[None, :] + math.pi, TWO_PI) - math.pi
    j, b = (int(i) for i in np.unravel_index(int(np.argmin(np.abs(rel))), rel.shape))
    if abs(rel[j, b]) > 1e-3:
        return None
    shift = float(t[j] - rel[j, b] - br[b])  # a multiple of 2 pi

    def pinned(V):  # the impact time held on the jump, which moves with the parameter
        V = np.array(V, dtype=float)
        V[K * j] = cont.problem(V[-1]).load.breaks[b] + shift
        return V

    keep = np.ones(U.size, dtype=bool)
    keep[K * j] = False
    V = pinned(U)
    for _ in range(30):
        try:
            F, J, _ = cont.FJ(V)
            e = np.zeros(V.size)
            e[-1] = 1e-7 * max(1.0, abs(V[-1]))
            try:
                J[:, -1] = (cont.F(pinned(V + e)) - cont.F(pinned(V - e))) / (2 * e[-1])
            except ValueError:
                J[:, -1] = (cont.F(pinned(V + e)) - F) / e[-1]
        except ValueError:
            return None
        try:
            dV = np.linalg.solve(J[:, keep], F)
        except np.linalg.LinAlgError:
            return None
        V[keep] -= dV
        try:
            V = pinned(V)
        except ValueError:
            return None
        if float(np.max(np.abs(dV))) <= cont.tol * max(1.0, float(np.max(np.abs(V)))):
            try:
                o = cont.orbit(V)
            except ValueError:
                return None
            return BranchEvent(kind=EventKind.LOAD_JUMP, parameter=cont.name, value=float(V[-1]), index=index,
                               orbit=o, multiplier=complex(math.nan, math.nan), _point=V)
    return None


class _LocateError(Exception):
    pass


def _fold(o):
    return float(np.prod(1.0 - o.multipliers).real)


def _pd(o):
    return float(np.prod(1.0 + o.multipliers).real)


def _ns(o):
    mu = o.multipliers
    cpx = mu[mu.imag > 1e-10 * np.maximum(1.0, np.abs(mu))]
    return float(np.prod(np.abs(cpx) ** 2 - 1.0)) if cpx.size else 1.0


def _clear(o):
    return -float(o.clearance)


def _vmin(o):
    return float(np.min(o.impact_velocities))


def _adm(o):
    return 1.0 if o.admissible else -1.0


def _nearest(o, target):
    mu = o.multipliers
    return complex(mu[int(np.argmin(np.abs(mu - target)))])


def _nearest_circle(o):
    mu = o.multipliers
    cpx = mu[np.abs(mu.imag) > 1e-8]
    return complex(cpx[int(np.argmin(np.abs(np.abs(cpx) - 1.0)))]) if cpx.size else complex(math.nan)


def _explained(at, cont, hb, grazes, before):
    """Whether a located grazing point is where the admissibility flag changes: the flag just
    before it (along the chord) is the first point's, just after it the other."""
    for hh in grazes:
        d = 1e-6 * abs(hb)
        Ua, Ub = at(hh - d if hb > 0 else hh + d), at(hh + d if hb > 0 else hh - d)
        if Ua is None or Ub is None:
            continue
        if cont.orbit(Ua).admissible == before and cont.orbit(Ub).admissible != before:
            return True
    return False


def _bisect_flag(at, cont, hb, xtol):
    a, b = 0.0, hb
    fa = cont.orbit(at(a)).admissible
    while abs(b - a) > xtol:
        mid = 0.5 * (a + b)
        U = at(mid)
        if U is None:
            return None
        if cont.orbit(U).admissible == fa:
            a = mid
        else:
            b = mid
    return 0.5 * (a + b)
