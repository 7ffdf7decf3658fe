"""The phase equation of one-impact orbits (paper eq. 14, theory §4): its right-hand
factor ``G(d, R)``, its residual, and every root ``phase`` in ``[0, 2 pi)``."""

from __future__ import annotations

import math

import numpy as np

from ..drives.base import autonomous
from ..dynamics.certified import enclose_zeros, zeros_in_clusters
from ..loads import Load
from ..model import BarModel

__all__ = ["phase_G", "phase_residual", "phase_roots"]

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




def _check_inputs(model, load):
    if not isinstance(model, BarModel):
        raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
    if autonomous(load):  # a drive is not a function of time (theory §10)
        raise ValueError(f"a {type(load).__name__} is not periodic in time: the phase equation and "
                         "the one-impact orbits of a periodic load do not apply; use find_orbit(model, "
                         "drive) (unknown period, theory §10) or simulate")
    if not isinstance(load, Load):
        raise ValueError(f"load must be a Load (CosineLoad, SquareWaveLoad, ...); got "
                         f"{type(load).__name__}")


def phase_residual(model: BarModel, load: Load, phase) -> np.ndarray:
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


def phase_roots(model: BarModel, load: Load, *, closed_form: bool = True) -> list[tuple[float, int]]:
    """Every root of the phase equation in ``[0, 2 pi)``, with its multiplicity (1, or 2 at a fold).

    Roots are enclosed with certainty: ``|F'| = (1 + R)|p - p0 - d V| <= 2 (1 + R) sup|p - p0|``
    bounds the slope of the residual, so an interval whose midpoint residual exceeds that bound
    times its half-width holds no root (see ``_certified``). Enclosed roots are refined by Brent's
    method; a cluster without a sign change is a double root when the residual's extremum there is
    zero to rounding.

    Parameters
    ----------
    model : BarModel
    load : Load
    closed_form : bool
        Use the closed form for a load with a single harmonic (default); ``False`` forces the
        certified search (used by the tests to check one against the other).

    Returns
    -------
    list of (float, int)
        ``(phase, multiplicity)`` sorted by phase.
    """
    _check_inputs(model, load)
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
        if out and abs(t - out[-1][0]) < 1e-9:
            out[-1] = (out[-1][0], 2)
            continue
        out.append((t, mult))
    if len(out) > 1 and abs(out[0][0] + TWO_PI - out[-1][0]) < 1e-9:
        out[0] = (out[0][0], 2)
        out.pop()
    return out


def _single_harmonic_roots(model, load):
    """Closed-form roots for a load with one harmonic ``p_k`` (the pneumatic load, eq. 33).

    ``F = A cos(k phase + theta) - B`` with ``A e^{i theta} = (1 + R) p_k / (d + i k)``; the roots are
    ``k phase = -theta +- arccos(B / A) (mod 2 pi)``, ``2k`` of them, a double one at ``|B| = A``.
    """
    orders = getattr(load, "orders", None)
    if orders is None or len(orders) != 1:
        return None
    k = int(orders[0])
    z = (1.0 + model.R) * load.amplitudes[0] / (model.d + 1j * k)
    A, theta = abs(z), math.atan2(z.imag, z.real)
    B = load.p0 * phase_G(model.d, model.R)
    return _cosine_roots(A, theta, B, k)


def _cosine_roots(A, theta, B, k, tol=1e-15):
    """Roots in ``[0, 2 pi)`` of ``A cos(k phase + theta) = B`` (``A > 0``) with their multiplicity:
    ``k phase = -theta +- arccos(B / A) (mod 2 pi)``, ``2k`` of them, ``k`` double ones at
    ``|B| = A`` (to the relative tolerance ``tol``)."""
    ratio = B / A
    if abs(ratio) > 1.0 + tol:
        return []
    if abs(ratio) >= 1.0 - tol:
        base, mult = [math.acos(max(-1.0, min(1.0, ratio)))], 2
    else:
        a = math.acos(ratio)
        base, mult = [a, -a], 1
    out = []
    for b in base:
        for j in range(k):
            out.append(((b - theta + TWO_PI * j) / k) % TWO_PI)
    return [(t, mult) for t in sorted(out)]
