"""Compiled closed-form flight between events and the certified step of the event search (theory §2,
§4): the modes advanced from an anchor (eq. 8), the particular solution of each load kind, the
bounds ``A`` on ``|h''|`` and ``J`` on ``|h'''|`` over a step, and the steps that cannot cross
``h = 0`` (see :mod:`impactbar.dynamics._event_loop`, which searches events with them). Plain float
arrays only; where numba caches compiled code (``CACHE``) is decided here, once for every kernel,
and the tiered execution of first calls installed (:mod:`impactbar.dynamics._tiers`)."""

from __future__ import annotations

import math

import numba
import numpy as np

from .._shared.compiling import watch_compiles
from .._shared.wrappers import internal_kernels

TWO_PI = 2.0 * math.pi


def _cache_probe():  # pragma: no cover - never called, only decorated
    return 0


def _cache_writable() -> bool:
    """Whether numba can cache compiled code: next to this file, or else in the user's cache folder
    (not in a read-only install without a writable cache folder)."""
    try:
        numba.njit(cache=True)(_cache_probe)
    except RuntimeError:
        return False
    return True


#: compiled code is cached on disk, so a new process compiles nothing compiled before; else (a
#: read-only install and no writable cache folder) it is compiled in memory
CACHE = _cache_writable()

# one line on stderr, once per process, while impactbar's kernels compile for more than 2 s
watch_compiles()

# a first call of a kernel not yet compiled runs its Python source while a child process compiles
# it into the cache (impactbar.dynamics._tiers)
from ._tiers import install as _install_tiers  # noqa: E402

_install_tiers(cache=CACHE)


@numba.njit(cache=CACHE, nogil=True)
def _bc(d, tau):
    """``b = (1 - e^{-d tau})/d``, ``c = (tau - b)/d`` with their ``d -> 0`` limits."""
    if d == 0.0:
        return tau, 0.5 * tau * tau
    y = d * tau
    if abs(y) < 1e-8:  # series: y may underflow to 0 for a denormal d, and expm1(-y)/d with it
        b = tau * (1.0 - 0.5 * y)
    else:
        b = -math.expm1(-y) / d
    if abs(y) < 1e-2:
        c = tau * tau * (0.5 - y / 6.0 + y * y / 24.0 - y**3 / 120.0 + y**4 / 720.0)
    else:
        c = (tau - b) / d
    return b, c


@numba.njit(cache=CACHE, nogil=True)
def _fundamental(w2, d, tau):
    """Fundamental matrix of ``q'' + d q' + w2 q = 0`` for ``w2 > 0``, every damping regime."""
    lam2 = w2 - 0.25 * d * d
    lam = math.sqrt(abs(lam2))
    x = lam * tau
    if lam2 >= 0.0:
        C = math.cos(x)
        S = tau * (math.sin(x) / x if abs(x) > 1e-8 else 1.0 - x * x / 6.0)
    elif abs(x) > 1e-4:  # overdamped: e^{-d tau/2} cosh, sinh as two decaying exponentials
        ep = 0.5 * math.exp((lam - 0.5 * d) * tau)  # (cosh overflows where e underflows)
        em = 0.5 * math.exp((-lam - 0.5 * d) * tau)
        eC = ep + em
        eS = (ep - em) / lam
        return eC + 0.5 * d * eS, eS, -w2 * eS, eC - 0.5 * d * eS
    else:
        C = math.cosh(x)
        S = tau * (1.0 + x * x / 6.0)
    e = math.exp(-0.5 * d * tau)
    return e * (C + 0.5 * d * S), e * S, -e * w2 * S, e * (C - 0.5 * d * S)


@numba.njit(cache=CACHE, nogil=True)
def load_value(load, level, t):
    """``p(t)``, ``p'(t)``, ``p''(t)`` of the load view ``load`` (derivatives 0 inside a piece of a
    piecewise-constant load, whose ``level`` the caller passes)."""
    if load.kind == 1:
        return level, 0.0, 0.0
    return harmonic_sum(load.p0, load.ks, load.pr, load.pim, t)


@numba.njit(cache=CACHE, nogil=True)
def harmonic_sum(h0, ks, hr, hi, t):
    """``h(t) = h0 + sum_j Re((hr_j + i hi_j) e^{i k_j t})`` and its first two derivatives: a
    Fourier load (eq. 7), and the particular response at the struck end that the event search
    sums the same way."""
    h = h0
    dh = 0.0
    ddh = 0.0
    for j in range(ks.size):
        k = ks[j]
        ck = math.cos(k * t)
        sk = math.sin(k * t)
        a = hr[j] * ck - hi[j] * sk
        h += a
        dh -= k * (hr[j] * sk + hi[j] * ck)
        ddh -= k * k * a
    return h, dh, ddh


@numba.njit(cache=CACHE, nogil=True)
def particular(load, B, level, t, qp, vp):
    """Fill ``qp, vp`` with the particular state at ``t`` (0 for a rigid mode's mean-load part) of
    the basis ``B`` (:class:`~impactbar.dynamics.compiled_views.ModalBasisView`) under ``load``."""
    kind, p0, ks = load.kind, load.p0, load.ks
    w2, hpr, hpi = B.w2, B.hpr, B.hpi
    M = w2.size
    for n in range(M):
        if w2[n] > 0.0:
            qp[n] = (p0 if kind == 0 else level) / w2[n]
        else:
            qp[n] = 0.0
        vp[n] = 0.0
    if kind == 0:
        for j in range(ks.size):
            k = ks[j]
            ck = math.cos(k * t)
            sk = math.sin(k * t)
            for n in range(M):
                qp[n] += hpr[n, j] * ck - hpi[n, j] * sk
                vp[n] -= k * (hpr[n, j] * sk + hpi[n, j] * ck)


@numba.njit(cache=CACHE, nogil=True)
def advance(load, B, level, ta, anchor, t, state):
    """State ``q, v`` at ``t`` from the anchor ``(ta, qa, va)`` with particular state ``qpa, vpa``
    there (``anchor = (qa, va, qpa, vpa)``); ``state = (q, v, qp, vp)`` receives the state and the
    particular state at ``t``."""
    qa, va, qpa, vpa = anchor
    q, v, qp, vp = state
    kind, p0 = load.kind, load.p0
    w2, d = B.w2, B.d
    tau = t - ta
    if kind == 0:
        particular(load, B, level, t, qp, vp)
    else:
        for n in range(w2.size):
            qp[n] = qpa[n]
            vp[n] = vpa[n]
    L = p0 if kind == 0 else level
    b, c = _bc(d, tau)
    ed = math.exp(-d * tau)
    for n in range(w2.size):
        dq = qa[n] - qpa[n]
        dv = va[n] - vpa[n]
        if w2[n] == 0.0:
            q[n] = qa[n] + (qp[n] - qpa[n]) + dv * b + L * c
            v[n] = vp[n] + dv * ed + L * b
        else:
            p11, p12, p21, p22 = _fundamental(w2[n], d, tau)
            q[n] = p11 * dq + p12 * dv + qp[n]
            v[n] = p21 * dq + p22 * dv + vp[n]


@numba.njit(cache=CACHE, nogil=True)
def functional(w2, d, wts, alpha, p, dp, ddp, q, v, qp, vp):
    """``h, h', h''`` of ``h = alpha p + sum w_n q_n`` at a state, and the rounding noise of ``h``
    and ``h'`` (``1e-14`` times the sum of the magnitudes they add and cancel)."""
    h = alpha * p
    dh = alpha * dp
    ddh = alpha * ddp
    mag = abs(h)
    dmag = abs(dh)
    for n in range(w2.size):
        h += wts[n] * q[n]
        dh += wts[n] * v[n]
        ddh += wts[n] * (p - d * v[n] - w2[n] * q[n])
        mag += abs(wts[n]) * (abs(q[n]) + abs(qp[n]))
        dmag += abs(wts[n]) * (abs(v[n]) + abs(vp[n]))
    return h, dh, ddh, 1e-14 * mag, 1e-14 * dmag


@numba.njit(cache=CACHE, nogil=True)
def bounds(load, B, wts, alpha, psup, L, state, horizon):
    """Bounds ``A >= |h''|`` and ``J >= |h'''|`` valid on ``[t, t + horizon]`` from the state
    ``(q, v, qp, vp)``, with ``psup >= |p|`` and ``L`` the mean load (or the piece's level)."""
    q, v, qp, vp = state
    p1, p2, p3 = load.p1, load.p2, load.p3
    w2, d, vpb, apb, jpb = B.w2, B.d, B.vpb, B.apb, B.jpb
    A = abs(alpha) * p2
    J = abs(alpha) * p3
    for n in range(w2.size):
        wn = abs(wts[n])
        if wn == 0.0:
            continue
        if w2[n] == 0.0:
            vmax = abs(v[n] - vp[n]) + vpb[n] + abs(L) * horizon
            a0 = psup + d * vmax
            A += wn * a0
            J += wn * (p1 + d * a0)
        else:
            e = math.sqrt((v[n] - vp[n]) ** 2 + w2[n] * (q[n] - qp[n]) ** 2)
            w = math.sqrt(w2[n])
            A += wn * ((d + w) * e + apb[n])
            J += wn * ((d * (d + w) + w2[n]) * e + jpb[n])
    return A, J


@numba.njit(cache=CACHE, nogil=True)
def sort_head(a, n):
    """Sort ``a[:n]`` in place, ascending (no NaN), and return ``a[:n]``: the few jumps of a load in a
    window, which arrive almost sorted. The same values as ``np.sort``, whose quicksort, with the
    slice assignment that wrote it back, cost some 3 s of CPU time to compile on a first run."""
    for i in range(1, n):
        x = a[i]
        j = i - 1
        while j >= 0 and a[j] > x:
            a[j + 1] = a[j]
            j -= 1
        a[j + 1] = x
    return a[:n]


@numba.njit(cache=CACHE, nogil=True)
def piece_end(breaks, m, j):
    """End time of the piece ``(m, j)`` (period ``m``, piece ``j``) of a piecewise-constant load."""
    if j + 1 < breaks.size:
        return m * TWO_PI + breaks[j + 1]
    return (m + 1) * TWO_PI


@numba.njit(cache=CACHE, nogil=True)
def piece_of(breaks, t):
    """Period index and piece index of time ``t`` for a piecewise-constant load: the piece whose
    start ``m 2 pi + breaks[j]`` and end (:func:`piece_end`) hold ``start <= t < end``, both computed
    as the event search computes them. (The phase ``t - m 2 pi`` alone rounds: a release found at a
    jump, ``te = piece_end(..)``, came out a rounding error inside the piece before it, so the
    flight from there started under the old level.)"""
    m = math.floor(t / TWO_PI)
    tm = t - m * TWO_PI
    if tm >= TWO_PI:
        m += 1
        tm -= TWO_PI
    j = np.int64(0)  # (not the literal 0: piece_end is compiled for one signature)
    for i in range(breaks.size):
        if breaks[i] <= tm:
            j = i
    J = breaks.size
    for _ in range(2):  # at most one piece off either way
        if t >= piece_end(breaks, m, j):
            j += 1
            if j == J:
                j = np.int64(0)
                m += 1
        elif t < m * TWO_PI + breaks[j]:
            j -= 1
            if j < 0:
                j = J - 1
                m -= 1
        else:
            break
    return m, j


@numba.njit(cache=CACHE, nogil=True)
def _cubic(g, dh, ddh, J, s):
    return g + s * (dh + s * (0.5 * ddh + s * J / 6.0))


@numba.njit(cache=CACHE, nogil=True)
def _cubic_cuts(dh, ddh, J, smax):
    """The positive roots below ``smax`` of ``f' = dh + ddh x + J x^2 / 2`` (``J >= 0``), where the
    cubic of :func:`_cubic_step` turns: their number and the two in increasing order (``smax`` for
    those missing)."""
    c1 = smax
    c2 = smax
    nc = 0
    if J > 0.0:
        disc = ddh * ddh - 2.0 * J * dh
        if disc >= 0.0:
            r = math.sqrt(disc)
            for x in ((-ddh - r) / J, (-ddh + r) / J):
                if 0.0 < x < smax:
                    if nc == 0:
                        c1 = x
                    else:
                        c2 = x
                    nc += 1
    elif ddh != 0.0:
        x = -dh / ddh
        if 0.0 < x < smax:
            c1 = x
            nc += 1
    return nc, c1, c2


@numba.njit(cache=CACHE, nogil=True)
def _cubic_step(g, dh, ddh, J, smax):
    """A step ``s`` with ``f(x) = g + dh x + ddh x^2/2 + J x^3/6 < 0`` on ``[0, s)`` (``g <= 0``,
    ``J >= 0``): the first root of ``f``, from below, or ``smax`` if there is none before it."""
    # monotone pieces of f, split at the cuts (scalars, so that a step allocates nothing)
    nc, c1, c2 = _cubic_cuts(dh, ddh, J, smax)
    lo = 0.0
    for i in range(nc + 1):
        hi = smax if i == nc else (c1 if i == 0 else c2)
        fh = _cubic(g, dh, ddh, J, hi)
        if fh >= 0.0:
            # f < 0 at lo, >= 0 at hi, monotone between: bisection keeps lo safe
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                if mid <= lo or mid >= hi:
                    break
                if _cubic(g, dh, ddh, J, mid) < 0.0:
                    lo = mid
                else:
                    hi = mid
                if hi - lo <= 2e-2 * hi:
                    break
            return lo
        lo = hi
    return smax


@numba.njit(cache=CACHE, nogil=True)
def _quadratic_step(g, dh, A):
    """First positive root of ``g + dh s + A s^2 / 2`` (``g <= 0``, ``A >= 0``), ``inf`` if none."""
    if A == 0.0:
        return -g / dh if dh > 0.0 else math.inf
    A2 = 2.0 * A * (-g)
    if dh >= 0.0:
        den = dh + math.sqrt(dh * dh + A2)
        return 2.0 * (-g) / den if den > 0.0 else 0.0
    return (-dh + math.sqrt(dh * dh + A2)) / A


@numba.njit(cache=CACHE, nogil=True)
def _cubic_step_fast(g, dh, ddh, J, smax):
    """:func:`_cubic_step` (the same certified step, to 2 %) with the root of each monotone piece
    found by the Illinois variant of regula falsi instead of bisection: the kept end ``lo`` always
    has ``f(lo) < 0``, so ``f < 0`` on ``[0, lo]``."""
    nc, c1, c2 = _cubic_cuts(dh, ddh, J, smax)
    lo = 0.0
    flo = g
    for i in range(nc + 1):
        hi = smax if i == nc else (c1 if i == 0 else c2)
        fh = _cubic(g, dh, ddh, J, hi)
        if fh >= 0.0:
            if flo >= 0.0:  # g = 0 at a cut: no safe step beyond lo
                return lo
            side = 0
            for _ in range(200):
                x = lo - flo * (hi - lo) / (fh - flo)
                if not (lo < x < hi):
                    x = 0.5 * (lo + hi)
                    if x <= lo or x >= hi:
                        break
                fx = _cubic(g, dh, ddh, J, x)
                if fx < 0.0:
                    lo = x
                    flo = fx
                    if side == -1:
                        fh *= 0.5
                    side = -1
                else:
                    hi = x
                    fh = fx
                    if side == 1:
                        flo *= 0.5
                    side = 1
                if hi - lo <= 2e-2 * hi:
                    break
            return lo
        lo = hi
        flo = fh
    return smax


@numba.njit(cache=CACHE, nogil=True)
def first_piece(load, B, ta, qpa, vpa):
    """Set up the load piece that holds ``ta``: its index ``(m, j)`` (period ``m``, piece ``j``;
    zeros for a Fourier load), its level, and the particular state at ``ta`` in ``qpa, vpa``.
    Returns ``m, j, level``."""
    kind, breaks, levels = load.kind, load.breaks, load.levels
    m = 0
    j = 0
    level = 0.0
    if kind == 1:
        m, j = piece_of(breaks, ta)
        level = levels[j]
    particular(load, B, level, ta, qpa, vpa)
    return m, j, level


@numba.njit(cache=CACHE, nogil=True)
def next_piece(load, B, level, ta, te, m, j, anchor, state):
    """Cross the load jump at ``te``: advance the anchor ``(ta, qa, va)`` to it, step the piece
    index ``(m, j)`` (``j`` wraps to the next period ``m + 1``) and set the new level's particular
    state ``qpa, vpa`` (``anchor = (qa, va, qpa, vpa)``). Returns the new ``ta, m, j, level``;
    ``state = (q, v, qp, vp)`` holds the state at ``te``."""
    qa, va, qpa, vpa = anchor
    q, v, _, _ = state
    breaks, levels, w2 = load.breaks, load.levels, B.w2
    advance(load, B, level, ta, anchor, te, state)
    for n in range(w2.size):
        qa[n] = q[n]
        va[n] = v[n]
    j += 1
    if j == breaks.size:
        j = 0
        m += 1
    level = levels[j]
    particular(load, B, level, te, qpa, vpa)
    return te, m, j, level


# the kernels Python may call (those of impactbar.dynamics.compiled, and _bc) keep their wrapper and
# cache entry; the others are link-only (their callers' libraries hold their machine code)
internal_kernels(globals(), python=("load_value", "piece_of", "sort_head", "_bc"))
