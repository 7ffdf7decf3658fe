"""Periodic motions with ``m`` impacts in ``n`` load periods (paper eqs. 8, 10, 11; theory §4, §5, §7).

A motion is cut into its ``m`` flights, one segment per flight, as in the hybrid multi-segment
boundary-value problems of continuation toolboxes (COCO's ``hspo``): each segment starts just after
an impact at load time ``t_j`` with the reduced state ``x_j = (q_1..q_N, q_0'..q_N')`` (``q_0``
follows from contact ``u(1, t_j) = 0``), flies in closed form (eq. 8) to the next impact time
``t_{j+1}``, where the end must touch the stop, and is mapped by the impact law (eq. 10) onto the
next segment's start. The last segment closes onto the first one ``2 pi n`` later. The unknowns are
the ``m`` impact times and states, ``2 m (N + 1)`` numbers, and the conditions as many: Newton's
method with the exact Jacobian (fundamental matrix and the vector field at both ends) needs no root
search. The Floquet multipliers are the eigenvalues of the product of the ``m`` impact-map Jacobians,
each with its saltation term (theory §7).

Under the wave impact law (theory §4b) each impact is a contact of duration ``2/s`` with a long
rod: the segment's state is taken at the end of the contact window, the flight lasts the interval
between impacts less ``2/s``, and the map across the window is affine in the arrival state, with the
drive's part and its rate from :func:`impactbar.laws.wave.impact.window_drive` (the analytic
Jacobian of :func:`impactbar.laws.wave.periodic.wave_impact_map_jacobian`, composed over the impacts).
Admissibility adds the characteristics solution's verdict on each contact (``"separates"``).

Here too :func:`periodic_orbits`, the one-impact orbits under every law (find_orbit's default
guess): from the law's phase equation (:mod:`impactbar.orbits.one_impact`), or, for a law without
one, by this solver from guesses (:func:`periodic_orbits_by_newton`).
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from .._shared.forcing import dispatch
from .._shared.threads import single_threaded_blas
from .._shared.validate import check_int, check_real
from ..drives.base import Drive
from ..dynamics.implementations import use_fast
from ..dynamics.modal import fundamental
from ..loads import Load
from ..model import BarModel
from ._assemble import _build
from ._newton import (
    POLISH_ITERATIONS,
    _chord,
    _converge,
    _converge_built,
)
from ._rigid_scalar import RigidFlight
from ._rigid_scalar import _b as _scalar_b
from .one_impact import OrbitList, _check_modes, phase_equation_orbits
from .orbit import MultiImpactOrbit as MultiImpactOrbit
from .orbit import PeriodicOrbit
from .phase import _check_inputs

__all__ = ["MultiImpactOrbit", "find_orbit", "periodic_orbits", "periodic_orbits_by_newton",
           "rock_periodic_orbits"]

TWO_PI = 2.0 * math.pi
MAX_UNKNOWNS = 6000
"""Largest segment problem, ``2 (N + 1) m`` unknowns: its dense Newton Jacobian takes
``8 * unknowns**2`` bytes (288 MB at the bound) and each Newton step a dense solve (seconds)."""
STALL_ITERATIONS = 40
"""Newton gives up when its residual has not halved in this many iterations (a bad start
wanders rather than converges)."""


# ------------------------------------------------------------------------------------------------
# the impact law: the one place that knows it
# ------------------------------------------------------------------------------------------------
def impact_law(model: BarModel, load: Load, t: float, y_minus: np.ndarray):
    """State where the next flight starts from the state at arrival, with its derivatives: the
    model's law's :meth:`~impactbar.laws.ContactLaw.impact_map` (eq. 10 under the paper's law,
    the contact window held for ``2/s`` under the wave law, theory §4b).

    Parameters
    ----------
    model : BarModel
    load : Load
        The drive load (it acts during a contact window).
    t : float
        Load time of the arrival (the start of contact).
    y_minus : numpy.ndarray, shape (2 N + 2,)
        Modal state ``(q_0..q_N, q_0'..q_N')`` at arrival.

    Returns
    -------
    y_plus : numpy.ndarray, shape (2 N + 2,)
        State where the next flight starts: just after the impact (eq. 10), at the end of the
        window (wave law).
    jac_y : numpy.ndarray, shape (2 N + 2, 2 N + 2)
        ``d y_plus / d y_minus``.
    jac_t : numpy.ndarray, shape (2 N + 2,)
        ``d y_plus / d t`` at fixed ``y_minus`` (zero for eq. 10).
    """
    return model.law.impact_map(model, load, t, y_minus)


def contact_window(model: BarModel) -> float:
    """Duration of an impact (the law's window): ``2/s`` under the wave law (theory §4b), 0 under
    eq. 10."""
    return model.law.window(model)


# ------------------------------------------------------------------------------------------------
# the multi-segment problem
# ------------------------------------------------------------------------------------------------
class _Segments:
    """The ``m``-segment boundary-value problem for one model, load, ``m`` and ``n``.

    Unknowns ``u = (t_1, x_1, ..., t_m, x_m)``, ``x_j`` of size ``2 M - 1`` (``M = N + 1``); residual
    block ``j``: ``(c . q(t_{j+1}-), reduce(impact(Y_j)) - x_{j+1})``.
    """

    def __init__(self, model: BarModel, load: Load, m: int, n: int):
        self.model, self.load, self.m, self.n = model, load, m, n
        M = model.n_modes + 1
        self.M = M
        size = 2 * M * m
        if size > MAX_UNKNOWNS:
            raise ValueError(
                f"impacts={m} with n_modes={model.n_modes} gives 2 (n_modes + 1) impacts = {size} "
                f"unknowns; the multi-impact problem is limited to {MAX_UNKNOWNS} (its dense Newton "
                f"Jacobian would take {8 * size**2 / 2**30:.3g} GiB): use fewer impacts or modes")
        self.w2 = model.frequencies**2
        self.d = model.d
        self.c = model.end_weights
        self.on_stop = model.law.flight_starts_on_stop
        # the components of a state the unknowns hold: q_0 = -sum_{n>=1} c_n q_n follows from contact,
        # unless a flight may start off the stop (the rod-rock law), where q_0 is an unknown too
        self.keep = slice(1, None) if self.on_stop else slice(0, None)
        self.B = 2 * M + (0 if self.on_stop else 1)  # unknowns (and conditions) per impact
        self.size = self.B * m
        self.T = contact_window(model)  # each flight starts T after its impact
        # the rigid bar under the paper's law: the whole evaluation in plain floats
        self.rigid = (RigidFlight(model.d, load) if M == 1 and model.law.rigid_closed_forms
                      and use_fast("orbits.rigid_segments") else None)

    # -- pieces -----------------------------------------------------------------------------------
    @cached_property
    def E(self):
        """Full state from reduced, shape ``(2 M, B - 1)`` (built once, on the general path only)."""
        M = self.M
        if not self.on_stop:
            return np.eye(2 * M)
        E = np.zeros((2 * M, 2 * M - 1))
        E[0, : M - 1] = -self.c[1:]
        E[1:M, : M - 1] = np.eye(M - 1)
        E[M:, M - 1:] = np.eye(M)
        return E

    def split(self, u):
        z = np.asarray(u, dtype=float).reshape(self.m, self.B)
        return z[:, 0], z[:, 1:]

    def full(self, x):
        return self.E @ x

    def f(self, t, y, left=False):
        """Vector field ``(q', p(t) - d q' - w2 q)`` (eq. 6); ``left`` takes ``p(t-)``."""
        M = self.M
        p = float(self.load.left_limit(t) if left else self.load(t))
        return np.concatenate((y[M:], p - self.d * y[M:] - self.w2 * y[:M]))

    def flight(self, t0, y0, t1):
        """State at ``t1`` of the flight that starts at ``t0`` in state ``y0`` (eq. 8)."""
        M = self.M
        q, v = self.load.propagate(self.w2, self.d, t0, y0[:M], y0[M:], [t1])
        return np.concatenate((q[:, 0], v[:, 0]))

    def phi(self, T):
        """Fundamental matrix of the free flight over ``T``, shape ``(2 M, 2 M)``."""
        p11, p12, p21, p22 = fundamental(self.w2, self.d, T)
        M = self.M
        i = np.arange(M)
        Phi = np.zeros((2 * M, 2 * M))
        Phi[i, i], Phi[i, i + M], Phi[i + M, i], Phi[i + M, i + M] = p11, p12, p21, p22
        return Phi

    def evaluate(self, u, jacobian=True):
        """Residual (and Jacobian) of the periodicity conditions; also the states at the impacts.

        Returns
        -------
        F : numpy.ndarray, shape (size,)
        DF : numpy.ndarray, shape (size, size) or None
        info : dict
            ``y_plus``, ``y_minus`` (m, 2 M) and the per-impact map Jacobians ``maps`` (m, 2 M, 2 M)
            (only with ``jacobian``).
        """
        if self.rigid is not None:
            return self._evaluate_rigid(u, jacobian)
        m, M = self.m, self.M
        K, B, keep = 2 * M, self.B, self.keep
        t, x = self.split(u)
        F = np.empty(self.size)
        DF = np.zeros((self.size, self.size)) if jacobian else None
        y_plus = np.empty((m, K))
        y_minus = np.empty((m, K))
        maps = np.empty((m, B, B)) if jacobian else None
        for j in range(m):
            jn = (j + 1) % m
            t1 = t[jn] + (TWO_PI * self.n if jn == 0 else 0.0)
            y0 = self.full(x[j])
            ts = t[j] + self.T
            Y = self.flight(ts, y0, t1)
            if jacobian:
                yp, Jy, Jt = impact_law(self.model, self.load, t1, Y)
            else:  # (the state alone: a law's Jacobian may cost many maps)
                yp = self.model.law.impact_state(self.model, self.load, t1, Y)
            y_plus[j], y_minus[j] = y0, Y
            r = slice(B * j, B * (j + 1))
            F[B * j] = self.c @ Y[:M]
            F[B * j + 1: B * (j + 1)] = yp[keep] - x[jn]
            if not jacobian:
                continue
            Phi = self.phi(t1 - ts)
            A = np.empty((K, B))  # dY / d(t_j, x_j)
            A[:, 0] = -Phi @ self.f(ts, y0)
            A[:, 1:] = Phi @ self.E
            f1 = self.f(t1, Y, left=True)  # dY / d t_{j+1}
            rows = np.vstack((self.c @ A[:M], (Jy @ A)[keep]))
            tcol = np.concatenate(([self.c @ f1[:M]], (Jy @ f1 + Jt)[keep]))
            DF[r, B * j: B * (j + 1)] += rows
            DF[r, B * jn] += tcol
            DF[B * j + 1: B * (j + 1), B * jn + 1: B * (jn + 1)] -= np.eye(B - 1)
            # the impact map z_j -> z_{j+1} with the impact time eliminated (saltation, theory §7)
            v_imp = float(self.c @ Y[M:])
            with np.errstate(divide="ignore", invalid="ignore"):
                rt = -(self.c @ A[:M]) / v_imp
            dy = Jy @ (A + np.outer(f1, rt)) + np.outer(Jt, rt)
            maps[j, 0] = rt
            maps[j, 1:] = dy[keep]
        return F, DF, {"y_plus": y_plus, "y_minus": y_minus, "maps": maps}

    def _evaluate_rigid(self, u, jacobian):
        """:meth:`evaluate` for the rigid bar under the paper's law, in plain floats: the same
        residual, Jacobian and impact maps as the general path with ``M = 1`` (the state after an
        impact is ``(0, v)``, eq. 10 is ``(q, v) -> (q, -R v)``, the fundamental matrix is
        ``[[1, b(T)], [0, e^{-d T}]]``), without its dozens of small numpy calls per flight."""
        m, d, R, flight = self.m, self.d, self.model.R, self.rigid
        z = np.asarray(u, dtype=float).reshape(m, 2)
        t, x = z[:, 0].tolist(), z[:, 1].tolist()
        F = np.empty(2 * m)
        y_plus = np.zeros((m, 2))
        y_plus[:, 1] = x
        y_minus = np.empty((m, 2))
        DF = np.zeros((2 * m, 2 * m)) if jacobian else None
        maps = np.empty((m, 2, 2)) if jacobian else None
        for j in range(m):
            jn = (j + 1) % m
            t0, v0 = t[j], x[j]
            t1 = t[jn] + (TWO_PI * self.n if jn == 0 else 0.0)
            q1, v1, p0, p1 = flight.state(t0, 0.0, v0, t1)
            y_minus[j] = q1, v1
            F[2 * j] = q1
            F[2 * j + 1] = -R * v1 - x[jn]
            if not jacobian:
                continue
            T = t1 - t0
            b, e = _scalar_b(d, T), math.exp(-d * T)
            a0, a1 = p0 - d * v0, p1 - d * v1  # accelerations at both ends of the flight
            A00, A01, A10, A11 = -(v0 + b * a0), b, -e * a0, e  # d(q1, v1) / d(t0, v0)
            r, c = 2 * j, 2 * jn
            DF[r, c] += v1  # d / d t1
            DF[r + 1, c] -= R * a1
            DF[r, r] += A00
            DF[r, r + 1] += A01
            DF[r + 1, r] -= R * A10
            DF[r + 1, r + 1] -= R * A11
            DF[r + 1, c + 1] -= 1.0
            rt0, rt1 = _quotient(-A00, v1), _quotient(-A01, v1)  # d t1 / d(t0, v0) at contact
            maps[j] = (rt0, rt1), (-R * (A10 + a1 * rt0), -R * (A11 + a1 * rt1))
        return F, DF, {"y_plus": y_plus, "y_minus": y_minus, "maps": maps}

    def monodromy(self, maps):
        """Product of the impact-map Jacobians, first impact first: ``DP_m ... DP_1``."""
        P = maps[0]
        for j in range(1, self.m):
            P = maps[j] @ P
        return P

    def scale(self, u):
        return max(1.0, float(np.max(np.abs(u))))

    def newton(self, u, *, tol=1e-12, max_iter=40, check=True):
        """Newton's method on ``F(u) = 0``. Returns the converged ``u`` or ``None``, and the
        iteration count; it stops early (``None``) when the residual has not halved in
        ``STALL_ITERATIONS`` iterations. With ``check`` the residual at the converged ``u`` must be
        finite (the caller checks it otherwise)."""
        u = np.array(u, dtype=float)
        best, best_it = math.inf, 0
        for it in range(1, max_iter + 1):
            F, DF, _ = self.evaluate(u)
            if not np.all(np.isfinite(F)) or not np.all(np.isfinite(DF)):
                return None, it
            size = float(np.max(np.abs(F)))
            if size <= 0.5 * best:
                best, best_it = size, it
            elif it - best_it >= STALL_ITERATIONS:
                return None, it
            try:
                du = np.linalg.solve(DF, F)
            except np.linalg.LinAlgError:
                return None, it
            u = u - du
            if float(np.max(np.abs(du))) <= tol * self.scale(u):
                if not check:
                    return u, it
                F, _, _ = self.evaluate(u, jacobian=False)
                return (u if np.all(np.isfinite(F)) else None), it
        return None, max_iter


def _quotient(a: float, b: float) -> float:
    """``a / b`` as numpy divides floats with its warnings off: ``+-inf`` or NaN where ``b = 0``
    (a grazing arrival's saltation term)."""
    if b != 0.0 or b != b:
        return a / b if b == b else math.nan
    if a == 0.0 or a != a:
        return math.nan
    return math.copysign(math.inf, a) * math.copysign(1.0, b)


# ------------------------------------------------------------------------------------------------
# guesses
# ------------------------------------------------------------------------------------------------
def _unknowns_from(problem: _Segments, times, states):
    """Unknown vector from impact times (m,) and full post-impact states (m, 2 M)."""
    times = np.asarray(times, dtype=float).ravel()
    states = np.asarray(states, dtype=float).reshape(times.size, -1)
    if times.size != problem.m or states.shape[1] != 2 * problem.M:
        raise ValueError(f"guess must give {problem.m} impact times and states of length "
                         f"{2 * problem.M}; got {times.size} times and states of shape {states.shape}")
    if not (np.all(np.isfinite(times)) and np.all(np.isfinite(states))):
        raise ValueError("guess must be finite")
    z = np.empty((problem.m, problem.B))
    z[:, 0] = times
    z[:, 1:] = states[:, problem.keep]
    return z.ravel()


def _as_segments(orbit):
    """(times, post-impact states, m, n) of a PeriodicOrbit."""
    return orbit.impact_times, orbit.states_after_impact, orbit.impacts, orbit.periods


def _repeat(times, states, n0, reps):
    t = np.concatenate([times + TWO_PI * n0 * r for r in range(reps)])
    return t, np.concatenate([states] * reps)


def doubling_direction(orbit, rank: int = 0):
    """The orbit taken twice round and the direction of the doubled orbit born at its period
    doubling (theory §7).

    With ``e`` the eigenvector of the monodromy's multiplier nearest ``-1`` and ``P_j`` the impact
    maps, the perturbation ``(e, P_1 e, ..., -e, -P_1 e, ...)`` of the ``2 m``-impact segment
    problem is its null vector at the doubling (the second copy is the first, mirrored).

    Parameters
    ----------
    orbit : PeriodicOrbit
    rank : int
        Which multiplier's eigenvector: the nearest ``-1`` (0, default), the next nearest (1), ...
        (where two multipliers are close to ``-1``, branch switching tries each).

    Returns
    -------
    z : numpy.ndarray, shape (2 m * 2 (N + 1),)
        Unknowns of the doubled segment problem for the orbit twice round.
    w : numpy.ndarray, same shape
        The direction, scaled to a largest entry of 1.
    """
    times, states, m0, n0 = _as_segments(orbit)
    base = _Segments(orbit.model, orbit.load, m0, n0)
    u0 = _unknowns_from(base, times, states)
    _, _, info = base.evaluate(u0)
    maps = info["maps"]
    mu, vec = np.linalg.eig(base.monodromy(maps))
    e = np.real(vec[:, int(np.argsort(np.abs(mu + 1.0), kind="stable")[rank])])
    pert = [e / np.max(np.abs(e))]
    for j in range(m0 - 1):
        pert.append(maps[j] @ pert[-1])
    pert = np.array(pert)
    z = np.concatenate([u0.reshape(m0, -1)] * 2)
    z[m0:, 0] += TWO_PI * n0
    w = np.concatenate((pert, -pert)).ravel()
    return z.ravel(), w / np.max(np.abs(w))


def _doubling_guesses(problem: _Segments, orbit,
                      amplitudes=(1e-2, -1e-2, 0.1, -0.1, 0.3, -0.3, 0.6, -0.6, 1.0, -1.0)):
    """Starts for the doubled orbit near a period doubling of ``orbit``: the orbit twice, pushed
    along :func:`doubling_direction` by a range of amplitudes (relative to its velocities)."""
    z, w = doubling_direction(orbit)
    _, states, _, _ = _as_segments(orbit)
    scale = max(1e-12, float(np.max(np.abs(states[:, problem.M:]))))
    return [z + a * scale * w for a in amplitudes], z


def _guesses(problem: _Segments, guess):
    """Candidate unknown vectors from the user's guess, best first, and a vector to avoid (the
    undoubled orbit repeated, when starting across a period doubling) or None."""
    m, n = problem.m, problem.n
    if guess is None:
        if m != n:
            raise ValueError(f"guess is required for impacts={m} != periods={n}")
        orbits = [o for o in periodic_orbits(problem.model, problem.load) if np.isfinite(o.phase)]
        if not orbits:
            raise ValueError("guess is required: there is no one-impact orbit to start from")
        orbits.sort(key=lambda o: (not o.stable, not o.admissible, o.max_abs_multiplier))
        return [_unknowns_from(problem, *_repeat(np.array([o.phase]), o.state_after_impact[None, :],
                                                 1, n)) for o in orbits], None
    if hasattr(guess, "orbit") and hasattr(guess, "kind") and hasattr(guess, "multiplier"):
        guess = guess.orbit  # a BranchEvent: its orbit (a period doubling's starts the doubled one)
    if isinstance(guess, PeriodicOrbit):
        times, states, m0, n0 = _as_segments(guess)
        if m % m0 or n % n0 or m // m0 != n // n0:
            raise ValueError(f"guess has {m0} impacts in {n0} periods; it can start an orbit with "
                             f"impacts={m0}*j, periods={n0}*j, not impacts={m}, periods={n}")
        reps = m // m0
        mu = guess.multipliers
        near_pd = np.any((mu.real < -0.5) & (np.abs(mu.imag) <= 1e-9 * np.maximum(1.0, np.abs(mu))))
        if reps == 2 and near_pd:
            starts, avoid = _doubling_guesses(problem, guess)
            return starts, avoid
        return [_unknowns_from(problem, *_repeat(times, states, n0, reps))], None
    if hasattr(guess, "impact_times") and hasattr(guess, "modal_state"):  # a Trajectory
        ti = np.asarray(guess.impact_times)
        if ti.size < m + 1:
            raise ValueError(f"guess (a Trajectory) has {ti.size} impacts; at least impacts + 1 = "
                             f"{m + 1} are needed")
        span = ti[-1] - ti[-1 - m]
        if abs(span - TWO_PI * n) > 0.25 * TWO_PI:
            raise ValueError(f"guess: the last {m} impact intervals of the Trajectory span "
                             f"{span:.6g}, far from 2 pi periods = {TWO_PI * n:.6g}")
        times = ti[-1 - m:-1]
        q, v = guess.modal_state(times + problem.T)  # where each flight starts
        states = np.vstack((q, v)).T
        if states.shape[1] != 2 * problem.M:
            raise ValueError("guess: the Trajectory's model has another number of modes")
        return [_unknowns_from(problem, times, states)], None
    if isinstance(guess, tuple) and len(guess) == 2:
        return [_unknowns_from(problem, guess[0], guess[1])], None
    raise ValueError("guess must be a PeriodicOrbit (MultiImpactOrbit), a Trajectory or a tuple "
                     f"(impact_times, states_after_impact); got {type(guess).__name__}")


def find_orbit(model: BarModel, load: Load | Drive, impacts: int = 1, periods: int = 1, guess=None, *,
               tol: float = 1e-12, max_iter: int = 40) -> PeriodicOrbit:
    r"""A periodic motion with ``impacts`` impacts in ``periods`` load periods, by Newton's method on
    the exact impact map (eqs. 8, 10, 11; theory §4, §5, §7).

    Each flight is the closed-form motion of the modal oscillators (eq. 8); the unknowns are the impact
    times and the states just after them, the conditions are contact at each impact and the impact law
    (eq. 10, or the wave law of theory §4b) between consecutive flights, closing after :math:`2\pi n` (``n
    = periods``). The Jacobian is exact (fundamental matrix, vector field at both ends of each flight, the
    wave law's drive rate); the multipliers are the eigenvalues of the product of the ``impacts``
    impact-map Jacobians with their saltation terms.

    Parameters
    ----------
    model : BarModel
        Either impact law: the paper's (eq. 10) or the wave law (``impact="wave"``, theory §4b),
        where each impact lasts :math:`2/s` and the flights start at the windows' ends.
    load : Load
        Any load of period :math:`2\pi`.
    impacts : int
        :math:`m \ge 1`, impacts per period of the motion.
    periods : int
        :math:`n \ge 1`, load periods per period of the motion.
    guess : optional
        Where Newton starts:

        - ``None``: the one-impact orbits of :func:`periodic_orbits`, repeated (``impacts ==
          periods`` only), stable ones first;
        - a :class:`~impactbar.continuation.BranchEvent`: its orbit (a period-doubling event
          starts the doubled orbit, as below);
        - a :class:`PeriodicOrbit` with ``m0`` impacts in ``n0``
          periods, repeated ``j`` times for ``impacts = j m0``, ``periods = j n0``; for ``j = 2``
          and a guess with a real multiplier below ``-1/2`` the copies are pushed apart along its
          eigenvector, so that an orbit near or past its period doubling gives the doubled orbit
          (a ``ValueError`` if Newton only finds the guess again);
        - a :class:`Trajectory`: its last ``impacts`` impacts (they must span about
          :math:`2\pi n` with ``n = periods``);
        - a tuple ``(impact_times, states_after_impact)`` of shapes ``(m,)`` and ``(m, 2 N + 2)``
          (under the wave law, the states at the windows' ends).
    tol : float
        Relative tolerance of the Newton step.
    max_iter : int
        Newton iterations per start, from 1 to 1000; a start stops earlier when the residual has not
        halved in 40 iterations.

    Returns
    -------
    PeriodicOrbit
        With ``impacts`` and ``periods`` as asked (``MultiImpactOrbit`` is another name for it).

    Raises
    ------
    ValueError
        For bad arguments (named), an unknown impact law, wave-law windows that do not fit
        (:math:`2m/s \ge 2\pi n`), a problem of more than ``MAX_UNKNOWNS = 6000``
        unknowns ``2 (n_modes + 1) impacts`` (its dense Jacobian), or when Newton does not
        converge from any start derived from ``guess`` (or only back onto the undoubled orbit).

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, find_orbit
    >>> o = find_orbit(BarModel(s=10, d=0, R=0.5, n_modes=4), CosineLoad(0.1, 1.0))
    >>> round(o.phase, 4), o.impacts
    (3.0367, 1)

    With a :class:`~impactbar.Drive` in place of the load (e.g. a
    :class:`~impactbar.PositionSwitchedDrive`) the system is autonomous and the period is unknown
    (theory §10): the result is a :class:`~impactbar.SwitchedOrbit`, a :class:`PeriodicOrbit`
    (``impacts`` per period; ``periods`` ignored; under every impact law), from
    :func:`~impactbar.orbits.find_switched_orbit`.
    """
    max_iter = check_int("max_iter", max_iter, lo=1, hi=1000)
    return dispatch(FIND_ORBIT, load)(model, load, impacts, periods, guess, tol, max_iter)


def _drive_orbit(model, drive, impacts, periods, guess, tol, max_iter) -> PeriodicOrbit:
    """:func:`find_orbit` under a drive: an autonomous orbit of unknown period (theory §10;
    ``periods`` has no meaning there)."""
    from .switched_search import find_switched_orbit  # (the drives' machinery, loaded on first use)

    return find_switched_orbit(model, drive, impacts, guess, tol=min(tol, 1e-13), max_iter=max(max_iter, 50))


def _load_orbit(model, load, impacts, periods, guess, tol, max_iter) -> PeriodicOrbit:
    """:func:`find_orbit` under a periodic load: Newton on the segment problem (theory §7)."""
    _check_inputs(model, load)
    m = check_int("impacts", impacts, lo=1, hi=4096)
    n = check_int("periods", periods, lo=1, hi=4096)
    tol = check_real("tol", tol, lo=0.0, lo_open=True, hi=1e-3)
    _check_law(model, load)
    if not m * contact_window(model) < TWO_PI * n:
        raise ValueError(f"impacts={m} contact windows of 2/s = {contact_window(model):.6g} do not fit "
                         f"in periods={n} load periods (wave law: s must exceed m/(pi n))")
    problem = _Segments(model, load, m, n)
    starts, avoid = _guesses(problem, guess)
    coarse = model.law.coarse_model(model)
    with single_threaded_blas():
        if coarse is not None and guess is not None:  # a guess of the motion: Newton on this model
            for u0 in starts:  # (its exact Jacobian costs a few blows) while it converges at once
                orbit = _converge_built(problem, u0, avoid, tol, min(max_iter, DIRECT_ITERATIONS))
                if orbit is not None:
                    return orbit
        if coarse is not None:  # Newton on the cheaper model first, its orbits polished on this one
            rough = _Segments(coarse, load, m, n)
            near = [u for u in (_converge(rough, u0, avoid, tol, max_iter) for u0 in starts) if u is not None]
            for u0 in near:
                u = _chord(problem, u0, rough.evaluate(u0)[1], avoid, tol)
                if u is None:
                    u = _converge(problem, u0, avoid, tol, min(max_iter, POLISH_ITERATIONS))
                if u is not None:
                    return _build(problem, u)
        for u0 in starts:
            orbit = _converge_built(problem, u0, avoid, tol, max_iter)
            if orbit is not None:
                return orbit
    raise ValueError(f"find_orbit: Newton did not converge to an orbit with {m} impacts in {n} "
                     "periods from the guess" + (" (only to the undoubled orbit)" if avoid is not None
                                                  else ""))


def _check_law(model, load):
    """Refuse at once a law without an impact map (``LawNotSupported``) or a load its map cannot
    take (a ``ValueError``, from one impact state from rest; not under a law with a coarse model,
    whose map is a whole blow: there the first residual refuses such a load)."""
    from ..laws.base import ContactLaw, LawNotSupported

    law = model.law
    if type(law).impact_map is ContactLaw.impact_map:
        raise LawNotSupported(law._missing("impact_map"))
    if law.coarse_model(model) is None:
        law.impact_state(model, load, 0.0, np.zeros(2 * model.n_modes + 2))


#: Newton iterations on the law's own model from a given guess before the coarse model is tried
#: (:func:`find_orbit`; a guess near the orbit converges in three to five)
DIRECT_ITERATIONS = 8


# ------------------------------------------------------------------------------------------------
# the one-impact orbits of every law (find_orbit's default guess): from the law's phase equation, or
# by Newton's method from guesses where it has none (both here, since each calls the other)
# ------------------------------------------------------------------------------------------------
def periodic_orbits(model: BarModel, load: Load | Drive, *, window=None) -> OrbitList:
    r"""Every one-impact-per-period steady state of the bar under the load (paper Section 2).

    Each root ``phase`` of the phase equation (eq. 14) in :math:`[0, 2\pi)` gives one orbit: the flexible
    modes' start state solves the periodicity and impact conditions (eqs. 10-13) exactly, mode by
    mode; the rigid mode strikes at :math:`2\pi p_0/(1 + R)` and its constant is fixed by contact
    :math:`u(1, 0) = 0` (:func:`~impactbar.orbits.one_impact.phase_equation_orbits`; under the wave law
    its own phase equation, theory §4b). Under a law without a phase equation
    (:attr:`~impactbar.laws.ContactLaw.has_phase_equation` ``False``, e.g. the rod-rock law) the
    orbits come from Newton's method from guesses instead (:func:`periodic_orbits_by_newton`): the
    orbits found, not a certified set.

    Parameters
    ----------
    model : BarModel
    load : Load
        Any load of period :math:`2\pi`: ``CosineLoad``, ``SquareWaveLoad``, ``FourierLoad``, ...;
        or a :class:`~impactbar.Drive` (theory §10): every one-impact orbit with a period in
        ``window`` (:func:`~impactbar.orbits.drive_orbits`).
    window : (float, float), optional
        Under a drive only: the periods searched.

    Returns
    -------
    OrbitList
        A ``list`` of :class:`PeriodicOrbit` sorted by phase, empty when none exists (e.g. above the
        fold, eq. 38); ``.to_dataframe()`` and ``.to_xarray()`` make it a table. Where the phase
        equation holds on a whole interval (a degenerate family, wave law), ``.families`` holds
        the interval and one orbit with ``multiplicity = 0`` stands for it, at its middle.

    Raises
    ------
    ValueError
        For inputs of the wrong type, or at an undamped resonance :math:`s n \pi = k` (eq. 16).

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, periodic_orbits
    >>> orbits = periodic_orbits(BarModel(s=10, d=0, R=0.5, n_modes=4), CosineLoad(0.5, 1.0))
    >>> [round(o.phase, 4) for o in orbits]
    [0.5511, 2.5905]
    """
    return dispatch(PERIODIC_ORBITS, load)(model, load, window)


def _drive_orbits(model, drive, window) -> OrbitList:
    """:func:`periodic_orbits` under a drive: every one-impact orbit in a window of periods (theory
    §10)."""
    from .switched_search import drive_orbits  # (the drives' machinery, loaded on first use)

    return drive_orbits(model, drive, window)


def _load_orbits(model, load, window) -> OrbitList:
    """:func:`periodic_orbits` under a periodic load: the law's phase equation, or Newton from
    guesses."""
    if window is not None:
        raise ValueError("window is for a drive's orbits (unknown period); a load's period is 2 pi")
    _check_inputs(model, load)
    _check_modes(model)
    if not model.law.has_phase_equation:  # the blow is a numerical map: Newton from guesses
        return periodic_orbits_by_newton(model, load)
    return phase_equation_orbits(model, load)


#: the solver of :func:`find_orbit` for each forcing family (the one place it is chosen)
FIND_ORBIT = {"load": _load_orbit, "drive": _drive_orbit}
#: the solver of :func:`periodic_orbits` for each forcing family (the one place it is chosen)
PERIODIC_ORBITS = {"load": _load_orbits, "drive": _drive_orbits}

#: load periods of the simulation guess
SETTLE_PERIODS = 60


def _paper_guesses(model: BarModel, load: Load) -> list:
    """The one-impact orbits of the law's paper-equivalent bar, stable ones first, each at its phase
    with the state it has one window after its impact (where this law's flight starts)."""
    law = model.law
    paper = law.paper_equivalent(model)
    T = law.window(model)
    guesses = []
    for o in sorted(periodic_orbits(paper, load), key=lambda o: (not o.stable, o.phase)):
        if not np.isfinite(o.phase):
            continue
        q, v = o.modal_state(np.array([T]))
        guesses.append((np.array([o.phase]), np.concatenate((q[:, 0], v[:, 0]))[None, :]))
    return guesses


def _simulated_guess(model: BarModel, load: Load):
    """A simulation from rest over :data:`SETTLE_PERIODS` load periods, if it has settled to one
    impact per period; else ``None``. It starts a gap of 0.1 times the problem's force scale (the
    load's bound, or the law's feed where larger) from the stop, so that the guess is the same
    motion at every scale of the load (the problem is homogeneous of degree one in it)."""
    from ..simulation import InitialState, simulate  # the simulator, loaded where a guess needs it

    scale = max(float(load.sup_abs), float(getattr(model.law, "feed", 0.0))) or 1.0
    try:
        tr = simulate(model, load, InitialState.rigid(-0.1 * scale, 0.0, n_modes=model.n_modes),
                      TWO_PI * SETTLE_PERIODS)
    except ValueError:
        return None
    ti = np.asarray(tr.impact_times)
    if ti.size < 4 or not np.allclose(np.diff(ti[-4:]), TWO_PI, atol=1e-3):
        return None
    return tr


def periodic_orbits_by_newton(model: BarModel, load: Load) -> OrbitList:
    """The one-impact orbits under a law without a phase equation, by Newton's method from guesses
    (theory §4d, §10): :func:`~impactbar.periodic_orbits` for such a model (e.g.
    ``impact=RodRock(...)``).

    The blow is a numerical map (for the rod-rock law, characteristics on the cell grid,
    :meth:`~impactbar.RodRock.impact_map`), so there is no closed-form phase equation to search:
    each orbit is found by :func:`~impactbar.find_orbit` (one impact in one period, the flight's
    start ``q_0`` among the unknowns where the law's flights may start off the stop) from two kinds
    of guesses:

    1. the one-impact orbits of the law's paper-equivalent bar
       (:meth:`~impactbar.laws.ContactLaw.paper_equivalent`: the same bar and load under the paper's
       law with the restitution this law's contact gives; for the rod-rock law a rigid piston's
       rebound from its rod and rock, ``R = -rebound_velocity / V`` at ``V = 1``, clipped to
       ``[0, 0.95]``), each taken at its phase with the state it has one window
       (:meth:`~impactbar.laws.ContactLaw.window`) after the impact, where this law's flight starts;
    2. where none of those gives a stable orbit, the end of a simulation from rest (60 load
       periods, started a gap of 0.1 times the load's bound from the stop), if it has settled to
       one impact per period.

    Steps and starts scale with the load (the finite-difference steps of the impact map are
    relative to the state), so that the orbits found are the same at every scale of the load.

    Where the law has a cheaper model of the same motion (:meth:`~impactbar.laws.ContactLaw.coarse_model`:
    the rod-rock law's exact blows on the lattice), each guess goes to it first and its orbit is
    polished on the law's own model. Orbits found twice (phases within ``1e-7``) are kept once.
    Guesses from which Newton does not converge give nothing: the list holds the orbits found, not a
    certified set of all of them.

    Parameters
    ----------
    model : BarModel
        Under a law with ``has_phase_equation = False`` (any law with ``window``, ``impact_map`` and
        ``contact`` is accepted).
    load : Load
        Of period ``2 pi``.

    Returns
    -------
    OrbitList
        Sorted by phase; each a :class:`~impactbar.PeriodicOrbit` of :func:`~impactbar.find_orbit`
        (multipliers of the law's impact map, admissibility, the law's record per blow in
        ``contacts``). Empty when no guess converges.

    Raises
    ------
    ValueError
        For a model or load :func:`~impactbar.find_orbit` refuses (named).

    Examples
    --------
    >>> import impactbar as ib
    >>> law = ib.RodRock(segments=[ib.RodSegment(length=10.0, impedance=2.0)],
    ...                  rock=ib.BilinearRock(k=60.0, k_u=1e6), blow_time=2.0)
    >>> model = ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=0, impact=law)
    >>> load = ib.PiecewiseConstantLoad([0.0, 1.0, 3.0], [-1.0, 2.0, 0.0])
    >>> orbits = ib.periodic_orbits(model, load)  # calls periodic_orbits_by_newton
    >>> [(round(o.phase, 4), o.stable) for o in orbits]
    [(2.6008, False), (3.5461, True)]
    """
    found = []
    coarse = model.law.coarse_model(model)
    starts = _paper_guesses(model if coarse is None else coarse, load)
    with single_threaded_blas():
        for guess in [*starts, None]:
            if guess is None:
                if any(o.stable for o in found):
                    break
                guess = _simulated_guess(model, load)
                if guess is None:
                    break
            try:
                if coarse is not None:  # the cheaper model's orbit from the guess, or none
                    guess = find_orbit(coarse, load, 1, 1, guess=guess)
                orbit = find_orbit(model, load, 1, 1, guess=guess)
            except ValueError:
                continue
            if all(abs(math.remainder(orbit.phase - o.phase, TWO_PI)) > 1e-7 for o in found):
                found.append(orbit)
    out = OrbitList(sorted(found, key=lambda o: o.phase))
    out._families = ()
    return out


#: :func:`periodic_orbits_by_newton` under the name it had in ``impactbar.laws`` (the rod-rock law's)
rock_periodic_orbits = periodic_orbits_by_newton
