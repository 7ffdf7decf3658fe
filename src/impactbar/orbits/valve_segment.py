r"""The valve's periodic orbits: the segment problem (theory §10).

One period of a one-impact orbit, counted from an impact (the valve's rules of
:class:`~impactbar.PositionSwitchedDrive`, delays ``tau_in`` after the impact and ``tau_out`` after
the crossing):

1. stroke force for ``tau_in`` (the switch to return triggered by the impact takes effect);
2. return force for ``h1``, until the gap ``y = -q_0`` rises through ``switch_out``;
3. return force for ``tau_out`` (the switch to stroke takes effect);
4. stroke force for ``h3``, until the struck end reaches the stop, ``c . q = 0``; the impact law
   (eq. 10) gives the state after the impact.

Every flight is the closed-form constant-force flow of the modes (eq. 8). The unknowns are the
state after the impact and the durations ``h1``, ``h3`` (the period is
``T = tau_in + h1 + tau_out + h3``); the
conditions are the switch, the contact and the impact law, solved by Newton's method with the exact
Jacobian (:class:`ValveProblem`, the valve's :class:`~impactbar.drives.OrbitProblem`). The monodromy
matrix is the product of the flows' fundamental matrices and of the saltation matrices at the switch
and the impact (Hiskens & Pai 2000; di Bernardo et al., *Piecewise-smooth Dynamical Systems*, 2008,
§2.5); one of its eigenvalues is the trivial ``1`` along the flow, reported apart, the others are the
multipliers of the Poincare map. With :math:`m \ge 2` impacts the intervals may differ (a period-2 motion
after a period doubling): multiple shooting, ``m`` blocks ``(state after impact k, h1_k, h3_k)``.

Under a law whose contact takes time (the wave law, theory §4b; the rod-rock law, §4d) the impact
is the law's contact, held under the stroke force for its duration ``ContactLaw.window`` (as
:func:`impactbar.simulate` runs it: the switch to return counts from the contact's end). The
unknowns hold the state where the contact ends; eq. 10 is replaced by the contact's map with its
Jacobian (exact for the wave law and the rod-rock law's exact blows, central differences on its
lattice); the period is
``T = window + tau_in + h1 + tau_out + h3``. The multipliers are those of the return map on the arrival
surface ``c . q = 0``, built from the same Jacobian by the implicit function theorem (the switch
and arrival times depend on the state); the trivial multiplier along the flow is then exactly 1.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..drives.orbitproblem import OrbitData, OrbitProblem, OrbitSearch, sorted_multipliers, split_multipliers
from ..drives.valve import RETURN, STROKE
from ..drives.valve.closed_forms import (
    rigid_orbit_start,
)
from ..dynamics.modal import step_constant
from ..laws.abilities import newton_start
from ._valve_flow import _affine, _apply, _blocks, _compose, _field, _fund, _legs, _matrix, _w2
from .valve_admissibility import _admissibility

if TYPE_CHECKING:
    from ..model import BarModel


class ContactMap:
    """The law's contact of an arrival under the constant stroke force, for a law whose contact
    takes time (the wave law, the rod-rock law): ``zd -> (z_after, dz_after/dzd)``
    (``ContactLaw.impact_map`` at load time 0; the force is constant, so the time does not matter),
    memoised on the last arrival state (Newton asks for it once per step, the orbit again).
    ``window`` is the contact's duration (``ContactLaw.window``); ``constant_load(p)`` the load of
    the constant force ``p`` (from the orbit solver: the loads sit beside the drives)."""

    def __init__(self, model: BarModel, drive, constant_load) -> None:
        self.model, self.law = model, model.law
        self.load = constant_load(float(drive.stroke))
        self.window = float(model.law.window(model))
        self._last = None

    def __call__(self, zd):
        zd = np.asarray(zd, dtype=float)
        if self._last is not None:
            at, z_after, jac = self._last
            if np.array_equal(at, zd):
                return z_after, jac
        z_after, jac, _ = self.law.impact_map(self.model, self.load, 0.0, zd)
        self._last = (zd.copy(), np.asarray(z_after, dtype=float), np.asarray(jac, dtype=float))
        _, z_after, jac = self._last
        return z_after, jac


def _jump(model: BarModel) -> np.ndarray:
    """The paper's impact law (eq. 10) as a matrix: ``q`` kept, ``v -> -R v``."""
    M = model.n_modes + 1
    return np.diag(np.concatenate((np.ones(M), np.full(M, -model.law.traits.kernel_restitution(model)))))


def _before_impact(model, drive, z0, durations):
    return _legs(model, drive, z0, durations)[3]


def _constants(model, drive=None, constant_load=None):
    """What the residual needs of the model, computed once per solve: ``(w2, c, Jv)``, ``Jv`` the
    impact law (eq. 10) as the diagonal ``(1, .., 1, -R, .., -R)``; under a law whose contact takes
    time (the wave law, the rod-rock law) ``Jv`` is the contact's map instead
    (:class:`ContactMap`, needs the ``drive`` and ``constant_load``)."""
    M = model.n_modes + 1
    if not model.law.traits.restitution_in_kernel:
        if drive is None or constant_load is None:
            raise ValueError("the contact map of a law whose contact takes time needs the drive")
        return _w2(model), model.end_weights, ContactMap(model, drive, constant_load)
    R = model.law.traits.kernel_restitution(model)
    return _w2(model), model.end_weights, np.concatenate((np.ones(M), np.full(M, -R)))


def _flights(model, drive, X, w2):
    """The four flights of the segment problem from ``X = (z0, h1, h3)``: ``(zb, zd, Eb, Ed,
    dzb_dh1, dzd_dh1, dzd_dh3)``, the states at the switch crossing and at the arrival, the flows'
    Jacobians from ``z0`` to them (per-mode 2x2 blocks) and the states' rates in ``h1``, ``h3``."""
    M = model.n_modes + 1
    d = model.d
    ps, pr = drive.stroke, -drive.ret
    z0, h1, h3 = X[:2 * M], X[2 * M], X[2 * M + 1]
    t_in, t_out = drive.delay_in, drive.delay_out
    E1, E3 = _blocks(w2, d, h1), _blocks(w2, d, h3)
    if t_in:
        Ei = _blocks(w2, d, t_in)
        za = _apply(Ei, _affine(w2, d, ps, t_in, Ei), z0)
    else:
        Ei, za = None, z0
    Eo = (Ei if t_out == t_in else _blocks(w2, d, t_out)) if t_out else None
    zb = _apply(E1, _affine(w2, d, pr, h1, E1), za)
    zc = _apply(Eo, _affine(w2, d, pr, t_out, Eo), zb) if t_out else zb
    zd = _apply(E3, _affine(w2, d, ps, h3, E3), zc)
    Eb = _compose(E1, Ei) if t_in else E1  # z0 -> zb
    Ebd = _compose(E3, Eo) if t_out else E3  # zb -> zd
    Ed = _compose(Ebd, Eb)
    dzb_dh1 = _field(w2, d, pr, zb)
    dzd_dh1 = _apply(Ebd, (np.zeros(M), np.zeros(M)), dzb_dh1)
    dzd_dh3 = _field(w2, d, ps, zd)
    return zb, zd, Eb, Ed, dzb_dh1, dzd_dh1, dzd_dh3


def _residual(model, drive, X, consts=None):
    """Residual and exact Jacobian of the segment problem (unknowns: state after the impact,
    ``h1``, ``h3``), with the flows as per-mode 2x2 blocks; ``consts`` from :func:`_constants`.
    Under a law whose contact takes time the state is the one where the contact ends, and the
    impact law is the contact's map with its Jacobian (exact for the wave law, by finite
    differences for the rod-rock law)."""
    M = model.n_modes + 1
    w2, c, Jv = consts if consts is not None else _constants(model, drive)
    z0 = X[:2 * M]
    zb, zd, Eb, Ed, dzb_dh1, dzd_dh1, dzd_dh3 = _flights(model, drive, X, w2)
    r = np.empty(2 * M + 2)
    Jac = np.zeros((2 * M + 2, 2 * M + 2))
    if isinstance(Jv, np.ndarray):  # eq. 10: a diagonal
        r[:2 * M] = z0 - Jv * zd
        Jac[:2 * M, :2 * M] = np.eye(2 * M) - Jv[:, None] * _matrix(Ed)
        Jac[:2 * M, 2 * M] = -Jv * dzd_dh1
        Jac[:2 * M, 2 * M + 1] = -Jv * dzd_dh3
    else:  # a contact that takes time: its map and Jacobian at the arrival state
        z_after, JP = Jv(zd)
        r[:2 * M] = z0 - z_after
        Jac[:2 * M, :2 * M] = np.eye(2 * M) - JP @ _matrix(Ed)
        Jac[:2 * M, 2 * M] = -JP @ dzd_dh1
        Jac[:2 * M, 2 * M + 1] = -JP @ dzd_dh3
    r[2 * M:], Jac[2 * M:] = _conditions(drive, c, zb, zd, Eb, Ed, dzb_dh1, dzd_dh1, dzd_dh3)
    return r, Jac


def _conditions(drive, c, zb, zd, Eb, Ed, dzb_dh1, dzd_dh1, dzd_dh3):
    """The switch and contact conditions of the segment problem and their Jacobian rows in
    ``(z0, h1, h3)``, from the flights of :func:`_flights`: ``-q_0 = switch_out`` at the switch
    crossing, ``c . q = 0`` at the arrival. Returns ``(g, G)``, shapes ``(2,)`` and
    ``(2, 2 M + 2)``."""
    M = c.size
    g = np.array([-zb[0] - drive.switch_out, c @ zd[:M]])
    G = np.zeros((2, 2 * M + 2))
    G[0, 0] = -Eb[0][0]
    G[0, M] = -Eb[1][0]
    G[0, 2 * M] = -dzb_dh1[0]
    G[1, :M] = c * Ed[0]
    G[1, M:2 * M] = c * Ed[1]
    G[1, 2 * M] = c @ dzd_dh1[:M]
    G[1, 2 * M + 1] = c @ dzd_dh3[:M]
    return g, G


def _residual_m(model, drive, X, m, consts=None):
    """Residual and exact Jacobian of the ``m``-impact segment problem (multiple shooting, theory
    §10): ``X`` holds ``m`` blocks ``(state after impact k, h1_k, h3_k)``; block ``k`` carries the
    switch and contact conditions of its interval, and its impact law lands on the state of block
    ``k + 1`` (of block 0 for the last)."""
    if m == 1:
        return _residual(model, drive, X, consts)
    consts = consts if consts is not None else _constants(model, drive)
    n = X.size // m
    S = n - 2
    r = np.empty(X.size)
    Jac = np.zeros((X.size, X.size))
    eye = np.eye(S)
    for k in range(m):
        a, nxt = k * n, ((k + 1) % m) * n
        rk, Jk = _residual(model, drive, X[a:a + n], consts)
        rk[:S] += X[nxt:nxt + S] - X[a:a + S]
        Jk[:S, :S] -= eye
        r[a:a + n] = rk
        Jac[a:a + n, a:a + n] = Jk
        Jac[a:a + S, nxt:nxt + S] += eye
    return r, Jac


def _flight_index(M, m):
    """Positions of the free flight times ``h1_k, h3_k`` in the unknowns of :func:`_residual_m`."""
    n = 2 * M + 2
    return np.array([k * n + 2 * M + j for k in range(m) for j in (0, 1)])


def _padded(state, M):
    state = np.asarray(state, dtype=float)
    if state.size == 2 * M:
        return state.copy()
    m = state.size // 2
    out = np.zeros(2 * M)
    k = min(m, M)
    out[:k] = state[:k]
    out[M:M + k] = state[m:m + k]
    return out


# --------------------------------------------------------------------------------------------------
# the valve's OrbitProblem
# --------------------------------------------------------------------------------------------------
#: most undamped resonances ``T = 2 k / (s n)`` in the window of a search of every orbit (``d = 0``):
#: orbits crowd at each, and each takes the search down to its smallest cells (about 1.5 s for 260)
MAX_RESONANCES = 1000
#: an impact's four legs of the force schedule in an orbit's ``durations`` (a row each, reshaped to
#: ``(m, DUR_SIZE)``): ``tau_in``, ``h1``, ``tau_out``, ``h3`` (theory §10)
DUR_TAU, DUR_H1, DUR_TAU2, DUR_H3 = range(4)
DUR_SIZE = 4


class ValveProblem(OrbitProblem):
    r"""The valve's periodic-orbit problem (module docstring): ``impacts`` blocks ``(state after
    impact k, h1_k, h3_k)``, the exact Jacobian, Newton's start and the orbit's multipliers.

    Parameters
    ----------
    model : BarModel
        Rigid or flexible, under any impact law (a contact that takes time is held under the stroke
        force).
    drive : PositionSwitchedDrive
    impacts : int
        :math:`m \ge 1`.
    constant_load : callable
        ``constant_load(p)``: the load of the constant force ``p`` (a contact law's map).

    Raises
    ------
    ValueError
        With ``model.R`` :math:`\ge 1` under a law that uses it (no energy leaves: the blows grow without
        bound).
    """

    default_start = "the rigid piston's orbit"

    def __init__(self, model: BarModel, drive, impacts: int, constant_load) -> None:
        self.model, self.drive, self.constant_load = model, drive, constant_load
        self.impacts = m = impacts  # (validated by the solvers that ask for the problem)
        law = model.law
        if model.R >= 1.0 and (law.traits.restitution_in_kernel or law.traits.uses_restitution):
            raise ValueError("model.R must be < 1 for a periodic motion under a position-switched drive "
                             "(with R = 1 no energy leaves and the blows grow without bound)")
        self.M = model.n_modes + 1
        self.size = m * (2 * self.M + 2)
        self.positive = _flight_index(self.M, m)
        self._consts = None

    @property
    def consts(self):
        """The residual's constants (:func:`_constants`), built once."""
        if self._consts is None:
            self._consts = _constants(self.model, self.drive, self.constant_load)
        return self._consts

    def residual(self, X):
        """Residual and exact Jacobian of the ``m``-impact segment problem (:func:`_residual_m`)."""
        return _residual_m(self.model, self.drive, X, self.impacts, self.consts)

    def _sibling(self, model, impacts=1):
        return ValveProblem(model, self.drive, impacts, self.constant_load)

    def initial(self, guess, tol, max_iter):
        """Newton's start. ``guess`` is a :class:`~impactbar.DrivenOrbit` (a one-impact orbit is
        repeated ``m`` times), a run of :func:`impactbar.simulate` under the drive (its last ``m``
        complete valve cycles, rigid or flexible bar, the paper's law: :func:`_from_run`), a tuple
        ``(states, h1, h3)``, or ``None`` (``m = 1``): the rigid bar's orbit from the closed form of
        :meth:`~impactbar.PositionSwitchedDrive.rigid_orbit` and the fixed point of the rigid
        piston's map of arrival velocities, solved and lifted to the flexible bar with one Newton
        step on its modes; under a law whose contact takes time, from the orbit of the same bar
        under the paper's law (``NewtonStart.paper_equivalent``)."""
        model, drive, m, M = self.model, self.drive, self.impacts, self.M
        if guess is None and m > 1:
            raise ValueError(f"impacts={m} needs a guess (an orbit, a simulated run or a tuple): without "
                             f"one Newton would find the one-impact orbit traversed {m} times")
        if not model.law.traits.restitution_in_kernel:  # the wave law, the rod-rock law: the contact's map
            if guess is not None:
                if hasattr(guess, "switch_kinds") and hasattr(guess, "impact_times"):
                    raise ValueError("a simulated run as a guess is read under the paper's law only; under "
                                     "a law whose contact takes time pass an orbit or a tuple (states, h1, "
                                     "h3), the states where the contacts end")
                return _guess_unknowns(guess, M, m)
            rigid = model.with_(n_modes=0)
            paper = self._sibling(newton_start(rigid.law).paper_equivalent(rigid))
            Xp = paper.solve(paper.initial(None, tol, max_iter), tol, max_iter)
            Xr = self._sibling(rigid).solve(Xp, tol, max_iter)
            return np.concatenate((_padded(Xr[:2], M), Xr[2:]))
        if guess is not None:
            return _guess_unknowns(guess, M, m)
        if M == 1:
            return _rigid_guess(model, drive)
        rigid = self._sibling(model.with_(n_modes=0))  # the rigid bar's orbit (same damping and delay)
        Xr = rigid.solve(_rigid_guess(rigid.model, drive), tol, max_iter)
        X = np.concatenate((_padded(Xr[:2], M), Xr[2:]))
        r, Jac = _residual(model, drive, X, self.consts)  # the flexible modes at the rigid switch time:
        keep = np.r_[0:2 * M, 2 * M + 1]  # one Newton step without the switch condition, h1 kept
        X[keep] += np.linalg.solve(Jac[np.ix_(keep, keep)], -r[keep])
        return X

    def resonances(self, window=None) -> float:
        """About how many resonances ``T = 2 k / (s n)`` of the flexible modes lie in ``window``
        (default: the search's default window); 0 for the rigid bar. The search's cost grows with
        them; 0 too where the search does not apply (:meth:`search`: a law whose contact takes
        time)."""
        from .valve_search import default_window

        model = self.model
        if not model.n_modes or not model.law.traits.restitution_in_kernel:
            return 0.0
        lo, hi = default_window(model, self.drive) if window is None else window
        return (float(hi) - float(lo)) * model.s * model.n_modes * (model.n_modes + 1) / 4.0

    def search(self, window):
        r"""Every one-impact orbit with a period in ``window`` under the paper's law, certified
        (:func:`~impactbar.orbits.valve_search.search_one_impact`: exclusion by bounds from the
        closed forms, the Krawczyk test on each root); ``None`` (the solvers' non-certified search)
        for :math:`m \ge 2`, under a law whose contact takes time, or with an overdamped mode."""
        from .valve_search import OneImpactEquations, default_window, search_one_impact

        model, drive = self.model, self.drive
        if self.impacts != 1 or not model.law.traits.restitution_in_kernel or \
                (model.n_modes and not model.s * math.pi > 0.5 * model.d):
            return None
        tau = drive.delay_in + drive.delay_out
        if window is None:
            window = default_window(model, drive)
        lo, hi = window
        lo, hi = max(float(lo), tau), float(hi)
        if not hi > lo:
            raise ValueError(f"window must hold periods above the two delays ({tau:g}); got {window}")
        if model.d == 0.0 and model.n_modes:  # undamped: orbits crowd at every resonance T = 2 k / (s n)
            count = self.resonances((lo, hi))
            if count > MAX_RESONANCES:
                raise ValueError(f"window ({lo:.6g}, {hi:.6g}) holds about {count:.0f} undamped resonances "
                                 f"T = 2 k / (s n) of the flexible modes (at most {MAX_RESONANCES}): narrow "
                                 "the window, or give the bar some damping d > 0")
        eq = OneImpactEquations(model, drive)
        with np.errstate(all="ignore"):
            res = search_one_impact(eq, (lo, hi))
        starts = [eq.state(T, h) for T, h in res.roots]
        return OrbitSearch(starts=starts, certified=res.certified, window=res.window,
                           unresolved=res.unresolved,
                           method=f"certified search over the periods {lo:.6g} to {hi:.6g} "
                                  f"({res.cells} cells)")

    def unknowns(self, orbit):
        """The unknowns of a found orbit: its states after the impacts and its ``h1``, ``h3``."""
        states = orbit.states if orbit.states is not None else orbit.state[None, :]
        legs = orbit.durations.reshape(-1, DUR_SIZE)
        return np.concatenate([np.concatenate((z, legs[k, [DUR_H1, DUR_H3]])) for k, z in enumerate(states)])

    def _block(self, X, k):
        n = 2 * self.M + 2
        z0 = X[k * n:k * n + 2 * self.M].copy()
        dur = np.array([self.drive.delay_in, X[k * n + 2 * self.M], self.drive.delay_out,
                        X[k * n + 2 * self.M + 1]])
        return z0, dur

    def pieces(self, X):
        """The flights of the period as ``(t0, t1, f)``, ``f(t) -> (q, v)`` at orbit times (from the
        state after the first impact; the contacts' windows between them)."""
        model, drive, M = self.model, self.drive, self.M
        w2, d = _w2(model), model.d
        window = float(model.law.window(model))
        ps, pr = drive.level(STROKE), drive.level(RETURN)
        out, t = [], 0.0
        for k in range(self.impacts):
            z0, dur = self._block(np.asarray(X, dtype=float), k)
            starts = (z0, *_legs(model, drive, z0, dur)[:3])
            for p, h, z in zip((ps, pr, pr, ps), dur, starts, strict=True):
                if h:
                    out.append((t, t + h, lambda tt, p=p, z=z, t0=t: step_constant(w2, d, p, z[:M], z[M:],
                                                                                      tt - t0)))
                    t += h
            t += window
        return out

    def admissibility(self, X, k):
        """The flights after impact ``k``: the end off the stop, the return crossing the first one,
        a forward impact (:func:`_admissibility`)."""
        return _admissibility(self.model, self.drive, *self._block(np.asarray(X, dtype=float), k))

    def orbit(self, X) -> OrbitData:
        """Multipliers from the monodromy matrix (the paper's law) or of the return map on the
        arrival surface (a contact that takes time), the states, durations and switches."""
        if not self.model.law.traits.restitution_in_kernel:
            return self.return_map_orbit(X)
        model, drive, m, M = self.model, self.drive, self.impacts, self.M
        X = np.asarray(X, dtype=float)
        Phi = np.eye(2 * M)
        states, before, durations, velocities, switch = [], [], [], [], []
        for k in range(m):
            z0, dur = self._block(X, k)
            Phi = _monodromy(model, drive, z0, dur) @ Phi
            _, zb, _, zd = _legs(model, drive, z0, dur)
            states.append(z0)
            before.append(zd)
            durations.append(dur)
            velocities.append(float(model.end_weights @ zd[M:]))
            switch.append(float(-zb[M]))
        za = _legs(model, drive, states[0], durations[0])[0]
        trivial, nontrivial = split_multipliers(Phi, _field(_w2(model), model.d, drive.level(RETURN), za))
        durations = np.concatenate(durations)
        return OrbitData(period=float(np.sum(durations)), durations=durations, states_after=np.array(states),
                         states_before=np.array(before), drive_states=np.zeros((m, 0)),
                         impact_times=_impact_times(durations, 0.0), multipliers=nontrivial,
                         trivial_multiplier=trivial,
                         switch_times=_switch_times(durations, 0.0), switch_velocity=min(switch),
                         contact_time=0.0, contact_forces=np.full(m, float(drive.stroke)),
                         monodromy=Phi, impact_velocities=np.array(velocities))

    def return_map_orbit(self, X) -> OrbitData:
        """The orbit under a law whose contact takes time: multipliers of the return map on the
        arrival surface (the switch and arrival times implicit in the state)."""
        model, drive, m, M = self.model, self.drive, self.impacts, self.M
        X = np.asarray(X, dtype=float)
        n = 2 * M + 2
        c = model.end_weights
        cmap = ContactMap(model, drive, self.constant_load)
        w2 = _w2(model)
        B = _surface_basis(c)
        P = np.eye(2 * M - 1)
        states, before, durations, velocities, switch = [], [], [], [], []
        first_dzd = JP_prev = None
        for k in range(m):
            Xk = X[k * n:(k + 1) * n]
            z0 = Xk[:2 * M].copy()
            dur = np.array([drive.delay_in, Xk[2 * M], drive.delay_out, Xk[2 * M + 1]])
            flights = _flights(model, drive, Xk, w2)
            zb, zd, _, Ed, _, dzd_dh1, dzd_dh3 = flights
            # the arrival's dependence on z0 with the switch and arrival times implicit
            _, G = _conditions(drive, c, *flights)
            dzd = _matrix(Ed) - np.column_stack((dzd_dh1, dzd_dh3)) @ np.linalg.solve(G[:, 2 * M:],
                                                                                     G[:, :2 * M])
            if k:
                P = B.T @ dzd @ JP_prev @ B @ P
            _, JP_prev = cmap(zd)
            if k == 0:
                first_dzd = dzd
            states.append(z0)
            before.append(zd)
            durations.append(dur)
            velocities.append(float(c @ zd[M:]))
            switch.append(float(-zb[M]))
        P = B.T @ first_dzd @ JP_prev @ B @ P  # the last contact lands on the first block's state
        mu = sorted_multipliers(np.linalg.eigvals(P) if P.size else np.array([]))
        durations = np.concatenate(durations)
        return OrbitData(period=float(np.sum(durations)) + m * cmap.window, durations=durations,
                         states_after=np.array(states), states_before=np.array(before),
                         drive_states=np.zeros((m, 0)), impact_times=_impact_times(durations, cmap.window),
                         multipliers=mu, trivial_multiplier=1.0,
                         switch_times=_switch_times(durations, cmap.window), switch_velocity=min(switch),
                         contact_time=cmap.window, contact_forces=np.full(m, float(drive.stroke)),
                         monodromy=None, impact_velocities=np.array(velocities))


def _impact_times(durations, contact_time):
    """Times after the first impact (where its contact ends) of the arrivals that end each
    interval."""
    if durations.size == 4:
        return np.array([float(np.sum(durations))])
    per = durations.reshape(-1, DUR_SIZE).sum(axis=1)
    return np.cumsum(per) + contact_time * np.arange(per.size)


def _switch_times(durations, contact_time):
    """Times after the first impact at which the switches take effect: to return, then to stroke,
    for each impact of the period in turn, shape ``(2 m,)``."""
    if durations.size == DUR_SIZE:  # the arithmetic below, in scalars
        start = 0.0 + contact_time
        tau, h1, tau2 = float(durations[DUR_TAU]), float(durations[DUR_H1]), float(durations[DUR_TAU2])
        return np.array([start + tau, start + tau + h1 + tau2])
    legs = durations.reshape(-1, DUR_SIZE)
    steps = legs.copy()
    steps[:, DUR_TAU] += contact_time  # the contact, then the stroke's tau
    start = np.concatenate(([0.0], np.cumsum(steps.sum(axis=1))))[:-1] + contact_time
    tau, h1, tau2 = legs[:, DUR_TAU], legs[:, DUR_H1], legs[:, DUR_TAU2]
    return np.column_stack((start + tau, start + tau + h1 + tau2)).ravel()


def _surface_basis(c: np.ndarray) -> np.ndarray:
    """Orthonormal basis, shape ``(2M, 2M - 1)``, of the arrival surface's tangent space
    ``{dz : c . dq = 0}``."""
    M = c.size
    a = np.concatenate((c, np.zeros(M)))
    q, _ = np.linalg.qr(np.column_stack((a / np.linalg.norm(a), np.eye(2 * M))))
    return q[:, 1:2 * M]


def _rigid_guess(model, drive):
    """Start of Newton for the rigid bar: the fixed point of the rigid piston's map of arrival
    velocities (compiled closed forms, :func:`impactbar.drives.valve.closed_forms.rigid_orbit_start`),
    from the undamped undelayed orbit in closed form (theory §10), which is the start itself where
    the map's iteration fails."""
    M = model.n_modes + 1
    R = model.law.traits.kernel_restitution(model)
    o = drive.rigid_orbit(min(model.R, 0.999))
    v, h1, h3 = rigid_orbit_start(float(model.d), float(R), tuple(drive.kernel_view), o["impact_velocity"])
    if not math.isfinite(v):
        v, h1, h3 = o["impact_velocity"], o["switch_time"], o["period"] - o["switch_time"]
    z0 = np.zeros(2 * M)
    z0[M] = -R * v
    return np.concatenate((z0, [h1, h3]))


def _guess_unknowns(guess, M, m):
    """The unknowns of :func:`_residual_m` from a guess of :meth:`ValveProblem.initial`: an orbit
    (read by its ``states``, ``state`` and ``durations``), a run (by its ``switch_kinds`` and
    ``impact_times``) or a tuple."""
    if hasattr(guess, "durations") and hasattr(guess, "state"):  # a DrivenOrbit of the valve
        states = guess.states if guess.states is not None else guess.state[None, :]
        legs = guess.durations.reshape(-1, DUR_SIZE)
        h1, h3 = legs[:, DUR_H1], legs[:, DUR_H3]
        reps = -(-m // len(states))
        states, h1, h3 = np.tile(states, (reps, 1))[:m], np.tile(h1, reps)[:m], np.tile(h3, reps)[:m]
    elif hasattr(guess, "switch_kinds") and hasattr(guess, "impact_times"):
        states, h1, h3 = _from_run(guess, m)
    else:
        try:
            states, h1, h3 = guess
        except (TypeError, ValueError):
            raise ValueError("guess must be a DrivenOrbit, a simulated run under the drive or a "
                             "tuple (states, h1, h3)") from None
        states = np.atleast_2d(np.asarray(states, dtype=float))
        h1, h3 = np.atleast_1d(np.asarray(h1, dtype=float)), np.atleast_1d(np.asarray(h3, dtype=float))
    if len(states) != m or h1.size != m or h3.size != m:
        raise ValueError(f"guess must hold {m} states and {m} flight times of each kind (impacts={m}); "
                         f"got {len(states)}, {h1.size}, {h3.size}")
    return np.concatenate([np.concatenate((_padded(z, M), [a, b]))
                           for z, a, b in zip(states, h1, h3, strict=True)])


def _from_run(run, m):
    """States just after the last ``m`` complete valve cycles of a run (rigid or flexible bar, the
    paper's law) and the flight times between its switches (each interval from the impact at
    ``t_i``: return from ``t_i + delay_in``, the ``switch_out`` crossing ``h1`` later, stroke from the
    crossing ``+ delay_out``, the next impact ``h3`` later). The state after impact ``k`` is the
    run's modal state at ``t_k`` (its flight from the impact; where a run's piece gives the state on
    arrival instead, the impact law is applied to it)."""
    ti = np.asarray(run.impact_times)
    ts = np.asarray(run.switch_times)
    kinds = tuple(run.switch_kinds)
    if ti.size < m + 1:
        raise ValueError(f"guess: the run has {ti.size} impacts; impacts={m} needs at least {m + 1} (run it "
                         "longer, until its impacts settle)")
    R = run.model.law.traits.kernel_restitution(run.model)
    c = run.model.end_weights
    drive = run.drive
    delays = drive.delay_in + drive.delay_out
    states, h1, h3 = [], [], []
    for k in range(ti.size - m - 1, ti.size - 1):
        a, b = ti[k], ti[k + 1]
        stroke = [t for t, kind in zip(ts, kinds, strict=True) if kind == "stroke" and a < t <= b]
        if not stroke:
            raise ValueError("guess: the run's last impacts are not one valve cycle apart (a chatter or a "
                             "sticking motion): give an orbit or a tuple (states, h1, h3)")
        ts_on = stroke[-1]
        q, v = run.modal_state(np.array([a]))
        q, v = q[:, 0], v[:, 0]
        if float(c @ v) > 0.0:  # the state on arrival: the impact law (eq. 10)
            v = -R * v
        states.append(np.concatenate((q, v)))
        h1.append(ts_on - a - delays)
        h3.append(b - ts_on)
    if min(h1) <= 0.0 or min(h3) <= 0.0:
        raise ValueError("guess: the run's valve cycles do not follow the drive's delays (a run under "
                         "another drive?)")
    return np.array(states), np.array(h1), np.array(h3)


def _monodromy(model, drive, z0, durations):
    """Monodromy matrix based just after the switch to return takes effect (theory §10): flows'
    fundamental matrices and the saltation matrices of the delayed switch and of the impact."""
    M = model.n_modes + 1
    w2, d = _w2(model), model.d
    ps, pr = drive.level(STROKE), drive.level(RETURN)
    t_in, h1, t_out, h3 = durations
    za, zb, zc, zd = _legs(model, drive, z0, durations)
    I2 = np.eye(2 * M)
    Eta_r = _fund(w2, d, t_out) if t_out else I2
    Eta_s = _fund(w2, d, t_in) if t_in else I2
    # return flight h1, crossing at zb: dt_c = -(g . dz_b) / (g . f), g = grad(-q_0)
    A = _fund(w2, d, h1)
    g = np.zeros(2 * M)
    g[0] = -1.0
    dtc = -np.outer(1.0, g) / (g @ _field(w2, d, pr, zb))  # row: dt_c = dtc @ dz_b
    A_c = Eta_r @ A  # dz_c- from dz_a+
    A = A_c + np.outer(_field(w2, d, pr, zc) - _field(w2, d, ps, zc), dtc[0] @ A)
    A = _fund(w2, d, h3) @ A  # dz_d-
    gc = np.concatenate((model.end_weights, np.zeros(M)))
    fd = _field(w2, d, ps, zd)
    dti = -gc / (gc @ fd)  # dt_i = dti @ dz_d
    J = _jump(model)
    z0p = J @ zd
    p_after = ps if t_in else pr
    A_imp = J @ A + np.outer(J @ fd - _field(w2, d, p_after, z0p), dti @ A)
    if t_in:  # stroke for tau_in, then the switch to return delayed from the impact: dt = dt_i
        Ei = _blocks(w2, d, t_in)
        za = _apply(Ei, _affine(w2, d, ps, t_in, Ei), z0p)  # next
        A = Eta_s @ A_imp + np.outer(_field(w2, d, ps, za) - _field(w2, d, pr, za), dti @ A)
    else:
        A = A_imp
    return A

