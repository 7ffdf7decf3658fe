"""The segment problem of a switched orbit (theory §10): the constant-force flows of the modes in
closed form (eq. 8), the residual of the valve cycle with its exact Jacobian, Newton's method, and
the flights' admissibility; the impact is eq. 10's, or the contact's map of a law whose contact
takes time (:class:`ContactMap`). Used by :mod:`impactbar.orbits.switched` and by the continuation
of switched orbits."""

from __future__ import annotations

import math

import numpy as np

from .._shared.status import Admissibility
from ..drives.switched import RETURN, STROKE
from ..dynamics._switchkernel import end_max_sampled, first_rising_crossing, rate_zero
from ..dynamics.modal import fundamental, step_constant
from ..model import BarModel


class ContactMap:
    """The law's contact of an arrival under the constant stroke force, for a law whose contact
    takes time (the wave law, the rod-rock law): ``zd -> (z_after, dz_after/dzd)``
    (``ContactLaw.impact_map`` at load time 0; the force is constant, so the time does not matter),
    memoised on the last arrival state (Newton asks for it once per step, the orbit again).
    ``window`` is the contact's duration (``ContactLaw.window``)."""

    def __init__(self, model: BarModel, drive) -> None:
        from ..loads import FourierLoad

        self.model, self.law = model, model.law
        self.load = FourierLoad(float(drive.stroke), [])
        self.window = float(model.law.window(model))
        self._last = None

    def __call__(self, zd):
        zd = np.asarray(zd, dtype=float)
        if self._last is not None and np.array_equal(self._last[0], zd):
            return self._last[1], self._last[2]
        z_after, jac, _ = self.law.impact_map(self.model, self.load, 0.0, zd)
        self._last = (zd.copy(), np.asarray(z_after, dtype=float), np.asarray(jac, dtype=float))
        return self._last[1], self._last[2]


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


def _constants(model, drive=None):
    """What the residual needs of the model, computed once per solve: ``(w2, c, Jv)``, ``Jv`` the
    impact law (eq. 10) as the diagonal ``(1, .., 1, -R, .., -R)``; under a law whose contact takes
    time (the wave law, the rod-rock law) ``Jv`` is the contact's map instead
    (:class:`ContactMap`, needs the ``drive``)."""
    M = model.n_modes + 1
    if not model.law.instantaneous:
        if drive is None:
            raise ValueError("the contact map of a law whose contact takes time needs the drive")
        return _w2(model), model.end_weights, ContactMap(model, drive)
    R = model.law.kernel_restitution(model)
    return _w2(model), model.end_weights, np.concatenate((np.ones(M), np.full(M, -R)))


def _flights(model, drive, X, w2):
    """The four flights of the segment problem from ``X = (z0, h1, h3)``: ``(zb, zd, Eb, Ed,
    dzb_dh1, dzd_dh1, dzd_dh3)``, the states at the switch crossing and at the arrival, the flows'
    Jacobians from ``z0`` to them (per-mode 2x2 blocks) and the states' rates in ``h1``, ``h3``."""
    M = model.n_modes + 1
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
    Eb = _compose(E1, Et) if tau else E1  # z0 -> zb
    Ebd = _compose(E3, Et) if tau else E3  # zb -> zd
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


def _newton(model, drive, X, tol, max_iter, consts=None, m=1):
    """Newton's method on the segment problem from ``X`` (damped while the flight times would
    change by more than a half). It stops when a step is below ``tol`` (relative), or when the
    next step, predicted from quadratic convergence (``|s_k|^2 / |s_(k-1)|``), would be: that
    saves the last residual, whose only use would be to see the step vanish."""
    M = model.n_modes + 1
    consts = consts if consts is not None else _constants(model, drive)
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
