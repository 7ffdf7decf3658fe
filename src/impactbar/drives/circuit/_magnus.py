r"""The fundamental matrix of a circuit's flight from its plain steps, by Magnus' method of order 4
(theory §11, "Sensitivities").

A flight of the circuit with a flexible piston is integrated by CVODE at the drive's tolerance; its
steps ``t_k``, states ``y_k`` and rates ``f_k`` give the cubic Hermite interpolant of the state
between the steps. The variational equations :math:`\Phi' = A(y(t)) \Phi` are linear, so rather
than integrating their ``n^2`` unknowns beside the state in CVODE's Newton systems, ``Phi`` is
taken over the same flight by the fourth-order Magnus integrator (Iserles & Norsett 1999; Blanes,
Casas, Oteo & Ros 2009, eq. (4.3)): on a step :math:`[t_0, t_0 + h]`, with :math:`A_1, A_2` the
Jacobian at the two Gauss-Legendre points :math:`t_0 + (1/2 \mp \sqrt 3 / 6) h` of the interpolated
state,

.. math::

    \Omega = \frac h2 (A_1 + A_2) + \frac{\sqrt 3\, h^2}{12} [A_2, A_1], \qquad
    \Phi \leftarrow e^{\Omega} \Phi .

The exponential is computed by the scaling-and-squaring Pade method (Higham 2005, the degree
chosen from :math:`\|\Omega\|_1`), each :math:`\Omega` in coordinates :math:`D^{-1} \Omega D`
that balance :math:`A` (:func:`scipy.linalg.matrix_balance` once a flight, ``D`` powers of two:
exact), where the modes' :math:`q' = v, v' = -\omega^2 q` are of one size. A constant :math:`A`
over a step is taken exactly: the piston's fast modes, which a BDF step over the variational
equations smooths, are carried by the exponential. The Magnus steps are the method's own, each
:math:`h \|D^{-1} A D\|_1 = \theta` (``A`` at the previous step's second Gauss point); the error
is of order 4 in ``theta`` (halving it divides the error by about 16), and at the default the
fundamental matrix is limited by the state's own accuracy (the drive's tolerance), not by Magnus
(``benchmarks/probes/monodromy_magnus.py``).

The loop that calls the network's Jacobian is generated with the network's other kernels
(:mod:`._netgen`'s ``magnus_phi``); this module holds what it calls.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ...dynamics.kernels import CACHE

__all__ = ["expm", "magnus_exp", "magnus_step", "state_at", "unscale", "DEFAULT_THETA", "balance"]

#: The Magnus steps' size, ``h ||D^-1 A D||_1`` (order 4: the error falls some 16 times a halving).
DEFAULT_THETA = 0.5

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")

# Higham (2005), Table 2.3: the largest 1-norms for the Pade degrees 3, 5, 7, 9, 13 in double precision
_THETA = (1.495585217958292e-2, 2.539398330063230e-1, 9.504178996162932e-1, 2.097847961257068,
          5.371920351148152)
_B3 = (120., 60., 12., 1.)
_B5 = (30240., 15120., 3360., 420., 30., 1.)
_B7 = (17297280., 8648640., 1995840., 277200., 25200., 1512., 56., 1.)
_B9 = (17643225600., 8821612800., 2075673600., 302702400., 30270240., 2162160., 110880., 3960., 90., 1.)
_B13 = (64764752532480000., 32382376266240000., 7771770303897600., 1187353796428800., 129060195264000.,
        10559470521600., 670442572800., 33522128640., 1323241920., 40840800., 960960., 16380., 182., 1.)
_C1 = 0.5 - math.sqrt(3.0) / 6.0  # the first Gauss-Legendre point of [0, 1]
_COMM = math.sqrt(3.0) / 12.0


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
def expm(A):
    r"""The matrix exponential :math:`e^A` by scaling and squaring with Pade approximants (Higham
    2005, Algorithm 2.3, without its balancing: the caller balances).

    Parameters
    ----------
    A : numpy.ndarray, shape (n, n)

    Returns
    -------
    numpy.ndarray, shape (n, n)
        To about ``1e-15`` relative (scipy's ``expm`` is the same algorithm).

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.linalg import expm as scipy_expm
    >>> A = np.array([[0.0, 1.0], [-4.0, -0.1]])
    >>> bool(np.allclose(expm(A), scipy_expm(A), rtol=1e-13, atol=1e-14))
    True
    """
    n = A.shape[0]
    eye = np.eye(n)
    nrm = _norm1(A)
    A2 = A @ A
    if nrm <= _THETA[0]:
        U = A @ (_B3[3] * A2 + _B3[1] * eye)
        V = _B3[2] * A2 + _B3[0] * eye
        return np.ascontiguousarray(np.linalg.solve(V - U, V + U))
    A4 = A2 @ A2
    if nrm <= _THETA[1]:
        U = A @ (_B5[5] * A4 + _B5[3] * A2 + _B5[1] * eye)
        V = _B5[4] * A4 + _B5[2] * A2 + _B5[0] * eye
        return np.ascontiguousarray(np.linalg.solve(V - U, V + U))
    A6 = A4 @ A2
    if nrm <= _THETA[2]:
        U = A @ (_B7[7] * A6 + _B7[5] * A4 + _B7[3] * A2 + _B7[1] * eye)
        V = _B7[6] * A6 + _B7[4] * A4 + _B7[2] * A2 + _B7[0] * eye
        return np.ascontiguousarray(np.linalg.solve(V - U, V + U))
    if nrm <= _THETA[3]:
        A8 = A4 @ A4
        U = A @ (_B9[9] * A8 + _B9[7] * A6 + _B9[5] * A4 + _B9[3] * A2 + _B9[1] * eye)
        V = _B9[8] * A8 + _B9[6] * A6 + _B9[4] * A4 + _B9[2] * A2 + _B9[0] * eye
        return np.ascontiguousarray(np.linalg.solve(V - U, V + U))
    s = max(0, int(math.ceil(math.log2(nrm / _THETA[4]))))
    sc = 2.0 ** -s
    B, B2, B4, B6 = A * sc, A2 * sc ** 2, A4 * sc ** 4, A6 * sc ** 6
    U = B @ (B6 @ (_B13[13] * B6 + _B13[11] * B4 + _B13[9] * B2) + _B13[7] * B6 + _B13[5] * B4
             + _B13[3] * B2 + _B13[1] * eye)
    V = B6 @ (_B13[12] * B6 + _B13[10] * B4 + _B13[8] * B2) + _B13[6] * B6 + _B13[4] * B4 \
        + _B13[2] * B2 + _B13[0] * eye
    E = np.ascontiguousarray(np.linalg.solve(V - U, V + U))
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
def magnus_step(A, d, theta, left):
    """The next Magnus step: ``theta / ||D^-1 A D||_1`` (``D = diag(d)``), the rest of the flight
    ``left`` where that is within a quarter of it (no sliver of a last step); and whether it is the
    last."""
    n = A.shape[0]
    nrm = 0.0
    for j in range(n):
        s = 0.0
        for i in range(n):
            s += abs(A[i, j]) * d[j] / d[i]
        nrm = max(nrm, s)
    h = theta / nrm if nrm > 0.0 else left
    if 1.25 * h >= left:
        return left, True
    return h, False


@nb.njit(**_JIT)
def magnus_exp(A1, A2, h, d):
    r"""``exp(D^-1 Omega D)`` of a Magnus step of length ``h`` with the Jacobians ``A1``, ``A2`` at
    its Gauss points (module docstring)."""
    Om = (0.5 * h) * (A1 + A2) + (_COMM * h * h) * (A2 @ A1 - A1 @ A2)
    n = Om.shape[0]
    for i in range(n):
        for j in range(n):
            Om[i, j] *= d[j] / d[i]
    return expm(Om)


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
    return np.ascontiguousarray(matrix_balance(A, permute=False, separate=True)[1][0])


GAUSS1 = _C1
