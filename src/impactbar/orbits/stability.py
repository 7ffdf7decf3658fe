"""Stability of one-impact orbits: the paper's Schur criterion (Section 3, eqs. 25-32) and the exact
Floquet multipliers of the impact map (theory §7)."""

from __future__ import annotations

import functools
import math

import numpy as np

from ..dynamics.modal import fundamental
from ..loads import Load
from ..model import BarModel

__all__ = ["impact_map_jacobian", "floquet_multipliers", "period_fundamental", "sort_multipliers",
           "schur_blocks", "schur_test", "quadratic_roots"]

TWO_PI = 2.0 * math.pi

#: A multiplier within this of the unit circle is marginal: the orbit is not called stable.
MARGINAL = 1e-9


def stable_verdict(admissible: bool, multipliers) -> bool:
    """The stability verdict of a periodic orbit (theory §5, §7): admissible, and every Floquet
    multiplier inside the unit circle by more than :data:`MARGINAL`."""
    return bool(admissible and np.all(np.abs(multipliers) < 1.0 - MARGINAL))

#: from this many flexible modes on, the multipliers come from the structured method (below it the
#: dense eigenvalue problem is as fast)
STRUCTURED_FROM = 40

#: ... and for damping up to this: heavier damping crowds the flexible modes' multipliers near 0
#: (|mu| ~ e^{-2 pi d}), where the two methods agree only to ~1e-8 of the spectral radius
STRUCTURED_MAX_DAMPING = 1.0


@functools.lru_cache(maxsize=64)
def period_fundamental(model: BarModel) -> tuple[np.ndarray, ...]:
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


def _impact_fields(model: BarModel, load: Load, phase: float, y_plus, y_minus, t_arrive=None):
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
    f1 = (vm, float(load.left_limit(phase if t_arrive is None else t_arrive)) - d * vm - w2 * qm)
    return v_imp, f0, f1


def impact_map_jacobian(model: BarModel, load: Load, phase: float, y_plus, y_minus) -> np.ndarray:
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
    dY, r = _arrival_derivative(model, load, phase, TWO_PI, y_plus, y_minus, phase)
    dY[M:, :] *= -model.R  # velocity reversal
    DP = np.empty((2 * M, 2 * M))
    DP[0, :] = r
    DP[1:, :] = dY[1:, :]
    return DP


def _arrival_derivative(model: BarModel, load: Load, t_start: float, flight: float, y_start, y_minus,
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
    v_imp, f0, f1 = _impact_fields(model, load, t_start, y_start, y_minus, t_arrive)
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
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # a2 subnormal: inf
        r1 = np.where(a2 != 0, qq / a2, complex(np.inf, 0.0))  # a2 = 0: a root at infinity
        r2 = np.where(qq != 0, a0 / qq, 0.0)
    return np.column_stack((r1, r2)).ravel()


def sort_multipliers(mu: np.ndarray) -> np.ndarray:
    """Multipliers in decreasing modulus, a complex pair with its positive imaginary part first
    (moduli equal to 12 digits count as equal, so the order does not hang on rounding)."""
    mu = np.asarray(mu, dtype=complex)
    mod = np.abs(mu)
    with np.errstate(invalid="ignore"):
        key = np.where(np.isfinite(mod), np.round(mod / max(float(np.max(mod[np.isfinite(mod)], initial=0.0)),
                                                            1e-300), 12), np.inf)
    return mu[np.lexsort((-mu.imag, -key))]


def floquet_multipliers(model: BarModel, load: Load, phase: float, y_plus, y_minus, *,
                        method: str = "auto") -> np.ndarray:
    """Floquet multipliers of a one-impact orbit under the paper's impact law (eqs. 10, 11): the
    eigenvalues of the impact map's Jacobian (theory §7), sorted by :func:`sort_multipliers`.

    ``method="dense"`` takes the eigenvalues of :func:`impact_map_jacobian`, ``O(N^3)``.
    ``method="structured"`` uses the structure of the map: in the state extended by the impact
    time, ``(y, tau)``, the Jacobian is the block-diagonal ``diag(J_R Phi_n(2 pi), 1)`` (one 2 x 2
    block per mode) plus a rank-2 correction (the impact-time dependence and the saltation term),
    and its eigenvalues are those of the map plus one zero. By the matrix determinant lemma they
    are the zeros of ``det(B - x) det(I_2 + V^T (B - x)^{-1} U)`` divided by ``x``, found all at
    once by the Aberth-Ehrlich iteration from the blocks' own eigenvalues, ``O(N^2)``; with
    ``R = 0`` the velocity rows vanish and ``N + 1`` multipliers are exactly 0, the rest those of
    the ``(N + 1)``-square displacement block. Where the iteration does not settle, the dense
    method is used. ``"auto"`` (default) picks the structured method from 40 flexible modes on, for
    ``d <= 1`` (tested against the dense method to 1e-10 of the spectral radius there; with heavier
    damping the flexible multipliers crowd near 0, ``|mu| ~ e^{-2 pi d}``, and agree only to ~1e-8).

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
        use = N >= STRUCTURED_FROM and model.d <= STRUCTURED_MAX_DAMPING
        method = "structured" if use else "dense"
    if method == "dense" or N == 0:
        return sort_multipliers(np.linalg.eigvals(impact_map_jacobian(model, load, phase, y_plus, y_minus)))
    if model.R == 0.0:
        M = N + 1
        DP = impact_map_jacobian(model, load, phase, y_plus, y_minus)
        return sort_multipliers(np.concatenate((np.linalg.eigvals(DP[:M, :M]), np.zeros(M))))
    parts = _structured_parts(model, load, phase, y_plus, y_minus)
    mu = _aberth(*parts)
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
    v, (f0q, f0v), (f1q, f1v) = _impact_fields(model, load, phase, y_plus, y_minus)
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


def _aberth(a, b, c, e, U, V, ut, vt, iters=60, tol=1e-12):
    """Zeros of ``det(B + U V^T - x) / x`` (the multipliers, see :func:`floquet_multipliers`) by
    the Aberth-Ehrlich iteration; ``None`` if it does not converge.

    ``det(B + U V^T - x) = det(B - x) det(S(x))`` with the 2 x 2 secular matrix
    ``S(x) = I + sum_n V_n^T adj(B_n - x) U_n / det(B_n - x) + vt ut^T / (1 - x)``; each
    ``V_n^T adj(B_n - x) U_n`` is linear in ``x``, so ``S`` and ``S'`` for all the current
    approximations are sums over the modes. In the extended state ``V``'s first column is
    ``e_tau`` (no modal part) and ``vt = (1, 0)``, so ``S``'s first row depends on the impact-time
    factor alone and its second row takes four sums over the modes. The Newton quotient is
    ``1 / (log det)'``. The sweeps run compiled (``_aberthkernel.aberth_iterate``), ``O(N^2)`` each.

    Raises
    ------
    ValueError
        If ``V`` has a modal part in its first column or ``vt`` is not ``(1, 0)`` (not the
        extended state's factors).
    """
    if np.any(V[:, :, 0]) or vt[0] != 1.0 or vt[1] != 0.0:
        raise ValueError("_aberth needs the extended state's factors: V[:, :, 0] = 0 and vt = (1, 0)")
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
    from ._aberthkernel import aberth_iterate  # lazy: numba loads on the first structured call

    X = np.ascontiguousarray(np.concatenate((N0, N1), axis=1).T, dtype=float)
    ok = aberth_iterate(x, np.ascontiguousarray(tr, dtype=float), np.ascontiguousarray(dt, dtype=float), X,
                        np.asarray(ut, dtype=complex), int(iters), float(tol))
    return x if ok else None
