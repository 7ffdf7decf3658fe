"""Stability of one-impact orbits: the paper's Schur criterion (Section 3, eqs. 25-32) and the exact
Floquet multipliers of the impact map (MODEL.md section 7)."""

from __future__ import annotations

import math

import numpy as np

from ..dynamics.modal import fundamental
from ..loads import Load
from ..model import BarModel

__all__ = ["impact_map_jacobian", "schur_blocks", "schur_test", "quadratic_roots"]

TWO_PI = 2.0 * math.pi




def impact_map_jacobian(model: BarModel, load: Load, phase: float, y_plus, y_minus) -> np.ndarray:
    """Analytic Jacobian of the impact map at a one-impact fixed point (MODEL.md section 7).

    The map takes ``z = (tau, q_1..q_N, q_0'..q_N')`` just after one impact to the same just after
    the next; ``q_0`` follows from contact ``u(1, tau) = 0``. The Jacobian combines the flow's
    fundamental matrix, the dependence on the impact time, the saltation term
    ``-(c . dq)/(c . q')`` and the velocity reversal ``J_R = diag(I, -R I)``.

    Parameters
    ----------
    model : BarModel
    load : Load
    phase : float
        Load time of the impact (rad).
    y_plus, y_minus : array_like, shape (2 N + 2,)
        Modal state ``(q_0..q_N, q_0'..q_N')`` just after and just before the impact.

    Returns
    -------
    numpy.ndarray, shape (2 N + 2, 2 N + 2)
        ``DP``; its eigenvalues are the Floquet multipliers.

    Raises
    ------
    ValueError
        At grazing (zero impact velocity), where the saltation term is infinite. An orbit that
        arrives moving backwards (inadmissible) still has a well-defined Jacobian.
    """
    M = model.n_modes + 1
    w2 = model.frequencies**2
    d, R = model.d, model.R
    c = model.end_weights
    yp = np.asarray(y_plus, dtype=float)
    ym = np.asarray(y_minus, dtype=float)
    qp, vp = yp[:M], yp[M:]
    qm, vm = ym[:M], ym[M:]
    v_imp = float(c @ vm)
    if not abs(v_imp) > 1e-14 * float(np.max(np.abs(ym))):  # relative: invariant under load -> L load
        raise ValueError("grazing impact (zero arrival velocity): the saltation term is infinite")
    p11, p12, p21, p22 = fundamental(w2, d, TWO_PI)
    Psi = np.block([[np.diag(p11), np.diag(p12)], [np.diag(p21), np.diag(p22)]])
    f0 = np.concatenate((vp, float(load(phase)) - d * vp - w2 * qp))
    f1 = np.concatenate((vm, float(load.left_limit(phase)) - d * vm - w2 * qm))
    # embedding of x = (q_1..q_N, v_0..v_N) into the full state, q_0 = -sum c_n q_n
    E = np.zeros((2 * M, 2 * M - 1))
    E[0, : M - 1] = -c[1:]
    E[1:M, : M - 1] = np.eye(M - 1)
    E[M:, M - 1:] = np.eye(M)
    A = np.empty((2 * M, 2 * M))
    A[:, 0] = -Psi @ f0
    A[:, 1:] = Psi @ E
    r = -(c @ A[:M, :]) / v_imp  # d tau' / d z
    dY = A + np.outer(f1, r)
    dY[M:, :] *= -R  # velocity reversal
    DP = np.empty((2 * M, 2 * M))
    DP[0, :] = r
    DP[1:M, :] = dY[1:M, :]
    DP[M:, :] = dY[M:, :]
    return DP


def schur_blocks(model: BarModel, load: Load, phase: float) -> np.ndarray:
    """The paper's quadratic blocks ``a2 xi^2 + a1 xi + a0`` (eqs. 27, 29-31), one per mode.

    The rigid block uses (eqs. 29, 30), with the harmonic sums in closed form:
    ``p0 sigma = (1/pi) sum_n (-1)^n v_n(phase)`` with ``v_n`` the periodic velocity response of mode
    ``n`` to the load, and ``p0 S2 = p(phase+) - p0 - d V(phase)``. Both are multiplied through by
    ``p0``, which leaves the roots unchanged and keeps ``p0 = 0`` finite. The flexible blocks use
    eq. 31 (valid for ``s >> 1``).

    Returns
    -------
    numpy.ndarray, shape (N + 1, 3)
        Rows ``(a2, a1, a0)``; row 0 is the rigid block.
    """
    N = model.n_modes
    d, R = model.d, model.R
    p0 = load.p0
    e2 = math.exp(-TWO_PI * d)
    if N > 0:
        w2 = model.frequencies[1:] ** 2
        _, vper = load.periodic_state(w2, d, [phase])
        sig = float(np.sum((-1.0) ** np.arange(1, N + 1) * vper[:, 0])) / math.pi
    else:
        sig = 0.0
    S2 = float(load(phase)) - p0 - d * float(load.rigid_velocity(d, phase))
    y = TWO_PI * d
    bracket = 1.0 - 0.5 * y if y < 1e-8 else -math.expm1(-y) / y  # series: no denormal quotient
    blocks = np.empty((N + 1, 3))
    blocks[0, 0] = p0 + (1.0 + R) * sig
    blocks[0, 1] = (-(1.0 + R * R * e2) * p0 - bracket * (1.0 + R) ** 2 * S2
                    - (1.0 - R * e2) * (1.0 + R) * sig)
    blocks[0, 2] = R * e2 * (R * p0 - (1.0 + R) * sig)
    if N > 0:
        lam = np.sqrt((model.frequencies[1:] ** 2 - 0.25 * d * d).astype(complex))
        blocks[1:, 0] = 1.0
        blocks[1:, 1] = -(1.0 - R) * math.exp(-math.pi * d) * np.cos(TWO_PI * lam).real
        blocks[1:, 2] = -R * e2
    return blocks


def schur_test(blocks: np.ndarray) -> bool:
    """Schur's conditions (eq. 28) on every block: ``|a0/a2| < 1`` and ``|a1/(a0 + a2)| < 1``."""
    a2, a1, a0 = blocks[:, 0], blocks[:, 1], blocks[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        ok = (np.abs(a0) < np.abs(a2)) & (np.abs(a1) < np.abs(a0 + a2))
    return bool(np.all(ok))


def quadratic_roots(blocks: np.ndarray) -> np.ndarray:
    """Both roots of each block ``a2 xi^2 + a1 xi + a0``, shape ``(2 (N + 1),)`` complex."""
    a2, a1, a0 = (blocks[:, j].astype(complex) for j in range(3))
    disc = np.sqrt(a1 * a1 - 4.0 * a2 * a0)
    # the numerically stable pair
    sgn = np.where((np.conj(a1) * disc).real >= 0.0, 1.0, -1.0)
    qq = -0.5 * (a1 + sgn * disc)
    with np.errstate(divide="ignore", invalid="ignore"):
        r1 = np.where(a2 != 0, qq / a2, complex(np.inf, 0.0))  # a2 = 0: a root at infinity
        r2 = np.where(qq != 0, a0 / qq, 0.0)
    return np.column_stack((r1, r2)).ravel()
