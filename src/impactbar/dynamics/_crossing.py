"""The certified event search of the compiled simulator (theory §2, §8): the first crossing of the
stop by the struck end in a flight, on plain float arrays (the flight loop that calls it is
:mod:`impactbar.dynamics._event_loop`).

The event search looks for the first ``t`` with ``h(t) = alpha p(t) + sum_n w_n q_n(t) >= 0``
(the end displacement ``c . q`` for an impact; minus the stop reaction for the end of contact).
It is guaranteed: from the exact ``h(a)``, ``h'(a)``, ``h''(a)`` and bounds ``A >= |h''|`` and
``J >= |h'''|`` valid on the whole step, the polynomials ``h(a) + h'(a) s + A s^2 / 2`` and
``h(a) + h'(a) s + h''(a) s^2 / 2 + J s^3 / 6`` bound ``h`` from above, so their first positive
roots are steps that cannot cross ``h = 0``. ``A`` and ``J`` come from the energy of the free part
of each mode, ``E_n = (v_n - v_pn)^2 + w2_n (q_n - q_pn)^2``, which never grows
(``dE/dt = -2 d v^2``). Once ``4 A |h| < h'^2`` the root is bracketed and unique on
``[a, a + 2|h|/h']`` and Newton (safeguarded by bisection) refines it to rounding.

Two specialised searches, with the same guarantee and the same impacts to rounding, take the
flights after an impact (``run_free_rigid``, ``run_free``, with their fast flag true):
:func:`rigid1_crossing` for the rigid bar under one harmonic, in scalars with bounds that keep the
signs of the present curvature, and
:func:`modal_crossing` for flexible modes under a Fourier load, in folded form (one sine and cosine
per mode) with coarse steps on a bound that needs no mode at all. Both refine by Halley steps.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .._shared.wrappers import internal_kernels
from ._flight import (  # the closed-form flight and the certified step, below this module
    CACHE,
    TWO_PI,
    _bc,
    _cubic_step,
    _cubic_step_fast,
    _quadratic_step,
    advance,
    bounds,
    first_piece,
    functional,
    harmonic_sum,
    load_value,
    next_piece,
    particular,
    piece_end,
)
from .compiled_views import LoadKernelView, ModalBasisView

# statuses of find_crossing
NONE = 0  # no crossing up to t_lim
CROSS = 1  # transversal crossing (or h >= 0 at the start / just after a load jump)
TOUCH = 2  # h reached 0 tangentially with h'' >= 0 (pressing)
FAIL = 3  # too many steps

_MAX_STEPS = 2_000_000

#: the rows of :func:`flow_scratch`'s block, by name: a row of a C-ordered block taken by an integer
#: is a C-contiguous array, where unpacking the block (``q, v, ... = blk``) gives arrays of any
#: layout ('A'), and every kernel that Python also calls with plain arrays compiles twice
FS_Q, FS_V, FS_QP, FS_VP, FS_QPA, FS_VPA, FS_QE, FS_VE = range(8)


@numba.njit(cache=CACHE, nogil=True)
def flow_scratch(qa, va):
    """The working arrays of a flight from the anchor ``qa, va``, rows of one block (one allocation:
    a short run's fixed cost): copies of ``qa, va``, then ``qp, vp, qpa, vpa`` and two more of the
    same length (``q, v`` of a flow evaluated apart from its start), uninitialised."""
    M = qa.size
    blk = np.empty((8, M))
    q, v, qp, vp, qpa, vpa = blk[FS_Q], blk[FS_V], blk[FS_QP], blk[FS_VP], blk[FS_QPA], blk[FS_VPA]
    for n in range(M):
        q[n] = qa[n]
        v[n] = va[n]
    return q, v, qp, vp, qpa, vpa, blk[FS_QE], blk[FS_VE]


@numba.njit(cache=CACHE, nogil=True)
def find_crossing(load_t, B_t, wts, alpha, anchor_t, qa, va, t_lim, htol, work):
    """First ``t`` in ``[anchor, t_lim]`` where ``h(t) >= 0`` (see the module docstring), in the
    basis ``B_t`` (the plain tuple of a :class:`~impactbar.dynamics.compiled_views.ModalBasisView`)
    under ``load_t`` (that of a :class:`~impactbar.dynamics.compiled_views.LoadKernelView`: numba
    dispatches plain tuples several times faster than named tuples); ``work = (q, v, qp, vp, qpa,
    vpa)``, arrays of the basis' size. Python and :func:`run_free` call it with the same types: one
    compilation, no wrapper kernel (a wrapper compiles its callees' code again).

    A start with ``0 <= h <= htol`` and ``h' <= 0`` (the end just left the stop) counts as
    ``h = 0``. ``anchor_t[0]`` and ``qa, va`` hold the anchor (the start of the search); for a
    piecewise-constant load they are moved to each load jump passed. On return ``q, v`` hold
    the state at the returned time.

    Returns
    -------
    status, t : int, float
    """
    load = LoadKernelView(*load_t)
    B = ModalBasisView(*B_t)
    q, v, qp, vp, qpa, vpa = work
    kind, p0, psup, breaks = load.kind, load.p0, load.psup, load.breaks
    w2, d = B.w2, B.d
    anchor = (qa, va, qpa, vpa)
    state = (q, v, qp, vp)
    ta = anchor_t[0]
    m, j, level = first_piece(load, B, ta, qpa, vpa)
    a = ta
    advance(load, B, level, ta, anchor, a, state)
    p, dp, ddp = load_value(load, level, a)
    h, dh, ddh, noise, dnoise = functional(w2, d, wts, alpha, p, dp, ddp, q, v, qp, vp)
    L = p0 if kind == 0 else level
    ps = psup if kind == 0 else abs(level)
    if -noise <= h <= htol + noise and abs(dh) <= dnoise and ddh > 0.0:
        # a start on the stop and at rest, both to rounding, and pressed on it: the end stays
        # there. (Left to the steps, a start a rounding error short of the stop flies a hair and
        # returns at a speed of about sqrt(2 |h| h''): a false impact, and with R = 0 the next
        # start is the same again, an endless chain of them.)
        return TOUCH, a
    for _ in range(_MAX_STEPS):
        if h > htol + noise or (h >= 0.0 and dh > dnoise):
            return CROSS, a
        t_cap = t_lim
        if kind == 1:
            te = piece_end(breaks, m, j)
            if te < t_cap:
                t_cap = te
        hcap = t_cap - a
        if hcap <= 0.0:
            if kind == 1 and t_cap < t_lim:
                # move the anchor to the jump and continue with the next level
                ta, m, j, level = next_piece(load, B, level, ta, t_cap, m, j, anchor, state)
                anchor_t[0] = ta
                L = level
                ps = abs(level)
                for n in range(w2.size):
                    qp[n] = qpa[n]
                    vp[n] = vpa[n]
                a = ta
                p, dp, ddp = load_value(load, level, a)
                h, dh, ddh, noise, dnoise = functional(w2, d, wts, alpha, p, dp, ddp, q, v, qp, vp)
                if h > htol + noise or (h >= 0.0 and dh > dnoise):
                    return CROSS, a
                continue
            return NONE, t_lim
        horizon = min(hcap, TWO_PI)
        A, J = bounds(load, B, wts, alpha, ps, L, state, horizon)
        g, dh, bracketed = _bracketed(h, dh, dnoise, A, horizon)
        if bracketed:  # a unique root on [a, a + 2|g|/dh]: safeguarded Newton
            lo, hi, t = _bracket(a, g, dh)
            for _it in range(100):
                advance(load, B, level, ta, anchor, t, state)
                p, dp, ddp = load_value(load, level, t)
                h, dh, ddh, noise, dnoise = functional(w2, d, wts, alpha, p, dp, ddp, q, v, qp, vp)
                lo, hi, t, done = _refine(t, h, -h / dh if dh > 0.0 else 0.0, lo, hi)
                if done:
                    break
            advance(load, B, level, ta, anchor, t, state)
            return CROSS, t
        # the cubic bound h + h' s + h'' s^2/2 + J s^3/6 is far better where h'' < 0 is small
        # (leaving the stop): take the larger of the two certified steps. Both hold only where
        # A and J do, on [a, a + horizon] (the rigid mode's velocity bound grows with the horizon)
        touch, a = _step_on(_quadratic_step(g, dh, A), _cubic_step(g, dh, ddh, J, horizon), a, horizon,
                            hcap, t_cap)
        if touch:  # tangential contact: h = 0, h' = 0 to rounding, and h'' >= 0: pressed on the stop
            return TOUCH, a
        advance(load, B, level, ta, anchor, a, state)
        p, dp, ddp = load_value(load, level, a)
        h, dh, ddh, noise, dnoise = functional(w2, d, wts, alpha, p, dp, ddp, q, v, qp, vp)
    return FAIL, a


@numba.njit(cache=CACHE, nogil=True)
def _bracketed(h, dh, dnoise, A, room):
    """The certified searches' test for a bracketed root (the module docstring): with
    ``g = min(h, 0)`` and a slope within its rounding ``dnoise`` taken as 0, the root is unique on
    ``[a, a + 2|g|/h']`` where ``4 A |g| < h'^2`` (``A >= |h''|`` there) and that interval fits in
    ``room``. Returns ``g, h', bracketed``."""
    g = min(h, 0.0)
    if 0.0 < dh <= dnoise:
        dh = 0.0  # a slope lost in rounding
    return g, dh, dh > 0.0 and 4.0 * A * (-g) < dh * dh and 2.0 * (-g) / dh <= room


@numba.njit(cache=CACHE, nogil=True)
def _bracket(a, g, dh):
    """The bracket ``[a, a + 2|g|/h']`` of :func:`_bracketed` and the Newton point from ``a`` in it."""
    hi = a + 2.0 * (-g) / dh
    t = a - g / dh
    if t > hi:
        t = hi
    return a, hi, t


@numba.njit(cache=CACHE, nogil=True)
def _refine(t, h, step, lo, hi):
    """One safeguarded step (Newton's or Halley's, ``step``) for the root of an increasing ``h``
    bracketed by ``[lo, hi]``, from ``t`` where ``h`` was evaluated: the new bracket, the next point
    (bisection where the step leaves the bracket) and whether the step or the bracket is down to
    rounding, the point then being the root's: the step's end where ``h(t) < 0`` (a rounding error
    past the last ``h < 0``), else ``t``."""
    if h < 0.0:
        lo = t
    else:
        hi = t
    tn = t + step
    if abs(step) <= 1e-15 * (1.0 + abs(t)) or hi - lo <= 4e-16 * (1.0 + abs(t)):
        return lo, hi, tn if h < 0.0 else t, True
    if not (lo < tn < hi):
        tn = 0.5 * (lo + hi)
    return lo, hi, tn, False


@numba.njit(cache=CACHE, nogil=True)
def _halley_step(h, dh, ddh):
    """Halley's step to a root of ``h`` from ``h, h', h''`` (0 where it is not defined)."""
    den = 2.0 * dh * dh - h * ddh
    return -2.0 * h * dh / den if dh > 0.0 and den > 0.0 else 0.0


@numba.njit(cache=CACHE, nogil=True)
def _step_on(tau, tc, a, horizon, hcap, t_cap):
    """The larger of two certified steps ``tau, tc`` from ``a``, at most ``horizon``: ``touch, a``,
    with ``touch`` where the step is down to rounding (a tangential contact; ``a`` unchanged), else
    the step's end, ``t_cap`` where it reaches ``hcap = t_cap - a``."""
    if tc > tau:
        tau = tc
    if tau <= 4e-16 * (1.0 + abs(a)):
        return True, a
    if tau > horizon:
        tau = horizon
    if tau >= hcap:
        return False, t_cap
    return False, a + tau


@numba.njit(cache=CACHE, nogil=True)
def _rigid1_state(d, p0, k, pr, pim, hr, hi, ta, qa, qpa, dv, t):
    """The rigid bar (one mode, ``w2 = 0``) under ``p0 + Re(p_k e^{ikt})`` at ``t`` from the anchor
    ``(ta, qa)`` with ``dv = v_a - v_p(ta)``: ``q, v``, the particular ``q_p, v_p`` and the load
    ``p``. The arithmetic of :func:`advance` and :func:`load_value` for this case, term by term,
    with each transcendental evaluated once."""
    tau = t - ta
    ck = math.cos(k * t)
    sk = math.sin(k * t)
    qp = hr * ck - hi * sk
    vp = -k * (hr * sk + hi * ck)
    b, c = _bc(d, tau)
    ed = math.exp(-d * tau)
    q = qa + (qp - qpa) + dv * b + p0 * c
    v = vp + dv * ed + p0 * b
    p = p0 + (pr * ck - pim * sk)
    return q, v, qp, vp, p


@numba.njit(cache=CACHE, nogil=True)
def rigid1_crossing(d, c0, p0, h1, ta, qa, va, t_lim, htol):
    """:func:`find_crossing` for the end of the rigid bar, ``h = c0 q_0`` (``c0 > 0``), under one
    harmonic ``p = p0 + Re(p_k e^{ikt})`` (``h1 = (k, pr, pim, hr, hi, habs)``: ``p_k = pr + i pim``,
    particular amplitude ``H = hr + i hi``, ``habs = |H|``), in scalars (theory §2, eq. 8 with
    ``N = 0``).

    Between impacts ``q = m(tau) + q_p(t)`` with ``m'' = D e^{-d tau}`` for a constant ``D`` (the
    harmonic particular solution obeys ``q_p'' + d q_p' = p - p0``, so ``p - d v = m'' - k^2 q_p``)
    and ``q_p(t + s) = q_p cos ks + (q_p'/k) sin ks``. From ``1 - cos x <= x^2/2`` and
    ``0 <= x - sin x <= x^3/6`` (``x >= 0``), for every ``s >= 0``::

        q(t + s) <= q + q' s + (max(m'', 0) + k^2 max(-q_p, 0)) s^2/2 + k^2 max(-q_p', 0) s^3/6,

    a bound with the signs of the present curvature in it. Its first root (bounded from below by a
    quadratic) is a step that cannot cross an impact; so is the step of the two-sided bound
    ``|q''| <= |m''| + k^2 |H|`` (``|m''|`` only decreases), and where ``q'' < 0`` (leaving the
    stop) that of the cubic bound of :func:`find_crossing`, with ``|q'''| <= d |m''| + k^3 |H|``.
    Once the root is bracketed (the test of :func:`find_crossing` with the two-sided bound),
    safeguarded Halley steps refine it to rounding from the root of the local quadratic model.

    Returns
    -------
    status, t, q, v, qp, p : int and floats
        As :func:`find_crossing`, with the state ``q, v``, the particular ``q_p`` and the load at
        ``t``.
    """
    k, pr, pim, hr, hi, habs = h1
    ck = math.cos(k * ta)
    sk = math.sin(k * ta)
    qpa = hr * ck - hi * sk
    vpa = -k * (hr * sk + hi * ck)
    dv = va - vpa
    kk = k * k
    a = ta
    q = qa + (qpa - qpa) + dv * 0.0 + p0 * 0.0  # advance(.., ta): the anchor as the kernel has it
    v = vpa + dv * 1.0 + p0 * 0.0
    qp = qpa
    vp = vpa
    p = p0 + (pr * ck - pim * sk)
    for _ in range(_MAX_STEPS):
        h = c0 * q
        dh = c0 * v
        ddh = c0 * (p - d * v)
        noise = 1e-14 * c0 * (abs(q) + abs(qp))
        dnoise = 1e-14 * c0 * (abs(v) + abs(vp))
        if h > htol + noise or (h >= 0.0 and dh > dnoise):
            return CROSS, a, q, v, qp, p
        hcap = t_lim - a
        if hcap <= 0.0:
            return NONE, t_lim, q, v, qp, p
        mpp = p - d * v + kk * qp  # m'' = D e^{-d tau} here, and its rounding
        err = 1e-15 * (abs(p) + d * abs(v) + kk * abs(qp))
        A = c0 * (abs(mpp) + err + kk * habs) * (1.0 + 1e-12)
        g, dh, bracketed = _bracketed(h, dh, dnoise, A, hcap)
        if bracketed:
            # a unique root on [a, a + 2|g|/dh] where h' > 0: safeguarded Halley from the root of
            # the local quadratic model
            lo, hib, tb = _bracket(a, g, dh)
            t = a + _quadratic_step(g, dh, max(ddh, 0.0)) if ddh >= 0.0 else tb
            if not (lo < t <= hib):
                t = tb
            for _it in range(100):
                q, v, qp, vp, p = _rigid1_state(d, p0, k, pr, pim, hr, hi, ta, qa, qpa, dv, t)
                h = c0 * q
                dh = c0 * v
                ddh = c0 * (p - d * v)
                lo, hib, t, done = _refine(t, h, _halley_step(h, dh, ddh), lo, hib)
                if done:
                    break
            if h < 0.0:  # t moved on from the last point evaluated: the state there
                q, v, qp, vp, p = _rigid1_state(d, p0, k, pr, pim, hr, hi, ta, qa, qpa, dv, t)
            return CROSS, t, q, v, qp, p
        horizon = min(hcap, TWO_PI)
        # the signed bound: a quadratic, then its cubic term bounded on [0, S] by a quadratic one
        alpha = c0 * (max(mpp, 0.0) + err + kk * max(-qp, 0.0)) * (1.0 + 1e-12)
        beta = c0 * kk * max(-vp, 0.0) * (1.0 + 1e-12)
        S = min(_quadratic_step(g, dh, alpha), horizon)
        alpha1 = alpha + beta * S / 3.0
        tau = S if beta == 0.0 else min(_quadratic_step(g, dh, alpha1), S)
        if alpha1 > A:  # the two-sided bound's step may be the longer one
            tau = max(tau, _quadratic_step(g, dh, A))
        tc = 0.0
        if ddh < 0.0:
            # the curvature pulls the end away (leaving the stop): the cubic bound with the exact
            # h'' of find_crossing, |h'''| <= c0 (d |m''| + k^3 |H|)
            J = c0 * (d * (abs(mpp) + err) + kk * k * habs) * (1.0 + 1e-12)
            tc = _cubic_step_fast(g, dh, ddh, J, horizon)
        touch, a = _step_on(tau, tc, a, horizon, hcap, t_lim)
        if touch:
            return TOUCH, a, q, v, qp, p
        q, v, qp, vp, p = _rigid1_state(d, p0, k, pr, pim, hr, hi, ta, qa, qpa, dv, a)
    return FAIL, a, q, v, qp, p


@numba.njit(cache=CACHE, nogil=True, inline="always")  # the hot loop of modal_crossing
def _modal_eval(load, B, fold, flight, work, t):
    """``h, h', h''`` of the end ``h = c . q`` at ``t`` in the folded form of the flight from
    ``ta`` (see :func:`modal_crossing`; ``flight = (ta, c0, r0, dv0, csum, sq0, sw0)``), and the
    rigid mode's free velocity ``v_0 - v_p0``."""
    p0, ks, pr, pim = load.p0, load.ks, load.pr, load.pim
    w2, d = B.w2, B.d
    lam, _, hcr, hci, hwr, hwi, _, _ = fold
    ta, c0, r0, dv0, csum, sq0, sw0 = flight
    _, _, ca, cb, cva, cvb = work
    tau = t - ta
    b, c = _bc(d, tau)
    ed = math.exp(-d * tau)
    e = math.exp(-0.5 * d * tau)
    p = p0
    hq = sq0
    hv = 0.0
    hw = sw0
    for j in range(ks.size):
        k = ks[j]
        ck = math.cos(k * t)
        sk = math.sin(k * t)
        p += pr[j] * ck - pim[j] * sk
        hq += hcr[j] * ck - hci[j] * sk
        hv -= k * (hcr[j] * sk + hci[j] * ck)
        hw += hwr[j] * ck - hwi[j] * sk
    fq = 0.0
    fv = 0.0
    fw = 0.0
    if tau == 0.0:  # at the anchor
        for n in range(1, w2.size):
            fq += ca[n]
            fv += cva[n]
            fw += w2[n] * ca[n]
    else:
        for n in range(1, w2.size):
            x = lam[n] * tau
            cs = math.cos(x)
            sn = math.sin(x)
            y = ca[n] * cs + cb[n] * sn
            fq += y
            fv += cva[n] * cs + cvb[n] * sn
            fw += w2[n] * y
    rv = dv0 * ed + p0 * b
    h = c0 * (r0 + dv0 * b + p0 * c) + hq + e * fq
    dh = c0 * rv + hv + e * fv
    ddh = p * csum - d * dh - (hw + e * fw)
    return h, dh, ddh, rv


@numba.njit(cache=CACHE, nogil=True)
def _coarse_eval(d, c0, p0, ks, hcr, hci, sq0, ta, r0, dv0, t):
    """The end's motion without the flexible modes' free vibration at ``t`` (see
    :func:`modal_crossing`): ``G, G', G''`` of ``c0 m(tau) + sum_n c_n q_pn(t)`` and the rigid
    mode's free velocity ``m'``."""
    tau = t - ta
    b, c = _bc(d, tau)
    ed = math.exp(-d * tau)
    hq, hv, h2 = harmonic_sum(sq0, ks, hcr, hci, t)
    rv = dv0 * ed + p0 * b
    return c0 * (r0 + dv0 * b + p0 * c) + hq, c0 * rv + hv, c0 * (p0 - d * rv) + h2, rv


@numba.njit(cache=CACHE, nogil=True)
def _modal_crossing(load, B, c, fold, ta, qa, va, t_lim, htol, work):
    """:func:`find_crossing` for an impact (``h = c . q``) of the free-free bar under a Fourier load
    whose flexible modes are all underdamped, with the flight written once in folded form (theory
    §2, eq. 8): ``q_n = e^{-d tau/2} (a_n cos lam_n tau + b_n sin lam_n tau) + q_pn(t)``, so that
    ``h`` and its derivatives cost one sine and cosine per mode and the particular parts are
    weighted sums (``hcr + i hci = sum_n c_n H_n``, ``hwr + i hwi = sum_n c_n w2_n H_n``) formed
    once per model. The bounds are those of :func:`bounds` with each flexible mode's free energy
    taken at the anchor (it never grows), so they are formed once per flight; the steps and the
    bracket test are those of :func:`find_crossing`, the refinement safeguarded Halley steps.
    Far from an impact the steps are taken on a bound that needs no mode at all:
    ``h <= G + sum_n sqrt(a_n^2 + b_n^2)`` (the flexible modes' free vibration, summed over
    ``n >= 1``, weighted by ``c_n``), with ``G`` the rigid mode's closed form plus the summed
    particular parts, whose derivatives are bounded as in :func:`rigid1_crossing`.
    Per model, ``fold = (lam, wsq, hcr, hci, hwr, hwi, nq0, nv0)``: ``lam_n = sqrt(w2_n - d^2/4)``,
    ``wsq = sqrt(w2)``, and ``nq0``, ``nv0`` the rounding scales ``2 sum_n |c_n| sup |q_pn|`` and
    ``2 sum_n |c_n| sup |v_pn|``; ``work = (qpa, vpa, ca, cb, cva, cvb)``, arrays of length ``M``.

    Returns
    -------
    status, t : int, float
        As :func:`find_crossing`; the caller evaluates the state at ``t``.
    """
    p0, ks, psup, p1 = load.p0, load.ks, load.psup, load.p1
    w2, d, vpb, apb, jpb = B.w2, B.d, B.vpb, B.apb, B.jpb
    lam, wsq, hcr, hci, hwr, hwi, nq0, nv0 = fold
    qpa, vpa, ca, cb, cva, cvb = work
    M = w2.size
    particular(load, B, 0.0, ta, qpa, vpa)
    c0 = c[0]
    r0 = qa[0] - qpa[0]
    dv0 = va[0] - vpa[0]
    csum = c0
    sq0 = 0.0
    sw0 = 0.0
    aflex = 0.0
    jflex = 0.0
    fmax = 0.0
    nq = nq0  # the rounding of h, h': sum |c_n| (|q_n| + |q_pn|) and the same of v, bounded
    nv = nv0
    for n in range(1, M):
        cn = c[n]
        dq = qa[n] - qpa[n]
        dv = va[n] - vpa[n]
        ca[n] = cn * dq
        cb[n] = cn * (0.5 * d * dq + dv) / lam[n]
        cva[n] = cn * dv
        cvb[n] = -cn * (w2[n] * dq + 0.5 * d * dv) / lam[n]
        csum += cn
        sq0 += cn * p0 / w2[n]
        sw0 += cn * p0
        en = math.sqrt(dv * dv + w2[n] * dq * dq)
        wn = wsq[n]
        an = abs(cn)
        aflex += an * ((d + wn) * en + apb[n])
        jflex += an * ((d * (d + wn) + w2[n]) * en + jpb[n])
        nq += abs(ca[n]) + abs(cb[n])
        nv += abs(cva[n]) + abs(cvb[n])
        fmax += math.sqrt(ca[n] * ca[n] + cb[n] * cb[n])
    ac0 = abs(c0)
    # coarse steps: h <= G + fmax, G = c0 m + sum_n c_n q_pn without the free vibration of the
    # flexible modes (|sum_n c_n x_n| <= fmax, their amplitudes only decay): certified steps on the
    # smooth G, at the cost of the rigid bar's, up to where G + fmax may reach 0
    fm = fmax * (1.0 + 1e-12) + 1e-14 * nq
    ag2 = 0.0
    ag3 = 0.0
    for j in range(ks.size):
        x = math.hypot(hcr[j], hci[j])
        ag2 += ks[j] * ks[j] * x
        ag3 += ks[j] * ks[j] * ks[j] * x
    flight = (ta, c0, r0, dv0, csum, sq0, sw0)
    a = ta
    for _ in range(_MAX_STEPS):
        hcap = t_lim - a
        if a > ta and hcap > 0.0:  # (at the anchor h = 0: no room for the coarse bound)
            G, G1, G2, rv = _coarse_eval(d, c0, p0, ks, hcr, hci, sq0, ta, r0, dv0, a)
            G += fm
            if G < -1e-3 * abs(G1):  # h <= G < 0 here: a coarse step
                horizon = min(hcap, TWO_PI)
                mpp = ac0 * abs(p0 - d * rv)  # |c0 m''|, which only decreases
                A = (mpp + ag2) * (1.0 + 1e-12) + 1e-15 * abs(G2)
                J = (d * mpp + ag3) * (1.0 + 1e-12)
                tau = _quadratic_step(G, G1, A)
                tc = _cubic_step_fast(G, G1, G2, J, horizon)
                if tc > tau:
                    tau = tc
                if tau > 4e-16 * (1.0 + abs(a)):
                    a = t_lim if tau >= hcap else a + min(tau, horizon)
                    continue
        h, dh, ddh, rv = _modal_eval(load, B, fold, flight, work, a)
        tau = a - ta
        b, cc = _bc(d, tau)
        noise = 1e-14 * (nq + ac0 * abs(r0 + dv0 * b + p0 * cc))
        dnoise = 1e-14 * (nv + ac0 * abs(rv))
        if h > htol + noise or (h >= 0.0 and dh > dnoise):
            return CROSS, a
        if hcap <= 0.0:
            return NONE, t_lim
        horizon = min(hcap, TWO_PI)
        vmax = abs(rv) + vpb[0] + abs(p0) * horizon
        a0 = psup + d * vmax
        A = ac0 * a0 + aflex
        J = ac0 * (p1 + d * a0) + jflex
        g, dh, bracketed = _bracketed(h, dh, dnoise, A, horizon)
        if bracketed:  # a unique root on [a, a + 2|g|/dh] where h' > 0: safeguarded Halley
            lo, hib, t = _bracket(a, g, dh)
            for _it in range(100):
                h, dh, ddh, rv = _modal_eval(load, B, fold, flight, work, t)
                lo, hib, t, done = _refine(t, h, _halley_step(h, dh, ddh), lo, hib)
                if done:
                    break
            return CROSS, t
        touch, a = _step_on(_quadratic_step(g, dh, A), _cubic_step_fast(g, dh, ddh, J, horizon), a,
                            horizon, hcap, t_lim)
        if touch:
            return TOUCH, a
    return FAIL, a


@numba.njit(cache=CACHE, nogil=True)
def modal_crossing(load, B, c, fold, ta, qa, va, t_lim, htol, work):
    """:func:`_modal_crossing` called from Python, with ``load`` and ``B`` as plain tuples
    (``tuple(view)``: numba dispatches them several times faster than named tuples)."""
    return _modal_crossing(LoadKernelView(*load), ModalBasisView(*B), c, fold, ta, qa, va, t_lim, htol, work)



# the kernels Python calls keep their wrapper and cache entry; the others (the event search's steps,
# the folded search, the flow's scratch) are link-only, for kernels
internal_kernels(globals(), python=("find_crossing", "modal_crossing", "rigid1_crossing"))
