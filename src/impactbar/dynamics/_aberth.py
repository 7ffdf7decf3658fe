"""Compiled Aberth-Ehrlich iteration behind the structured Floquet multipliers (theory §7), used by
:func:`impactbar.dynamics.monodromy.aberth` (every law's structured multipliers) in place of the
numpy loop (which builds a few ``(K, M)`` complex arrays per sweep). Same iteration, same start,
same stopping rule, loop by loop: the zeros agree with the numpy path to rounding. Imported lazily,
so ``import impactbar`` does not load numba.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ._event_loop import CACHE

#: one, complex: :func:`_cdiv`'s numerator where a caller divides one by a complex (a complex argument
#: like every other call's, so that ``_cdiv`` compiles once; a float's imaginary part is 0.0 too)
ONE = complex(1.0, 0.0)


@numba.njit(cache=CACHE, nogil=True, fastmath=False)
def _cdiv(a, b):
    """``a / b`` for complex ``b``, scaled against overflow; ``b = 0`` gives a non-finite value (as
    numpy does) where numba's complex division would raise."""
    s = max(abs(b.real), abs(b.imag))
    if s == 0.0 or math.isnan(s):
        return complex(math.inf, math.nan)
    if math.isinf(s):  # a finite a over an infinite b is 0, as in numpy
        ok = math.isfinite(a.real) and math.isfinite(a.imag)
        return complex(0.0, 0.0) if ok else complex(math.nan, math.nan)
    br = b.real / s
    bi = b.imag / s
    q = 1.0 / (s * (br * br + bi * bi))
    return complex(a.real * br + a.imag * bi, a.imag * br - a.real * bi) * q

# The fast-math kernel below does real arithmetic only, and everything else through the helpers
# here, compiled without fast math, said explicitly: a callee that does not say inherits fast math
# from the kernel that compiles it first, and numba compiles its own implementations of complex
# multiplication, division and abs, of max() and of the array constructors once per process with
# the flags of their first caller. The kernel's machine code, and the multipliers' last bits, so
# depended on which kernels the process had compiled before (2 ulp at 64 modes between a fresh
# process and one that had run the test suite).


@numba.njit(cache=CACHE, nogil=True, fastmath=False)
def _work(K):
    """The sweeps' buffers for ``K`` zeros: all active, no correction yet."""
    return np.ones(K, dtype=np.bool_), np.zeros(K, dtype=np.complex128), np.empty(K), np.empty(K)


@numba.njit(cache=CACHE, nogil=True, fastmath=False)
def _correction(xi, s, ds, s89, ut, acr, aci):
    """Aberth's correction of the zero ``xi`` from the sums over the modes (``s = (s_0, ..., s_3)``
    and ``ds``, their derivatives, as real and imaginary parts; ``s89``: those of the pole term)
    and Aberth's sum ``acr + i aci`` over the other zeros (see :func:`aberth_iterate`)."""
    s0 = complex(s[0], s[1])
    s1 = complex(s[2], s[3])
    s2 = complex(s[4], s[5])
    s3 = complex(s[6], s[7])
    wt = _cdiv(ONE, 1.0 - xi)
    w2 = wt * wt
    # S = [[S00, S01], [S10, S11]] and its derivative [[D00, D01], [D10, D11]]
    S00 = 1.0 + wt * ut[0]
    S01 = wt * ut[1]
    S10 = s0 + xi * s2
    S11 = 1.0 + (s1 + xi * s3)
    D00 = w2 * ut[0]
    D01 = w2 * ut[1]
    D10 = s2 + complex(ds[0], ds[1]) + xi * complex(ds[4], ds[5])
    D11 = s3 + complex(ds[2], ds[3]) + xi * complex(ds[6], ds[7])
    detS = S00 * S11 - S01 * S10
    trSS = _cdiv(S11 * D00 - S01 * D10 - S10 * D01 + S00 * D11, detS)
    logd = 2.0 * xi * complex(s89[0], s89[1]) - complex(s89[2], s89[3]) - wt + trSS - _cdiv(ONE, xi)
    newton = _cdiv(ONE, logd)
    return _cdiv(newton, 1.0 - newton * complex(acr, aci))


@numba.njit(cache=CACHE, nogil=True, fastmath=False)
def _settled(c, x, tol):
    """Whether the correction ``c`` of the zero ``x`` is below ``tol`` relative to ``max(1, |x|)``."""
    return abs(c) <= tol * max(1.0, abs(x))


# compiled with the kernel's own flags (it does real arithmetic only): inlined there, its sums
# reassociate as the kernel's own did, to the same bits
@numba.njit(cache=CACHE, nogil=True, error_model="numpy", fastmath={"reassoc", "contract", "arcp"})
def _add_mode(sr, si, dr, di, xj, wr, wi, vr, vi):
    """One mode's term of a sum ``s_m`` and of its derivative: ``(sr + i si, dr + i di)`` plus
    ``xj (W, dW)`` with ``xj = X[m, n]``, ``W = wr + i wi``, ``dW = vr + i vi``, as real and
    imaginary parts."""
    return sr + wr * xj, si + wi * xj, dr + vr * xj, di + vi * xj


# x / 0 gives inf (checked below); reassociation lets the sums over the modes run in SIMD lanes
@numba.njit(cache=CACHE, nogil=True, error_model="numpy", fastmath={"reassoc", "contract", "arcp"})
def aberth_iterate(x, tr, dt, X, ut, iters, tol):
    """Refine the approximations ``x`` (shape ``(K,)``, complex, changed in place) of the zeros of
    ``det(B - x) det(S(x)) / x`` (see ``monodromy.aberth``); returns ``True`` once every
    correction is below ``tol`` relative to ``max(1, |x|)``, ``False`` if ``iters`` sweeps do not
    settle or a correction is not finite.

    ``tr, dt`` (shape ``(M,)``) are the blocks' traces and determinants. The rank-2 factor ``V``
    has no modal part in its first column (it is ``e_tau``, the impact time's coordinate) and the
    impact-time row is ``vt ut^T`` with ``vt = (1, 0)``, so the secular matrix is
    ``S(x) = [[1 + ut_0 / (1 - x), ut_1 / (1 - x)], [s_0(x), 1 + s_1(x)]]`` with
    ``s_m(x) = sum_n (X[m, n] + x X[m + 2, n]) / det(B_n - x)``: ``X`` (shape ``(4, M)``, real)
    holds the second row of ``N0_n, N1_n`` in ``V_n^T adj(B_n - x) U_n = N0_n + x N1_n``, ``ut``
    (shape ``(2,)``, complex) the impact-time factor. Per zero and sweep: five sums over the modes
    (four and the pole term ``sum (2 x - tr_n) / det(B_n - x)``) with their derivatives, and
    Aberth's sum over the other zeros."""
    K = x.shape[0]
    M = tr.shape[0]
    active, corr, xre, xim = _work(K)
    n_active = K
    for _ in range(iters):
        for i in range(K):
            xre[i] = x[i].real
            xim[i] = x[i].imag
        for i in range(K):
            if not active[i]:
                continue
            xi = x[i]
            xr = xi.real
            xm = xi.imag
            # sums over the modes, as scalars (real and imaginary parts): W X_m, dW X_m, W, W tr
            s0r = s0i = d0r = d0i = 0.0
            s1r = s1i = d1r = d1i = 0.0
            s2r = s2i = d2r = d2i = 0.0
            s3r = s3i = d3r = d3i = 0.0
            s8r = s8i = s9r = s9i = 0.0
            for n in range(M):
                # W = 1 / det(B_n - x) = 1 / (x^2 - tr x + dt), in real arithmetic (X is real)
                t = tr[n]
                zr = (xr - t) * xr - xm * xm + dt[n]
                zi = xm * (2.0 * xr - t)
                q = 1.0 / (zr * zr + zi * zi)
                wr = zr * q
                wi = -zi * q
                # dW = (tr - 2 x) W^2, the derivative of W
                w2r = wr * wr - wi * wi
                w2i = 2.0 * wr * wi
                ar = t - 2.0 * xr
                ai = -2.0 * xm
                vr = ar * w2r - ai * w2i
                vi = ar * w2i + ai * w2r
                s0r, s0i, d0r, d0i = _add_mode(s0r, s0i, d0r, d0i, X[0, n], wr, wi, vr, vi)
                s1r, s1i, d1r, d1i = _add_mode(s1r, s1i, d1r, d1i, X[1, n], wr, wi, vr, vi)
                s2r, s2i, d2r, d2i = _add_mode(s2r, s2i, d2r, d2i, X[2, n], wr, wi, vr, vi)
                s3r, s3i, d3r, d3i = _add_mode(s3r, s3i, d3r, d3i, X[3, n], wr, wi, vr, vi)
                s8r += wr
                s8i += wi
                s9r += wr * t
                s9i += wi * t
            # Aberth's sum of 1 / (x_i - x_j) over the others, in real arithmetic
            acr = 0.0
            aci = 0.0
            for j in range(K):
                if j != i:
                    ur = xr - xre[j]
                    um = xm - xim[j]
                    q = 1.0 / (ur * ur + um * um)
                    acr += ur * q
                    aci -= um * q
            c = _correction(xi, (s0r, s0i, s1r, s1i, s2r, s2i, s3r, s3i),
                            (d0r, d0i, d1r, d1i, d2r, d2i, d3r, d3i), (s8r, s8i, s9r, s9i), ut, acr, aci)
            if not (math.isfinite(c.real) and math.isfinite(c.imag)):
                return False
            corr[i] = c
        for i in range(K):
            if active[i]:
                x[i] -= corr[i]
                if _settled(corr[i], x[i], tol):
                    active[i] = False
                    n_active -= 1
        if n_active == 0:
            return True
    return False
