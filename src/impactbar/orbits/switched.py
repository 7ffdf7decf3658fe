"""Periodic motions under a position-switched drive: autonomous, with an unknown period (theory §10).

One period of a one-impact orbit, counted from an impact (the valve's rules of
:class:`~impactbar.PositionSwitchedDrive`, delay ``tau``):

1. stroke force for ``tau`` (the switch to return triggered by the impact takes effect);
2. return force for ``h1``, until the gap ``y = -q_0`` rises through ``switch_out``;
3. return force for ``tau`` (the switch to stroke takes effect);
4. stroke force for ``h3``, until the struck end reaches the stop, ``c . q = 0``; the impact law
   (eq. 10) gives the state after the impact.

Every flight is the closed-form constant-force flow of the modes (eq. 8). The unknowns are the
state after the impact and the durations ``h1``, ``h3`` (the period is ``T = 2 tau + h1 + h3``); the
conditions are the switch, the contact and the impact law, solved by Newton's method with the exact
Jacobian. The monodromy matrix is the product of the flows' fundamental matrices and of the saltation
matrices at the switch and the impact (Hiskens & Pai 2000; di Bernardo et al., *Piecewise-smooth
Dynamical Systems*, 2008, §2.5); one of its eigenvalues is the trivial ``1`` along the flow, reported
apart, the others are the multipliers of the Poincare map.

Under a law whose contact takes time (the wave law, theory §4b; the rod-rock law, §4d) the impact
is the law's contact, held under the stroke force for its duration ``ContactLaw.window`` (as
:func:`impactbar.simulate` runs it: the switch to return counts from the contact's end). The
unknowns hold the state where the contact ends; eq. 10 is replaced by the contact's map with its
Jacobian (exact for the wave law, central differences for the rod-rock law); the period is
``T = window + 2 tau + h1 + h3``. The multipliers are those of the return map on the arrival
surface ``c . q = 0``, built from the same Jacobian by the implicit function theorem (the switch
and arrival times depend on the state); the trivial multiplier along the flow is then exactly 1.
The flows, the residual and Newton's method are in ``impactbar.orbits._switchflow``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._shared.status import Admissibility
from .._shared.validate import check_int, check_real
from ..drives.switched import RETURN, STROKE, PositionSwitchedDrive
from ..dynamics._switchkernel import rigid_orbit_start
from ..model import BarModel
from ._switchflow import (  # noqa: F401 (the segment problem; _residual_m, _flight_index for continuation)
    ContactMap,
    _admissibility,
    _affine,
    _apply,
    _before_impact,
    _blocks,
    _conditions,
    _constants,
    _field,
    _flight_index,
    _flights,
    _fund,
    _jump,
    _legs,
    _matrix,
    _newton,
    _padded,
    _residual,
    _residual_m,
    _w2,
)

__all__ = ["SwitchedOrbit", "find_switched_orbit", "orbit_at"]


@dataclass(frozen=True)
class SwitchedOrbit:
    """A periodic motion with ``m`` impacts per period under a position-switched drive (theory §10).

    Attributes
    ----------
    model : BarModel
    drive : PositionSwitchedDrive
    period : float
        Period ``T`` (the model's time unit, eq. 2).
    durations : numpy.ndarray, shape (4 m,)
        The four flights between consecutive impacts, for each impact in turn: stroke ``tau``,
        return ``h1`` (to the switch crossing), return ``tau``, stroke ``h3`` (to the impact).
    state : numpy.ndarray, shape (2 N + 2,)
        Modal state ``(q_0..q_N, q_0'..q_N')`` just after the first impact.
    impact_velocity : float
        ``u_t(1, t-)``, the struck end's velocity arriving at the stop at the end of the first
        interval from ``state`` (for ``m = 1`` the impact ``state`` follows; every interval's in
        :attr:`impact_velocities`).
    multipliers : numpy.ndarray, shape (2 N + 1,)
        Non-trivial Floquet multipliers (those of the Poincare map), largest modulus first.
    trivial_multiplier : float
        The multiplier along the flow, ``1`` in exact arithmetic (its distance from 1 measures the
        rounding of the monodromy matrix).
    admissibility : Admissibility
        Whether the motion is physical (sampled check, theory §5 and §10).
    switch_velocity : float
        The gap's rate ``y' = -q_0'`` where it rises through ``switch_out`` (the smallest over the
        period's crossings): 0 where the orbit grazes the switching surface (theory §10).
    states : numpy.ndarray, shape (m, 2 N + 2), optional
        The modal state just after each impact (``states[0]`` is ``state``).
    contact_time : float
        Under a law whose contact takes time (the wave law, the rod-rock law), the contact's
        duration (the window ``2/s``, ``RodRock.window``): ``state`` and ``states`` are then where
        each contact ends, the ``durations`` follow it, and ``period = sum(durations) + m
        contact_time``. 0 under the paper's law.

    Examples
    --------
    >>> from impactbar import BarModel, PositionSwitchedDrive, find_orbit
    >>> drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    >>> orbit = find_orbit(BarModel(s=10.0, d=0.05, R=0.5, n_modes=0), drive)
    >>> round(orbit.period, 6), round(orbit.blow_frequency * orbit.period, 12)  # found, not given
    (4.607776, 1.0)
    """

    model: BarModel
    drive: PositionSwitchedDrive
    period: float
    durations: np.ndarray
    state: np.ndarray
    impact_velocity: float
    multipliers: np.ndarray
    trivial_multiplier: float
    admissibility: Admissibility
    switch_velocity: float = math.nan
    _monodromy: np.ndarray = field(repr=False, default=None)
    states: np.ndarray = field(repr=False, default=None)
    _velocities: np.ndarray = field(repr=False, default=None)
    contact_time: float = 0.0

    @property
    def impacts(self) -> int:
        """Impacts per period ``m`` (the ``durations`` hold four flights per impact)."""
        return self.durations.size // 4

    @property
    def impact_velocities(self) -> np.ndarray:
        """``(m,)``: the struck end's velocity arriving at the impact that ends each interval from
        ``states[k]``, in order (``impact_velocity`` first; the last one's impact leads to
        ``state``)."""
        if self._velocities is None:
            return np.array([self.impact_velocity])
        return np.asarray(self._velocities)

    @property
    def admissible(self) -> bool:
        """Whether :attr:`admissibility` is ``"admissible"``."""
        return self.admissibility == Admissibility.ADMISSIBLE

    @property
    def blow_frequency(self) -> float:
        """Blows per unit of the model's time, ``m / T`` (``m`` impacts per period); with the time
        scale ``t = Omega t_SI`` (eq. 2) the blow frequency in Hz is ``Omega m / T``."""
        return self.impacts / self.period

    @property
    def switch_times(self) -> np.ndarray:
        """Times after the first impact at which the switches take effect: to return, then to
        stroke, for each impact of the period in turn, shape ``(2 m,)``."""
        steps = self.durations.reshape(-1, 4).copy()
        steps[:, 0] += self.contact_time  # the contact, then the stroke's tau
        start = np.concatenate(([0.0], np.cumsum(steps.sum(axis=1))))[:-1] + self.contact_time
        tau, h1, tau2 = self.durations[0::4], self.durations[1::4], self.durations[2::4]
        return np.column_stack((start + tau, start + tau + h1 + tau2)).ravel()

    @property
    def impact_energy(self) -> float:
        """Kinetic energy of the bar arriving at the stop, ``(1/2) int_0^1 u_t^2 dx`` (units of
        ``m L^2 Omega^2``, eq. 2), the mean over the ``m`` impacts of the period (so that the
        percussive power is ``impact_energy * blow_frequency``)."""
        M = self.model.n_modes + 1
        states = self.states if self.states is not None else self.state[None, :]
        total = 0.0
        for k, z0 in enumerate(states):
            v = _before_impact(self.model, self.drive, z0, self.durations[4 * k:4 * k + 4])[M:]
            total += 0.5 * (v[0] ** 2 + 2.0 * float(np.sum(v[1:] ** 2)))
        return total / len(states)

    @property
    def stable(self) -> bool:
        """Admissible with every non-trivial multiplier inside the unit circle."""
        return self.admissibility == Admissibility.ADMISSIBLE and bool(np.all(np.abs(self.multipliers) < 1.0))

    @property
    def contacts(self) -> tuple:
        """The record of each impact's contact under a law whose contact takes time, in order
        (:meth:`~impactbar.laws.ContactLaw.blow` of each arrival under the stroke force: a
        :class:`~impactbar.WaveImpact` under the wave law; under the rod-rock law a record with the
        blow's ``work_on_rock``, ``permanent_penetration``, ``efficiency``, ... of
        :class:`~impactbar.Blow`); empty under the paper's law."""
        if self.model.law.instantaneous:
            return ()
        from ..loads import FourierLoad

        load = FourierLoad(float(self.drive.stroke), [])
        states = self.states if self.states is not None else self.state[None, :]
        arrivals = [_before_impact(self.model, self.drive, z0, self.durations[4 * k:4 * k + 4])
                    for k, z0 in enumerate(states)]
        return tuple(self.model.law.blow(self.model, load, 0.0, zd) for zd in arrivals)


def _rigid_guess(model, drive):
    """Start of Newton for the rigid bar: the fixed point of the rigid piston's map of arrival
    velocities (compiled closed forms, :func:`impactbar.dynamics._switchkernel.rigid_fixed_point`),
    from the undamped undelayed orbit in closed form (theory §10), which is the start itself where
    the map's iteration fails."""
    M = model.n_modes + 1
    R = model.law.kernel_restitution(model)
    o = drive.rigid_orbit(min(model.R, 0.999))
    v, h1, h3 = rigid_orbit_start(float(model.d), float(R), tuple(drive.kernel_view), o["impact_velocity"])
    if not math.isfinite(v):
        v, h1, h3 = o["impact_velocity"], o["switch_time"], o["period"] - o["switch_time"]
    z0 = np.zeros(2 * M)
    z0[M] = -R * v
    return np.concatenate((z0, [h1, h3]))


def find_switched_orbit(model: BarModel, drive: PositionSwitchedDrive, impacts: int = 1, guess=None,
                        *, tol: float = 1e-13, max_iter: int = 50) -> SwitchedOrbit:
    """The periodic motion with ``m`` impacts per period under a position-switched drive (theory §10).

    Called by :func:`impactbar.find_orbit` when its load is a
    :class:`~impactbar.PositionSwitchedDrive`. Between consecutive impacts the valve goes through
    its cycle once (stroke ``tau``, return until the switch crossing, return ``tau``, stroke until
    the impact); with ``m >= 2`` the intervals may differ (a period-2 motion after a period
    doubling), and the unknowns are the ``m`` states after the impacts and the ``2 m`` free flight
    times (multiple shooting).

    Parameters
    ----------
    model : BarModel
        Rigid or flexible bar, under any impact law: the paper's (eq. 10), or a contact that takes
        time, the wave law (theory §4b) or the rod-rock law (§4d), held under the stroke force
        (theory §10; the orbit's ``state`` is then where the contact
        ends, and ``contacts`` holds the blows).
    drive : PositionSwitchedDrive
    impacts : int
        Impacts per period ``m >= 1``; with ``m >= 2`` a ``guess`` is needed.
    guess : SwitchedOrbit, SwitchedTrajectory, tuple or None
        Where Newton starts: an orbit (e.g. from a nearby parameter; a one-impact orbit is
        repeated ``m`` times, which Newton keeps unless the halves are perturbed), a run of
        :func:`impactbar.simulate` under the drive (its last ``m`` complete valve cycles, rigid
        bar), a tuple ``(states, h1, h3)`` (states after the impacts, shape ``(m, 2 N + 2)`` or
        ``(2 N + 2,)`` for ``m = 1``, and the free flight durations, shape ``(m,)``), or ``None``
        (``m = 1`` only): the rigid closed form of :meth:`PositionSwitchedDrive.rigid_orbit`.
    tol : float
        Relative tolerance of the Newton step.
    max_iter : int
        Largest number of Newton steps.

    Returns
    -------
    SwitchedOrbit

    Raises
    ------
    ValueError
        On a bad argument, ``impacts >= 2`` without a guess, a simulated run as the guess under a
        law other than the paper's, or when Newton does not converge.

    Examples
    --------
    The rigid piston of theory §10 (``v = sqrt(2 x1 (a_s + a_r) / (1 - R^2))``, multiplier ``R^2``):

    >>> from impactbar import BarModel, PositionSwitchedDrive, find_orbit
    >>> o = find_orbit(BarModel(s=10, d=0, R=0.215, n_modes=0),
    ...                PositionSwitchedDrive(stroke=1, ret=1, switch_out=1))
    >>> round(o.period, 6), round(o.impact_velocity, 6), round(float(o.multipliers[0]), 6)
    (4.569933, 2.047892, 0.046225)

    The same orbit as a two-impact one (its two intervals equal, the period doubled):

    >>> o2 = find_orbit(o.model, o.drive, impacts=2, guess=o)
    >>> o2.impacts, round(o2.period / o.period, 12), round(o2.blow_frequency * o.period, 12)
    (2, 2.0, 1.0)
    """
    if not isinstance(model, BarModel):
        raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
    if not isinstance(drive, PositionSwitchedDrive):
        raise ValueError(f"drive must be a PositionSwitchedDrive; got {type(drive).__name__}")
    m = check_int("impacts", impacts, lo=1)
    tol = check_real("tol", tol, lo=0.0, lo_open=True)
    max_iter = check_int("max_iter", max_iter, lo=1)
    if not model.law.instantaneous:  # the wave law, the rod-rock law: the contact's map
        if model.R >= 1.0 and model.law.uses_restitution:
            raise ValueError("model.R must be < 1 for a periodic motion under a position-switched drive "
                             "(with R = 1 no energy leaves and the blows grow without bound)")
        return find_contact_orbit(model, drive, m, guess, tol, max_iter)
    if model.R >= 1.0:
        raise ValueError("model.R must be < 1 for a periodic motion under a position-switched drive "
                         "(with R = 1 no energy leaves and the blows grow without bound)")
    M = model.n_modes + 1
    if guess is None and m > 1:
        raise ValueError(f"impacts={m} needs a guess (an orbit, a simulated run or a tuple): without "
                         f"one Newton would find the one-impact orbit traversed {m} times")
    if guess is None and M > 1:  # the rigid bar's orbit (same damping and delay), then lifted
        rigid = model.with_(n_modes=0)
        Xr = _newton(rigid, drive, _rigid_guess(rigid, drive), tol, max_iter)
        X = np.concatenate((_padded(Xr[:2], M), Xr[2:]))
    elif guess is None:
        X = _rigid_guess(model, drive)
    else:
        X = _guess_unknowns(guess, M, m)
    consts = _constants(model, drive)
    if guess is None and M > 1:  # the flexible modes at the rigid switch time: one Newton step
        r, Jac = _residual(model, drive, X, consts)  # without the switch condition, h1 kept
        keep = np.r_[0:2 * M, 2 * M + 1]
        X[keep] += np.linalg.solve(Jac[np.ix_(keep, keep)], -r[keep])
    X = _newton(model, drive, X, tol, max_iter, consts, m)
    return orbit_at(model, drive, X, m)


def _guess_unknowns(guess, M, m):
    """The unknowns of :func:`_residual_m` from a guess of :func:`find_switched_orbit`."""
    if isinstance(guess, SwitchedOrbit):
        states = guess.states if guess.states is not None else guess.state[None, :]
        h1, h3 = guess.durations[1::4], guess.durations[3::4]
        reps = -(-m // len(states))
        states, h1, h3 = np.tile(states, (reps, 1))[:m], np.tile(h1, reps)[:m], np.tile(h3, reps)[:m]
    elif hasattr(guess, "switch_kinds") and hasattr(guess, "impact_times"):
        states, h1, h3 = _from_run(guess, m)
    else:
        try:
            states, h1, h3 = guess
        except (TypeError, ValueError):
            raise ValueError("guess must be a SwitchedOrbit, a simulated run under the drive or a "
                             "tuple (states, h1, h3)") from None
        states = np.atleast_2d(np.asarray(states, dtype=float))
        h1, h3 = np.atleast_1d(np.asarray(h1, dtype=float)), np.atleast_1d(np.asarray(h3, dtype=float))
    if len(states) != m or h1.size != m or h3.size != m:
        raise ValueError(f"guess must hold {m} states and {m} flight times of each kind (impacts={m}); "
                         f"got {len(states)}, {h1.size}, {h3.size}")
    return np.concatenate([np.concatenate((_padded(z, M), [a, b]))
                           for z, a, b in zip(states, h1, h3, strict=True)])


def _from_run(run, m):
    """States after the last ``m`` impacts of a rigid run and the flight times between its switches
    (each interval: return at ``t_i + tau``, stroke at the crossing ``+ tau``, the next impact)."""
    if run.model.n_modes != 0:
        raise ValueError("a simulated run as a guess is read for the rigid bar only; pass the orbit "
                         "of the rigid bar or a tuple (states, h1, h3)")
    ti, vi = np.asarray(run.impact_times), np.asarray(run.impact_velocities)
    ts = np.asarray(run.switch_times)
    kinds = tuple(run.switch_kinds)
    if ti.size < m + 1:
        raise ValueError(f"guess: the run has {ti.size} impacts; impacts={m} needs at least {m + 1}")
    tau, R = run.drive.delay, run.model.R
    states, h1, h3 = [], [], []
    for k in range(ti.size - m - 1, ti.size - 1):
        a, b = ti[k], ti[k + 1]
        stroke = [t for t, kind in zip(ts, kinds, strict=True) if kind == "stroke" and a < t <= b]
        if not stroke:
            raise ValueError("guess: the run's last impacts are not one valve cycle apart")
        ts_on = stroke[-1]
        states.append([0.0, -R * vi[k]])
        h1.append(ts_on - a - 2.0 * tau)
        h3.append(b - ts_on)
    return np.array(states), np.array(h1), np.array(h3)


def orbit_at(model: BarModel, drive: PositionSwitchedDrive, X, impacts: int = 1) -> SwitchedOrbit:
    """The orbit of a solution ``X`` of the segment problem (``impacts`` blocks ``(state after the
    impact, h1, h3)``): multipliers from the monodromy matrix, admissibility (theory §10). Used by
    :func:`find_switched_orbit` and by the continuation of switched orbits."""
    if not model.law.instantaneous:
        return contact_orbit_at(model, drive, X, impacts)
    M = model.n_modes + 1
    X = np.asarray(X, dtype=float)
    n = 2 * M + 2
    Phi = np.eye(2 * M)
    states, durations, velocities, switch, adm = [], [], [], [], Admissibility.ADMISSIBLE
    for k in range(impacts):
        z0 = X[k * n:k * n + 2 * M].copy()
        dur = np.array([drive.delay, X[k * n + 2 * M], drive.delay, X[k * n + 2 * M + 1]])
        Phi = _monodromy(model, drive, z0, dur) @ Phi
        _, zb, _, zd = _legs(model, drive, z0, dur)
        states.append(z0)
        durations.append(dur)
        velocities.append(float(model.end_weights @ zd[M:]))
        switch.append(float(-zb[M]))
        if adm == Admissibility.ADMISSIBLE:
            adm = _admissibility(model, drive, z0, dur)
    za = _legs(model, drive, states[0], durations[0])[0]
    trivial, nontrivial = _split_multipliers(Phi, _field(_w2(model), model.d, drive.level(RETURN), za))
    durations = np.concatenate(durations)
    return SwitchedOrbit(model=model, drive=drive, period=float(np.sum(durations)), durations=durations,
                         state=states[0], impact_velocity=velocities[0], multipliers=nontrivial,
                         trivial_multiplier=trivial, admissibility=adm, switch_velocity=min(switch),
                         _monodromy=Phi, states=np.array(states), _velocities=np.array(velocities))


def _monodromy(model, drive, z0, durations):
    """Monodromy matrix based just after the switch to return takes effect (theory §10): flows'
    fundamental matrices and the saltation matrices of the delayed switch and of the impact."""
    M = model.n_modes + 1
    w2, d = _w2(model), model.d
    ps, pr = drive.level(STROKE), drive.level(RETURN)
    tau, h1, _, h3 = durations
    za, zb, zc, zd = _legs(model, drive, z0, durations)
    I2 = np.eye(2 * M)
    Eta_r = _fund(w2, d, tau) if tau else I2
    Eta_s = Eta_r
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
    p_after = ps if tau else pr
    A_imp = J @ A + np.outer(J @ fd - _field(w2, d, p_after, z0p), dti @ A)
    if tau:  # stroke for tau, then the switch to return delayed from the impact: dt = dt_i
        za = _apply(_blocks(w2, d, tau), _affine(w2, d, ps, tau, _blocks(w2, d, tau)), z0p)  # next
        A = Eta_s @ A_imp + np.outer(_field(w2, d, ps, za) - _field(w2, d, pr, za), dti @ A)
    else:
        A = A_imp
    return A


def _split_multipliers(Phi, f):
    """The trivial multiplier along ``f`` and the others: ``Phi`` in the orthonormal basis
    ``(f/|f|, B)`` is block upper triangular (``Phi f = f``)."""
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
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    if np.all(np.abs(mu.imag) <= 1e-14 * np.maximum(1.0, np.abs(mu))):
        mu = mu.real
    return float(P[0, 0]), mu


# --------------------------------------------------------------------------------------------------
# contacts that take time (the wave law, the rod-rock law)
# --------------------------------------------------------------------------------------------------
def find_contact_orbit(model: BarModel, drive: PositionSwitchedDrive, impacts: int, guess, tol: float,
                       max_iter: int):
    """:func:`~impactbar.orbits.find_switched_orbit` under a law whose contact takes time (module
    docstring): without a guess, Newton starts from the orbit of the same bar under the paper's law
    (``ContactLaw.paper_equivalent``: the same ``R``, or a rigid piston's rebound from the rod and
    rock), solved first for the rigid bar and lifted to the flexible one."""
    M = model.n_modes + 1
    if guess is None:
        if impacts > 1:
            raise ValueError(f"impacts={impacts} needs a guess (an orbit or a tuple): without one Newton "
                             f"would find the one-impact orbit traversed {impacts} times")
        rigid = model.with_(n_modes=0)
        p = find_switched_orbit(rigid.law.paper_equivalent(rigid), drive, tol=tol, max_iter=max_iter)
        Xr = _newton(rigid, drive, np.concatenate((p.state, p.durations[[1, 3]])), tol, max_iter,
                     _constants(rigid, drive))
        X = np.concatenate((_padded(Xr[:2], M), Xr[2:]))
    else:
        if hasattr(guess, "switch_kinds") and hasattr(guess, "impact_times"):
            raise ValueError("a simulated run as a guess is read under the paper's law only; under a law "
                             "whose contact takes time pass an orbit or a tuple (states, h1, h3), the "
                             "states where the contacts end")
        X = _guess_unknowns(guess, M, impacts)
    X = _newton(model, drive, X, tol, max_iter, _constants(model, drive), impacts)
    return contact_orbit_at(model, drive, X, impacts)


def _surface_basis(c: np.ndarray) -> np.ndarray:
    """Orthonormal basis, shape ``(2M, 2M - 1)``, of the arrival surface's tangent space
    ``{dz : c . dq = 0}``."""
    M = c.size
    a = np.concatenate((c, np.zeros(M)))
    q, _ = np.linalg.qr(np.column_stack((a / np.linalg.norm(a), np.eye(2 * M))))
    return q[:, 1:2 * M]


def contact_orbit_at(model: BarModel, drive: PositionSwitchedDrive, X, impacts: int = 1):
    """The :class:`~impactbar.SwitchedOrbit` of a solution ``X`` (``impacts`` blocks ``(state where
    the contact ends, h1, h3)``) under a law whose contact takes time: multipliers of the return map
    on the arrival surface, admissibility of the flights (as for the paper's law) and of the
    contacts (held for their whole window: the wave law's ``separates`` and ``sticks``, theory §4b).
    Called by :func:`~impactbar.orbits.switched.orbit_at`."""
    from .admissibility import _window_departure

    M = model.n_modes + 1
    X = np.asarray(X, dtype=float)
    n = 2 * M + 2
    c = model.end_weights
    cmap = ContactMap(model, drive)
    w2 = _w2(model)
    B = _surface_basis(c)
    P = np.eye(2 * M - 1)
    states, durations, velocities, switch, adm = [], [], [], [], Admissibility.ADMISSIBLE
    first_dzd = JP_prev = None
    for k in range(impacts):
        Xk = X[k * n:(k + 1) * n]
        z0 = Xk[:2 * M].copy()
        dur = np.array([drive.delay, Xk[2 * M], drive.delay, Xk[2 * M + 1]])
        flights = _flights(model, drive, Xk, w2)
        zb, zd, _, Ed, _, dzd_dh1, dzd_dh3 = flights
        # the arrival's dependence on z0 with the switch and arrival times implicit
        G = _conditions(drive, c, *flights)[1]
        dzd = _matrix(Ed) - np.column_stack((dzd_dh1, dzd_dh3)) @ np.linalg.solve(G[:, 2 * M:], G[:, :2 * M])
        if k:
            P = B.T @ dzd @ JP_prev @ B @ P
        JP_prev = cmap(zd)[1]
        if k == 0:
            first_dzd = dzd
        states.append(z0)
        durations.append(dur)
        velocities.append(float(c @ zd[M:]))
        switch.append(float(-zb[M]))
        if adm == Admissibility.ADMISSIBLE:
            adm = _admissibility(model, drive, z0, dur)
            if velocities[-1] > 0.0:
                rec = model.law.blow(model, cmap.load, 0.0, zd)
                separates = bool(getattr(rec, "separations", ()))
                adm = _window_departure(adm, False, float(c @ z0[M:]), separates)
    P = B.T @ first_dzd @ JP_prev @ B @ P  # the last contact lands on the first block's state
    mu = np.linalg.eigvals(P) if P.size else np.array([])
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    if np.all(np.abs(mu.imag) <= 1e-14 * np.maximum(1.0, np.abs(mu))):
        mu = mu.real
    durations = np.concatenate(durations)
    return SwitchedOrbit(model=model, drive=drive, period=float(np.sum(durations)) + impacts * cmap.window,
                         durations=durations, state=states[0], impact_velocity=velocities[0],
                         multipliers=mu, trivial_multiplier=1.0, admissibility=adm,
                         switch_velocity=min(switch), states=np.array(states),
                         _velocities=np.array(velocities), contact_time=cmap.window)
