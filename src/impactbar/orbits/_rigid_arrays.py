"""The rigid bar's closed forms (:mod:`impactbar.orbits.rigid`) compiled, point by point over
parameter arrays: what a sweep's chunk of thousands of points needs.

The vectorised numpy closed forms of :mod:`impactbar.orbits.rigid` (the reference of the switch
``"orbits.rigid_arrays"``, :mod:`impactbar.dynamics.implementations`) make some fifty passes over
temporary arrays per call, and their bracketed zero search iterates every orbit until the slowest
has converged. These kernels run the formulas of :mod:`impactbar.orbits._rigid_scalar` (one point in
plain floats, line by line the same as the vectorised ones) in one compiled loop over the points,
writing each orbit's fields straight into the result's arrays.

One source: the formulas themselves (the phase equation's roots, the flights, the verdict and the
multipliers, :data:`impactbar.orbits._rigid_scalar.SHARED`) are numba's copies of the functions of
``_rigid_scalar``, the reference, made by :func:`_compiled` from that module's code; only the loops
over the points and the cosine flight's zero search (Halley steps from the secant's zero where the
reference takes Newton's from the middle: the same zero) are written here. The tests hold them to
the numpy closed forms and to the general path (``tests/dynamics/test_fast_paths.py``).

Sources: the phase equation (eq. 14, theory §4), the stationary points of the end's displacement
arc by arc (theory §5), the 2 x 2 impact-map Jacobian (theory §7), the paper's rigid block (eqs. 29,
30, theory §6). Imported lazily: a single ``periodic_orbits`` call on a rigid bar loads no numba.
"""

from __future__ import annotations

import math
import types

import numba
import numpy as np

from .._shared.literals import plain_literals
from ..dynamics.compiled import CACHE, sort_head
from . import _rigid_scalar

TWO_PI = 2.0 * math.pi
INF = math.inf
NAN = math.nan

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")


def _compiled(names) -> dict:
    """numba's copies of the functions ``names`` of :mod:`._rigid_scalar` (the reference), made from
    its code: each copy runs in the reference module's globals with every one of ``names`` replaced
    by its copy, so that the copies call one another compiled (cached as the reference's functions,
    next to its source), each once for all constant arguments (:func:`plain_literals`: ``_verdict``'s
    ``ng = 0``)."""
    scope = dict(vars(_rigid_scalar))
    for name in names:
        f = getattr(_rigid_scalar, name)
        copy = types.FunctionType(f.__code__, scope, f.__name__, f.__defaults__, f.__closure__)
        copy.__qualname__ = f.__qualname__
        scope[name] = numba.njit(**_JIT)(copy)
    copies = {name: scope[name] for name in names}
    plain_literals(dict(copies, __name__=_rigid_scalar.__name__))
    return copies


_copies = _compiled(_rigid_scalar.SHARED)
(_b, _sign, _verdict, _cosine_roots, _cosine_flight, _crossing, _velocity, _displacement, _exp_level_time,
 _square_wave, _square_impact, _square_flight) = (_copies[name] for name in (
    "_b", "_sign", "_verdict", "_cosine_roots", "_cosine_flight", "_crossing", "_velocity", "_displacement",
    "_exp_level_time", "_square_wave", "_square_impact", "_square_flight"))

#: the places in ``out``, the fields of ``RigidOrbits`` in order
(O_N, O_PHASE, O_MULT, O_VMINUS, O_VPLUS, O_QMINUS, O_STATUS, O_CLEAR, O_CLEARERR, O_MULTS, O_SCHUR,
 O_SCHUROK, O_STABLE, O_FALLBACK) = range(14)
#: the place of the admissible flag in ``_verdict``'s orbit
V_OK = 0
#: the arcs of a flight where the velocity changes sign (``brk``, a row each): the arc's start and
#: end (phases), the velocity's sign at its start (+1: a maximum of the displacement inside), the
#: velocity at its start and at its end
BRK_LO, BRK_HI, BRK_SIGN, BRK_VLO, BRK_VHI, BRK_COLS = range(6)


@numba.njit(inline="always", **_JIT)
def _store(out, i, j, phase, mult, v_minus, v_plus, q_minus, orbit):
    """Write orbit ``j`` of point ``i`` (``orbit``, from :func:`_verdict`) into ``out``, the fields
    of ``RigidOrbits`` in order (straight-line code: inlined, its references cost nothing)."""
    _, status, clearance, err, mu0, mu1, s0, s1, schur_ok, stable = orbit
    out[O_PHASE][i, j] = phase
    out[O_MULT][i, j] = mult
    out[O_VMINUS][i, j] = v_minus
    out[O_VPLUS][i, j] = v_plus
    out[O_QMINUS][i, j] = q_minus
    out[O_STATUS][i, j] = status
    out[O_CLEAR][i, j] = clearance
    out[O_CLEARERR][i, j] = err
    out[O_MULTS][i, j, 0] = mu0
    out[O_MULTS][i, j, 1] = mu1
    out[O_SCHUR][i, j, 0] = s0
    out[O_SCHUR][i, j, 1] = s1
    out[O_SCHUROK][i, j] = schur_ok
    out[O_STABLE][i, j] = stable


# ------------------------------------------------------------------------------------------------
# the cosine load p0 + pk cos(k t)
# ------------------------------------------------------------------------------------------------
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
    n_orbits, fallback = out[O_N], out[O_FALLBACK]
    K2 = 2 * k
    phs = np.empty(K2)
    zs = np.empty(K2)
    bounds = np.empty(K2 + 2)
    brk = np.empty((K2 + 1, BRK_COLS))  # the arcs with a zero of v: ends, sign at the start, v at the ends
    kf = float(k)
    for i in range(d.size):
        di, Ri, p0i, pki = d[i], R[i], p0[i], pk[i]
        exists, double, a, theta, den = _cosine_roots(di, Ri, p0i, pki, kf)
        if not exists:
            n_orbits[i] = 0
            continue
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

        v_plus = -Ri * TWO_PI * p0i / (1.0 + Ri)  # theory §4: the rigid mode strikes at 2 pi p0/(1+R)
        psup = abs(p0i) + abs(pki)
        r0 = Ri == 0.0
        crosses, alpha = _crossing(p0i, pki)
        for m in range(n):
            ph = phs[m]
            # the flight: V(t) = ca cos(k t) + cb sin(k t), W its antiderivative
            ca, cb, free, W0 = _cosine_flight(di, pki, kf, den, ph, v_plus)
            v_minus = _velocity(TWO_PI, ph, kf, ca, cb, p0i, di, free)
            q_minus = _displacement(TWO_PI, ph, kf, ca, cb, p0i, di, free, W0)
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
                    brk[nb, BRK_LO], brk[nb, BRK_HI], brk[nb, BRK_SIGN] = lo, hi, s_lo
                    brk[nb, BRK_VLO], brk[nb, BRK_VHI] = v_lo, v_hi
                    nb += 1
                    n_max += s_lo > 0.0
                s_lo, v_lo = s_hi, v_hi
            # the clearance is the largest stationary value: a maximum's, if there is one (a minimum
            # is below the maximum next to it, since u(1, .) rises from it to that maximum or falls
            # to it from there), so the minima's zeros are sought only where there is none
            ng = 0
            gmax = -INF
            for j in range(nb):
                if n_max > 0 and not brk[j, BRK_SIGN] > 0.0:
                    continue
                tz = _cosine_zero((ph, kf, ca, cb, p0i, pki, di, free), brk[j, BRK_LO], brk[j, BRK_HI],
                                  brk[j, BRK_SIGN], brk[j, BRK_VLO], brk[j, BRK_VHI])
                g = _displacement(tz, ph, kf, ca, cb, p0i, di, free, W0)
                gmax = g if ng == 0 else max(gmax, g)
                ng += 1
            x = kf * ph
            orbit = _verdict(di, Ri, p0i, psup, v_plus, v_minus, p_plus, p_plus,
                             ca * math.cos(x) + cb * math.sin(x), ng, gmax)
            if not orbit[V_OK]:
                fallback[i] = True
                break
            _store(out, i, m, ph, mult, v_minus, v_plus, q_minus, orbit)


# ------------------------------------------------------------------------------------------------
# the square wave of eq. 34
# ------------------------------------------------------------------------------------------------
@numba.njit(**_JIT)
def square_orbits(d, R, q, kappa, out):
    """Every one-impact orbit of the rigid bar under the square wave (eq. 34) at each point,
    written into ``out`` as :func:`cosine_orbits`; none where ``kappa >= 2`` (a constant load,
    which the callers leave to the general path)."""
    n_orbits, fallback = out[O_N], out[O_FALLBACK]
    phs = np.empty(2)
    for i in range(d.size):
        di, Ri, qi = d[i], R[i], q[i]
        if not kappa[i] < 2.0:
            n_orbits[i] = 0
            continue
        a, p0, V0, V1, al0, al1, target = _square_wave(di, Ri, qi, kappa[i])
        n = 0
        tau = _exp_level_time(V0, al0, di, target)
        if tau < a:  # NaN compares false
            phs[n] = tau % TWO_PI
            n += 1
        tau = _exp_level_time(V1, al1, di, target)
        if tau < TWO_PI - a:
            phs[n] = (a + tau) % TWO_PI
            n += 1
        sort_head(phs, np.int64(n))  # (np.int64: a literal n would compile sort_head again)
        mult = 1
        if n == 2 and (phs[1] - phs[0] < 1e-9 or phs[0] + TWO_PI - phs[1] < 1e-9):
            n, mult = 1, 2  # one double root, as in phase_roots
        n_orbits[i] = n

        v_plus = -Ri * TWO_PI * p0 / (1.0 + Ri)
        for m in range(n):
            ph = phs[m]
            V_phase, p_plus, p_minus = _square_impact(ph, a, qi, di, V0, V1, al0, al1)
            qs, vs, ng, gmax = _square_flight(ph, a, qi, di, v_plus, Ri == 0.0)
            orbit = _verdict(di, Ri, p0, qi, v_plus, vs, p_plus, p_minus, V_phase, ng, gmax)
            if not orbit[V_OK]:
                fallback[i] = True
                break
            _store(out, i, m, ph, mult, vs, v_plus, qs, orbit)
