"""The rigid bar's closed forms (:mod:`impactbar.orbits.rigid`) at ONE parameter point, in plain
floats (``math``, ``cmath``): what a single :func:`impactbar.periodic_orbits` call needs.

The vectorised functions of :mod:`impactbar.orbits.rigid` (the reference of the fast paths, tested
against the general path) pay numpy's per-call overhead some fifty times on 1-element arrays (about
0.5 ms a call); these are the same formulas, line by line, with the same tolerances and conventions,
on Python floats (some 30 us a call). The tests check them against the vectorised closed forms and
the general path on random parameters (``tests/dynamics/test_fast_paths.py``).

This module is the one source of the compiled loop over a sweep's points too: the functions named
in :data:`SHARED` use plain floats, tuples and ``math``/``cmath`` only, and
:mod:`impactbar.orbits._rigid_arrays` compiles these very functions with numba; two of them, plain
arithmetic, serve the vectorised closed forms as they are (:func:`harmonic_term`, and ``trace_det``,
which the paper law's ``rigid_multipliers`` defines). Sources: the phase equation (eq. 14, theory
§4), the stationary points of the end's displacement arc by arc (theory §5), the 2 x 2 impact-map
Jacobian (theory §7), the paper's rigid block (eqs. 29, 30, theory §6).
"""

from __future__ import annotations

import cmath
import math
from typing import NamedTuple

import numpy as np

from ..dynamics.compiled_views import FOURIER
from ..laws.paper.stability import trace_det
from ..loads.abilities import compiled_kind, left_limit
from .stability import MARGINAL

TWO_PI = 2.0 * math.pi
INF = math.inf
NAN = math.nan
_RIGID_W2 = np.zeros(1)  # the rigid mode's squared frequency, for Load.propagate


class RigidOrbit(NamedTuple):
    """One orbit of the rigid bar at one point (the fields of ``PeriodicOrbit``, as floats)."""

    phase: float
    multiplicity: int
    impact_velocity: float
    v_plus: float
    q_minus: float
    status: int  # index into rigid.STATUS
    clearance: float
    clearance_error: float
    multipliers: tuple  # two complex numbers, by decreasing modulus
    schur_roots: tuple  # two complex numbers
    schur_stable: bool
    stable: bool


# ------------------------------------------------------------------------------------------------
# the shared formulas: plain floats, tuples and math/cmath only, so that numba compiles these very
# functions for the loop over a sweep's points (orbits/_rigid_arrays.py makes its copies of them)
# ------------------------------------------------------------------------------------------------
def _beta(y):
    if y < 1e-2:
        return 0.5 + y / 12.0 - y**3 / 720.0 + y**5 / 30240.0
    return 1.0 / (-math.expm1(-y)) - 1.0 / y


def _G(d, R):
    """``G(d, R)`` of the phase equation (eq. 14, theory §4)."""
    return TWO_PI * ((1.0 + R) * _beta(TWO_PI * d) - R)


def _b(d, t):
    """``b(t) = (1 - exp(-d t)) / d`` (``t`` at ``d = 0``)."""
    y = d * t
    if abs(y) < 1e-8:
        return t * (1.0 - 0.5 * y)
    return -math.expm1(-y) / d


def _c(d, t):
    """``c(t) = (t - b(t)) / d`` (``t^2/2`` at ``d = 0``), by its series where it cancels."""
    y = d * t
    if abs(y) < 1e-2:
        return t * t * (0.5 - y / 6.0 + y * y / 24.0 - y**3 / 120.0 + y**4 / 720.0)
    return (t - (-math.expm1(-y) / d)) / d


def _sign(x):
    return 1.0 if x > 0.0 else (-1.0 if x < 0.0 else (0.0 if x == 0.0 else NAN))


def multipliers(d, R, p_plus, p_minus, v_plus, v_minus):
    """The two Floquet multipliers (theory §7 with ``N = 0``), as ``rigid.rigid_multipliers``."""
    if not abs(v_minus) > 1e-14 * abs(v_minus):  # grazing: the saltation term is infinite
        return (complex(INF, 0.0), complex(INF, 0.0))
    half_tr, det = trace_det(_b(d, TWO_PI), math.exp(-TWO_PI * d), R, p_plus, p_minus, v_plus, v_minus, d)
    disc = cmath.sqrt(complex(half_tr * half_tr - det, 0.0))
    big = half_tr + (1.0 if half_tr >= 0.0 else -1.0) * disc
    small = det / big if big != 0.0 else 0j
    m0, m1 = abs(big), abs(small)
    tie = abs(m1 - m0) <= 1e-12 * max(m0, m1)
    if (not tie and m1 > m0) or (tie and small.imag > big.imag):
        return (small, big)
    return (big, small)


def _quadratic_roots(a2, a1, a0):
    """Both roots of ``a2 x^2 + a1 x + a0`` (real coefficients), as ``stability.quadratic_roots``."""
    disc = cmath.sqrt(complex(a1 * a1 - 4.0 * a2 * a0, 0.0))
    sgn = 1.0 if a1 * disc.real >= 0.0 else -1.0
    qq = -0.5 * (a1 + sgn * disc)
    r1 = qq / a2 if a2 != 0.0 else complex(INF, 0.0)
    r2 = a0 / qq if qq != 0.0 else 0j
    return (r1, r2)


def _verdict(d, R, p0, psup, v_plus, v_minus, p_plus, p_minus, V_phase, ng, gmax):
    """One orbit's flags, clearance, multipliers and the paper's block (as ``rigid._assemble``),
    from its states and the largest value ``gmax`` of ``u(1, .)`` at the ``ng`` zeros of its
    velocity: ``(ok, status, clearance, clearance_error, mu0, mu1, schur0, schur1, schur_stable,
    stable)``, ``ok`` false for a degenerate orbit (arrival or departure nearly at rest), which the
    general path takes."""
    scale = max(abs(v_minus), psup, 1e-300)
    acc0 = p_plus - d * v_plus
    r0 = R == 0.0
    if (not abs(v_minus) > 1e-6 * scale or (r0 and not abs(acc0) > 1e-6 * scale)
            or (not r0 and not abs(v_plus) > 1e-6 * scale)):
        return (False, 0, 0.0, 0.0, 0j, 0j, 0j, 0j, False, False)
    clearance = gmax if ng > 0 else -INF
    gabs = abs(clearance) if ng > 0 else 0.0  # relative to the value itself, as rigid._assemble
    err = 1e-12 * (scale + gabs)
    tol = max(err, 1e-11 * scale)
    status = 0
    if clearance >= -tol:
        status = 2
    if clearance > tol:
        status = 1
    if r0 and not acc0 < 0.0:
        status = 4
    if not v_minus > 1e-12 * scale:
        status = 2 if abs(v_minus) <= 1e-12 * scale else 3
    mu0, mu1 = multipliers(d, R, p_plus, p_minus, v_plus, v_minus)
    # the paper's rigid block (eqs. 29, 30) with sigma = 0, multiplied through by p0
    e2 = math.exp(-TWO_PI * d)
    S2 = p_plus - p0 - d * V_phase
    y = TWO_PI * d
    factor = 1.0 - 0.5 * y if y < 1e-8 else -math.expm1(-y) / y
    a2 = p0
    a1 = -(1.0 + R * R * e2) * p0 - factor * (1.0 + R) ** 2 * S2
    a0 = R * e2 * (R * p0)
    s0, s1 = _quadratic_roots(a2, a1, a0)
    schur_ok = abs(a0) < abs(a2) and abs(a1) < abs(a0 + a2)
    stable = status == 0 and abs(mu0) < 1.0 - MARGINAL and abs(mu1) < 1.0 - MARGINAL
    return (True, status, clearance, err, mu0, mu1, s0, s1, schur_ok, stable)


def harmonic_term(d, R, pk, k):
    """``(den, zr, zi)``: ``den = d^2 + k^2`` and ``(1 + R) pk / (d + i k) = zr + i zi``, the
    harmonic's term of the phase equation (eq. 14) under ``p0 + pk cos(k t)``: plain arithmetic,
    the same for floats and for numpy arrays (:mod:`impactbar.orbits.rigid`)."""
    den = d * d + k * k
    return den, (1.0 + R) * pk * d / den, -(1.0 + R) * pk * k / den


def _cosine_roots(d, R, p0, pk, k):
    """The phase equation under ``p0 + pk cos(k t)`` in closed form, ``A cos(k phase + theta) = B``:
    ``(exists, double, a, theta, den)``, the roots ``(+-a - theta + 2 pi j) / k`` (one family for a
    double root), ``den = d^2 + k^2``."""
    den, zr, zi = harmonic_term(d, R, pk, k)
    A = math.hypot(zr, zi)
    theta = math.atan2(zi, zr)
    B = p0 * _G(d, R)
    ratio = B / A if A > 0.0 else INF
    if not (abs(ratio) <= 1.0 + 1e-15 and A > 0.0):
        return (False, False, 0.0, theta, den)
    double = abs(ratio) >= 1.0 - 1e-15
    return (True, double, math.acos(min(max(ratio, -1.0), 1.0)), theta, den)


def _cosine_flight(d, pk, k, den, t0, v0):
    """The rigid bar's flight from the stop at load time ``t0`` with velocity ``v0`` under ``p0 + pk
    cos(k t)``: ``(ca, cb, free, W0)``, the periodic velocity ``V = ca cos(k t) + cb sin(k t)``, the
    free part's start and the antiderivative's value at ``t0``."""
    ca, cb = pk * d / den, pk * k / den
    x = k * t0
    return ca, cb, v0 - (ca * math.cos(x) + cb * math.sin(x)), (ca * math.sin(x) - cb * math.cos(x)) / k


def _velocity(tau, t0, k, ca, cb, p0, d, free):
    """The flight's velocity at ``tau`` after its start (:func:`_cosine_flight`)."""
    x = k * (t0 + tau)
    return ca * math.cos(x) + cb * math.sin(x) + p0 * _b(d, tau) + free * math.exp(-d * tau)


def _displacement(tau, t0, k, ca, cb, p0, d, free, W0):
    """The flight's displacement at ``tau`` after its start (:func:`_cosine_flight`)."""
    x = k * (t0 + tau)
    return (ca * math.sin(x) - cb * math.cos(x)) / k - W0 + p0 * _c(d, tau) + free * _b(d, tau)


def _crossing(p0, pk):
    """``(crosses, alpha)``: whether ``p0 + pk cos(k t)`` changes sign, at ``k t = +-alpha``."""
    crossing = -p0 / pk if pk != 0.0 else INF
    return abs(crossing) < 1.0, math.acos(min(max(crossing, -1.0), 1.0))


def _log1p_ratio(x):
    return 1.0 - 0.5 * x if abs(x) < 1e-8 else math.log1p(x) / x


def _exp_level_time(v, alpha, d, target):
    """Time ``tau >= 0`` at which ``v e^{-d tau} + alpha b(tau)`` reaches ``target``; NaN if never
    (as ``rigid._exp_level_time``)."""
    den = alpha - d * v
    if den == 0.0:
        return NAN
    x = d * (v - target) / den
    if not x > -1.0:
        return NAN
    tau = (target - v) / den * _log1p_ratio(x)
    return tau if tau >= 0.0 else NAN


def _square_wave(d, R, q, kappa):
    """The rigid velocity of eq. 14 under the square wave (``kappa < 2``): ``(a, p0, V0, V1, al0, al1,
    target)``, the jump ``a = kappa pi``, the mean, ``V`` at the starts of the two pieces, ``p - p0``
    on them and the phase equation's level ``V(phase) = p0 G / (1 + R)``."""
    a = kappa * math.pi  # the jump from +q to -q
    p0 = q * (kappa - 1.0)
    len0, len1 = a, TWO_PI - a
    al0, al1 = q - p0, -q - p0  # p - p0 on each piece
    bT0, bT1 = _b(d, len0), _b(d, len1)
    E2 = math.exp(-d * a)
    D2 = al0 * bT0
    v0 = -(D2 * bT1 + al0 * _c(d, len0) + al1 * _c(d, len1)) / (bT0 + E2 * bT1)
    return a, p0, v0, v0 * E2 + D2, al0, al1, p0 * _G(d, R) / (1.0 + R)


def _square_impact(ph, a, q, d, V0, V1, al0, al1):
    """``(V(phase), p(phase), p(phase-))`` of an impact at ``ph`` under the square wave."""
    if ph >= a:
        V_phase, p_plus = V1 * math.exp(-d * (ph - a)) + al1 * _b(d, ph - a), -q
    else:
        V_phase, p_plus = V0 * math.exp(-d * ph) + al0 * _b(d, ph), q
    return V_phase, p_plus, -q if (ph == 0.0 or ph > a) else q  # the left limit


def _square_flight(ph, a, q, d, v_plus, r0):
    """The flight of the orbit with phase ``ph`` under the square wave: three arcs of constant load
    in orbit time, cut where the load jumps; ``(q, v)`` at its end and the count and largest of
    ``u(1, .)`` at the zeros of its velocity."""
    c1, c2 = (a - ph) % TWO_PI, (-ph) % TWO_PI
    edges = (0.0, min(c1, c2), max(c1, c2), TWO_PI)
    qs, vs = 0.0, v_plus
    ng = 0
    gmax = -INF
    for j in range(3):
        T = edges[j + 1] - edges[j]
        mid = (ph + 0.5 * (edges[j] + edges[j + 1])) % TWO_PI
        L = q if mid < a else -q
        tz = NAN if (j == 0 and r0) else _exp_level_time(vs, L, d, 0.0)
        if tz < T and not (j == 0 and tz <= 0.0):  # the impact itself is no stationary point
            g = qs + vs * _b(d, tz) + L * _c(d, tz)
            gmax = g if ng == 0 else max(gmax, g)
            ng += 1
        qs = qs + vs * _b(d, T) + L * _c(d, T)
        vs = vs * math.exp(-d * T) + L * _b(d, T)
    return qs, vs, ng, gmax


#: the functions above, which :mod:`impactbar.orbits._rigid_arrays` compiles from this source
SHARED = ("_beta", "_G", "_b", "_c", "_sign", "trace_det", "multipliers", "_quadratic_roots", "_verdict",
          "harmonic_term", "_cosine_roots", "_cosine_flight", "_velocity", "_displacement", "_crossing",
          "_log1p_ratio", "_exp_level_time", "_square_wave", "_square_impact", "_square_flight")


# ------------------------------------------------------------------------------------------------
# one point: the orbits as RigidOrbit records
# ------------------------------------------------------------------------------------------------
def _assemble(phase, mult, d, R, p0, psup, v_plus, v_minus, q_minus, p_plus, p_minus, V_phase, g):
    """One orbit (:func:`_verdict`) as a :class:`RigidOrbit`, from the values ``g`` of ``u(1, .)`` at
    the zeros of its velocity; ``None`` for a degenerate orbit."""
    ok, status, clearance, err, mu0, mu1, s0, s1, schur_ok, stable = _verdict(
        d, R, p0, psup, v_plus, v_minus, p_plus, p_minus, V_phase, len(g), max(g) if g else -INF)
    if not ok:
        return None
    return RigidOrbit(phase, mult, v_minus, v_plus, q_minus, status, clearance, err, (mu0, mu1),
                      (s0, s1), schur_ok, stable)


class _CosineFlight:
    """The rigid bar's flight from the stop under ``p0 + pk cos(k t)`` (as ``rigid._CosineFlight``),
    in the time ``tau`` since its start at load time ``t0`` with velocity ``v0``
    (:func:`_cosine_flight`)."""

    __slots__ = ("d", "p0", "pk", "k", "t0", "ca", "cb", "free", "W0")

    def __init__(self, d, p0, pk, k, t0, v0):
        self.d, self.p0, self.pk, self.k, self.t0 = d, p0, pk, k, t0
        self.ca, self.cb, self.free, self.W0 = _cosine_flight(d, pk, k, d * d + k * k, t0, v0)

    def velocity(self, tau):
        return _velocity(tau, self.t0, self.k, self.ca, self.cb, self.p0, self.d, self.free)

    def displacement(self, tau):
        return _displacement(tau, self.t0, self.k, self.ca, self.cb, self.p0, self.d, self.free, self.W0)

    def load(self, tau):
        return self.p0 + self.pk * math.cos(self.k * (self.t0 + tau))

    def stationary_values(self, bounds, s_lo):
        """``u(1, .)`` at the zeros of the velocity between consecutive ``bounds`` (the load's zeros,
        so at most one per arc), ``s_lo`` the velocity's sign just after the start (theory §5)."""
        g = []
        for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
            s_hi = _sign(self.velocity(hi))
            if s_lo * s_hi < 0.0 and hi > lo:
                g.append(self.displacement(_bracketed_zero(self.velocity, self.load, self.d, lo, hi, s_lo)))
            s_lo = s_hi
        return g


# ------------------------------------------------------------------------------------------------
# the cosine load p0 + pk cos(k t)
# ------------------------------------------------------------------------------------------------
def cosine_orbits(d, R, p0, pk, k):
    """Every one-impact orbit of the rigid bar under ``p0 + pk cos(k t)`` (eq. 33) at one point, as
    ``rigid.rigid_cosine_orbits`` does for arrays: a list of :class:`RigidOrbit` in order of phase,
    or ``None`` if an orbit is degenerate (the general path takes the point)."""
    d, R, p0, pk, k = float(d), float(R), float(p0), float(pk), int(k)
    exists, double, a, theta, _ = _cosine_roots(d, R, p0, pk, k)
    if not exists:
        return []
    phases = [((base - theta + TWO_PI * j) / k) % TWO_PI
              for base in ((a,) if double else (a, -a)) for j in range(k)]
    phases.sort()
    mult = 2 if double else 1

    v_plus = -R * TWO_PI * p0 / (1.0 + R)  # theory §4: the rigid mode strikes at 2 pi p0/(1+R)
    psup = abs(p0) + abs(pk)
    r0 = R == 0.0
    crosses, alpha = _crossing(p0, pk)
    load_zeros = ([(alpha + TWO_PI * j) / k for j in range(k)] + [(TWO_PI * j - alpha) / k for j in range(k)]
                  if crosses else [])
    out = []
    for ph in phases:
        flight = _CosineFlight(d, p0, pk, k, ph, v_plus)
        v_minus = flight.velocity(TWO_PI)
        q_minus = flight.displacement(TWO_PI)
        p_plus = p0 + pk * math.cos(k * ph)
        # the stationary points of u(1, t): at most one zero of v per arc of constant load sign
        inner = sorted((z - ph) % TWO_PI for z in load_zeros) + [TWO_PI] * (2 * k - len(load_zeros))
        g = flight.stationary_values([0.0, *inner, TWO_PI], _sign(p_plus if r0 else v_plus))
        orbit = _assemble(ph, mult, d, R, p0, psup, v_plus, v_minus, q_minus, p_plus, p_plus,
                          flight.ca * math.cos(k * ph) + flight.cb * math.sin(k * ph), g)
        if orbit is None:
            return None
        out.append(orbit)
    return out


def _bracketed_zero(velocity, load, d, a, b, fa, iters=60):
    """The zero of ``velocity`` in ``[a, b]`` (``sign v(a) = fa``, one zero inside): Newton steps with
    ``v' = p - d v``, safeguarded by bisection (as ``rigid._bracketed_zero``)."""
    t = 0.5 * (a + b)
    for _ in range(iters):
        v = velocity(t)
        den = load(t) - d * v
        if _sign(v) == fa:
            a = t
        else:
            b = t
        if den == 0.0:
            t = 0.5 * (a + b)
            continue
        newton = v / den
        tn = t - newton
        if abs(newton) <= 1e-13 * (1.0 + abs(t)):
            return tn
        t = tn if a <= tn <= b else 0.5 * (a + b)
    return t


# ------------------------------------------------------------------------------------------------
# the square wave of eq. 34
# ------------------------------------------------------------------------------------------------
def square_orbits(d, R, q, kappa):
    """Every one-impact orbit of the rigid bar under the square wave (eq. 34, ``1 <= kappa < 2``) at
    one point, as ``rigid.rigid_square_orbits`` does for arrays: a list of :class:`RigidOrbit` in
    order of phase, or ``None`` if an orbit is degenerate."""
    d, R, q, kappa = float(d), float(R), float(q), float(kappa)
    if not kappa < 2.0:
        return []
    a, p0, V0, V1, al0, al1, target = _square_wave(d, R, q, kappa)
    phases = []
    for start, V, al, length in ((0.0, V0, al0, a), (a, V1, al1, TWO_PI - a)):
        tau = _exp_level_time(V, al, d, target)
        if tau < length:  # NaN compares false
            phases.append((start + tau) % TWO_PI)
    phases.sort()
    mult = 1
    if len(phases) == 2 and (phases[1] - phases[0] < 1e-9 or phases[0] + TWO_PI - phases[1] < 1e-9):
        phases, mult = phases[:1], 2  # one double root, as in phase_roots

    v_plus = -R * TWO_PI * p0 / (1.0 + R)
    out = []
    for ph in phases:
        V_phase, p_plus, p_minus = _square_impact(ph, a, q, d, V0, V1, al0, al1)
        qs, vs, ng, gmax = _square_flight(ph, a, q, d, v_plus, R == 0.0)
        ok, status, clearance, err, mu0, mu1, s0, s1, schur_ok, stable = _verdict(
            d, R, p0, q, v_plus, vs, p_plus, p_minus, V_phase, ng, gmax)
        if not ok:
            return None
        out.append(RigidOrbit(ph, mult, vs, v_plus, qs, status, clearance, err, (mu0, mu1), (s0, s1),
                              schur_ok, stable))
    return out


# ------------------------------------------------------------------------------------------------
# the rigid bar's flight under any load, in plain floats (the multi-impact segment problem)
# ------------------------------------------------------------------------------------------------
SCALAR_HARMONICS = 16
"""Most harmonics a Fourier load may have for :class:`RigidFlight` to sum them in plain floats (a
load with more is summed by numpy, one call per time)."""


class RigidFlight:
    """The rigid bar's flight ``q'' + d q' = p(t)`` (eq. 8 with ``N = 0``) from one state to a later
    time, and the load there, in plain floats.

    Under a :class:`~impactbar.FourierLoad` the flight is the closed form of
    :meth:`~impactbar.FourierLoad.flow` for the rigid mode, term by term (a subclass that redefines
    the load's value or flow flies by its own :meth:`~impactbar.loads.Load.propagate`): the periodic part
    ``Re sum_k H_k p_k e^{ikt}`` with ``H_k = 1 / (i k d - k^2)``, and the free part
    ``q = dq + b(tau) dv + p_0 c(tau)``, ``v = e^{-d tau} dv + p_0 b(tau)`` of the start's
    difference ``(dq, dv)`` from the periodic part (theory §2, §4). Any other load flies by its own
    :meth:`~impactbar.loads.Load.propagate` (one call, converted to floats).

    Parameters
    ----------
    d : float
        Damping, ``>= 0``.
    load : Load
        The drive load.
    """

    __slots__ = ("d", "load", "p0", "terms", "numpy_terms")

    def __init__(self, d, load):
        self.d, self.load = float(d), load
        self.terms = self.numpy_terms = None
        # a subclass that redefines the load flies by its own propagate
        if compiled_kind(load, "__call__", "propagate", "flow") != FOURIER:
            self.p0 = None
            return
        self.p0 = float(load.p0)
        k, pk = load.abilities.orders.astype(float), load.abilities.amplitudes
        hp = pk / (1j * k * self.d - k * k)  # the rigid mode's transfer terms (FourierLoad._transfer)
        hv = hp * (1j * k)
        if k.size <= SCALAR_HARMONICS:
            self.terms = tuple(zip(k.tolist(), pk.tolist(), hp.tolist(), hv.tolist(), strict=True))
        else:
            self.numpy_terms = (k, pk, hp, hv)

    def _periodic(self, t):
        """``(q_p, v_p)(t)`` of the periodic part, and ``p(t)``."""
        if self.terms is not None:
            qp = vp = p = 0.0
            for k, pk, hp, hv in self.terms:
                e = cmath.exp(complex(0.0, k * t))
                qp += (hp * e).real
                vp += (hv * e).real
                p += (pk * e).real
            return qp, vp, self.p0 + p
        k, pk, hp, hv = self.numpy_terms
        e = np.exp(1j * k * t)
        return float((hp @ e).real), float((hv @ e).real), self.p0 + float((pk @ e).real)

    def state(self, t0, q0, v0, t1):
        """``(q, v)`` at ``t1`` of the flight from ``(q0, v0)`` at ``t0``, and the load ``p(t0)`` and
        ``p(t1-)`` (left limit), as floats."""
        if self.p0 is None:
            load = self.load
            q, v = load.propagate(_RIGID_W2, self.d, t0, [q0], [v0], [t1])
            return (float(q[0, 0]), float(v[0, 0]), float(load(t0)), float(left_limit(load, t1)))
        d = self.d
        qp0, vp0, p_start = self._periodic(t0)
        qp1, vp1, p_end = self._periodic(t1)
        dq, dv = q0 - qp0, v0 - vp0
        tau = t1 - t0
        b = _b(d, tau)
        return (qp1 + dq + b * dv + self.p0 * _c(d, tau), vp1 + math.exp(-d * tau) * dv + self.p0 * b,
                p_start, p_end)


def cosine_clearance(d, p0, pk, k, t0, v0, horizon, at_rest):
    """The rigid bar's clearance over one flight under ``p0 + pk cos(k t)``: the largest ``u(1, t)``
    at a zero of its velocity in ``(t0, t0 + horizon)``, the flight starting on the stop at load time
    ``t0`` with velocity ``v0`` (theory §5).

    Since ``v' = p(t) - d v``, every zero of ``v`` crosses with the sign of the load there, so an arc
    of constant load sign holds at most one; the arcs' ends are the load's zeros, in closed form, and
    each zero of ``v`` is found by :func:`_bracketed_zero` between them (as :func:`cosine_orbits`
    does over one period). ``at_rest``: the end leaves at rest, the sign just after ``t0`` is the
    load's. Returns ``-inf`` where the velocity keeps its sign.
    """
    flight = _CosineFlight(d, p0, pk, k, t0, v0)
    bounds = [0.0]
    crossing = -p0 / pk if pk != 0.0 else INF
    if abs(crossing) < 1.0:  # the load's zeros in (0, horizon): k t = +-alpha mod 2 pi
        alpha, period = math.acos(crossing), TWO_PI / k
        first = sorted(((z - t0) % period) for z in (alpha / k, -alpha / k))
        for j in range(int(horizon / period) + 1):
            bounds.extend(f + j * period for f in first if 0.0 < f + j * period < horizon)
    bounds.append(horizon)
    g = flight.stationary_values(bounds, _sign(flight.load(0.0) if at_rest else v0))
    return max(g) if g else -INF
