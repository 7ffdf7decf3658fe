r"""The fundamental matrix of a circuit's flight from its plain steps, by Magnus' method of order 6
(theory §11, "Sensitivities").

A flight of the circuit with a flexible piston is integrated by CVODE at the drive's tolerance; its
steps ``t_k``, states ``y_k`` and rates ``f_k`` give the cubic Hermite interpolant of the state
between the steps. The variational equations :math:`\Phi' = A(y(t)) \Phi` are linear, so rather
than integrating their ``n^2`` unknowns beside the state in CVODE's Newton systems, ``Phi`` is
taken over the same flight by the sixth-order Magnus integrator of Blanes, Casas & Ros (2000,
BIT 40, 434; Blanes, Casas, Oteo & Ros 2009, Phys. Rep. 470, 151): on a step
:math:`[t_0, t_0 + h]`, with :math:`A_1, A_2, A_3` the Jacobian of the interpolated state at the
three Gauss-Legendre points :math:`t_0 + (1/2 - \sqrt{15}/10) h`, :math:`t_0 + h/2`,
:math:`t_0 + (1/2 + \sqrt{15}/10) h`,

.. math::

    \alpha_1 = h A_2, \quad \alpha_2 = \frac{\sqrt{15}\, h}{3} (A_3 - A_1), \quad
    \alpha_3 = \frac{10 h}{3} (A_3 - 2 A_2 + A_1), \\
    C_1 = [\alpha_1, \alpha_2], \quad C_2 = -\frac1{60} [\alpha_1, 2 \alpha_3 + C_1], \\
    \Omega = \alpha_1 + \frac{\alpha_3}{12}
             + \frac1{240} [-20 \alpha_1 - \alpha_3 + C_1, \alpha_2 + C_2], \qquad
    \Phi \leftarrow e^{\Omega} \Phi

(three commutators, six products). The exponential is computed by scaling and squaring with the
Taylor polynomials of Bader, Blanes & Casas (2019; at the steps' :math:`\|\Omega\|_1 \approx
\theta = 1` the degree 18 in five products, a squaring where the norm passes 1.09, no solve), each
:math:`\Omega` in coordinates :math:`D^{-1} \Omega D` that balance :math:`A`
(:func:`scipy.linalg.matrix_balance` once a flight, ``D`` powers of two: exact), where the modes'
:math:`q' = v, v' = -\omega^2 q` are of one size. A constant :math:`A` over a step is taken
exactly: the piston's fast modes, which a BDF step over the variational equations smooths, are
carried by the exponential. The Magnus steps are the method's own, each
:math:`h \|D^{-1} A D\|_1 = \theta` (``A`` at the previous step's last Gauss point); the error is of
order 6 in ``theta`` (halving it divides the error by about 64 where the Jacobian is smooth; the
state's interpolant has kinks that scatter it). At the default ``theta = 1`` each flight's ``Phi``
of the preset ``circuit-drifter``'s orbit with 4, 8 and 16 modes is nearer a converged Magnus
``Phi`` than the fourth-order method's at ``theta = 1/2`` (the way before, twice the steps), and
the fundamental matrix is limited by the state's own accuracy (the drive's tolerance), not by
Magnus (``benchmarks/probes/monodromy_magnus.py``).

The loop that calls the network's Jacobian is generated with the network's other kernels
(:mod:`._netgen`'s ``magnus_phi``); this module holds what it calls.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..._shared.literals import plain_literals
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE

__all__ = ["expm", "magnus_exp", "magnus_step", "scales", "state_at", "unscale", "DEFAULT_THETA", "balance"]

#: The Magnus steps' size, ``h ||D^-1 A D||_1`` (order 6: the error falls some 64 times a halving).
DEFAULT_THETA = 1.0

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")

# Bader, Blanes & Casas (2019), "Computing the matrix exponential with an optimized Taylor polynomial
# approximation", Mathematics 7, 1174: the Taylor polynomials of degree 4, 8, 12 and 18 in 2, 3, 4 and 5
# products (theirs, (2.2), (2.6)-(2.8), (2.13)-(2.16); the degree-12 one is theirs with a_{02} = 4.6), each
# with the largest 1-norm at which its backward error is below the unit roundoff (their Table 2)
_THETA4, _THETA8, _THETA12, _THETA18 = (3.397168839976962e-4, 4.991228871115323e-2, 2.996158913811580e-1,
                                        1.090863719290036)
_S177 = math.sqrt(177.0)
_X3 = 2.0 / 3.0
_T8_A = ((1.0 + _S177) / 88.0 * _X3, (1.0 + _S177) / 352.0 * _X3)
_T8_U2 = (857.0 - 58.0 * _S177) / 630.0
_T8_C = ((-271.0 + 29.0 * _S177) / (315.0 * _X3), 11.0 * (-1.0 + _S177) / (1260.0 * _X3),
         11.0 * (-9.0 + _S177) / (5040.0 * _X3), -(-89.0 + _S177) / (5040.0 * _X3 ** 2))
# degree 12: the factors' coefficients of I, A, A^2, A^3
_T12 = ((-0.0186023205146205532243437300433, -0.00500702322573317730979741843919,
         -0.573420122960522263905952420789, -0.133399693943892059700768926983),
        (4.6, 0.992875103538486836140479571505, -0.132445561052799638845074997454, 0.0017299),
        (0.211693118299809442949323323336, 0.158224384715726725371768893252,
         0.165635169436727415011171668419, 0.0107862779315792425026320640108),
        (0.0, -0.131810610138301840156819349464, -0.0202785554058925907933568229945,
         -0.00675951846863086359778560766482))
# degree 18: the factors' coefficients of I, A, A^2, A^3, A^6
_T18 = ((0.0, -0.100365581030144620014614939405, -0.00802924648241156960116919515244,
         -0.000892138498045729955685466128049, 0.0),
        (0.0, 0.39784974949964507614519612771028, 1.3678377846041171992252370687822,
         0.49828962252538267755685881726227, -0.00063789819459472330924155005649193),
        (-10.967639605296206259351746267537, 1.6801581387890619718278540172481,
         0.057177984647886551270287171322525, -0.0069821012248805208429046648380155,
         0.000033497501708607053831336734066844),
        (-0.090431683239081056197146887701835, -0.067640451907138190756007990037971,
         0.067596130177045964608279919507894, 0.029555257042931552742606918224223,
         -0.000013918025751606070112473997934374),
        (0.0, 0.0, -0.0923364619367118592764570775143, -0.0169364939002081717191385115723,
         -0.0000140086798182036159794363205726))
_S15 = math.sqrt(15.0)
_G1 = 0.5 - _S15 / 10.0  # the first of the three Gauss-Legendre points of [0, 1] (then 1/2, 1 - _G1)


@nb.njit(**_JIT)
def _norm1(A):
    n = A.shape[0]
    nrm = 0.0
    for j in range(n):
        s = 0.0
        for i in range(n):
            s += abs(A[i, j])
        nrm = max(nrm, s)
    return nrm


@nb.njit(**_JIT)
def _comb(c, A, A2, A3, A6, out):
    """``out = c_0 I + c_1 A + c_2 A^2 + c_3 A^3 + c_4 A^6`` (``c`` of 5; contiguous arrays, taken flat:
    the loop vectorises), returned."""
    m = A.size
    a, a2, a3, a6, o = A.reshape(m), A2.reshape(m), A3.reshape(m), A6.reshape(m), out.reshape(m)
    for k in range(m):
        o[k] = c[1] * a[k] + c[2] * a2[k] + c[3] * a3[k] + c[4] * a6[k]
    for i in range(A.shape[0]):
        out[i, i] += c[0]
    return out


@nb.njit(**_JIT)
def _taylor(A, nrm):
    """The Taylor polynomial of ``e^A`` of the least degree of 4, 8, 12, 18 whose backward error at the
    1-norm ``nrm`` (at most ``_THETA18``) is below the unit roundoff."""
    n = A.shape[0]
    A2 = A @ A
    zero = np.zeros((n, n))
    if nrm <= _THETA4:  # I + A + A^2 (I/2 + A/6 + A^2/24)
        E = _comb((1.0, 1.0, 0.0, 0.0, 0.0), A, A2, zero, zero, np.empty((n, n)))
        E += A2 @ _comb((0.5, 1.0 / 6.0, 1.0 / 24.0, 0.0, 0.0), A, A2, zero, zero, np.empty((n, n)))
        return E
    if nrm <= _THETA8:
        A4 = A2 @ _comb((0.0, _T8_A[0], _T8_A[1], 0.0, 0.0), A, A2, zero, zero, np.empty((n, n)))
        c = _T8_C
        E = _comb((0.0, 0.0, _X3, 0.0, 1.0), A, A2, zero, A4, np.empty((n, n))) \
            @ _comb((c[0], c[1], c[2], 0.0, c[3]), A, A2, zero, A4, np.empty((n, n)))
        E += _comb((1.0, 1.0, _T8_U2, 0.0, 0.0), A, A2, zero, zero, np.empty((n, n)))
        return E
    A3 = A2 @ A
    if nrm <= _THETA12:
        q = [_comb((c[0], c[1], c[2], c[3], 0.0), A, A2, A3, zero, np.empty((n, n))) for c in _T12]
        q6 = q[2] + q[3] @ q[3]
        E = (q[1] + q6) @ q6
        E += q[0]
        return E
    A6 = A3 @ A3
    q0 = _comb(_T18[0], A, A2, A3, A6, np.empty((n, n)))
    q1 = _comb(_T18[1], A, A2, A3, A6, np.empty((n, n)))
    q2 = _comb(_T18[2], A, A2, A3, A6, np.empty((n, n)))
    q9 = _comb(_T18[3], A, A2, A3, A6, np.empty((n, n)))
    q9 += q0 @ _comb(_T18[4], A, A2, A3, A6, A2)  # (over A^2: each entry read before it is written)
    q2 += q9
    E = np.dot(q2, q9, A3)
    E += q1
    return E


@nb.njit(**_JIT)
def expm(A):
    r"""The matrix exponential :math:`e^A` by scaling and squaring with the Taylor polynomials of Bader,
    Blanes & Casas (2019; degrees 4 to 18 in 2 to 5 products, chosen by :math:`\|A\|_1`: at the
    Magnus steps' :math:`\|A\|_1 \approx 1` the polynomial of degree 18, at most a squaring, no solve).
    Without balancing: the caller balances.

    Parameters
    ----------
    A : numpy.ndarray, shape (n, n)

    Returns
    -------
    numpy.ndarray, shape (n, n)
        To about ``1e-15`` relative (the polynomials' backward error below the unit roundoff).

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.linalg import expm as scipy_expm
    >>> A = np.array([[0.0, 1.0], [-4.0, -0.1]])
    >>> bool(np.allclose(expm(A), scipy_expm(A), rtol=1e-13, atol=1e-14))
    True
    """
    nrm = _norm1(A)
    s = 0
    if nrm > _THETA18:
        s = max(0, int(math.ceil(math.log2(nrm / _THETA18))))
    E = _taylor(A * 2.0 ** -s, nrm * 2.0 ** -s)
    for _ in range(s):
        E = E @ E
    return E


@nb.njit(**_JIT)
def state_at(t, y, f, tau, k, out):
    """The cubic Hermite interpolant of the steps ``t`` (states ``y``, rates ``f``) at ``tau`` into
    ``out``: the step holding ``tau`` searched forward from ``k``, and returned (the next search's
    start)."""
    last = t.size - 2
    while k < last and t[k + 1] < tau:
        k += 1
    h = t[k + 1] - t[k]
    s = (tau - t[k]) / h
    s2 = s * s
    s3 = s2 * s
    a0 = 2.0 * s3 - 3.0 * s2 + 1.0
    b0 = (s3 - 2.0 * s2 + s) * h
    a1 = -2.0 * s3 + 3.0 * s2
    b1 = (s3 - s2) * h
    y0, f0, y1, f1 = y[k], f[k], y[k + 1], f[k + 1]
    for i in range(out.size):
        out[i] = a0 * y0[i] + b0 * f0[i] + a1 * y1[i] + b1 * f1[i]
    return k


@nb.njit(**_JIT)
def scales(d):
    """``S[i, j] = d[j] / d[i]``: the balanced ``D^-1 A D`` (``D = diag(d)``) is ``A * S`` entry by
    entry."""
    n = d.size
    S = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            S[i, j] = d[j] / d[i]
    return S


@nb.njit(**_JIT)
def magnus_step(A, S, theta, left):
    """The next Magnus step: ``theta / ||A * S||_1`` (the balanced ``A``, :func:`scales`), the rest of
    the flight ``left`` where that is within a quarter of it (no sliver of a last step); and whether it
    is the last."""
    n = A.shape[0]
    nrm = 0.0
    for j in range(n):
        s = 0.0
        for i in range(n):
            s += abs(A[i, j]) * S[i, j]
        nrm = max(nrm, s)
    h = theta / nrm if nrm > 0.0 else left
    if 1.25 * h >= left:
        return left, True
    return h, False


@nb.njit(**_JIT)
def magnus_exp(A1, A2, A3, h, S):
    r"""``exp(Omega)`` of a Magnus step of length ``h`` in the balanced coordinates (``A * S``,
    :func:`scales`; a similarity, so the commutators are the same there) with the Jacobians ``A1``,
    ``A2``, ``A3`` at its three Gauss points: Blanes, Casas & Ros' sixth order in three commutators
    (module docstring), each of two products (the entry-by-entry loops over the flattened arrays)."""
    n = A1.shape[0]
    W = np.empty((7, n, n))
    a1, a2, P, Q, X, Z = W[0], W[1], W[3], W[4], W[5], W[6]  # (W[2]: alpha_3, by f[2] only)
    f = W.reshape(7, n * n)
    b1, b2, b3, s = A1.reshape(n * n), A2.reshape(n * n), A3.reshape(n * n), S.reshape(n * n)
    w2, w3 = _S15 / 3.0 * h, 10.0 / 3.0 * h
    for k in range(n * n):
        f[0, k] = h * b2[k] * s[k]  # alpha_1
        f[1, k] = w2 * (b3[k] - b1[k]) * s[k]  # alpha_2
        f[2, k] = w3 * ((b3[k] - b2[k]) - (b2[k] - b1[k])) * s[k]  # alpha_3
    np.dot(a1, a2, P)
    np.dot(a2, a1, Q)
    for k in range(n * n):
        c1 = f[3, k] - f[4, k]  # C_1 = [alpha_1, alpha_2]
        f[5, k] = c1 - 20.0 * f[0, k] - f[2, k]  # -20 alpha_1 - alpha_3 + C_1
        f[6, k] = 2.0 * f[2, k] + c1
    np.dot(a1, Z, P)
    np.dot(Z, a1, Q)
    for k in range(n * n):
        f[6, k] = f[1, k] - (f[3, k] - f[4, k]) / 60.0  # alpha_2 + C_2
    np.dot(X, Z, P)
    np.dot(Z, X, Q)
    for k in range(n * n):
        f[0, k] += f[2, k] / 12.0 + (f[3, k] - f[4, k]) / 240.0
    return expm(a1)


@nb.njit(**_JIT)
def unscale(Phi, d):
    """``D Phi D^-1`` in place (``D = diag(d)``), returned."""
    n = Phi.shape[0]
    for i in range(n):
        for j in range(n):
            Phi[i, j] *= d[i] / d[j]
    return Phi


def balance(jac_base, y, par, M, n) -> np.ndarray:
    """The diagonal ``d`` (powers of two) that balances the Jacobian at the state ``y``
    (:func:`scipy.linalg.matrix_balance`, no permutation)."""
    from scipy.linalg import matrix_balance

    A = np.empty((n, n))
    jac_base(np.ascontiguousarray(y), par, M, A)
    if not np.all(np.isfinite(A)):
        return np.ones(n)
    _, (scale, _) = matrix_balance(A, permute=False, separate=True)
    return np.ascontiguousarray(scale)


GAUSS1 = _G1

plain_literals(globals())  # one machine code per kernel for all constant arguments (state_at's k = 0)
internal_kernels(globals(), from_python="compile")  # kernels call them (the generated magnus_phi): link-only
