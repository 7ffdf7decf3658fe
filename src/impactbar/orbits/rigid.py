"""Closed forms for the rigid bar (``n_modes = 0``), vectorised over parameter arrays.

For the rigid bar the one-impact orbit needs no search at all (theory §4-§6):

- the phase equation (eq. 14) of the pneumatic load (eq. 33) is ``A cos(k phase + theta) = B``;
- the end's velocity ``v = q_0'`` obeys ``v' + d v = p``, so at a zero of ``v`` its slope is the
  load: every zero inside an arc where the load pulls (``p < 0``) is downward, every zero inside an
  arc where it pushes is upward, and each arc holds at most one zero (two zeros in a row would need
  one of each kind). The stationary points of ``u(1, t) = q_0`` are found arc by arc, one bracketed
  root each, with no certified search;
- the impact map's Jacobian is 2 x 2 (theory §7), its eigenvalues a quadratic formula.

Everything here takes numpy arrays of parameters (broadcast together) and returns arrays; the
general path in :mod:`impactbar.orbits.one_impact` is the reference these are tested against.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._shared.status import Admissibility
from ..dynamics.implementations import use_fast
from ..laws.paper.stability import _b, rigid_multipliers
from ..loads import CosineLoad, SquareWaveLoad
from ._rigid_scalar import harmonic_term
from .stability import MARGINAL, quadratic_roots

__all__ = ["RigidOrbits", "rigid_cosine_orbits", "rigid_square_orbits", "rigid_multipliers", "phase_G_array",
           "STATUS", "CLOSED_FORM_KINDS", "closed_form_groups"]

TWO_PI = 2.0 * math.pi

#: admissibility codes used by :class:`RigidOrbits`, in the order of their integer codes
STATUS = (Admissibility.ADMISSIBLE, Admissibility.PENETRATES, Admissibility.GRAZING,
          Admissibility.BACKWARD_IMPACT, Admissibility.STICKS)


#: the kinds of load (the table of loads, :data:`impactbar.loads.LOADS`) whose one-impact orbits of
#: the rigid bar have closed forms here
CLOSED_FORM_KINDS = (CosineLoad.traits.kind, SquareWaveLoad.traits.kind)


def closed_form_groups(kind: str, par):
    """The points of a grid that the closed forms take, in groups of one call each.

    Parameters
    ----------
    kind : str
        The load's kind, one of :data:`CLOSED_FORM_KINDS`.
    par : mapping of str to numpy.ndarray, shape (P,) each
        The model's ``d`` and ``R`` and the load's parameters at every point (numbers).

    Returns
    -------
    list of (numpy.ndarray, callable, tuple) or None
        ``(points, solve, args)``: ``solve(*args)`` gives the :class:`RigidOrbits` of the points
        ``points`` (indices into the grid), in order; the points not in any group (a square wave of
        ``kappa = 2``, a constant load) take the general path. ``None`` for a kind without closed
        forms.
    """
    if kind == CosineLoad.traits.kind:
        ks = par["k"].astype(int)
        groups = []
        for k in np.unique(ks):
            sel = np.nonzero(ks == k)[0]
            groups.append((sel, rigid_cosine_orbits,
                           (*(par[n][sel].astype(float) for n in ("d", "R", "p0", "pk")), int(k))))
        return groups
    if kind == SquareWaveLoad.traits.kind:
        sel = np.nonzero(par["kappa"].astype(float) < 2.0)[0]  # kappa = 2: a constant load, the general path
        return [(sel, rigid_square_orbits, tuple(par[n][sel].astype(float)
                                                 for n in ("d", "R", "q", "kappa")))]
    return None


def _beta(y):
    """``beta(y) = 1/(1 - exp(-y)) - 1/y`` elementwise, by its series where the difference cancels."""
    y = np.asarray(y, dtype=float)
    small = y < 1e-2
    ys = np.where(small, 1.0, y)
    series = 0.5 + y / 12.0 - y**3 / 720.0 + y**5 / 30240.0
    return np.where(small, series, 1.0 / (-np.expm1(-ys)) - 1.0 / ys)


def phase_G_array(d, R):
    """``G(d, R) = 2 pi [(1 + R) beta(2 pi d) - R]`` of the phase equation (eq. 14, theory §4),
    elementwise over arrays ``d``, ``R``."""
    return TWO_PI * ((1.0 + R) * _beta(TWO_PI * np.asarray(d, dtype=float)) - R)


def _c(d, t):
    """``c(t) = (t - b(t)) / d`` elementwise (``t^2/2`` at ``d = 0``), series where it cancels."""
    y = d * t
    small = np.abs(y) < 1e-2
    dd = np.where(small, 1.0, d)
    series = t * t * (0.5 - y / 6.0 + y * y / 24.0 - y**3 / 120.0 + y**4 / 720.0)
    return np.where(small, series, (t - (-np.expm1(-dd * t) / dd)) / dd)


class RigidOrbits(NamedTuple):
    """One-impact orbits of the rigid bar at many parameter points (the fields of
    :class:`impactbar.PeriodicOrbit`, as arrays).

    Each point has ``J`` orbit slots (``2 k`` for the cosine load, 2 for the square wave), filled in
    order of phase; unused slots hold NaN, 0, False or -1.

    Attributes
    ----------
    n_orbits : numpy.ndarray of int, shape (P,)
        Number of orbits at each point.
    phase : numpy.ndarray, shape (P, J)
        Phase lag in ``[0, 2 pi)`` (rad), a root of eq. 14.
    multiplicity : numpy.ndarray of int, shape (P, J)
        1, or 2 for a double root (a fold).
    impact_velocity : numpy.ndarray, shape (P, J)
        ``u_t(1, 2 pi-)``, the arrival velocity (``2 pi p0 / (1 + R)``, theory §4).
    v_plus : numpy.ndarray, shape (P, J)
        Velocity just after the impact, ``-R`` times the arrival velocity.
    q_minus : numpy.ndarray, shape (P, J)
        ``u(1, 2 pi-)``, zero up to rounding.
    status : numpy.ndarray of int8, shape (P, J)
        Index into :data:`STATUS` (``PeriodicOrbit.admissibility``); -1 in unused slots.
    clearance, clearance_error : numpy.ndarray, shape (P, J)
        As ``PeriodicOrbit.clearance`` and ``clearance_error`` (``-inf`` without a stationary point).
    multipliers : numpy.ndarray of complex, shape (P, J, 2)
        Floquet multipliers, by decreasing modulus (``inf`` at grazing).
    schur_roots : numpy.ndarray of complex, shape (P, J, 2)
        Roots of the paper's rigid block (eqs. 29, 30).
    schur_stable, stable : numpy.ndarray of bool, shape (P, J)
        The paper's criterion (eq. 28); admissible with every ``|multiplier| < 1``.
    fallback : numpy.ndarray of bool, shape (P,)
        Points with a degenerate orbit (arrival or departure nearly at rest, within 1e-6 of the
        load's scale), which the closed form leaves to the general path; their other fields are
        not to be used.
    """

    n_orbits: np.ndarray
    phase: np.ndarray
    multiplicity: np.ndarray
    impact_velocity: np.ndarray
    v_plus: np.ndarray
    q_minus: np.ndarray
    status: np.ndarray
    clearance: np.ndarray
    clearance_error: np.ndarray
    multipliers: np.ndarray
    schur_roots: np.ndarray
    schur_stable: np.ndarray
    stable: np.ndarray
    fallback: np.ndarray

    @property
    def admissible(self) -> np.ndarray:
        """``status == "admissible"``, shape (P, J)."""
        return self.status == 0

    @property
    def max_abs_multiplier(self) -> np.ndarray:
        """Largest ``|multiplier|`` of each orbit, shape (P, J) (NaN in unused slots)."""
        return np.abs(self.multipliers[..., 0])


def _cosine_roots(d, R, p0, pk, k):
    """Roots of the phase equation for ``p0 + pk cos(k t)`` (eq. 14 in closed form), shape (P, 2k)."""
    # F = (1 + R) Re[pk e^{i k phase}/(d + i k)] - p0 G = A cos(k phase + theta) - B
    _, zr, zi = harmonic_term(d, R, pk, k)
    A = np.hypot(zr, zi)
    theta = np.arctan2(zi, zr)
    B = p0 * phase_G_array(d, R)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(A > 0.0, B / np.where(A > 0.0, A, 1.0), np.inf)
    exists = (np.abs(ratio) <= 1.0 + 1e-15) & (A > 0.0)
    double = exists & (np.abs(ratio) >= 1.0 - 1e-15)
    a = np.arccos(np.clip(ratio, -1.0, 1.0))
    j = np.arange(k)
    base = np.stack((a, -a), axis=-1)  # (P, 2)
    ph = ((base[:, :, None] - theta[:, None, None] + TWO_PI * j) / k) % TWO_PI  # (P, 2, k)
    ph = ph.reshape(-1, 2 * k)
    ph[double, k:] = np.nan  # a double root once
    ph[~exists] = np.nan
    ph = np.sort(ph, axis=1)  # NaN last
    mult = np.where(np.isnan(ph), 0, np.where(double[:, None], 2, 1))
    return ph, mult


class _CosineFlight:
    """The rigid bar's flight between impacts under ``p0 + pk cos(k t)``, one entry per orbit.

    With ``V`` the periodic zero-mean solution of ``V' + d V = p - p0`` and ``W`` its antiderivative
    (closed forms), the flight from the impact at load time ``phase`` with velocity ``v+`` is
    ``v(t) = V(phase + t) + p0 b(t) + (v+ - V(phase)) e^{-d t}`` and
    ``u(1, t) = q_0(t) = W(phase + t) - W(phase) + p0 c(t) + (v+ - V(phase)) b(t)`` (theory §4).
    The parameter arrays broadcast against the times (see :meth:`take`).
    """

    def __init__(self, d, p0, pk, phase, k, free=None, W0=None, v_plus=None):
        self.d, self.p0, self.pk, self.phase, self.k = d, p0, pk, phase, k
        self.a = pk * d / (d * d + k * k)  # V(t) = a cos(k t) + b sin(k t)
        self.b = pk * k / (d * d + k * k)
        self.free = v_plus - self._V(phase) if free is None else free
        self.W0 = self._W(phase) if W0 is None else W0

    def take(self, rows, grid=False):
        """The flights of some orbits, as columns (``grid``: times of shape (rows, B))."""
        def g(x):
            x = x[rows]
            return x[:, None] if grid else x
        return _CosineFlight(g(self.d), g(self.p0), g(self.pk), g(self.phase), self.k,
                             free=g(self.free), W0=g(self.W0))

    def _V(self, tl):
        x = self.k * tl
        return self.a * np.cos(x) + self.b * np.sin(x)

    def _W(self, tl):
        x = self.k * tl
        return (self.a * np.sin(x) - self.b * np.cos(x)) / self.k

    def velocity(self, t):
        return self._V(self.phase + t) + self.p0 * _b(self.d, t) + self.free * np.exp(-self.d * t)

    def displacement(self, t):
        return (self._W(self.phase + t) - self.W0 + self.p0 * _c(self.d, t)
                + self.free * _b(self.d, t))

    def load(self, t):
        return self.p0 + self.pk * np.cos(self.k * (self.phase + t))


def rigid_cosine_orbits(d, R, p0, pk, k: int) -> RigidOrbits:
    """Every one-impact orbit of the rigid bar under ``p0 + pk cos(k t)`` (eq. 33) at many points.

    The same orbits, admissibility, clearance and multipliers as
    :func:`impactbar.periodic_orbits` with ``BarModel(s, d, R, 0)`` and ``CosineLoad(p0, pk, k)``
    (the tests check them against it to 1e-10), from closed forms: the phase equation (eq. 14,
    theory §4), the stationary points of the end's displacement, one per arc of constant load sign
    (theory §5), and the 2 x 2 impact-map Jacobian (theory §7). The wave-speed ratio ``s`` plays
    no part in a rigid bar.

    Parameters
    ----------
    d, R, p0, pk : array_like
        Damping (``>= 0``), restitution coefficient (``[0, 1]``), mean load and amplitude
        (dimensionless, eq. 2); broadcast together, then flattened to ``P`` points. Not validated:
        the callers pass validated values.
    k : int
        Order of the harmonic, ``>= 1`` (one value for all points).

    Returns
    -------
    RigidOrbits
        ``fallback`` marks the points with a degenerate orbit (arrival or departure nearly at
        rest) that the closed form leaves to the general path.
    """
    d, R, p0, pk = (np.ravel(x) for x in np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (d, R, p0, pk))))
    k = int(k)
    if use_fast("orbits.rigid_arrays"):
        return _compiled("cosine_orbits", (d, R, p0, pk, k), 2 * k)
    ph, mult = _cosine_roots(d, R, p0, pk, k)
    pi_, ji = np.nonzero(~np.isnan(ph))  # one row per orbit
    o_d, o_R, o_p0, o_pk, o_ph = d[pi_], R[pi_], p0[pi_], pk[pi_], ph[pi_, ji]
    O = o_d.size
    allo = np.arange(O)
    v_plus = -o_R * TWO_PI * o_p0 / (1.0 + o_R)  # theory §4: the rigid mode strikes at 2 pi p0/(1+R)
    fl = _CosineFlight(o_d, o_p0, o_pk, o_ph, k, v_plus=v_plus)
    v_minus = fl.velocity(TWO_PI)
    q_minus = fl.displacement(TWO_PI)
    p_plus = o_p0 + o_pk * np.cos(k * o_ph)
    psup = np.abs(o_p0) + np.abs(o_pk)
    r0 = o_R == 0.0

    # --- stationary points of u(1, t): at most one zero of v per arc of constant load sign, and
    # it exists iff v changes sign over the arc (v' = p - d v, so v' = p at a zero of v)
    bounds = np.full((O, 2 * k + 2), TWO_PI)
    bounds[:, 0] = 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(o_pk != 0.0, -o_p0 / np.where(o_pk != 0.0, o_pk, 1.0), np.inf)
    crosses = np.abs(ratio) < 1.0
    alpha = np.arccos(np.clip(ratio, -1.0, 1.0))
    jj = TWO_PI * np.arange(k)
    zs = np.concatenate(((alpha[:, None] + jj) / k, (jj - alpha[:, None]) / k), axis=1)
    zs = np.mod(zs - o_ph[:, None], TWO_PI)  # the load's sign changes, in orbit time
    zs[~crosses] = TWO_PI
    bounds[:, 1:-1] = np.sort(zs, axis=1)
    vb = fl.take(allo, grid=True).velocity(bounds)
    # the sign just after the impact: that of v+, or for R = 0 (v+ = 0) of the acceleration
    vb[:, 0] = np.where(r0, p_plus, v_plus)
    lo_t, hi_t = bounds[:, :-1], bounds[:, 1:]
    sgn = np.sign(vb)
    bracket = (sgn[:, :-1] * sgn[:, 1:] < 0.0) & (hi_t > lo_t)
    oi, ai = np.nonzero(bracket)
    sub = fl.take(oi)
    t = _bracketed_zero(sub, lo_t[oi, ai], hi_t[oi, ai], sgn[oi, ai])
    g = sub.displacement(t)
    return _assemble(ph, mult, pi_, ji, o_d, o_R, o_p0, psup, v_plus, v_minus, q_minus, p_plus, p_plus,
                     fl._V(o_ph), oi, g)


def _compiled(kernel: str, args: tuple, J: int) -> RigidOrbits:
    """The closed forms by the compiled loop over the points (``orbits/_rigid_arrays.py``, the fast
    side of ``"orbits.rigid_arrays"``): the result's arrays, filled with the unused slots' values,
    are written orbit by orbit."""
    from . import _rigid_arrays

    P = args[0].size
    out = RigidOrbits(
        n_orbits=np.zeros(P, dtype=np.int64),
        phase=np.full((P, J), np.nan),
        multiplicity=np.zeros((P, J), dtype=np.int64),
        impact_velocity=np.full((P, J), np.nan),
        v_plus=np.full((P, J), np.nan),
        q_minus=np.full((P, J), np.nan),
        status=np.full((P, J), -1, dtype=np.int8),
        clearance=np.full((P, J), np.nan),
        clearance_error=np.full((P, J), np.nan),
        multipliers=np.full((P, J, 2), np.nan, dtype=complex),
        schur_roots=np.full((P, J, 2), np.nan, dtype=complex),
        schur_stable=np.zeros((P, J), dtype=bool),
        stable=np.zeros((P, J), dtype=bool),
        fallback=np.zeros(P, dtype=bool),
    )
    getattr(_rigid_arrays, kernel)(*(np.ascontiguousarray(a) for a in args[:4]), *args[4:], tuple(out))
    return out


def _log1p_ratio(x):
    """``log1p(x) / x`` elementwise, 1 at 0."""
    small = np.abs(x) < 1e-8
    xs = np.where(small, 1.0, x)
    return np.where(small, 1.0 - 0.5 * x, np.log1p(xs) / xs)


def _exp_level_time(v, alpha, d, target):
    """Time ``tau >= 0`` at which ``v e^{-d tau} + alpha b(tau)`` (the solution of ``y' + d y = alpha``
    from ``v``, monotone) reaches ``target``; NaN if never. Written without the ``alpha/d``
    cancellation: ``tau = (target - v)/(alpha - d v) log1p(x)/x``, ``x = d (v - target)/(alpha - d v)``."""
    den = alpha - d * v
    ok = den != 0.0
    dens = np.where(ok, den, 1.0)
    x = d * (v - target) / dens
    ok &= x > -1.0
    tau = (target - v) / dens * _log1p_ratio(np.where(ok, x, 0.0))
    return np.where(ok & (tau >= 0.0), tau, np.nan)


def rigid_square_orbits(d, R, q, kappa) -> RigidOrbits:
    """Every one-impact orbit of the rigid bar under the square wave of eq. 34 at many points.

    The load is ``+q`` on ``[0, kappa pi)`` and ``-q`` on the rest of the period. On each piece the
    rigid velocity solves ``y' + d y = const`` in closed form and is monotone, so the phase
    equation (eq. 14) has at most one root per piece, solved in closed form, and so has the end's
    velocity between impacts on each arc of constant load (theory §4, §5); the multipliers are the
    2 x 2 closed form (theory §7). The same orbits, flags and multipliers as
    :func:`impactbar.periodic_orbits` with ``SquareWaveLoad(q, kappa)`` on ``BarModel(s, d, R, 0)``
    (tested against it to 1e-10).

    Parameters
    ----------
    d, R, q, kappa : array_like
        Damping (``>= 0``), restitution coefficient (``[0, 1]``), level ``q > 0`` and load factor
        ``1 <= kappa < 2`` (dimensionless, eqs. 2, 34); broadcast together, flattened to ``P``
        points. Not validated: the callers pass validated values.

    Returns
    -------
    RigidOrbits
        Two orbit slots per point.
    """
    d, R, q, kappa = (np.ravel(x) for x in np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (d, R, q, kappa))))
    if use_fast("orbits.rigid_arrays"):
        return _compiled("square_orbits", (d, R, q, kappa), 2)
    a = kappa * np.pi  # the jump from +q to -q
    p0 = q * (kappa - 1.0)
    starts = np.stack((np.zeros_like(a), a), axis=1)  # (P, 2)
    lengths = np.stack((a, TWO_PI - a), axis=1)
    alpha = np.stack((q - p0, -q - p0), axis=1)  # p - p0 on each piece
    # the periodic zero-mean rigid velocity: V = V_j e^{-d tau} + alpha_j b(tau) on piece j
    dc = d[:, None]
    bT, cT = _b(dc, lengths), _c(dc, lengths)
    E2 = np.exp(-d * a)
    D2 = alpha[:, 0] * bT[:, 0]
    v0 = -(D2 * bT[:, 1] + alpha[:, 0] * cT[:, 0] + alpha[:, 1] * cT[:, 1]) / (bT[:, 0] + E2 * bT[:, 1])
    Vs = np.stack((v0, v0 * E2 + D2), axis=1)
    # the phase equation (1 + R) V(phase) = p0 G: one root at most on each piece
    target = (p0 * phase_G_array(d, R) / (1.0 + R))[:, None]
    tau = _exp_level_time(Vs, alpha, dc, target)
    ph = np.where(tau < lengths, starts + tau, np.nan)
    ph = np.where(kappa[:, None] < 2.0, np.mod(ph, TWO_PI), np.nan)
    ph = np.sort(ph, axis=1)
    mult = np.where(np.isnan(ph), 0, 1)
    # two roots within 1e-9 (across a jump, or the period's end) are one double root, as in
    # phase_roots
    both = ~np.isnan(ph[:, 1])
    close = both & ((ph[:, 1] - ph[:, 0] < 1e-9) | (ph[:, 0] + TWO_PI - ph[:, 1] < 1e-9))
    mult[close, 0] = 2
    mult[close, 1] = 0
    ph[close, 1] = np.nan

    pi_, ji = np.nonzero(~np.isnan(ph))
    o_d, o_R, o_q, o_p0, o_a, o_ph = d[pi_], R[pi_], q[pi_], p0[pi_], a[pi_], ph[pi_, ji]
    O = o_d.size
    piece = o_ph >= o_a  # 0 on [0, a), 1 on [a, 2 pi)
    tau0 = o_ph - np.where(piece, o_a, 0.0)
    V_phase = Vs[pi_, piece.astype(int)] * np.exp(-o_d * tau0) + alpha[pi_, piece.astype(int)] * _b(o_d, tau0)
    p_plus = np.where(piece, -o_q, o_q)
    p_minus = np.where((o_ph == 0.0) | ((o_ph > o_a) & piece), -o_q, o_q)  # the left limit
    v_plus = -o_R * TWO_PI * o_p0 / (1.0 + o_R)
    # the flight: three arcs of constant load in orbit time, cut where the load jumps
    cuts = np.sort(np.stack((np.mod(o_a - o_ph, TWO_PI), np.mod(-o_ph, TWO_PI)), axis=1), axis=1)
    edges = np.concatenate((np.zeros((O, 1)), cuts, np.full((O, 1), TWO_PI)), axis=1)
    qs, vs = np.zeros(O), v_plus.copy()
    zero_at, zero_g = [], []
    r0 = o_R == 0.0
    for j in range(3):
        T = edges[:, j + 1] - edges[:, j]
        mid = np.mod(o_ph + 0.5 * (edges[:, j] + edges[:, j + 1]), TWO_PI)
        L = np.where(mid < o_a, o_q, -o_q)
        tz = _exp_level_time(vs, L, o_d, 0.0)
        if j == 0:  # the impact itself is no stationary point (R = 0 leaves at rest)
            tz = np.where(r0, np.nan, tz)
        hit = tz < T  # NaN compares false
        hit &= ~((j == 0) & (tz <= 0.0))
        rows = np.nonzero(hit)[0]
        t_hit = tz[rows]
        zero_at.append(rows)
        zero_g.append(qs[rows] + vs[rows] * _b(o_d[rows], t_hit) + L[rows] * _c(o_d[rows], t_hit))
        qs = qs + vs * _b(o_d, T) + L * _c(o_d, T)
        vs = vs * np.exp(-o_d * T) + L * _b(o_d, T)
    return _assemble(ph, mult, pi_, ji, o_d, o_R, o_p0, o_q, v_plus, vs, qs, p_plus, p_minus,
                     V_phase, np.concatenate(zero_at), np.concatenate(zero_g))


def _assemble(ph, mult, pi_, ji, o_d, o_R, o_p0, psup, v_plus, v_minus, q_minus, p_plus, p_minus,
              V_phase, oi, g) -> RigidOrbits:
    """Flags, clearance, multipliers and the paper's block of every orbit (one entry per orbit,
    ``pi_, ji`` its point and slot), from its states and the values ``g`` of ``u(1, .)`` at the
    zeros of its velocity (orbit ``oi``), with the general path's conventions (admissibility.py)."""
    P, J = ph.shape
    O = o_d.size
    scale = np.maximum(np.maximum(np.abs(v_minus), psup), 1e-300)
    acc0 = p_plus - o_d * v_plus  # for R = 0 (v+ = 0): the end's acceleration just after impact
    r0 = o_R == 0.0
    # degenerate orbits are left to the general path: arrival or departure nearly at rest (for
    # R = 0 the departure at rest is exact and its sign is that of the load, unless that is ~0)
    degenerate = (~(np.abs(v_minus) > 1e-6 * scale) | (r0 & ~(np.abs(acc0) > 1e-6 * scale))
                  | (~r0 & ~(np.abs(v_plus) > 1e-6 * scale)))
    # the general path's conventions (admissibility.py): the largest stationary value, its error
    clearance = np.full(O, -np.inf)
    if oi.size:  # per orbit: the largest value (oi grouped by orbit)
        order = np.argsort(oi, kind="stable")
        oi, g = oi[order], g[order]
        first = np.flatnonzero(np.diff(oi, prepend=-1))
        clearance[oi[first]] = np.maximum.reduceat(g, first)
    gabs = np.where(np.isfinite(clearance), np.abs(clearance), 0.0)
    err = 1e-12 * (scale + gabs)  # relative to the problem's scale and the value, as admissibility.py
    tol = np.maximum(err, 1e-11 * scale)
    status = np.zeros(O, dtype=np.int8)
    status[clearance >= -tol] = 2
    status[clearance > tol] = 1
    status[r0 & ~(acc0 < 0.0)] = 4
    late = ~(v_minus > 1e-12 * scale)
    status[late] = np.where(np.abs(v_minus[late]) <= 1e-12 * scale[late], 2, 3)

    mu = rigid_multipliers(o_d, o_R, p_plus, p_minus, v_plus, v_minus)
    # the paper's rigid block (eqs. 29, 30) with sigma = 0, multiplied through by p0
    e2 = np.exp(-TWO_PI * o_d)
    S2 = p_plus - o_p0 - o_d * V_phase
    y = TWO_PI * o_d
    small = y < 1e-8  # series, as stability.schur_blocks: no denormal quotient
    factor = np.where(small, 1.0 - 0.5 * y, -np.expm1(-y) / np.where(small, 1.0, y))
    a2 = o_p0
    a1 = -(1.0 + o_R * o_R * e2) * o_p0 - factor * (1.0 + o_R) ** 2 * S2
    a0 = o_R * e2 * (o_R * o_p0)
    schur = quadratic_roots(np.column_stack((a2, a1, a0))).reshape(-1, 2)
    with np.errstate(invalid="ignore"):
        schur_ok = (np.abs(a0) < np.abs(a2)) & (np.abs(a1) < np.abs(a0 + a2))
    stable = (status == 0) & np.all(np.abs(mu) < 1.0 - MARGINAL, axis=-1)

    def scatter(vals, fill, dtype=float, extra=()):
        out = np.full((P, J, *extra), fill, dtype=dtype)
        out[pi_, ji] = vals
        return out

    fb = np.zeros(P, dtype=bool)
    fb[pi_[degenerate]] = True
    return RigidOrbits(
        n_orbits=(~np.isnan(ph)).sum(axis=1),
        phase=ph,
        multiplicity=mult,
        impact_velocity=scatter(v_minus, np.nan),
        v_plus=scatter(v_plus, np.nan),
        q_minus=scatter(q_minus, np.nan),
        status=scatter(status, -1, np.int8),
        clearance=scatter(clearance, np.nan),
        clearance_error=scatter(err, np.nan),
        multipliers=scatter(mu, np.nan, complex, (2,)),
        schur_roots=scatter(schur, np.nan, complex, (2,)),
        schur_stable=scatter(schur_ok, False, bool),
        stable=scatter(stable, False, bool),
        fallback=fb,
    )


def _bracketed_zero(fl, a, b, fa, iters=60):
    """The zero of the velocity of each flight ``fl`` in its bracket ``[a, b]`` (``sign v(a) = fa``,
    the opposite sign at ``b``, one zero inside): Newton steps with ``v' = p - d v``, safeguarded by
    bisection, vectorised; stops when every step is below 1e-13 (the stationary value, what is
    wanted, is then exact to rounding)."""
    t = 0.5 * (a + b)
    for _ in range(iters):
        v = fl.velocity(t)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = v / (fl.load(t) - fl.d * v)
        same = np.sign(v) == fa
        a = np.where(same, t, a)
        b = np.where(same, b, t)
        tn = t - newton
        ok = np.abs(newton) <= 1e-13 * (1.0 + np.abs(t))
        if ok.all():
            return tn
        bad = ~((tn >= a) & (tn <= b)) & ~ok
        t = np.where(bad, 0.5 * (a + b), tn)
    return t
