"""Compiled contact windows of the wave impact law (theory §4b): the drive's moments over a window,
the load's jumps inside it, the scan step of the contact test, and the window held in contact
throughout (:func:`wave_window`; the windows in which contact is lost are
:func:`impactbar.laws.wave._separation.wave_contact`'s)."""

from __future__ import annotations

import math

import numba
import numpy as np

from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE, TWO_PI, load_value, piece_of, sort_head
from ...dynamics.compiled_views import LoadKernelView


@numba.njit(cache=CACHE, nogil=True)
def _window_load(load, t):
    """``p(t)``, right-continuous at the jumps of a piecewise-constant load."""
    if load.kind == 1:
        m, j = piece_of(load.breaks, t)
        return load.levels[j]
    p, dp, ddp = load_value(load, 0.0, t)
    return p


@numba.njit(cache=CACHE, nogil=True)
def scan_step(N, rate):
    """The grid step of a contact window's scan for the wave law's contact function (window time,
    ``[0, 2]``): a trigonometric sum of highest frequency ``N pi`` plus the load's, whose ``rate``
    (rad per unit window time) bounds how fast it turns: 6 nodes per period, at most 1/16."""
    hg = min(1.0 / 16.0, 1.0 / (3.0 * (N + 1)))
    if rate > 0.0:
        hg = min(hg, math.pi / (3.0 * rate))
    return hg


@numba.njit(cache=CACHE, nogil=True)
def window_jumps(load, s, t0, jumps):
    """Write the jumps of a piecewise-constant load inside ``[t0, t0 + 2/s]`` as sorted
    ``theta = s (t - t0)`` in ``(0, 2)`` into ``jumps``; returns their number."""
    nj = 0
    breaks = load.breaks
    if load.kind == 1:
        T = 2.0 / s
        m0 = math.floor(t0 / TWO_PI)
        m1 = math.floor((t0 + T) / TWO_PI)
        for m in range(m0, m1 + 1):
            for i in range(breaks.size):
                tj = m * TWO_PI + breaks[i]
                if t0 < tj < t0 + T and nj < jumps.size:
                    jumps[nj] = s * (tj - t0)
                    nj += 1
        sort_head(jumps, np.int64(nj))  # (np.int64: a literal nj would compile sort_head again)
    return nj


@numba.njit(cache=CACHE, nogil=True)
def _window_moments(load, s, rate, t0, jumps, gl_x, gl_w, ic_, is_):
    """Add the moments ``int P(theta) cos(n pi theta)``, ``... sin ...`` of the drive
    ``P(theta) = p(t0 + theta/s)`` over ``[0, 1]`` (row 0) and ``[1, 2]`` (row 1) to ``ic_, is_``
    (shape (2, M)): Gauss-Legendre panels split at the load's ``jumps`` (in theta, sorted); for a
    piecewise-constant load, constant between the jumps, the moments of each piece ``[m - w, m + w]``
    in closed form, ``2 P sin(n pi w) (cos, sin)(n pi m) / (n pi)`` (the difference of the ends'
    sines and cosines as a product, without its cancellation on a short piece; ``O(M)`` per piece
    instead of ``O(M)`` per node; ``impact._exact_moments`` is its numpy reference)."""
    M = ic_.shape[1]
    N = M - 1
    nj = jumps.size
    hq = 8.0 / (math.pi * N + rate + 1.0)
    for half in range(2):
        lo = float(half)
        for ic in range(nj + 1):
            hi = float(half + 1)
            for i in range(ic, nj):  # the next jump inside this half, if any
                if lo < jumps[i] < hi:
                    hi = jumps[i]
                    break
            width = hi - lo
            if width > 0.0 and load.kind == 1:
                mid = 0.5 * (lo + hi)
                P = _window_load(load, t0 + mid / s)
                ic_[half, 0] += P * width
                cm, sm = math.cos(math.pi * mid), math.sin(math.pi * mid)
                cw, sw = math.cos(0.5 * math.pi * width), math.sin(0.5 * math.pi * width)
                cmn, smn, cwn, swn = 1.0, 0.0, 1.0, 0.0
                for n in range(1, M):
                    cmn, smn = cmn * cm - smn * sm, smn * cm + cmn * sm
                    cwn, swn = cwn * cw - swn * sw, swn * cw + cwn * sw
                    k = 2.0 * P * swn / (math.pi * n)
                    ic_[half, n] += k * cmn
                    is_[half, n] += k * smn
            elif width > 0.0:
                npan = max(1, int(math.ceil(width / hq)))
                half_w = 0.5 * width / npan
                for pnl in range(npan):
                    mid = lo + half_w * (2.0 * pnl + 1.0)
                    for g in range(gl_x.size):
                        th = mid + half_w * gl_x[g]
                        wp = half_w * gl_w[g] * _window_load(load, t0 + th / s)
                        c1, s1 = math.cos(math.pi * th), math.sin(math.pi * th)
                        cn, sn = 1.0, 0.0
                        for n in range(M):
                            ic_[half, n] += wp * cn
                            is_[half, n] += wp * sn
                            cn, sn = cn * c1 - sn * s1, sn * c1 + cn * s1
            lo = hi
            if lo >= half + 1.0:
                break


@numba.njit(cache=CACHE, nogil=True)
def window_moments(load, s, rate, t0s, jumps, gl_x, gl_w, ic_, is_):
    """:func:`_window_moments` called from Python for the windows starting at each of ``t0s``
    (shape (P,)), each start's moments added to ``ic_[i], is_[i]`` (shape (P, 2, M)), with ``load``
    as plain tuples (``tuple(view)``: numba dispatches them several times faster than named
    tuples). One call for all the starts of a load: the dispatch, not the moments, was most of a
    call with one start."""
    view = LoadKernelView(*load)
    for i in range(t0s.size):
        _window_moments(view, s, rate, t0s[i], jumps, gl_x, gl_w, ic_[i], is_[i])


@numba.njit(cache=CACHE, nogil=True)
def tabled_moments(p0, w, a, c, sn, ic_, is_):
    """:func:`window_moments` for a load ``p0 + a(t)`` of one harmonic or none, without jumps, from
    its nodes tabled once (``impact._node_table``: the weights ``w`` (2, J), the harmonic ``a`` at each
    start's nodes (P, 2, J), ``cos, sin(n pi theta)`` ``c, sn`` (2, J, M)): each node's load
    ``p0 + a``, weighted, added to ``ic_[i], is_[i]`` (shape (P, 2, M)) node by node in the kernel's
    order, so the same floats, without the nodes' cosines and sines (which do not depend on ``p0``)."""
    M = ic_.shape[2]
    for i in range(a.shape[0]):
        for half in range(2):
            for j in range(w.shape[1]):
                wp = w[half, j] * (p0 + a[i, half, j])
                for n in range(M):
                    ic_[i, half, n] += wp * c[half, j, n]
                    is_[i, half, n] += wp * sn[half, j, n]


@numba.njit(cache=CACHE, nogil=True)
def wave_window(load_t, s, R, c, rate, t0, q, v, gl_x, gl_w, qa, va):
    """The contact window ``[t0, t0 + 2/s]`` of the wave law held in contact throughout: checks that
    the invariant arriving at the rod, ``A(theta)``, stays ``>= 0`` on the scan grid of
    :mod:`impactbar.laws.wave.impact` (both limits at every jump) and, if so, writes
    ``(q, v) -> -R (q, v) + drive`` into ``qa, va`` (the drive by Gauss-Legendre panels split at the
    load's jumps; ``qa[0]`` from contact) and returns True. False (nothing written) means the
    contact separates: the caller solves it in full. Called from Python with the load's view as the
    plain tuple ``load_t`` (numba dispatches it several times faster than a named tuple), made a view
    here (no wrapper kernel: a wrapper compiles its callees' code again)."""
    load = LoadKernelView(*load_t)
    kind, psup, breaks = load.kind, load.psup, load.breaks
    M = q.size
    N = M - 1
    a = np.empty(M)
    b = np.empty(M)
    scale = 2.0 * psup / s
    for n in range(M):
        a[n] = v[n] if n == 0 else 2.0 * v[n]
        b[n] = -2.0 * s * math.pi * n * q[n]
        scale += abs(a[n]) + abs(b[n])
    periods = math.floor((t0 + 2.0 / s) / TWO_PI) - math.floor(t0 / TWO_PI) + 1
    jumps = np.empty(periods * breaks.size if kind == 1 else 0)  # room for every jump in the window
    nj = window_jumps(load, s, t0, jumps)
    # the static correction (dynamics.invariants.PistonInvariants): the strain's b_0 (1 - x) +
    # sum 2 p_end sin(n pi x) / (s n pi), p_end the drive's force at x = 0 (a square wave's level on
    # the window's first piece)
    t_p = t0 + 0.5 * (jumps[0] if nj > 0 else 2.0) / s if kind == 1 else t0
    p_end = _window_load(load, t_p)
    b[0] = -p_end / s
    scale += abs(b[0])
    for n in range(1, M):
        scale -= abs(b[n])
        b[n] += 2.0 * p_end / (s * math.pi * n)
        scale += abs(b[n])
    tol = 1e-13 * scale
    # -- the scan of A: [0, 1] from the start state, [1, 2] from beta0 and the drive
    hg = scan_step(N, rate)
    cuts = np.empty(nj + 2)
    ncut = 0
    cuts[ncut] = 1.0
    ncut += 1
    for i in range(nj):
        if jumps[i] < 1.0:
            cuts[ncut] = 1.0 + jumps[i]
            ncut += 1
    cuts[ncut] = 2.0
    ncut += 1
    lo = 0.0
    for ic in range(ncut):
        hi = cuts[ic]
        npts = max(2, int(math.ceil((hi - lo) / hg)) + 1)
        level = 0.0
        if lo >= 1.0 and kind == 1:  # the drive's level on this piece, read at its middle
            level = _window_load(load, t0 + (0.5 * (lo + hi) - 1.0) / s)
        for k in range(npts):
            th = lo + (hi - lo) * k / (npts - 1)
            A = 0.0
            x = 1.0 - th if lo < 1.0 else th - 1.0
            sgn = -1.0 if lo < 1.0 else 1.0  # alpha0(1 - theta), or beta0(theta - 1)
            c1, s1 = math.cos(math.pi * x), math.sin(math.pi * x)
            cn, sn = 1.0, 0.0  # cos(n pi x), sin(n pi x) by rotation
            for n in range(M):
                A += a[n] * cn + sgn * b[n] * sn
                cn, sn = cn * c1 - sn * s1, sn * c1 + cn * s1
            A += sgn * b[0] * (1.0 - x)  # the static correction's (1 - x) term
            if lo >= 1.0:
                u = x
                if kind == 1:
                    A += 2.0 * level / s
                else:
                    A += 2.0 * _window_load(load, t0 + u / s) / s
            if A < -tol:
                return False
        lo = hi
    ic_ = np.zeros((2, M))
    is_ = np.zeros((2, M))
    _window_moments(load, s, rate, t0, jumps[:nj], gl_x, gl_w, ic_, is_)
    for n in range(M):
        va[n] = -R * v[n] + (ic_[1, n] - R * ic_[0, n]) / s
        if n == 0:
            qa[n] = 0.0
        else:
            qa[n] = -R * q[n] - (is_[1, n] - R * is_[0, n]) / (s * s * math.pi * n)
    g0 = 0.0
    for n in range(1, M):
        g0 += c[n] * qa[n]
    qa[0] = -g0
    return True


# the window's helpers only kernels call are link-only (their callers hold their code): a first run
# compiles each once, inside the kernel that calls it, not also alone
internal_kernels(globals(), python=("window_moments", "tabled_moments", "wave_window", "scan_step"))
