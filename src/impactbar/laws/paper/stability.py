"""The Floquet multipliers of a one-impact orbit under the paper's impact law (eqs. 10, 11, theory
§7): the exact Jacobian of the impact map, with its saltation term and the velocity reversal
``J_R = diag(I, -R I)``, and its eigenvalues by a dense or a structured ``O(N^2)`` method (the
building blocks, shared by every law, are :mod:`impactbar.dynamics.monodromy`); for the rigid bar
the 2 x 2 Jacobian's eigenvalues in closed form, elementwise over arrays (:func:`rigid_multipliers`,
which the rigid closed forms of :mod:`impactbar.orbits.rigid` call too)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...dynamics import monodromy as MD
from ...dynamics.monodromy import (
    TWO_PI,
    aberth,
    arrival_derivative,
    impact_fields,
    period_fundamental,
    sort_multipliers,
)
from ..base import BarModelLike

if TYPE_CHECKING:
    from ...loads import Load

__all__ = ["impact_map_jacobian", "floquet_multipliers", "rigid_multipliers", "trace_det"]


def impact_map_jacobian(model: BarModelLike, load: Load, phase: float, y_plus, y_minus) -> np.ndarray:
    """Analytic Jacobian of the impact map at a one-impact fixed point (theory §7).

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
    dY, r = arrival_derivative(model, load, phase, TWO_PI, y_plus, y_minus, phase)
    dY[M:, :] *= -model.R  # velocity reversal
    DP = np.empty((2 * M, 2 * M))
    DP[0, :] = r
    DP[1:, :] = dY[1:, :]
    return DP


def floquet_multipliers(model: BarModelLike, load: Load, phase: float, y_plus, y_minus, *,
                        method: str = "auto") -> np.ndarray:
    r"""Floquet multipliers of a one-impact orbit under the paper's impact law (eqs. 10, 11): the
    eigenvalues of the impact map's Jacobian (theory §7), sorted by :func:`sort_multipliers`.

    ``method="dense"`` takes the eigenvalues of :func:`impact_map_jacobian`, :math:`O(N^3)`.
    ``method="structured"`` uses the structure of the map: in the state extended by the impact time,
    :math:`(y, \tau)`, the Jacobian is the block-diagonal :math:`\operatorname{diag}(J_R \Phi_n(2\pi), 1)`
    (one :math:`2 \times 2` block per mode) plus a rank-2 correction (the impact-time dependence and the
    saltation term), and its eigenvalues are those of the map plus one zero. By the matrix determinant
    lemma they are the zeros of :math:`\det(B - x) \det(I_2 + V^T (B - x)^{-1} U)` divided by :math:`x`,
    found all at once by the Aberth-Ehrlich iteration from the blocks' own eigenvalues, :math:`O(N^2)`;
    with :math:`R = 0` the velocity rows vanish and :math:`N + 1` multipliers are exactly 0, the rest
    those of the :math:`(N + 1)`-square displacement block. Where the iteration does not settle, the dense
    method is used. ``"auto"`` (default) picks the structured method from 40 flexible modes on, for
    :math:`d \le 1` (tested against the dense method to :math:`10^{-10}` of the spectral radius there;
    with heavier damping the flexible multipliers crowd near 0, :math:`|\mu| \sim e^{-2\pi d}`, and agree
    only to about :math:`10^{-8}`).

    Parameters
    ----------
    model, load, phase, y_plus, y_minus
        As :func:`impact_map_jacobian`: the bar, the load, the impact's load time (rad) and the
        modal states just after and just before it, shape ``(2 N + 2,)``.
    method : {"auto", "dense", "structured"}

    Returns
    -------
    numpy.ndarray of complex, shape (2 N + 2,)

    Raises
    ------
    ValueError
        At grazing (zero arrival velocity, the saltation term is infinite), or for an unknown
        ``method``.
    """
    if method not in ("auto", "dense", "structured"):
        raise ValueError(f"method must be 'auto', 'dense' or 'structured'; got {method!r}")
    N = model.n_modes
    if method == "auto":
        use = N >= MD.STRUCTURED_FROM and model.d <= MD.STRUCTURED_MAX_DAMPING
        method = "structured" if use else "dense"
    if method == "dense" or N == 0:
        return sort_multipliers(np.linalg.eigvals(impact_map_jacobian(model, load, phase, y_plus, y_minus)))
    if model.R == 0.0:
        M = N + 1
        DP = impact_map_jacobian(model, load, phase, y_plus, y_minus)
        return sort_multipliers(np.concatenate((np.linalg.eigvals(DP[:M, :M]), np.zeros(M))))
    parts = _structured_parts(model, load, phase, y_plus, y_minus)
    mu = aberth(*parts)
    if mu is None:
        return sort_multipliers(np.linalg.eigvals(impact_map_jacobian(model, load, phase, y_plus, y_minus)))
    return sort_multipliers(mu)


def _structured_parts(model, load, phase, y_plus, y_minus):
    """Blocks and rank-2 factors of the impact map's Jacobian in the extended state (theory §7).

    With ``S = I - F1 chat^T / v`` (saltation, ``F1 = (f1, 1)``, ``chat`` reads ``u(1, .)``),
    ``J = diag(J_R, 1)`` and the fixed-duration flow ``P + h e_tau^T`` (``P = diag(Phi, 1)``,
    ``h = (f1 - Phi f0, 0)``): ``DP_ext = J S (P + h e_tau^T) = J P + U V^T`` with
    ``U = [J h - (chat . h / v) J F1, -J F1 / v]`` and ``V = [e_tau, P^T chat]``.

    Returns the 2 x 2 blocks ``[[a, b], [c, e]]`` of ``J P`` per mode (arrays of shape (M,)), the
    factors per mode ``U, V`` (shape (M, 2, 2): mode, component q/v, column) and those of the
    impact-time row, ``ut, vt`` (shape (2,)).
    """
    M = model.n_modes + 1
    R = model.R
    c = model.end_weights
    v, (f0q, f0v), (f1q, f1v) = impact_fields(model, load, phase, y_plus, y_minus)
    p11, p12, p21, p22 = period_fundamental(model)
    hq = f1q - (p11 * f0q + p12 * f0v)
    hv = f1v - (p21 * f0q + p22 * f0v)
    ch = float(c @ hq)
    U = np.empty((M, 2, 2))
    U[:, 0, 0] = hq - ch / v * f1q
    U[:, 1, 0] = -R * hv + R * ch / v * f1v
    U[:, 0, 1] = -f1q / v
    U[:, 1, 1] = R * f1v / v
    V = np.zeros((M, 2, 2))
    V[:, 0, 1] = c * p11
    V[:, 1, 1] = c * p12
    ut = np.array([-ch / v, -1.0 / v])
    vt = np.array([1.0, 0.0])
    return p11, p12, -R * p21, -R * p22, U, V, ut, vt


def _b(d, t):
    """``b(t) = (1 - exp(-d t)) / d`` elementwise (``t`` at ``d = 0``)."""
    y = d * t
    dd = np.where(d == 0.0, 1.0, d)
    return np.where(np.abs(y) < 1e-8, t * (1.0 - 0.5 * y), -np.expm1(-y) / dd)


def trace_det(b, e, R, p_plus, p_minus, v_plus, v_minus, d):
    """Half the trace and the determinant of the rigid bar's 2 x 2 impact-map Jacobian (theory §7
    with ``N = 0``), ``b = b(2 pi)``, ``e = exp(-2 pi d)``: plain arithmetic, the same for numpy
    arrays (:func:`rigid_multipliers`) and for floats (``impactbar.orbits._rigid_scalar``, and its
    compiled copy)."""
    a_p = p_plus - d * v_plus
    a_m = p_minus - d * v_minus
    r0 = (v_plus + b * a_p) / v_minus
    r1 = -b / v_minus
    j10 = -R * (-e * a_p + a_m * r0)
    j11 = -R * (e + a_m * r1)
    return 0.5 * (r0 + j11), r0 * j11 - r1 * j10


def rigid_multipliers(d, R, p_plus, p_minus, v_plus, v_minus):
    """Floquet multipliers of a rigid-bar one-impact orbit: eigenvalues of the 2 x 2 impact-map
    Jacobian (theory §7 with ``N = 0``), elementwise over arrays.

    With ``b = b(2 pi)``, ``e = exp(-2 pi d)``, the state ``z = (tau, q_0')`` and ``v-`` the arrival
    velocity, the Jacobian is
    ``[[r0, r1], [-R (-e a+ + a- r0), -R (e + a- r1)]]`` with ``a+- = p(phase+-) - d v+-``,
    ``r0 = (v+ + b a+)/v-``, ``r1 = -b/v-``.

    Parameters
    ----------
    d, R : array_like
        Damping and restitution coefficient.
    p_plus, p_minus : array_like
        Load just after and just before the impact, ``p(phase)``, ``p(phase-)``.
    v_plus, v_minus : array_like
        Rigid velocity just after and just before the impact.

    Returns
    -------
    numpy.ndarray of complex, shape ``broadcast + (2,)``
        Sorted by decreasing modulus (the one with positive imaginary part first in a complex pair).
        ``inf`` where the arrival velocity is zero (grazing, the saltation term is infinite).
    """
    d, R, p_plus, p_minus, v_plus, v_minus = np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (d, R, p_plus, p_minus, v_plus, v_minus)))
    graze = ~(np.abs(v_minus) > 1e-14 * np.abs(v_minus))  # relative, as the general path: zero only
    half_tr, det = trace_det(_b(d, TWO_PI), np.exp(-TWO_PI * d), R, p_plus, p_minus, v_plus,
                             np.where(graze, 1.0, v_minus), d)
    disc = np.sqrt((half_tr * half_tr - det).astype(complex))
    # the stable pair: the larger root first, the other from the product
    big = half_tr + np.where(half_tr >= 0.0, 1.0, -1.0) * disc
    small = np.where(big != 0.0, det / np.where(big != 0.0, big, 1.0), 0.0)
    mu = np.stack((big, small), axis=-1)
    # order: decreasing modulus; a complex pair with the positive imaginary part first
    m0, m1 = np.abs(mu[..., 0]), np.abs(mu[..., 1])
    tie = np.abs(m1 - m0) <= 1e-12 * np.maximum(m0, m1)  # as dynamics.monodromy.sort_multipliers
    swap = (~tie & (m1 > m0)) | (tie & (mu[..., 1].imag > mu[..., 0].imag))
    mu = np.where(swap[..., None], mu[..., ::-1], mu)
    mu[graze] = np.inf + 0j
    return mu
