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

The entry points that solve it, :func:`~impactbar.orbits.find.find_orbit` (from the starts a guess
gives) and :func:`~impactbar.orbits.find.periodic_orbits`, are in :mod:`impactbar.orbits.find`.
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from ..dynamics.implementations import use_fast
from ..dynamics.modal import fundamental
from ..laws.abilities import newton_start
from ..loads import Load
from ..loads.abilities import left_limit
from ..model import BarModel
from ._rigid_scalar import RigidFlight
from ._rigid_scalar import _b as _scalar_b
from .orbit import MultiImpactOrbit as MultiImpactOrbit

__all__ = ["MultiImpactOrbit", "impact_law", "doubling_direction"]

TWO_PI = 2.0 * math.pi
MAX_UNKNOWNS = 6000
"""Largest segment problem, ``2 (N + 1) m`` unknowns: its dense Newton Jacobian takes
``8 * unknowns**2`` bytes (288 MB at the bound) and each Newton step a dense solve (seconds)."""
#: an impact's row of the unknowns (``u`` reshaped to ``(m, B)``): its time, then its state from
#: ``Z_STATE`` on
Z_TIME, Z_STATE = 0, 1
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
        self.on_stop = model.law.traits.flight_starts_on_stop
        # the components of a state the unknowns hold: q_0 = -sum_{n>=1} c_n q_n follows from contact,
        # unless a flight may start off the stop (the rod-rock law), where q_0 is an unknown too
        self.keep = slice(1, None) if self.on_stop else slice(0, None)
        self.B = 2 * M + (0 if self.on_stop else 1)  # unknowns (and conditions) per impact
        self.size = self.B * m
        self.T = contact_window(model)  # each flight starts T after its impact
        # the rigid bar under the paper's law: the whole evaluation in plain floats
        self.rigid = (RigidFlight(model.d, load) if M == 1 and model.law.traits.rigid_closed_forms
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
        return z[:, Z_TIME], z[:, Z_STATE:]

    def full(self, x):
        return self.E @ x

    def f(self, t, y, left=False):
        """Vector field ``(q', p(t) - d q' - w2 q)`` (eq. 6); ``left`` takes ``p(t-)``."""
        M = self.M
        p = float(left_limit(self.load, t) if left else self.load(t))
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
                yp = newton_start(self.model.law).impact_state(self.model, self.load, t1, Y)
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
        t, x = z[:, Z_TIME].tolist(), z[:, Z_STATE].tolist()
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
    z[:, Z_TIME] = times
    z[:, Z_STATE:] = states[:, problem.keep]
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
    z[m0:, Z_TIME] += TWO_PI * n0
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

