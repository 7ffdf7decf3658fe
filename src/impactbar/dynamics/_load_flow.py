"""Compiled evaluation of the exact modal flow under a Fourier load (theory §3, eq. 8), used by
:meth:`impactbar.FourierLoad.flow` (and so by the certified admissibility search, theory §5) in place
of a few dozen small numpy operations per call.

It evaluates the same closed form as the numpy path, term by term: the periodic particular solution
``Re sum_k H_nk p_k e^{i k t}`` plus the static deflection, the free part of each underdamped
flexible mode folded into ``e^{-d tau/2} (a cos(lam tau) + b sin(lam tau))``, and for the rigid mode
``dq + b(tau) dv + p0 c(tau)``, ``e^{-d tau} dv + p0 b(tau)``. The same for a
piecewise-constant load (``piecewise_flow``), and the certified search's bound of the end's
acceleration (``end_velocity_bound``). Results agree with the numpy paths to rounding.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .._shared.wrappers import internal_kernels
from ._flight import CACHE, _bc


@numba.njit(cache=CACHE, nogil=True)
def fourier_column(tj, q, v, j, ck, sk, flow, C, S, phased):
    """Column ``j`` of :func:`fourier_flow`: the states at the time ``tj``, written into ``q, v``
    (``ck, sk`` are scratch of shape ``(K,)``, ``C, S`` of shape ``(M,)``).

    ``phased`` (``np.bool_``, not a literal: one compile) says that ``C, S`` already hold the
    folded modes' phases ``cos, sin(lam_n (tj - t0))``, kept by a caller that steps the time by
    fixed amounts (a rotation per mode in place of a cosine and a sine: the certified search's
    bisection); otherwise they are computed here. Only the folded modes (``kind`` 1) read them."""
    t0, d, p0, k, H, V, kind = flow
    M = H.shape[1]
    K = k.size
    tau = tj - t0
    if not phased:
        for n in range(M):
            if kind[n] == 1:
                x = V[1, n] * tau
                C[n] = math.cos(x)
                S[n] = math.sin(x)
    for m in range(K):
        x = k[m] * tj
        ck[m] = math.cos(x)
        sk[m] = math.sin(x)
    ed = math.exp(-0.5 * d * tau) if d != 0.0 else 1.0
    for n in range(M):
        qs = 0.0
        vs = 0.0
        for m in range(K):
            qs += H[0, n, m] * ck[m] - H[1, n, m] * sk[m]
            vs += H[2, n, m] * ck[m] - H[3, n, m] * sk[m]
        qs += V[0, n]
        if kind[n] == 1:
            qs += (V[2, n] * C[n] + V[3, n] * S[n]) * ed
            vs += (V[4, n] * C[n] + V[5, n] * S[n]) * ed
        elif kind[n] == 2:
            b, c = _bc(d, tau)
            qs += V[6, n] + b * V[7, n] + p0 * c
            vs += math.exp(-d * tau) * V[7, n] + p0 * b
        q[n, j] = qs
        v[n, j] = vs


@numba.njit(cache=CACHE, nogil=True)
def fourier_flow(t, flow):
    """States ``(q, v)`` of shape ``(M, T)`` at the times ``t`` (shape ``(T,)``) of the flow
    ``flow = (t0, d, p0, k, H, V, kind)`` from ``FourierLoad.flow``: start time, damping, mean
    load, orders; ``H`` (shape ``(4, M, K)``) holds ``H p`` and ``i k H p``, real and imaginary
    parts; ``V`` (shape ``(8, M)``) holds per mode the static deflection, and the frequency ``lam``
    and coefficients ``cq, sq, cv, sv`` of a folded underdamped flexible mode (``kind[n]`` 1), and
    the free part ``dq, dv`` of the rigid mode (``kind[n]`` 2; 0: the particular solution alone).
    Three arrays where there were fourteen: every kernel call counts a reference to each array it
    is passed, and the certified search passes these once per evaluation."""
    _, _, _, k, H, _, _ = flow
    M = H.shape[1]
    K = k.size
    T = t.size
    q = np.empty((M, T))
    v = np.empty((M, T))
    ck = np.empty(K)
    sk = np.empty(K)
    C = np.empty(M)
    S = np.empty(M)
    for j in range(T):
        fourier_column(t[j], q, v, j, ck, sk, flow, C, S, np.bool_(False))
    return q, v


@numba.njit(cache=CACHE, nogil=True)
def piecewise_column(w2, d, lv, tj, q0, v0, q, v, j):
    """Column ``j`` of :func:`piecewise_flow`: the exact step of length ``tj`` under the constant
    ``lv`` from the state ``(q0, v0)`` (shape ``(M,)``), written into ``q, v``."""
    M = w2.size
    e = math.exp(-0.5 * d * tj) if d != 0.0 else 1.0
    b, c = _bc(d, tj)
    ed = math.exp(-d * tj)
    for n in range(M):
        if w2[n] == 0.0:
            q[n, j] = q0[n] + b * v0[n] + lv * c
            v[n, j] = ed * v0[n] + lv * b
        else:
            lam = math.sqrt(w2[n] - 0.25 * d * d)
            x = lam * tj
            eC = e * math.cos(x)
            p12 = e * math.sin(x) / lam
            hd = 0.5 * d * p12
            qs = lv / w2[n]
            dq = q0[n] - qs
            q[n, j] = (eC + hd) * dq + p12 * v0[n] + qs
            v[n, j] = -w2[n] * p12 * dq + (eC - hd) * v0[n]


@numba.njit(cache=CACHE, nogil=True)
def piecewise_flow(w2, d, level, piece, tau, qn, vn):
    """States ``(q, v)`` of shape ``(M, T)`` under a piecewise-constant load: column ``j`` is the
    exact step of length ``tau[j]`` under the constant ``level[j]`` from the state
    ``(qn[:, piece[j]], vn[:, piece[j]])`` at the start of its piece (theory §3, eq. 34); flexible
    modes underdamped."""
    M = w2.size
    T = tau.size
    q = np.empty((M, T))
    v = np.empty((M, T))
    for j in range(T):
        pj = piece[j]
        piecewise_column(w2, d, level[j], tau[j], qn[:, pj], vn[:, pj], q, v, j)
    return q, v


@numba.njit(cache=CACHE, nogil=True)
def end_velocity_bound(c, absc, w2, d, psup, q, v, center, delta, half):
    """``g' = c . q'`` at the midpoints and the bound ``sum_n |c_n| B_n >= |g''|`` on the intervals
    ``[mid - half, mid + half]`` of the admissibility search (theory §5), from each mode's energy
    about the static deflection under the local load ``center`` (``|p - center| <= delta``);
    ``q, v`` of shape ``(M, T)`` at the midpoints."""
    M, T = q.shape
    g1 = np.empty(T)
    L = np.empty(T)
    for j in range(T):
        g1[j], L[j] = bound_column(c, absc, w2, d, psup, q, v, j, center[j], delta[j], half[j])
    return g1, L


@numba.njit(cache=CACHE, nogil=True)
def bound_column(c, absc, w2, d, psup, q, v, j, center, delta, h):
    """Column ``j`` of :func:`end_velocity_bound`: ``(g', bound of |g''|)``."""
    M = q.shape[0]
    grow = math.exp(d * h)
    gs = 0.0
    ls = 0.0
    for n in range(M):
        vn = v[n, j]
        gs += c[n] * vn
        if w2[n] > 0.0:
            wc = math.sqrt(w2[n])
            r = wc * q[n, j] - center / wc
            Eb = (math.sqrt(vn * vn + r * r) + delta * h) * grow
            b = delta + (d + wc) * Eb
        else:
            b = psup + d * ((abs(vn) + psup * h) * grow)
        ls += absc[n] * b
    return gs, ls


# all of them callable from Python (impactbar.dynamics.compiled): none link-only, all counting
# references leanly and without a C wrapper
internal_kernels(globals(), python=("fourier_flow", "piecewise_flow", "fourier_column", "piecewise_column",
                                    "bound_column", "end_velocity_bound"))
