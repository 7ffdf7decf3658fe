"""Compiled contact window of the wave impact law with separation (theory §4b).

:func:`wave_contact` is the characteristics solution of :class:`impactbar.laws.wave._characteristics._Contact`
and its post-contact projection, step for step, for the loads the simulator's kernel takes (a load of
finitely many harmonics, ``kind = 0``, or a piecewise-constant one, ``kind = 1``): the same scan grid
of the invariant ``A(theta)`` arriving at the rod end, the same tolerance, the same separation and
re-contact searches (Brent's method as :func:`scipy.optimize.brentq`, to ``1e-15``), the same
Gauss-Legendre panels for the waves reflected by the free end. The simulator calls it for the windows
in which contact is lost (:func:`impactbar.laws.wave._window.wave_window` takes the others);
the reference of ``"simulate.wave_separation"`` (:mod:`impactbar.dynamics.implementations`) is the
Python solver, which it is tested against.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..._shared.columns import IV_HI, IV_LO
from ...dynamics.compiled import CACHE, TWO_PI, load_value, propagate_views, sort_head
from ...dynamics.compiled_views import LoadKernelView, ModalBasisView
from ._window import _window_moments, scan_step, window_jumps

#: contact intervals a window may hold before the kernel gives up (the caller then solves it in Python)
MAX_INTERVALS = 256
_MAX_LOOPS = 10_000


@numba.njit(cache=CACHE, nogil=True)
def _trig(a, b, npi, x, sgn):
    """``sum a_n cos(n pi x) + sgn (b_0 (1 - x) + sum_{n >= 1} b_n sin(n pi x))``: ``beta0(x)``
    (``sgn = 1``), ``alpha0(x)`` (-1); ``b_0`` is the static correction's ``(1 - x)`` coefficient
    (:class:`impactbar.laws.wave._characteristics.PistonInvariants`)."""
    acc_c = a[0]
    acc_s = b[0] * (1.0 - x)
    for n in range(1, a.size):
        arg = npi[n] * x
        acc_c += math.cos(arg) * a[n]
        acc_s += math.sin(arg) * b[n]
    return acc_c + sgn * acc_s


@numba.njit(cache=CACHE, nogil=True)
def _trig_int(a, b, npi, x, sgn):
    """``int_0^x alpha0`` (``sgn = 1``) or ``int_0^x beta0`` (``sgn = -1``)."""
    acc_s = 0.0
    acc_c = -b[0] * (x - 0.5 * x * x)
    for n in range(1, a.size):
        arg = npi[n] * x
        acc_s += math.sin(arg) * (a[n] / npi[n])
        acc_c += (math.cos(arg) - 1.0) * (b[n] / npi[n])
    return a[0] * x + acc_s + sgn * acc_c

#: the places in the window ``win`` (:func:`_p`): the load view, the window's start, the wave
#: speed, the jumps, their number, the pieces' levels, their edges, the load's integral at them
W_LOAD, W_T0, W_S, W_JW, W_NJ, W_LW, W_EW, W_CW = range(8)


@numba.njit(cache=CACHE, nogil=True)
def _p(win, u, left):
    """The drive ``P(u) = p(t0 + u/s)``; for a piecewise-constant load the level of the piece holding
    ``u`` between the window's jumps ``jw[:nj]`` (the left one at a jump when ``left``). The window
    ``win = (load, t0, s, jw, nj, lw, ew, cw)``: the load view, the window's start and wave speed,
    its jumps (theta), their number, the levels of its pieces, their edges (time since ``t0``) and
    the running integral of the load at them."""
    load, t0, s, jw, nj, lw = win[W_LOAD], win[W_T0], win[W_S], win[W_JW], win[W_NJ], win[W_LW]
    kind = load.kind
    if kind == 1:
        j = 0
        if left:
            while j < nj and jw[j] < u:
                j += 1
        else:
            while j < nj and jw[j] <= u:
                j += 1
        return lw[j]
    p, dp, ddp = load_value(load, 0.0, t0 + u / s)
    return p


@numba.njit(cache=CACHE, nogil=True)
def _p_int(win, u):
    """``int_0^u P dtheta'``, exact (closed form, or piece by piece); ``win`` as in :func:`_p`."""
    load, t0, s, nj, lw, ew, cw = win[W_LOAD], win[W_T0], win[W_S], win[W_NJ], win[W_LW], win[W_EW], win[W_CW]
    kind, p0, ks, pr, pim = load.kind, load.p0, load.ks, load.pr, load.pim
    tau = u / s
    if kind == 1:
        j = 0
        while j + 1 < nj + 2 and ew[j + 1] <= tau:
            j += 1
        j = min(j, nj)
        return s * (cw[j] + lw[j] * (tau - ew[j]))
    osc = 0.0
    for i in range(ks.size):
        k = ks[i]
        # Re (p_k e^{i k t0} / (i k)) (e^{i k tau} - 1)
        cr = (pr[i] * math.cos(k * t0) - pim[i] * math.sin(k * t0)) / k
        ci = (pr[i] * math.sin(k * t0) + pim[i] * math.cos(k * t0)) / k
        # c = (cr + i ci) / i = ci - i cr ; times (cos(k tau) - 1 + i sin(k tau))
        osc += ci * (math.cos(k * tau) - 1.0) + cr * math.sin(k * tau)
    return s * (p0 * tau + osc)


@numba.njit(cache=CACHE, nogil=True)
def _A(a, b, npi, win, th, left):
    """The invariant arriving at the rod end at ``th``."""
    s = win[W_S]
    if th < 1.0 or (left and th == 1.0):
        return _trig(a, b, npi, 1.0 - th, -1.0)
    u = th - 1.0
    return _trig(a, b, npi, u, 1.0) + 2.0 * _p(win, u, left) / s


@numba.njit(cache=CACHE, nogil=True)
def _Acum(a, b, npi, win, acum1, th):
    """``int_0^th A``."""
    s = win[W_S]
    if th <= 1.0:
        return acum1 - _trig_int(a, b, npi, 1.0 - th, 1.0)
    u = th - 1.0
    return (acum1 + _trig_int(a, b, npi, u, -1.0)
            + 2.0 * _p_int(win, u) / s)


@numba.njit(cache=CACHE, nogil=True)
def _f(mode, base, a, b, npi, win, acum1, x):
    """The root searches' functions: ``A(x-)`` (mode 0) or the gap ``base - Acum(x)`` (mode 1)."""
    if mode == 0:
        return _A(a, b, npi, win, x, np.bool_(True))
    return base - _Acum(a, b, npi, win, acum1, x)


@numba.njit(cache=CACHE, nogil=True)
def _brent(mode, base, a, b, npi, win, acum1, xa, xb):
    """Brent's root of :func:`_f` in ``[xa, xb]`` with ``xtol = rtol = 1e-15``: the algorithm of
    :func:`scipy.optimize.brentq` (100 iterations). Returns ``(root, ok)``."""
    xtol = 1e-15
    rtol = 1e-15
    xpre, xcur = xa, xb
    xblk = 0.0
    fblk = 0.0
    spre = 0.0
    scur = 0.0
    fpre = _f(mode, base, a, b, npi, win, acum1, xpre)
    fcur = _f(mode, base, a, b, npi, win, acum1, xcur)
    if fpre == 0.0:
        return xpre, True
    if fcur == 0.0:
        return xcur, True
    if (fpre < 0.0) == (fcur < 0.0):
        return xcur, False
    for _ in range(100):
        if fpre != 0.0 and fcur != 0.0 and ((fpre < 0.0) != (fcur < 0.0)):
            xblk = xpre
            fblk = fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre = xcur
            xcur = xblk
            xblk = xpre
            fpre = fcur
            fcur = fblk
            fblk = fpre
        delta = 0.5 * (xtol + rtol * abs(xcur))
        sbis = 0.5 * (xblk - xcur)
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur, True
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(spre), 3.0 * abs(sbis) - delta):
                spre = scur
                scur = stry
            else:
                spre = sbis
                scur = sbis
        else:
            spre = sbis
            scur = sbis
        xpre = xcur
        fpre = fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0.0 else -delta
        fcur = _f(mode, base, a, b, npi, win, acum1, xcur)
    return xcur, False


@numba.njit(cache=CACHE, nogil=True)
def _panel_count(lo, hi, h):
    return max(1, int(math.ceil((hi - lo) / h)))


@numba.njit(cache=CACHE, nogil=True)
def _project_free(a, b, npi, win, R, lo, hi, incoming, h, gl, dv, dse):
    """Add the projection of the waves the free rod end reflects on ``[lo, hi]`` (in ``x``) to ``dv``
    (``cos``) and ``dse`` (``sin``): the alpha that left the end free (``incoming``, ``x = 1 - theta``,
    no breaks) or the beta (``x = theta - 1``, panels split at the load's jumps); ``win`` as in
    :func:`_p`, ``gl = (gl_x, gl_w)`` the Gauss-Legendre nodes and weights."""
    s, jw, nj = win[W_S], win[W_JW], win[W_NJ]
    gl_x, gl_w = gl
    M = a.size
    seg_lo = lo
    while seg_lo < hi:
        seg_hi = hi
        if not incoming:
            for i in range(nj):
                if seg_lo < jw[i] < seg_hi:
                    seg_hi = jw[i]
                    break
        width = seg_hi - seg_lo
        if width > 0.0:
            m = _panel_count(seg_lo, seg_hi, h)
            half = 0.5 * width / m
            for pnl in range(m):
                mid = seg_lo + half * (2.0 * pnl + 1.0)
                for g in range(gl_x.size):
                    x = mid + half * gl_x[g]
                    w = half * gl_w[g]
                    if incoming:
                        dal = (1.0 + R) * _trig(a, b, npi, x, -1.0)
                        dbe = 0.0
                    else:
                        dal = 0.0
                        pv = _p(win, x, np.bool_(False))
                        dbe = (1.0 + R) * (_trig(a, b, npi, x, 1.0) + 2.0 * pv / s)
                    wc = 0.5 * (dal + dbe) * w
                    ws = 0.5 * (dbe - dal) * w
                    for n in range(M):
                        arg = npi[n] * x
                        dv[n] += math.cos(arg) * wc
                        dse[n] += math.sin(arg) * ws
        seg_lo = seg_hi


@numba.njit(cache=CACHE, nogil=True)
def wave_contact(load_t, s, R, rate, t0, q, v, gl_x, gl_w, qa, va, contact):
    """The contact window ``[t0, t0 + 2/s]`` of the wave law, separations included (theory §4b),
    under the load ``load_t``, the plain tuple of a
    :class:`~impactbar.dynamics.compiled_views.LoadKernelView` (numba dispatches plain tuples several
    times faster than named tuples; no wrapper kernel: a wrapper compiles its callees' code again).

    Writes the post-contact modal state into ``qa, va`` and the contact intervals (``theta = s (t -
    t0)`` in ``[0, 2]``) into ``contact`` (shape ``(MAX_INTERVALS, 2)``) and returns their number;
    -1 (nothing to trust) when the piston arrives moving away from the rod, a root search fails or
    the intervals overflow: the caller then solves the window in Python.
    """
    load = LoadKernelView(*load_t)
    kind, psup, breaks, levels = load.kind, load.psup, load.breaks, load.levels
    M = q.size
    N = M - 1
    npi = np.empty(M)
    a = np.empty(M)
    b = np.empty(M)
    for n in range(M):
        npi[n] = math.pi * n
        a[n] = v[n] if n == 0 else 2.0 * v[n]
        b[n] = -2.0 * s * npi[n] * q[n]
    b[0] = 0.0
    # -- the load over the window: its jumps (theta), piece levels and running integral (time)
    T = 2.0 / s
    jt = np.empty(0)
    if kind == 1:
        m0 = math.floor(t0 / TWO_PI)
        m1 = math.floor((t0 + T) / TWO_PI)
        jt = np.empty((m1 - m0 + 1) * breaks.size)
        nj = 0
        for m in range(m0, m1 + 1):
            for i in range(breaks.size):
                tj = m * TWO_PI + breaks[i]
                if t0 < tj < t0 + T:
                    jt[nj] = tj
                    nj += 1
        jt = sort_head(jt, np.int64(nj))  # (np.int64: a literal nj would compile sort_head again)
    nj = jt.size
    jw = np.empty(nj)
    ew = np.empty(nj + 2)  # piece edges, time since t0
    ew[0] = 0.0
    for i in range(nj):
        jw[i] = s * (jt[i] - t0)
        ew[i + 1] = jt[i] - t0
    ew[nj + 1] = (t0 + T) - t0
    lw = np.empty(nj + 1)
    cw = np.zeros(nj + 2)
    if kind == 1:
        nb = breaks.size
        for i in range(nj + 1):  # the level at the piece's middle
            tm = t0 + 0.5 * (ew[i] + ew[i + 1])
            ph = tm - TWO_PI * math.floor(tm / TWO_PI)
            j = 0
            while j < nb and breaks[j] <= ph:
                j += 1
            lw[i] = levels[(j - 1) % nb]
            cw[i + 1] = cw[i] + lw[i] * (ew[i + 1] - ew[i])
    else:
        lw[:] = 0.0
    win = (load, t0, s, jw, nj, lw, ew, cw)
    # (flags as np.bool_ / np.int64: a literal True, False, 0 or 1 compiles the callee once per value)
    p_end = _p(win, 0.0, np.bool_(False))  # the static correction
    b[0] = -p_end / s
    for n in range(1, M):
        b[n] += 2.0 * p_end / (s * npi[n])
    scale = 2.0 * psup / s
    for n in range(M):
        scale += abs(a[n]) + abs(b[n])
    tol = 1e-13 * scale
    acum1 = _trig_int(a, b, npi, 1.0, 1.0)
    if _A(a, b, npi, win, 0.0, np.bool_(False)) < -tol:
        return -1
    # -- the scan grid: breaks at 1 and at 1 + the jumps of the first half
    hg = scan_step(N, rate)
    edges = np.empty(nj + 3)
    ne = 0
    edges[ne] = 0.0
    ne += 1
    edges[ne] = 1.0
    ne += 1
    for i in range(nj):
        if jw[i] < 1.0:
            e = 1.0 + jw[i]
            if edges[ne - 1] < e < 2.0:
                edges[ne] = e
                ne += 1
    edges[ne] = 2.0
    ne += 1
    ng = 1
    for i in range(ne - 1):
        ng += max(2, int(math.ceil((edges[i + 1] - edges[i]) / hg)) + 1) - 1
    grid = np.empty(ng)
    isbreak = np.zeros(ng, dtype=np.bool_)
    grid[0] = 0.0
    kk = 1
    for i in range(ne - 1):
        lo, hi = edges[i], edges[i + 1]
        npts = max(2, int(math.ceil((hi - lo) / hg)) + 1)
        step = (hi - lo) / (npts - 1)
        for k in range(1, npts - 1):
            grid[kk] = k * step + lo
            kk += 1
        grid[kk] = hi
        isbreak[kk] = i < ne - 2
        kk += 1
    Ag = np.empty(ng)
    Agl = np.empty(ng)
    for k in range(ng):
        Ag[k] = _A(a, b, npi, win, grid[k], np.bool_(False))
        Agl[k] = Ag[k]
        if isbreak[k]:
            Agl[k] = _A(a, b, npi, win, grid[k], np.bool_(True))
    # -- contact, separation, re-contact
    nc = 0
    th = 0.0
    on = True
    start = 0.0
    for _ in range(_MAX_LOOPS):
        if th >= 2.0:
            break
        k0 = 0
        while k0 < ng and grid[k0] <= th:
            k0 += 1
        if on:
            k = k0
            while k < ng and not (Agl[k] < -tol or Ag[k] < -tol):
                k += 1
            if nc >= contact.shape[0]:
                return -1
            if k == ng:
                contact[nc, IV_LO] = start
                contact[nc, IV_HI] = 2.0
                nc += 1
                th = 2.0
                break
            if not Agl[k] < -tol:  # A jumps below zero at a break
                th_sep = grid[k]
            else:
                lo = max(th, grid[k - 1])
                th_sep = lo
                if _A(a, b, npi, win, lo, np.bool_(False)) > 0.0:
                    th_sep, ok = _brent(np.int64(0), 0.0, a, b, npi, win, acum1, lo, grid[k])
                    if not ok:
                        return -1
            contact[nc, IV_LO] = start
            contact[nc, IV_HI] = th_sep
            nc += 1
            th = th_sep
            on = False
        else:
            base = _Acum(a, b, npi, win, acum1, th)
            k = k0
            while k < ng and base - _Acum(a, b, npi, win, acum1, grid[k]) > 0.0:
                k += 1
            if k == ng:
                th = 2.0
                break
            lo = th if k == k0 else grid[k - 1]
            if k == k0:  # find a point where the gap is open, or call it grazing
                x = 0.5 * (th + grid[k0])
                found = False
                for _i in range(40):
                    if _f(np.int64(1), base, a, b, npi, win, acum1, x) > 0.0:
                        found = True
                        break
                    x = 0.5 * (th + x)
                if not found:  # no gap opened: contact goes on
                    if nc > 0:
                        nc -= 1
                        start = contact[nc, IV_LO]
                    else:
                        start = 0.0
                    on = True
                    th = grid[k0]
                    continue
                lo = x
            ga = _f(np.int64(1), base, a, b, npi, win, acum1, lo)
            gb = _f(np.int64(1), base, a, b, npi, win, acum1, grid[k])
            if ga <= 0.0:
                th_re = lo
            elif gb > 0.0:
                th_re = grid[k]
            else:
                th_re, ok = _brent(np.int64(1), base, a, b, npi, win, acum1, lo, grid[k])
                if not ok:
                    return -1
            th = th_re
            on = True
            start = th_re
    # -- the post-contact state: the contact map and drive, plus the waves the free end reflected
    ic_ = np.zeros((2, M))
    is_ = np.zeros((2, M))
    _window_moments(load, s, rate, t0, jw, gl_x, gl_w, ic_, is_)
    gl = (gl_x, gl_w)
    for n in range(M):
        va[n] = -R * v[n] + (ic_[1, n] - R * ic_[0, n]) / s
        qa[n] = 0.0 if n == 0 else -R * q[n] - (is_[1, n] - R * is_[0, n]) / (s * s * npi[n])
    h = 8.0 / (2.0 * math.pi * (N + 1) + 2.0 * rate + 1.0)
    dv = np.zeros(M)
    dse = np.zeros(M)
    for i in range(nc + 1):  # the gaps between the contact intervals
        ga_ = 0.0 if i == 0 else contact[i - 1, IV_HI]
        gb_ = 2.0 if i == nc else contact[i, IV_LO]
        if gb_ <= ga_:
            continue
        lo, hi = ga_, min(gb_, 1.0)
        if hi > lo:
            _project_free(a, b, npi, win, R, 1.0 - hi, 1.0 - lo, np.bool_(True), h, gl, dv, dse)
        lo, hi = max(ga_, 1.0), gb_
        if hi > lo:
            _project_free(a, b, npi, win, R, lo - 1.0, hi - 1.0, np.bool_(False), h, gl, dv, dse)
    for n in range(M):
        va[n] += dv[n]
        if n > 0:
            qa[n] -= dse[n] / (s * npi[n])
    gap = 0.0
    last_end = contact[nc - 1, IV_HI] if nc > 0 else 0.0
    if last_end < 2.0:
        gap = (_Acum(a, b, npi, win, acum1, last_end)
               - _Acum(a, b, npi, win, acum1, 2.0))
    q0 = -gap / s
    sign = -1.0
    for n in range(1, M):
        q0 -= 2.0 * sign * qa[n]
        sign = -sign
    qa[0] = q0
    return nc


@numba.njit(cache=CACHE, nogil=True)
def _square_wave_residuals(load, B, s, R, c, fund, gl_x, gl_w, phases, out):
    """The wave law's phase residual ``u(1, 2 pi-)`` of a one-impact orbit under a piecewise-constant
    load, for each of ``phases`` into ``out``: the computation of
    :func:`impactbar.laws.wave.periodic.wave_orbit_states` (drive of the window by the panels of
    :func:`~impactbar.laws.wave._window.window_moments`, the flight driven from rest by
    :func:`~impactbar.dynamics._event_loop.propagate_many`, the periodicity conditions solved mode by mode
    with the flight's fundamental matrix ``fund = (p11, p12, p21, p22)``) in the basis ``B`` (its
    ``w2`` and ``d``; a piecewise-constant load has no harmonic response)."""
    p11, p12, p21, p22 = fund
    breaks = load.breaks
    M = B.w2.size
    T = 2.0 / s
    zeros = np.zeros(M)
    ic_ = np.empty((2, M))
    is_ = np.empty((2, M))
    fq = np.empty((M, 1))
    fv = np.empty((M, 1))
    ts = np.empty(1)
    qm = np.empty(M)
    qe = np.empty(M)
    ve = np.empty(M)
    for i in range(phases.size):
        ph = phases[i]
        periods = math.floor((ph + T) / TWO_PI) - math.floor(ph / TWO_PI) + 1
        jumps = np.empty(periods * breaks.size)
        nj = window_jumps(load, s, ph, jumps)
        ic_[:, :] = 0.0
        is_[:, :] = 0.0
        _window_moments(load, s, 0.0, ph, jumps[:nj], gl_x, gl_w, ic_, is_)
        ts[0] = ph + TWO_PI
        propagate_views(load, B, ph + T, zeros, zeros, ts, fq, fv)
        for n in range(M):
            h = (ic_[1, n] - R * ic_[0, n]) / s
            g = 0.0 if n == 0 else -(is_[1, n] - R * is_[0, n]) / (s * s * math.pi * n)
            a11 = 1.0 + R * p11[n]
            a12 = R * p12[n]
            a21 = R * p21[n]
            a22 = 1.0 + R * p22[n]
            det = a11 * a22 - a12 * a21
            r1 = p11[n] * g + p12[n] * h + fq[n, 0]
            r2 = p21[n] * g + p22[n] * h + fv[n, 0]
            qm[n] = (a22 * r1 - a12 * r2) / det
            vm = (a11 * r2 - a21 * r1) / det
            qe[n] = -R * qm[n] + g
            ve[n] = -R * vm + h
        e0 = 0.0
        for n in range(1, M):
            e0 += c[n] * qe[n]
        qm[0] = -e0 + p12[0] * ve[0] + fq[0, 0]
        r = 0.0
        for n in range(M):
            r += c[n] * qm[n]
        out[i] = r


@numba.njit(cache=CACHE, nogil=True)
def square_wave_residuals(load, B, s, R, c, fund, gl_x, gl_w, phases, out):
    """:func:`_square_wave_residuals` called from Python, with ``load`` and ``B`` as plain tuples
    (``tuple(view)``: numba dispatches them several times faster than named tuples)."""
    return _square_wave_residuals(LoadKernelView(*load), ModalBasisView(*B), s, R, c, fund, gl_x, gl_w,
                                  phases, out)

