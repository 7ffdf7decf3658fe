"""Compiled certified admissibility search (theory §5), used by
:func:`impactbar.orbits.admissibility._admissibility` in place of the numpy search (a few dozen
small numpy calls per bisection level and per Newton step).

It runs the same algorithm as the numpy path, step by step: the exclusion of intervals where
``|g'(mid)| > L h`` (``g = u(1, t)``, ``L`` the bound of ``|g''|`` from each mode's energy), the
vectorised Newton iteration on the zeros of ``g'`` with the same stopping rule, and the branch and
bound on the stationary values (the bounds of ``g`` from the midpoint, and from a found zero by
Taylor's theorem). The modal flow is the exact closed form of :mod:`impactbar.dynamics._load_flow`
under a Fourier load (kind 0 of the load's kernel view) or a piecewise-constant load (kind 1).
Results agree with the numpy path to rounding. Imported lazily, so ``import impactbar`` does not load numba.
"""

from __future__ import annotations

import math
import threading

import numba
import numpy as np

from .._shared.wrappers import internal_kernels
from ..dynamics.compiled import CACHE, bound_column, fourier_column, piecewise_column
from ..dynamics.compiled_views import LoadKernelView

TWO_PI = 2.0 * math.pi
_MAXF = np.finfo(np.float64).max
#: the places in :func:`admissibility_search`'s tuples: ``prob = (c, absc, w2, d, psup)``,
#: ``src = (load, F, P)`` and its scratch ``work``: the modal state's columns ``q, v``, the load's
#: ``ck, sk``, the frequencies ``W``, ``_upper``'s ``eb, above, vabove``, two rows of the folded
#: modes' phases (the first ``_upper``'s ``l3``)
PB_C, PB_ABSC, PB_W2, PB_D, PB_PSUP = range(5)
SRC_LOAD, SRC_F, SRC_P = range(3)
WK_Q, WK_V, WK_CK, WK_SK, WK_W, WK_EB, WK_ABOVE, WK_VABOVE, WK_PH1, WK_PH2 = range(10)
#: the most entries (intervals times modes) of the folded modes' phases that the bisection keeps
#: to step them by rotations (four arrays of 8 MiB at most, ``phase_buffers``); a level with more
#: evaluates them directly
PHASE_BUDGET = 1 << 20


@numba.njit(cache=CACHE, nogil=True)
def _right(a, x):
    """``np.searchsorted(a, x, side="right")`` for a short sorted ``a``."""
    n = 0
    while n < a.size and a[n] <= x:
        n += 1
    return n


@numba.njit(cache=CACHE, nogil=True, inline="always")
def _load(t, load):
    """The load ``p(t)`` at the absolute time ``t`` (``load``: the load's kernel view, ``src[SRC_LOAD]``
    of :func:`admissibility_search`). Inlined, and given the view alone: a kernel call counts a
    reference to every array it is passed, and ``src`` holds some twenty."""
    if load.kind == 0:
        k, pr, pim, p0 = load.ks, load.pr, load.pim, load.p0
        s = 0.0
        for m in range(k.size):
            x = k[m] * t
            s += math.cos(x) * pr[m] - math.sin(x) * pim[m]
        return p0 + s
    brk, lv = load.breaks, load.levels
    tm = t % TWO_PI
    idx = _right(brk, tm) - 1
    if idx < 0:
        idx = brk.size - 1
    return lv[idx]


@numba.njit(cache=CACHE, nogil=True, inline="always")
def _variation(mid, half, load):
    """``(center, delta)`` with ``|p - center| <= delta`` on ``[mid - half, mid + half]`` (as
    ``Load.variation``; ``load`` the view, as :func:`_load`)."""
    center = _load(mid, load)
    if load.kind == 0:
        return center, min(load.p1 * half, 2.0 * load.posc)
    brk, spread = load.breaks, load.spread
    if brk.size == 1:  # a constant load: no jump at all
        return center, 0.0
    lo = mid - half
    hi = mid + half
    jump = 2.0 * half >= TWO_PI
    for b in brk:
        if math.floor((hi - b) / TWO_PI) - math.floor((lo - b) / TWO_PI) > 0.0:
            jump = True
    return center, spread if jump else 0.0


@numba.njit(cache=CACHE, nogil=True)
def _state(t, work, src):
    """The modal state at the absolute time ``t`` into column 0 of ``q, v`` (shape ``(M, 1)``)."""
    q, v, ck, sk = work[WK_Q], work[WK_V], work[WK_CK], work[WK_SK]
    load, F, P = src
    if load.kind == 0:
        # (a literal 0 or True would compile it again)
        fourier_column(t, q, v, np.int64(0), ck, sk, F, work[WK_PH1], work[WK_PH2], np.bool_(False))
        return
    w2, d, nodes, levels, qn, vn = P
    j = _right(nodes, t) - 1
    j = min(max(j, 0), nodes.size - 2)
    piecewise_column(w2, d, levels[j], max(t - nodes[j], 0.0), qn[:, j], vn[:, j], q, v, 0)


@numba.njit(cache=CACHE, nogil=True)
def _dot(c, x):
    s = 0.0
    for n in range(c.size):
        s += c[n] * x[n, 0]
    return s


@numba.njit(cache=CACHE, nogil=True, inline="always")  # one caller: inlined
def _g(phase, t, c, work, src):
    """``g(t) = c . q(phase + t)``."""
    q = work[WK_Q]
    _state(phase + t, work, src)
    return _dot(c, q)


@numba.njit(cache=CACHE, nogil=True)
def _joint(phase, mid, half, prob, work, src):
    """``(g(mid), g'(mid), L)``: the end's displacement and velocity, and the bound of ``|g''|`` on
    ``[mid - half, mid + half]`` (``gprime_and_bound`` of the numpy path)."""
    c, absc, w2, d, psup = prob
    q, v = work[WK_Q], work[WK_V]
    ta = phase + mid
    _state(ta, work, src)
    center, delta = _variation(ta, half, src[SRC_LOAD])
    g1, L = bound_column(c, absc, w2, d, psup, q, v, 0, center, delta, half)
    return _dot(c, q), g1, L


@numba.njit(cache=CACHE, nogil=True, error_model="numpy")  # (no zero-division checks: vectorised)
def _upper(ta, half, prob, work, load):
    """``(g(mid), g'(mid), L, U, X)`` from the state at the absolute time ``ta = phase + mid`` (the
    interval's midpoint), already in ``work`` (:func:`_state`): :func:`_joint`, an upper bound ``U``
    of ``g`` and a margin ``X`` that excludes a zero of ``g'`` on ``[mid - half, mid + half]`` where
    it is positive, both with the high modes' tail split off.

    With the modes ``n <= K`` (their ``g_K``, ``g_K'`` and bound ``L_K`` of ``|g_K''|``) and the
    rest bounded by their energies (``E_n`` the bound of ``sqrt(v^2 + (w q - p_c / w)^2)`` on the
    interval, as in ``L``): ``|q_n| <= |p_c| / w_n^2 + E_n / w_n`` and ``|q_n'| <= E_n``, so
    ``g <= g_K(mid) + (|g_K'(mid)| + L_K h) h + sum_{n > K} |c_n| (|p_c| / w_n^2 + E_n / w_n)``
    and ``|g'| >= |g_K'(mid)| - L_K h - sum_{n > K} |c_n| E_n``. ``U`` is the least bound over
    ``K`` and ``X`` the largest margin (``K = N``: the tests from ``L`` alone). The high modes that
    ring after an impact make ``L`` large, but move the end little and slowly: these bounds prune
    and exclude the intervals that the ones from ``L`` keep.

    ``X`` also holds the second-order margin ``|g'(mid)| - |g''(mid)| h - L3 h^2 / 2`` (``L3`` the
    bound of ``|g'''|`` of :func:`_single`, Taylor's theorem about ``mid``) where the load is smooth
    on the interval: once ``h`` is below the period of the highest mode, it excludes the intervals
    where the end rests nearly still (the plateaus that a contact window of the wave law leaves,
    where ``|g'|`` stays below ``L h`` down to tiny ``h``)."""
    c, absc, w2, d, psup = prob
    q, v, W = work[WK_Q], work[WK_V], work[WK_W]
    eb, above, vabove = work[WK_EB], work[WK_ABOVE], work[WK_VABOVE]
    w, iw, iw2 = W[0], W[1], W[2]
    center, delta = _variation(ta, half, load)
    M = c.size
    grow = math.exp(d * half)
    # above[K]: the tail's bound of |g| over the modes n > K, vabove[K] that of |g'|; eb[n] and
    # l3[n]: mode n's terms of L and L3. First each mode's terms from the bound E_n of its energy
    # on the interval (one square root per mode), in a loop without a carried dependence (so that
    # it is vectorised: its square root and divisions were most of the bound's cost at many
    # modes), then the tails' sums, from the last mode down, in the same order as before.
    ac = abs(center)
    dh = delta * half
    slope = load.p1 if load.kind == 0 else 0.0
    l3 = work[WK_PH1]  # (the scratch of _state's phases, free here)
    for n in range(M):
        vn = v[n, 0]
        flex = w2[n] > 0.0
        wc = w[n]
        r = wc * q[n, 0] - center * iw[n]
        Eb = (math.sqrt(vn * vn + r * r) + dh) * grow
        # eb[n]: |c_n| times the bound of |q_n''|, l3[n]: of |q_n'''|; a mode without stiffness
        # is never in the tail: its tail terms are infinite
        b = delta + (d + wc) * Eb if flex else psup + d * ((abs(vn) + psup * half) * grow)
        eb[n] = absc[n] * b
        l3[n] = absc[n] * (slope + d * b + w2[n] * Eb) if flex else absc[n] * (slope + d * b)
        above[n] = absc[n] * (ac * iw2[n] + Eb * iw[n]) if flex else math.inf
        vabove[n] = absc[n] * Eb if flex else math.inf
    tail = 0.0
    vtail = 0.0
    for n in range(M - 1, -1, -1):
        tn = above[n]
        vt = vabove[n]
        above[n] = tail
        vabove[n] = vtail
        tail += tn
        vtail += vt
    smooth = load.kind == 0 or delta == 0.0  # g'' continuous on the interval
    gK = 0.0
    g1 = 0.0
    g2 = 0.0
    L = 0.0
    L3 = 0.0
    best = math.inf
    margin = -math.inf
    for n in range(M):
        vn = v[n, 0]
        gK += c[n] * q[n, 0]
        g1 += c[n] * vn
        g2 += c[n] * (center - d * vn - w2[n] * q[n, 0])
        L += eb[n]
        L3 += l3[n]
        best = min(best, gK + (abs(g1) + L * half) * half + above[n])
        margin = max(margin, abs(g1) - (L * half + vabove[n]) * (1.0 + 1e-9))
    if smooth:
        margin = max(margin, abs(g1) - (abs(g2) * half + 0.5 * L3 * half * half) * (1.0 + 1e-9))
    return gK, g1, L, best, margin


@numba.njit(cache=CACHE, nogil=True)
def _enclose(phase, a, b, mids, half, limits, best, prob, work, src, phases):
    """The bisection loop of ``certified.enclose_zeros`` (``merge=False``) from the midpoints
    ``mids`` of intervals of half-width ``half``; returns ``(lo, hi, ok, best)``, ``ok`` false where
    the numpy path raises (more than ``max_intervals`` survivors). With ``prune``, the intervals
    where ``g`` stays below ``best`` (raised by each level's samples, as ``_sample_bound``) are
    dropped too (``_numpy_search``'s ``prune``). ``limits = (min_width, max_intervals, atol, prune,
    floor)``, all floats (``prune`` 1.0 or 0.0), so that every caller shares one compilation.
    ``phases``: the four buffers of :func:`admissibility_search`."""
    min_width, max_intervals, atol, prune, floor = limits
    q, v, ck, sk = work[WK_Q], work[WK_V], work[WK_CK], work[WK_SK]
    F = src[SRC_F]
    t0, _, _, _, _, V, _ = F  # the flow (t0, d, p0, k, H, V, kind)
    lam = V[1]  # the folded modes' frequencies
    M = q.shape[0]
    rotate = src[SRC_LOAD].kind == 0  # a Fourier load: the folded modes' phases stepped by rotations
    # the phases cos, sin(lam (t - t0)) at the kept intervals' midpoints (rows parent[i] of C, S)
    # (two pairs of buffers, swapped between levels; given by the caller, who keeps them from one
    # search to the next: fresh arrays cost their page faults at every search)
    C, S, Cn, Sn = phases
    parent = np.empty(0, dtype=np.int64)
    ch = np.empty(M)  # cos, sin(lam half) of the current level
    sh = np.empty(M)
    have = False
    while True:
        n = mids.size
        gs = np.empty(n)
        fs = np.empty(n)
        ls = np.empty(n)
        us = np.empty(n)
        xs = np.empty(n)
        store = rotate and n <= Cn.shape[0]
        for i in range(n):
            ta = phase + mids[i]
            if store:
                ci = Cn[i]
                si = Sn[i]
                if have:  # a child at its parent's midpoint -/+ half: rotate the parent's phases
                    sg = 1.0 if i % 2 else -1.0
                    pc = C[parent[i // 2]]
                    ps = S[parent[i // 2]]
                    for m in range(M):
                        ci[m] = pc[m] * ch[m] - sg * (ps[m] * sh[m])
                        si[m] = ps[m] * ch[m] + sg * (pc[m] * sh[m])
                else:
                    tau = ta - t0
                    for m in range(M):
                        x = lam[m] * tau
                        ci[m] = math.cos(x)
                        si[m] = math.sin(x)
                fourier_column(ta, q, v, np.int64(0), ck, sk, F, ci, si, np.bool_(True))
            else:
                _state(ta, work, src)
            gs[i], fs[i], ls[i], us[i], xs[i] = _upper(ta, half, prob, work, src[SRC_LOAD])
        if prune:
            best = max(best, _sample_bound(mids, gs, fs, atol, floor))
        keep = np.empty(n, dtype=np.bool_)
        nk = 0
        for i in range(n):
            bound = ls[i] * half
            keep[i] = abs(fs[i]) <= bound * (1.0 + 1e-9) + atol + 1e-300 and not xs[i] > atol + 1e-300
            if prune and keep[i]:
                keep[i] = min(gs[i] + (abs(fs[i]) + 0.5 * ls[i] * half) * half, us[i]) >= best
            if keep[i]:
                nk += 1
        kept = np.empty(nk)
        parent = np.empty(nk, dtype=np.int64)
        j = 0
        for i in range(n):
            if keep[i]:
                kept[j] = mids[i]
                parent[j] = i
                j += 1
        mids = kept
        if mids.size == 0 or 2.0 * half <= min_width:
            break
        if mids.size > max_intervals:
            return np.empty(0), np.empty(0), False, best
        half *= 0.5
        have = store
        if have:
            C, Cn = Cn, C
            S, Sn = Sn, S
            for m in range(M):
                x = lam[m] * half
                ch[m] = math.cos(x)
                sh[m] = math.sin(x)
        split = np.empty(2 * mids.size)  # sorted, as the midpoints are and 4 half apart
        for i in range(mids.size):
            split[2 * i] = mids[i] - half
            split[2 * i + 1] = mids[i] + half
        mids = split
    lo = np.empty(mids.size)
    hi = np.empty(mids.size)
    for i in range(mids.size):
        lo[i] = max(mids[i] - half, a)
        hi[i] = min(mids[i] + half, b)
    return lo, hi, True, best


@numba.njit(cache=CACHE, nogil=True)
def _enclose_in(phase, a, b, lo, hi, n0, bounds, best, prob, work, src, phases):
    """``certified.enclose_zeros`` continued from the intervals ``[lo, hi]``, each split into ``n0``
    pieces, down to a 64th of the widest, dropping on the way the pieces where ``g`` stays below
    ``best`` (a lower bound of the largest stationary value, raised by each level's samples as in
    the first enclosure: such a piece cannot hold the largest one). ``bounds = (max_intervals,
    atol, floor)``. Returns ``(lo, hi, ok, best)``."""
    max_intervals, atol, floor = bounds
    width = 0.0
    for i in range(lo.size):
        width = max(width, hi[i] - lo[i])
    x = max(abs(a), abs(b), 1.0)
    if not width > 4.0 * (np.nextafter(x, np.inf) - x) * n0:
        return lo.copy(), hi.copy(), True, best
    half = 0.5 * width / n0
    mids = np.empty(lo.size * n0)
    m = 0
    for i in range(lo.size):
        for j in range(n0):
            mj = lo[i] + half * (2.0 * j + 1.0)
            if mj < hi[i] + half:
                mids[m] = mj
                m += 1
    limits = (width / 64.0, float(max_intervals), atol, 1.0, floor)  # (floats: one type of _enclose)
    return _enclose(phase, a, b, mids[:m].copy(), half, limits, best, prob, work, src, phases)


@numba.njit(cache=CACHE, nogil=True)
def _newton(phase, lo, hi, prob, work, src):
    """``admissibility._newton_stationary``: the same iteration, element by element (an element
    leaves it once converged or out of its interval)."""
    c, w2, d = prob[PB_C], prob[PB_W2], prob[PB_D]
    q, v = work[WK_Q], work[WK_V]
    n = lo.size
    t = np.empty(n)
    ok = np.zeros(n, dtype=np.bool_)
    inside = np.zeros(n, dtype=np.bool_)
    active = np.ones(n, dtype=np.bool_)
    for i in range(n):
        t[i] = 0.5 * (lo[i] + hi[i])
    M = c.size
    for _ in range(8):
        done = True
        for i in range(n):
            if not active[i]:
                continue
            ta = phase + t[i]
            _state(ta, work, src)
            p = _load(ta, src[SRC_LOAD])
            g1 = 0.0
            g2 = 0.0
            for k in range(M):
                g1 += c[k] * v[k, 0]
                g2 += c[k] * (p - d * v[k, 0] - w2[k] * q[k, 0])
            step = g1 / g2 if g2 != 0.0 else math.inf
            if step != step:  # as np.nan_to_num(step, nan=inf)
                step = math.inf
            elif step == math.inf:
                step = _MAXF
            elif step == -math.inf:
                step = -_MAXF
            fin = math.isfinite(step)
            t_new = t[i] - (step if fin else 0.0)
            inside[i] = (t_new >= lo[i]) and (t_new <= hi[i]) and fin
            t[i] = min(max(t_new, lo[i]), hi[i])
            ok[i] = inside[i] and abs(step) < 1e-12
            active[i] = inside[i] and not ok[i]
            if active[i]:
                done = False
        if done:
            break
    return t, ok


@numba.njit(cache=CACHE, nogil=True)
def _value_bounds(phase, lo, hi, prob, work, src):
    """``g`` at the midpoints of ``[lo, hi]`` and its upper bound ``g(mid) + (|g'| + L h / 2) h``
    (Taylor's theorem, ``L`` bounding ``|g''|``)."""
    n = lo.size
    gm = np.empty(n)
    upper = np.empty(n)
    g1 = np.empty(n)
    for i in range(n):
        mid = 0.5 * (lo[i] + hi[i])
        half = 0.5 * (hi[i] - lo[i])
        _state(phase + mid, work, src)
        gm[i], g1[i], L2, ut, _ = _upper(phase + mid, half, prob, work, src[SRC_LOAD])
        upper[i] = min(gm[i] + (abs(g1[i]) + 0.5 * L2 * half) * half, ut)
    return gm, upper, g1


@numba.njit(cache=CACHE, nogil=True)
def _sample_bound(mid, gm, g1, atol, floor):
    """``admissibility._sample_bound``: a lower bound of the largest stationary value from the
    samples ``g(mid), g'(mid)`` at the sorted times ``mid``."""
    a = -1
    b = -1
    for i in range(mid.size):
        if mid[i] > floor:
            if a < 0 and g1[i] > atol:
                a = i
            if g1[i] < -atol:
                b = i
    if a < 0 or b <= a:
        return -math.inf
    top = -math.inf
    for i in range(a, b + 1):
        top = max(top, gm[i])
    return top - atol


@numba.njit(cache=CACHE, nogil=True)
def _single(phase, ts, lo, hi, prob, work, src):
    """``admissibility._numpy_search``'s ``single_zero``: ``|g''(ts)| > L3 r``, so that ``ts`` is
    the only zero of ``g'`` on ``[lo, hi]``."""
    c, absc, w2, d, psup = prob
    q, v = work[WK_Q], work[WK_V]
    mid = 0.5 * (lo + hi)
    half = 0.5 * (hi - lo)
    ta = phase + mid
    _state(ta, work, src)
    center, delta = _variation(ta, half, src[SRC_LOAD])
    if src[SRC_LOAD].kind == 0:
        slope = src[SRC_LOAD].p1
    else:
        if delta != 0.0:  # a jump of the load inside: no certificate
            return False
        slope = 0.0
    M = c.size
    grow = math.exp(d * half)
    L3 = 0.0
    for n in range(M):
        vn = v[n, 0]
        if w2[n] > 0.0:
            wc = math.sqrt(w2[n])
            r = wc * q[n, 0] - center / wc
            Eb = (math.sqrt(vn * vn + r * r) + delta * half) * grow
            t3 = slope + d * (delta + (d + wc) * Eb) + w2[n] * Eb
        else:
            t3 = slope + d * (psup + d * ((abs(vn) + psup * half) * grow))
        L3 += absc[n] * t3
    ta = phase + ts
    _state(ta, work, src)
    p = _load(ta, src[SRC_LOAD])
    g2 = 0.0
    for n in range(M):
        g2 += c[n] * (p - d * v[n, 0] - w2[n] * q[n, 0])
    return abs(g2) > L3 * max(ts - lo, hi - ts)


@numba.njit(cache=CACHE, nogil=True)
def _top(x, k):
    """Indices of the ``k`` largest ``x``, largest first, the first of equal ones first (as
    ``np.argsort(-x, kind="mergesort")[:k]``)."""
    k = min(k, x.size)
    out = np.empty(k, dtype=np.int64)
    taken = np.zeros(x.size, dtype=np.bool_)
    for j in range(k):
        m = -1
        for i in range(x.size):
            if not taken[i] and (m < 0 or x[i] > x[m]):
                m = i
        out[j] = m
        taken[m] = True
    return out


@numba.njit(cache=CACHE, nogil=True)
def _amax(x):
    """``np.max(x)`` of a non-empty ``x`` (a NaN propagates, as there), in a loop: numba's generic
    reduction cost some 0.5 s of CPU time more to compile on a first run."""
    m = x[0]
    for i in range(x.size):
        if math.isnan(x[i]):
            return x[i]
        if x[i] > m:
            m = x[i]
    return m


@numba.njit(cache=CACHE, nogil=True)
def _low(gm, upper):
    """``np.min(2.0 * gm - upper)`` for non-empty arrays of one size (a NaN propagates), in a loop."""
    m = 2.0 * gm[0] - upper[0]
    for i in range(gm.size):
        y = 2.0 * gm[i] - upper[i]
        if math.isnan(y):
            return y
        if y < m:
            m = y
    return m


_BUFFERS = threading.local()


def phase_buffers(M):
    """The four ``(R, M)`` buffers of :func:`admissibility_search` (``R = PHASE_BUDGET // M``),
    kept per thread and reused by every search with ``M`` modes: a search touches only the rows it
    needs, and reused pages cost no page faults (fresh arrays at every bisection, some 3 MiB each,
    cost the wave law's two searches at 1024 modes 10 of their 68 ms)."""
    bufs = getattr(_BUFFERS, "phases", None)
    if bufs is None or bufs[0].shape[1] != M:
        rows = PHASE_BUDGET // max(M, 1)
        bufs = tuple(np.empty((rows, M)) for _ in range(4))
        _BUFFERS.phases = bufs  # (one set per thread: the last M only)
    return bufs


@numba.njit(cache=CACHE, nogil=True)
def admissibility_search(phase, horizon, at_rest, atol, seeds, pieces, floor, prob, phases, src_tuples):
    """The largest stationary value of ``g = u(1, t)`` over ``[0, horizon]`` after the impact at
    ``phase`` (``admissibility._numpy_search`` and ``_stationary_values``, ``rounds = 8``).

    ``prob = (c, absc, w2, d, psup)``: the end's weights and their magnitudes, the squared
    frequencies, the damping and ``sup |p|``. ``src = (load, F, P)``: the load's kernel view
    (:class:`~impactbar.dynamics.compiled_views.LoadKernelView`), the data of the flight's compiled
    Fourier flow (``FourierLoad.flow``'s ``kernel_args``, the argument of
    :func:`~impactbar.dynamics._load_flow.fourier_flow`) and of the piecewise-constant one
    ``(w2, d, nodes, levels, qn, vn)``; the one the load's kind does not use holds placeholders of
    the same types, so that one compilation serves every load. From Python the load view comes as
    the plain tuple ``tuple(view)`` in ``src_tuples`` (numba dispatches it several times faster than
    a named tuple), made a view here (no wrapper kernel: a wrapper compiles its callees' code again).
    ``seeds`` intervals are tried first by the branch and bound (``admissibility.SEEDS``), and an
    interval searched again is split into ``pieces`` (``admissibility.RETRY_PIECES``). ``phases``:
    four arrays of shape ``(R, M)`` (:func:`phase_buffers`), the bisection's store of the folded
    modes' phases; a level of more than ``R`` intervals computes them directly.

    Returns
    -------
    code : int
        0, or 1 where the numpy path raises (the first enclosure does not converge).
    v_max : float
        The largest stationary value (``-inf`` without one), or an upper bound of it.
    err : float
        As ``_stationary_values``'s ``err``.
    """
    src = (LoadKernelView(*src_tuples[SRC_LOAD]), src_tuples[SRC_F], src_tuples[SRC_P])
    c = prob[PB_C]
    M = c.size
    K = src[SRC_LOAD].ks.size
    q = np.empty((M, 1))
    v = np.empty((M, 1))
    ck = np.empty(K)
    sk = np.empty(K)
    # scratch of _upper (the frequencies and their reciprocals, so that the bounds take no
    # division, 1 for a mode without stiffness, where they are not used; the modes' terms of L
    # and the tails' bounds) and of fourier_column (the folded modes' phases; _upper's terms of L3)
    W = np.ones((3, M))
    for n in range(M):
        if prob[PB_W2][n] > 0.0:
            W[0, n] = math.sqrt(prob[PB_W2][n])
            W[1, n] = 1.0 / W[0, n]
            W[2, n] = 1.0 / prob[PB_W2][n]
    work = (q, v, ck, sk, W, np.empty(M), np.empty(M), np.empty(M), np.empty(M), np.empty(M))
    n0 = 64
    half0 = 0.5 * horizon / n0
    mids = np.empty(n0)
    for i in range(n0):
        mids[i] = half0 * (2.0 * i + 1.0)
    lo, hi, good, best = _enclose(phase, 0.0, horizon, mids, half0, (6e-3, 400_000.0, atol, 1.0, floor),
                                  -math.inf, prob, work, src, phases)
    if not good:
        return 1, -math.inf, 0.0
    if at_rest:
        sel = lo > 1e-6
        lo, hi = lo[sel], hi[sel]

    err = 0.0
    gm, upper, g1 = _value_bounds(phase, lo, hi, prob, work, src)
    if lo.size:
        mid = np.empty(lo.size)
        for i in range(lo.size):
            mid[i] = 0.5 * (lo[i] + hi[i])
        best = max(best, _sample_bound(mid, gm, g1, atol, floor))
    for _ in range(8):
        sel = upper >= best
        lo, hi, gm, upper = lo[sel], hi[sel], gm[sel], upper[sel]
        n = lo.size
        if n == 0:
            break
        t = np.empty(n)
        ok = np.zeros(n, dtype=np.bool_)
        vals = np.full(n, -math.inf)
        tried = np.zeros(n, dtype=np.bool_)
        batch = _top(upper, seeds)
        for stage in range(2):
            if stage == 1:
                nb = 0
                for i in range(n):
                    if not tried[i] and upper[i] >= best:
                        nb += 1
                if nb == 0:
                    break
                batch = np.empty(nb, dtype=np.int64)
                nb = 0
                for i in range(n):
                    if not tried[i] and upper[i] >= best:
                        batch[nb] = i
                        nb += 1
            tb, okb = _newton(phase, lo[batch], hi[batch], prob, work, src)
            for j in range(batch.size):
                i = batch[j]
                tried[i] = True
                t[i] = tb[j]
                ok[i] = okb[j]
                if okb[j]:
                    vals[i] = _g(phase, tb[j], c, work, src)
            for j in range(batch.size):
                if okb[j]:
                    best = max(best, vals[batch[j]])
        # the intervals searched again: a found zero whose Taylor bound can still beat the best
        # value (bounds about the zero), an interval where Newton failed (bounds from the midpoint)
        nr = 0
        retry = np.zeros(n, dtype=np.bool_)
        for i in range(n):
            if not tried[i]:
                continue
            if ok[i]:
                mid = 0.5 * (lo[i] + hi[i])
                half = 0.5 * (hi[i] - lo[i])
                _, _, L2 = _joint(phase, mid, half, prob, work, src)
                r = max(t[i] - lo[i], hi[i] - t[i])
                taylor = vals[i] + 0.5 * L2 * r * r
                if taylor > best + atol and not _single(phase, t[i], lo[i], hi[i], prob, work, src):
                    gm[i] = vals[i]
                    upper[i] = taylor
                    retry[i] = upper[i] >= best
            else:
                retry[i] = upper[i] >= best
            if retry[i]:
                nr += 1
        if nr == 0:
            lo = np.empty(0)
            break
        rlo = np.empty(nr)
        rhi = np.empty(nr)
        rgm = np.empty(nr)
        rup = np.empty(nr)
        j = 0
        for i in range(n):
            if retry[i]:
                rlo[j], rhi[j], rgm[j], rup[j] = lo[i], hi[i], gm[i], upper[i]
                j += 1
        lo, hi, good, best = _enclose_in(phase, 0.0, horizon, rlo, rhi, pieces, (20_000.0, atol, floor), best,
                                         prob, work, src, phases)
        if not good:  # a zero of high order: the enclosure no longer shrinks
            top = _amax(rup)
            best = max(best, top)
            err = max(err, top - _low(rgm, rup))
            lo = np.empty(0)
            break
        gm, upper, g1 = _value_bounds(phase, lo, hi, prob, work, src)
    if lo.size:  # rounds exhausted: bound what is left
        top = _amax(upper)
        if top >= best:
            best = top
            err = max(err, top - _low(gm, upper))
    return 0, best, err


# Python calls the search alone: its helpers are link-only (its library holds their machine code)
internal_kernels(globals(), python=("admissibility_search",))
