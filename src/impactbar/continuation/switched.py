"""Continuation of periodic motions under a drive (theory §10).

The augmented problem for the engine (:mod:`impactbar.continuation.engine`) is the drive's
periodic-orbit problem (:func:`impactbar.orbits.switched.orbit_problem`: the drive's own, e.g. the
valve's segment problem, unknowns the state after the impact and the free flight times ``h1``,
``h3``; or the generic shooting problem) with the continued parameter appended: any continuable
parameter of the problem (:func:`impactbar.parameters.parameters`: the drive's, the valve's
``stroke``, ``ret``, ``switch_out``, ``delay``; the bar's ``R``, ``d``, ``s``; its impact law's).
The events are those of :func:`impactbar.continue_orbit` (fold, period doubling, Neimark-Sacker, an
impact velocity through 0, a change of admissibility), confirmed by the multipliers of the
autonomous map (the trivial one along the flow set apart), and the grazing of a switching surface:
the gap's rate at a switch crossing going through 0.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.optimize import brentq

from .._shared.parameters import check_continuable, parameter_value, with_parameter
from .._shared.status import BranchStatus, EventKind
from .._shared.validate import check_real
from ..orbits.switched import SwitchedOrbit, orbit_of, orbit_problem
from .branch import Branch, BranchEvent
from .engine import ContinuationSettings, _Engine, _settings
from .parameters import _target

__all__ = ["continue_switched"]

EVENT_KINDS = tuple(EventKind)

#: the chord steps of a corrector (``chord="all"``) before the Jacobian is taken again at the iterate
CHORD_STEPS = 6


class _SwitchedProblem:
    """The periodic-orbit problem of a drive in ``U = (X, lambda)``, for the engine.

    Where the flights are integrated: ``forward_lambda``, ``F_lam`` a forward difference (else the
    central difference of before); ``chord``, the first corrector step after an orbit with that
    orbit's Jacobian (a chord step; else the full Newton step of before), or with ``"all"`` every
    step (the residuals by plain flights; the Jacobian taken again after ``CHORD_STEPS`` steps
    without a new orbit). Set by :func:`continue_switched`."""

    def __init__(self, model, drive, name, detect, *, events=True, stop_on=(), xtol=1e-10, impacts=1,
                 doubled=False, base=None, forward_lambda=True, chord=True):
        self.model0, self.drive0, self.name, self.detect = model, drive, name, detect
        self.forward_lambda, self.chord = forward_lambda, chord
        self.events, self.stop_on, self.xtol = events, stop_on, xtol
        self.m, self.doubled, self.base = impacts, doubled, base
        self.pair = functools.lru_cache(maxsize=16)(self._pair)
        self._chord = None  # the last orbit's F_u, for the next corrector's first step
        self._uses = 0  # the chord steps since it was taken
        start = self.pair(float(parameter_value(model, drive, name)))[2]
        self.flights = start.positive
        self.W = np.append(np.full(start.size, 1.0 / start.size), 1.0)

    def _pair(self, lam: float):
        """The model, drive and orbit problem at the parameter value ``lam``."""
        model, drive = with_parameter(self.model0, self.drive0, self.name, lam)
        problem = orbit_problem(model, drive, self.m)
        if self.base is not None:
            problem.adopt(self.base)
        return model, drive, problem

    def F(self, U):
        return self.pair(float(U[-1]))[2].value(U[:-1])

    def FJ(self, U, F_lam=None):
        """Residual, the Jacobian ``[F_u, F_lam]`` (``F_u`` the problem's, one that only steers the
        corrector where the problem has one: ``ShootingProblem.steering_residual``, Magnus' coarser
        steps; ``F_lam`` by central differences unless given, one-sided at the edge of the
        parameter's range) and ``F_lam``.

        Where the flights are integrated (a drive whose flights carry the variational equations,
        the oil circuit) ``F_lam`` is a forward difference from ``F`` (one flight instead of two; its
        error ``O(h)``, ``h = 1e-6``, only slows the corrector's convergence, whose residual is
        exact, and tilts the predictor's tangent by as much)."""
        problem = self.pair(float(U[-1]))[2]
        every = self.chord == "all"
        chord = self._chord
        if not every:
            self._chord = None
        if chord is not None and (F_lam is None or every) and self._uses < CHORD_STEPS:
            F, DF = problem.value(U[:-1]), chord  # the last orbit's Jacobian: a chord step
            self._uses += 1
        else:
            # (a Jacobian that only steers: Magnus' coarser steps where the flights are integrated)
            F, DF = getattr(problem, "steering_residual", problem.residual)(U[:-1])
            if every and getattr(problem, "variational", False):
                self._chord, self._uses = DF, 0
        if F_lam is None:
            h = 1e-6 * max(1.0, abs(U[-1]))
            sides = []
            for sign in (1.0, -1.0):
                if sign < 0.0 and self.forward_lambda and getattr(problem, "variational", False) and \
                        sides[0] is not None:
                    sides.append(None)
                    break
                try:
                    sides.append(self.F(np.append(U[:-1], U[-1] + sign * h)))
                except ValueError:
                    sides.append(None)
            up, down = sides
            if up is None and down is None:
                raise ValueError(f"{self.name}: no admissible value within {h:g} of {U[-1]}")
            F_lam = ((up if up is not None else F) - (down if down is not None else F)) / (
                h * ((up is not None) + (down is not None)))
        return F, np.column_stack((DF, F_lam)), F_lam

    def orbit(self, U, admissibility=True):
        """The orbit at ``U``. Where the flights are integrated, the Jacobian of its residual (from
        the variational flight the orbit's data came from, remembered by the problem: no flight
        more; the drive's own steps, as the multipliers') is kept for the first step of the next
        corrector (a chord step: the residual by a plain flight, ``F_u`` the last orbit's), which the
        steering Jacobian's steps then finish."""
        problem = self.pair(float(U[-1]))[2]
        ob = orbit_of(problem, U[:-1])
        if self.chord and getattr(problem, "variational", False):
            try:
                self._chord = problem.residual(U[:-1])[1]
            except ValueError:
                self._chord = None
            self._uses = 0
        return ob

    def acceptable(self, U):
        """Positive flight times; on a branch started at a period doubling, halves that differ
        (else the corrector fell back onto the one-impact orbit traversed twice)."""
        ok = bool(np.all(U[self.flights] > 0.0))
        return ok and (not self.doubled or _halves_gap(U) > 1e-7 * max(1.0, float(np.max(np.abs(U)))))

    def after_point(self, engine, points, tangents, orbits):
        if not self.events:
            return [], None
        tests = first_chord_tests([_tests(o) for o in orbits[-2:]], self.doubled, len(points))
        new = self.detect(engine, points, tangents, tests, orbits, self.xtol)
        graze = _switch_grazing(engine, points, tangents, orbits, self.xtol)
        borders = _borders(engine, points, tangents, orbits, self.xtol)
        if graze is not None or borders:
            new += ([graze] if graze is not None else []) + borders
            Ua = points[-2]
            ta = tangents[-2] if tangents[-2] is not None else points[-1] - Ua
            new.sort(key=lambda e: engine.dot(ta, e._point - Ua))
        hit = [e for e in new if e.kind in self.stop_on]
        return new, (BranchStatus.stopped_at(hit[0].kind) if hit else None)

    def corner(self, engine, U, index):
        return None


def first_chord_tests(tests: list, doubled: bool, points: int) -> list:
    """The test functions at the last two points of a branch, ``tests``, with the fold test of a
    doubled branch's first point replaced by its second's: that point is the parent's period
    doubling, where the doubled orbit has the multiplier ``(-1)^2 = +1``, so ``det(I - P)`` is zero
    there up to rounding and its sign is no crossing (the event is the parent's period doubling,
    reported on its branch; theory §7)."""
    if doubled and points == 2:
        tests[0] = dict(tests[0], fold=tests[1]["fold"])
    return tests


def _tests(o: SwitchedOrbit) -> dict:
    """The test functions of :func:`impactbar.continuation.core._detect` at a switched orbit (no
    clearance: the grazing of the stop between impacts shows in the admissibility flag)."""
    mu = o.multipliers
    cpx = mu[mu.imag > 1e-10 * np.maximum(1.0, np.abs(mu))]
    ns = float(np.prod(np.abs(cpx) ** 2 - 1.0)) if cpx.size else 1.0
    return {"fold": float(np.prod(1.0 - mu).real), "period-doubling": float(np.prod(1.0 + mu).real),
            "neimark-sacker": ns, "pairs": int(cpx.size),
            "grazing": math.nan, "impact": o.impact_velocity, "admissible": o.admissible}


def _locate(engine, points, tangents, value, xtol):
    """The point where ``value(orbit)`` changes sign between the last two points, by Brent's method
    along the chord (each trial point corrected onto the branch); ``None`` where it cannot be
    located."""
    Ua, Ub = points[-2], points[-1]
    ta = tangents[-2] if tangents[-2] is not None else (Ub - Ua) / engine.norm(Ub - Ua)
    hb = engine.dot(ta, Ub - Ua)
    found = {}

    def g(hh):
        pred = Ua + hh * ta
        U, _ = engine.correct(pred, ta, pred)
        if U is None:
            raise ValueError("no point")
        found[hh] = U
        return value(engine.orbit(U))

    try:
        hh = brentq(g, 0.0, hb, xtol=xtol, rtol=4 * np.finfo(float).eps, maxiter=200) if hb else None
    except (ValueError, RuntimeError):
        return None
    if hh is None:
        return None
    U = found.get(hh)
    if U is None:
        g(hh)
        U = found[hh]
    return U


def _switch_grazing(engine, points, tangents, orbits, xtol):
    """A grazing of the switching surface between the last two points: the gap's rate at the
    switch crossing changes sign; located by Brent's method along the chord (as the other events)."""
    a, b = orbits[-2].switch_velocity, orbits[-1].switch_velocity
    if not a * b < 0.0:
        return None
    U = _locate(engine, points, tangents, lambda o: o.switch_velocity, xtol)
    if U is None:
        return None
    return BranchEvent(kind=EventKind.GRAZING, parameter=engine.problem.name, value=float(U[-1]),
                       index=len(points) - 1, orbit=engine.orbit(U), multiplier=complex(math.nan, math.nan),
                       _point=U)


def border_tests(o) -> dict:
    """The drive's border-collision tests at a switched orbit (:meth:`~impactbar.Drive.border_tests`
    over the flights of its period); ``{}`` for a drive without them."""
    problem = o.problem
    if not hasattr(problem, "flights"):
        return {}
    return o.drive.border_tests(problem.flights(problem.unknowns(o)))


def _borders(engine, points, tangents, orbits, xtol) -> list:
    """The drive's border collisions between the last two points (a test of
    :func:`border_tests` through 0), each located by Brent's method along the chord."""
    a, b = border_tests(orbits[-2]), border_tests(orbits[-1])
    out = []
    for name in a:
        if name in b and a[name] * b[name] < 0.0:
            U = _locate(engine, points, tangents, lambda o, name=name: border_tests(o)[name], xtol)
            if U is not None:
                out.append(BranchEvent(kind=EventKind.BORDER_COLLISION, parameter=engine.problem.name,
                                       value=float(U[-1]), index=len(points) - 1, orbit=engine.orbit(U),
                                       multiplier=complex(math.nan, math.nan), _point=U, surface=name))
    return out


def checked_events(stop_on, xtol: float) -> tuple[tuple, float]:
    """``stop_on`` as a tuple of event kinds and ``xtol`` in ``(0, 1e-2]``, checked (a ValueError
    names the argument)."""
    xtol = check_real("xtol", xtol, lo=0.0, lo_open=True, hi=1e-2)
    stop_on = tuple(stop_on)
    for k in stop_on:
        if k not in EVENT_KINDS:
            raise ValueError(f"stop_on must hold event kinds from {EVENT_KINDS}; got {k!r}")
    return stop_on, xtol


def _halves_gap(U) -> float:
    """Largest difference between the two halves of a doubled point's unknowns (its parameter
    apart)."""
    u = U[:-1]
    n = u.size // 2
    return float(np.max(np.abs(u[:n] - u[n:])))


def _doubled_starts(engine, ev, steps):
    """Branch switching at a period doubling of a switched orbit: the doubling point as a
    two-impact solution ``(X, X, lambda)`` and the first point of the period-2 branch, along the
    null vector of the doubled problem's ``F_u`` (antisymmetric between the halves: the
    eigenvector of the multiplier ``-1``), tried both ways. Yields ``(U0, (U1, t1))``; a first point
    counts only if its halves differ by a tenth of its distance from the doubling."""
    o = ev.orbit
    X = o.problem.unknowns(o)
    U0 = np.concatenate((X, X, [float(ev.value)]))
    _, J, _ = engine.problem.FJ(U0, np.zeros(U0.size - 1))
    w = np.append(np.linalg.svd(J[:, :-1])[2][-1], 0.0)
    w /= engine.norm(w)
    for first in doubled_first_points(engine, U0, w, steps, _halves_gap):
        yield U0, first


def doubled_first_points(engine, U0, w, steps, gap):
    """First points of a doubled branch from the doubling ``U0`` along ``w``, each way in turn:
    Newton on the hyperplane normal to ``w`` from ``U0 +- h w``, ``h`` halved from the first step
    until a point is found whose halves differ (``gap(U)``) by a tenth of its distance from ``U0``.
    Yields ``(U1, t1)``, the point and its tangent (shared with the branch switching of
    :func:`impactbar.continue_orbit` for time-periodic orbits)."""
    h0, _, min_step = steps
    for sign in (1.0, -1.0):
        h = h0
        while h >= min_step:
            pred = U0 + sign * h * w
            U1, _ = engine.correct(pred, w, pred)
            if U1 is not None:
                move = float(np.max(np.abs(U1[:-1] - U0[:-1])))
                if move > 1e-3 * h and gap(U1) >= 0.1 * move and engine.problem.acceptable(U1):
                    yield U1, engine.tangent(U1, (U1 - U0) / engine.norm(U1 - U0))
                    break
            h *= 0.5


def continue_switched(orbit, parameter: str, to: float, detect, *,
                      settings: ContinuationSettings | None = None, events: bool = True, stop_on=(),
                      xtol: float = 1e-10, forward_lambda: bool = True, chord: bool | str = True) -> Branch:
    """Follow a periodic motion under a drive as one parameter changes, by pseudo-arclength
    continuation (theory §7, §10). Called by :func:`impactbar.continue_orbit` when its start is a
    :class:`~impactbar.SwitchedOrbit`, or a ``"period-doubling"`` :class:`BranchEvent` of a branch of
    them.

    Parameters
    ----------
    orbit : SwitchedOrbit or BranchEvent
        The start (from :func:`impactbar.find_orbit` with the drive), ``m`` impacts per period; or
        a period doubling of a one-impact branch: the two-impact branch that bifurcates there is
        followed (branch switching: its first point is taken along the doubled problem's null
        vector, whose halves are opposite, both ways tried), while the parameter stays within
        ``|to - doubling|`` of the doubling, on whichever side it bifurcates.
    parameter : str
        One of the drive's :attr:`~impactbar.Drive.parameters` (the valve's ``"stroke"``, ``"ret"``:
        force levels, dimensionless, eq. 2; ``"switch_out"``: bar lengths; ``"delay"`` (both delays),
        ``"delay_out"``, ``"delay_in"``: dimensionless time; the oil circuit's in its units, theory
        §11), ``"R"``, ``"d"``, ``"s"``, or the impact law's own (under the rod-rock law
        ``"rock.k"``, ``"rock.k_u"``, ``"bit_mass"``, ``"feed"``, in the law's units, theory §4d;
        ``"segment<i>.length"`` where its blows are exact: :meth:`RodRock.check_continuable
        <impactbar.laws.ContactLaw.check_continuable>`); the event's own parameter for a period
        doubling.
    to : float
        Target value; the branch stops there or where it leaves the range between start and ``to``.
    detect : callable
        The event detection of :func:`impactbar.continue_orbit`
        (``impactbar.continuation.core._detect``, handed in: this module sits below that one).
    settings : ContinuationSettings, optional
        Steps, point limit and Newton tolerance.
    events : bool
        Detect and locate events: ``"fold"``, ``"period-doubling"``, ``"neimark-sacker"`` (from the
        non-trivial multipliers), ``"grazing"`` (an impact velocity, or the gap's rate at the switch
        crossing, through 0), ``"admissibility"``, ``"border-collision"`` (the drive's state touching
        one of its switching surfaces: :meth:`~impactbar.Drive.border_tests`).
    stop_on : iterable of str
        Event kinds at which to stop.
    xtol : float
        Tolerance of the event location along the chord.
    forward_lambda : bool
        Where the flights are integrated (the oil circuit): the Jacobian's parameter column by a
        forward difference (one flight a point instead of two); ``False``: the central difference
        of before (a benchmark's baseline). Ignored for closed-form flights.
    chord : bool or "all"
        Where the flights are integrated: each corrector's first step a chord step with the last
        orbit's Jacobian (``True``, the default), every step (``"all"``: the residuals by plain
        flights, the orbit's own variational flight the only one a point, about half the cost; the
        points are then the plain flights' roots, 3e-8 from the variational ones'), or none
        (``False``: the full Newton steps of before, a benchmark's baseline). Ignored for closed-form
        flights.

    Returns
    -------
    Branch
        Its ``orbits`` are :class:`~impactbar.SwitchedOrbit` (``period``, ``blow_frequency``,
        multipliers); ``impacts = m`` (``2`` from a period doubling), ``periods = 1``.

    Raises
    ------
    ValueError
        For a bad argument (named), a start that is not a solution, or a period doubling from
        which no two-impact branch leaves.
    """
    if not (chord is True or chord is False or chord == "all"):
        raise ValueError(f"chord must be True, False or 'all'; got {chord!r}")
    switch = None
    if isinstance(orbit, BranchEvent):
        if orbit.kind != EventKind.PERIOD_DOUBLING or orbit.orbit.impacts != 1:
            raise ValueError("orbit: a BranchEvent start must be a period doubling of a one-impact "
                             "switched orbit")
        if parameter != orbit.parameter:
            raise ValueError(f"parameter must be the doubling's own, {orbit.parameter!r}; got {parameter!r}")
        switch, orbit = orbit, orbit.orbit
    model, drive = orbit.model, orbit.drive
    check_continuable(model, drive, parameter)  # an unknown name (the allowed listed), a non-smooth one
    lam0 = parameter_value(model, drive, parameter)
    if lam0 is None:  # the valve's delay where its two delays differ
        raise ValueError(f"parameter {parameter!r} has no value on this drive ({drive!r}): follow one of "
                         f"its own, e.g. 'delay_out' or 'delay_in'")
    lam0 = float(lam0)
    to = _target(parameter, lam0, to)
    settings = _settings(settings)
    steps = settings.steps(abs(to - lam0))
    stop_on, xtol = checked_events(stop_on, xtol)
    direction = 1.0 if to > lam0 else -1.0
    m = 2 if switch is not None else orbit.impacts
    problem = _SwitchedProblem(model, drive, parameter, detect, events=events, stop_on=stop_on, xtol=xtol,
                               impacts=m, doubled=switch is not None, base=orbit.problem,
                               forward_lambda=forward_lambda, chord=chord)
    # Newton's corrector no finer than the flights' accuracy (a drive with integrated flights: ten
    # times the integrator's rtol, ShootingProblem.accuracy; closed forms keep the settings' tol)
    engine = _Engine(problem, max(settings.tol, float(getattr(orbit.problem, "accuracy", 0.0))))
    if switch is not None:
        lo, hi = lam0 - abs(to - lam0), lam0 + abs(to - lam0)  # it may leave on either side
        for U0, first in _doubled_starts(engine, switch, steps):
            P, orbits, found, status = engine.march(U0, None, to, direction, lo, hi, steps,
                                                    settings.max_points, first=first)
            if len(orbits) > 2 or status != BranchStatus.STEP_TOO_SMALL:
                break
        else:
            raise ValueError("branch switching at the period doubling failed: no two-impact branch "
                             "along the doubled problem's null vector")
        return Branch(parameter=parameter, values=P[:, -1].copy(), orbits=orbits, events=tuple(found),
                      status=status, impacts=m, periods=1, _points=P)
    U0 = np.append(orbit.problem.unknowns(orbit), lam0)
    F0, J0, _ = problem.FJ(U0)
    if float(np.max(np.abs(F0))) > 1e-9 * max(1.0, float(np.max(np.abs(U0)))):
        raise ValueError("orbit: not a solution of the segment problem at the start value")
    t0 = np.linalg.svd(J0)[2][-1]
    t0 /= engine.norm(t0)
    if t0[-1] * direction < 0:
        t0 = -t0
    lo, hi = min(lam0, to), max(lam0, to)
    P, orbits, found, status = engine.march(U0, t0, to, direction, lo, hi, steps, settings.max_points)
    return Branch(parameter=parameter, values=P[:, -1].copy(), orbits=orbits, events=tuple(found),
                  status=status, impacts=m, periods=1, _points=P)
