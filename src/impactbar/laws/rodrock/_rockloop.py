"""Compiled blow on the rod and the rock (theory §4d): the loop of
:func:`impactbar.laws.rodrock.blow.rod_rock_blow` with its bit (``_Bit``), step for step the same
arithmetic (the reference is the Python loop, ``use_reference("rock.blow")``).

Bit state ``bs`` (float64, ``BIT_SIZE``): ``p, w, branch, p_max, R_max, p_perm, work``; parameters
``bp`` (``BITP_SIZE``): ``Z, k, k_u, m, feed``; the slots named ``BIT_*``, ``BITP_*`` (and the loop's
``CTRL_*``, ``ACC_*``) in :mod:`impactbar.laws.rodrock._records`.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..._shared.wrappers import internal_kernels, link_only
from ...dynamics.compiled import CACHE
from ._bit import contact_step, damped_flow
from ._records import (
    ACC_ENDED,
    ACC_FA,
    ACC_GA,
    ACC_GAP,
    ACC_HELD,
    ACC_LOSS,
    ACC_STEPS,
    ACC_USHANK,
    ACC_WORK,
    BIT_BRANCH,
    BIT_P,
    BIT_PMAX,
    BIT_PPERM,
    BIT_RMAX,
    BIT_W,
    BIT_WORK,
    BITP_FEED,
    BITP_K,
    BITP_KU,
    BITP_MASS,
    BITP_Z,
    BITREC_FORCE,
    BITREC_PEN,
    CTRL_DT,
    CTRL_FA,
    CTRL_FREE,
    CTRL_GA,
    CTRL_GAP,
    CTRL_HELD,
    CTRL_LOCATE,
    CTRL_QUIET,
    CTRL_STOP,
)

_LOAD, _ELASTIC, _FREE = 0.0, 1.0, 2.0


@numba.njit(cache=CACHE, nogil=True)
def _coeffs(bs, bp):
    if bs[BIT_BRANCH] == _LOAD:
        return bp[BITP_K], 0.0
    if bs[BIT_BRANCH] == _ELASTIC:
        return bp[BITP_KU], bs[BIT_PPERM]
    return 0.0, 0.0


@numba.njit(cache=CACHE, nogil=True)
def _work(bs, bp, p0, p1):
    b, ref = _coeffs(bs, bp)
    return b * (p1 - p0) * (0.5 * (p0 + p1) - ref)


@numba.njit(cache=CACHE, nogil=True)
def _unload(bs, bp):
    bs[BIT_PMAX] = bs[BIT_P]
    bs[BIT_RMAX] = bp[BITP_K] * bs[BIT_P]
    bs[BIT_PPERM] = bs[BIT_PMAX] - bs[BIT_RMAX] / bp[BITP_KU]
    bs[BIT_BRANCH] = _ELASTIC


@numba.njit(cache=CACHE, nogil=True)
def _lift_off(bs, E, Z, T, p0):
    """A massless bit off the rock (``p' = E/Z``): ``(rate, t_hit, tau)``, ``t_hit`` its return to
    ``p_perm`` (inf: none), ``tau`` the sub-step's end, the earlier of ``T`` and ``t_hit``."""
    rate = E / Z
    t_hit = (bs[BIT_PPERM] - p0) / rate if rate > 0.0 and p0 + rate * T >= bs[BIT_PPERM] else math.inf
    return rate, t_hit, min(T, t_hit)


@numba.njit(cache=CACHE, nogil=True)
def _massless_switch(bs, b, ref, E, Z, T, p0):
    """A massless bit on a rock branch (``Z p' = E - b (p - p_ref)``, ``b > 0``): the sub-step's end
    ``tau`` and the branch there, ``(tau, nxt, p_nxt, which, g, lam)``: ``nxt`` the next branch
    (-1: none before ``T``), ``p_nxt`` the penetration of the switch, ``which`` its row of ``bs``
    (``BIT_PMAX`` or ``BIT_PPERM``), ``g = Z p'(0)`` and ``lam = b/Z``."""
    p_inf = E / b + ref
    lam = b / Z
    tau = T
    nxt, p_nxt, which = -1.0, 0.0, 0
    # g = b (p_inf - p0), Z times the rate at p0: the forms below lose nothing to a soft rock's huge
    # p_inf (with p_inf itself, a rock of k = 1e-16 was read as a rigid wall)
    g = E - b * (p0 - ref)
    if bs[BIT_BRANCH] == _ELASTIC:
        if p_inf > bs[BIT_PMAX] >= p0:
            tau_h = -math.log1p(-(bs[BIT_PMAX] - p0) * b / g) / lam
            if tau_h < T:
                tau, nxt, p_nxt, which = tau_h, _LOAD, bs[BIT_PMAX], BIT_PMAX
        elif p_inf < bs[BIT_PPERM] <= p0:
            tau_h = -math.log1p(-(bs[BIT_PPERM] - p0) * b / g) / lam
            if tau_h < T:
                tau, nxt, p_nxt, which = tau_h, _FREE, bs[BIT_PPERM], BIT_PPERM
    return tau, nxt, p_nxt, which, g, lam


@numba.njit(cache=CACHE, nogil=True)
def _massless(bs, bp, E, T):
    Z = bp[BITP_Z]
    b, ref = _coeffs(bs, bp)
    p0 = bs[BIT_P]
    if bs[BIT_BRANCH] == _LOAD and E - b * p0 < 0.0:
        _unload(bs, bp)
        return 0.0
    if b == 0.0:
        rate, t_hit, tau = _lift_off(bs, E, Z, T, p0)
        p1 = bs[BIT_PPERM] if tau == t_hit else p0 + rate * tau
        bs[BIT_P] = p1
        if tau == t_hit:
            bs[BIT_BRANCH] = _ELASTIC
        bs[BIT_W] = rate
        return tau
    tau, nxt, p_nxt, _, g, lam = _massless_switch(bs, b, ref, E, Z, T, p0)
    if nxt < 0.0:
        p1 = p0 + g / Z * (-math.expm1(-lam * tau)) / lam
    else:
        p1 = p_nxt
    bs[BIT_WORK] += _work(bs, bp, p0, p1)
    bs[BIT_P] = p1
    bs[BIT_W] = (E - b * (p1 - ref)) / Z
    if nxt >= 0.0:
        bs[BIT_BRANCH] = nxt
    return tau


#: The bit's flow on a rock branch (:func:`impactbar.laws.rodrock._bit.damped_flow`, compiled link-only).
_damped = link_only(numba.njit(cache=CACHE, nogil=True)(damped_flow))


@numba.njit(cache=CACHE, nogil=True)
def _overdamped(b, m, half, delta, tau):
    """``expm1(lam_1 tau)/lam_1`` and ``expm1(lam_2 tau)/lam_2`` of an overdamped bit's two
    eigenvalues (``lam_1 = (b/m)/lam_2`` without cancellation)."""
    lam1, lam2 = b / m / (half - delta), half - delta
    f1 = math.expm1(lam1 * tau) / lam1 if lam1 * tau != 0.0 else tau
    return f1, math.expm1(lam2 * tau) / lam2


@numba.njit(cache=CACHE, nogil=True)
def _flow(bs, bp, E, tau):
    b, ref = _coeffs(bs, bp)
    Z, m = bp[BITP_Z], bp[BITP_MASS]
    if b == 0.0:
        w_inf = E / Z
        decay = math.exp(-Z * tau / m)
        p = bs[BIT_P] + w_inf * tau + (bs[BIT_W] - w_inf) * (m / Z) * (-math.expm1(-Z * tau / m))
        return p, w_inf + (bs[BIT_W] - w_inf) * decay
    p_eq = ref + E / b
    x0, w0 = bs[BIT_P] - p_eq, bs[BIT_W]
    half = -Z / (2.0 * m)
    C, S, delta = _damped(b, m, half, tau)
    if delta > 0.5 * abs(half):
        # overdamped: p - p0 = g/(m 2 delta) (expm1(lam_1 t)/lam_1 - expm1(lam_2 t)/lam_2) + S w0 with
        # g = E - b (p0 - p_ref), without p_eq, which a soft rock makes huge (with it, a rock of
        # k = 1e-16 was read as a rigid wall)
        g = E - b * (bs[BIT_P] - ref)
        f1, f2 = _overdamped(b, m, half, delta, tau)
        return bs[BIT_P] + g / m * (f1 - f2) / (2.0 * delta) + S * w0, C * w0 + S * (g / m + half * w0)
    x = C * x0 + S * (-half * x0 + w0)
    w = C * w0 + S * (-b / m * x0 + half * w0)
    return p_eq + x, w


@numba.njit(cache=CACHE, nogil=True)
def _event(bs, p, w):
    if bs[BIT_BRANCH] == _LOAD:
        return w
    if bs[BIT_BRANCH] == _ELASTIC:
        return min(bs[BIT_PMAX] - p, p - bs[BIT_PPERM])
    return bs[BIT_PPERM] - p


@numba.njit(cache=CACHE, nogil=True)
def _switch_time(bs, bp, E, T):
    """A bit with mass on its branch for at most ``T``: ``(tau, hit)``, the first branch change
    (``_event`` turning negative; ``hit``) bracketed on samples that catch every one (4 for a
    non-oscillating flow, more per half period otherwise) and bisected to rounding, else ``T``."""
    b, _ = _coeffs(bs, bp)
    half = bp[BITP_Z] / (2.0 * bp[BITP_MASS])
    disc = half * half - b / bp[BITP_MASS]
    n = 4 if disc >= 0.0 else 4 + math.ceil(4.0 * math.sqrt(-disc) * T / math.pi)
    taus = np.linspace(0.0, T, n + 1)
    prev = 0.0
    for i in range(1, n + 1):
        t = taus[i]
        p, w = _flow(bs, bp, E, t)
        if _event(bs, p, w) < 0.0:
            lo, hi = prev, t
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                pm, wm = _flow(bs, bp, E, mid)
                if _event(bs, pm, wm) < 0.0:
                    hi = mid
                else:
                    lo = mid
            return hi, True
        prev = t
    return T, False


@numba.njit(cache=CACHE, nogil=True)
def _branch_after(bs, p1):
    """The branch a bit with mass enters from a rock branch other than loading at its switch at
    ``p1``: loading again past ``p_max``, else off the rock; off it, onto the elastic branch."""
    if bs[BIT_BRANCH] == _ELASTIC:
        bs[BIT_BRANCH] = _LOAD if p1 >= bs[BIT_PMAX] else _FREE
    else:
        bs[BIT_BRANCH] = _ELASTIC


@numba.njit(cache=CACHE, nogil=True)
def _with_mass(bs, bp, E, T):
    if bs[BIT_BRANCH] == _LOAD and bs[BIT_W] < 0.0:
        _unload(bs, bp)
        return 0.0
    if bs[BIT_BRANCH] == _ELASTIC and bs[BIT_P] >= bs[BIT_PMAX] and bs[BIT_W] > 0.0:
        bs[BIT_BRANCH] = _LOAD
        return 0.0
    p0 = bs[BIT_P]
    tau, hit = _switch_time(bs, bp, E, T)
    p1, w1 = _flow(bs, bp, E, tau)
    bs[BIT_WORK] += _work(bs, bp, p0, p1)
    bs[BIT_P], bs[BIT_W] = p1, w1
    if hit:
        if bs[BIT_BRANCH] == _LOAD:
            _unload(bs, bp)
        else:
            _branch_after(bs, p1)
    return tau


@numba.njit(cache=CACHE, nogil=True)
def bit_step(bs, bp, E, dt):
    """Advance the bit by ``dt`` under ``E = 2 F + f`` (``_Bit.step``)."""
    left = dt
    for _ in range(64):
        if left <= 0.0:
            break
        if bp[BITP_MASS] == 0.0:
            left -= _massless(bs, bp, E, left)
        else:
            left -= _with_mass(bs, bp, E, left)


#: The piston-shank contact over one step (:func:`impactbar.laws.rodrock._bit.contact_step`), link-only.
_contact_step = link_only(numba.njit(cache=CACHE, nogil=True)(contact_step))


@numba.njit(cache=CACHE, nogil=True)
def piston_free(F, G, Z, n_p, bs, bp, dt):
    """Whether the blow under a drive is over after a step out of contact (theory §11, "when the
    coupled blow ends"; the exact blow's certificate under a drive): the piston's momentum
    ``sum (F - G) / (s n_p)`` over its cells ``<= 0`` (from then on its course is the drive's), and
    the rock not loading: with a feed that is all (the exact blow's ``"may_yield"``), without one
    the energy of rod, bit and rock ``Psi`` below ``R_max^2 / (2 k_u)``, which it would need to
    yield again."""
    if bs[BIT_BRANCH] == _LOAD:
        return False
    momentum = 0.0
    for j in range(n_p):
        momentum += F[j] - G[j]
    if momentum > 0.0:
        return False
    f, ku = bp[BITP_FEED], bp[BITP_KU]
    if f > 0.0:
        return True
    b, ref = _coeffs(bs, bp)
    R = max(b * (bs[BIT_P] - ref), 0.0)
    psi = 0.5 * bp[BITP_MASS] * bs[BIT_W] * bs[BIT_W] + R * R / (2.0 * ku)
    for j in range(n_p, F.size):
        psi += (F[j] * F[j] + G[j] * G[j]) / Z[j] * dt
    return psi < bs[BIT_RMAX] * bs[BIT_RMAX] / (2.0 * ku)


@numba.njit(cache=CACHE, nogil=True)
def blow_loop(F, G, Z, bounds, bs, bp, ctrl, drive, junc, bitrec, field, acc):
    """The blow's loop (``rod_rock_blow``). ``bounds`` (int): the cell right of each segment
    boundary, the shank first; ``ctrl`` (slots ``CTRL_*``): ``dt, energy_stop, quiet, gap, free,
    locate`` and the waves at the contact the step before (end once separated for ``quiet`` steps,
    0: never; the piston-shank gap at the start; 1: end where the piston is free for good,
    :func:`piston_free`, ``ended`` 2; 1: the contact's switches inside their steps,
    :func:`~impactbar.laws.rodrock._bit.contact_step`); ``drive`` (n_max,): the drive's
    force on the piston's far end, averaged over each step; ``junc`` (n_max, J): forces at the
    boundaries per step; ``bitrec`` (n_max + 1, 2): rock force and penetration; ``field``
    (n_max, cells) or (0, cells); ``acc`` out: ``u_shank, grid_loss, steps, ended, gap,
    drive_work`` and the waves at the contact on the last step. Returns nothing; ``F``, ``G`` hold
    the final waves."""
    dt, stop, quiet = ctrl[CTRL_DT], ctrl[CTRL_STOP], ctrl[CTRL_QUIET]
    n_cells = F.size
    n_p = bounds[0]
    jc = n_p - 1
    feed, m = bp[BITP_FEED], bp[BITP_MASS]
    Zl = Z[n_cells - 1]
    gap = ctrl[CTRL_GAP]
    contact = gap <= 0.0
    locate = ctrl[CTRL_LOCATE] > 0.0
    held, fprev, gprev = ctrl[CTRL_HELD] > 0.0, ctrl[CTRL_FA], ctrl[CTRL_GA]
    free = ctrl[CTRL_FREE] > 0.0  # (a driven blow's stretch: its contact was before it)
    last = 0 if contact or free else -1  # the last step in contact (-1: none yet; no end before one)
    u_shank, grid_loss, work = 0.0, 0.0, 0.0
    N = np.empty(n_cells - 1)
    Fn = np.empty(n_cells)
    Gn = np.empty(n_cells)
    b0, _ = _coeffs(bs, bp)
    bitrec[0, BITREC_FORCE] = b0 * bs[BIT_P]
    bitrec[0, BITREC_PEN] = bs[BIT_P]
    n_max = junc.shape[0]
    steps, ended = n_max, 0.0
    for step in range(n_max):
        for j in range(n_cells - 1):
            za, zb = Z[j], Z[j + 1]
            N[j] = (2.0 * zb * F[j] + 2.0 * za * G[j + 1]) / (za + zb)
        fa, ga = F[jc], G[jc + 1]
        f_next = N[jc - 1] - G[jc] if jc > 0 else drive[step] - G[0]  # (the waves arriving next)
        g_next = N[jc + 1] - F[jc + 1] if jc + 2 < n_cells else ga
        N[jc], gap, contact = _contact_step(Z[jc], Z[jc + 1], N[jc], fa, ga, (fprev, gprev),
                                            (f_next, g_next), gap, contact, locate, held, dt)
        fprev, gprev, held = fa, ga, True
        for j in range(n_cells - 1):
            Fn[j + 1] = N[j] - G[j + 1]
            Gn[j] = N[j] - F[j]
        pd = drive[step]
        Fn[0] = pd - G[0]  # the driven far end: N = p
        work += pd * (pd - 2.0 * G[0]) / Z[0] * dt
        Fi = F[n_cells - 1]
        p0, work0, ke0 = bs[BIT_P], bs[BIT_WORK], 0.5 * m * bs[BIT_W] * bs[BIT_W]
        bit_step(bs, bp, 2.0 * Fi + feed, dt)
        g_avg = Fi - Zl * (bs[BIT_P] - p0) / dt
        Gn[n_cells - 1] = g_avg
        e_in = (bs[BIT_WORK] - work0) - feed * (bs[BIT_P] - p0) + 0.5 * m * bs[BIT_W] * bs[BIT_W] - ke0
        grid_loss += (Fi * Fi - g_avg * g_avg) * dt / Zl - e_in
        u_shank += (Fn[jc + 1] - G[jc + 1]) / Z[jc + 1] * dt
        for i in range(bounds.size):
            junc[step, i] = N[bounds[i] - 1]
        b, ref = _coeffs(bs, bp)
        bitrec[step + 1, BITREC_FORCE] = max(b * (bs[BIT_P] - ref), 0.0)
        bitrec[step + 1, BITREC_PEN] = bs[BIT_P]
        if field.shape[0] > 0:
            for j in range(n_cells):
                field[step, j] = F[j] + G[j]
        for j in range(n_cells):
            F[j] = Fn[j]
            G[j] = Gn[j]
        if contact:
            last = step
        elif last < 0:
            pass
        elif quiet > 0.0 and step - last >= quiet:
            steps, ended = step + 1, 2.0
            break
        elif free and piston_free(F, G, Z, n_p, bs, bp, dt):
            steps, ended = step + 1, 2.0
            break
        if not contact and last >= 0 and step % 8 == 0:
            rod_e = 0.0
            for j in range(n_p, n_cells):
                rod_e += (F[j] * F[j] + G[j] * G[j]) / Z[j]
            if rod_e * dt + 0.5 * m * bs[BIT_W] * bs[BIT_W] < stop:
                steps, ended = step + 1, 1.0
                break
    acc[ACC_USHANK], acc[ACC_LOSS], acc[ACC_STEPS] = u_shank, grid_loss, steps
    acc[ACC_ENDED], acc[ACC_GAP], acc[ACC_WORK] = ended, gap, work
    acc[ACC_HELD], acc[ACC_FA], acc[ACC_GA] = 1.0 if held else 0.0, fprev, gprev


internal_kernels(globals(), python=("blow_loop", "piston_free"))  # the others: link-only (kernels call them)
