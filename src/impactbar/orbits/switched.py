"""Periodic motions under a position-switched drive: autonomous, with an unknown period (theory §10).

One period of a one-impact orbit, counted from an impact (the valve's rules of
:class:`~impactbar.drives.PositionSwitchedDrive`, delay ``tau``):

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

from .._status import Admissibility
from .._validate import check_int, check_real
from ..drives.switched import RETURN, STROKE, PositionSwitchedDrive, first_rising_crossing
from ..dynamics.modal import fundamental, step_constant
from ..model import BarModel

__all__ = ["SwitchedOrbit", "find_switched_orbit"]


@dataclass(frozen=True)
class SwitchedOrbit:
    """A periodic motion with one impact per period under a position-switched drive (theory §10).

    Attributes
    ----------
    model : BarModel
    drive : PositionSwitchedDrive
    period : float
        Period ``T`` (the model's time unit, eq. 2).
    durations : numpy.ndarray, shape (4,)
        The four flights of the period: stroke ``tau``, return ``h1`` (to the switch crossing),
        return ``tau``, stroke ``h3`` (to the impact).
    state : numpy.ndarray, shape (2 N + 2,)
        Modal state ``(q_0..q_N, q_0'..q_N')`` just after the impact.
    impact_velocity : float
        ``u_t(1, T-)``, the struck end's velocity arriving at the stop.
    multipliers : numpy.ndarray, shape (2 N + 1,)
        Non-trivial Floquet multipliers (those of the Poincare map), largest modulus first.
    trivial_multiplier : float
        The multiplier along the flow, ``1`` in exact arithmetic (its distance from 1 measures the
        rounding of the monodromy matrix).
    admissibility : Admissibility
        Whether the motion is physical (sampled check, theory §5 and §10).
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
    _monodromy: np.ndarray = field(repr=False, default=None)

    @property
    def blow_frequency(self) -> float:
        """Blows per unit of the model's time, ``1 / T``; with the time scale ``t = Omega t_SI``
        (eq. 2) the blow frequency in Hz is ``Omega / T``."""
        return 1.0 / self.period

    @property
    def switch_times(self) -> np.ndarray:
        """Times after the impact at which the switches take effect: to return, then to stroke,
        shape ``(2,)``."""
        tau, h1, tau2, _ = self.durations
        return np.array([tau, tau + h1 + tau2])

    @property
    def impact_energy(self) -> float:
        """Kinetic energy of the bar arriving at the stop, ``(1/2) int_0^1 u_t^2 dx`` (units of
        ``m L^2 Omega^2``, eq. 2)."""
        z = _before_impact(self.model, self.drive, self.state, self.durations)
        v = z[self.model.n_modes + 1:]
        return 0.5 * (v[0] ** 2 + 2.0 * float(np.sum(v[1:] ** 2)))

    @property
    def stable(self) -> bool:
        """Admissible with every non-trivial multiplier inside the unit circle."""
        return self.admissibility == Admissibility.ADMISSIBLE and bool(np.all(np.abs(self.multipliers) < 1.0))


# --------------------------------------------------------------------------------------------------
# flows
# --------------------------------------------------------------------------------------------------
def _w2(model: BarModel) -> np.ndarray:
    return (model.s * np.pi * np.arange(model.n_modes + 1)) ** 2


def _flow(w2, d, p, z, h):
    M = w2.size
    q, v = step_constant(w2, d, p, z[:M], z[M:], h)
    return np.concatenate((q, v))


def _field(w2, d, p, z):
    M = w2.size
    q, v = z[:M], z[M:]
    return np.concatenate((v, p - d * v - w2 * q))


def _fund(w2, d, h):
    """The flow's Jacobian ``E(h)``, shape ``(2M, 2M)`` (block-diagonal per mode)."""
    p11, p12, p21, p22 = fundamental(w2, d, np.full(w2.shape, float(h)))
    return np.block([[np.diag(p11), np.diag(p12)], [np.diag(p21), np.diag(p22)]])


def _jump(model: BarModel) -> np.ndarray:
    """The paper's impact law (eq. 10) as a matrix: ``q`` kept, ``v -> -R v``."""
    M = model.n_modes + 1
    return np.diag(np.concatenate((np.ones(M), np.full(M, -model.R))))


def _legs(model, drive, z0, durations):
    """States at the ends of the four flights from ``z0`` (after the impact)."""
    w2, d = _w2(model), model.d
    ps, pr = drive.level(STROKE), drive.level(RETURN)
    tau, h1, _, h3 = durations
    za = _flow(w2, d, ps, z0, tau) if tau else z0.copy()
    zb = _flow(w2, d, pr, za, h1)
    zc = _flow(w2, d, pr, zb, tau) if tau else zb.copy()
    zd = _flow(w2, d, ps, zc, h3)
    return za, zb, zc, zd


def _before_impact(model, drive, z0, durations):
    return _legs(model, drive, z0, durations)[3]


# --------------------------------------------------------------------------------------------------
# Newton on the segment problem
# --------------------------------------------------------------------------------------------------
def _residual(model, drive, X):
    M = model.n_modes + 1
    c = model.end_weights
    z0, h1, h3 = X[:2 * M], X[2 * M], X[2 * M + 1]
    tau = drive.delay
    za, zb, zc, zd = _legs(model, drive, z0, (tau, h1, tau, h3))
    J = _jump(model)
    r = np.empty(2 * M + 2)
    r[:2 * M] = z0 - J @ zd
    r[2 * M] = -zb[0] - drive.switch_out
    r[2 * M + 1] = c @ zd[:M]
    # exact Jacobian
    w2, d = _w2(model), model.d
    ps, pr = drive.level(STROKE), drive.level(RETURN)
    Es_tau, Er_tau = (_fund(w2, d, tau), _fund(w2, d, tau)) if tau else (np.eye(2 * M),) * 2
    Er1, Es3 = _fund(w2, d, h1), _fund(w2, d, h3)
    dzb_dz0 = Er1 @ Es_tau
    dzd_dz0 = Es3 @ Er_tau @ dzb_dz0
    dzb_dh1 = _field(w2, d, pr, zb)
    dzd_dh1 = Es3 @ Er_tau @ dzb_dh1
    dzd_dh3 = _field(w2, d, ps, zd)
    Jac = np.zeros((2 * M + 2, 2 * M + 2))
    Jac[:2 * M, :2 * M] = np.eye(2 * M) - J @ dzd_dz0
    Jac[:2 * M, 2 * M] = -J @ dzd_dh1
    Jac[:2 * M, 2 * M + 1] = -J @ dzd_dh3
    Jac[2 * M, :2 * M] = -dzb_dz0[0]
    Jac[2 * M, 2 * M] = -dzb_dh1[0]
    Jac[2 * M + 1, :2 * M] = c @ dzd_dz0[:M]
    Jac[2 * M + 1, 2 * M] = c @ dzd_dh1[:M]
    Jac[2 * M + 1, 2 * M + 1] = c @ dzd_dh3[:M]
    return r, Jac


def _rigid_guess(model, drive):
    """Start of Newton: the rigid undamped undelayed orbit in closed form (theory §10)."""
    M = model.n_modes + 1
    R = min(model.R, 0.999)
    o = drive.rigid_orbit(R)
    z0 = np.zeros(2 * M)
    z0[M] = -R * o["impact_velocity"]
    return np.concatenate((z0, [o["switch_time"], o["period"] - o["switch_time"]]))


def find_switched_orbit(model: BarModel, drive: PositionSwitchedDrive, impacts: int = 1, guess=None,
                        *, tol: float = 1e-13, max_iter: int = 50) -> SwitchedOrbit:
    """The one-impact periodic motion under a position-switched drive (theory §10).

    Called by :func:`impactbar.find_orbit` when its load is a
    :class:`~impactbar.drives.PositionSwitchedDrive`.

    Parameters
    ----------
    model : BarModel
        Rigid or flexible bar under the paper's impact law (eq. 10).
    drive : PositionSwitchedDrive
    impacts : int
        Impacts per period; only ``1`` so far.
    guess : SwitchedOrbit, tuple or None
        Where Newton starts: an orbit (e.g. from a nearby parameter), a tuple ``(state, h1, h3)``
        (state after the impact, shape ``(2 N + 2,)``, and the two free flight durations), or
        ``None``: the rigid closed form of :meth:`PositionSwitchedDrive.rigid_orbit`.
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
        On a bad argument, an impact law other than the paper's, or when Newton does not converge.
    """
    if not isinstance(model, BarModel):
        raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
    if not isinstance(drive, PositionSwitchedDrive):
        raise ValueError(f"drive must be a PositionSwitchedDrive; got {type(drive).__name__}")
    check_int("impacts", impacts, lo=1, hi=1)
    tol = check_real("tol", tol, lo=0.0, lo_open=True)
    max_iter = check_int("max_iter", max_iter, lo=1)
    if model.impact != "paper":
        raise ValueError(f"find_orbit with a PositionSwitchedDrive supports the paper's impact law "
                         f"only (model.impact = 'paper'); got {model.impact!r}")
    if model.R >= 1.0:
        raise ValueError("model.R must be < 1 for a periodic motion under a position-switched drive "
                         "(with R = 1 no energy leaves and the blows grow without bound)")
    M = model.n_modes + 1
    if guess is None and M > 1:  # the rigid bar's orbit (same damping and delay), then lifted
        rigid = find_switched_orbit(model.with_(n_modes=0), drive, tol=tol, max_iter=max_iter)
        X = np.concatenate((_padded(rigid.state, M), rigid.durations[[1, 3]]))
    elif guess is None:
        X = _rigid_guess(model, drive)
    elif isinstance(guess, SwitchedOrbit):
        X = np.concatenate((_padded(guess.state, M), guess.durations[[1, 3]]))
    else:
        state, h1, h3 = guess
        X = np.concatenate((_padded(np.asarray(state, dtype=float), M), [float(h1), float(h3)]))
    if guess is None and M > 1:  # the flexible modes at the rigid switch time: one Newton step
        r, Jac = _residual(model, drive, X)  # without the switch condition, h1 kept
        keep = np.r_[0:2 * M, 2 * M + 1]
        X[keep] += np.linalg.solve(Jac[np.ix_(keep, keep)], -r[keep])
    for _ in range(max_iter):
        r, Jac = _residual(model, drive, X)
        step = np.linalg.solve(Jac, -r)
        big = np.max(np.abs(step[2 * M:]) / np.abs(X[2 * M:]))
        if big > 0.5:  # damped while far: the flight times change by at most a half
            step *= 0.5 / big
        X = X + step
        if X[2 * M] <= 0.0 or X[2 * M + 1] <= 0.0:
            raise ValueError("Newton left the region of positive flight times: give a guess closer "
                             "to the orbit (e.g. from simulate)")
        if np.max(np.abs(step)) <= tol * max(1.0, np.max(np.abs(X))):
            break
    else:
        raise ValueError(f"find_orbit did not converge in {max_iter} Newton steps (last step "
                         f"{np.max(np.abs(step)):.2e})")
    z0 = X[:2 * M]
    durations = np.array([drive.delay, X[2 * M], drive.delay, X[2 * M + 1]])
    Phi = _monodromy(model, drive, z0, durations)
    za = _legs(model, drive, z0, durations)[0]
    f = _field(_w2(model), model.d, drive.level(RETURN), za)
    trivial, nontrivial = _split_multipliers(Phi, f)
    zd = _legs(model, drive, z0, durations)[3]
    c = model.end_weights
    return SwitchedOrbit(model=model, drive=drive, period=float(np.sum(durations)), durations=durations,
                         state=z0, impact_velocity=float(c @ zd[M:]), multipliers=nontrivial,
                         trivial_multiplier=trivial,
                         admissibility=_admissibility(model, drive, z0, durations), _monodromy=Phi)


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
        A = Eta_s @ A_imp + np.outer(_field(w2, d, ps, za) - _field(w2, d, pr, za), dti @ A)
    else:
        A = A_imp
    return A


def _split_multipliers(Phi, f):
    """The trivial multiplier along ``f`` and the others: ``Phi`` in the orthonormal basis
    ``(f/|f|, B)`` is block upper triangular (``Phi f = f``)."""
    n = f.size
    fhat = f / np.linalg.norm(f)
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
    """Sampled check (theory §5, §10): the end off the stop inside every flight, the return crossing
    the first one, and a forward impact."""
    M = model.n_modes + 1
    w2, d = _w2(model), model.d
    c = model.end_weights
    ps, pr = drive.level(STROKE), drive.level(RETURN)
    tau, h1, _, h3 = durations
    zd = _legs(model, drive, z0, durations)[3]
    if c @ zd[M:] <= 0.0:
        return Admissibility.BACKWARD_IMPACT
    za, zb, zc, _ = _legs(model, drive, z0, durations)
    # the crossing must be the first rising one of the gap in the return flight
    t_first = first_rising_crossing(d, -za[0], -za[M], -pr, drive.switch_out)
    if not math.isclose(t_first, h1, rel_tol=1e-8, abs_tol=1e-12):
        return Admissibility.PENETRATES
    n = max(samples, int(8 * model.s * model.n_modes * sum(durations)))
    worst = -math.inf
    scale = max(1.0, float(np.max(np.abs(z0[:M]))))
    for p, z, h in ((ps, z0, tau), (pr, za, h1), (pr, zb, tau), (ps, zc, h3)):
        if h <= 0.0:
            continue
        t = np.linspace(0.0, h, n)[1:-1]
        q, _ = step_constant(w2, d, p, z[:M], z[M:], t)
        worst = max(worst, float(np.max(c @ q)) if t.size else -math.inf)
    if worst > 1e-12 * scale:
        return Admissibility.PENETRATES
    if c @ z0[M:] >= 0.0 and model.R > 0.0:
        return Admissibility.STICKS
    return Admissibility.ADMISSIBLE
