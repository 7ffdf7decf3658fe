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

from .._shared.forcing import dispatch
from .._shared.status import BranchStatus, EventKind
from .._shared.threads import single_threaded_blas
from ..orbits.driven import check_orbit
from ..orbits.multi_impact import Z_TIME
from ..orbits.orbit import PeriodicOrbit
from ..orbits.segments import (
    SegmentProblem,
    build_orbit,
    doubling_direction,
    halves_gap,
    normalise,
    same_orbit,
    unknowns_from,
)
from .branch import Branch, BranchEvent
from .driven import checked_events, continue_driven, doubled_first_points, first_chord_tests
from .engine import ContinuationSettings, _Engine, _settings
from .parameters import _check_parameter, _target, parameter_value, with_parameter

__all__ = ["continue_orbit", "EVENT_KINDS"]

TWO_PI = 2.0 * math.pi

#: Event kinds, in the order they are reported.
EVENT_KINDS = tuple(EventKind)

# ------------------------------------------------------------------------------------------------
# the augmented problem of a branch: the segment problem in (u, lambda)
# ------------------------------------------------------------------------------------------------
class _OrbitProblem:
    """The segment problem of :func:`find_orbit` in ``U = (u, lambda)``, for the engine
    (:mod:`impactbar.continuation.engine`), with the branch's event detection."""

    def __init__(self, model, load, name, m, n, tol, *, events=True, stop_on=(), xtol=1e-10,
                 doubled=False):
        self.model0, self.load0, self.name, self.m, self.n, self.tol = model, load, name, m, n, tol
        self.events, self.stop_on, self.xtol, self.doubled = events, stop_on, xtol, doubled
        self._cache = {}
        size = SegmentProblem(model, load, m, n).size  # (t, state) per impact
        # weighted arclength: the state's squared norm is averaged over its components (as AUTO
        # does), so the parameter keeps its share however many modes and impacts there are
        self.W = np.append(np.full(size, 1.0 / size), 1.0)

    def segments(self, lam):
        key = float(lam)
        p = self._cache.get(key)
        if p is None:
            model, load = with_parameter(self.model0, self.load0, self.name, key)
            p = SegmentProblem(model, load, self.m, self.n)
            if len(self._cache) > 16:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = p
        return p

    def F(self, U):
        F, _, _ = self.segments(U[-1]).evaluate(U[:-1], jacobian=False)
        return F

    def FJ(self, U, F_lam=None):
        """Residual, the full Jacobian ``[F_u, F_lam]`` and ``F_lam``, by central differences
        unless given (Newton's corrector reuses the one of its first iteration)."""
        u, lam = U[:-1], U[-1]
        F, DF, _ = self.segments(lam).evaluate(u)
        if F_lam is not None:
            return F, np.column_stack((DF, F_lam)), F_lam
        h = 1e-6 * max(1.0, abs(lam))
        try:
            Fp, _, _ = self.segments(lam + h).evaluate(u, jacobian=False)
            Fm, _, _ = self.segments(lam - h).evaluate(u, jacobian=False)
            Fl = (Fp - Fm) / (2 * h)
        except ValueError:  # at the edge of the parameter's range: one-sided
            try:
                Fp, _, _ = self.segments(lam + h).evaluate(u, jacobian=False)
                Fl = (Fp - F) / h
            except ValueError:
                Fm, _, _ = self.segments(lam - h).evaluate(u, jacobian=False)
                Fl = (F - Fm) / h
        return F, np.column_stack((DF, Fl)), Fl

    def orbit(self, U, admissibility=True):
        """The orbit at a branch point, its first impact time brought into ``[0, 2 pi)``."""
        p = self.segments(U[-1])
        u = normalise(p, U[:-1])
        return build_orbit(p, U[:-1] if u is None else u, admissibility=admissibility)

    def acceptable(self, U):
        """The impact times stay in order (and apart by the contact windows); on a branch born at
        a period doubling, the orbit stays doubled (a step onto the undoubled orbit traversed
        twice, which crosses the branch at the doubling, is refused)."""
        p = self.segments(U[-1])
        if self.doubled and same_orbit(U[:-1], U[:-1], p):
            return False
        return normalise(p, U[:-1]) is not None

    def after_point(self, engine, points, tangents, orbits):
        """The events between the last two points, and the status to stop with (``stop_on``)."""
        if not self.events:
            return [], None
        tests = first_chord_tests([_tests(o) for o in orbits[-2:]], self.doubled, len(points))
        new = _detect(engine, points, tangents, tests, orbits, self.xtol)
        hit = [e for e in new if e.kind in self.stop_on]
        return new, (BranchStatus.stopped_at(hit[0].kind) if hit else None)

    def corner(self, engine, U, index):
        """A load-jump event where the steps fail or stay tiny (:func:`_load_jump`)."""
        return _load_jump(self, U, index)


def _tests(orbit: PeriodicOrbit):
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


def continue_orbit(orbit, parameter: str, to: float, *, settings: ContinuationSettings | None = None,
                   step: float | None = None, max_step: float | None = None,
                   min_step: float | None = None, max_points: int | None = None, events: bool = True,
                   stop_on=(), tol: float | None = None, xtol: float = 1e-10) -> Branch:
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
    orbit : PeriodicOrbit, MultiImpactOrbit, BranchEvent or DrivenOrbit
        The start. A ``"period-doubling"`` :class:`BranchEvent` starts the doubled branch (``2 m``
        impacts in ``2 n`` periods) from the event, along the bifurcating direction (branch
        switching). A :class:`~impactbar.DrivenOrbit` (an orbit under a :class:`~impactbar.Drive`,
        unknown period) is followed in one of the drive's parameters (the valve's ``"stroke"``,
        ``"ret"``, ``"switch_out"``, ``"delay"``; the oil circuit's), ``"R"``, ``"d"``, ``"s"`` or the
        impact law's own (on the rock ``"rock.k"``, ...), with the grazing of a
        switching surface among the events (theory §10;
        :func:`impactbar.continuation.driven.continue_driven`).
    parameter : str
        One of ``"p0"``, ``"pk"`` (a :class:`CosineLoad`), ``"q"``, ``"kappa"`` (a
        :class:`SquareWaveLoad`), ``"R"``, ``"d"``, ``"s"`` (the :class:`BarModel`), and the
        impact law's own (:attr:`~impactbar.laws.ContactLaw.parameters`): under the rod-rock law
        ``"rock.k"``, ``"rock.k_u"``, ``"bit_mass"``, ``"feed"`` (theory §4d).
    to : float
        Target value; the branch stops there, or where it leaves the range between the start and
        ``to`` after a fold. A branch started at a period doubling may bifurcate to either side:
        it is followed while the parameter stays within ``|to - start|`` of the doubling.
    settings : ContinuationSettings, optional
        Steps, point limit and Newton tolerance (the same object :func:`continue_bifurcation`
        takes); default ``ContinuationSettings()``.
    step, max_step, min_step, max_points, tol : optional
        Override the fields of ``settings`` of the same names (see
        :class:`ContinuationSettings`: arclength steps in a weighted norm, defaults
        ``|to - start| / 50``, ``/ 10`` and ``1e-9`` times that; at most 2000 points; relative
        Newton tolerance ``1e-11``).
    events : bool
        Detect and locate events.
    stop_on : iterable of str
        Event kinds at which to stop (e.g. ``("grazing",)``), from :class:`EventKind`.
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
        if orbit.kind != EventKind.PERIOD_DOUBLING:
            raise ValueError(f"a BranchEvent start must be a period doubling; got {str(orbit.kind)!r}")
        switch = orbit
        base = check_orbit(orbit.orbit, "orbit.orbit")
    else:
        base = check_orbit(orbit)
    settings = _settings(settings, step=step, max_step=max_step, min_step=min_step,
                         max_points=max_points, tol=tol)
    return dispatch(CONTINUATIONS, base.load, "orbit's load")(orbit, base, switch, parameter, to, settings,
                                                             events, stop_on, xtol)


def _continue_drive(orbit, base, switch, parameter, to, settings, events, stop_on, xtol) -> Branch:
    """:func:`continue_orbit` under a drive: an autonomous orbit of unknown period (theory §10)."""
    return continue_driven(orbit, parameter, to, _detect, events=events, stop_on=stop_on, xtol=xtol,
                             settings=settings)


def _continue_load(orbit, base, switch, parameter, to, settings, events, stop_on, xtol) -> Branch:
    """:func:`continue_orbit` under a periodic load: the segment problem of :func:`find_orbit` with
    the parameter appended (theory §7)."""
    model, load = base.model, base.load
    _check_parameter(model, load, parameter, continuation=True)
    lam0 = parameter_value(model, load, parameter)
    to = _target(parameter, lam0, to, model, load)
    steps = settings.steps(abs(to - lam0))
    stop_on, xtol = checked_events(stop_on, xtol)
    direction = 1.0 if to > lam0 else -1.0
    m, n = (2 * base.impacts, 2 * base.periods) if switch is not None else (base.impacts, base.periods)
    problem = _OrbitProblem(model, load, parameter, m, n, settings.tol, events=events,
                            stop_on=stop_on, xtol=xtol, doubled=switch is not None)
    engine = _Engine(problem, settings.tol)
    lo, hi = min(lam0, to), max(lam0, to)
    with single_threaded_blas():
        if switch is not None:
            lo, hi = lam0 - abs(to - lam0), lam0 + abs(to - lam0)  # it may leave on either side
            for U0, first in _switch(engine, switch, lam0, steps):
                P, orbits, found, status = engine.march(U0, None, to, direction, lo, hi, steps,
                                                        settings.max_points, first=first)
                if len(orbits) > 2 or status != BranchStatus.STEP_TOO_SMALL:
                    break  # every point past the doubling is doubled (``acceptable``)
            else:
                raise ValueError("branch switching at the period doubling failed: no doubled "
                                 "branch along any direction of a multiplier near -1")
        else:
            U0, t0 = _start(engine, base, lam0, direction)
            P, orbits, found, status = engine.march(U0, t0, to, direction, lo, hi, steps,
                                                    settings.max_points)
    return Branch(parameter=parameter, values=P[:, -1].copy(), orbits=orbits, events=tuple(found),
                  status=status, impacts=m, periods=n, _points=P)


#: the solver of :func:`continue_orbit` for each forcing family (the one place it is chosen)
CONTINUATIONS = {"load": _continue_load, "drive": _continue_drive}


def _start(engine, base, lam0, direction):
    """The start point on the branch and its tangent towards ``to``."""
    problem = engine.problem
    u0 = unknowns_from(problem.segments(lam0), base.impact_times, base.states_after_impact)
    U0 = np.append(u0, lam0)
    F0, J0, _ = problem.FJ(U0)
    if float(np.max(np.abs(F0))) <= 1e-11 * max(1.0, float(np.max(np.abs(U0)))):
        engine.last_J = J0  # already a solution (at a fold, Newton at fixed parameter is singular)
    else:
        U0, _ = engine.correct(U0, np.eye(U0.size)[-1], U0)
        if U0 is None:
            raise ValueError("orbit: Newton at the start value did not converge; is it a solution?")
    # the tangent: the null vector of [F_u, F_lam] (by SVD: also at a fold), towards `to`
    _, _, Vh = np.linalg.svd(engine.last_J)
    t0 = Vh[-1]
    t0 /= engine.norm(t0)
    if t0[-1] * direction < 0:
        t0 = -t0
    return U0, t0


def _switch(engine, ev, lam0, steps):
    """Branch switching at a period doubling: starts of the doubled orbit's branch, each along a
    null vector ``(e, P_1 e, ..., -e, -P_1 e, ...)`` built from the eigenvector ``e`` of a real
    multiplier near ``-1`` (the nearest first, then the others within 0.1 of it; each both ways).

    Yields ``(U0, (U1, t1))``: the doubling point, and the first point of the doubled branch with
    its tangent. A first point counts only if it is doubled: its two halves differ by at least a
    tenth of its distance from the doubling (on the doubled branch the departure is along the
    antisymmetric null vector; on the undoubled orbit traversed twice the halves coincide)."""
    mu = ev.orbit.multipliers
    near = np.abs(mu + 1.0)
    real = np.abs(mu.imag) <= 1e-9 * np.maximum(1.0, np.abs(mu))
    ranks = [r for r, i in enumerate(np.argsort(near, kind="stable")) if r == 0 or
             (real[i] and near[i] <= 0.1)]
    def gap(U):
        return halves_gap(U[:-1], engine.problem.segments(U[-1]))

    for rank in ranks:
        z, w = doubling_direction(ev.orbit, rank)
        U0 = np.append(z, lam0)
        w = np.append(w, 0.0)
        w /= engine.norm(w)
        for first in doubled_first_points(engine, U0, w, steps, gap):
            yield U0, first


def _detect(engine, points, tangents, tests, orbits, xtol):
    """Events between the last two points, located in order along the chord."""
    Ua, Ub = points[-2], points[-1]
    ta = tangents[-2] if tangents[-2] is not None else (Ub - Ua) / engine.norm(Ub - Ua)
    A, B = tests[-2], tests[-1]
    hb = engine.dot(ta, Ub - Ua)
    idx = len(points) - 1
    out = []

    def at(hh):
        if hh == 0.0:
            return Ua
        if hh == hb:
            return Ub
        pred = Ua + hh * ta
        U, _ = engine.correct(pred, ta, pred)
        return U

    def locate(fn):
        def g(hh):
            U = at(hh)
            if U is None:
                raise _LocateError
            return fn(engine.orbit(U, admissibility=fn is _clear or fn is _vmin or fn is _adm))

        try:
            hh = brentq(g, 0.0, hb, xtol=xtol, rtol=4 * np.finfo(float).eps, maxiter=200)
        except (_LocateError, ValueError, RuntimeError):
            return None
        return hh

    def add(kind, hh, crit_fn):
        U = at(hh)
        if U is None:
            return
        o = engine.orbit(U)
        out.append(BranchEvent(kind=kind, parameter=engine.problem.name, value=float(U[-1]), index=idx,
                               orbit=o, multiplier=crit_fn(o), _point=U))

    def confirmed(hh, fn, before, after, target):
        """A located sign change of ``det(I -+ P)`` is an event only where a real multiplier
        crosses ``target`` there: not through a pole (the test function's magnitude at the
        located point above both ends', e.g. the saltation term ``~1/v`` at a grazing impact)."""
        U = at(hh)
        if U is None:
            return False
        o = engine.orbit(U, admissibility=False)
        if abs(fn(o)) > max(abs(before), abs(after)):
            return False  # a pole: the sign changes through infinity
        return _crosses(o, target, lambda d: _side(at, engine, hb, hh, d, xtol, target))

    if A["fold"] * B["fold"] < 0:
        hh = locate(_fold)
        if hh is not None and confirmed(hh, _fold, A["fold"], B["fold"], 1.0):
            turned = (tangents[-2] is not None and tangents[-1] is not None
                      and tangents[-2][-1] * tangents[-1][-1] < 0)
            add(EventKind.FOLD if turned else EventKind.BRANCH_POINT, hh, lambda o: _nearest(o, 1.0))
    if A["period-doubling"] * B["period-doubling"] < 0:
        hh = locate(_pd)
        if hh is not None and confirmed(hh, _pd, A["period-doubling"], B["period-doubling"], -1.0):
            add(EventKind.PERIOD_DOUBLING, hh, lambda o: _nearest(o, -1.0))
    if A["pairs"] == B["pairs"] and A["pairs"] and A["neimark-sacker"] * B["neimark-sacker"] < 0:
        hh = locate(_ns)
        if hh is not None:
            U = at(hh)
            o = engine.orbit(U, admissibility=False)
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
    if A["admissible"] != B["admissible"] and not _explained(at, engine, hb, grazes, A["admissible"]):
        # e.g. sticking at R = 0, or a grazing the clearance did not show
        hh = _bisect_flag(at, engine, hb, xtol)
        if hh is not None:
            add(EventKind.ADMISSIBILITY, hh, lambda o: complex(math.nan, math.nan))
    out.sort(key=lambda e: engine.dot(ta, e._point - Ua))
    return out


def _load_jump(problem, U, index):
    """Where an impact of the branch reaches a jump of a piecewise-constant load (the flow is not
    differentiable there, and the branch has a corner, e.g. the hydraulic existence edge, Fig. 8):
    Newton on ``F(u, lambda) = 0`` with the impact time nearest a jump pinned to it. Returns a
    ``"load-jump"`` event, or None when no impact is near a jump or Newton fails."""
    pieces = problem.segments(U[-1]).load.abilities.pieces
    if pieces is None:  # a continuous load: no jump
        return None
    K = problem.segments(U[-1]).B  # unknowns per impact
    t = U[:-1].reshape(problem.m, K)[:, Z_TIME]

    br = pieces[0]
    rel = np.mod(t[:, None] - br[None, :] + math.pi, TWO_PI) - math.pi
    j, b = (int(i) for i in np.unravel_index(int(np.argmin(np.abs(rel))), rel.shape))
    if abs(rel[j, b]) > 1e-3:
        return None
    shift = float(t[j] - rel[j, b] - br[b])  # a multiple of 2 pi

    def pinned(V):  # the impact time held on the jump, which moves with the parameter
        V = np.array(V, dtype=float)
        V[K * j] = problem.segments(V[-1]).load.abilities.pieces[0][b] + shift
        return V

    keep = np.ones(U.size, dtype=bool)
    keep[K * j] = False
    V = pinned(U)
    for _ in range(30):
        try:
            F, J, _ = problem.FJ(V)
            e = np.zeros(V.size)
            e[-1] = 1e-7 * max(1.0, abs(V[-1]))
            try:
                J[:, -1] = (problem.F(pinned(V + e)) - problem.F(pinned(V - e))) / (2 * e[-1])
            except ValueError:
                J[:, -1] = (problem.F(pinned(V + e)) - F) / e[-1]
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
        if float(np.max(np.abs(dV))) <= problem.tol * max(1.0, float(np.max(np.abs(V)))):
            try:
                o = problem.orbit(V)
            except ValueError:
                return None
            return BranchEvent(kind=EventKind.LOAD_JUMP, parameter=problem.name, value=float(V[-1]),
                               index=index, orbit=o, multiplier=complex(math.nan, math.nan), _point=V)
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


#: A located fold or period doubling has a real multiplier this close to ``+1`` or ``-1``, or one
#: that crosses it within the location's bracket (:func:`_crosses`).
CRITICAL_TOL = 1e-6


def _real_offset(o, target):
    """The real multiplier nearest ``target`` minus ``target`` (``inf`` when none is real)."""
    mu = o.multipliers
    real = mu[np.abs(mu.imag) <= 1e-9 * np.maximum(1.0, np.abs(mu))].real
    if real.size == 0:
        return math.inf
    return float(real[int(np.argmin(np.abs(real - target)))] - target)


def _crosses(o, target, side):
    """Whether a real multiplier of the located orbit ``o`` is at ``target``: within
    :data:`CRITICAL_TOL`, or changing sides of it between the orbits ``side(-1)`` and ``side(+1)``
    just before and after the located point (a steep multiplier located to a coarse ``xtol``)."""
    off = _real_offset(o, target)
    if abs(off) <= CRITICAL_TOL:
        return True
    if not abs(off) < 0.1:
        return False
    a, b = side(-1.0), side(1.0)
    if a is None or b is None:
        return False
    oa, ob = _real_offset(a, target), _real_offset(b, target)
    return max(abs(oa), abs(ob)) < 0.1 and oa * ob <= 0.0


def _side(at, engine, hb, hh, d, xtol, target):
    """The orbit at ``2 xtol`` from the located point ``hh`` along the chord, before it (``d < 0``)
    or after it (``d > 0``)."""
    step = max(2.0 * xtol, 1e-12 * abs(hb)) * math.copysign(1.0, hb) * d
    U = at(min(max(hh + step, min(0.0, hb)), max(0.0, hb)))
    return None if U is None else engine.orbit(U, admissibility=False)


def _nearest(o, target):
    mu = o.multipliers
    return complex(mu[int(np.argmin(np.abs(mu - target)))])


def _nearest_circle(o):
    mu = o.multipliers
    cpx = mu[np.abs(mu.imag) > 1e-8]
    return complex(cpx[int(np.argmin(np.abs(np.abs(cpx) - 1.0)))]) if cpx.size else complex(math.nan)


def _explained(at, engine, hb, grazes, before):
    """Whether a located grazing point is where the admissibility flag changes: the flag just
    before it (along the chord) is the first point's, just after it the other."""
    for hh in grazes:
        d = 1e-6 * abs(hb)
        Ua, Ub = at(hh - d if hb > 0 else hh + d), at(hh + d if hb > 0 else hh - d)
        if Ua is None or Ub is None:
            continue
        if engine.orbit(Ua).admissible == before and engine.orbit(Ub).admissible != before:
            return True
    return False


def _bisect_flag(at, engine, hb, xtol):
    a, b = 0.0, hb
    fa = engine.orbit(at(a)).admissible
    while abs(b - a) > xtol:
        mid = 0.5 * (a + b)
        U = at(mid)
        if U is None:
            return None
        if engine.orbit(U).admissible == fa:
            a = mid
        else:
            b = mid
    return 0.5 * (a + b)
