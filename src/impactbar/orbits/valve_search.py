r"""Every one-impact orbit of the valve in a window of periods, certified (theory §10).

Under the paper's impact law a one-impact orbit of :class:`~impactbar.PositionSwitchedDrive` is, for
given flight times, the solution of linear equations: the schedule of forces (stroke for
:math:`\tau_\mathrm{in}`, return for :math:`h_1 + \tau_\mathrm{out}`, stroke for :math:`h_3`; period
:math:`T = \tau_\mathrm{in} + h_1 + \tau_\mathrm{out} + h_3`) fixes every mode's periodic motion,
mode by mode. Per flexible mode :math:`n` (frequency :math:`w_n = s n \pi`, static deflection
:math:`P / w_n^2` under a force :math:`P`), with the flow :math:`E(t)` of
:math:`q'' + d q' + w_n^2 q = 0`, the impact law :math:`J = \operatorname{diag}(1, -R)` and the step
of the static state between the two forces
:math:`\Delta = ((\mathrm{stroke} + \mathrm{ret}) / w_n^2, 0)`, the state just after the impact is

.. math::

    z_n = (\mathrm{stroke} / w_n^2, 0) + (I - J E(T))^{-1} J \,[E(T - \tau_\mathrm{in}) - E(h_3)]\,
    \Delta ,

the rigid mode's velocity after the impact follows from the impact law, its position from contact
(:math:`u(1) = 0` at the impact: :math:`q_0 = -e`, :math:`e` the flexible modes' share of the end's
displacement). Two conditions remain, on the two unknowns :math:`(T, h_3)`:

- :math:`F_1`: the rigid coordinate comes back to where it left (a function of the rigid mode alone);
- :math:`F_2 = e + X - x_1` (:math:`x_1` = ``switch_out``): the gap at the crossing, :math:`X` the
  rigid mode's excursion from the impact to it.

Both and their exact Jacobian are closed forms (:class:`OneImpactEquations`). The search
(:func:`search_one_impact`) covers the window :math:`[T_\mathrm{min}, T_\mathrm{max}]` times
:math:`0 \le h_3 \le T_\mathrm{max} - \tau` with square cells, bisected: a cell is excluded when
:math:`|F_i(\mathrm{mid})|` exceeds the bound of its
gradient over the cell times its half-width (the mean-value theorem), the gradient enclosed by
interval arithmetic on the closed forms (each flexible function is :math:`e^{-d t/2}` times a
sinusoid, enclosed to second order, and the resolvent's determinant
:math:`1 - R e^{-dT} - e^{-dT/2}[(1 - R) \cos(l T) + (1 + R) \frac{d}{2 l} \sin(l T)]` directly). The
survivors are grouped into clusters; in each, Newton's method on :math:`(F_1, F_2)` finds a point and
the Krawczyk test on a box around it, with the same enclosure of the Jacobian, proves that the box
holds exactly one root (R. Krawczyk, *Computing* 4, 1969; R. E. Moore, *Interval Analysis*,
1966). So every root with a period in the window is found, once, except in clusters that neither
exclusion nor the test resolves down to the smallest cells (``MIN_CELL``): a double root (a fold of
the orbits in a parameter) or, undamped (``d = 0``), a resonance ``T = 2 k / (s n)``, where the
mode's periodic motion does not exist and ``F2`` has a pole. These are reported with their period
interval; Newton's method is tried there too, and a root it finds is listed as not certified.

Rounding: the point values carry an absolute floor of ``1e-12`` times the size of their terms, and
the interval arithmetic is not rounded outward (the floor covers it); "certified" is meant up to
that.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["OneImpactEquations", "search_one_impact", "OneImpactRoots", "default_window", "MIN_CELL",
           "FIRST_CELLS", "MAX_CELLS"]

#: smallest cell, relative to the window's width: a cluster still undecided there is reported
MIN_CELL = 1e-10
#: cells across the window's widest side at the start
FIRST_CELLS = 16
#: most cells alive at once (a bound on the memory and the time; reached only with d = 0 and a wide
#: window full of resonances)
MAX_CELLS = 400_000
#: a point's coordinates (a row of the points ``x``, of their boxes' radii ``rad`` and of the roots):
#: the period T and the last stroke's time h_3 (the two unknowns)
X_T, X_H = 0, 1
#: most cells in a cluster on which the Krawczyk test is tried
CLUSTER_CELLS = 64
#: rounding floor of the point values, relative to the size of their terms
FLOOR = 1e-12


# --------------------------------------------------------------------------------------------------
# intervals
# --------------------------------------------------------------------------------------------------
class _Iv:
    """Arrays of intervals ``[lo, hi]`` with the arithmetic the enclosures need (not rounded
    outward: the search's floors cover rounding)."""

    __slots__ = ("lo", "hi")
    __array_ufunc__ = None  # an array on the left defers to the reflected operators below

    def __init__(self, lo, hi=None):
        self.lo = lo
        self.hi = lo if hi is None else hi

    def __add__(self, o):
        if isinstance(o, _Iv):
            return _Iv(self.lo + o.lo, self.hi + o.hi)
        return _Iv(self.lo + o, self.hi + o)

    __radd__ = __add__

    def __neg__(self):
        return _Iv(-self.hi, -self.lo)

    def __sub__(self, o):
        if isinstance(o, _Iv):
            return _Iv(self.lo - o.hi, self.hi - o.lo)
        return _Iv(self.lo - o, self.hi - o)

    def __rsub__(self, o):
        return _Iv(o - self.hi, o - self.lo)

    def __mul__(self, o):
        if not isinstance(o, _Iv):
            a, b = self.lo * o, self.hi * o
            return _Iv(np.minimum(a, b), np.maximum(a, b))
        p1, p2, p3, p4 = self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi
        return _Iv(np.minimum(np.minimum(p1, p2), np.minimum(p3, p4)),
                   np.maximum(np.maximum(p1, p2), np.maximum(p3, p4)))

    __rmul__ = __mul__

    def __truediv__(self, o):
        """Division; where ``o`` holds 0 the result is the whole line."""
        zero = (o.lo <= 0.0) & (o.hi >= 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            out = self * _Iv(np.where(zero, -np.inf, 1.0 / o.hi), np.where(zero, np.inf, 1.0 / o.lo))
        return _Iv(np.where(zero, -np.inf, out.lo), np.where(zero, np.inf, out.hi))

    def mag(self):
        """``max |x|`` over the interval (``nan`` read as unbounded)."""
        m = np.maximum(np.abs(self.lo), np.abs(self.hi))
        return np.where(np.isnan(m), np.inf, m)

    def sum(self, axis=-1):
        return _Iv(self.lo.sum(axis), self.hi.sum(axis))


def _b(d, t):
    """``b(t) = (1 - e^{-d t}) / d`` (``t`` at ``d = 0``): the rigid velocity's response, increasing."""
    return -np.expm1(-d * t) / d if d else np.asarray(t, dtype=float)


def _c(d, t):
    """``c(t) = (t - b(t)) / d`` (``t^2 / 2`` at ``d = 0``): the rigid displacement's response."""
    t = np.asarray(t, dtype=float)
    if not d:
        return 0.5 * t * t
    y = d * t
    with np.errstate(over="ignore", invalid="ignore"):
        full = (t - _b(d, t)) / d
    series = t * t * (0.5 - y / 6.0 + y * y / 24.0 - y**3 / 120.0 + y**4 / 720.0)
    return np.where(np.abs(y) < 1e-2, series, full)


# --------------------------------------------------------------------------------------------------
# the reduced equations
# --------------------------------------------------------------------------------------------------
class OneImpactEquations:
    r"""The valve's one-impact orbits as two equations in :math:`(T, h_3)` (module docstring), their
    exact Jacobian, the enclosure of the Jacobian over boxes, and the state after the impact.

    Parameters
    ----------
    model : BarModel
        Under the paper's impact law (restitution ``model.law.traits.kernel_restitution(model)``), every
        flexible mode underdamped (:math:`d < 2 s \pi`).
    drive : PositionSwitchedDrive
    """

    def __init__(self, model, drive) -> None:
        self.d = d = float(model.d)
        self.R = float(model.law.traits.kernel_restitution(model))
        self.ps, self.pr, self.x1 = float(drive.stroke), float(drive.ret), float(drive.switch_out)
        self.dl = self.ps + self.pr
        self.t_in, self.t_out = float(drive.delay_in), float(drive.delay_out)
        self.tau = self.t_in + self.t_out
        self.w2 = model.frequencies[1:] ** 2
        self.lam = np.sqrt(self.w2 - 0.25 * d * d)
        self.c = np.asarray(model.end_weights[1:], dtype=float)
        self.absc = np.abs(self.c)
        self.k = self.dl / self.w2
        self.static = float(np.sum(self.c * self.ps / self.w2))
        self.M = model.n_modes + 1

    # -- the rigid mode --------------------------------------------------------------------------
    def _rigid(self, T, h):
        """``(F1, dF1, X, dX, v0, scale1, scale2)``: the rigid coordinate's return, the excursion to
        the crossing, their gradients in ``(T, h3)``, the velocity after the impact and the sizes
        of the terms (rounding floors)."""
        d, R, ps, dl = self.d, self.R, self.ps, self.dl
        a, tc = T - self.t_in, T - self.t_out - h
        h1 = tc - self.t_in
        eT, ea, eh, ec = np.exp(-d * T), np.exp(-d * a), np.exp(-d * h), np.exp(-d * tc)
        bT, ba, bh, bc, b1 = _b(d, T), _b(d, a), _b(d, h), _b(d, tc), _b(d, h1)
        G = ps * bT - dl * (ba - bh)
        D = 1.0 + R * eT
        v0 = -R * G / D
        v0T = (-R * (ps * eT - dl * ea) - v0 * (-R * d * eT)) / D
        v0h = -R * dl * eh / D
        cT, ca, ch = _c(d, T), _c(d, a), _c(d, h)
        F1 = bT * v0 + ps * cT - dl * (ca - ch)
        F1T = eT * v0 + bT * v0T + ps * bT - dl * ba
        F1h = bT * v0h + dl * bh
        cc, c1 = _c(d, tc), _c(d, h1)
        X = -(bc * v0 + ps * cc - dl * c1)
        vc = ec * v0 + ps * bc - dl * b1  # the rigid velocity at the crossing
        XT = -(vc + bc * v0T)
        Xh = vc - bc * v0h
        s1 = np.abs(bT * v0) + ps * np.abs(cT) + dl * (np.abs(ca) + np.abs(ch))
        s2 = np.abs(bc * v0) + ps * np.abs(cc) + dl * np.abs(c1)
        return F1, (F1T, F1h), X, (XT, Xh), v0, s1, s2

    # -- the flexible modes ------------------------------------------------------------------------
    def _flows(self, t):
        """``A, B, C, D`` of ``E(t)`` per mode and the derivatives ``C', D'``; ``t`` shape
        ``(K, 1)``."""
        d, lam, w2 = self.d, self.lam, self.w2
        m = np.exp(-0.5 * d * t)
        cs = m * np.cos(lam * t)
        sn = m * np.sin(lam * t) / lam
        A, B, C, D = cs + 0.5 * d * sn, sn, -w2 * sn, cs - 0.5 * d * sn
        return A, B, C, D, -w2 * A - d * C, -w2 * B - d * D

    def _flexible(self, T, h):
        """Per mode: the end share ``q`` after the impact, its gradient, the velocity after the
        impact, shapes ``(K, N)``."""
        R, k = self.R, self.k
        AT, BT, CT, DT, CT1, DT1 = self._flows(T[:, None])
        Aa, _, Ca, _, Ca1, _ = self._flows(T[:, None] - self.t_in)
        Ah, _, Ch, _, Ch1, _ = self._flows(h[:, None])
        rq, rv = k * (Aa - Ah), k * (Ca - Ch)
        K22 = 1.0 + R * DT
        N = K22 * rq - R * BT * rv
        NT = R * DT1 * rq + K22 * k * Ca - R * DT * rv - R * BT * k * Ca1
        Nh = -K22 * k * Ch + R * BT * k * Ch1
        det = (1.0 - AT) * K22 + R * BT * CT
        detT = -CT * K22 + (1.0 - AT) * R * DT1 + R * (DT * CT + BT * (-self.w2 * AT - self.d * CT))
        wq = N / det
        wv = (-R * CT * rq - (1.0 - AT) * R * rv) / det
        return wq, ((NT - wq * detT) / det, Nh / det), wv

    # -- point values ------------------------------------------------------------------------------
    def point(self, T, h):
        """``F = (F1, F2)``, shape ``(K, 2)``, the Jacobian, ``(K, 2, 2)``, and the rounding floors
        ``(K, 2)`` at the points ``(T, h3)``."""
        T = np.atleast_1d(np.asarray(T, dtype=float))
        h = np.atleast_1d(np.asarray(h, dtype=float))
        F1, g1, X, gX, _, s1, s2 = self._rigid(T, h)
        e, eT, eh, se = self.static, 0.0, 0.0, abs(self.static)
        if self.w2.size:
            wq, (wT, wh), _ = self._flexible(T, h)
            e = e + wq @ self.c
            eT, eh = wT @ self.c, wh @ self.c
            se = se + np.abs(wq) @ self.absc
        F = np.stack((F1, e + X - self.x1), axis=-1)
        J = np.empty(F.shape + (2,))
        J[:, 0, 0], J[:, 0, 1] = g1
        J[:, 1, 0], J[:, 1, 1] = gX[0] + eT, gX[1] + eh
        floor = FLOOR * np.stack((s1, s2 + se + self.x1 + np.abs(X)), axis=-1) + 1e-300
        return F, J, floor

    def state(self, T: float, h: float) -> np.ndarray:
        """The unknowns of the valve's segment problem at ``(T, h3)``: the modal state just after
        the impact, shape ``(2 N + 2,)``, then ``h1``, ``h3``."""
        T, h = np.array([float(T)]), np.array([float(h)])
        M = self.M
        _, _, _, _, v0, _, _ = self._rigid(T, h)
        z = np.zeros(2 * M)
        z[M] = v0[0]
        if self.w2.size:
            wq, _, wv = self._flexible(T, h)
            z[1:M] = self.ps / self.w2 + wq[0]
            z[M + 1:] = wv[0]
        z[0] = -float(self.c @ z[1:M])
        return np.concatenate((z, [T[0] - self.tau - h[0], h[0]]))

    # -- enclosures over boxes -----------------------------------------------------------------------
    def _trig(self, t, r):
        """What the enclosures over ``[t - r, t + r]`` share: ``e^{-d t / 2}``, ``cos(l t)``,
        ``sin(l t)``, the largest ``e^{-d t / 2}`` and ``r``."""
        d, lam = self.d, self.lam
        return np.exp(-0.5 * d * t), np.cos(lam * t), np.sin(lam * t), np.exp(-0.5 * d * (t - r)), r

    def _family(self, trig, alpha, beta):
        """Enclosure of ``f = e^{-d t / 2} (alpha cos(l t) + beta sin(l t))`` over ``[t - r, t + r]``
        (``trig`` of :meth:`_trig`), shapes ``(K, N)``: ``f(t) +- (|f'(t)| r + rho w^2 m r^2 / 2)``
        (second order; ``|f''| <= rho w^2 m``, ``rho = |(alpha, beta)|``, ``m`` the largest
        ``e^{-d t / 2}``), within ``+- rho m``."""
        m, cs, sn, m_top, r = trig
        d, lam = self.d, self.lam
        f = m * (alpha * cs + beta * sn)
        f1 = m * ((lam * beta - 0.5 * d * alpha) * cs - (lam * alpha + 0.5 * d * beta) * sn)
        top = np.hypot(alpha, beta) * m_top
        rad = np.abs(f1) * r + 0.5 * self.w2 * top * r * r
        return _Iv(np.maximum(f - rad, -top), np.minimum(f + rad, top))

    def _mono(self, fn, lo, hi, increasing=True):
        a, b = fn(lo), fn(hi)
        return _Iv(a, b) if increasing else _Iv(b, a)

    def jacobian_box(self, T, h, rT, rh):
        """Enclosures of the four entries of the Jacobian of ``(F1, F2)`` in ``(T, h3)`` over the
        boxes ``[T +- rT] x [h3 +- rh]`` (arrays of shape ``(K,)``): ``((J11, J12), (J21, J22))``."""
        d, R, ps, dl = self.d, self.R, self.ps, self.dl
        tl, th = T - rT, T + rT
        hl, hh = h - rh, h + rh
        al, ah = tl - self.t_in, th - self.t_in
        cl, ch = tl - self.t_out - hh, th - self.t_out - hl

        def ex(lo, hi):
            return self._mono(lambda t: np.exp(-d * t), lo, hi, False)

        def bb(lo, hi):
            return self._mono(lambda t: _b(d, t), lo, hi)

        eT, bT, ea, ba = ex(tl, th), bb(tl, th), ex(al, ah), bb(al, ah)
        eh, bh, ec, bc = ex(hl, hh), bb(hl, hh), ex(cl, ch), bb(cl, ch)
        b1 = bb(cl - self.t_in, ch - self.t_in)
        G = ps * bT - dl * (ba - bh)
        D = 1.0 + R * eT
        v0 = -R * G / D
        v0T = (-R * (ps * eT - dl * ea) + v0 * (R * d) * eT) / D
        v0h = (-R * dl) * eh / D
        F1T = eT * v0 + bT * v0T + ps * bT - dl * ba
        F1h = bT * v0h + dl * bh
        vc = ec * v0 + ps * bc - dl * b1
        F2T = -(vc + bc * v0T)
        F2h = vc - bc * v0h
        if self.w2.size:
            eT_, eh_ = self._flexible_box(T[:, None], h[:, None], rT[:, None], rh[:, None])
            F2T = F2T + (eT_ * self.c).sum()
            F2h = F2h + (eh_ * self.c).sum()
        return (F1T, F1h), (F2T, F2h)

    def _flexible_box(self, T, h, rT, rh):
        """Enclosures of the flexible modes' ``(dw_q/dT, dw_q/dh3)`` over the boxes, ``(K, N)``."""
        d, R, lam, w2, k = self.d, self.R, self.lam, self.w2, self.k
        hd = 0.5 * d / lam
        fam = self._family

        def flows(trig, full):
            A = fam(trig, 1.0, hd)
            C = fam(trig, 0.0, -w2 / lam)
            C1 = fam(trig, -w2, w2 * hd)  # -w2 A - d C
            if not full:
                return A, None, C, None, C1, None
            B = fam(trig, 0.0, 1.0 / lam)
            D = fam(trig, 1.0, -hd)
            D1 = fam(trig, -d, -w2 / lam + d * hd)  # -w2 B - d D
            return A, B, C, D, C1, D1

        trig_T = self._trig(T, rT)
        AT, BT, CT, DT, CT1, DT1 = flows(trig_T, True)
        Aa, _, Ca, _, Ca1, _ = flows(self._trig(T - self.t_in, rT), False)
        Ah, _, Ch, _, Ch1, _ = flows(self._trig(h, rh), False)
        rq, rv = (Aa - Ah) * k, (Ca - Ch) * k
        K22 = 1.0 + R * DT
        N = K22 * rq - R * BT * rv
        NT = R * DT1 * rq + K22 * Ca * k - R * DT * rv - R * BT * Ca1 * k
        Nh = -(K22 * Ch * k) + R * BT * Ch1 * k
        # the determinant and its rate as functions of T alone: 1 - R e^{-dT} - f(T), R d e^{-dT} - f'(T)
        al, be = 1.0 - R, (1.0 + R) * hd
        f = fam(trig_T, al, be)
        f1 = fam(trig_T, lam * be - 0.5 * d * al, -(lam * al + 0.5 * d * be))
        ex = _Iv(np.exp(-d * (T + rT)), np.exp(-d * (T - rT)))
        det = 1.0 - R * ex - f
        detT = (R * d) * ex - f1
        return NT / det - (N / det) * (detT / det), Nh / det

    def det_box(self, T, rT):
        """Enclosure of each flexible mode's determinant ``det(I - J E(T))`` over ``[T +- rT]``,
        ``(K, N)``: it holds 0 near an undamped resonance."""
        d, R, lam = self.d, self.R, self.lam
        hd = 0.5 * d / lam
        f = self._family(self._trig(T[:, None], rT[:, None]), 1.0 - R, (1.0 + R) * hd)
        ex = _Iv(np.exp(-d * (T + rT))[:, None], np.exp(-d * (T - rT))[:, None])
        return 1.0 - R * ex - f


# --------------------------------------------------------------------------------------------------
# the search
# --------------------------------------------------------------------------------------------------
class OneImpactRoots(NamedTuple):
    """What :func:`search_one_impact` finds.

    Attributes
    ----------
    roots : numpy.ndarray, shape (K, 2)
        ``(T, h3)`` of each root, by increasing period.
    certified : numpy.ndarray of bool, shape (K,)
        Whether the Krawczyk test proved the root unique in its box (else found by Newton's method
        in an unresolved cluster).
    boxes : numpy.ndarray, shape (K, 2)
        The half-widths of the box around each certified root that holds no other.
    unresolved : tuple of (float, float, str)
        Period intervals of clusters neither excluded nor resolved down to the smallest cells, with
        the reason (``"resonance"``: an undamped mode's periodic motion has a pole there;
        ``"not resolved"``: e.g. a double root).
    window : (float, float)
        The window of periods searched.
    cells : int
        Cells examined (the search's cost).
    """

    roots: np.ndarray
    certified: np.ndarray
    boxes: np.ndarray
    unresolved: tuple
    window: tuple
    cells: int


def default_window(model, drive) -> tuple[float, float]:
    """The default window of periods: from a tenth to ten times the rigid piston's period ``T_r``
    (the rigid bar of the same damping, restitution and delays; the closed form of
    :meth:`~impactbar.PositionSwitchedDrive.rigid_orbit` where the rigid map's fixed point fails),
    and above the two delays."""
    from ..drives.valve.closed_forms import rigid_orbit_start

    R = float(model.law.traits.kernel_restitution(model))
    o = drive.rigid_orbit(min(R, 0.999))
    tau = drive.delay_in + drive.delay_out
    v, h1, h3 = rigid_orbit_start(float(model.d), R, tuple(drive.kernel_view), o["impact_velocity"])
    Tr = tau + h1 + h3 if math.isfinite(v) else tau + o["period"]
    return max(0.1 * Tr, tau + 1e-3 * (Tr - tau)), 10.0 * Tr


def _clusters(i, j):
    """Labels of the 8-connected clusters of the grid cells ``(i, j)`` (scipy's connected
    components)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = i.size
    if n == 0:
        return 0, np.zeros(0, dtype=np.int64)
    span = int(j.max() - j.min()) + 3
    key = (i - i.min() + 1) * span + (j - j.min() + 1)
    order = np.argsort(key)
    skey = key[order]
    rows, cols = [np.arange(n)], [np.arange(n)]
    for di, dj in ((0, 1), (1, -1), (1, 0), (1, 1)):
        target = key + di * span + dj
        pos = np.clip(np.searchsorted(skey, target), 0, n - 1)
        hit = skey[pos] == target
        rows.append(np.flatnonzero(hit))
        cols.append(order[pos[hit]])
    r, c = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(r.size), (r, c)), shape=(n, n))
    return connected_components(graph, directed=False)


def _newton(eq, x, steps=8):
    """Newton's method on ``(F1, F2)`` from the points ``x`` (K, 2), vectorised: the points (NaN
    where a step failed) and whether the last step was below ``1e-13`` of the point."""
    x = x.copy()
    ok = np.zeros(x.shape[0], dtype=bool)
    for _ in range(steps):
        F, J, _ = eq.point(x[:, X_T], x[:, X_H])
        det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            s0 = (J[:, 1, 1] * F[:, 0] - J[:, 0, 1] * F[:, 1]) / det
            s1 = (-J[:, 1, 0] * F[:, 0] + J[:, 0, 0] * F[:, 1]) / det
        x[:, X_T] -= s0
        x[:, X_H] -= s1
        ok = np.abs(s0) + np.abs(s1) <= 1e-13 * (1.0 + np.abs(x[:, X_T]))
        if np.all(ok | ~np.isfinite(x[:, X_T])):
            break
    return x, ok


def _krawczyk(eq, x, rad):
    """The Krawczyk test on the boxes ``x +- rad`` (K, 2): ``True`` where the box holds exactly one
    root of ``(F1, F2)``. With ``Y`` the inverse of the Jacobian at ``x`` and ``J(X)`` its enclosure
    over the box, the box is mapped into itself's interior by ``x - Y F(x) + (I - Y J(X))(X - x)``,
    i.e. ``|Y F(x)|_i + sum_j |I - Y J(X)|_ij rad_j < rad_i``."""
    F, J, floor = eq.point(x[:, X_T], x[:, X_H])
    with np.errstate(divide="ignore", invalid="ignore"):
        Y = np.linalg.inv(J)
    (g11, g12), (g21, g22) = eq.jacobian_box(x[:, X_T], x[:, X_H], rad[:, X_T], rad[:, X_H])
    G = ((g11, g12), (g21, g22))
    ok = np.all(np.isfinite(Y.reshape(-1, 4)), axis=1)
    YF = np.abs(np.einsum("kij,kj->ki", Y, F)) + np.einsum("kij,kj->ki", np.abs(Y), floor)
    for i in range(2):
        total = YF[:, i].copy()
        for j in range(2):
            m = Y[:, i, 0] * G[0][j] + Y[:, i, 1] * G[1][j]  # (Y J(X))_ij
            m = (1.0 if i == j else 0.0) - m
            total += m.mag() * rad[:, j]
        ok &= total < rad[:, i]
    return ok


def search_one_impact(eq: OneImpactEquations, window: tuple[float, float], *,
                      progress=None) -> OneImpactRoots:
    """Every root of ``(F1, F2)`` with ``T`` in ``window`` and ``h1, h3 > 0`` (module docstring).

    Parameters
    ----------
    eq : OneImpactEquations
    window : (float, float)
        ``T_min < T_max``, both above the two delays' sum.
    progress : callable, optional
        ``progress(level, cells)`` after each level of bisection.

    Returns
    -------
    OneImpactRoots
    """
    T_lo, T_hi = window
    T_lo, T_hi = float(T_lo), float(T_hi)
    tau = eq.tau
    H = T_hi - tau
    W = max(T_hi - T_lo, H)
    r = 0.5 * W / FIRST_CELLS
    r_min = MIN_CELL * W
    T0, h0 = T_lo, 0.0  # the grid's corner: cell (i, j) has its centre at (T0 + (2i+1) r, h0 + (2j+1) r)
    ii, jj = np.meshgrid(np.arange(int(math.ceil((T_hi - T_lo) / (2 * r)))),
                         np.arange(int(math.ceil(H / (2 * r)))), indexing="ij")
    ii, jj = ii.ravel(), jj.ravel()
    roots, boxes, certified, unresolved = [], [], [], []
    cells = 0
    level = 0
    while ii.size:
        Tm, hm = T0 + (2 * ii + 1) * r, h0 + (2 * jj + 1) * r
        inside = (Tm - tau - hm > -2.0 * r) & (Tm - r < T_hi) & (Tm + r > T_lo)
        ii, jj, Tm, hm = ii[inside], jj[inside], Tm[inside], hm[inside]
        cells += ii.size
        F, _, floor = eq.point(Tm, hm)
        rr = np.full(Tm.size, r)
        (g11, g12), (g21, g22) = eq.jacobian_box(Tm, hm, rr, rr)
        keep = (np.abs(F[:, 0]) <= (g11.mag() + g12.mag()) * r * (1 + 1e-9) + floor[:, 0]) & \
               (np.abs(F[:, 1]) <= (g21.mag() + g22.mag()) * r * (1 + 1e-9) + floor[:, 1])
        ii, jj, Tm, hm, F, floor = ii[keep], jj[keep], Tm[keep], hm[keep], F[keep], floor[keep]
        if progress is not None:
            progress(level, ii.size)
        last = r <= r_min
        if ii.size and (ii.size <= 4096 or last):
            n_cl, label = _clusters(ii, jj)
            resolved = np.zeros(n_cl, dtype=bool)
            count = np.bincount(label, minlength=n_cl)
            lo_T = np.full(n_cl, np.inf)
            hi_T = np.full(n_cl, -np.inf)
            lo_h, hi_h = lo_T.copy(), hi_T.copy()
            np.minimum.at(lo_T, label, Tm - r)
            np.maximum.at(hi_T, label, Tm + r)
            np.minimum.at(lo_h, label, hm - r)
            np.maximum.at(hi_h, label, hm + r)
            score = np.max(np.abs(F) / (floor + np.abs(F).max(axis=0) + 1e-300), axis=1)
            best = np.full(n_cl, -1)
            best_score = np.full(n_cl, np.inf)
            for k in np.argsort(score)[::-1]:  # (the last write per cluster is its best cell)
                best[label[k]] = k
                best_score[label[k]] = score[k]
            trial = np.flatnonzero((count <= CLUSTER_CELLS) | last)
            if trial.size:
                x0 = np.column_stack((Tm[best[trial]], hm[best[trial]]))
                x, conv = _newton(eq, x0)
                fin = np.all(np.isfinite(x), axis=1)
                inside = fin & (x[:, X_T] >= lo_T[trial] - 2 * r) & (x[:, X_T] <= hi_T[trial] + 2 * r) & \
                    (x[:, X_H] >= lo_h[trial] - 2 * r) & (x[:, X_H] <= hi_h[trial] + 2 * r)
                rad = np.column_stack((np.maximum(hi_T[trial] - x[:, X_T], x[:, X_T] - lo_T[trial]),
                                       np.maximum(hi_h[trial] - x[:, X_H], x[:, X_H] - lo_h[trial])))
                rad = np.maximum(rad, r) * 1.01
                good = np.zeros(trial.size, dtype=bool)
                if np.any(inside):
                    xs = np.where(inside[:, None], x, x0)
                    good = inside & _krawczyk(eq, xs, rad)
                for t, xk, rk, g, cv, ins in zip(trial, x, rad, good, conv, inside, strict=True):
                    if g:
                        resolved[t] = True
                        roots.append(xk)
                        boxes.append(rk)
                        certified.append(True)
                    elif last:
                        resolved[t] = True
                        reason = "not resolved"
                        detb = eq.det_box(np.array([0.5 * (lo_T[t] + hi_T[t])]),
                                          np.array([0.5 * (hi_T[t] - lo_T[t])]))
                        if eq.w2.size and np.any((detb.lo <= 0.0) & (detb.hi >= 0.0)):
                            reason = "resonance"
                        if cv and ins:
                            roots.append(xk)
                            boxes.append(np.zeros(2))
                            certified.append(False)
                        unresolved.append((float(lo_T[t]), float(hi_T[t]), reason))
            alive = ~resolved[label]
            ii, jj = ii[alive], jj[alive]
        if not ii.size or last:
            break
        if ii.size > MAX_CELLS:
            raise ValueError(f"the search of the valve's orbits needs more than {MAX_CELLS} cells at once "
                             f"(window {window}): narrow the window (with d = 0 every undamped resonance "
                             "of a flexible mode holds orbits near it)")
        r *= 0.5
        level += 1
        ii = np.concatenate((2 * ii, 2 * ii + 1, 2 * ii, 2 * ii + 1))
        jj = np.concatenate((2 * jj, 2 * jj, 2 * jj + 1, 2 * jj + 1))
    out = np.array(roots).reshape(-1, 2)
    T, h = out[:, X_T], out[:, X_H]
    keep = (T >= T_lo) & (T <= T_hi) & (h > 0.0) & (T - tau - h > 0.0)
    boxes_a = np.array(boxes).reshape(-1, 2)[keep]
    out, cert = out[keep], np.array(certified, dtype=bool)[keep]
    order = np.argsort(out[:, X_T], kind="stable")
    out, boxes_a, cert = out[order], boxes_a[order], cert[order]
    # the same root from two clusters (their boxes overlap): kept once, certified if either is
    uniq = []
    for k in range(out.shape[0]):
        for u in uniq:
            if np.all(np.abs(out[k] - out[u]) <= 1e-9 * (1.0 + np.abs(out[u]))):
                cert[u] |= cert[k]
                break
        else:
            uniq.append(k)
    return OneImpactRoots(roots=out[uniq], certified=cert[uniq], boxes=boxes_a[uniq],
                          unresolved=tuple(sorted(unresolved)), window=(T_lo, T_hi), cells=cells)
