"""Compiled core of the event-driven simulator (theory §2, §4, §8). Plain float arrays only.

Between events every mode obeys ``q'' + d q' + w2 q = p(t)`` and is advanced in closed form from an
*anchor* (the last impact, or for a piecewise-constant load the last load jump):

- harmonic load (``kind = 0``): ``q = Phi(t - ta) (y_a - y_p(ta)) + y_p(t)`` with the periodic
  particular solution ``y_p = p0/w2 + Re sum_k H_nk p_k exp(i k t)`` (eq. 8); the rigid mode adds
  the mean-load terms ``p0 c(tau)``, ``p0 b(tau)``;
- piecewise-constant load (``kind = 1``): the same with the static deflection ``level / w2`` of
  the current piece; the search stops at every jump and re-anchors there, so nothing is truncated.

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
from ._flightkernel import (  # the closed-form flight and the certified step, below this module
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
    piece_of,
)
from .kernelview import LoadKernelView, ModalBasisView

# statuses of find_crossing
NONE = 0  # no crossing up to t_lim
CROSS = 1  # transversal crossing (or h >= 0 at the start / just after a load jump)
TOUCH = 2  # h reached 0 tangentially with h'' >= 0 (pressing)
FAIL = 3  # too many steps

# statuses of run_free
END = 0
MAXIMP = 1
CHATTER = 2
CONTACT = 3
FULL = 4
FAILED = 5

_MAX_STEPS = 2_000_000


@numba.njit(cache=CACHE, nogil=True)
def flow_scratch(qa, va):
    """The working arrays of a flight from the anchor ``qa, va``, rows of one block (one allocation:
    a short run's fixed cost): copies of ``qa, va``, then ``qp, vp, qpa, vpa`` and two more of the
    same length (``q, v`` of a flow evaluated apart from its start), uninitialised."""
    M = qa.size
    q, v, qp, vp, qpa, vpa, qe, ve = np.empty((8, M))  # its rows
    for n in range(M):
        q[n] = qa[n]
        v[n] = va[n]
    return q, v, qp, vp, qpa, vpa, qe, ve


@numba.njit(cache=CACHE, nogil=True)
def find_crossing(load_t, B_t, wts, alpha, anchor_t, qa, va, t_lim, htol, work):
    """First ``t`` in ``[anchor, t_lim]`` where ``h(t) >= 0`` (see the module docstring), in the
    basis ``B_t`` (the plain tuple of a :class:`~impactbar.dynamics.kernelview.ModalBasisView`)
    under ``load_t`` (that of a :class:`~impactbar.dynamics.kernelview.LoadKernelView`: numba
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


def _run_free(load_t, B_t, R, c, start, t_end, max_imp, tail_tol, out, rigid_fast, modal_fast):
    """Free flight with impacts from ``start = (t, q, v)`` in the free-free basis ``B_t`` (the plain
    tuple of a :class:`~impactbar.dynamics.kernelview.ModalBasisView`) under ``load_t`` (that of a
    :class:`~impactbar.dynamics.kernelview.LoadKernelView`: numba dispatches plain tuples several
    times faster than named tuples); ``q, v`` are overwritten with the final state. Compiled twice
    from this one source, as :func:`run_free` (flexible bars: ``rigid_fast`` is ``None``) and
    :func:`run_free_rigid` (``modal_fast`` is ``None``), each with one signature and no wrapper
    kernel (a wrapper compiles its callees' code again).

    Every impact (``c . q = 0`` reached with ``c . v > 0``) applies ``v -> -R v`` (eqs. 10, 11); its
    time, the arrival velocity ``c . v`` and the state just after are written to
    ``out = (out_t, out_vel, out_q, out_v)``. Stops at
    ``t_end`` (END), after ``max_imp`` impacts (MAXIMP), when the buffers are full (FULL), when the
    bounces accumulate (CHATTER: the returned time is the accumulation point, ``v = 0``; with
    ``R > 0`` tested before the count, so the last impact asked for may end in CHATTER too, its
    bounces summed) or the end arrives tangentially and pressed (CONTACT).

    With ``rigid_fast`` true the flights that follow an impact (or start
    clearly off the stop, or leaving it) are searched by :func:`rigid1_crossing` (the rigid bar under
    one harmonic), with ``modal_fast`` true by :func:`modal_crossing` (flexible modes under a
    Fourier load, all underdamped): the same impacts, to rounding. A flight from rest on the stop (a release),
    where rounding decides whether the end leaves, and every other case are searched by
    :func:`find_crossing`. Either flag may be ``None``: numba then drops that search from the
    compiled code (a rigid run compiles no flexible search, and the other way round).

    Returns
    -------
    n, status, t : int, int, float
    """
    load = LoadKernelView(*load_t)
    B = ModalBasisView(*B_t)
    kind, p0, ks, pr, pim = load.kind, load.p0, load.ks, load.pr, load.pim
    breaks, levels = load.breaks, load.levels
    w2, d, hpr, hpi, vpb = B.w2, B.d, B.hpr, B.hpi, B.vpb
    out_t, out_vel, out_q, out_v = out
    t, q, v = start
    M = w2.size
    qa, va, qp, vp, qpa, vpa, anchor, _ = flow_scratch(q, v)
    anchor[0] = t
    n = 0
    cap = out_t.size
    rigid1 = False
    if rigid_fast is not None:
        rigid1 = rigid_fast and kind == 0 and M == 1 and w2[0] == 0.0 and ks.size <= 1
    k1 = pr1 = pim1 = hr1 = hi1 = 0.0
    if rigid1 and ks.size == 1:
        k1, pr1, pim1, hr1, hi1 = ks[0], pr[0], pim[0], hpr[0, 0], hpi[0, 0]
    habs1 = math.hypot(hr1, hi1)
    h1 = (k1, pr1, pim1, hr1, hi1, habs1)
    qp1 = p1t = 0.0
    work = (q, v, qp, vp, qpa, vpa)
    # the free-free bar under a Fourier load, every flexible mode underdamped: modal_crossing (its
    # data set up only where it is compiled: a rigid run allocates and sums none of it)
    modal = False
    if modal_fast is not None:
        modal = modal_fast and kind == 0 and M > 1 and w2[0] == 0.0
        K = ks.size
        lam, wsq, ca, cb, cva, cvb = np.empty((6, M))  # (one allocation: a short run's fixed cost)
        hcr, hci, hwr, hwi = np.zeros((4, K))
        nq0 = 0.0
        nv0 = 0.0
        for i in range(M):
            lam2 = w2[i] - 0.25 * d * d
            if i > 0 and lam2 <= 0.0:
                modal = False
            lam[i] = math.sqrt(abs(lam2))
            wsq[i] = math.sqrt(w2[i])
            hs = 0.0
            for j in range(ks.size):
                hs += math.hypot(hpr[i, j], hpi[i, j])
            nq0 += 2.0 * abs(c[i]) * (hs + (abs(p0) / w2[i] if i > 0 else 0.0))
            nv0 += 2.0 * abs(c[i]) * vpb[i]
        for i in range(M):
            for j in range(K):
                hcr[j] += c[i] * hpr[i, j]
                hci[j] += c[i] * hpi[i, j]
                hwr[j] += c[i] * w2[i] * hpr[i, j]
                hwi[j] += c[i] * w2[i] * hpi[i, j]
        fold = (lam, wsq, hcr, hci, hwr, hwi, nq0, nv0)
        mwork = (qpa, vpa, ca, cb, cva, cvb)
        anc = (qa, va, qpa, vpa)  # (the arrays are updated in place: the tuples are built once)
        stt = (q, v, qp, vp)
    while True:
        htol = 0.0
        for i in range(M):
            htol += abs(c[i] * qa[i])
        htol *= 1e-14
        # a flight after an impact, or from a start clearly off the stop or leaving it; from a
        # release (or a start) at rest on the stop rounding decides whether the end leaves: those
        # flights take the reference search
        off = n > 0
        if not off and (rigid1 or modal):
            hs = vs = hm = vm = 0.0
            for i in range(M):
                hs += c[i] * qa[i]
                vs += c[i] * va[i]
                hm += abs(c[i] * qa[i])
                vm += abs(c[i] * va[i])
            off = hs < -1e-9 * hm or vs < -1e-9 * vm
        fast1 = rigid1 and off
        st = NONE
        tc = t_end
        if rigid_fast is not None:  # (the branches on None are dropped at compile time)
            if fast1:
                st, tc, q[0], v[0], qp1, p1t = rigid1_crossing(d, c[0], p0, h1, anchor[0], qa[0],
                                                               va[0], t_end, htol)
        if modal_fast is not None:
            if modal and off:
                st, tc = _modal_crossing(load, B, c, fold, anchor[0], qa, va, t_end, htol, mwork)
                # the state there by the reference flow (qpa, vpa hold the anchor's particular state)
                advance(load, B, 0.0, anchor[0], anc, tc, stt)
        if not (fast1 or (modal and off)):
            st, tc = find_crossing(load_t, B_t, c, 0.0, anchor, qa, va, t_end, htol, work)
        if st == NONE:
            return n, END, t_end
        if st == FAIL:
            return n, FAILED, tc
        vend = 0.0
        for i in range(M):
            vend += c[i] * v[i]
        if st == TOUCH or vend <= 0.0:
            return n, CONTACT, tc
        out_t[n] = tc
        out_vel[n] = vend
        g = 0.0
        for i in range(M):
            v[i] = -R * v[i]
            g += c[i] * q[i]
        q[0] -= g  # the end exactly on the stop (a shift of the mean: no energy)
        for i in range(M):
            out_q[n, i] = q[i]
            out_v[n, i] = v[i]
        n += 1
        # With R > 0 the chatter test comes before the count's: the bounces that accumulate after
        # the last impact asked for are its own, not impacts of their own. (R = 0 leaves the end at
        # rest on the stop, no bounce to sum; R < 0: the kernel applies no law, the law's contact
        # step does, one arrival per call.)
        if n >= max_imp and R <= 0.0:
            return n, MAXIMP, tc
        if fast1:  # functional(...) of the rigid bar, term by term
            ddh = c[0] * (p1t - d * v[0])
            noise = 1e-14 * (abs(c[0]) * (abs(q[0]) + abs(qp1)))
        else:
            if kind == 1:
                mm, jj = piece_of(breaks, tc)
                level = levels[jj]
            else:
                level = 0.0
            p, dp, ddp = load_value(load, level, tc)
            h, dh, ddh, noise, dnoise = functional(w2, d, c, 0.0, p, dp, ddp, q, v, qp, vp)
        if ddh > 0.0 and R >= 0.0:  # (R = 0: the end stays on the stop, tail 0)
            # R < 1: the bounces accumulate at tc + tail. R = 1: they do not accumulate, but
            # damping shrinks them without end (ever more impacts per unit time)
            tail = 2.0 * R * vend / ddh / (1.0 - R) if R < 1.0 else math.inf
            # the next bounce is lost in rounding when its height (R v)^2 / (2 h'') is near
            # the noise of c . q: its time and velocity are then noise, so jump (for R = 1 to
            # contact now: bounces below the rounding noise are contact)
            height = 0.5 * (R * vend) ** 2 / ddh
            if tail < tail_tol or height < 1e3 * noise:
                for i in range(M):
                    v[i] = 0.0
                return n, CHATTER, tc + (tail if R < 1.0 else 0.0)
        if n >= max_imp:
            return n, MAXIMP, tc
        if n >= cap:
            return n, FULL, tc
        t = tc
        anchor[0] = tc
        for i in range(M):
            qa[i] = q[i]
            va[i] = v[i]


#: :func:`_run_free` for flexible bars (``run_free(load, B, R, c, (t, q, v), t_end, max_imp,
#: tail_tol, out, None, fast)``: the modal search where ``fast``, no rigid one compiled)
run_free = numba.njit(cache=CACHE, nogil=True)(_run_free)
#: :func:`_run_free` for the rigid bar (``..., fast, None)``: the search in scalars where ``fast``,
#: no flexible search compiled)
run_free_rigid = numba.njit(cache=CACHE, nogil=True)(_run_free)


def _propagate(load_t, B_t, ta, qa, va, ts, out_q, out_v):
    """Exact states at the sorted times ``ts >= ta`` from ``(ta, qa, va)`` into ``out_q, out_v``
    (shape (M, T)); a piecewise-constant load is followed jump by jump, by piece index (no
    rounding of a jump time into the wrong piece). ``load_t`` and ``B_t``: a
    :class:`~impactbar.dynamics.kernelview.LoadKernelView` and a
    :class:`~impactbar.dynamics.kernelview.ModalBasisView`, or their plain tuples. Compiled twice
    from this one source, as :func:`propagate_many` (called from Python with plain tuples: numba
    dispatches them several times faster than named tuples) and ``_propagate_many`` (called from
    compiled code with the views), each with one signature and no wrapper kernel (a wrapper
    compiles its callees' code again)."""
    load = LoadKernelView(*load_t)
    B = ModalBasisView(*B_t)
    kind, breaks = load.kind, load.breaks
    w2 = B.w2
    M = w2.size
    qa, va, qp, vp, qpa, vpa, q, v = flow_scratch(qa, va)
    anchor = (qa, va, qpa, vpa)
    state = (q, v, qp, vp)
    m, j, level = first_piece(load, B, ta, qpa, vpa)
    for i in range(ts.size):
        t = ts[i]
        if kind == 1:
            while True:
                te = piece_end(breaks, m, j)
                if t < te:
                    break
                ta, m, j, level = next_piece(load, B, level, ta, te, m, j, anchor, state)
        advance(load, B, level, ta, anchor, t, state)
        for n in range(M):
            out_q[n, i] = q[n]
            out_v[n, i] = v[n]


#: :func:`_propagate` called from Python (``load`` and ``B`` as plain tuples)
propagate_many = numba.njit(cache=CACHE, nogil=True)(_propagate)
#: :func:`_propagate` called from compiled code (``load`` and ``B`` as the views)
_propagate_many = numba.njit(cache=CACHE, nogil=True)(_propagate)

# the kernels Python calls keep their wrapper and cache entry; the others (the event search's steps,
# the folded search, the flow's scratch, propagate_views) are link-only, for kernels
internal_kernels(globals(), python=("run_free", "run_free_rigid", "find_crossing", "modal_crossing",
                                    "rigid1_crossing", "propagate_many"))
