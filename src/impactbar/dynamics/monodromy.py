"""The linearisation of a flight and its arrival at the stop, and the Floquet multipliers built from it
(theory §7): the shared building blocks of every impact law's exact multipliers.

:func:`period_fundamental` (each mode's fundamental matrix over one load period, cached per model),
:func:`arrival_derivative` (the state at the next arrival differentiated with respect to the start
of a flight, with the saltation term ``-(c . dq)/(c . q')`` of the arrival time), :func:`sort_multipliers`
(the one order of every multiplier the package reports) and the structured eigenvalue method
:func:`aberth` (``O(N^2)``: a block-diagonal map plus a rank-2 correction, the Aberth-Ehrlich
iteration compiled in :mod:`impactbar.dynamics._aberth`). A law composes them with its own
impact map: the paper's ``J_R = diag(I, -R I)`` (:mod:`impactbar.laws.paper.stability`), the wave
law's window (:mod:`impactbar.laws.wave.periodic`). The model and the load are read through their
attributes and methods (``frequencies``, ``d``, ``end_weights``; ``load(t)``, ``load.abilities.left_limit``):
like the rest of :mod:`impactbar.dynamics`, this module imports no other impactbar subpackage."""

from __future__ import annotations

import functools
import math

import numpy as np

from .modal import fundamental

__all__ = ["period_fundamental", "sort_multipliers", "STRUCTURED_FROM", "STRUCTURED_MAX_DAMPING",
           "impact_fields", "arrival_derivative", "aberth"]


TWO_PI = 2.0 * math.pi


#: from this many flexible modes on, the multipliers come from the structured method (below it the
#: dense eigenvalue problem is as fast)
STRUCTURED_FROM = 40


#: ... and for damping up to this: heavier damping crowds the flexible modes' multipliers near 0
#: (|mu| ~ e^{-2 pi d}), where the two methods agree only to ~1e-8 of the spectral radius
STRUCTURED_MAX_DAMPING = 1.0


@functools.lru_cache(maxsize=64)
def period_fundamental(model) -> tuple[np.ndarray, ...]:
    """Fundamental matrix over one load period, ``Phi(2 pi)`` of every mode of ``model`` (eq. 8).

    Computed once per model and cached (a model is immutable): the orbit's start state, its
    Jacobian and its multipliers all need it.

    Returns
    -------
    tuple of numpy.ndarray
        ``(phi11, phi12, phi21, phi22)``, each shape ``(N + 1,)``, read-only.
    """
    out = []
    for a in fundamental(model.frequencies**2, model.d, TWO_PI):
        a = np.array(a, dtype=float)
        a.flags.writeable = False
        out.append(a)
    return tuple(out)


def impact_fields(model, load, phase: float, y_plus, y_minus, t_arrive=None):
    """The arrival velocity ``c . q'`` and the vector field ``(q', q'')`` of the modes at the start
    of a flight (load time ``phase``, state ``y_plus``) and at its arrival (load time ``t_arrive``,
    default ``phase``: one load period later, state ``y_minus``); raises ``ValueError`` at grazing
    (zero arrival velocity)."""
    M = model.n_modes + 1
    w2 = model.frequencies**2
    d = model.d
    yp = np.asarray(y_plus, dtype=float)
    ym = np.asarray(y_minus, dtype=float)
    qp, vp = yp[:M], yp[M:]
    qm, vm = ym[:M], ym[M:]
    v_imp = float(model.end_weights @ vm)
    if not abs(v_imp) > 1e-14 * float(np.max(np.abs(ym))):  # relative: invariant under load -> L load
        raise ValueError("grazing impact (zero arrival velocity): the saltation term is infinite")
    f0 = (vp, float(load(phase)) - d * vp - w2 * qp)
    t1 = phase if t_arrive is None else t_arrive
    left = load.abilities.left_limit  # (p(t-) where the load has jumps, else p(t))
    f1 = (vm, float(left(t1) if left is not None else load(t1)) - d * vm - w2 * qm)
    return v_imp, f0, f1


def arrival_derivative(model, load, t_start: float, flight: float, y_start, y_minus,
                        t_arrive: float, fund=None):
    """Derivative of the state at the next impact with respect to ``z = (t_start, q_1..q_N,
    q_0'..q_N')`` at the start of a flight of length ``flight`` (theory §7).

    ``dY = Psi [dy - f(t_start, y) dt_start] + f(t', Y) dt'`` with the saltation
    ``dt' = -(c . dq)/(c . q')``; ``q_0`` follows from contact at the start. Returns ``(dY, r)``,
    ``dY`` of shape ``(2 N + 2, 2 N + 2)`` and ``r = dt'/dz``. Raises ``ValueError`` at grazing.
    ``fund``, if given, is the fundamental matrix over ``flight`` (``(p11, p12, p21, p22)`` of
    :func:`~impactbar.dynamics.modal.fundamental`), cached by the caller.
    """
    M = model.n_modes + 1
    c = model.end_weights
    v_imp, f0, f1 = impact_fields(model, load, t_start, y_start, y_minus, t_arrive)
    f0, f1 = np.concatenate(f0), np.concatenate(f1)
    # the period's fundamental matrix is cached per model
    if fund is None:
        fund = (period_fundamental(model) if flight == TWO_PI
                else fundamental(model.frequencies**2, model.d, flight))
    p11, p12, p21, p22 = fund
    # Psi = [[diag p11, diag p12], [diag p21, diag p22]] applied to f0 and to the embedding of
    # x = (q_1..q_N, v_0..v_N) into the full state (q_0 = -sum c_n q_n), entry by entry
    A = np.zeros((2 * M, 2 * M))
    A[:M, 0] = -(p11 * f0[:M] + p12 * f0[M:])
    A[M:, 0] = -(p21 * f0[:M] + p22 * f0[M:])
    n = np.arange(1, M)  # q_n, column n
    A[0, 1:M] = -p11[0] * c[1:]
    A[M, 1:M] = -p21[0] * c[1:]
    A[n, n] = p11[1:]
    A[M + n, n] = p21[1:]
    m = np.arange(M)  # v_m, column M + m
    A[m, M + m] = p12
    A[M + m, M + m] = p22
    r = -(c @ A[:M, :]) / v_imp  # d tau' / d z
    return A + np.outer(f1, r), r


def sort_multipliers(mu: np.ndarray) -> np.ndarray:
    """Multipliers in decreasing modulus, a complex pair with its positive imaginary part first
    (moduli equal to 12 digits count as equal, so the order does not hang on rounding)."""
    mu = np.asarray(mu, dtype=complex)
    mod = np.abs(mu)
    with np.errstate(invalid="ignore"):
        key = np.where(np.isfinite(mod), np.round(mod / max(float(np.max(mod[np.isfinite(mod)], initial=0.0)),
                                                            1e-300), 12), np.inf)
    return mu[np.lexsort((-mu.imag, -key))]


def aberth(a, b, c, e, U, V, ut, vt, iters=60, tol=1e-12):
    """Zeros of ``det(B + U V^T - x) / x`` (the multipliers, see :func:`floquet_multipliers`) by
    the Aberth-Ehrlich iteration; ``None`` if it does not converge.

    ``det(B + U V^T - x) = det(B - x) det(S(x))`` with the 2 x 2 secular matrix
    ``S(x) = I + sum_n V_n^T adj(B_n - x) U_n / det(B_n - x) + vt ut^T / (1 - x)``; each
    ``V_n^T adj(B_n - x) U_n`` is linear in ``x``, so ``S`` and ``S'`` for all the current
    approximations are sums over the modes. In the extended state ``V``'s first column is
    ``e_tau`` (no modal part) and ``vt = (1, 0)``, so ``S``'s first row depends on the impact-time
    factor alone and its second row takes four sums over the modes. The Newton quotient is
    ``1 / (log det)'``. The sweeps run compiled (``_aberth.aberth_iterate``), ``O(N^2)`` each.

    Raises
    ------
    ValueError
        If ``V`` has a modal part in its first column or ``vt`` is not ``(1, 0)`` (not the
        extended state's factors).
    """
    if np.any(V[:, :, 0]) or vt[0] != 1.0 or vt[1] != 0.0:
        raise ValueError("aberth needs the extended state's factors: V[:, :, 0] = 0 and vt = (1, 0)")
    tr = a + e
    dt = a * e - b * c
    # the second row of V_n^T adj(B_n - x) U_n = N0_n + x N1_n, adj(B_n - x) = [[e, -b], [-c, a]] - x I
    adj0 = np.stack((np.stack((e, -b), -1), np.stack((-c, a), -1)), -2)
    N0 = np.einsum("kij,ki,kjm->km", adj0, V[:, :, 1], U)
    N1 = -np.einsum("ki,kim->km", V[:, :, 1], U)
    # start: each block's eigenvalues, nudged off the poles (golden-angle directions)
    disc = np.sqrt((0.25 * tr * tr - dt).astype(complex))
    x = np.concatenate((0.5 * tr + disc, 0.5 * tr - disc))
    nudge = np.exp(2j * np.pi * ((np.arange(x.size) * 0.6180339887498949) % 1.0))
    x = x * (1.0 + 1e-6 * nudge) + 1e-9 * nudge
    from ._aberth import aberth_iterate  # lazy: numba loads on the first structured call

    X = np.ascontiguousarray(np.concatenate((N0, N1), axis=1).T, dtype=float)
    ok = aberth_iterate(x, np.ascontiguousarray(tr, dtype=float), np.ascontiguousarray(dt, dtype=float), X,
                        np.asarray(ut, dtype=complex), int(iters), float(tol))
    return x if ok else None
