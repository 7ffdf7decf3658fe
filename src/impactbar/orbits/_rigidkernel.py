"""The rigid bar's closed forms (:mod:`impactbar.orbits.rigid`) compiled, point by point over
parameter arrays: what a sweep's chunk of thousands of points needs.

The vectorised numpy closed forms of :mod:`impactbar.orbits.rigid` (the reference of the switch
``"orbits.rigid_arrays"``, :mod:`impactbar.dynamics.implementations`) make some fifty passes over
temporary arrays per call, and their bracketed zero search iterates every orbit until the slowest
has converged. These kernels take the formulas of :mod:`impactbar.orbits._rigid_scalar` (one point
in plain floats, line by line the same as the vectorised ones) and run them in one compiled loop
over the points, writing each orbit's fields straight into the result's arrays. The tests hold them
to the numpy closed forms and to the general path (``tests/dynamics/test_fast_paths.py``).

Sources: the phase equation (eq. 14, theory §4), the stationary points of the end's displacement
arc by arc (theory §5), the 2 x 2 impact-map Jacobian (theory §7), the paper's rigid block (eqs. 29,
30, theory §6). Imported lazily: a single ``periodic_orbits`` call on a rigid bar loads no numba.
"""

from __future__ import annotations

import cmath
import math

import numba
import numpy as np

from ..dynamics._flightkernel import sort_head
from ..dynamics._kernel import CACHE
from .stability import MARGINAL

TWO_PI = 2.0 * math.pi
INF = math.inf
NAN = math.nan

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")


@numba.njit(**_JIT)
def _b(d, t):
    """``b(t) = (1 - exp(-d t)) / d`` (``t`` at ``d = 0``)."""
    y = d * t
    if abs(y) < 1e-8:
        return t * (1.0 - 0.5 * y)
    return -math.expm1(-y) / d


@numba.njit(**_JIT)
def _c(d, t):
    """``c(t) = (t - b(t)) / d`` (``t^2/2`` at ``d = 0``), by its series where it cancels."""
    y = d * t
    if abs(y) < 1e-2:
        return t * t * (0.5 - y / 6.0 + y * y / 24.0 - y**3 / 120.0 + y**4 / 720.0)
    return (t - (-math.expm1(-y) / d)) / d


@numba.njit(**_JIT)
def _G(d, R):
    """``G(d, R)`` of the phase equation (eq. 14, theory §4)."""
    y = TWO_PI * d
    if y < 1e-2:
        beta = 0.5 + y / 12.0 - y**3 / 720.0 + y**5 / 30240.0
    else:
        beta = 1.0 / (-math.expm1(-y)) - 1.0 / y
    return TWO_PI * ((1.0 + R) * beta - R)


@numba.njit(**_JIT)
def _sign(x):
    if x > 0.0:
        return 1.0
    if x < 0.0:
        return -1.0
    if x == 0.0:
        return 0.0
    return NAN


@numba.njit(**_JIT)
def _assemble(d, R, p0, psup, v_plus, v_minus, p_plus, p_minus, V_phase, ng, gmax):
    """One orbit's flags, clearance, multipliers and the paper's block from its states and the
    largest value ``gmax`` of ``u(1, .)`` at the ``ng`` zeros of its velocity: ``(ok, status,
    clearance, clearance_error, mu0, mu1, schur0, schur1, schur_stable, stable)``, ``ok`` false
    for a degenerate orbit (arrival or departure nearly at rest), which the general path takes."""
    scale = max(abs(v_minus), psup, 1e-300)
    acc0 = p_plus - d * v_plus
    r0 = R == 0.0
    if (not abs(v_minus) > 1e-6 * scale or (r0 and not abs(acc0) > 1e-6 * scale)
            or (not r0 and not abs(v_plus) > 1e-6 * scale)):
        return (False, 0, 0.0, 0.0, complex(0.0, 0.0), complex(0.0, 0.0), complex(0.0, 0.0),
                complex(0.0, 0.0), False, False)
    clearance = gmax if ng > 0 else -INF
    gabs = abs(clearance) if ng > 0 else 0.0
    err = 1e-12 * (scale + gabs)
    tol = max(err, 1e-11 * scale)
    status = 0
    if clearance >= -tol:
        status = 2
    if clearance > tol:
        status = 1
    if r0 and not acc0 < 0.0:
        status = 4
    if not v_minus > 1e-12 * scale:
        status = 2 if abs(v_minus) <= 1e-12 * scale else 3
    # the Floquet multipliers: the 2 x 2 impact-map Jacobian (theory §7 with N = 0)
    if not abs(v_minus) > 1e-14 * abs(v_minus):  # grazing: the saltation term is infinite
        mu0 = complex(INF, 0.0)
        mu1 = complex(INF, 0.0)
    else:
        b = _b(d, TWO_PI)
        e = math.exp(-TWO_PI * d)
        a_p = p_plus - d * v_plus
        a_m = p_minus - d * v_minus
        r0_ = (v_plus + b * a_p) / v_minus
        r1_ = -b / v_minus
        j10 = -R * (-e * a_p + a_m * r0_)
        j11 = -R * (e + a_m * r1_)
        half_tr = 0.5 * (r0_ + j11)
        det = r0_ * j11 - r1_ * j10
        disc = cmath.sqrt(complex(half_tr * half_tr - det, 0.0))
        big = half_tr + (1.0 if half_tr >= 0.0 else -1.0) * disc
        small = det / big if big != 0.0 else complex(0.0, 0.0)
        m0, m1 = abs(big), abs(small)
        tie = abs(m1 - m0) <= 1e-12 * max(m0, m1)
        if (not tie and m1 > m0) or (tie and small.imag > big.imag):
            mu0, mu1 = small, big
        else:
            mu0, mu1 = big, small
    # the paper's rigid block (eqs. 29, 30) with sigma = 0, multiplied through by p0
    e2 = math.exp(-TWO_PI * d)
    S2 = p_plus - p0 - d * V_phase
    y = TWO_PI * d
    factor = 1.0 - 0.5 * y if y < 1e-8 else -math.expm1(-y) / y
    a2 = p0
    a1 = -(1.0 + R * R * e2) * p0 - factor * (1.0 + R) ** 2 * S2
    a0 = R * e2 * (R * p0)
    disc = cmath.sqrt(complex(a1 * a1 - 4.0 * a2 * a0, 0.0))
    sgn = 1.0 if a1 * disc.real >= 0.0 else -1.0
    qq = -0.5 * (a1 + sgn * disc)
    s0 = qq / a2 if a2 != 0.0 else complex(INF, 0.0)
    s1 = a0 / qq if qq != 0.0 else complex(0.0, 0.0)
    schur_ok = abs(a0) < abs(a2) and abs(a1) < abs(a0 + a2)
    stable = status == 0 and abs(mu0) < 1.0 - MARGINAL and abs(mu1) < 1.0 - MARGINAL
    return True, status, clearance, err, mu0, mu1, s0, s1, schur_ok, stable


@numba.njit(inline="always", **_JIT)
def _store(out, i, j, phase, mult, v_minus, v_plus, q_minus, orbit):
    """Write orbit ``j`` of point ``i`` (``orbit``, from :func:`_assemble`) into ``out``, the fields
    of ``RigidOrbits`` in order (straight-line code: inlined, its references cost nothing)."""
    out[1][i, j] = phase
    out[2][i, j] = mult
    out[3][i, j] = v_minus
    out[4][i, j] = v_plus
    out[5][i, j] = q_minus
    out[6][i, j] = orbit[1]
    out[7][i, j] = orbit[2]
    out[8][i, j] = orbit[3]
    out[9][i, j, 0] = orbit[4]
    out[9][i, j, 1] = orbit[5]
    out[10][i, j, 0] = orbit[6]
    out[10][i, j, 1] = orbit[7]
    out[11][i, j] = orbit[8]
    out[12][i, j] = orbit[9]


# ------------------------------------------------------------------------------------------------
# the cosine load p0 + pk cos(k t)
# ------------------------------------------------------------------------------------------------
@numba.njit(**_JIT)
def _velocity(t, ph, k, ca, cb, p0, d, free):
    x = k * (ph + t)
    return ca * math.cos(x) + cb * math.sin(x) + p0 * _b(d, t) + free * math.exp(-d * t)


@numba.njit(**_JIT)
def _displacement(t, ph, k, ca, cb, p0, d, free, W0):
    x = k * (ph + t)
    return (ca * math.sin(x) - cb * math.cos(x)) / k - W0 + p0 * _c(d, t) + free * _b(d, t)


@numba.njit(**_JIT)
def _cosine_zero(flight, a, b, fa, va, vb):
    """The zero of the velocity of the flight ``(ph, k, ca, cb, p0, pk, d, free)`` in ``[a, b]``
    (``sign v(a) = fa``, one zero inside, ``va``, ``vb`` the velocities at the ends): Halley steps
    with ``v' = p - d v`` and ``v'' = p' - d v'`` (the load's cosine and sine are computed for
    ``v`` anyway) from the secant's zero, safeguarded by bisection; the same zero as
    ``_rigid_scalar``'s Newton steps from the middle."""
    ph, k, ca, cb, p0, pk, d, free = flight
    t = a + (b - a) * (va / (va - vb))
    if not a < t < b:
        t = 0.5 * (a + b)
    for _ in range(60):
        x = k * (ph + t)
        cx, sx = math.cos(x), math.sin(x)
        v = ca * cx + cb * sx + p0 * _b(d, t) + free * math.exp(-d * t)
        v1 = p0 + pk * cx - d * v  # v' = p - d v
        v2 = -pk * k * sx - d * v1  # v'' = p' - d v'
        if _sign(v) == fa:
            a = t
        else:
            b = t
        den = 2.0 * v1 * v1 - v * v2
        if den == 0.0 or v1 == 0.0:
            t = 0.5 * (a + b)
            continue
        newton = 2.0 * v * v1 / den  # Halley's step: no transcendental beyond Newton's
        tn = t - newton
        if abs(newton) <= 1e-13 * (1.0 + abs(t)):
            return tn
        t = tn if a <= tn <= b else 0.5 * (a + b)
    return t


@numba.njit(**_JIT)
def cosine_orbits(d, R, p0, pk, k, out):
    """Every one-impact orbit of the rigid bar under ``p0 + pk cos(k t)`` at each point, written
    into ``out`` (the arrays of ``RigidOrbits``, filled beforehand with the unused slots' values).

    ``d``, ``R``, ``p0``, ``pk``: float arrays of shape (P,); ``k``: the harmonic's order (int).
    """
    n_orbits, fallback = out[0], out[13]
    K2 = 2 * k
    phs = np.empty(K2)
    zs = np.empty(K2)
    bounds = np.empty(K2 + 2)
    brk = np.empty((K2 + 1, 5))  # the arcs with a zero of v: ends, sign at the start, v at the ends
    kf = float(k)
    for i in range(d.size):
        di, Ri, p0i, pki = d[i], R[i], p0[i], pk[i]
        den = di * di + kf * kf
        zr = (1.0 + Ri) * pki * di / den
        zi = -(1.0 + Ri) * pki * kf / den
        A = math.hypot(zr, zi)
        theta = math.atan2(zi, zr)
        B = p0i * _G(di, Ri)
        ratio = B / A if A > 0.0 else INF
        if not (abs(ratio) <= 1.0 + 1e-15 and A > 0.0):
            n_orbits[i] = 0
            continue
        double = abs(ratio) >= 1.0 - 1e-15
        a = math.acos(min(max(ratio, -1.0), 1.0))
        n = 0
        for base in (a, -a):
            for j in range(k):
                phs[n] = ((base - theta + TWO_PI * j) / kf) % TWO_PI
                n += 1
            if double:
                break
        sort_head(phs, np.int64(n))  # (np.int64: a literal n would compile sort_head again)
        mult = 2 if double else 1
        n_orbits[i] = n

        # the flight: V(t) = ca cos(k t) + cb sin(k t), W its antiderivative
        ca = pki * di / den
        cb = pki * kf / den
        v_plus = -Ri * TWO_PI * p0i / (1.0 + Ri)  # theory §4: the rigid mode strikes at 2 pi p0/(1+R)
        psup = abs(p0i) + abs(pki)
        r0 = Ri == 0.0
        crossing = -p0i / pki if pki != 0.0 else INF
        crosses = abs(crossing) < 1.0
        alpha = math.acos(min(max(crossing, -1.0), 1.0))
        for m in range(n):
            ph = phs[m]
            x = kf * ph
            free = v_plus - (ca * math.cos(x) + cb * math.sin(x))
            W0 = (ca * math.sin(x) - cb * math.cos(x)) / kf
            x1 = kf * (ph + TWO_PI)
            c1, s1, bT = math.cos(x1), math.sin(x1), _b(di, TWO_PI)
            v_minus = ca * c1 + cb * s1 + p0i * bT + free * math.exp(-di * TWO_PI)
            q_minus = (ca * s1 - cb * c1) / kf - W0 + p0i * _c(di, TWO_PI) + free * bT
            p_plus = p0i + pki * math.cos(kf * ph)
            # the stationary points of u(1, t): at most one zero of v per arc of constant load sign
            bounds[0] = 0.0
            for j in range(k):
                if crosses:
                    zs[j] = ((alpha + TWO_PI * j) / kf - ph) % TWO_PI
                    zs[k + j] = ((TWO_PI * j - alpha) / kf - ph) % TWO_PI
                else:
                    zs[j] = TWO_PI
                    zs[k + j] = TWO_PI
            sort_head(zs, K2)
            for j in range(K2):
                bounds[j + 1] = zs[j]
            bounds[K2 + 1] = TWO_PI
            # the arcs where v changes sign, and how many of them hold a maximum (v from + to -)
            nb = 0
            n_max = 0
            s_lo = _sign(p_plus if r0 else v_plus)  # the sign just after the impact
            v_lo = v_plus
            for j in range(K2 + 1):
                lo, hi = bounds[j], bounds[j + 1]
                v_hi = v_minus if hi == TWO_PI else _velocity(hi, ph, kf, ca, cb, p0i, di, free)
                s_hi = _sign(v_hi)
                if s_lo * s_hi < 0.0 and hi > lo:
                    brk[nb, 0], brk[nb, 1], brk[nb, 2], brk[nb, 3], brk[nb, 4] = lo, hi, s_lo, v_lo, v_hi
                    nb += 1
                    n_max += s_lo > 0.0
                s_lo, v_lo = s_hi, v_hi
            # the clearance is the largest stationary value: a maximum's, if there is one (a minimum
            # is below the maximum next to it, since u(1, .) rises from it to that maximum or falls
            # to it from there), so the minima's zeros are sought only where there is none
            ng = 0
            gmax = -INF
            for j in range(nb):
                if n_max > 0 and not brk[j, 2] > 0.0:
                    continue
                tz = _cosine_zero((ph, kf, ca, cb, p0i, pki, di, free), brk[j, 0], brk[j, 1], brk[j, 2],
                                  brk[j, 3], brk[j, 4])
                g = _displacement(tz, ph, kf, ca, cb, p0i, di, free, W0)
                gmax = g if ng == 0 else max(gmax, g)
                ng += 1
            orbit = _assemble(di, Ri, p0i, psup, v_plus, v_minus, p_plus, p_plus,
                              ca * math.cos(x) + cb * math.sin(x), ng, gmax)
            if not orbit[0]:
                fallback[i] = True
                break
            _store(out, i, m, ph, mult, v_minus, v_plus, q_minus, orbit)


# ------------------------------------------------------------------------------------------------
# the square wave of eq. 34
# ------------------------------------------------------------------------------------------------
@numba.njit(**_JIT)
def _exp_level_time(v, alpha, d, target):
    """Time ``tau >= 0`` at which ``v e^{-d tau} + alpha b(tau)`` reaches ``target``; NaN if never."""
    den = alpha - d * v
    if den == 0.0:
        return NAN
    x = d * (v - target) / den
    if not x > -1.0:
        return NAN
    ratio = 1.0 - 0.5 * x if abs(x) < 1e-8 else math.log1p(x) / x
    tau = (target - v) / den * ratio
    return tau if tau >= 0.0 else NAN


@numba.njit(**_JIT)
def square_orbits(d, R, q, kappa, out):
    """Every one-impact orbit of the rigid bar under the square wave (eq. 34) at each point,
    written into ``out`` as :func:`cosine_orbits`; none where ``kappa >= 2`` (a constant load,
    which the callers leave to the general path)."""
    n_orbits, fallback = out[0], out[13]
    phs = np.empty(2)
    edges = np.empty(4)
    for i in range(d.size):
        di, Ri, qi = d[i], R[i], q[i]
        if not kappa[i] < 2.0:
            n_orbits[i] = 0
            continue
        a = kappa[i] * math.pi  # the jump from +q to -q
        p0 = qi * (kappa[i] - 1.0)
        len0, len1 = a, TWO_PI - a
        al0, al1 = qi - p0, -qi - p0  # p - p0 on each piece
        bT0, bT1 = _b(di, len0), _b(di, len1)
        E2 = math.exp(-di * a)
        D2 = al0 * bT0
        v0 = -(D2 * bT1 + al0 * _c(di, len0) + al1 * _c(di, len1)) / (bT0 + E2 * bT1)
        V0, V1 = v0, v0 * E2 + D2
        target = p0 * _G(di, Ri) / (1.0 + Ri)
        n = 0
        tau = _exp_level_time(V0, al0, di, target)
        if tau < len0:  # NaN compares false
            phs[n] = tau % TWO_PI
            n += 1
        tau = _exp_level_time(V1, al1, di, target)
        if tau < len1:
            phs[n] = (a + tau) % TWO_PI
            n += 1
        sort_head(phs, np.int64(n))  # (np.int64: a literal n would compile sort_head again)
        mult = 1
        if n == 2 and (phs[1] - phs[0] < 1e-9 or phs[0] + TWO_PI - phs[1] < 1e-9):
            n, mult = 1, 2  # one double root, as in phase_roots
        n_orbits[i] = n

        v_plus = -Ri * TWO_PI * p0 / (1.0 + Ri)
        r0 = Ri == 0.0
        for m in range(n):
            ph = phs[m]
            if ph >= a:
                V_phase = V1 * math.exp(-di * (ph - a)) + al1 * _b(di, ph - a)
                p_plus = -qi
            else:
                V_phase = V0 * math.exp(-di * ph) + al0 * _b(di, ph)
                p_plus = qi
            p_minus = -qi if (ph == 0.0 or ph > a) else qi  # the left limit
            # the flight: three arcs of constant load in orbit time, cut where the load jumps
            c1, c2 = (a - ph) % TWO_PI, (-ph) % TWO_PI
            edges[0], edges[1], edges[2], edges[3] = 0.0, min(c1, c2), max(c1, c2), TWO_PI
            qs, vs = 0.0, v_plus
            ng = 0
            gmax = -INF
            for j in range(3):
                T = edges[j + 1] - edges[j]
                mid = (ph + 0.5 * (edges[j] + edges[j + 1])) % TWO_PI
                L = qi if mid < a else -qi
                tz = NAN if (j == 0 and r0) else _exp_level_time(vs, L, di, 0.0)
                if tz < T and not (j == 0 and tz <= 0.0):  # the impact itself is no stationary point
                    g = qs + vs * _b(di, tz) + L * _c(di, tz)
                    gmax = g if ng == 0 else max(gmax, g)
                    ng += 1
                qs = qs + vs * _b(di, T) + L * _c(di, T)
                vs = vs * math.exp(-di * T) + L * _b(di, T)
            orbit = _assemble(di, Ri, p0, qi, v_plus, vs, p_plus, p_minus, V_phase, ng, gmax)
            if not orbit[0]:
                fallback[i] = True
                break
            _store(out, i, m, ph, mult, vs, v_plus, qs, orbit)
