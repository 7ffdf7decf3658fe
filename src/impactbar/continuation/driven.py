"""Continuation of periodic motions under a drive (theory §10).

The augmented problem for the engine (:mod:`impactbar.continuation.engine`) is the drive's
periodic-orbit problem (:func:`impactbar.orbits.driven.orbit_problem`: the drive's own, e.g. the
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
from scipy.interpolate import BarycentricInterpolator
from scipy.optimize import brentq

from .._shared.parameters import check_continuable, parameter_value, with_parameter
from .._shared.status import BranchStatus, EventKind
from .._shared.validate import check_real
from ..orbits.driven import DrivenOrbit, orbit_of, orbit_problem
from .branch import Branch, BranchEvent
from .engine import ContinuationSettings, _Engine, _settings
from .parameters import _target

__all__ = ["continue_driven"]

EVENT_KINDS = tuple(EventKind)

#: the chord steps of a corrector (``chord="all"``) before the Jacobian is taken again at the iterate
CHORD_STEPS = 6

#: the chord's rate of convergence assumed for a corrector's first step (``chord="orbit"``: the
#: last orbit's Jacobian; the observed rate of the corrector before replaces it)
CHORD_RATE = 0.1

#: a chord whose steps shrink by less than this factor takes the Jacobian again (``chord="orbit"``)
CHORD_STALL = 0.5

#: a chord whose rate leaves more steps than this to the tolerance takes the Jacobian again
#: (``chord="orbit"``: a variational period and ``F_lam``'s flight cost some four plain periods)
CHORD_STEPS_LEFT = 4.0

#: the ratios of successive chord steps (one Jacobian) that predict the next step by their largest
#: (``chord="orbit"``): with fewer, the prediction takes ``CHORD_RATE`` at least. A chord's first
#: ratio underestimates its rate (the predictor's error lies mostly where the predicted Jacobian is
#: right; on the preset's branch of eight points with 8 modes three points flew the variational flight
#: twice where the last ratio alone predicted the next step), and a variational
#: flight at an iterate that is not the point costs some four plain periods (itself and ``F_lam``'s
#: flight), one chord step more one
RATIOS_KNOWN = 2

#: the corrector's last iterate, whose residual the orbit's variational flight takes, is the first
#: whose estimated error is below this fraction of the tolerance, and the point where that flight's
#: step is (``chord="orbit"``: the point is then within it, not a step below it)
EXACT_FACTOR = 0.3

#: ``F_lam`` from the chord between two points (``chord="orbit"``, :meth:`_SwitchedProblem._record`)
#: where the parameter moves by this fraction of its length (and a thousandth of its size) at least
SECANT_SLOPE = 0.1

#: the points after which ``F_lam`` is measured by a flight where the chords gave none
#: (``chord="orbit"``, :meth:`_SwitchedProblem._record`)
STALE = 3

#: how far, in their spread, the corrector's Jacobian is extrapolated from the last points'
#: (``chord="orbit"``, :meth:`_SwitchedProblem._along`)
REACH = 3.0


def _last_value(pairs: list):
    """The value of the last ``(U, value)`` pair in ``pairs``; None where there is none."""
    if not pairs:
        return None
    _, value = pairs[-1]
    return value


class _SwitchedProblem:
    """The periodic-orbit problem of a drive in ``U = (X, lambda)``, for the engine.

    Where the flights are integrated: ``forward_lambda``, ``F_lam`` a forward difference (else the
    central difference of before); ``chord``, the first corrector step after an orbit with that
    orbit's Jacobian (a chord step; else the full Newton step of before), or with ``"all"`` every
    step (the residuals by plain flights; the Jacobian taken again after ``CHORD_STEPS`` steps
    without a new orbit), or with ``"orbit"`` the problem's own corrector (:meth:`_correct`, where
    the variational flights' state has a plain flight of its own: ``ShootingProblem.state_flights``;
    elsewhere as ``True``). Set by :func:`continue_driven`."""

    def __init__(self, model, drive, name, detect, *, events=True, stop_on=(), xtol=1e-10, impacts=1,
                 doubled=False, base=None, forward_lambda=True, chord=True):
        self.model0, self.drive0, self.name, self.detect = model, drive, name, detect
        self.forward_lambda, self.chord = forward_lambda, chord
        self.events, self.stop_on, self.xtol = events, stop_on, xtol
        self.m, self.doubled, self.base = impacts, doubled, base
        self.pair = functools.lru_cache(maxsize=16)(self._pair)
        self._chord = None  # the last orbit's F_u, for the next corrector's first step
        self._uses = 0  # the chord steps since it was taken
        self._rate = CHORD_RATE  # the last corrector's rate of convergence (chord="orbit")
        self._fus, self._lams = [], []  # the last (U, F_u) and (U, F_lam) (chord="orbit": _record)
        self._age = 0  # the points recorded since the last F_lam
        start = self.problem_at(float(parameter_value(model, drive, name)))
        self.flights = start.positive
        self.W = np.append(np.full(start.size, 1.0 / start.size), 1.0)
        #: the problem's own corrector (chord="orbit" where the flights allow it), else None: Newton's
        own = chord == "orbit" and getattr(start, "state_flights", False)
        self.corrector = self._correct if own else None
        if self.corrector is None and chord == "orbit":
            self.chord = True  # (the chord's first step, the steering Jacobian's after it)

    def _pair(self, lam: float):
        """The model, drive and orbit problem at the parameter value ``lam`` (its flights by the
        start's, its problem's ``settings``: the oil circuit's solver options follow the branch)."""
        model, drive = with_parameter(self.model0, self.drive0, self.name, lam)
        problem = orbit_problem(model, drive, self.m, getattr(self.base, "settings", None))
        if self.base is not None:
            problem.adopt(self.base)
        return model, drive, problem

    def problem_at(self, lam: float):
        """The orbit problem at the parameter value ``lam`` (:meth:`_pair`'s, cached)."""
        _, _, problem = self.pair(lam)
        return problem

    def F(self, U):
        return self.problem_at(float(U[-1])).value(U[:-1])

    def FJ(self, U, F_lam=None):
        """Residual, the Jacobian ``[F_u, F_lam]`` (``F_u`` the problem's, one that only steers the
        corrector where the problem has one: ``ShootingProblem.steering_residual``, Magnus' coarser
        steps; ``F_lam`` by central differences unless given, one-sided at the edge of the
        parameter's range) and ``F_lam``.

        Where the flights are integrated (a drive whose flights carry the variational equations,
        the oil circuit) ``F_lam`` is a forward difference from ``F`` (one flight instead of two; its
        error ``O(h)``, ``h = 1e-6``, only slows the corrector's convergence, whose residual is
        exact, and tilts the predictor's tangent by as much)."""
        problem = self.problem_at(float(U[-1]))
        if self.corrector is not None:  # (outside the own corrector: the orbit's Jacobian and F_lam)
            F, DF = self._exact(problem, U)
            if F_lam is None:
                F_lam = self._column(U, F)
                self._record(U, F, DF, F_lam)
            return F, np.column_stack((DF, F_lam)), F_lam
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

    def _exact(self, problem, U):
        """The residual at ``U`` and the multipliers' Jacobian ``F_u``, by the variational flights at
        the drive's own steps, kept whole (the orbit at ``U`` takes them: no flight more); ``F_u``
        kept for the chord."""
        F, self._chord = problem.residual(U[:-1], keep=True)
        return F, self._chord

    def _column(self, U, F):
        """``F_lam`` at ``U`` by a forward difference (backward at the edge of the parameter's range)
        of the residual whose root the orbit is (``ShootingProblem.root_value``, ``F`` its value at
        ``U``): one flight of the variational flights' state."""
        h = 1e-6 * max(1.0, abs(U[-1]))
        for sign in (1.0, -1.0):
            try:
                return sign * (self.problem_at(float(U[-1] + sign * h)).root_value(U[:-1]) - F) / h
            except ValueError:
                continue
        raise ValueError(f"{self.name}: no admissible value within {h:g} of {U[-1]}")

    def _along(self, records, U):
        """The value at ``U`` of a quantity that ``records`` holds at points of the branch
        ``[(U_i, value_i)]``: Lagrange's polynomial through the last three of one shape (two, one)
        in their coordinate along the branch (the projection on the chord between the first and
        the last of them, in the arclength's weights), ``U`` within ``REACH`` times their spread of
        them (their values carry the flights' noise, which a polynomial magnifies as far); else,
        and for a point that the others' spread does not set apart, the older left out. One record:
        its value."""
        _, last = records[-1]
        pts = [(Ui, v) for Ui, v in records[-3:] if v.shape == last.shape]
        while len(pts) > 1:
            (U_first, _), (U_last, _) = pts[0], pts[-1]
            d = self.W * (U_last - U_first)
            x = [float(Ui @ d) for Ui, _ in pts]
            xu = float(U @ d)
            gaps = [abs(a - b) for i, a in enumerate(x) for b in x[i + 1:]]
            spread = max(gaps)
            if min(gaps) > 0.05 * spread and min(x) - REACH * spread <= xu <= max(x) + REACH * spread:
                break
            pts = pts[1:]
        if len(pts) < 2:
            _, value = pts[-1]
            return value
        return BarycentricInterpolator(x, np.stack([v for _, v in pts]))(xu)

    def _record(self, U, F, Fu, F_lam=None):
        """Keep ``F_u`` at the point ``U`` (of the branch, or a point the events' location corrected;
        ``F`` the residual there) and ``F_lam``: given, or else from the chord from the point before
        (the residual is 0 at both, so that ``(J_a + J_b) / 2 (U_b - U_a) = O(h^3)``, the
        trapezoidal rule along the chord, gives ``F_lam`` in its middle from the two ``F_u``) where
        the chord moves the parameter (``SECANT_SLOPE`` of its length and of the parameter's size at
        least: the points' own errors, divided by the move, are ``F_lam``'s); else the records of
        before, unless there are none or they are ``STALE`` points old: then measured by a flight
        (:meth:`_column`). Returns ``[F_u, F_lam]`` at ``U``."""
        same = [(Ui, Fi) for Ui, Fi in self._fus if Fi.shape == Fu.shape]
        last_lam = _last_value(self._lams)
        if F_lam is None and same:
            Ua, Fa = same[-1]
            d = U - Ua
            norm = math.sqrt(float(d @ (self.W * d)))
            if abs(d[-1]) >= SECANT_SLOPE * max(norm, 1e-3 * max(1.0, abs(U[-1]))):
                self._lams = (self._lams + [(0.5 * (U + Ua), -0.5 * (Fa + Fu) @ d[:-1] / d[-1])])[-2:]
                self._age = 0
                F_lam = False
            elif last_lam is not None and last_lam.size == F.size and self._age < STALE:
                self._age += 1
                F_lam = False
        if F_lam is None:
            F_lam = self._column(U, F)
        if F_lam is not False:
            self._lams = (self._lams + [(U.copy(), F_lam)])[-2:]
            self._age = 0
        self._fus = (self._fus + [(U.copy(), Fu)])[-3:]
        return np.column_stack((Fu, self._along(self._lams, U)))

    def _correct(self, engine, U_pred, normal, anchor, max_iter):
        """The corrector (``chord="orbit"``): Newton's iteration on ``F(U) = 0``,
        ``<normal, U - anchor> = 0`` with the Jacobian that the last points predict (the variational
        flights' ``F_u``, the multipliers', quadratic along the branch from the last three, and
        ``F_lam`` linear from the last two: :meth:`_record`, :meth:`_along`), the residuals by plain
        flights at the variational flights' tolerance (their state: the orbits are the roots of
        the same residual as Newton's of before). Once the chord's rate (the last corrector's,
        ``CHORD_RATE`` at first, before this chord's steps; then the largest ratio of its steps, at
        least ``CHORD_RATE`` on fewer than ``RATIOS_KNOWN`` ratios) says that the iterate is within
        ``EXACT_FACTOR`` of the tolerance,
        its residual is taken by the orbit's own variational flight instead: where its step is then
        within as much, the iterate is the point (its orbit, its multipliers and the next chord's
        ``F_u`` from that flight), else the step is a Newton step with the new ``F_u`` and ``F_lam``
        measured there (:meth:`_column`), and the chord goes on. A chord that stalls (its steps
        shrink by less than ``CHORD_STALL``), or whose rate leaves more than ``CHORD_STEPS_LEFT`` steps
        to the tolerance, takes the Jacobian again so.

        Returns
        -------
        U : numpy.ndarray or None
            The point, or ``None`` where the corrector failed.
        iterations : int
            For the engine's step control, which counts Newton's iterations: those that Newton's
            method would take from the same predictor (:func:`_newton_iterations`), and one more for
            each Jacobian taken again, at most the iterations taken.
        J : numpy.ndarray or None
            ``[F_u, F_lam]`` at ``U`` (the tangent's), ``None`` with a failure.
        """
        U = np.array(U_pred, dtype=float)
        normal = engine.W * normal
        n = U.size - 1
        last_fu, last_lam = _last_value(self._fus), _last_value(self._lams)
        known = last_fu is not None and last_fu.shape[0] == n and last_lam is not None and last_lam.size == n
        J = np.column_stack((self._along(self._fus, U), self._along(self._lams, U))) if known else None
        exact, fresh = not known, False  # (fresh: the chord's F_u taken at an iterate of this corrector)
        prev = first = None
        ratios = []  # the ratios of successive steps of this chord (one Jacobian)
        again = 0  # the variational flights at iterates that were not the point
        for it in range(1, max_iter + 1):
            try:  # (an iterate may leave the parameter's range: a failure, the step then shortened)
                problem = self.problem_at(float(U[-1]))
                if exact:
                    F, Fu = self._exact(problem, U)
                    J = np.column_stack((Fu, J[:, -1] if J is not None else self._column(U, F)))
                else:
                    F = problem.root_value(U[:-1])
            except ValueError:
                return None, it, None
            if not (np.all(np.isfinite(F)) and np.all(np.isfinite(J))):
                return None, it, None
            try:
                dU = np.linalg.solve(np.vstack((J, normal)), np.append(F, normal @ (U - anchor)))
            except np.linalg.LinAlgError:
                return None, it, None
            step, scale = float(np.max(np.abs(dU))), max(1.0, float(np.max(np.abs(U - dU))))
            target = EXACT_FACTOR * engine.tol * scale
            first = step if first is None else first
            if exact and step > target:  # (not the point: a Newton step, F_lam taken here too)
                again += 1
                try:
                    J = np.column_stack((J[:, :-1], self._column(U, F)))
                    dU = np.linalg.solve(np.vstack((J, normal)), np.append(F, normal @ (U - anchor)))
                except (ValueError, np.linalg.LinAlgError):
                    return None, it, None
                step = float(np.max(np.abs(dU)))
            if prev is not None and prev > target and not fresh:
                # (the chord's rate, the last step's noise aside: the flights' ~1e-12 of the unknowns)
                rate = max(step, 1e-2 * target) / prev
                if it == 2:
                    self._rate = min(max(rate, 1e-6), CHORD_STALL)
            if exact and step <= target:  # the orbit's flight at U: the point
                try:
                    J = self._record(U, F, J[:, :-1])
                except ValueError:
                    return None, it, None
                return U, min(it, _newton_iterations(first, target, scale) + again), J
            rate = self._rate if prev is None else step / prev
            if exact:
                fresh, rate = True, min(rate, CHORD_RATE)
            elif prev is not None and rate > CHORD_STALL:
                if fresh and rate > 1.0:
                    return None, it, None  # (diverging with a Jacobian of its own)
                rate = 1.0  # stalled: the next iterate's F_u taken again (exact)
            elif prev is not None and step > target and \
                    math.log(target / step) / math.log(max(rate, 1e-300)) > CHORD_STEPS_LEFT:
                rate = 1.0  # slow: the Jacobian taken again costs fewer flights than the chord's steps
            elif prev is not None and not fresh:
                ratios.append(rate)
                rate = predicted_rate(ratios)
            U = U - dU
            exact = rate >= 1.0 or rate * step <= target
            prev = step
        return None, max_iter, None

    def orbit(self, U, admissibility=True):
        """The orbit at ``U``. Where the flights are integrated, the Jacobian of its residual (from
        the variational flight the orbit's data came from, remembered by the problem: no flight
        more; the drive's own steps, as the multipliers') is kept for the first step of the next
        corrector (a chord step: the residual by a plain flight, ``F_u`` the last orbit's), which the
        steering Jacobian's steps then finish."""
        problem = self.problem_at(float(U[-1]))
        ob = orbit_of(problem, U[:-1])
        if self.chord and getattr(problem, "variational", False):
            try:
                _, self._chord = problem.residual(U[:-1])
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


def predicted_rate(ratios: list) -> float:
    """The rate at which a corrector's chord (``chord="orbit"``) is expected to go on: the largest
    ratio of successive steps it has shown with one Jacobian, and at least :data:`CHORD_RATE` while
    it has shown fewer than :data:`RATIOS_KNOWN` (a chord's first ratio underestimates its rate).

    Parameters
    ----------
    ratios : list of float
        The ratios of the chord's successive steps so far (at least one), each positive.

    Returns
    -------
    float
        The rate that predicts the next step (that step's size over the last one's).

    Examples
    --------
    >>> predicted_rate([0.008])
    0.1
    >>> predicted_rate([0.008, 0.06])
    0.06
    """
    return max(max(ratios), CHORD_RATE if len(ratios) < RATIOS_KNOWN else 0.0)


def _newton_iterations(first: float, target: float, scale: float) -> int:
    """The iterations that Newton's method would take from a predictor whose first step is
    ``first`` to a step within ``target`` (its error squared each step, relative to ``scale``;
    the step below ``target`` predicted, not taken, as the engine's corrector does): what a
    corrector of chord steps reports to the engine's step control, which counts Newton's."""
    e, t = first / scale, target / scale
    if not e > t:
        return 1
    if e >= 1.0:
        return 10
    return 1 + math.ceil(math.log2(math.log(t) / math.log(e)))


def first_chord_tests(tests: list, doubled: bool, points: int) -> list:
    """The test functions at the last two points of a branch, ``tests``, with the fold test of a
    doubled branch's first point replaced by its second's: that point is the parent's period
    doubling, where the doubled orbit has the multiplier ``(-1)^2 = +1``, so ``det(I - P)`` is zero
    there up to rounding and its sign is no crossing (the event is the parent's period doubling,
    reported on its branch; theory §7)."""
    if doubled and points == 2:
        tests[0] = dict(tests[0], fold=tests[1]["fold"])
    return tests


def _tests(o: DrivenOrbit) -> dict:
    """The test functions of :func:`impactbar.continuation.one_parameter._detect` at a driven orbit (no
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
    """The drive's border-collision tests at a driven orbit (its ability ``border_tests``,
    :attr:`~impactbar.Drive.abilities`, over the flights of its period); ``{}`` for a drive without
    them."""
    problem, tests = o.problem, o.drive.abilities.border_tests
    if tests is None or not hasattr(problem, "flights"):
        return {}
    return tests(problem.flights(problem.unknowns(o)))


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
    """Branch switching at a period doubling of a driven orbit: the doubling point as a
    two-impact solution ``(X, X, lambda)`` and the first point of the period-2 branch, along the
    null vector of the doubled problem's ``F_u`` (antisymmetric between the halves: the
    eigenvector of the multiplier ``-1``), tried both ways. Yields ``(U0, (U1, t1))``; a first point
    counts only if its halves differ by a tenth of its distance from the doubling."""
    o = ev.orbit
    X = o.problem.unknowns(o)
    U0 = np.concatenate((X, X, [float(ev.value)]))
    _, J, _ = engine.problem.FJ(U0, np.zeros(U0.size - 1))
    _, _, Vh = np.linalg.svd(J[:, :-1])
    w = np.append(Vh[-1], 0.0)
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


def continue_driven(orbit, parameter: str, to: float, detect, *,
                      settings: ContinuationSettings | None = None, events: bool = True, stop_on=(),
                      xtol: float = 1e-10, forward_lambda: bool = True,
                      chord: bool | str = "orbit") -> Branch:
    """Follow a periodic motion under a drive as one parameter changes, by pseudo-arclength
    continuation (theory §7, §10). Called by :func:`impactbar.continue_orbit` when its start is a
    :class:`~impactbar.DrivenOrbit`, or a ``"period-doubling"`` :class:`BranchEvent` of a branch of
    them.

    Parameters
    ----------
    orbit : DrivenOrbit or BranchEvent
        The start (from :func:`impactbar.find_orbit` with the drive; its problem's flight
        ``settings``, the oil circuit's solver options, are every point's), ``m`` impacts per period; or
        a period doubling of a one-impact branch: the two-impact branch that bifurcates there is
        followed (branch switching: its first point is taken along the doubled problem's null
        vector, whose halves are opposite, both ways tried), while the parameter stays within
        ``|to - doubling|`` of the doubling, on whichever side it bifurcates.
    parameter : str
        One of the drive's parameters, ``traits.parameters`` (the valve's ``"stroke"``, ``"ret"``:
        force levels, dimensionless, eq. 2; ``"switch_out"``: bar lengths; ``"delay"`` (both delays),
        ``"delay_out"``, ``"delay_in"``: dimensionless time; the oil circuit's in its units, theory
        §11), ``"R"``, ``"d"``, ``"s"``, or the impact law's own (under the rod-rock law
        ``"rock.k"``, ``"rock.k_u"``, ``"bit_mass"``, ``"feed"``, in the law's units, theory §4d;
        ``"segment<i>.length"`` where its blows are exact: :meth:`RodRock.parameter_table
        <impactbar.laws.RodRock.parameter_table>`); the event's own parameter for a period
        doubling.
    to : float
        Target value; the branch stops there or where it leaves the range between start and ``to``.
    detect : callable
        The event detection of :func:`impactbar.continue_orbit`
        (``impactbar.continuation.one_parameter._detect``, handed in: this module sits below that one).
    settings : ContinuationSettings, optional
        Steps, point limit and Newton tolerance.
    events : bool
        Detect and locate events: ``"fold"``, ``"period-doubling"``, ``"neimark-sacker"`` (from the
        non-trivial multipliers), ``"grazing"`` (an impact velocity, or the gap's rate at the switch
        crossing, through 0), ``"admissibility"``, ``"border-collision"`` (the drive's state touching
        one of its switching surfaces: its ability ``border_tests``).
    stop_on : iterable of str
        Event kinds at which to stop.
    xtol : float
        Tolerance of the event location along the chord.
    forward_lambda : bool
        Where the flights are integrated (the oil circuit): the Jacobian's parameter column by a
        forward difference (one flight a point instead of two); ``False``: the central difference
        of before (a benchmark's baseline). Ignored for closed-form flights.
    chord : bool, "all" or "orbit"
        Where the flights are integrated: ``"orbit"`` (the default), where the variational flights'
        state is a plain flight's at their tolerance (the oil circuit's flexible piston, Magnus'
        fundamental matrix), every corrector step a chord step with the Jacobian that the last points
        predict (their orbits' ``F_u``, quadratic along the branch; ``F_lam`` from the chords between
        them), the residuals by those plain flights, and the last iterate's by the orbit's own
        variational flight, which is then the point's: one variational period a point, against three
        before (the 8-mode point 0.47 s of CPU against 0.97 s; the points within ``EXACT_FACTOR`` of
        the corrector's tolerance, not a step below it: with 8 modes their unknowns 2e-10 of their
        size from ``find_orbit``'s at their parameter values, the multipliers 2e-8), elsewhere as
        ``True``; ``True``, each corrector's first step a chord step with the last orbit's Jacobian,
        then Newton's steps with a steering Jacobian (the way before); every step (``"all"``: the
        residuals by plain flights, the Jacobian taken again after ``CHORD_STEPS``; the points are
        then the plain flights' roots, 3e-8 from the variational ones'); or none (``False``: the full
        Newton steps of before, a benchmark's baseline). Ignored for closed-form flights.

    Returns
    -------
    Branch
        Its ``orbits`` are :class:`~impactbar.DrivenOrbit` (``period``, ``blow_frequency``,
        multipliers); ``impacts = m`` (``2`` from a period doubling), ``periods = 1``.

    Raises
    ------
    ValueError
        For a bad argument (named), a start that is not a solution, or a period doubling from
        which no two-impact branch leaves.
    """
    if not (chord is True or chord is False or chord in ("all", "orbit")):
        raise ValueError(f"chord must be True, False, 'all' or 'orbit'; got {chord!r}")
    switch = None
    if isinstance(orbit, BranchEvent):
        if orbit.kind != EventKind.PERIOD_DOUBLING or orbit.orbit.impacts != 1:
            raise ValueError("orbit: a BranchEvent start must be a period doubling of a one-impact "
                             "driven orbit")
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
    _, _, Vh = np.linalg.svd(J0)
    t0 = Vh[-1]
    t0 /= engine.norm(t0)
    if t0[-1] * direction < 0:
        t0 = -t0
    lo, hi = min(lam0, to), max(lam0, to)
    P, orbits, found, status = engine.march(U0, t0, to, direction, lo, hi, steps, settings.max_points)
    return Branch(parameter=parameter, values=P[:, -1].copy(), orbits=orbits, events=tuple(found),
                  status=status, impacts=m, periods=1, _points=P)
