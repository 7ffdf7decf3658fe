"""One-impact periodic orbits (paper Section 2, MODEL.md sections 4, 5, 7).

``periodic_orbits(model, load)`` finds every root ``phase`` of the phase equation (eq. 14),
builds the orbit's modal state, decides admissibility rigorously, and computes the exact Floquet
multipliers and the paper's Schur criterion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ._certified import enclose_zeros, zeros_in_clusters
from ._threads import single_threaded_blas
from .loads import Load
from .modal import fundamental
from .model import BarModel
from .stability import (
    impact_map_jacobian,
    phase_G,
    quadratic_roots,
    schur_blocks,
    schur_test,
)

__all__ = ["PeriodicOrbit", "periodic_orbits", "phase_residual", "phase_roots", "orbit_multipliers"]

TWO_PI = 2.0 * math.pi


def _check_inputs(model, load):
    if not isinstance(model, BarModel):
        raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
    if not isinstance(load, Load):
        raise ValueError(f"load must be a Load (CosineLoad, SquareWaveLoad, ...); got "
                         f"{type(load).__name__}")


def phase_residual(model: BarModel, load: Load, phase) -> np.ndarray:
    """Left minus right side of the phase equation (eq. 14, MODEL.md section 4).

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

    clusters = enclose_zeros(F, lambda m, h: np.full(np.shape(m), lip), 0.0, TWO_PI,
                             n0=64, min_width=1e-7)
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
    ratio = B / A
    if abs(ratio) > 1.0 + 1e-15:
        return []
    if abs(ratio) >= 1.0 - 1e-15:
        base, mult = [math.acos(max(-1.0, min(1.0, ratio)))], 2
    else:
        a = math.acos(ratio)
        base, mult = [a, -a], 1
    out = []
    for b in base:
        for j in range(k):
            out.append(((b - theta + TWO_PI * j) / k) % TWO_PI)
    return [(t, mult) for t in sorted(out)]


@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """A one-impact-per-period steady state (paper Section 2) with its stability.

    Orbit time ``t`` is counted from an impact: the impacts are at ``t = 0, 2 pi, ...``, and the load
    acting at orbit time ``t`` is ``p(t + phase)`` (eq. 7).

    Attributes
    ----------
    model : BarModel
    load : Load
    phase : float
        Phase lag ``phase`` in ``[0, 2 pi)`` between load and impact cycle (rad), a root of eq. 14.
    multiplicity : int
        1, or 2 for a double root of the phase equation (a fold, where two orbits merge).
    impact_velocity : float
        ``u_t(1, 2 pi-)``, velocity of the struck end just before impact (dimensionless); > 0 for a
        physical orbit.
    admissible : bool
        The end stays off the stop between impacts (``u(1, t) < 0`` for ``0 < t < 2 pi``), leaves it
        (for ``R = 0``: the end's acceleration just after impact points away from the stop) and
        arrives moving forward (MODEL.md section 5). Decided with certified bounds, not sampling.
    admissibility : str
        ``"admissible"``, or why not: ``"penetrates"``, ``"grazing"``, ``"backward impact"``,
        ``"sticks"`` (R = 0 and the load presses the end on the stop after impact).
    clearance : float
        Largest value of ``u(1, t)`` at its stationary points between impacts (dimensionless): < 0
        for an admissible orbit, > 0 where the end swings through the stop, ~0 at grazing. By Rolle's
        theorem there is at least one stationary point.
    clearance_error : float
        Bound on the error of ``clearance`` from the enclosure of the stationary points.
    multipliers : numpy.ndarray of complex, shape (2 N + 2,)
        Exact Floquet multipliers (eigenvalues of the impact map's Jacobian, MODEL.md section 7),
        sorted by decreasing modulus.
    stable : bool
        ``admissible`` and every ``|multiplier| < 1``.
    schur_roots : numpy.ndarray of complex, shape (2 N + 2,)
        Roots of the paper's quadratic blocks (eqs. 27, 29-31), rigid block first.
    schur_stable : bool
        The paper's criterion (Schur's conditions, eq. 28) on every block; ignores admissibility.
    state_after_impact : numpy.ndarray, shape (2 N + 2,)
        Modal state ``(q_0..q_N, q_0'..q_N')`` at ``t = 0+``.
    state_before_impact : numpy.ndarray, shape (2 N + 2,)
        Modal state at ``t = 2 pi-``.
    """

    model: BarModel
    load: Load
    phase: float
    multiplicity: int
    impact_velocity: float
    admissible: bool
    admissibility: str
    clearance: float
    clearance_error: float
    multipliers: np.ndarray = field(repr=False)
    stable: bool
    schur_roots: np.ndarray = field(repr=False)
    schur_stable: bool
    state_after_impact: np.ndarray = field(repr=False)
    state_before_impact: np.ndarray = field(repr=False)

    @property
    def max_abs_multiplier(self) -> float:
        """Largest ``|multiplier|`` (spectral radius of the impact map's Jacobian)."""
        return float(np.max(np.abs(self.multipliers)))

    @property
    def modal_state_after_impact(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q, q')`` just after the impact, each shape ``(N + 1,)``."""
        M = self.model.n_modes + 1
        return self.state_after_impact[:M].copy(), self.state_after_impact[M:].copy()

    def modal_state(self, t):
        """Modal displacements and velocities at orbit times ``t``.

        Parameters
        ----------
        t : array_like, shape (T,)
            Orbit times (dimensionless); taken modulo ``2 pi``, and a multiple of ``2 pi`` gives the
            state just after the impact.

        Returns
        -------
        q, v : numpy.ndarray, shape (N + 1, T)
        """
        t = np.atleast_1d(np.asarray(t, dtype=float)).ravel()
        return self._state_in_period(np.mod(t, TWO_PI))

    def _state_in_period(self, t):
        """State at orbit times ``0 <= t <= 2 pi`` without wrapping (``2 pi`` is before impact)."""
        M = self.model.n_modes + 1
        return self.load.propagate(self.model.frequencies**2, self.model.d, self.phase,
                                   self.state_after_impact[:M], self.state_after_impact[M:],
                                   self.phase + np.asarray(t, dtype=float))

    def _field(self, x, t, velocity):
        x = np.asarray(x, dtype=float)
        t = np.asarray(t, dtype=float)
        xb, tb = np.broadcast_arrays(x, t)
        shapes = self.model.shape_functions(xb.ravel())  # (P, M)
        tt, inv = np.unique(tb.ravel(), return_inverse=True)
        q, v = self.modal_state(tt)
        modal = (v if velocity else q)[:, inv]  # (M, P)
        return np.einsum("pm,mp->p", shapes, modal).reshape(xb.shape)

    def displacement(self, x, t) -> np.ndarray:
        """Displacement ``u(x, t)`` (eq. 15), dimensionless.

        Parameters
        ----------
        x : array_like
            Positions in ``[0, 1]``; broadcast against ``t``.
        t : array_like
            Orbit times (periodic with period ``2 pi``).

        Returns
        -------
        numpy.ndarray, shape ``broadcast(x, t).shape``
        """
        return self._field(x, t, velocity=False)

    def velocity(self, x, t) -> np.ndarray:
        """Velocity ``u_t(x, t)``, same conventions as :meth:`displacement`; at multiples of
        ``2 pi`` the velocity just after the impact."""
        return self._field(x, t, velocity=True)

    def end_displacement(self, t) -> np.ndarray:
        """Displacement of the struck end ``u(1, t)``, shape of ``t``."""
        t = np.asarray(t, dtype=float)
        q, _ = self.modal_state(t.ravel())
        return (self.model.end_weights @ q).reshape(t.shape)

    def to_dict(self) -> dict:
        """A JSON-ready summary (floats, lists of ``[re, im]``; ``clearance`` may be ``-inf``)."""
        return {
            "phase": self.phase,
            "multiplicity": self.multiplicity,
            "impact_velocity": self.impact_velocity,
            "admissible": self.admissible,
            "admissibility": self.admissibility,
            "clearance": self.clearance,
            "stable": self.stable,
            "max_abs_multiplier": self.max_abs_multiplier,
            "multipliers": [[m.real, m.imag] for m in self.multipliers],
            "schur_stable": self.schur_stable,
            "schur_roots": [[m.real, m.imag] for m in self.schur_roots],
        }


def periodic_orbits(model: BarModel, load: Load) -> list[PeriodicOrbit]:
    """Every one-impact-per-period steady state of the bar under the load (paper Section 2).

    Each root ``phase`` of the phase equation (eq. 14) in ``[0, 2 pi)`` gives one orbit: the flexible
    modes' start state solves the periodicity and impact conditions (eqs. 10-13) exactly, mode by
    mode; the rigid mode strikes at ``2 pi p0 / (1 + R)`` and its constant is fixed by contact
    ``u(1, 0) = 0``.

    Parameters
    ----------
    model : BarModel
    load : Load
        Any load of period ``2 pi``: ``CosineLoad``, ``SquareWaveLoad``, ``FourierLoad``, ...

    Returns
    -------
    list of PeriodicOrbit
        Sorted by phase; empty when none exists (e.g. above the fold, eq. 38).

    Raises
    ------
    ValueError
        For inputs of the wrong type, or at an undamped resonance ``s n pi = k`` (eq. 16).

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, periodic_orbits
    >>> orbits = periodic_orbits(BarModel(s=10, d=0, R=0.5, n_modes=4), CosineLoad(0.5, 1.0))
    >>> [round(o.phase, 4) for o in orbits]
    [0.5148, 2.6268]
    """
    _check_inputs(model, load)
    with single_threaded_blas():
        return [_build_orbit(model, load, ph, mult) for ph, mult in phase_roots(model, load)]


def _start_state(model: BarModel, load: Load, phase: float) -> np.ndarray:
    """Modal state just after the impact of the orbit with this phase (eqs. 10-13)."""
    N = model.n_modes
    R, d = model.R, model.d
    q = np.zeros(N + 1)
    v = np.zeros(N + 1)
    if N > 0:
        w2 = model.frequencies[1:] ** 2
        zeros = np.zeros(N)
        fq, fv = load.propagate(w2, d, phase, zeros, zeros, [phase + TWO_PI])
        fq, fv = fq[:, 0], fv[:, 0]
        p11, p12, p21, p22 = fundamental(w2, d, TWO_PI)
        # y = J_R (Phi y + f),  J_R = diag(1, -R)
        a11, a12, a21, a22 = 1.0 - p11, -p12, R * p21, 1.0 + R * p22
        det = a11 * a22 - a12 * a21
        if np.any(np.abs(det) < 1e-13):
            if R == 1.0 and d == 0.0:
                raise ValueError("R = 1 with d = 0 and flexible modes: a conservative bar with elastic "
                                 "impacts has a continuum of one-impact orbits, not isolated ones; "
                                 "use d > 0, R < 1 or n_modes = 0")
            raise ValueError("the periodicity conditions are singular (undamped resonance, eq. 16)")
        r1, r2 = fq, -R * fv
        q[1:] = (a22 * r1 - a12 * r2) / det
        v[1:] = (a11 * r2 - a21 * r1) / det
    v[0] = -R * TWO_PI * load.p0 / (1.0 + R)
    q[0] = -float(model.end_weights[1:] @ q[1:])
    return np.concatenate((q, v))


def orbit_multipliers(model: BarModel, load: Load, phase: float, *, paper: bool = False) -> np.ndarray:
    """Floquet multipliers of the orbit with this phase, without the admissibility check.

    Parameters
    ----------
    model : BarModel
    load : Load
    phase : float
        A root of the phase equation (rad).
    paper : bool
        Return the roots of the paper's quadratic blocks (eqs. 27-31) instead of the exact
        multipliers (MODEL.md section 7).

    Returns
    -------
    numpy.ndarray of complex, shape (2 N + 2,)
    """
    if paper:
        return quadratic_roots(schur_blocks(model, load, phase))
    y_plus, y_minus = _impact_states(model, load, phase)
    with single_threaded_blas():
        return np.linalg.eigvals(impact_map_jacobian(model, load, phase, y_plus, y_minus))


def _impact_states(model: BarModel, load: Load, phase: float):
    """Modal states just after (``t = 0+``) and just before (``t = 2 pi-``) the orbit's impact."""
    M = model.n_modes + 1
    y_plus = _start_state(model, load, phase)
    qm, vm = load.propagate(model.frequencies**2, model.d, phase, y_plus[:M], y_plus[M:],
                            [phase + TWO_PI])
    return y_plus, np.concatenate((qm[:, 0], vm[:, 0]))


def _build_orbit(model: BarModel, load: Load, phase: float, mult: int) -> PeriodicOrbit:
    M = model.n_modes + 1
    y_plus, y_minus = _impact_states(model, load, phase)
    c = model.end_weights
    v_imp = float(c @ y_minus[M:])

    status, clearance, cerr = _admissibility(model, load, phase, y_plus, v_imp)
    admissible = status == "admissible"

    try:
        DP = impact_map_jacobian(model, load, phase, y_plus, y_minus)
    except ValueError:  # exact grazing: a multiplier is infinite
        mu = np.full(2 * M, np.inf + 0j)
    else:
        mu = np.linalg.eigvals(DP)
        mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    blocks = schur_blocks(model, load, phase)
    return PeriodicOrbit(
        model=model,
        load=load,
        phase=float(phase),
        multiplicity=int(mult),
        impact_velocity=v_imp,
        admissible=admissible,
        admissibility=status,
        clearance=clearance,
        clearance_error=cerr,
        multipliers=mu,
        stable=bool(admissible and np.all(np.abs(mu) < 1.0)),
        schur_roots=quadratic_roots(blocks),
        schur_stable=schur_test(blocks),
        state_after_impact=y_plus,
        state_before_impact=y_minus,
    )


def _admissibility(model, load, phase, y_plus, v_imp):
    """Decide admissibility (MODEL.md section 5) with certified bounds.

    The stationary points of ``g(t) = u(1, t)`` are the zeros of ``g' = c . q'``; they are enclosed
    with a bound of ``|g''|`` on each interval, built from each mode's energy about the static
    deflection under the local load: ``sqrt(v^2 + w^2 (q - P/w^2)^2)`` grows at most by the load's
    variation times the time elapsed (and by ``e^{d h}`` going backwards), and
    ``|q''| <= delta + (d + w) sqrt(E)``.
    """
    M = model.n_modes + 1
    w2 = model.frequencies**2
    w = np.sqrt(w2)
    d, R = model.d, model.R
    c = model.end_weights
    absc = np.abs(c)
    psup = load.sup_abs
    q0, v0 = y_plus[:M], y_plus[M:]

    flow = load.flow(w2, d, phase, q0, v0)

    def states(t):
        return flow(phase + np.asarray(t, dtype=float))

    def g(t):
        return c @ states(t)[0]

    def gprime_and_bound(mid, half):
        q, v = states(mid)
        center, delta = load.variation(phase + mid, half)
        grow = np.exp(d * np.asarray(half))
        bound = np.empty_like(q)
        flex = w2 > 0
        wc = w[flex, None]
        sqrtE = np.sqrt(v[flex] ** 2 + (wc * q[flex] - center / wc) ** 2)
        Eb = (sqrtE + delta * half) * grow
        bound[flex] = delta + (d + wc) * Eb
        vb = (np.abs(v[~flex]) + psup * half) * grow
        bound[~flex] = psup + d * vb
        return c @ v, absc @ bound

    scale = max(abs(v_imp), psup, 1e-300)
    clusters = enclose_zeros(None, None, 0.0, TWO_PI, n0=64, min_width=6e-3,
                             joint=gprime_and_bound, merge=False, atol=1e-13 * scale)
    # the departure: for R = 0 every velocity is zero just after impact, so t = 0 is a stationary
    # point of g; the end leaves the stop iff its acceleration there points away from the stop.
    if R == 0.0:
        acc0 = float(c @ (float(load(phase)) - d * v0 - w2 * q0))
        clusters = [cl for cl in clusters if cl[0] > 1e-6]
    # the stationary points that can carry the largest value are refined to full precision
    values, err_b = _stationary_values(states, gprime_and_bound, load, phase, c, w2, d, clusters,
                                       atol=1e-13 * scale)
    err = err_b + 1e-12 * scale * (1.0 + max((abs(v) for v in values), default=0.0))
    clearance = max(values) if values else -math.inf
    tol = max(err, 1e-11 * scale)
    if not v_imp > 1e-12 * scale:
        status = "grazing" if abs(v_imp) <= 1e-12 * scale else "backward impact"
    elif R == 0.0 and not acc0 < 0.0:
        status = "sticks"
    elif clearance > tol:
        status = "penetrates"
    elif clearance >= -tol:
        status = "grazing"
    else:
        status = "admissible"
    return status, clearance, err


def _newton_stationary(states, load, phase, c, w2, d, lo, hi):
    """Vectorised Newton for zeros of ``g' = c . q'`` on intervals ``[lo, hi]``, with
    ``g'' = c . (p - d q' - w2 q)``. Returns the final points and which converged inside."""
    t = 0.5 * (lo + hi)
    ok = np.zeros(t.size, dtype=bool)
    for _ in range(8):
        q, v = states(t)
        g1 = c @ v
        g2 = c @ (load(phase + t)[None, :] - d * v - w2[:, None] * q)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(g2 != 0.0, g1 / g2, np.inf)
        step = np.nan_to_num(step, nan=np.inf)
        t_new = t - np.where(np.isfinite(step), step, 0.0)
        inside = (t_new >= lo) & (t_new <= hi) & np.isfinite(step)
        t = np.clip(t_new, lo, hi)
        ok = inside & (np.abs(step) < 1e-12)
        if np.all(ok | ~inside):
            break
    return t, ok


def _stationary_values(states, bound, load, phase, c, w2, d, intervals, rounds=8, atol=0.0):
    """Largest values of ``g = c . q`` at its stationary points, by branch and bound.

    All narrow intervals that may hold a zero of ``g'`` get a vectorised Newton step; converged
    points give stationary values. An interval where Newton fails is kept only if an upper bound of
    ``g`` on it, ``g(mid) + (|g'(mid)| + L h) h``, can still beat the best value found; those are
    split 64-fold by the certified exclusion and tried again. Where that cannot go on (a zero of
    ``g'`` of high order, whose enclosure does not shrink), the upper bounds themselves are used.

    Returns
    -------
    values : list of float
    err : float
        Bound on the error of the largest value (0 up to rounding when every stationary point
        that matters was located; otherwise the spread of the bounds on the unresolved intervals,
        whose upper end is reported).
    """
    def value_bounds(iv):
        """``g`` at the midpoints and its upper bound on each interval."""
        mid = 0.5 * (iv[:, 0] + iv[:, 1])
        half = 0.5 * (iv[:, 1] - iv[:, 0])
        gm = c @ states(mid)[0]
        g1, L2 = bound(mid, half)
        return gm, gm + (np.abs(g1) + L2 * half) * half

    values: list[float] = []
    err = 0.0
    best = -math.inf
    cur = np.array(intervals, dtype=float).reshape(-1, 2)
    for _ in range(rounds):
        if cur.size == 0:
            break
        lo, hi = cur[:, 0], cur[:, 1]
        t, ok = _newton_stationary(states, load, phase, c, w2, d, lo, hi)
        if np.any(ok):
            vals = c @ states(t[ok])[0]
            values.extend(float(x) for x in vals)
            best = max(best, float(np.max(vals)))
        rest = cur[~ok]
        if rest.size == 0:
            cur = rest
            break
        gm, upper = value_bounds(rest)
        keep = upper >= best
        rest, gm, upper = rest[keep], gm[keep], upper[keep]
        cur = rest
        if rest.size == 0:
            break
        width = float(np.max(rest[:, 1] - rest[:, 0]))
        try:
            cur = np.array(enclose_zeros(None, None, 0.0, TWO_PI, n0=8, min_width=width / 64.0,
                                         joint=bound, intervals=rest, merge=False,
                                         max_intervals=20_000, atol=atol)).reshape(-1, 2)
        except RuntimeError:  # a zero of high order: the enclosure no longer shrinks
            lower = 2.0 * gm - upper  # gm - slack
            values.append(float(np.max(upper)))  # conservative: never below the true value
            err = max(err, float(np.max(upper) - np.min(lower)))
            cur = np.empty((0, 2))
            break
    if cur.size:  # rounds exhausted: bound what is left
        gm, upper = value_bounds(cur)
        if float(np.max(upper)) >= best:
            values.append(float(np.max(upper)))  # conservative: never below the true value
            err = max(err, float(np.max(upper) - np.min(2.0 * gm - upper)))
    return values, err
