"""The paper's phase equation of one-impact orbits (eq. 14, theory §4): its right-hand factor
``G(d, R)``, its residual, every root ``phase`` in ``[0, 2 pi)`` (certified), and the existence edge
of the pneumatic load in closed form (eq. 38)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ...dynamics.certified import cosine_roots, enclose_zeros, zeros_in_clusters
from ..base import BarModelLike

if TYPE_CHECKING:
    from ...loads import Load

__all__ = ["phase_G", "phase_residual", "phase_roots", "pneumatic_existence_edge"]

TWO_PI = 2.0 * math.pi


def _beta(y: float) -> float:
    """``beta(y) = 1/(1 - exp(-y)) - 1/y``, by its series where the difference cancels."""
    if y < 1e-2:
        return 0.5 + y / 12.0 - y**3 / 720.0 + y**5 / 30240.0
    return 1.0 / (-math.expm1(-y)) - 1.0 / y


def phase_G(d: float, R: float) -> float:
    """Right-hand factor ``G(d, R)`` of the phase equation (eq. 14 rewritten, theory §4).

    ``G = 2 pi (1 + R e^{-2 pi d}) / (1 - e^{-2 pi d}) - (1 + R)/d = 2 pi [(1 + R) beta(2 pi d) - R]``,
    evaluated through ``beta`` so that it is accurate as ``d -> 0`` (``G(0, R) = pi (1 - R)``).
    """
    return TWO_PI * ((1.0 + R) * _beta(TWO_PI * d) - R)


def phase_residual(model: BarModelLike, load: Load, phase) -> np.ndarray:
    """Left minus right side of the phase equation (eq. 14, theory §4).

    ``F(phase) = (1 + R) Re sum_{k>=1} H_0k p_k (i k) e^{i k phase} - p0 G(d, R)``; the sum is the
    periodic zero-mean rigid velocity ``V(phase)`` (exact for every load, no truncation).

    Parameters
    ----------
    model : BarModel
    load : Load
    phase : array_like, shape (...)
        Phase lags (rad).

    Returns
    -------
    numpy.ndarray, shape (...)
    """
    R = model.R
    return (1.0 + R) * load.rigid_velocity(model.d, phase) - load.p0 * phase_G(model.d, R)


def phase_roots(model: BarModelLike, load: Load, *, closed_form: bool = True) -> list[tuple[float, int]]:
    """Every root of the phase equation in ``[0, 2 pi)``, with its multiplicity (1, or 2 at a fold):
    :func:`impactbar.orbits.phase_roots` without its check of the inputs (the solvers check them
    once). Certified: see there, for the parameters and the ``(phase, multiplicity)`` pairs returned,
    sorted by phase.

    Raises
    ------
    ValueError
        If the certified search cannot separate the roots of a nearly constant load.
    """
    R = model.R
    lip = 2.0 * (1.0 + R) * load.sup_oscillation
    scale = (1.0 + R) * load.sup_oscillation + abs(load.p0 * phase_G(model.d, R))
    if lip == 0.0:  # constant load: no phase dependence
        return []
    single = _single_harmonic_roots(model, load) if closed_form else None
    if single is not None:
        return single

    def F(t):
        return phase_residual(model, load, t)

    osc = load.sup_oscillation

    def slope_bound(mid, half):
        # |F'| = (1 + R)|p - p0 - d V| on [mid - half, mid + half], with |p - center| <= delta and
        # |V| <= |V(mid)| + 2 sup|p - p0| half; never above the global bound. (The global bound
        # alone made the search run out of intervals for a nearly constant load.)
        center, delta = load.variation(mid, half)
        vb = np.abs(load.rigid_velocity(model.d, mid)) + 2.0 * osc * half
        local = (1.0 + R) * (np.abs(center - load.p0) + delta + model.d * vb)
        return np.minimum(local, lip)

    try:
        # the rounding floor matters: the local bound can be the exact slope
        clusters = enclose_zeros(F, slope_bound, 0.0, TWO_PI, n0=64, min_width=1e-7,
                                 atol=1e-12 * scale)
    except RuntimeError as exc:  # pragma: no cover - the local bound keeps the search finite
        raise ValueError(f"phase equation: {exc}; the load {load!r} is too close to a degenerate "
                         "one (a constant load) for a certified search") from exc
    roots = zeros_in_clusters(F, clusters, atol=1e-12 * scale)
    out: list[tuple[float, int]] = []
    for t, mult in sorted((math.fmod(t, TWO_PI) % TWO_PI, m) for t, m in roots):
        if out:
            last, _ = out[-1]
            if abs(t - last) < 1e-9:
                out[-1] = (last, 2)
                continue
        out.append((t, mult))
    if len(out) > 1:
        (first, _), (last, _) = out[0], out[-1]
        if abs(first + TWO_PI - last) < 1e-9:
            out[0] = (first, 2)
            out.pop()
    return out


def _single_harmonic_roots(model, load):
    """Closed-form roots for a load with one harmonic ``p_k`` (the pneumatic load, eq. 33).

    ``F = A cos(k phase + theta) - B`` with ``A e^{i theta} = (1 + R) p_k / (d + i k)``; the roots are
    ``k phase = -theta +- arccos(B / A) (mod 2 pi)``, ``2k`` of them, a double one at ``|B| = A``.
    """
    own = load.abilities
    orders = own.orders
    if orders is None or len(orders) != 1:
        return None
    k = int(orders[0])
    z = (1.0 + model.R) * own.amplitudes[0] / (model.d + 1j * k)
    A, theta = abs(z), math.atan2(z.imag, z.real)
    B = load.p0 * phase_G(model.d, model.R)
    return cosine_roots(A, theta, B, k)


def pneumatic_existence_edge(R, d: float = 0.0, k: int = 1):
    """Existence edge of the pneumatic load (eq. 38 generalised to ``d > 0``), closed form.

    One-impact orbits exist iff ``k p0 / pk <= k (1 + R) / (sqrt(d^2 + k^2) G(d, R))``; at ``d = 0``
    this is ``(1/pi)(1 + R)/(1 - R)`` (eq. 38).

    Parameters
    ----------
    R : float or array_like
        Restitution coefficient(s) in ``[0, 1)``.
    d : float
        Damping.
    k : int
        Order of the harmonic.

    Returns
    -------
    float or numpy.ndarray
        The load factor ``k p0 / pk`` at the fold.
    """
    R = np.asarray(R, dtype=float)
    G = np.vectorize(lambda r: phase_G(d, r))(R)
    with np.errstate(divide="ignore"):
        out = k * (1.0 + R) / (math.hypot(d, k) * G)
    return float(out) if out.ndim == 0 else out
