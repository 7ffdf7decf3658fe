"""An independent solution of the rod-rock blow, to check the package's exact solver.

It shares no code with :mod:`impactbar.laws.rodrock.exact` and its kernels, and is built otherwise:

- every segment of piston and rod is a delay line (method of characteristics: the wave leaving one
  end arrives at the other its travel time later, unchanged); each wave's history is stored as
  *piecewise Chebyshev interpolants* in time, fitted adaptively (16, 32, 64 first-kind points, a
  piece halved until its last coefficients fall below ``1e-14`` of its values), breaking only where
  a wave is not smooth (the impact, the arrival of a break, a switch);
- the waves are the *total* ones: with a feed force ``f`` the rod starts statically compressed,
  ``F = G = f/2`` in every rod segment, and the feed acts where it does, on the shank (the exact
  solver instead carries the waves above that static state and puts ``f`` into the bit's equation);
- the junctions are algebraic (welded: ``N = 2 (Z_b f_a + Z_a g_b)/(Z_a + Z_b)``; the piston's far
  end free; the piston-shank interface welded while the contact force
  ``N = (2 Z_b f_a + 2 Z_a g_b - Z_a f)/(Z_a + Z_b)`` is ``>= 0`` (the shank's own force then
  ``N + f``), free otherwise (the shank's force ``f``), its gap the integral of the relative
  velocity, contact again where the gap closes);
- at the bit, ``m p'' + Z p' + R(p) = 2 F`` (``F`` the total arriving wave, so ``2 F_dyn + f``) on
  each branch of Lundberg's law (loading ``R = k p``, unloading/reloading ``R = k_u (p - p_perm)``,
  lifted ``R = 0``) is solved by Duhamel's integral of its impulse response (written out below,
  ``expm1`` and ``sin`` forms free of cancellation) against the arriving wave, evaluated by
  Gauss-Legendre quadrature on panels graded geometrically towards both ends (exact for the fast
  exponents of a stiff rock or a light bit); the bit starts at rest on fresh rock loaded to the
  feed, ``p = f/k`` (``p`` from the rock's surface before the feed), on the loading branch;
- every switch (separation, re-contact, unloading, reloading, lift-off, landing) is the first sign
  change of an interpolant, from the real roots of its colleague matrix (numpy ``chebroots``) and a
  sampled sign check, refined by ``brentq``.

Units are the exact solver's: travel times, impedances, the rock's stiffnesses, the bit's mass and the
feed as :func:`impactbar.laws.rodrock.exact.exact_blow` takes them, a rigid unstressed piston at ``V``.
:func:`reference_blow` returns a :class:`Reference` with the blow's quantities the tests compare, measured as
the exact solver measures them (its conventions with a feed: ``advance`` from ``p = f/k``, the
loading episodes from there, a rod junction's force above the feed's static ``f``, the bit's force
total).

The energy account, in the total waves: ``E_0 + f x_s + E_s = W + R^2/(2 k_u) + E_p + E_r + m v^2/2``,
``x_s`` the shank's displacement (the integral of its velocity), ``E_s = f^2 C_rod/2 + f^2/(2 k_u)``
the energy stored under the feed at impact (``C_rod = sum T_i/Z_i``), ``W`` the work the rock
dissipated, ``E_p`` and ``E_r`` the wave energies ``int (F^2 + G^2) dt / Z`` of piston and rod (the
rod's static strain included).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import chebyshev as C
from scipy.optimize import brentq

LOAD, ELASTIC, FREE = 0, 1, 2
_NS = (16, 32, 64)
_NODES = {n: np.cos(np.pi * (np.arange(n) + 0.5) / n) for n in _NS}
_DCT = {}
for _n in _NS:
    _m = np.cos(np.outer(np.arange(_n), np.pi * (np.arange(_n) + 0.5) / _n)) * (2.0 / _n)
    _m[0] /= 2.0
    _DCT[_n] = _m
_GX, _GW = np.polynomial.legendre.leggauss(32)


#: the shortest time scale of the blow (set by :class:`_Blow`): fits are graded from each start
_GRADE = [math.inf]


def _fit(fun, a, b, floor, out, depth=0):
    """Append to ``out`` pieces ``(a, b, coefs)`` interpolating ``fun`` on ``[a, b]``: adaptive, on
    pieces graded geometrically from ``a`` (widths from ``_GRADE[0]``, doubling), as every fast
    exponential starts at a break and decays: no sample would see a boundary layer thinner than the
    spacing of the nodes."""
    if depth == 0 and b - a > 2.0 * _GRADE[0]:
        e, w = [a], _GRADE[0]
        while a + 2.0 * w < b:
            e.append(a + w)
            w *= 2.0
        e.append(b)
        for lo, hi in zip(e[:-1], e[1:], strict=True):
            _fit(fun, lo, hi, floor, out, 1)
        return out
    for n in _NS:
        t = 0.5 * (a + b) + 0.5 * (b - a) * _NODES[n]
        y = fun(t)
        c = _DCT[n] @ y
        # below rounding: of the values, and of time itself (a shift of a few ulps of t, which a
        # stiff exponent turns into 1e6 ulps of the value)
        slope = float(np.max(np.abs(np.diff(y) / np.diff(t)))) if n > 1 else 0.0
        tol = max(floor, 2e-14 * float(np.max(np.abs(y))), 16.0 * 2.2e-16 * max(abs(a), abs(b)) * slope)
        if np.max(np.abs(c[-3:])) <= tol:
            keep = np.nonzero(np.abs(c) > 0.1 * tol)[0]
            c = c[: (keep[-1] + 1 if keep.size else 1)]
            out.append((a, b, c))
            return out
    if depth >= 50 or b - a <= 1e-13 * max(1.0, abs(a)):
        out.append((a, b, c))
        return out
    mid = 0.5 * (a + b)
    _fit(fun, a, mid, floor, out, depth + 1)
    _fit(fun, mid, b, floor, out, depth + 1)
    return out


def _peval(pieces, t):
    """Evaluate a list of contiguous pieces at ``t`` (an array)."""
    t = np.asarray(t, dtype=float)
    out = np.empty(t.shape)
    starts = [p[0] for p in pieces]
    idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(pieces) - 1)
    for i in np.unique(idx):
        a, b, c = pieces[i]
        msk = idx == i
        out[msk] = C.chebval((2.0 * t[msk] - a - b) / (b - a), c)
    return out


class History:
    """A function of time stored as contiguous Chebyshev pieces; ``breaks`` the starts of pieces at
    which it is not smooth."""

    def __init__(self):
        self.a, self.b, self.c = [], [], []
        self.breaks = []

    def add(self, pieces, genuine):
        for j, (a, b, c) in enumerate(pieces):
            self.a.append(a)
            self.b.append(b)
            self.c.append(c)
            if genuine and j == 0:
                self.breaks.append(a)

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape)
        if t.size == 0:
            return out
        lo = max(bisect.bisect_right(self.a, float(t.min())) - 1, 0)
        hi = max(bisect.bisect_right(self.a, float(t.max())) - 1, 0)
        if lo == hi:
            a, b, c = self.a[lo], self.b[lo], self.c[lo]
            return C.chebval((2.0 * t - a - b) / (b - a), c)
        idx = np.clip(np.searchsorted(self.a[lo:hi + 1], t, side="right") - 1, 0, hi - lo) + lo
        for i in np.unique(idx):
            a, b, c = self.a[i], self.b[i], self.c[i]
            msk = idx == i
            out[msk] = C.chebval((2.0 * t[msk] - a - b) / (b - a), c)
        return out

    def breaks_in(self, lo, hi):
        i = bisect.bisect_right(self.breaks, lo)
        j = bisect.bisect_left(self.breaks, hi)
        return self.breaks[i:j]

    def integral(self, lo, hi, square=False):
        """``int f dt`` (or ``int f^2 dt``) over ``[lo, hi]``, exact on the pieces."""
        tot = 0.0
        for a, b, c in zip(self.a, self.b, self.c, strict=True):
            x0, x1 = max(a, lo), min(b, hi)
            if x1 <= x0:
                continue
            cc = C.chebmul(c, c) if square else c
            ci = C.chebint(cc)
            u0, u1 = (2.0 * x0 - a - b) / (b - a), (2.0 * x1 - a - b) / (b - a)
            tot += 0.5 * (b - a) * (C.chebval(u1, ci) - C.chebval(u0, ci))
        return tot

    def maximum(self, t_end):
        """The largest value on ``[0, t_end]`` and the first time it is reached."""
        best, when = -math.inf, 0.0
        cands = []
        for a, b, c in zip(self.a, self.b, self.c, strict=True):
            if b <= 0.0 or a >= t_end:
                continue
            lo, hi = (2.0 * max(a, 0.0) - a - b) / (b - a), (2.0 * min(b, t_end) - a - b) / (b - a)
            xs = [lo, hi]
            if c.size > 2:
                r = C.chebroots(C.chebder(c))
                r = r[np.abs(r.imag) < 1e-9].real
                xs += [x for x in r if lo < x < hi]
            for x in xs:
                cands.append((0.5 * (a + b) + 0.5 * (b - a) * x, float(C.chebval(x, c))))
        best = max(v for _, v in cands)
        tol = 1e-13 * max(abs(best), 1e-300)
        when = min(t for t, v in cands if v >= best - tol)
        return best, when


def _first_exit(pieces, x0, scale):
    """The first time after ``x0`` where the function of ``pieces`` goes below ``-1e-12 scale``, or the
    change over a few ulps of the clock at the blow's fastest rate if more (a hysteresis of rounding's
    order: a turning point at rounding level does not chatter): ``None``
    when it does not (to the pieces' end); ``x0`` when it is negative from the start. Every sign
    change is at a real root of the colleague matrix; each stretch between roots is sampled."""
    for a, b, c in pieces:
        # at least the change over a few ulps of the clock at the fastest rate
        tiny = scale * (1e-12 + 16.0 * 2.2e-16 * abs(b) / _GRADE[0])
        r = np.array([])
        if c.size > 1 and np.any(c[1:] != 0.0):
            r = C.chebroots(c)
            r = np.sort(r[np.abs(r.imag) < 1e-7].real)
            r = r[(r > -1.0) & (r < 1.0)]
        pts = np.concatenate(([-1.0], r, [1.0]))
        for lo, hi in zip(pts[:-1], pts[1:], strict=True):
            if hi <= lo:
                continue
            probe = lo + (hi - lo) * np.array([0.125, 0.375, 0.5, 0.625, 0.875, 1.0])
            vals = C.chebval(probe, c)
            if np.min(vals) >= -tiny:
                continue
            x = lo
            before = C.chebval(max(lo - 1e-9, -1.0), c)
            j = int(np.argmax(vals < 0.0))
            if lo > -1.0 and before > 0.0:
                x = brentq(lambda u, c=c: C.chebval(u, c), max(lo - 1e-9, -1.0), probe[j], xtol=1e-16,
                           rtol=1e-15)
            return max(a + 0.5 * (b - a) * (x + 1.0), x0)
    return None


def _impulse(m, Z, b):
    """The impulse response ``G`` (``G(0) = 0, G'(0) = 1``) of ``m y'' + Z y' + b y`` and ``G'``, as
    functions of ``sigma`` (arrays): no cancellation for close or far apart roots."""
    disc = Z * Z - 4.0 * m * b
    if disc < 0.0:
        al, om = -Z / (2.0 * m), math.sqrt(-disc) / (2.0 * m)

        def G(s):
            return np.exp(al * s) * np.sin(om * s) / om

        def dG(s):
            return np.exp(al * s) * (np.cos(om * s) + al * np.sin(om * s) / om)

        return G, dG, max(abs(al), om), om
    q = -0.5 * (Z + math.sqrt(disc))
    r1, r2 = q / m, (b / q if b != 0.0 else 0.0)  # fast, slow
    d = r1 - r2

    def E(s):
        return s if d == 0.0 else np.expm1(d * s) / d

    def G(s):
        return np.exp(r2 * s) * E(s)

    if abs(r2) < 0.5 * abs(r1):
        def dG(s):
            return (r1 * np.exp(r1 * s) - r2 * np.exp(r2 * s)) / d
    else:
        def dG(s):
            return np.exp(r2 * s) * (1.0 + r1 * E(s))
    return G, dG, abs(r1), 0.0


def _duhamel(kernels, u, x, t, w0, cap):
    """``int_0^{t - x} K(sigma) u(t - sigma) d sigma`` for each kernel ``K`` and each ``t``: Gauss-
    Legendre on panels graded geometrically from both ends (first width ``w0``), at most ``cap``."""
    t = np.atleast_1d(t)
    nodes, weights, owner = [], [], []
    for i, ti in enumerate(t):
        tau = ti - x
        if tau <= 0.0:
            continue
        e = [0.0, tau]
        w = w0
        while w < 0.5 * tau:
            e += [w, tau - w]
            w *= 2.0
        e = np.unique(np.clip(e, 0.0, tau))
        edges = [e[0]]
        for lo, hi in zip(e[:-1], e[1:], strict=True):
            k = max(1, math.ceil((hi - lo) / cap))
            edges += list(lo + (hi - lo) * np.arange(1, k + 1) / k)
        edges = np.array(edges)
        lo, hi = edges[:-1, None], edges[1:, None]
        s = (0.5 * (lo + hi) + 0.5 * (hi - lo) * _GX).ravel()
        nodes.append(s)
        weights.append((0.5 * (hi - lo) * _GW).ravel())
        owner.append(np.full(s.size, i))
    res = [np.zeros(t.size) for _ in kernels]
    if not nodes:
        return res
    s = np.concatenate(nodes)
    wts = np.concatenate(weights)
    own = np.concatenate(owner)
    us = u(t[own] - s) * wts
    for r, K in zip(res, kernels, strict=True):
        r += np.bincount(own, weights=K(s) * us, minlength=t.size)
    return res


@dataclass
class Reference:
    """The reference blow's numbers (the exact solver's units)."""

    efficiency: float
    work_on_rock: float
    rock_energy: float
    piston_energy: float
    max_penetration: float
    permanent_penetration: float
    advance: float
    rebound_velocity: float
    peak_values: np.ndarray
    peak_times: np.ndarray
    loadings: np.ndarray
    separations: int
    recontacts: int
    energy_error: float
    histories: dict
    available_energy: float = 0.0
    feed_work: float = 0.0
    rod_energy: float = 0.0
    shank_displacement: float = 0.0
    bit_velocity: float = 0.0


class _Blow:
    def __init__(self, Tp, Zp, Tr, Zr, k, k_u, m, V, feed=0.0):
        self.T = np.concatenate((Tp, Tr)).astype(float)
        self.Z = np.concatenate((Zp, Zr)).astype(float)
        self.P, self.J = len(Tp), self.T.size
        self.k, self.k_u, self.m, self.V = float(k), float(k_u), float(m), float(V)
        self.feed = float(feed)
        self.h = float(self.T.min())
        self.F = max(float(np.max(np.asarray(Zp) * V)), self.feed)  # force scale
        self.eps = 1e-12 * self.h
        J = self.J
        self.R = [None] + [History() for _ in range(J)]   # emitted at node i - 1 into segment i
        self.L = [None] + [History() for _ in range(J)]   # emitted at node i into segment i
        self.N = [None] + [History() for _ in range(J - 1)]  # junction forces
        self.Rb, self.pb = History(), History()  # rock force, penetration
        for i in range(1, J + 1):
            Ti, Zi = self.T[i - 1], self.Z[i - 1]
            # the piston moving rigidly, unstressed; the rod at rest, compressed by the feed
            F0, G0 = (0.5 * Zi * V, -0.5 * Zi * V) if i <= self.P else (0.5 * self.feed, 0.5 * self.feed)
            self.R[i].add([(-Ti, 0.0, np.array([F0]))], True)
            self.L[i].add([(-Ti, 0.0, np.array([G0]))], True)
        self.contact, self.gap = True, 0.0
        self.separations = self.recontacts = 0
        # the bit: branch, penetration, velocity, rock force, p_max, R_max, p_perm; at rest on fresh
        # rock loaded to the feed
        p0 = self.p0 = self.feed / self.k
        self.br, self.p, self.v, self.Rf, self.q = LOAD, p0, 0.0, self.feed, p0
        self.pmax, self.Rmax = p0, self.feed
        self.pperm = self.pmax - self.Rmax / self.k_u
        self.t_peak = 0.0
        self.episodes = []  # [t0, t1, p0, p1]
        self.ep = [0.0, None, p0, None]
        Zb = self.Z[-1]
        rates = [k / Zb, k_u / Zb, 1.0 / self.h]
        osc = 0.0
        if m > 0.0:
            for b in (k, k_u, 0.0):
                *_, r, o = _impulse(m, Zb, b)
                rates.append(r)
                osc = max(osc, o)
        self.w0 = 1.0 / max(rates)
        _GRADE[0] = self.w0
        self.cap = min(self.h / 8.0, 8.0 / osc if osc > 0.0 else math.inf)

    # arrivals at node i
    def f_in(self, i):
        R, T = self.R[i], self.T[i - 1]
        return lambda t: R(t - T)

    def g_in(self, i):
        L, T = self.L[i + 1], self.T[i]
        return lambda t: L(t - T)

    def _breaks(self, i, lo, hi):
        out = []
        if i >= 1:
            out += [b + self.T[i - 1] for b in self.R[i].breaks_in(lo - self.T[i - 1] - self.eps,
                                                                   hi - self.T[i - 1] + self.eps)]
        if i <= self.J - 1:
            out += [b + self.T[i] for b in self.L[i + 1].breaks_in(lo - self.T[i] - self.eps,
                                                                   hi - self.T[i] + self.eps)]
        return sorted(out)

    def run(self, t_end):
        t0 = 0.0
        while t0 < t_end - self.eps:
            t1 = min(t0 + self.h, t_end)
            for i in range(self.J + 1):
                br = self._breaks(i, t0, t1)
                start_genuine = any(abs(b - t0) <= self.eps for b in br)
                cuts = [t0]
                for b in br:
                    if b > cuts[-1] + self.eps and b < t1 - self.eps:
                        cuts.append(b)
                cuts.append(t1)
                for j, (x, y) in enumerate(zip(cuts[:-1], cuts[1:], strict=True)):
                    self._node(i, x, y, start_genuine or j > 0 or t0 == 0.0)
            t0 = t1
        self.t_end = t_end

    def _node(self, i, x, y, genuine):
        if i == 0:
            g = self.g_in(0)
            self.R[1].add(_fit(lambda t: -g(t), x, y, 1e-14 * self.F, []), genuine)
        elif i == self.J:
            self._bit(x, y, genuine)
        elif i == self.P:
            self._contact(x, y, genuine)
        else:
            f, g = self.f_in(i), self.g_in(i)
            Za, Zb = self.Z[i - 1], self.Z[i]

            def N(t):
                return 2.0 * (Zb * f(t) + Za * g(t)) / (Za + Zb)

            Np = _fit(N, x, y, 1e-14 * self.F, [])
            self.N[i].add(Np, genuine)
            self.L[i].add(_fit(lambda t: _peval(Np, t) - f(t), x, y, 1e-14 * self.F, []), genuine)
            self.R[i + 1].add(_fit(lambda t: _peval(Np, t) - g(t), x, y, 1e-14 * self.F, []), genuine)

    def _contact(self, x, y, genuine):
        i = self.P
        f, g = self.f_in(i), self.g_in(i)
        Za, Zb = self.Z[i - 1], self.Z[i]
        fl = 1e-14 * self.F
        fd = self.feed
        while x < y:
            if self.contact:
                # the contact force N (the piston's end's); the shank's is N + f (the feed pushes it)
                def N(t):
                    return (2.0 * Zb * f(t) + 2.0 * Za * g(t) - Za * fd) / (Za + Zb)

                Np = _fit(N, x, y, fl, [])
                te = _first_exit(Np, x, self.F)
                e = y if te is None else te
                if e > x + self.eps:
                    Np = _fit(N, x, e, fl, []) if e < y else Np
                    self.N[i].add(Np, genuine)
                    self.L[i].add(_fit(lambda t, Np=Np: _peval(Np, t) - f(t), x, e, fl, []), genuine)
                    self.R[i + 1].add(_fit(lambda t, Np=Np: _peval(Np, t) + fd - g(t), x, e, fl, []),
                                      genuine)
                if te is not None:
                    self.contact, self.gap = False, 0.0
                    self.separations += 1
                    genuine = True
                x = e
            else:
                # v_shank - v_piston, the shank's end force f: v_s = (f - 2 g)/Z_b, v_p = 2 f_in/Z_a
                def dgap(t):
                    return (fd - 2.0 * g(t)) / Zb - 2.0 * f(t) / Za

                dp = _fit(dgap, x, y, 1e-14 * self.V, [])
                gp, acc = [], self.gap
                for a, b, c in dp:
                    ci = C.chebint(c) * (0.5 * (b - a))
                    ci[0] += acc - C.chebval(-1.0, ci)
                    gp.append((a, b, ci))
                    acc = float(C.chebval(1.0, ci))
                te = _first_exit(gp, x, self.V * self.h)
                # a separation begins at a double zero: only a crossing well after it counts
                e = y if te is None else te
                if e > x + self.eps:
                    self.N[i].add([(x, e, np.array([0.0]))], genuine)
                    self.L[i].add(_fit(lambda t: -f(t), x, e, fl, []), genuine)
                    self.R[i + 1].add(_fit(lambda t: fd - g(t), x, e, fl, []), genuine)
                    self.gap = float(_peval(gp, np.array([e]))[0]) if e < y else acc
                if te is not None:
                    self.contact, self.gap = True, 0.0
                    self.recontacts += 1
                    genuine = True
                x = e

    # -- the bit -------------------------------------------------------------------------------
    def _branch_solution(self, x, y):
        """Pieces of the branch's state on ``[x, y]``: ``(y1, y2)`` = (R, p) for a massless bit
        (``p`` only when lifted), (q, v) with a mass (``p = p_ref + q``)."""
        f = self.f_in(self.J)
        Zb, k, k_u, m = self.Z[-1], self.k, self.k_u, self.m

        def u(t):
            return 2.0 * f(t)

        if m == 0.0:
            if self.br == FREE:
                p0 = self.p

                def fun(t):
                    return p0 + _duhamel([lambda s: np.ones_like(s) / Zb], u, x, t, self.w0, self.cap)[0]

                return _fit(fun, x, y, 1e-14 * self.F / k, []), None
            lam = (k if self.br == LOAD else k_u) / Zb
            R0 = self.Rf

            def fun(t):
                tau = np.atleast_1d(t) - x
                return R0 * np.exp(-lam * tau) + lam * _duhamel([lambda s: np.exp(-lam * s)], u, x, t,
                                                                self.w0, self.cap)[0]

            return _fit(fun, x, y, 1e-14 * self.F, []), None
        b = (k, k_u, 0.0)[self.br]
        G, dG, *_ = _impulse(m, Zb, b)
        q0, v0 = self.q, self.v
        cache = {}

        def both(t):
            key = (t[0], t.size)
            if key not in cache:
                tau = np.atleast_1d(t) - x
                iq, iv = _duhamel([G, dG], u, x, t, self.w0, self.cap)
                Ph = dG(tau) + Zb / m * G(tau)
                cache.clear()
                cache[key] = (q0 * Ph + v0 * G(tau) + iq / m, q0 * (-b / m) * G(tau) + v0 * dG(tau) + iv / m)
            return cache[key]

        qs = _fit(lambda t: both(t)[0], x, y, 1e-14 * self.F / max(b, k), [])
        vs = _fit(lambda t: both(t)[1], x, y, 1e-14 * self.V, [])
        return qs, vs

    def _bit(self, x, y, genuine):
        J = self.J
        f = self.f_in(J)
        k, k_u, m = self.k, self.k_u, self.m
        fl = 1e-14 * self.F
        stuck = 0
        while x < y:
            A, B = self._branch_solution(x, y)
            # the exits of this branch, as functions >= 0 while it holds
            if m == 0.0:
                if self.br == LOAD:
                    ex = [(_fit(lambda t, A=A: 2.0 * f(t) - _peval(A, t), x, y, fl, []), self.F, ELASTIC)]
                elif self.br == ELASTIC:
                    ex = [([(a, b, _shift(-c, self.Rmax)) for a, b, c in A], self.F, LOAD),
                          (A, self.F, FREE)]
                else:
                    ex = [([(a, b, _shift(-c, self.pperm)) for a, b, c in A], self.F / k, ELASTIC)]
            else:
                if self.br == LOAD:
                    ex = [(B, self.V, ELASTIC)]
                elif self.br == ELASTIC:
                    ex = [([(a, b, _shift(-c, self.Rmax / k_u)) for a, b, c in A], self.F / k_u, LOAD),
                          (A, self.F / k_u, FREE)]
                else:
                    ex = [([(a, b, -c) for a, b, c in A], self.F / k_u, ELASTIC)]
            te, nxt = None, None
            for pcs, sc, to in ex:
                t = _first_exit(pcs, x, sc)
                if t is not None and (te is None or t < te):
                    te, nxt = t, to
            e = y if te is None else te
            if e > x + self.eps:
                stuck = 0
                self._store(A, B, x, e, genuine)
            else:
                stuck += 1
                if stuck > 4:
                    raise RuntimeError(f"the bit's branch chatters at t = {x}")
                e = x
                self._state_at(A, B, x, at_start=True)
            if te is not None:
                self._switch(nxt, e)
                genuine = True
            x = e

    def _state_at(self, A, B, t, at_start=False):
        if at_start:
            return
        tt = np.array([t])
        if self.m == 0.0:
            if self.br == FREE:
                self.p = float(_peval(A, tt)[0])
                self.Rf = 0.0
            else:
                self.Rf = float(_peval(A, tt)[0])
                self.p = self.Rf / self.k if self.br == LOAD else self.pperm + self.Rf / self.k_u
        else:
            q = self.q = float(_peval(A, tt)[0])
            self.v = float(_peval(B, tt)[0])
            self.p = q + (0.0 if self.br == LOAD else self.pperm)
            self.Rf = (self.k * q, self.k_u * q, 0.0)[self.br]

    def _store(self, A, B, x, e, genuine):
        J, f, Zb = self.J, self.f_in(self.J), self.Z[-1]
        fl = 1e-14 * self.F
        k, k_u, m, br, pperm = self.k, self.k_u, self.m, self.br, self.pperm
        if m == 0.0:
            if br == FREE:
                def R(t):
                    return np.zeros_like(t)

                def p(t):
                    return _peval(A, t)
            else:
                def R(t):
                    return _peval(A, t)

                def p(t):
                    return _peval(A, t) / k if br == LOAD else pperm + _peval(A, t) / k_u

            def g(t):
                return R(t) - f(t)
        else:
            off = 0.0 if br == LOAD else pperm
            bb = (k, k_u, 0.0)[br]

            def R(t):
                return bb * _peval(A, t)

            def p(t):
                return off + _peval(A, t)

            def g(t):
                return f(t) - Zb * _peval(B, t)
        self.L[J].add(_fit(g, x, e, fl, []), genuine)
        self.Rb.add(_fit(R, x, e, fl, []), genuine)
        self.pb.add(_fit(p, x, e, fl / self.k, []), genuine)
        self._state_at(A, B, e)
        if br == LOAD and self.p > self.pmax:
            self.pmax, self.Rmax, self.t_peak = self.p, self.k * self.p, e

    def _switch(self, to, t):
        """Change branch at ``t``; the state carried over exactly (the rock force and ``q`` not
        recomputed from ``p - p_perm``, which would lose ``1/gamma`` of their digits)."""
        k, k_u = self.k, self.k_u
        if self.br == LOAD:  # the end of a loading
            self.pmax, self.Rmax = max(self.pmax, self.p), max(self.Rmax, k * self.p)
            self.pperm = self.pmax - self.Rmax / k_u
            self.ep[1], self.ep[3] = t, self.p
            if self.ep[3] > self.ep[2]:
                self.episodes.append(list(self.ep))
        if to == LOAD:
            self.ep = [t, None, self.pmax, None]
            self.p, self.Rf, self.q = self.pmax, self.Rmax, self.pmax
        elif to == ELASTIC:
            if self.br == LOAD:
                self.Rf, self.q = self.Rmax, self.Rmax / k_u
            else:
                self.Rf = 0.0
        else:
            self.Rf = 0.0
        self.br = to

    def result(self):
        t_end = self.t_end
        k, k_u, m, V = self.k, self.k_u, self.m, self.V
        P = self.P
        Mp = float(np.sum(self.Z[:P] * self.T[:P]))
        E0 = 0.5 * Mp * V * V
        eps = [list(e) for e in self.episodes]
        if self.br == LOAD and self.p > self.ep[2]:
            eps.append([self.ep[0], t_end, self.ep[2], self.p])
        loads = np.array([[a, b, p0, p1, 0.5 * (1.0 - k / k_u) * k * (p1 - p0) * (p1 + p0)]
                          for a, b, p0, p1 in eps]).reshape(-1, 5)
        work = float(loads[:, 4].sum())
        imp = self.N[P].integral(0.0, t_end)
        Ep = sum((self.R[i].integral(t_end - self.T[i - 1], t_end, True)
                  + self.L[i].integral(t_end - self.T[i - 1], t_end, True)) / self.Z[i - 1]
                 for i in range(1, P + 1))
        Er = sum((self.R[i].integral(t_end - self.T[i - 1], t_end, True)
                  + self.L[i].integral(t_end - self.T[i - 1], t_end, True)) / self.Z[i - 1]
                 for i in range(P + 1, self.J + 1))
        # the shank's displacement: the integral of its velocity (F - G)/Z over the blow
        Ts, Zs = self.T[P], self.Z[P]
        xs = (self.R[P + 1].integral(0.0, t_end) - self.L[P + 1].integral(-Ts, t_end - Ts)) / Zs
        fd = self.feed
        feed_work = fd * xs
        stored = 0.5 * fd * fd * float(np.sum(self.T[P:] / self.Z[P:])) + fd * fd / (2.0 * k_u)
        available = E0 + feed_work + stored
        rock = self.Rf ** 2 / (2.0 * k_u)
        rod = Er + 0.5 * m * self.v ** 2
        err = abs(available - (work + rock + Ep + rod)) / available
        vals, times = [], []
        for j in range(1, self.J):
            v_, t_ = self.N[j].maximum(t_end)
            vals.append(v_ - (fd if j > P else 0.0))  # a rod junction's force above the feed's
            times.append(t_)
        vals.append(self.Rmax)
        times.append(self.t_peak)
        return Reference(
            efficiency=work / available, work_on_rock=work, rock_energy=rock, piston_energy=Ep,
            max_penetration=self.pmax, permanent_penetration=self.pmax - self.Rmax / k_u,
            advance=self.p - self.p0, rebound_velocity=V - imp / Mp, peak_values=np.array(vals),
            peak_times=np.array(times), loadings=loads, separations=self.separations,
            recontacts=self.recontacts, energy_error=err,
            histories={"junction": self.N, "rock_force": self.Rb, "penetration": self.pb},
            available_energy=available, feed_work=feed_work, rod_energy=rod, shank_displacement=xs,
            bit_velocity=self.v)


def _shift(c, v):
    """The Chebyshev series ``c + v``."""
    c = c.copy()
    c[0] += v
    return c


def reference_blow(piston_times, piston_impedances, rod_times, rod_impedances, *, k, k_u, bit_mass=0.0,
                   feed=0.0, impact_velocity=1.0, t_end):
    """The blow of a rigid unstressed piston at ``impact_velocity`` on a rod resting on fresh rock,
    statically compressed by the feed force ``feed >= 0`` on its shank (the bit at ``p = feed/k``),
    followed to ``t_end``, solved independently of the package (the module's text says how).

    Returns
    -------
    Reference
    """
    if not feed >= 0.0:
        raise ValueError(f"feed must be >= 0; got {feed!r}")
    b = _Blow(np.atleast_1d(piston_times), np.atleast_1d(piston_impedances), np.atleast_1d(rod_times),
              np.atleast_1d(rod_impedances), k, k_u, bit_mass, impact_velocity, feed)
    b.run(float(t_end))
    return b.result()
