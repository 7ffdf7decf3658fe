"""One-impact periodic orbits under the wave impact law (theory §4b, with §4 and §7).

The impact starts at load time ``phase`` and lasts the window ``T = 2/s``; the flight lasts
``2 pi - T``. Held in contact for the whole window, the contact map is affine (theory §4b):
``(q_n, q_n') -> -R (q_n, q_n') + (g_n, h_n)(phase)`` for ``n >= 1``, ``q_0' -> -R q_0' + h_0``, with the
drive part of :func:`impactbar.laws.wave.impact.window_drive`, and the rigid displacement set by
contact at the window's end (positions from the rod end, which each blow advances). Periodicity is
then solved mode by mode, and the phase equation is the return of the struck end to the rod end:

    r(phase) = b(2 pi - T) q_0'(T) + f_0(phase) + sum_{n>=1} c_n (q_n(2 pi-) - q_n(T)) = 0,

with ``f_0`` the rigid displacement the load drives over the flight. Unlike eq. 14 the flexible modes
enter: their displacement is not continuous through the contact.

Exact rigid identity (the analogue of eq. 14's ``2 pi p0 / (1 + R)``): integrating
``q_0'' + d q_0' = p`` over the flight, with the contact's momentum balance
``q_0'(T) = -R q_0'(0) + int_{T/2}^{T} p - R int_0^{T/2} p`` (the drive's waves that reach the rod
within the window), and the displacement periodic relative to the rod, the impact velocity of the
rigid mode is, for the rigid bar at every ``d`` and for any number of modes at ``d = 0``
(with flexible modes and damping the contact-set ``q_0`` couples them in, and it holds only to
O(d), about 1e-4 at ``d = 0.05``),

    q_0'(2 pi-) = 2 pi p0 / (1 + R) - int_0^{1/s} p(phase + t) dt:

the contact time shifts it by the drive impulse of the window's first half. As ``s -> inf`` both
laws give the same rigid orbits.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq

from ...dynamics import compiled as K
from ...dynamics import monodromy as MD
from ...dynamics.certified import cosine_roots
from ...dynamics.compiled_views import FOURIER, PIECEWISE, ModalBasisView
from ...dynamics.implementations import use_fast
from ...dynamics.modal import fundamental
from ...dynamics.monodromy import aberth, arrival_derivative, impact_fields, sort_multipliers
from ...loads import FourierLoad, Load, PiecewiseConstantLoad
from ...loads.abilities import compiled_kind
from ..base import BarModelLike, OrbitState
from .impact import _wave_impact, window_drive, window_drives

__all__ = ["wave_orbit_states", "wave_phase_residual", "wave_phase_roots", "wave_phase_families",
           "wave_impact_map_jacobian", "wave_floquet_multipliers", "wave_existence_edge", "window_map",
           "orbit_state"]

TWO_PI = 2.0 * math.pi


# "wave.residual" (dynamics.implementations): the phase residual of a piecewise-constant load by one
# compiled call for all phases (``laws.wave._separation.square_wave_residuals``); the reference is
# :func:`wave_orbit_states` phase by phase (the same residuals to rounding)


class _Window(NamedTuple):
    """A period's window ``2/s`` and flight ``2 pi - 2/s``."""

    window: float
    flight: float


def _window(model: BarModelLike) -> _Window:
    T = 2.0 / model.s
    return _Window(T, TWO_PI - T)


@functools.lru_cache(maxsize=64)
def _flight_fundamental(model: BarModelLike) -> tuple[np.ndarray, ...]:
    """Fundamental matrix over the flight ``2 pi - 2/s`` of every mode (eq. 8), computed once per
    model (a model is immutable) and read-only: the phase scan evaluates the residual hundreds of
    times."""
    out = []
    for a in fundamental(model.frequencies**2, model.d, _window(model).flight):
        a = np.array(a, dtype=float)
        a.flags.writeable = False
        out.append(a)
    return tuple(out)


def _forced_flight(model: BarModelLike, load: Load, t0: float, t1: float):
    """State at ``t1`` of every mode driven from rest at ``t0`` (exact): the compiled flow for a
    piecewise-constant load, the load's own flow otherwise."""
    w2 = model.frequencies**2
    M = w2.size
    zeros = np.zeros(M)
    if compiled_kind(load) == PIECEWISE:  # fast path: the compiled flow of a piecewise-constant load
        q, v = np.empty((M, 1)), np.empty((M, 1))
        K.propagate_many(tuple(load.abilities.kernel.view), tuple(ModalBasisView.unforced(w2, model.d)),
                         float(t0), zeros, zeros, np.array([float(t1)]), q, v)
    else:
        q, v = load.propagate(w2, model.d, t0, zeros, zeros, [t1])
    return q[:, 0], v[:, 0]


def wave_orbit_states(model: BarModelLike, load: Load, phase: float, *, rates: bool = True):
    """Periodic modal states of the candidate orbit with this phase under the wave law.

    Parameters
    ----------
    model : BarModel
        With ``s > 1/pi`` (the window ``2/s`` shorter than the period).
    load : Load
    phase : float
        Load time at which contact starts (rad).
    rates : bool
        Also compute the drive's rates ``d(g, h)/d phase`` (default; the Jacobian needs them).

    Returns
    -------
    residual : float
        ``u(1, 2 pi-)``: the phase equation's residual (0 at an orbit).
    y_end : numpy.ndarray, shape (2 N + 2,)
        Modal state ``(q, q')`` at the end of the window (orbit time ``2/s``).
    y_minus : numpy.ndarray, shape (2 N + 2,)
        Modal state just before the impact (orbit time ``2 pi-``).
    drive_rate : tuple of numpy.ndarray
        ``d(g, h)/d phase`` (for the impact map's Jacobian); ``(None, None)`` with ``rates=False``.

    Notes
    -----
    Every output is linear in the load, and a shift of the phase is a shift of the load: under a
    load of finitely many harmonics (a :class:`~impactbar.loads.FourierLoad`, highest order ``K``)
    each output is a trigonometric polynomial of the phase of degree ``K``. Its coefficients are
    recovered exactly from ``2 K + 1`` phases (once per model and load, the samples the phase scan
    of :func:`wave_phase_roots` takes), and every later phase is a sum of ``K + 1`` terms: the same
    states to rounding, with the rates the exact derivative of the same sums. Other loads are
    computed phase by phase.
    """
    r, y_end, y_minus, rate, _ = _orbit_states(model, load, phase, rates=rates)
    return r, y_end, y_minus, rate


def _orbit_states(model: BarModelLike, load: Load, phase: float, *, rates: bool = True):
    """:func:`wave_orbit_states` and the drive's part ``(g, h)`` of the window (for
    :func:`~impactbar.laws.wave.impact.wave_impact`), from the phase series where the load has one."""
    if not _has_series(model, load):
        return _direct_states(model, load, phase, rates=rates)
    M = model.n_modes + 1
    coef = _state_series(model, load)
    k = np.arange(coef.shape[0])
    e = np.exp(1j * k * float(phase))
    e[1:] *= 2.0
    vals = (e @ coef).real  # c_0 + 2 Re sum_k c_k e^{i k phase}
    y_end, y_minus = vals[:2 * M], vals[2 * M:4 * M]
    g, h = vals[4 * M:5 * M], vals[5 * M:]
    rate = (None, None)
    if rates:
        dvals = ((1j * k * e) @ coef).real
        rate = (dvals[4 * M:5 * M], dvals[5 * M:])
    return float(model.end_weights @ y_minus[:M]), y_end, y_minus, rate, (g, h)


def _has_series(model: BarModelLike, load: Load) -> bool:
    """Whether the states are a trigonometric polynomial of the phase (:func:`wave_orbit_states`'
    notes): a load of finitely many harmonics whose evaluation is :class:`FourierLoad`'s own, and a
    window shorter than the period."""
    return (compiled_kind(load, "__call__", "propagate", "flow") == FOURIER and load.abilities.orders.size > 0
            and _window(model).flight > 0.0)


@functools.lru_cache(maxsize=16)
def _state_series(model: BarModelLike, load: FourierLoad) -> np.ndarray:
    """Coefficients ``c_k``, ``k = 0..K``, shape ``(K + 1, 6 N + 6)``, of ``(y_end, y_minus, g, h)``
    (rows of :func:`_direct_states`) as ``c_0 + 2 Re sum_k c_k e^{i k phase}``: the discrete Fourier
    transform of ``2 K + 1`` equally spaced phases, exact for a trigonometric polynomial of degree
    ``K`` (any :class:`FourierLoad`: the phase scan reads the residual's coefficients from it even
    where :func:`_has_series` leaves the states to :func:`_direct_states`). Computed once per model
    and load (both immutable), read-only."""
    K = int(np.max(load.abilities.orders))
    Ms = 2 * K + 1
    phases = TWO_PI * np.arange(Ms) / Ms
    N = model.n_modes
    g, h = window_drives(model.s, model.R, N, load, phases)
    _, y_end, y_minus = _periodic_solve(model, _forced_flights(model, load, phases), g, h)
    coef = np.fft.fft(np.concatenate((y_end, y_minus, g, h), axis=1), axis=0)[:K + 1] / Ms
    coef.flags.writeable = False
    return coef


def _direct_states(model: BarModelLike, load: Load, phase: float, *, rates: bool = True):
    """:func:`_orbit_states` at one phase, by the flight and the window's drive (any load)."""
    s, R, N = model.s, model.R, model.n_modes
    T, F = _window(model)
    forced = _forced_flight(model, load, phase + T, phase + TWO_PI)
    if rates:
        g, h, dg, dh = window_drive(s, R, N, load, phase, derivative=True)
    else:
        (g, h), dg, dh = window_drive(s, R, N, load, phase), None, None
    r, y_end, y_minus = _periodic_solve(model, forced, g, h)
    return float(r), y_end, y_minus, (dg, dh), (g, h)


def _periodic_solve(model: BarModelLike, forced, g, h):
    """The periodicity conditions ``y- = Phi (J y- + (g, h)) + f`` (``J = -R I``, ``Phi`` the
    flight's fundamental matrix, ``f = forced`` the flight from rest, ``(g, h)`` the window's drive)
    solved mode by mode, and the window's map: ``(u(1, 2 pi-), y_end, y_minus)``. Every array may
    carry a leading axis of phases (shape ``(P, N + 1)``; the outputs then do too)."""
    R, N = model.R, model.n_modes
    fq, fv = forced
    p11, p12, p21, p22 = _flight_fundamental(model)
    a11, a12, a21, a22 = 1.0 + R * p11, R * p12, R * p21, 1.0 + R * p22
    det = a11 * a22 - a12 * a21
    if np.any(np.abs(det) < 1e-13):
        raise ValueError("the periodicity conditions are singular (R = 1 without damping)")
    r1 = p11 * g + p12 * h + fq
    r2 = p21 * g + p22 * h + fv
    qm = (a22 * r1 - a12 * r2) / det
    vm = (a11 * r2 - a21 * r1) / det
    y_minus = np.concatenate((qm, vm), axis=-1)
    y_end = -R * y_minus + np.concatenate((g, h), axis=-1)  # window_map, row by row
    c = model.end_weights
    y_end[..., 0] = -(y_end[..., 1:N + 1] @ c[1:])
    y_minus[..., 0] = y_end[..., 0] + p12[0] * y_end[..., N + 1] + fq[..., 0]
    return y_minus[..., :N + 1] @ c, y_end, y_minus


def _forced_flights(model: BarModelLike, load: Load, phases):
    """``(fq, fv)``, shape ``(P, N + 1)``: :func:`_forced_flight` over ``[phase + 2/s, phase + 2 pi]``
    for each of the ``phases``. Under a load whose flow is :class:`FourierLoad`'s closed form (valid
    at every time) one trajectory ``X`` from rest serves them all: the forced system is linear, so
    the state from rest over the flight is ``X(t1) - Phi X(t0)`` (``Phi`` the flight's fundamental
    matrix, as in :func:`_periodic_solve`). Other loads take one flight per phase."""
    T, _ = _window(model)
    phases = np.asarray(phases, dtype=float)
    if compiled_kind(load, "flow") != FOURIER:  # (a flow that is not FourierLoad's closed form)
        return tuple(np.array(a) for a in zip(*(_forced_flight(model, load, float(p) + T, float(p) + TWO_PI)
                                               for p in phases), strict=True))
    w2 = model.frequencies**2
    zeros = np.zeros(w2.size)
    X = load.abilities.flow(w2, model.d, float(phases[0]) + T, zeros, zeros)
    q, v = X(np.concatenate((phases + T, phases + TWO_PI)))
    P = phases.size
    q0, v0, q1, v1 = q[:, :P].T, v[:, :P].T, q[:, P:].T, v[:, P:].T
    p11, p12, p21, p22 = _flight_fundamental(model)
    return q1 - (p11 * q0 + p12 * v0), v1 - (p21 * q0 + p22 * v0)


def window_map(model: BarModelLike, y_minus, g, h) -> np.ndarray:
    """The wave law's map across a contact window held for its whole length ``2/s`` (theory §4b).

    Parameters
    ----------
    model : BarModel
    y_minus : array_like, shape (2 N + 2,)
        Modal state ``(q, q')`` at arrival.
    g, h : numpy.ndarray, shape (N + 1,)
        The drive's part (:func:`impactbar.laws.wave.impact.window_drive`).

    Returns
    -------
    numpy.ndarray, shape (2 N + 2,)
        ``-R y_minus + (g, h)``, with ``q_0`` set by contact with the (advanced) rod end at the
        window's end, ``q_0 = -sum_{n>=1} c_n q_n``.
    """
    M = model.n_modes + 1
    y_plus = -model.R * np.asarray(y_minus, dtype=float) + np.concatenate((g, h))
    c = model.end_weights
    y_plus[0] = -float(c[1:] @ y_plus[1:M])  # in contact with the rod end at the end of the window
    return y_plus


def wave_phase_residual(model: BarModelLike, load: Load, phase) -> np.ndarray:
    """Residual of the wave law's phase equation, ``u(1, 2 pi-)`` (module docstring), shape of
    ``phase``."""
    ph = np.asarray(phase, dtype=float)
    if use_fast("wave.residual") and compiled_kind(load) == PIECEWISE and _window(model).flight > 0.0:
        return _square_wave_residuals(model, load, ph)
    out = np.array([r for r, *_ in (_orbit_states(model, load, float(p), rates=False) for p in ph.ravel())])
    return out.reshape(ph.shape)


def _square_wave_residuals(model: BarModelLike, load: PiecewiseConstantLoad, ph: np.ndarray) -> np.ndarray:
    """:func:`wave_phase_residual` for a piecewise-constant load, all phases in one compiled call."""
    from . import _separation as WK
    from .impact import _GL_W, _GL_X

    p11, p12, p21, p22 = _flight_fundamental(model)
    R = model.R
    if np.any(np.abs((1.0 + R * p11) * (1.0 + R * p22) - R * R * p12 * p21) < 1e-13):
        raise ValueError("the periodicity conditions are singular (R = 1 without damping)")
    phases = np.ascontiguousarray(ph, dtype=float).ravel()
    out = np.empty(phases.size)
    basis = ModalBasisView.unforced(model.frequencies**2, model.d)
    WK.square_wave_residuals(tuple(load.abilities.kernel.view), tuple(basis), float(model.s), float(R),
                             np.ascontiguousarray(model.end_weights, dtype=float), (p11, p12, p21, p22),
                             _GL_X, _GL_W, phases, out)
    return out.reshape(ph.shape)


def wave_phase_roots(model: BarModelLike, load: Load) -> list[tuple[float, int]]:
    """Roots of the wave law's phase equation in ``[0, 2 pi)`` with their multiplicity.

    For a load with finitely many harmonics (``FourierLoad``, ``CosineLoad``) the residual is a
    trigonometric polynomial of the phase of the load's degree ``K``: it is recovered exactly from
    ``2 K + 1`` samples, in closed form for a single harmonic (the pneumatic load). Other loads (the
    square wave) are sampled on 128 intervals, those around a sampled minimum of ``|r|`` 16 times
    finer, and every sign change is refined by Brent's method; a double root without a sign change
    (a fold) is then not reported. (Not a certified search, unlike eq. 14's.)

    Where the residual vanishes on a whole interval of phases (a degenerate family of orbits, e.g.
    the rigid bar under a square wave whose short pulse falls inside the second half of the contact
    window: the flight is then the same for every phase there), the rounding noise's sign changes
    are not roots: the interval is reported by :func:`wave_phase_families` instead, and no root
    is returned inside it.

    Warnings
    --------
    For loads other than finite Fourier sums the search is **not certified**: two roots closer than
    about ``2 pi / (128 * 16)`` away from a sampled minimum of ``|r|``, or a double root (a fold of
    the orbit branch, where ``r`` touches zero without changing sign), may be missed; an even
    number of roots inside one sampling interval is invisible. Near a fold, check the orbit count
    by continuation or a finer scan of :func:`wave_phase_residual`.

    Returns
    -------
    list of (float, int)
        ``(phase, multiplicity)`` sorted by phase; empty when the window ``2/s`` is not shorter than
        the period.
    """
    roots, _ = _phase_scan(model, load)
    return list(roots)


def wave_phase_families(model: BarModelLike, load: Load) -> list[tuple[float, float]]:
    """Intervals of phases on which the wave law's phase residual vanishes identically: each a
    continuum (a degenerate family) of one-impact orbits.

    A sampled run of at least three consecutive phases where ``|r| <= 1e-10 max |r|`` (the
    residual is linear in the load, so the test is the same at every load scale) marks a family;
    its ends are refined by bisection on the same test. Loads with finitely many harmonics have
    none (their residual, a trigonometric polynomial, vanishes on an interval only if it vanishes
    everywhere).

    Returns
    -------
    list of (float, float)
        ``(start, end)`` phases (rad), ``start`` in ``[0, 2 pi)`` and ``end > start`` (above
        ``2 pi`` when the interval wraps round); empty when there is no family.
    """
    _, families = _phase_scan(model, load)
    return list(families)


#: A residual at most this fraction of its largest sampled magnitude is rounding noise.
FLAT_RTOL = 1e-10


@functools.lru_cache(maxsize=16)
def _phase_scan(model: BarModelLike, load: Load) -> tuple[tuple, tuple]:
    """``(roots, families)`` of :func:`wave_phase_roots` and :func:`wave_phase_families`, computed
    once per model and load (both immutable)."""
    T, F = _window(model)
    if F <= 0.0:
        return (), ()
    families = ()
    if compiled_kind(load) == FOURIER:  # finitely many harmonics: the residual's own series
        orders = load.abilities.orders
        K = int(np.max(orders)) if orders.size else 0
        if K == 0:
            return (), ()
        # r = c0 + 2 Re sum_k c_k e^{i k phi}: the residual's coefficients from the states' series
        M = model.n_modes + 1
        coef = _state_series(model, load)[:, 2 * M:3 * M] @ model.end_weights
        c0 = coef[0].real
        if orders.size == 1:
            k = int(orders[0])
            ck = 2.0 * coef[k]  # r = c0 + |ck| cos(k phase + arg ck)
            if ck == 0.0:
                return (), ()
            return tuple(cosine_roots(abs(ck), math.atan2(ck.imag, ck.real), -c0, k, tol=1e-13)), ()
        ks = np.arange(1, K + 1)

        def resid(p):
            p = np.asarray(p, dtype=float)
            return c0 + 2.0 * (np.exp(1j * np.multiply.outer(p, ks)) @ coef[1:K + 1]).real

        grid = np.linspace(0.0, TWO_PI, 64 * K + 1)
        r = resid(grid)
        flat = np.zeros(grid.size, dtype=bool)
    else:
        def resid(p):
            return wave_phase_residual(model, load, p)

        grid, r = _refined_grid(resid, 129)
        flat, families = _flat_runs(resid, grid, r)
    roots = []
    for i in range(grid.size - 1):
        if flat[i] or flat[i + 1]:
            continue
        if r[i] == 0.0:
            roots.append(float(grid[i]))
        elif r[i] * r[i + 1] < 0.0:
            roots.append(brentq(lambda p: float(resid(np.array([p]))[0]), grid[i], grid[i + 1],
                                xtol=1e-14, rtol=1e-15))
    return tuple((t % TWO_PI, 1) for t in sorted(roots)), families


def _flat_runs(resid, grid, r):
    """Where the sampled residual ``r`` is rounding noise (``|r| <= FLAT_RTOL max |r|``) on at least
    three consecutive phases. Returns the mask of the samples in such runs and their neighbours
    (no root is sought there) and the runs' intervals, their ends refined by bisection."""
    a = np.abs(r)
    tol = FLAT_RTOL * float(np.max(a)) if a.size else 0.0
    small = a <= tol
    runs, i, n = [], 0, grid.size
    while i < n:
        if small[i]:
            j = i
            while j + 1 < n and small[j + 1]:
                j += 1
            if j - i >= 2:
                runs.append([i, j])
            i = j + 1
        else:
            i += 1
    mask = np.zeros(n, dtype=bool)
    for i, j in runs:
        mask[max(i - 1, 0):j + 2] = True
    if not runs:
        return mask, ()

    def is_flat(p):
        return abs(float(resid(np.array([p]))[0])) <= tol

    def edge(inside, outside):
        for _ in range(60):
            if abs(outside - inside) <= 1e-13:
                break
            mid = 0.5 * (inside + outside)
            if is_flat(mid):
                inside = mid
            else:
                outside = mid
        return inside

    intervals = []
    for i, j in runs:
        lo = grid[i] if i == 0 else edge(grid[i], grid[i - 1])
        hi = grid[j] if j == n - 1 else edge(grid[j], grid[j + 1])
        intervals.append([lo, hi])
    # the grid holds 0 and 2 pi: a run through both ends is one interval round the circle
    (start, _), *_ = runs
    *_, (_, stop) = runs
    if len(intervals) > 1 and start == 0 and stop == n - 1:
        (_, first_hi), *middle, (lo, _) = intervals
        intervals = [*middle, [lo, first_hi + TWO_PI]]
    elif len(intervals) == 1 and start == 0 and stop == n - 1:
        intervals = [[0.0, TWO_PI]]
    return mask, tuple((float(lo) % TWO_PI, float(lo) % TWO_PI + float(hi - lo)) for lo, hi in intervals)


def wave_existence_edge(model: BarModelLike, k: int = 1) -> float:
    """Existence edge of the pneumatic load (eq. 33) under the wave law: the largest ``k p0 / pk``
    with one-impact orbits.

    The residual is linear in the load: ``r = p0 a + pk |b| cos(k phase + theta)`` with ``a`` the
    residual of the unit mean load and ``|b|`` the amplitude of the unit harmonic's, so orbits exist
    iff ``|p0 a| <= pk |b|`` (the analogue of eq. 38; ``inf`` when ``a = 0``, ``nan`` when the
    window does not fit in the period).

    Parameters
    ----------
    model : BarModel
        Under the wave law.
    k : int
        Order of the harmonic, ``>= 1``.

    Returns
    -------
    float

    Notes
    -----
    Kept for the last 256 models and orders (a model is immutable): a chart asks for the edge of
    each model in every search of its stability edges.
    """
    return _existence_edge(model, k)


@functools.lru_cache(maxsize=256)
def _existence_edge(model: BarModelLike, k: int) -> float:
    """:func:`wave_existence_edge`, computed."""
    from ...loads import CosineLoad

    if _window(model).flight <= 0.0:
        return math.nan
    a = abs(float(wave_phase_residual(model, CosineLoad(1.0, 0.0, k), 0.0)))
    Ms = 2 * k + 1
    ph = TWO_PI * np.arange(Ms) / Ms
    b = 2.0 * abs(np.fft.fft(wave_phase_residual(model, CosineLoad(0.0, 1.0, k), ph))[k]) / Ms
    return math.inf if a == 0.0 else k * b / a


def _refined_grid(resid, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` equispaced phases, each interval around a sampled local minimum of ``|r|`` without a
    sign change split 16-fold (where two roots close to a fold may hide between samples). Returns
    the phases and the residual there (each phase evaluated once)."""
    grid = np.linspace(0.0, TWO_PI, n)
    r0 = resid(grid)
    r = np.abs(r0)
    extra = []
    for i in range(1, n - 1):
        if r[i] <= r[i - 1] and r[i] <= r[i + 1]:
            extra.append(np.linspace(grid[i - 1], grid[i + 1], 33)[1:-1])
    full = np.unique(np.concatenate([grid, *extra]))
    known = np.isin(full, grid)
    out = np.empty(full.size)
    out[known] = r0[np.searchsorted(grid, full[known])]
    if not np.all(known):
        out[~known] = resid(full[~known])
    return full, out


def orbit_state(model: BarModelLike, load: Load, phase: float) -> OrbitState:
    """The wave law's one-impact orbit with this phase (theory §4b): contact over ``[0, 2/s]``, flight
    over ``[2/s, 2 pi]``. The states at the window's end and at the arrival, the multipliers
    (:func:`wave_floquet_multipliers`) and, for an arrival moving into the rod, the contact by
    characteristics (:class:`~impactbar.WaveImpact`) with whether it loses contact inside the
    window."""
    M = model.n_modes + 1
    _, y_end, y_minus, rate, drive = _orbit_states(model, load, phase)
    c = model.end_weights
    v_imp = float(c @ y_minus[M:])
    impact = None
    if v_imp > 0.0:
        qm = y_minus[:M].copy()
        qm[0] -= float(c @ qm)  # the end exactly on the rod end (rounding)
        impact = _wave_impact(model, load, float(phase), qm, y_minus[M:], drive)
    mu = wave_floquet_multipliers(model, load, phase, y_end, y_minus, rate)
    return OrbitState(state_after_impact=y_end, state_before_impact=y_minus, multipliers=mu, impact=impact,
                      separates=impact is not None and bool(impact.separations))


def wave_impact_map_jacobian(model: BarModelLike, load: Load, phase: float, y_end, y_minus,
                             drive_rate) -> np.ndarray:
    """Analytic Jacobian of the wave law's impact map at a one-impact fixed point (theory §7, §4b).

    The map takes ``z = (t_e, q_1..q_N, q_0'..q_N')`` at the end of one contact window to the same at
    the end of the next; ``q_0`` follows from contact. With ``Psi`` the fundamental matrix over the
    flight ``2 pi - 2/s``, ``f`` the vector field, ``c`` the end weights:

        dY = Psi [dy_e - f(t_e, y_e) dt_e],   dtau' = -(c . dq) / (c . q'(tau')),
        dz' = -R [dY + f(tau', Y) dtau'] + (dg, dh)/dphase dtau',    dt_e' = dtau'.

    Parameters
    ----------
    model, load, phase
        As for :func:`wave_orbit_states`.
    y_end, y_minus : array_like, shape (2 N + 2,)
        States at the end of the window and just before the impact.
    drive_rate : tuple of numpy.ndarray
        ``d(g, h)/d phase`` from :func:`wave_orbit_states`.

    Returns
    -------
    numpy.ndarray, shape (2 N + 2, 2 N + 2)

    Raises
    ------
    ValueError
        At grazing (zero impact velocity).
    """
    M = model.n_modes + 1
    T, F = _window(model)
    dY, r = arrival_derivative(model, load, phase + T, F, y_end, y_minus, phase + TWO_PI,
                                _flight_fundamental(model))
    dY = -model.R * dY + np.outer(np.concatenate(drive_rate), r)
    DP = np.empty((2 * M, 2 * M))
    DP[0, :] = r
    DP[1:, :] = dY[1:, :]
    return DP


def wave_floquet_multipliers(model: BarModelLike, load: Load, phase: float, y_end, y_minus, drive_rate, *,
                             method: str = "auto") -> np.ndarray:
    """Floquet multipliers of a one-impact orbit under the wave law: the eigenvalues of
    :func:`wave_impact_map_jacobian` (theory §7, §4b), sorted by
    :func:`~impactbar.dynamics.monodromy.sort_multipliers`.

    ``method="dense"`` takes the eigenvalues of the Jacobian, ``O(N^3)``. ``method="structured"``
    uses the structure the paper's law has (:func:`~impactbar.laws.paper.stability.floquet_multipliers`):
    in the state extended by the window's end time, the map is ``W S (P + h e_t^T)`` (flight of
    fixed length ``2 pi - 2/s``, saltation ``S``, window ``W``). ``W = diag(-R I, 1) +
    (Q g') e_t^T`` on the image of ``S`` (which keeps the end on the rod end, so contact's
    projection ``Q`` acts only on the drive's rate ``g' = d(g, h)/d phase``), and ``e_t^T S (P + h
    e_t^T) = (1 - c.h/v) e_t^T - (P^T c)^T / v`` lies in the span of the saltation's own factors:
    the map is the block-diagonal ``diag(-R Phi_n(2 pi - 2/s), 1)`` plus a rank-2 correction, and its
    eigenvalues (those of the map and one zero) come from the same Aberth-Ehrlich iteration,
    ``O(N^2)``. With ``R = 0`` the map is ``u r^T`` (rank one): one multiplier ``r . u``, the rest 0.
    ``"auto"`` (default) takes the structured method from 40 flexible modes on for ``d <= 1`` (as
    for the paper's law), the dense one otherwise or where the iteration does not settle.

    Parameters
    ----------
    model, load, phase, y_end, y_minus, drive_rate
        As for :func:`wave_impact_map_jacobian`.
    method : {"auto", "dense", "structured"}

    Returns
    -------
    numpy.ndarray of complex, shape (2 N + 2,)
        Infinite at exact grazing (zero impact velocity).

    Raises
    ------
    ValueError
        For an unknown ``method``.
    """
    if method not in ("auto", "dense", "structured"):
        raise ValueError(f"method must be 'auto', 'dense' or 'structured'; got {method!r}")
    M = model.n_modes + 1
    if method == "auto":
        use = model.n_modes >= MD.STRUCTURED_FROM and model.d <= MD.STRUCTURED_MAX_DAMPING
        method = "structured" if use else "dense"
    try:
        if method == "dense" or model.n_modes == 0:
            DP = wave_impact_map_jacobian(model, load, phase, y_end, y_minus, drive_rate)
            return sort_multipliers(np.linalg.eigvals(DP))
        if model.R == 0.0:  # DP = u r^T
            DP = wave_impact_map_jacobian(model, load, phase, y_end, y_minus, drive_rate)
            u = np.concatenate(([1.0], np.concatenate(drive_rate)[1:]))
            return sort_multipliers(np.concatenate(([complex(DP[0] @ u)], np.zeros(2 * M - 1))))
        parts = _wave_structured_parts(model, load, phase, y_end, y_minus, drive_rate)
    except ValueError:  # exact grazing: a multiplier is infinite
        return np.full(2 * M, np.inf + 0j)
    mu = aberth(*parts)
    if mu is None:
        DP = wave_impact_map_jacobian(model, load, phase, y_end, y_minus, drive_rate)
        return sort_multipliers(np.linalg.eigvals(DP))
    return sort_multipliers(mu)


def _wave_structured_parts(model, load, phase, y_end, y_minus, drive_rate):
    """The blocks and rank-2 factors (as :func:`impactbar.laws.paper.stability._structured_parts`) of
    the wave law's impact map in the state extended by the window's end time (see
    :func:`wave_floquet_multipliers`)."""
    M = model.n_modes + 1
    R = model.R
    c = model.end_weights
    T, F = _window(model)
    v, (f0q, f0v), (f1q, f1v) = impact_fields(model, load, phase + T, y_end, y_minus, phase + TWO_PI)
    p11, p12, p21, p22 = _flight_fundamental(model)
    hq = f1q - (p11 * f0q + p12 * f0v)
    hv = f1v - (p21 * f0q + p22 * f0v)
    ch = float(c @ hq)
    gq, gv = (np.array(a, dtype=float) for a in drive_rate)
    gq[0] = -float(c[1:] @ gq[1:])  # contact's projection of the drive's rate
    a0, a1 = 1.0 - ch / v, -1.0 / v
    U = np.empty((M, 2, 2))
    U[:, 0, 0] = -R * hq + R * ch / v * f1q + a0 * gq
    U[:, 1, 0] = -R * hv + R * ch / v * f1v + a0 * gv
    U[:, 0, 1] = R * f1q / v + a1 * gq
    U[:, 1, 1] = R * f1v / v + a1 * gv
    V = np.zeros((M, 2, 2))
    V[:, 0, 1] = c * p11
    V[:, 1, 1] = c * p12
    ut = np.array([-ch / v, -1.0 / v])
    vt = np.array([1.0, 0.0])
    return -R * p11, -R * p12, -R * p21, -R * p22, U, V, ut, vt
