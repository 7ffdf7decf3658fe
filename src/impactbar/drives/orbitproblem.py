"""Periodic orbits of a drive: the problem a solver of :func:`impactbar.find_orbit` asks a drive for
(:class:`OrbitProblem`, what a solution gives, :class:`OrbitData`), Newton's method and the chord
method that solve it, and the multipliers' split off the flow's own (theory §10, §11)."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from .base import Drive

__all__ = ["OrbitData", "OrbitProblem", "OrbitSearch", "newton", "chord", "StalledIteration",
           "split_multipliers", "sorted_multipliers"]


class OrbitData(NamedTuple):
    """What an :class:`OrbitProblem` gives of a solution: the fields of
    :class:`~impactbar.DrivenOrbit` the orbit solver does not compute itself.

    Attributes
    ----------
    period : float
    durations : numpy.ndarray
        The flights between consecutive events of the period, in order from the first impact (or
        the end of its contact).
    states_after, states_before : numpy.ndarray, shape (m, 2 N + 2)
        The bar's state just after each impact (where its contact ends) and on arrival at the next
        impact, in order (the last arrival leads to ``states_after[0]``).
    impact_velocities : numpy.ndarray, shape (m,)
        The struck end's velocity at each of those arrivals.
    impact_times : numpy.ndarray, shape (m,)
        Their times after the first state of ``states_after``.
    drive_states : numpy.ndarray, shape (m, k)
        The drive's continuous state just after each impact.
    multipliers : numpy.ndarray
        The non-trivial Floquet multipliers, largest modulus first.
    trivial_multiplier : float
    switch_times : numpy.ndarray
        Times after the first impact at which the drive switched.
    switch_velocity : float
        The smallest rate of the gap at the drive's position crossings (0 where a switching surface
        is grazed), ``nan`` where the drive has none.
    contact_time : float
        The law's window (0 under the paper's law), or the longest blow where the blows end by
        their own test (the rod-rock law's under a drive with state, theory §11).
    contact_forces : numpy.ndarray, shape (m,)
        The drive's force held during each contact.
    monodromy : numpy.ndarray or None
    """

    period: float
    durations: np.ndarray
    states_after: np.ndarray
    states_before: np.ndarray
    impact_velocities: np.ndarray
    impact_times: np.ndarray
    drive_states: np.ndarray
    multipliers: np.ndarray
    trivial_multiplier: float
    switch_times: np.ndarray
    switch_velocity: float
    contact_time: float
    contact_forces: np.ndarray
    monodromy: np.ndarray | None


class OrbitSearch(NamedTuple):
    """What an :class:`OrbitProblem` gives of a systematic search of its solutions
    (:meth:`OrbitProblem.search`): the starts of Newton's method, one per solution, and what is
    certified of them.

    Attributes
    ----------
    starts : list of numpy.ndarray
        The unknowns of each solution found (to be polished by :meth:`OrbitProblem.solve`).
    certified : numpy.ndarray of bool
        Per start: the solution is proved unique in a box around it, and the search proved that
        the window holds no solution outside those boxes and :attr:`unresolved`.
    window : (float, float)
        The periods searched.
    unresolved : tuple of (float, float, str)
        Period intervals the search could not decide, with the reason.
    method : str
        One line: how the starts were found (for the result's record).
    """

    starts: list
    certified: np.ndarray
    window: tuple
    unresolved: tuple
    method: str


class OrbitProblem(ABC):
    """The periodic-orbit problem of a drive (unknown period, theory §10): unknowns ``X``, a residual
    with its Jacobian, Newton's start from a guess and the orbit of a solution. The valve's
    (:class:`~impactbar.orbits.valve_segment.ValveProblem`) and the generic shooting problem
    (:class:`~impactbar.orbits.driven.ShootingProblem`) implement it; :func:`impactbar.find_orbit`
    and :func:`impactbar.continue_orbit` call only these members.

    Attributes
    ----------
    model, drive, impacts
        The bar, the drive and the impacts per period ``m``.
    size : int
        The number of unknowns.
    positive : numpy.ndarray of int
        Indices of the unknowns that must stay positive (flight times): Newton's step is damped so
        that they change by at most a half.
    default_start : str
        What :meth:`initial` starts from without a guess, in words (the error of
        :func:`impactbar.find_orbit` lists it among the starts it tried).
    starts_from_rest : bool
        Whether that start already is the motion from rest on the stop followed until it settles
        (the default guess chain of :func:`impactbar.find_orbit` then skips its own run from rest).
    settled_into : tuple of int or None
        Where :meth:`initial` followed a motion that settled into ``k > 1`` impacts a period, not
        the ``impacts`` asked for: ``(k, impacts followed)`` (the chain's error says so); ``None``.
    """

    model: Any
    drive: Drive
    impacts: int
    size: int
    positive: np.ndarray
    default_start: str = "the drive's default start"
    starts_from_rest: bool = False
    settled_into: tuple | None = None

    @abstractmethod
    def initial(self, guess, tol: float, max_iter: int) -> np.ndarray:
        """Newton's start from ``guess`` (``None``: the drive's default)."""

    @abstractmethod
    def residual(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The residual and its Jacobian at ``X``."""

    def value(self, X: np.ndarray) -> np.ndarray:
        """The residual alone at ``X`` (a problem whose Jacobian costs more than its residual, as the
        variational flights of a drive with state, computes only this)."""
        r, _ = self.residual(X)
        return r

    def solve(self, X: np.ndarray, tol: float, max_iter: int) -> np.ndarray:
        """Newton's method from ``X`` (:func:`newton`)."""
        return newton(self.residual, X, self.positive, tol, max_iter)

    def adopt(self, other: OrbitProblem) -> OrbitProblem:
        """Take from ``other``, the problem of a nearby solution (another parameter value, or the
        one-impact problem of a doubled branch), what this one needs besides the unknowns (the
        generic shooting's start times and modes); returns ``self``."""
        return self

    @abstractmethod
    def unknowns(self, orbit) -> np.ndarray:
        """The unknowns of a found orbit (a :class:`~impactbar.DrivenOrbit` of this problem)."""

    @abstractmethod
    def orbit(self, X: np.ndarray) -> OrbitData:
        """The orbit of a solution ``X``."""

    def search(self, window: tuple[float, float] | None) -> OrbitSearch | None:
        """A systematic search of every solution with a period in ``window`` (``None``: the
        problem's default window), or ``None`` where the problem has none (the solvers then take
        their non-certified search from guesses)."""
        return None

    @abstractmethod
    def pieces(self, X: np.ndarray) -> list:
        r"""The flights of the period as ``(t0, t1, f)``: ``f(t)`` gives the modal state ``(q, v)``,
        shapes ``(N + 1, T)``, at orbit times :math:`t_0 \le t \le t_1` from the first state of the unknowns
        (the contacts' windows lie between the flights)."""

    @abstractmethod
    def admissibility(self, X: np.ndarray, k: int):
        """The admissibility of the flights after impact ``k`` (an
        :class:`~impactbar.Admissibility`), the contacts apart."""


#: what :func:`newton` and :func:`chord` say of a singular Jacobian
_SINGULAR = ("find_orbit: the Jacobian of the periodic-orbit problem is singular at the guess (the motion it "
             "starts from does not repeat: e.g. a drive too weak to bring the piston back to the stop); give "
             "a guess, or check the drive's parameters with simulate")


def newton(residual, X, positive, tol: float, max_iter: int) -> np.ndarray:
    """Newton's method on ``residual(X) -> (r, J)`` from ``X``, damped while the unknowns at
    ``positive`` (flight times) would change by more than a half. It stops when a step is below
    ``tol`` (relative), or when the next step, predicted from quadratic convergence
    (:math:`|s_k|^2 / |s_{k-1}|`), would be: that saves the last residual, whose only use would be to
    see the step vanish. It gives up where its steps have stalled (:data:`STALL_STEPS`: they circle
    instead of shrinking).

    Raises
    ------
    ValueError
        When a flight time turns non-positive, the Jacobian is singular, the steps stall or
        ``max_iter`` steps do not converge.
    """
    hi = positive
    lo = np.setdiff1d(np.arange(np.size(X)), hi)  # the states (positions and velocities)
    last = math.inf
    step = np.zeros(0)
    stalled = _Stall()
    for _ in range(max_iter):
        r, Jac = residual(X)
        try:
            step = np.linalg.solve(Jac, -r)
        except np.linalg.LinAlgError:
            raise ValueError(_SINGULAR) from None
        X, size, done, damped = _advance(X, step, hi, lo, Jac, tol, last, 1e-4)
        if done:
            return X
        if at_rounding_floor(size, last):  # no more progress: the rounding floor of a
            return X  # poorly conditioned orbit (multipliers near 1), reached
        if stalled(size, damped):
            raise stalled.error(step)
        last = size
    raise ValueError(f"find_orbit did not converge in {max_iter} Newton steps (last step "
                     f"{np.max(np.abs(step)):.2e})")


def chord(value, jacobian, X, positive, tol: float, max_iter: int, first=None, first_value=None,
          handover: float = 0.0, first_here: bool = False, first_bound=None) -> np.ndarray:
    """The chord method (a simplified Newton's method) on ``value(X) -> r`` from ``X``: every step
    with one Jacobian, ``first`` (``jacobian(X)`` where not given) factorised once, the residuals by
    ``value`` alone; the Jacobian taken again (``jacobian``, at the iterate) only where the steps stop
    shrinking by at least half. Damped and stopped as :func:`newton` is, the next step predicted from
    the steps' linear convergence (:math:`|s_k|^2 / |s_{k-1}|`, the same test).

    For residuals whose Jacobian costs much more than the residual itself (the variational
    equations of an integrated drive: n squared more unknowns than the flight): the Jacobian only
    steers the iteration, so ``first`` may be rougher than the residual (from a flight at a looser
    tolerance); the root is the residual's. ``first_here``: ``first`` is the Jacobian at ``X`` (the
    first step a Newton step); ``first_value``, where given, is ``value(X)`` (from the flight that
    gave ``first``: no flight more). With ``handover > 0``, a Newton step (its Jacobian taken at its
    own start) of relative size at most ``handover`` ends the iteration: the iterate's error is then
    of order the step's square, and the caller finishes with a Newton step of its own instead of
    the chord's steps. ``first_bound``, where ``first_value`` is a looser flight's residual: the
    second step (the first from ``value``) then measures that residual's error rather than the
    chord's contraction, which ``first_bound(s1)`` bounds after a first step of size ``s1`` (the
    Jacobian's own error and its change over that step); that step ends the iteration where the
    bound times its size is below ``tol``. Raises as :func:`newton` does, its stall test
    (:data:`STALL_STEPS`) counting its Newton steps alone (:class:`StalledIteration`: Newton's method
    from its start circles).
    """
    import scipy.linalg as sl

    hi, lo = positive, np.setdiff1d(np.arange(np.size(X)), positive)
    Jac, lu, last, step = (jacobian(X) if first is None else first), None, math.inf, np.zeros(0)
    fresh = first is None or first_here
    r, bound = first_value, None  # (bound: the contraction's after a looser first residual's step)
    stalled = _Stall()
    for _ in range(max_iter):
        if lu is None:
            if not np.all(np.isfinite(Jac)):
                raise ValueError("find_orbit: the Jacobian of the periodic-orbit problem is not finite")
            with np.errstate(all="ignore"):
                lu = sl.lu_factor(Jac, check_finite=False)
            if np.any(np.diag(lu[0]) == 0.0):
                raise ValueError(_SINGULAR)
        step = sl.lu_solve(lu, -(value(X) if r is None else r), check_finite=False)
        loose, r = r is not None and first_bound is not None, None
        X, size, done, damped = _advance(X, step, hi, lo, Jac, tol, last, 0.25)
        done = done or (bound is not None and not damped and bound * size <= tol)
        bound = first_bound(size) if loose and not damped else None
        if done or (fresh and size <= handover):
            return X
        if fresh and at_rounding_floor(size, last):  # the rounding floor, reached (as newton's)
            return X
        if fresh and stalled(size, damped):  # (its Newton steps: Newton's method itself circles)
            raise stalled.error(step)
        fresh = False  # (whether the next step's Jacobian is at its own start: a Newton step)
        if math.isfinite(last) and size > 0.5 * last:  # no longer contracting: the Jacobian again
            Jac, lu, fresh = jacobian(X), None, True
        last = size
    raise ValueError(f"find_orbit did not converge in {max_iter} Newton steps (last step "
                     f"{np.max(np.abs(step)):.2e})")


def _advance(X, step, hi, lo, Jac, tol: float, last: float, rate: float):
    """One step of :func:`newton` or :func:`chord`: ``(X + step, its size, converged, damped)``, the
    step damped while far (the flight times at ``hi`` change by at most a half), converged when the
    step, or the next one predicted from the last two (where they shrink by ``rate`` at least), is
    below ``tol``."""
    big = float(np.max(np.abs(step[hi]) / np.abs(X[hi]))) if hi.size else 0.0
    if big > 0.5:  # damped while far: the flight times change by at most a half
        step = step * (0.5 / big)
    X = X + step
    if np.any(X[hi] <= 0.0):
        raise ValueError("Newton left the region of positive flight times: give a guess closer "
                         "to the orbit (e.g. from simulate)")
    # the step relative to the states' and the times' own sizes (relative to
    # max(1, |X|) it depended on the drive's scale, states scaling with it and times not)
    times = _relative(step, X, hi)
    size = max(_relative(step, X, lo), times)
    # states that vanish at the orbit (R = 0: at rest on the stop): a rounding step of 1e-33 in
    # them read as a relative change of 1; they are converged when their step is below tol
    # times how much they change with the flight times (|dr/dt| |t|, scaling as they do)
    if lo.size and hi.size and times <= tol and float(np.max(np.abs(step[lo]))) \
            <= tol * float(np.max(np.abs(Jac[:, hi]))) * float(np.max(np.abs(X[hi]))):
        return X, size, True, big > 0.5
    done = size <= tol or (big <= 0.5 and math.isfinite(last) and size < rate * last
                           and size * size <= tol * last)
    return X, size, done, big > 0.5


#: Newton's steps (and the chord's) have stalled when this many in a row, none damped, fail to fall
#: below :data:`STALL_FACTOR` times the smallest step before them: an iteration that circles (the
#: oil circuit's orbit on a design without one: a step of 1.7e-3 for 48 steps, each 0.2 to 0.3 s of
#: CPU) rather than one on its way to a root (in the 700 converging runs of the drives', orbits' and
#: optimiser's tests no more than two steps in a row failed to halve the smallest before them)
STALL_STEPS = 5
#: by how much a step must fall below the smallest before it to count as progress (:data:`STALL_STEPS`)
STALL_FACTOR = 0.5


class StalledIteration(ValueError):
    """Raised by :func:`newton` and :func:`chord` where their steps have stalled
    (:data:`STALL_STEPS`, the chord's counting only its Newton steps): no root near the start."""


class _Stall:
    """:func:`newton`'s and :func:`chord`'s stall test (:data:`STALL_STEPS`): called with a step's
    size and whether it was damped, ``True`` once the steps have stalled; a damped step (far from a
    root, its size set by the damping) starts the count again."""

    def __init__(self):
        self.best, self.count = math.inf, 0

    def __call__(self, size: float, damped: bool) -> bool:
        if damped or size <= STALL_FACTOR * self.best:
            self.best, self.count = (math.inf if damped else size), 0
            return False
        self.count += 1
        return self.count >= STALL_STEPS

    def error(self, step) -> StalledIteration:
        return StalledIteration(
            f"find_orbit: Newton stalled ({STALL_STEPS} steps in a row none below {STALL_FACTOR:g} of the "
            f"smallest before it, {self.best:.2e} relative; last step {np.max(np.abs(step)):.2e}): no root "
            "near this start")


def at_rounding_floor(size: float, last: float) -> bool:
    """Whether Newton's steps have reached the rounding floor of a poorly conditioned orbit
    (multipliers near 1): a step ``size`` below 1e-9 (relative, :func:`step_size`) that shrank by
    less than a quarter from the step before, ``last``.

    Parameters
    ----------
    size, last : float

    Returns
    -------
    bool
    """
    return 0.25 * last < size < 1e-9


def step_size(step, X, positive) -> float:
    """The size of a Newton step as :func:`newton` measures it: ``max |step|`` relative to ``max |X|``
    over the flight times (``positive``) and over the states (the rest), the larger.

    Parameters
    ----------
    step, X : numpy.ndarray, shape (n,)
    positive : numpy.ndarray of int
        Where ``X`` holds flight times.

    Returns
    -------
    float
    """
    states = np.setdiff1d(np.arange(np.size(X)), positive)
    return max(_relative(step, X, states), _relative(step, X, positive))


def _relative(step, X, index) -> float:
    """``max |step|`` over ``index`` relative to ``max |X|`` there (0 for an empty index)."""
    if not np.size(index):
        return 0.0
    ref = float(np.max(np.abs(X[index])))
    size = float(np.max(np.abs(step[index])))
    return size / ref if ref > 0.0 else size


def split_multipliers(Phi: np.ndarray, f: np.ndarray) -> tuple[float, np.ndarray]:
    """The trivial multiplier along the vector field ``f`` and the others (theory §10): ``Phi`` in
    the orthonormal basis ``(f/|f|, B)`` is block upper triangular (``Phi f = f``).

    Returns
    -------
    trivial : float
    multipliers : numpy.ndarray
        The others, largest modulus first (real where every imaginary part is rounding).
    """
    n = f.size
    fhat = f / np.linalg.norm(f)
    if n == 2:  # the rigid bar: P = Q^T Phi Q is triangular, so mu = trace - P[0, 0]
        trivial = float(fhat @ Phi @ fhat)
        return trivial, np.array([float(np.trace(Phi)) - trivial])
    Q, _ = np.linalg.qr(np.column_stack((fhat, np.eye(n))))
    Q = Q[:, :n]
    Q[:, 0] = fhat
    Q, _ = np.linalg.qr(Q)
    if Q[:, 0] @ fhat < 0:
        Q[:, 0] = -Q[:, 0]
    P = Q.T @ Phi @ Q
    mu = np.linalg.eigvals(P[1:, 1:]) if n > 1 else np.array([])
    return float(P[0, 0]), sorted_multipliers(mu)


def sorted_multipliers(mu: np.ndarray) -> np.ndarray:
    """Multipliers by decreasing modulus (stable order), real where every imaginary part is
    rounding."""
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    if np.all(np.abs(mu.imag) <= 1e-14 * np.maximum(1.0, np.abs(mu))):
        mu = mu.real
    return mu
