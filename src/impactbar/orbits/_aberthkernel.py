"""Compiled Aberth-Ehrlich iteration behind the structured Floquet multipliers (theory §7), used by
:func:`impactbar.orbits.stability.floquet_multipliers` in place of the numpy loop (which builds a
few ``(K, M)`` complex arrays per sweep). Same iteration, same start, same stopping rule, loop by
loop: the zeros agree with the numpy path to rounding. Imported lazily, so ``import impactbar``
does not load numba.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..dynamics._kernel import CACHE


@numba.njit(cache=CACHE, nogil=True)
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

# x / 0 gives inf (checked below); reassociation lets the sums over the modes run in SIMD lanes
@numba.njit(cache=CACHE, nogil=True, error_model="numpy", fastmath={"reassoc", "contract", "arcp"})
def aberth_iterate(x, tr, dt, X, Nt, iters, tol):
    """Refine the approximations ``x`` (shape ``(K,)``, complex, changed in place) of the zeros of
    ``det(B - x) det(S(x)) / x`` (see ``stability._aberth``); returns ``True`` once every
    correction is below ``tol`` relative to ``max(1, |x|)``, ``False`` if ``iters`` sweeps do not
    settle or a correction is not finite.

    ``tr, dt`` (shape ``(M,)``) are the blocks' traces and determinants, ``X`` (shape ``(8, M)``)
    the (real) coefficients ``N0, N1`` (rows) of ``V_n^T adj(B_n - x) U_n = N0_n + x N1_n`` (row-major 2 x 2),
    ``Nt`` (shape ``(4,)``) those of the impact-time row."""
    K = x.shape[0]
    M = tr.shape[0]
    active = np.ones(K, dtype=np.bool_)
    n_active = K
    corr = np.zeros(K, dtype=np.complex128)
    xre = np.empty(K)
    xim = np.empty(K)
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
            # sums over the modes, as scalars (real and imaginary parts): W X_j, dW X_j, W, W tr
            s0r = s0i = d0r = d0i = 0.0
            s1r = s1i = d1r = d1i = 0.0
            s2r = s2i = d2r = d2i = 0.0
            s3r = s3i = d3r = d3i = 0.0
            s4r = s4i = d4r = d4i = 0.0
            s5r = s5i = d5r = d5i = 0.0
            s6r = s6i = d6r = d6i = 0.0
            s7r = s7i = d7r = d7i = 0.0
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
                xj = X[0, n]
                s0r += wr * xj
                s0i += wi * xj
                d0r += vr * xj
                d0i += vi * xj
                xj = X[1, n]
                s1r += wr * xj
                s1i += wi * xj
                d1r += vr * xj
                d1i += vi * xj
                xj = X[2, n]
                s2r += wr * xj
                s2i += wi * xj
                d2r += vr * xj
                d2i += vi * xj
                xj = X[3, n]
                s3r += wr * xj
                s3i += wi * xj
                d3r += vr * xj
                d3i += vi * xj
                xj = X[4, n]
                s4r += wr * xj
                s4i += wi * xj
                d4r += vr * xj
                d4i += vi * xj
                xj = X[5, n]
                s5r += wr * xj
                s5i += wi * xj
                d5r += vr * xj
                d5i += vi * xj
                xj = X[6, n]
                s6r += wr * xj
                s6i += wi * xj
                d6r += vr * xj
                d6i += vi * xj
                xj = X[7, n]
                s7r += wr * xj
                s7i += wi * xj
                d7r += vr * xj
                d7i += vi * xj
                s8r += wr
                s8i += wi
                s9r += wr * t
                s9i += wi * t
            s = (complex(s0r, s0i), complex(s1r, s1i), complex(s2r, s2i), complex(s3r, s3i),
                 complex(s4r, s4i), complex(s5r, s5i), complex(s6r, s6i), complex(s7r, s7i),
                 complex(s8r, s8i), complex(s9r, s9i))
            sd = (complex(d0r, d0i), complex(d1r, d1i), complex(d2r, d2i), complex(d3r, d3i),
                  complex(d4r, d4i), complex(d5r, d5i), complex(d6r, d6i), complex(d7r, d7i))
            wt = _cdiv(1.0, 1.0 - xi)
            s00 = s[0] + xi * s[4] + wt * Nt[0]
            s01 = s[1] + xi * s[5] + wt * Nt[1]
            s02 = s[2] + xi * s[6] + wt * Nt[2]
            s03 = s[3] + xi * s[7] + wt * Nt[3]
            w2 = wt * wt
            s10 = s[4] + sd[0] + xi * sd[4] + w2 * Nt[0]
            s11 = s[5] + sd[1] + xi * sd[5] + w2 * Nt[1]
            s12 = s[6] + sd[2] + xi * sd[6] + w2 * Nt[2]
            s13 = s[7] + sd[3] + xi * sd[7] + w2 * Nt[3]
            S00 = 1.0 + s00
            S11 = 1.0 + s03
            detS = S00 * S11 - s01 * s02
            trSS = _cdiv(S11 * s10 - s01 * s12 - s02 * s11 + S00 * s13, detS)
            logd = 2.0 * xi * s[8] - s[9] - wt + trSS - _cdiv(1.0, xi)
            newton = _cdiv(1.0, logd)
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
            c = _cdiv(newton, 1.0 - newton * complex(acr, aci))
            if not (np.isfinite(c.real) and np.isfinite(c.imag)):
                return False
            corr[i] = c
        for i in range(K):
            if active[i]:
                x[i] -= corr[i]
                if abs(corr[i]) <= tol * max(1.0, abs(x[i])):
                    active[i] = False
                    n_active -= 1
        if n_active == 0:
            return True
    return False
