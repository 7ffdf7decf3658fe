"""The wave law's contact window on characteristics (theory §4b, §4c): the drive over the window
(:class:`_WindowLoad`), the piston's fields at impact with the static correction (:class:`PistonInvariants`,
shared with the rod-rock law: :mod:`impactbar.dynamics.invariants`) and the solver of the contact
with the long rod, separations included (:class:`_Contact`).
:mod:`impactbar.laws.wave.impact` builds :class:`~impactbar.WaveImpact` from it."""

from __future__ import annotations

import bisect
import copy
import functools
import math
from functools import cached_property

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from ..._shared.columns import IV_HI, IV_LO
from ...dynamics.invariants import PistonInvariants
from ...loads.abilities import jumps
from . import _window as KW
from ._jumps import _bernoulli, _singular_coefficients, locate_jumps

_GL_X, _GL_W = np.polynomial.legendre.leggauss(20)


def _panel_halves(lo: float, hi: float, breaks, h: float):
    """The panels of :func:`_panels` as their midpoints and half widths, shape ``(K,)`` each."""
    br = np.asarray(breaks, dtype=float).ravel()
    pts = np.unique(np.concatenate(([lo, hi], br[(br > lo) & (br < hi)])))
    width = np.diff(pts)
    if not width.size:
        return np.empty(0), np.empty(0)
    m = np.maximum(np.ceil(width / h), 1.0).astype(np.intp)  # panels per piece
    half = 0.5 * width / m
    first = np.cumsum(m) - m  # each piece's first panel
    k = np.arange(first[-1] + m[-1]) - np.repeat(first, m)  # the panel's index in its piece
    half = np.repeat(half, m)
    return np.repeat(pts[:-1], m) + half * (2.0 * k + 1.0), half


def _panels(lo: float, hi: float, breaks, h: float):
    """Gauss-Legendre nodes and weights on ``[lo, hi]``, split at ``breaks`` and into panels of width
    at most ``h`` (20 nodes each: exact to rounding for ``e^{i w x}`` with ``w h <= 8``). All panels
    in one array operation: the same nodes and weights, to the bit, as panel by panel."""
    mids, half = _panel_halves(lo, hi, breaks, h)
    return (mids[:, None] + half[:, None] * _GL_X).ravel(), (half[:, None] * _GL_W).ravel()


class _Moments:
    """The cumulative moments ``M_n(y) = int_lo^y f(y') e^{i n pi y'} dy'`` of a field ``f`` along one
    family of characteristics, smooth between ``breaks``: the panels of :func:`_panels` on ``[lo,
    hi]`` summed once, and at a ``y`` the partial panel up to it by the same 20-node rule (``y`` and
    ``y'`` alike in a panel with no break inside: exact to rounding, as :func:`_panels`)."""

    def __init__(self, f, lo: float, hi: float, breaks, h: float, npi):
        mids, half = _panel_halves(lo, hi, breaks, h)
        self.f, self.npi, self.lo = f, npi, lo
        self.left = mids - half
        x = (mids[:, None] + half[:, None] * _GL_X).ravel()
        fw = f(x) * (half[:, None] * _GL_W).ravel()
        per = (np.exp(1j * np.multiply.outer(x, npi)) * fw[:, None]).reshape(mids.size, 20, npi.size)
        self.cum = np.concatenate((np.zeros((1, npi.size)), np.cumsum(per.sum(axis=1), axis=0)))

    def __call__(self, y) -> np.ndarray:
        """``M_n(y)`` for ``lo <= y <= hi``, shape ``(y.size, N + 1)``, complex."""
        y = np.atleast_1d(np.asarray(y, dtype=float))
        k = np.clip(np.searchsorted(self.left, y, side="right") - 1, 0, max(self.left.size - 1, 0))
        a = self.left[k] if self.left.size else np.full(y.shape, self.lo)
        half = 0.5 * (y - a)
        x = ((a + half)[:, None] + half[:, None] * _GL_X).ravel()
        fw = (self.f(x) * (half[:, None] * _GL_W).ravel()).reshape(y.size, 20)
        part = np.einsum("ij,ijn->in", fw, np.exp(1j * np.multiply.outer(x, self.npi)).reshape(
            y.size, 20, self.npi.size))
        return self.cum[k] + part


def _window_rate(load, s: float) -> float:
    """``k_max / s``: how fast the drive turns in window time ``theta = s t`` (0 without harmonics);
    it sizes the panels of the window's moments and does not depend on the window's start."""
    orders = load.abilities.orders
    return float(np.max(orders)) / s if orders is not None and len(orders) else 0.0


class _WindowLoad:
    """The drive load over the window as a function of ``theta = s (t - t0)``, ``0 <= theta <= 2``,
    with its jumps located once (so that a value at a jump is never decided by rounding)."""

    def __init__(self, load, s: float, t0: float):
        self.load, self.s, self.t0 = load, s, t0
        t1 = t0 + 2.0 / s
        tj = np.asarray(jumps(load, t0, t1), dtype=float)  # (a load's jumps, a drive history's steps)
        self.t_edges = np.concatenate(([t0], tj, [t1]))
        self.jumps = s * (tj - t0)  # in theta, inside (0, 2)
        self.rate = _window_rate(load, s)

    def __call__(self, theta, left: bool = False) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        t = self.t0 + theta / self.s
        if self.jumps.size:
            j = np.searchsorted(self.jumps, theta, side="left" if left else "right")
            lo, hi = self.t_edges[j], self.t_edges[j + 1]
            pad = 1e-9 * (hi - lo)
            t = np.clip(t, lo + pad, hi - pad)
        return np.asarray(self.load(t), dtype=float)

    def value(self, theta: float, left: bool = False) -> float:
        """``P(theta)`` for one ``theta`` (as ``__call__``, without array overhead: the root
        searches of the contact call it once per iteration)."""
        if self._pieces is not None:  # constant between the jumps located at set-up
            j = bisect.bisect_left(self.jumps, theta) if left else bisect.bisect_right(self.jumps, theta)
            return float(self._pieces[0][j])
        return float(self(theta, left=left))

    @cached_property
    def _pieces(self):
        """``(levels, cum, edges)`` of a piecewise-constant load over the window (None otherwise)."""
        own = self.load.abilities
        if own.pieces is None or own.orders is not None:
            return None
        edges = self.t_edges - self.t0
        levels = self(self.s * 0.5 * (edges[:-1] + edges[1:]))
        cum = np.concatenate(([0.0], np.cumsum(levels * np.diff(edges))))
        return levels, cum, edges

    def integral1(self, theta: float) -> float:
        """``int_0^theta p dtheta'`` for one ``theta`` (as :meth:`integral`)."""
        pieces = self._pieces
        if pieces is None:
            return float(self.integral(theta)[0])
        levels, cum, edges = pieces
        tau = theta / self.s
        j = min(max(bisect.bisect_right(edges, tau) - 1, 0), levels.size - 1)
        return self.s * float(cum[j] + levels[j] * (tau - edges[j]))

    def integral(self, theta) -> np.ndarray:
        """``int_0^theta p dtheta'``, exact: in closed form for a load of finitely many harmonics,
        piece by piece for a piecewise-constant one, else the load's own rigid-mode integral."""
        theta = np.atleast_1d(np.asarray(theta, dtype=float))
        tau = theta / self.s
        own = self.load.abilities
        orders = own.orders
        if orders is not None:  # p0 tau + Re sum p_k (e^{ik(t0 + tau)} - e^{ik t0}) / (ik)
            k = np.asarray(orders, dtype=float)
            ck = own.amplitudes * np.exp(1j * k * self.t0) / (1j * k)
            osc = (np.expm1(1j * np.multiply.outer(tau, k)) @ ck).real
            return self.s * (self.load.p0 * tau + osc)
        if self._pieces is not None:  # constant between the jumps located at set-up
            levels, cum, edges = self._pieces
            j = np.clip(np.searchsorted(edges, tau, side="right") - 1, 0, levels.size - 1)
            return self.s * (cum[j] + levels[j] * (tau - edges[j]))
        _, v = self.load.propagate(np.zeros(1), 0.0, self.t0, np.zeros(1), np.zeros(1), self.t0 + tau)
        return self.s * v[0]


class _LocatedPiston(PistonInvariants):
    """The fields at impact with their jumps carried exactly (theory §4c): the Bernoulli functions of
    :func:`locate_jumps` plus the modal series of the continuous remainder (the modes kept less the
    Bernoulli functions' first ``N`` modes), plus the static correction. On the modes kept it is
    the modal state, as :class:`PistonInvariants`."""

    def __init__(self, piston: PistonInvariants, y, jumps):
        self.__dict__.update(piston.__dict__)
        self.jy = np.asarray(y, dtype=float)
        self.jJ, self.jK, self.jL = (np.asarray(u, dtype=float) for u in jumps)
        c = _singular_coefficients(self.npi.size - 1, self.jy, jumps)
        self.a = piston.a.copy()
        self.b = piston.b.copy()
        self.a[1:] -= 2.0 * c.real
        self.b[1:] -= 2.0 * c.imag

    def _t(self, yv):
        return ((np.asarray(yv, dtype=float)[..., None] - self.jy) * 0.5) % 1.0

    def _w(self, yv):
        t = self._t(yv)
        return -(_bernoulli(t, 1) @ self.jJ) - (_bernoulli(t, 2) @ self.jK) - (
            2.0 / 3.0) * (_bernoulli(t, 3) @ self.jL)

    def _wint(self, yv):
        """An antiderivative of the Bernoulli part in ``y`` (periodic and continuous)."""
        t = self._t(yv)
        return -(_bernoulli(t, 2) @ self.jJ) - (2.0 / 3.0) * (_bernoulli(t, 3) @ self.jK) - (
            1.0 / 3.0) * (_bernoulli(t, 4) @ self.jL)

    def alpha(self, x):
        return super().alpha(x) + self._w(x)

    def beta(self, x):
        return super().beta(x) + self._w(-np.asarray(x, dtype=float))

    def alpha1(self, x: float) -> float:
        return super().alpha1(x) + float(self._w(x))

    def beta1(self, x: float) -> float:
        return super().beta1(x) + float(self._w(-x))

    def int1(self, x: float, sign: float) -> float:
        return float(self._int(np.asarray(x, dtype=float), sign))

    def _int(self, x, sign):
        x = np.asarray(x, dtype=float)
        w0 = self._wint(0.0)
        extra = self._wint(x) - w0 if sign > 0 else w0 - self._wint(-x)
        return super()._int(x, sign) + extra

    @property
    def jump_breaks(self) -> np.ndarray:
        """``theta`` in ``(0, 2)`` at which the located jumps reach the rod end (``1 - y``)."""
        th = 1.0 - self.jy[np.abs(self.jJ) > 0.0]
        return np.sort(th[(th > 0.0) & (th < 2.0)])


#: :func:`held_throughout` tabulates the scan up to this many flexible modes: its table, the cosine
#: and sine of every mode at every node of the scan grid (about ``100 (N + 1)^2`` bytes), is built
#: in about 0.07 ms at 48 modes, less than two windows' solver scans cost; at 64 modes and more it
#: would cost as much as the scans it spares (0.3 ms at 64 modes, its pages faulted in afresh).
HELD_TEST_MAX_MODES = 48

#: :func:`held_throughout` calls a window held where ``A`` exceeds this fraction of the window's
#: scale at every node: far above the rounding by which its sums may differ from the solver's
#: (a few ``N + 1`` units of rounding of the scale) and above the solver's tolerance ``1e-13``.
HELD_MARGIN = 1e-10


@functools.lru_cache(maxsize=4)
def _held_scan_table(M: int, hg: float):
    """The scan of :meth:`_Contact.solve` for ``M`` modes and grid step ``hg`` where the drive has no
    jump in the window: the solver's grid (both limits at ``theta = 1``) as a table ``T``, shape
    ``(2 M - 1, nodes)``, with ``A = (a, b_1..b_N) T + b_0 w`` (plus the drive's ``2 P(u)/s`` on the
    last ``u.size`` nodes), and ``w``, ``u``. Cached per ``(M, hg)``, read-only."""
    grid = np.unique(np.concatenate([np.linspace(a, b, max(2, math.ceil((b - a) / hg) + 1))
                                     for a, b in ((0.0, 1.0), (1.0, 2.0))]))
    x = 1.0 - grid[grid <= 1.0]  # alpha0(1 - theta), the left limit at theta = 1 included
    u = grid[grid >= 1.0] - 1.0  # beta0(theta - 1) and the drive
    # e^{i n pi y} as powers of e^{i pi y}, one mode at a time over all nodes (products in place
    # of M sines and cosines per node: within about 2 M units of rounding, far inside the margin)
    z = np.exp(1j * math.pi * np.concatenate((x, u)))
    e = np.empty((M, z.size), dtype=complex)
    e[0] = 1.0
    for n in range(1, M):
        np.multiply(e[n - 1], z, out=e[n])
    sin = e.imag[1:]
    sin[:, :x.size] *= -1.0  # alpha0 = sum a_n cos - sum b_n sin - b_0 (1 - x)
    table = np.concatenate((e.real, sin))
    w = np.concatenate((-(1.0 - x), 1.0 - u))
    for arr in (table, w, u):
        arr.flags.writeable = False
    return table, w, u


def held_throughout(s: float, q, v, load, t0: float) -> bool:
    """Whether the window from the state ``(q, v)`` at load time ``t0`` holds contact throughout, by
    the solver's own scan (:meth:`_Contact.solve`: the arriving invariant ``A`` on its grid, both
    limits at ``theta = 1``) with the sums tabulated (:func:`_held_scan_table`) and a margin: True
    only where ``A > HELD_MARGIN * scale`` at every node, so that the solver, whose test is ``A >=
    -1e-13 scale`` on the same nodes, finds one contact interval ``[0, 2]`` and no gap whatever the
    sums' rounding. False means "not decided here" (a drive that jumps inside the window, more than
    :data:`HELD_TEST_MAX_MODES` modes, a separation or a window near one): the solver decides."""
    N = q.size - 1
    if N > HELD_TEST_MAX_MODES:
        return False
    wl = _WindowLoad(load, s, t0)
    if wl.jumps.size:
        return False
    piston = PistonInvariants(s, q, v, wl.value(0.0))
    scale = _window_scale(piston, load, s)
    table, w, u = _held_scan_table(N + 1, KW.scan_step(N, float(wl.rate)))
    A = np.concatenate((piston.a, piston.b[1:])) @ table + piston.b[0] * w
    A[w.size - u.size:] += 2.0 * wl(u) / s
    return bool(np.all(A > HELD_MARGIN * scale))  # (False where A is not finite)


def held_post_state(s: float, R: float, q, v, drive):
    """The post-window state of a window held in contact throughout (no gap, no free interval):
    ``-R (q, v) + (g, h)`` with ``q_0`` from contact; :meth:`_Contact.post_state` takes it there."""
    g, h = drive
    qa = -R * q + g
    va = -R * v + h
    cw = 2.0 * (-1.0) ** np.arange(qa.size)
    qa[0] = -0.0 / s - float(cw[1:] @ qa[1:])
    return qa, va


def _window_scale(piston, load, s: float) -> float:
    """The scale of a window's invariants, the solver's tolerances and :func:`held_throughout`'s
    margin are relative to: the piston's wave amplitudes and the drive's largest ``2 |p| / s``."""
    return float(np.sum(np.abs(piston.a)) + np.sum(np.abs(piston.b)) + 2.0 * load.sup_abs / s)


class _Contact:
    """The characteristics solution over the window, in ``theta = s t`` (``0..2``)."""

    def __init__(self, s, R, q, v, load, t0, fast=True):
        self.s, self.R = s, R
        self.fast = fast  # scalar root-search evaluations (False: through the array forms)
        self.N = q.size - 1
        self.p = _WindowLoad(load, s, t0)
        self.piston = PistonInvariants(s, q, v, self.p.value(0.0))  # the drive's force at x = 0
        # A(theta): alpha arriving at the rod; smooth between these breaks
        self.breaks = np.unique(np.concatenate(([1.0], 1.0 + self.p.jumps[self.p.jumps < 1.0])))
        self.h_quad = 8.0 / (2.0 * math.pi * (self.N + 1) + 2.0 * self.p.rate + 1.0)
        self.scale = _window_scale(self.piston, load, s)
        self._acum1 = float(self.piston.int_alpha(1.0))

    # -- the incoming invariant at the rod and its integral ------------------------------------
    def A(self, th, left=False):
        th0 = np.asarray(th, dtype=float)
        th = np.atleast_1d(th0)
        first = th < 1.0 if not left else th <= 1.0
        out = np.empty(th.shape)
        out[first] = self.piston.alpha(1.0 - th[first])
        u = th[~first] - 1.0
        out[~first] = self.piston.beta(u) + 2.0 * self.p(u, left=left) / self.s
        return out.reshape(th0.shape)

    def Acum(self, th):
        th = np.atleast_1d(np.asarray(th, dtype=float))
        out = np.empty(th.shape)
        first = th <= 1.0
        out[first] = self._acum1 - self.piston.int_alpha(1.0 - th[first])
        u = th[~first] - 1.0
        if u.size:
            out[~first] = self._acum1 + self.piston.int_beta(u) + 2.0 * self.p.integral(u) / self.s
        return out

    def A1(self, th: float, left: bool = False) -> float:
        """:meth:`A` at one ``theta`` (the root searches' scalar form; the same sums)."""
        if not self.fast:
            return float(self.A(np.array([th]), left=left)[0])
        if th < 1.0 or (left and th == 1.0):
            return self.piston.alpha1(1.0 - th)
        u = th - 1.0
        return self.piston.beta1(u) + 2.0 * self.p.value(u, left=left) / self.s

    def Acum1(self, th: float) -> float:
        """:meth:`Acum` at one ``theta``."""
        if not self.fast:
            return float(self.Acum(th)[0])
        if th <= 1.0:
            return self._acum1 - self.piston.int1(1.0 - th, 1.0)
        u = th - 1.0
        return self._acum1 + self.piston.int1(u, -1.0) + 2.0 * self.p.integral1(u) / self.s

    def _A_uniform(self, grid, m: int):
        """:meth:`A` on the scan grid of a window whose drive has no jump: ``theta = j/m`` on
        ``[0, 1]`` and ``1 + j/m`` on ``[1, 2]``, where the modal sums at ``x = k/m`` are one
        type-I discrete cosine and sine transform each (``O(m log m)``, the dense sums' values to
        rounding). ``None`` where the grid is not that one (or ``m <= N``: the sums would alias)."""
        if grid.size != 2 * m + 1 or m <= self.N:
            return None
        from scipy.fft import dct, dst

        pst = self.piston
        z = np.zeros(m + 1)
        z[:self.N + 1] = pst.a
        cos_sum = 0.5 * (dct(z, type=1) + z[0])  # sum_n a_n cos(n pi k/m), k = 0..m
        sin_sum = np.zeros(m + 1)  # sum_{n>=1} b_n sin(n pi k/m); 0 at both ends
        if m > 1:
            y = np.zeros(m - 1)
            y[:self.N] = pst.b[1:]
            sin_sum[1:m] = 0.5 * dst(y, type=1)
        out = np.empty(2 * m + 1)
        x = 1.0 - grid[:m]  # alpha0(1 - theta) at theta = j/m: x = k/m, k = m - j
        k = np.arange(m, 0, -1)
        out[:m] = cos_sum[k] - (sin_sum[k] + pst.b[0] * (1.0 - x))
        u = grid[m:] - 1.0  # beta0(theta - 1) plus the drive
        out[m:] = cos_sum + sin_sum + pst.b[0] * (1.0 - u) + 2.0 * self.p(u) / self.s
        return out

    # -- contact and separation --------------------------------------------------------------------
    def solve(self):
        tol = 1e-13 * self.scale
        if self.A(0.0) < -tol:  # a touch at zero speed (to rounding) is a contact all the same
            raise ValueError("the piston must arrive moving towards the rod (impact velocity >= 0)")
        # A is a trigonometric sum of highest frequency N pi (plus the load's): 6 nodes per period
        hg = KW.scan_step(self.N, float(self.p.rate))
        edges = np.concatenate(([0.0], self.breaks, [2.0]))
        grid = np.unique(np.concatenate([np.linspace(a, b, max(2, math.ceil((b - a) / hg) + 1))
                                         for a, b in zip(edges[:-1], edges[1:], strict=True)]))
        Ag = self._A_uniform(grid, math.ceil(1.0 / hg)) if self.breaks.size == 1 else None
        if Ag is None:
            Ag = self.A(grid)
        Agl = Ag.copy()  # left limits: they differ at the breaks only
        at = np.searchsorted(grid, self.breaks)
        Agl[at] = self.A(grid[at], left=True)
        contact = []
        th, on = 0.0, True
        start = 0.0
        for _ in range(10_000):
            if th >= 2.0:
                break
            k0 = np.searchsorted(grid, th, side="right")
            if on:
                # first grid node after th where A < 0 (left limit first: a jump down is a separation)
                neg_l = Agl[k0:] < -tol
                neg_r = Ag[k0:] < -tol
                hit = np.flatnonzero(neg_l | neg_r)
                if hit.size == 0:
                    contact.append((start, 2.0))
                    th = 2.0
                    break
                k = k0 + hit[0]
                if not neg_l[hit[0]]:  # A jumps below zero at a break
                    th_sep = grid[k]
                else:
                    a = max(th, grid[k - 1])
                    th_sep = brentq(lambda x: self.A1(x, left=True), a, grid[k],
                                    xtol=1e-15, rtol=1e-15) if self.A1(a) > 0 else a
                contact.append((start, th_sep))
                th, on = th_sep, False
            else:
                base = self.Acum1(th)

                def G(x, base=base):
                    return base - self.Acum1(x)

                nodes = grid[k0:]
                Gn = base - self.Acum(nodes)
                hit = np.flatnonzero(Gn <= 0.0)
                if hit.size == 0:
                    th = 2.0
                    break
                k = hit[0]
                a = th if k == 0 else nodes[k - 1]
                if k == 0:  # find a point where the gap is open, or call it grazing
                    x = 0.5 * (th + nodes[0])
                    for _ in range(40):
                        if G(x) > 0.0:
                            break
                        x = 0.5 * (th + x)
                    else:
                        x = None
                    if x is None:  # no gap opened: contact goes on
                        start_prev, _ = contact.pop() if contact else (0.0, None)
                        start, on = start_prev, True
                        th = float(nodes[0])
                        continue
                    a = x
                ga, gb = G(a), G(nodes[k])
                if ga <= 0.0:  # the vectorised and the scalar gap differ by rounding here
                    th_re = float(a)
                elif gb > 0.0:
                    th_re = float(nodes[k])
                else:
                    th_re = brentq(G, a, nodes[k], xtol=1e-15, rtol=1e-15)
                th, on, start = th_re, True, th_re
        self.contact = np.array(contact, dtype=float).reshape(-1, 2)
        self.grid, self.Ag = grid, Ag
        last_end = self.contact[-1, IV_HI] if len(self.contact) else 0.0
        self.gap_theta = 0.0 if last_end >= 2.0 else float(self.Acum(last_end)[0] - self.Acum(2.0)[0])
        return self

    def in_contact(self, th):
        th = np.asarray(th, dtype=float)
        m = np.zeros(th.shape, dtype=bool)
        for a, b in self.contact:
            m |= (th >= a) & (th <= b)
        return m

    def B(self, th, left=False):
        """The invariant sent back into the piston at the rod end."""
        A = self.A(th, left=left)
        return np.where(self.in_contact(th), -self.R * A, A)

    def force(self, th):
        th = np.asarray(th, dtype=float)
        inside = (th >= 0.0) & (th <= 2.0)
        thc = np.clip(th, 0.0, 2.0)
        F = 0.5 * self.s * (1.0 + self.R) * self.A(thc)
        return np.where(inside & self.in_contact(thc), F, 0.0)

    def switches(self):
        c = self.contact.ravel()
        return c[(c > 0.0) & (c < 2.0)]

    # -- results -------------------------------------------------------------------------------
    def post_state(self, q, v, drive):
        s, R = self.s, self.R
        free = []
        c = self.contact
        gaps = np.concatenate(([0.0], c.ravel(), [2.0])).reshape(-1, 2)  # the gaps between contact intervals
        for a, b in zip(gaps[:, IV_LO], gaps[:, IV_HI], strict=True):
            if b > a:
                free.append((a, b))
        if not free:  # held throughout: no gap
            return held_post_state(s, R, q, v, drive)
        g, h = drive
        qa = -R * q + g
        va = -R * v + h
        npi = self.piston.npi
        xs, dal, dbe, ws = [], [], [], []
        for a, b in free:
            for lo, hi in ((a, min(b, 1.0)), (max(a, 1.0), b)):
                if hi <= lo:
                    continue
                if hi <= 1.0:  # alpha that left the rod end free: x = 1 - theta
                    x, w = _panels(1.0 - hi, 1.0 - lo, [], self.h_quad)
                    xs.append(x)
                    ws.append(w)
                    dal.append((1.0 + R) * self.piston.alpha(x))
                    dbe.append(np.zeros_like(x))
                else:  # beta: x = theta - 1
                    x, w = _panels(lo - 1.0, hi - 1.0, self.p.jumps, self.h_quad)
                    xs.append(x)
                    ws.append(w)
                    dal.append(np.zeros_like(x))
                    dbe.append((1.0 + R) * (self.piston.beta(x) + 2.0 * self.p(x) / s))
        x = np.concatenate(xs)
        w = np.concatenate(ws)
        dal = np.concatenate(dal)
        dbe = np.concatenate(dbe)
        arg = np.multiply.outer(npi, x)
        va = va + np.cos(arg) @ (0.5 * (dal + dbe) * w)
        dse = np.sin(arg[1:]) @ (0.5 * (dbe - dal) * w)
        qa[1:] -= dse / (s * npi[1:])
        cw = 2.0 * (-1.0) ** np.arange(qa.size)
        qa[0] = -self.gap_theta / s - float(cw[1:] @ qa[1:])
        return qa, va

    def contact_quad(self, th_end=2.0):
        xs, ws = [], []
        for a, b in self.contact:
            b = min(b, th_end)
            if b > a:
                x, w = _panels(a, b, self.breaks, self.h_quad)
                xs.append(x)
                ws.append(w)
        if not xs:
            return np.empty(0), np.empty(0)
        return np.concatenate(xs), np.concatenate(ws)

    def rod_energy(self, th_end=2.0):
        """``int F^2 / Z_s dt`` up to ``th_end``: ``(1 - R^2)/4 int_contact A^2 dtheta``."""
        x, w = self.contact_quad(th_end)
        return 0.25 * (1.0 - self.R**2) * float(w @ self.A(x) ** 2)

    def impulse(self, th_end=2.0):
        c = np.minimum(self.contact, th_end)
        if not len(c):
            return 0.0
        return 0.5 * (1.0 + self.R) * float(np.sum(self.Acum(c[:, IV_HI]) - self.Acum(c[:, IV_LO])))

    def drive_work(self, th_end=2.0):
        """``int p u_t(0) dt`` up to ``th_end``, ``u_t(0) = beta(0) + p/s``."""
        sw = self.switches()
        br = np.concatenate(([1.0], self.p.jumps, 1.0 + sw[sw < 1.0]))
        x, w = _panels(0.0, th_end, br, self.h_quad)
        p = self.p(x)
        return float(w @ (p * (self._beta_line(x) + p / self.s))) / self.s

    def _line_breaks(self):
        """Where the fields may jump along each family of characteristics: ``eta = x + theta`` for
        ``beta`` and ``xi = x - theta`` for ``alpha`` (the corners' images, the switches and the
        load's jumps)."""
        j, sw = self.p.jumps, self.switches()
        eta = np.concatenate(([1.0, 2.0], 2.0 + j, 1.0 + sw))  # beta line breaks
        xi = np.concatenate(([0.0], -eta, -j))  # alpha line breaks
        return eta, xi

    def _x_breaks(self, th):
        """Positions where the fields at ``th`` may jump: :meth:`_line_breaks` at ``th``."""
        eta, xi = self._line_breaks()
        return np.concatenate((eta - th, xi + th))

    def field_energy(self, th=2.0):
        """Energy of the exact fields at ``th``: ``(1/4) int (alpha^2 + beta^2) dx``."""
        x, w = _panels(0.0, 1.0, self._x_breaks(th), self.h_quad)
        al, be = self.invariants_at(x, th)
        return 0.25 * float(w @ (al * al + be * be))

    def force_extremes(self):
        if not len(self.contact):
            return 0.0, 0.0
        inside = self.in_contact(self.grid)
        F = self.force(self.grid)
        k = int(np.argmax(np.where(inside, F, -np.inf)))
        fmax = self._refine(k, -1.0)
        # the one-sided limits at the located jumps (a jump's value is one of them)
        side = self._jumps[:, None] + np.array([-1.0, 1.0]) * 1e-13
        side = side[self.in_contact(side)]
        Fs = self.force(side)
        if Fs.size:
            fmax = max(fmax, float(Fs.max()))
        full = len(self.contact) == 1 and self.contact[0, IV_LO] == 0.0 and self.contact[0, IV_HI] >= 2.0
        if not full:
            return fmax, 0.0
        k = int(np.argmin(F))
        fmin = self._refine(k, 1.0)
        return fmax, min(fmin, float(Fs.min())) if Fs.size else fmin

    _jumps = np.empty(0)  # the located jumps' arrival at the rod end (theta), in the grid

    def located(self) -> _Contact:
        """The same window (contact intervals kept) whose piston fields at impact carry their jumps
        and kinks exactly (:func:`locate_jumps`, :class:`_LocatedPiston`, theory §4c): the force
        history without Gibbs overshoot at the jumps left by earlier releases and separations.
        Itself when no jump is found, or when the located peak force differs from the series'
        by more than the series can overshoot, ``0.1 s (1 + R)/2`` times the jumps' sum, plus
        1e-3 of the peak (a jump placed wrong: the series is then the better guess)."""
        y, jumps = locate_jumps(self.piston.a, self.piston.b, self.scale)
        if not np.any(jumps[0]):
            return self
        out = self._copy()
        out.piston = _LocatedPiston(self.piston, y, jumps)
        out._jumps = out.piston.jump_breaks
        out.breaks = np.unique(np.concatenate((self.breaks, out._jumps)))
        out.grid = np.unique(np.concatenate((self.grid, out._jumps)))
        plain, _ = self.force_extremes()
        gibbs = 0.05 * self.s * (1.0 + self.R) * float(np.sum(np.abs(jumps[0]))) + 1e-3 * abs(plain)
        located, _ = out.force_extremes()
        if abs(located - plain) > gibbs:
            return self
        return out

    def _copy(self) -> _Contact:
        """A shallow copy without the tables of :meth:`state_at` (the copy's fields differ)."""
        out = copy.copy(self)
        out.__dict__.pop("_line_moments", None)
        out.__dict__.pop("_state_asked", None)
        return out

    def smoothed(self) -> _Contact:
        """The same window (contact intervals kept) whose piston fields are smoothed by the Jackson
        kernel (a positive kernel: no Gibbs overshoot, ``O(1/N^2)`` on smooth fields; Weisse et al.,
        Rev. Mod. Phys. 78 (2006) 275, eq. 71); the static correction is kept as it is."""
        M = self.N + 1
        n = np.arange(M)
        g = ((M - n) * np.cos(math.pi * n / M) + np.sin(math.pi * n / M) / math.tan(math.pi / M)) / M
        out = self._copy()
        out.piston = copy.copy(self.piston)
        out.piston.a = self.piston.a * g
        out.piston.b = np.concatenate((self.piston.b[:1], self.piston.b[1:] * g[1:]))
        return out

    def _refine(self, k, sign):
        g = self.grid
        best = float(self.force(g[k]))
        lo, hi = g[max(k - 1, 0)], g[min(k + 1, g.size - 1)]
        for a, b in ((lo, g[k]), (g[k], hi)):
            if b <= a:
                continue
            # a break inside (a, b) is a node of the grid, so the piece is smooth
            res = minimize_scalar(lambda x: sign * float(self.force(x)), bounds=(a, b), method="bounded",
                                  options={"xatol": 1e-13})
            val = float(self.force(res.x))
            best = max(best, val) if sign < 0 else min(best, val)
        return best

    def invariants_at(self, x, th):
        """``alpha(x, th), beta(x, th)`` for ``0 <= th <= 2`` (d'Alembert: each is carried along its
        characteristic from the start state, the drive end or the rod end)."""
        x = np.asarray(x, dtype=float)
        return self._alpha_line(x - th), self._beta_line(x + th)

    def _beta_line(self, eta):
        """``beta`` on the characteristic ``x + theta = eta`` (``0 <= eta <= 3``): from the start
        state, or sent back by the rod end at ``theta = eta - 1``."""
        eta = np.asarray(eta, dtype=float)
        return np.where(eta <= 1.0, self.piston.beta(np.minimum(eta, 1.0)),
                        self.B(np.clip(eta - 1.0, 0.0, 2.0)))

    def _alpha_line(self, xi):
        """``alpha`` on the characteristic ``x - theta = xi`` (``-2 <= xi <= 1``): from the start
        state, or reflected at the drive end at ``theta = -xi`` with the drive's ``2 p / s``."""
        xi = np.asarray(xi, dtype=float)
        tau = np.clip(-xi, 0.0, 2.0)
        return np.where(xi >= 0.0, self.piston.alpha(np.maximum(xi, 0.0)),
                        self._beta_line(tau) + 2.0 * self.p(tau) / self.s)

    def gap_at(self, th):
        """Gap between the piston end and the rod end at ``th`` (in ``theta`` units: divide by s)."""
        c = self.contact
        if len(c) == 0 or th <= c[0, IV_HI]:
            return 0.0
        k = np.searchsorted(c[:, IV_LO], th, side="right") - 1
        if th <= c[k, IV_HI]:
            return 0.0
        return float(self.Acum(c[k, IV_HI])[0] - self.Acum(th)[0])

    def state_at(self, th):
        """Modal state (projected) at ``th``, positions from the rod end's current position.

        The first call of a window projects the fields at ``th`` on the panels split where they may
        jump (:meth:`_state_by_panels`); the window asks again (a history sampled through the blow),
        so later calls take the projections from the fields' cumulative moments along each family of
        characteristics, tabulated once (:meth:`_line_moments`): the same integrals, equal to the
        panels' to rounding (about 1e-15 of the fields' scale), in O(N) per call."""
        if not self.__dict__.get("_state_asked", False):
            self._state_asked = True
            return self._state_by_panels(th)
        ma, mb = self._line_moments
        npi = self.piston.npi
        turn = np.exp(1j * npi * th)  # x = xi + th = eta - th
        Ia = turn * np.subtract(*ma([1.0 - th, -th]))  # int_0^1 e^{i n pi x} alpha(x, th) dx
        Ib = np.conj(turn) * np.subtract(*mb([1.0 + th, th]))  # the same of beta
        return self._state_from(th, 0.5 * (Ia.real + Ib.real), 0.5 * (Ib.imag - Ia.imag)[1:])

    @cached_property
    def _line_moments(self):
        """The cumulative moments (:class:`_Moments`) of ``alpha`` on ``xi`` in ``[-2, 1]`` and of
        ``beta`` on ``eta`` in ``[0, 3]``: every ``theta`` of the window reads its fields there."""
        eta, xi = self._line_breaks()
        npi = self.piston.npi
        return (_Moments(self._alpha_line, -2.0, 1.0, xi, self.h_quad, npi),
                _Moments(self._beta_line, 0.0, 3.0, eta, self.h_quad, npi))

    def _state_by_panels(self, th):
        """:meth:`state_at` by the quadrature of the fields at ``th`` (panels split at
        :meth:`_x_breaks`)."""
        x, w = _panels(0.0, 1.0, self._x_breaks(th), self.h_quad)
        al, be = self.invariants_at(x, th)
        arg = np.multiply.outer(self.piston.npi, x)
        return self._state_from(th, np.cos(arg) @ (0.5 * (al + be) * w),
                                np.sin(arg[1:]) @ (0.5 * (be - al) * w))

    def _state_from(self, th, cos_sum, sin_sum):
        """``(q, v)`` at ``th`` from ``int cos(n pi x) u_t dx`` for ``n = 0..N`` and ``int sin(n pi x)
        s u_x dx`` for ``n = 1..N`` (``q_0`` from the gap)."""
        s, npi = self.s, self.piston.npi
        v = np.asarray(cos_sum, dtype=float)
        q = np.zeros_like(v)
        q[1:] = -sin_sum / (s * npi[1:])
        cw = 2.0 * (-1.0) ** np.arange(q.size)
        q[0] = -self.gap_at(th) / s - float(cw[1:] @ q[1:])
        return q, v

    def stress_extremes(self, J):
        """Max and min of ``N = s (alpha - beta)/2`` at the nodes of a ``J``-cell lattice."""
        k = np.arange(-2 * J, J + 1)  # xi = x - theta in cells
        al = self._alpha_line(k / J)
        be = self._beta_line(np.arange(0, 3 * J + 1) / J)  # eta = x + theta in cells
        hi, lo = -np.inf, np.inf
        i = np.arange(J + 1)
        for m in range(2 * J + 1):
            N = 0.5 * self.s * (al[i - m + 2 * J] - be[i + m])
            hi = max(hi, float(N.max()))
            lo = min(lo, float(N.min()))
        return hi, lo


