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
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._shared.status import Admissibility
from .._shared.validate import check_int, check_real
from ..drives.switched import RETURN, STROKE, PositionSwitchedDrive
from ..dynamics._switchkernel import end_max_sampled, first_rising_crossing, rate_zero, rigid_orbit_start
from ..dynamics.modal import fundamental, step_constant
from ..model import BarModel

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
        start = np.concatenate(([0.0], np.cumsum(self.durations)))[:-1:4]
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


# --------------------------------------------------------------------------------------------------
# flows
# --------------------------------------------------------------------------------------------------
def _w2(model: BarModel) -> np.ndarray:
    return (model.s * np.pi * np.arange(model.n_modes + 1)) ** 2


def _field(w2, d, p, z):
    M = w2.size
    q, v = z[:M], z[M:]
    return np.concatenate((v, p - d * v - w2 * q))


def _fund(w2, d, h):
    """The flow's Jacobian ``E(h)``, shape ``(2M, 2M)`` (block-diagonal per mode)."""
    return _matrix(_blocks(w2, d, h))


def _jump(model: BarModel) -> np.ndarray:
    """The paper's impact law (eq. 10) as a matrix: ``q`` kept, ``v -> -R v``."""
    M = model.n_modes + 1
    return np.diag(np.concatenate((np.ones(M), np.full(M, -model.law.kernel_restitution(model)))))


def _legs(model, drive, z0, durations):
    """States at the ends of the four flights from ``z0`` (after the impact)."""
    w2, d = _w2(model), model.d
    ps, pr = drive.level(STROKE), drive.level(RETURN)
    tau, h1, _, h3 = durations
    out = []
    z = z0
    for p, h in ((ps, tau), (pr, h1), (pr, tau), (ps, h3)):
        if h:
            E = _blocks(w2, d, h)
            z = _apply(E, _affine(w2, d, p, h, E), z)
        out.append(z)
    return tuple(out)


def _before_impact(model, drive, z0, durations):
    return _legs(model, drive, z0, durations)[3]


# --------------------------------------------------------------------------------------------------
# Newton on the segment problem
# --------------------------------------------------------------------------------------------------
def _blocks(w2, d, h):
    """The flow's Jacobian over ``h`` as its per-mode 2x2 blocks ``(a, b, c, e)``, each ``(M,)``
    (:func:`~impactbar.dynamics.modal.fundamental`, with the rigid mode and underdamped flexible
    modes in direct closed form)."""
    h = float(h)
    lam2 = w2[1:] - 0.25 * d * d
    if lam2.size and not np.all(lam2 > 0.0):  # an overdamped mode: the general forms
        return fundamental(w2, d, np.full(w2.shape, h))
    b0 = -math.expm1(-d * h) / d if d else h
    a = np.empty(w2.size)
    b = np.empty(w2.size)
    c = np.empty(w2.size)
    e = np.empty(w2.size)
    a[0], b[0], c[0], e[0] = 1.0, b0, 0.0, math.exp(-d * h)
    if lam2.size:
        lam = np.sqrt(lam2)
        damp = math.exp(-0.5 * d * h)
        cs = damp * np.cos(lam * h)
        sn = damp * np.sin(lam * h) / lam
        a[1:] = cs + 0.5 * d * sn
        b[1:] = sn
        c[1:] = -w2[1:] * sn
        e[1:] = cs - 0.5 * d * sn
    return a, b, c, e


def _affine(w2, d, p, h, E):
    """The constant part ``g`` of the flow ``z(h) = E z0 + g`` under the force ``p`` (eq. 8)."""
    a, _, c, _ = E
    gq = np.empty(w2.size)
    gv = np.empty(w2.size)
    y = d * h
    if d == 0.0:
        b0, c0 = h, 0.5 * h * h
    else:
        b0 = -math.expm1(-y) / d
        c0 = h * h * (0.5 - y / 6.0 + y * y / 24.0 - y**3 / 120.0 + y**4 / 720.0) if abs(y) < 1e-2 \
            else (h - b0) / d
    gq[0], gv[0] = p * c0, p * b0
    if w2.size > 1:
        qs = p / w2[1:]  # static deflection of the flexible modes
        gq[1:] = qs * (1.0 - a[1:])
        gv[1:] = -c[1:] * qs
    return gq, gv


def _compose(E2, E1):
    a2, b2, c2, e2 = E2
    a1, b1, c1, e1 = E1
    return a2 * a1 + b2 * c1, a2 * b1 + b2 * e1, c2 * a1 + e2 * c1, c2 * b1 + e2 * e1


def _apply(E, g, z):
    M = g[0].size
    a, b, c, e = E
    q, v = z[:M], z[M:]
    return np.concatenate((a * q + b * v + g[0], c * q + e * v + g[1]))


def _matrix(E):
    a, b, c, e = E
    M = a.size
    out = np.zeros((2 * M, 2 * M))
    i = np.arange(M)
    out[i, i], out[i, M + i], out[M + i, i], out[M + i, M + i] = a, b, c, e
    return out


def _constants(model):
    """What the residual needs of the model, computed once per solve: ``(w2, c, Jv)``, ``Jv`` the
    impact law (eq. 10) as the diagonal ``(1, .., 1, -R, .., -R)``."""
    M = model.n_modes + 1
    R = model.law.kernel_restitution(model)
    return _w2(model), model.end_weights, np.concatenate((np.ones(M), np.full(M, -R)))


def _residual(model, drive, X, consts=None):
    """Residual and exact Jacobian of the segment problem (unknowns: state after the impact,
    ``h1``, ``h3``), with the flows as per-mode 2x2 blocks; ``consts`` from :func:`_constants`."""
    M = model.n_modes + 1
    w2, c, Jv = consts if consts is not None else _constants(model)
    d = model.d
    ps, pr = drive.stroke, -drive.ret
    z0, h1, h3 = X[:2 * M], X[2 * M], X[2 * M + 1]
    tau = drive.delay
    E1, E3 = _blocks(w2, d, h1), _blocks(w2, d, h3)
    if tau:
        Et = _blocks(w2, d, tau)
        za = _apply(Et, _affine(w2, d, ps, tau, Et), z0)
    else:
        Et, za = None, z0
    zb = _apply(E1, _affine(w2, d, pr, h1, E1), za)
    zc = _apply(Et, _affine(w2, d, pr, tau, Et), zb) if tau else zb
    zd = _apply(E3, _affine(w2, d, ps, h3, E3), zc)
    r = np.empty(2 * M + 2)
    r[:2 * M] = z0 - Jv * zd
    r[2 * M] = -zb[0] - drive.switch_out
    r[2 * M + 1] = c @ zd[:M]
    Eb = _compose(E1, Et) if tau else E1  # z0 -> zb
    Ebd = _compose(E3, Et) if tau else E3  # zb -> zd
    Ed = _compose(Ebd, Eb)
    dzb_dh1 = _field(w2, d, pr, zb)
    dzd_dh1 = _apply(Ebd, (np.zeros(M), np.zeros(M)), dzb_dh1)
    dzd_dh3 = _field(w2, d, ps, zd)
    Jac = np.zeros((2 * M + 2, 2 * M + 2))
    Jac[:2 * M, :2 * M] = np.eye(2 * M) - Jv[:, None] * _matrix(Ed)
    Jac[:2 * M, 2 * M] = -Jv * dzd_dh1
    Jac[:2 * M, 2 * M + 1] = -Jv * dzd_dh3
    Jac[2 * M, 0] = -Eb[0][0]
    Jac[2 * M, M] = -Eb[1][0]
    Jac[2 * M, 2 * M] = -dzb_dh1[0]
    Jac[2 * M + 1, :M] = c * Ed[0]
    Jac[2 * M + 1, M:2 * M] = c * Ed[1]
    Jac[2 * M + 1, 2 * M] = c @ dzd_dh1[:M]
    Jac[2 * M + 1, 2 * M + 1] = c @ dzd_dh3[:M]
    return r, Jac


def _residual_m(model, drive, X, m, consts=None):
    """Residual and exact Jacobian of the ``m``-impact segment problem (multiple shooting, theory
    §10): ``X`` holds ``m`` blocks ``(state after impact k, h1_k, h3_k)``; block ``k`` carries the
    switch and contact conditions of its interval, and its impact law lands on the state of block
    ``k + 1`` (of block 0 for the last)."""
    if m == 1:
        return _residual(model, drive, X, consts)
    consts = consts if consts is not None else _constants(model)
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
        Rigid or flexible bar under the paper's impact law (eq. 10).
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
        On a bad argument, an impact law other than the paper's, ``impacts >= 2`` without a guess,
        or when Newton does not converge.

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
    if not model.law.instantaneous:
        raise ValueError(f"find_orbit with a PositionSwitchedDrive supports the paper's instantaneous "
                         f"impact law only (model.impact = 'paper'); got {model.impact!r}")
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
    consts = _constants(model)
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


def _newton(model, drive, X, tol, max_iter, consts=None, m=1):
    """Newton's method on the segment problem from ``X`` (damped while the flight times would
    change by more than a half). It stops when a step is below ``tol`` (relative), or when the
    next step, predicted from quadratic convergence (``|s_k|^2 / |s_(k-1)|``), would be: that
    saves the last residual, whose only use would be to see the step vanish."""
    M = model.n_modes + 1
    consts = consts if consts is not None else _constants(model)
    hi = _flight_index(M, m)
    last = math.inf
    for _ in range(max_iter):
        r, Jac = _residual_m(model, drive, X, m, consts)
        step = np.linalg.solve(Jac, -r)
        big = np.max(np.abs(step[hi]) / np.abs(X[hi]))
        if big > 0.5:  # damped while far: the flight times change by at most a half
            step *= 0.5 / big
        X = X + step
        if np.any(X[hi] <= 0.0):
            raise ValueError("Newton left the region of positive flight times: give a guess closer "
                             "to the orbit (e.g. from simulate)")
        size = float(np.max(np.abs(step)))
        scale = tol * max(1.0, float(np.max(np.abs(X))))
        if size <= scale or (big <= 0.5 and math.isfinite(last) and size < 1e-4 * last
                             and size * size <= scale * last):
            return X
        last = size
    raise ValueError(f"find_orbit did not converge in {max_iter} Newton steps (last step "
                     f"{np.max(np.abs(step)):.2e})")


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


def _admissibility(model, drive, z0, durations, samples: int = 400) -> Admissibility:
    """The end off the stop inside every flight, the return crossing the first one, and a forward
    impact (theory §5, §10): exact for the rigid bar (one turning point per flight), sampled on a
    grid finer than the stiffest mode's period for a flexible one."""
    M = model.n_modes + 1
    w2, d = _w2(model), model.d
    c = model.end_weights
    ps, pr = drive.level(STROKE), drive.level(RETURN)
    tau, h1, _, h3 = durations
    za, zb, zc, zd = _legs(model, drive, z0, durations)
    if c @ zd[M:] <= 0.0:
        return Admissibility.BACKWARD_IMPACT
    # the crossing must be the first rising one of the gap in the return flight
    t_first = first_rising_crossing(d, -za[0], -za[M], -pr, drive.switch_out)
    if not math.isclose(t_first, h1, rel_tol=1e-8, abs_tol=1e-12):
        return Admissibility.PENETRATES
    flights = ((ps, z0, tau), (pr, za, h1), (pr, zb, tau), (ps, zc, h3))
    if M == 1:  # the rigid bar: q_0 has at most one turning point per flight (theory §10), exact
        for p, z, h in flights:
            if h <= 0.0:
                continue
            t_turn = rate_zero(d, float(z[1]), p)
            inner = [float(z[0])] if z is not z0 else []
            if 0.0 < t_turn < h:
                inner.append(float(_apply(_blocks(w2, d, t_turn), _affine(w2, d, p, t_turn,
                                                                          _blocks(w2, d, t_turn)), z)[0]))
            if inner and max(inner) > 1e-12 * max(1.0, drive.switch_out):
                return Admissibility.PENETRATES
        if c @ z0[M:] >= 0.0 and model.R > 0.0:
            return Admissibility.STICKS
        return Admissibility.ADMISSIBLE
    n = max(samples, int(8 * model.s * model.n_modes * sum(durations)))
    worst = -math.inf
    scale = max(1.0, float(np.max(np.abs(z0[:M]))))
    under = bool(np.all(w2[1:] > 0.25 * d * d))  # every flexible mode underdamped: compiled
    for p, z, h in flights:
        if h <= 0.0 or n < 3:
            continue
        if under:
            worst = max(worst, float(end_max_sampled(w2, d, p, c, z[:M], z[M:], h, n)))
            continue
        t = np.linspace(0.0, h, n)[1:-1]
        q, _ = step_constant(w2, d, p, z[:M], z[M:], t)
        worst = max(worst, float(np.max(c @ q)))
    if worst > 1e-12 * scale:
        return Admissibility.PENETRATES
    if c @ z0[M:] >= 0.0 and model.R > 0.0:
        return Admissibility.STICKS
    return Admissibility.ADMISSIBLE
