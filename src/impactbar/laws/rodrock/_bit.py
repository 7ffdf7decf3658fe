"""The rock-bit of the rod-rock blow (theory §4d): the bilinear rock's branches and the bit's step
(:class:`_Bit`), and the blow's lattice loop in numpy, the reference of the compiled one
(``"rock.blow"``); split from :mod:`impactbar.laws.rodrock.blow`."""

from __future__ import annotations

import math

import numpy as np

from ..._shared.wrappers import internal_jitable

# branches of the bilinear law
_LOAD, _ELASTIC, _FREE = 0, 1, 2


def damped_flow(b, m, half, tau):
    """The bit's flow on a rock branch, ``m p'' + Z p' + b p = 0`` (``half = -Z/(2m)``, ``b > 0``),
    after ``tau``: ``(C, S, delta)`` with ``e^{A tau} = C I + S (A - half I)``, ``delta`` the
    eigenvalues' half-distance where real (else 0). Plain Python: :class:`_Bit` calls it as it is,
    the compiled blow (:mod:`impactbar.laws.rodrock._rockloop`) compiles it."""
    disc = half * half - b / m
    delta = 0.0
    if disc >= 0.0:
        delta = math.sqrt(disc)
        e2 = math.exp((half - delta) * tau)
        if delta * tau > 1.0:  # a stiff bit (small mass): e2 underflows, expm1 overflows
            # lam_1 = half + delta without the cancellation of a stiff bit's two near-opposite terms:
            # lam_1 lam_2 = b/m (with the cancellation, bit masses 1e-100 .. 1e-16 lost the rock's load)
            S = (math.exp(b / m / (half - delta) * tau) - e2) / (2.0 * delta)
        else:
            S = e2 * (math.expm1(2.0 * delta * tau) / (2.0 * delta) if delta * tau > 1e-300 else tau)
        C = e2 + delta * S
    else:
        om = math.sqrt(-disc)
        e = math.exp(half * tau)
        C, S = e * math.cos(om * tau), e * math.sin(om * tau) / om
    return C, S, delta


class _Bit:
    """The bit and the rock at the rod's end: exact per-cell solution of
    ``m p'' + Z p' + R(p) = 2 F + f`` on the branches of the bilinear law."""

    def __init__(self, Z, k, k_u, m, feed):
        self.Z, self.k, self.k_u, self.m, self.f = Z, k, k_u, m, feed
        self.p = feed / k  # fresh rock loaded to the feed force
        self.w = 0.0
        self.branch = _LOAD
        self.p_max, self.R_max = self.p, feed
        self.p_perm = self.p_max - self.R_max / k_u
        self.work = 0.0  # int R dp since the blow started

    def force(self) -> float:
        if self.branch == _LOAD:
            return self.k * self.p
        if self.branch == _ELASTIC:
            return max(self.k_u * (self.p - self.p_perm), 0.0)
        return 0.0

    def _coeffs(self):
        """``R = b (p - p_ref)`` on the current branch: ``(b, p_ref)``."""
        if self.branch == _LOAD:
            return self.k, 0.0
        if self.branch == _ELASTIC:
            return self.k_u, self.p_perm
        return 0.0, 0.0

    def _work(self, p0, p1) -> float:
        """``int R dp`` from ``p0`` to ``p1`` on the current branch (no cancellation for a stiff one)."""
        b, ref = self._coeffs()
        return b * (p1 - p0) * (0.5 * (p0 + p1) - ref)

    def _unload(self):
        self.p_max, self.R_max = self.p, self.k * self.p
        self.p_perm = self.p_max - self.R_max / self.k_u
        self.branch = _ELASTIC

    def step(self, E: float, dt: float) -> None:
        """Advance by ``dt`` under the input ``E = 2 F + f``."""
        left, guard = dt, 0
        while left > 0.0 and guard < 64:
            guard += 1
            tau = self._substep_massless(E, left) if self.m == 0.0 else self._substep_mass(E, left)
            left -= tau

    # -- massless bit: p' = (E - a - b p)/Z ---------------------------------------------------------
    def _substep_massless(self, E, T):
        Z = self.Z
        b, ref = self._coeffs()
        p0 = self.p
        if self.branch == _LOAD and E - b * p0 < 0.0:
            self._unload()
            return 0.0
        if b == 0.0:  # lift-off: p' = E/Z
            rate = E / Z
            t_hit = (self.p_perm - p0) / rate if rate > 0.0 and p0 + rate * T >= self.p_perm else math.inf
            tau = min(T, t_hit)
            p1 = self.p_perm if tau == t_hit else p0 + rate * tau
            self.p = p1
            if tau == t_hit:
                self.branch = _ELASTIC
            self.w = rate
            return tau
        p_inf = E / b + ref
        lam = b / Z
        tau, nxt = T, None
        # g = b (p_inf - p0), Z times the rate at p0: the forms below lose nothing to a soft rock's
        # huge p_inf (with p_inf itself, a rock of k = 1e-16 was read as a rigid wall)
        g = E - b * (p0 - ref)
        if self.branch == _ELASTIC:
            if p_inf > self.p_max >= p0:
                tau_h = -math.log1p(-(self.p_max - p0) * b / g) / lam
                if tau_h < T:
                    tau, nxt = tau_h, (_LOAD, self.p_max)
            elif p_inf < self.p_perm <= p0:
                tau_h = -math.log1p(-(self.p_perm - p0) * b / g) / lam
                if tau_h < T:
                    tau, nxt = tau_h, (_FREE, self.p_perm)
        if nxt is None:
            p1 = p0 + g / Z * (-math.expm1(-lam * tau)) / lam
        else:
            branch, p1 = nxt
        self.work += self._work(p0, p1)
        self.p = p1
        self.w = (E - b * (p1 - ref)) / Z
        if nxt is not None:
            self.branch = branch
        return tau

    # -- bit with mass: exact 2x2 linear flow ---------------------------------------------------------
    def _flow(self, E, tau):
        """``(p, w)`` after ``tau`` on the current branch: the exact solution of
        ``m p'' + Z p' + b (p - p_ref) = E`` (``e^{A t} = C I + S (A + Z/(2m) I)`` with the
        eigenvalues ``lam_2 <= lam_1`` of ``A``; ``S = e^{lam_2 t} expm1(2 delta t)/(2 delta)`` with no
        loss near critical damping)."""
        b, ref = self._coeffs()
        m, Z = self.m, self.Z
        if b == 0.0:  # lift-off: w -> E/Z with rate Z/m
            w_inf = E / Z
            decay = math.exp(-Z * tau / m)
            p = self.p + w_inf * tau + (self.w - w_inf) * (m / Z) * (-math.expm1(-Z * tau / m))
            return p, w_inf + (self.w - w_inf) * decay
        p_eq = ref + E / b
        x0, w0 = self.p - p_eq, self.w
        half = -Z / (2.0 * m)
        C, S, delta = damped_flow(b, m, half, tau)
        # A - half I = [[-half, 1], [-b/m, half]]
        if delta > 0.5 * abs(half):
            # overdamped: p - p0 = g/(m 2 delta) (expm1(lam_1 t)/lam_1 - expm1(lam_2 t)/lam_2) + S w0 with
            # g = E - b (p0 - p_ref), without p_eq, which a soft rock makes huge (with it, a rock of
            # k = 1e-16 was read as a rigid wall)
            g = E - b * (self.p - ref)
            lam1, lam2 = b / m / (half - delta), half - delta
            f1 = math.expm1(lam1 * tau) / lam1 if lam1 * tau != 0.0 else tau
            f2 = math.expm1(lam2 * tau) / lam2
            return self.p + g / m * (f1 - f2) / (2.0 * delta) + S * w0, C * w0 + S * (g / m + half * w0)
        x = C * x0 + S * (-half * x0 + w0)
        w = C * w0 + S * (-b / m * x0 + half * w0)
        return p_eq + x, w

    def _samples(self, T):
        """Sample count that brackets every branch change in ``[0, T]``: 4 for a non-oscillating
        flow (a sum of two exponentials has at most one extremum), more per half period otherwise."""
        b, _ = self._coeffs()
        half = self.Z / (2.0 * self.m)
        disc = half * half - b / self.m
        return 4 if disc >= 0.0 else 4 + math.ceil(4.0 * math.sqrt(-disc) * T / math.pi)

    def _event(self, p, w):
        """Signed distance to leaving the current branch (a sign change ends it)."""
        if self.branch == _LOAD:
            return w
        if self.branch == _ELASTIC:
            return min(self.p_max - p, p - self.p_perm)
        return self.p_perm - p

    def _substep_mass(self, E, T):
        if self.branch == _LOAD and self.w < 0.0:
            self._unload()
            return 0.0
        if self.branch == _ELASTIC and self.p >= self.p_max and self.w > 0.0:
            self.branch = _LOAD
            return 0.0
        p0 = self.p
        taus = np.linspace(0.0, T, self._samples(T) + 1)[1:]
        tau, hit = T, False
        prev = 0.0
        for t in taus:
            p, w = self._flow(E, t)
            if self._event(p, w) < 0.0:
                lo, hi = prev, t
                for _ in range(60):
                    mid = 0.5 * (lo + hi)
                    if self._event(*self._flow(E, mid)) < 0.0:
                        hi = mid
                    else:
                        lo = mid
                tau, hit = hi, True
                break
            prev = t
        p1, w1 = self._flow(E, tau)
        self.work += self._work(p0, p1)
        self.p, self.w = p1, w1
        if hit:
            if self.branch == _LOAD:
                self._unload()
            elif self.branch == _ELASTIC:
                self.branch = _LOAD if p1 >= self.p_max else _FREE
            else:
                self.branch = _ELASTIC
        return tau


@internal_jitable  # (called by the compiled loop's copies of the functions below too: link-only)
def _fronts(fa, ga, prev, nxt):
    """The part of a step before each arriving wave's front (``opens_inside``; 0 where its values
    before and after agree)."""
    f0, g0 = prev
    f1, g1 = nxt
    pf = 0.0 if f0 == f1 else min(max((fa - f1) / (f0 - f1), 0.0), 1.0)
    pg = 0.0 if g0 == g1 else min(max((ga - g1) / (g0 - g1), 0.0), 1.0)
    return pf, pg


@internal_jitable
def _piece(k, pf, pg, prev, nxt):
    """The ``k``-th of the three pieces of a step the arriving waves' fronts ``pf, pg``
    (:func:`_fronts`) cut it into: ``(a, b, F, G)``, its ends (parts of the step) and the waves."""
    cuts = (0.0, min(pf, pg), max(pf, pg), 1.0)
    a, b = cuts[k], cuts[k + 1]
    m = 0.5 * (a + b)
    f0, g0 = prev
    f1, g1 = nxt
    return a, b, f0 if m < pf else f1, g0 if m < pg else g1


@internal_jitable
def closes_inside(za, zb, fa, ga, prev, nxt, gap, dt):
    """Where the piston-shank gap ``gap`` closes inside a step, the arriving waves read as in
    :func:`opens_inside`: ``(s, impulse)``, the part of the step before (1: not inside it) and the
    welded force's integral (per ``dt``) from there, where it presses."""
    pf, pg = _fronts(fa, ga, prev, nxt)
    s, impulse = 1.0, 0.0
    for k in range(3):
        a, b, f, g = _piece(k, pf, pg, prev, nxt)
        if b <= a:
            continue
        force = max((2.0 * zb * f + 2.0 * za * g) / (za + zb), 0.0)
        if s < 1.0:
            impulse += force * (b - a)
            continue
        closing = (-2.0 * g / zb - 2.0 * f / za) * (b - a) * dt
        if gap + closing < 0.0:
            s = a + (b - a) * gap / -closing
            impulse += force * (b - s)
        else:
            gap += closing
    return s, impulse


@internal_jitable
def opens_inside(za, zb, fa, ga, prev, nxt, dt):
    """Where the piston-shank contact (impedances ``za | zb``), closed at a step's start, opens
    inside the step (``BlowGrid.locate``): each arriving wave's cell average (``fa``, ``ga``) read as
    its value on the step before (``prev = (F, G)``) up to a front and on the next (``nxt``) after
    it, the front where the two average to the cell's; the contact opens where the welded force of
    the waves so read first pulls. ``(s, impulse, gap)``: the part of the step in contact (1: all of
    it), the welded force's integral over it (per ``dt``) and the gap at the step's end."""
    pf, pg = _fronts(fa, ga, prev, nxt)
    s, impulse, gap = 1.0, 0.0, 0.0
    for k in range(3):
        a, b, f, g = _piece(k, pf, pg, prev, nxt)
        if b <= a:
            continue
        if s >= 1.0 and 2.0 * zb * f + 2.0 * za * g < 0.0:
            s = a
        if s >= 1.0:
            impulse += (2.0 * zb * f + 2.0 * za * g) / (za + zb) * (b - a)
        else:
            gap += (-2.0 * g / zb - 2.0 * f / za) * (b - a) * dt
    return s, impulse, max(gap, 0.0)


def contact_step(za, zb, n_weld, fa, ga, prev, nxt, gap, contact, locate, held, dt):
    """The piston-shank contact (impedances ``za | zb``) over one step of the blow's loop, from the
    welded force ``n_weld`` of the arriving waves ``fa, ga``, the ``gap`` and whether in ``contact``
    at its start: ``(N, gap, contact)`` its force averaged over the step, the gap and the contact at
    its end. Welded while the force presses, else free ends with the gap summed over the step (and
    floored at 0), contact again from the first step that starts with it closed and pressing; with
    ``locate`` the switches inside the step, from the waves on the step before and the next
    (``prev``, ``nxt``: ``(F, G)``; ``held``: whether ``prev`` holds them, not on the blow's first
    step, where a re-contact has the gap linear over the step)."""
    inside = locate and held
    if contact:
        contact = n_weld >= 0.0
        if inside:
            part, impulse, g_end = opens_inside(za, zb, fa, ga, prev, nxt, dt)
            if 0.0 < part < 1.0:  # pressing up to `part`, apart from there
                return impulse, g_end, False
    else:
        contact = gap <= 0.0 and n_weld >= 0.0
    if contact:
        return n_weld, gap, True
    closing = (-2.0 * ga / zb - 2.0 * fa / za) * dt
    part, impulse = 1.0, 0.0
    if inside:  # closed inside the step: the force from there, averaged over it
        part, impulse = closes_inside(za, zb, fa, ga, prev, nxt, gap, dt)
    elif locate and gap + closing < 0.0:
        part, impulse = -gap / closing, n_weld * (1.0 + gap / closing)
    if part < 1.0:
        return impulse, 0.0, True
    return 0.0, max(gap + closing, 0.0), False


def _python_loop(F, G, Z, bounds, bit, dt, n_max, stop, quiet, gap0, drive, record_field, locate=False):
    """The blow's loop in numpy (the reference of ``"rock.blow"``; ``locate``: ``BlowGrid.locate``)."""
    Za, Zb = Z[:-1], Z[1:]
    wa, wb = 2.0 * Zb / (Za + Zb), 2.0 * Za / (Za + Zb)
    n_p, bit_mass, feed = int(bounds[0]), bit.m, bit.f
    gap = gap0
    contact = gap <= 0.0
    prev = (0.0, 0.0)  # the waves arriving at the contact on the step before (from the second)
    u_shank, grid_loss, work = 0.0, 0.0, 0.0
    last = 0 if contact else -1  # the last step in contact (-1: none yet; no end before a contact)
    jc = n_p - 1  # the contact is between cells jc and jc + 1
    junc, bitf, pen, fld = [], [bit.force()], [bit.p], []
    ended = "t_max"
    for step in range(n_max):
        N = wa * F[:-1] + wb * G[1:]  # welded junctions at every interior boundary
        # the piston-shank contact
        Fa, Gb = F[jc], G[jc + 1]
        nxt = (N[jc - 1] - G[jc] if jc > 0 else drive[step] - G[0],  # (the waves arriving next)
               N[jc + 1] - F[jc + 1] if jc + 2 < F.size else Gb)
        N[jc], gap, contact = contact_step(Za[jc], Zb[jc], N[jc], Fa, Gb, prev, nxt, gap, contact, locate,
                                           step > 0, dt)
        prev = (Fa, Gb)
        Fn = np.empty_like(F)
        Gn = np.empty_like(G)
        Fn[1:] = N - G[1:]
        Gn[:-1] = N - F[:-1]
        Fn[0] = drive[step] - G[0]  # the piston's driven far end: N = p
        work += drive[step] * (drive[step] - 2.0 * G[0]) / Z[0] * dt
        # the bit and the rock
        Fi = F[-1]
        p0, w_work0, ke0 = bit.p, bit.work, 0.5 * bit_mass * bit.w * bit.w
        bit.step(2.0 * Fi + feed, dt)
        g_avg = Fi - Z[-1] * (bit.p - p0) / dt
        Gn[-1] = g_avg
        e_in = (bit.work - w_work0) - feed * (bit.p - p0) + 0.5 * bit_mass * bit.w * bit.w - ke0
        grid_loss += (Fi * Fi - g_avg * g_avg) * dt / Z[-1] - e_in
        u_shank += (Fn[jc + 1] - G[jc + 1]) / Zb[jc] * dt
        junc.append(N[bounds - 1])
        bitf.append(bit.force())
        pen.append(bit.p)
        if record_field:
            fld.append(F + G)
        F, G = Fn, Gn
        if contact:
            last = step
        elif last < 0:
            pass
        elif quiet > 0 and step - last >= quiet:
            ended = "separated"
            break
        if not contact and last >= 0 and step % 8 == 0:
            rod_e = float(np.sum((F[n_p:] ** 2 + G[n_p:] ** 2) / Z[n_p:])) * dt
            if rod_e + 0.5 * bit_mass * bit.w * bit.w < stop:
                ended = "energy"
                break
    junc = np.array(junc).reshape(-1, bounds.size)
    return (F, G, junc, np.array(bitf), np.array(pen), np.array(fld),
            (u_shank, grid_loss, ended, gap, work))


def feed_gain(R_max: float, f: float) -> float:
    """How much rock work the energy ``Psi`` above the static state can still buy under the feed
    ``f``: at most ``R_max / (R_max - f)`` of it (each new yield from ``R_max`` on lowers ``Psi`` by
    its dissipation less the feed's work on the permanent advance, at least ``1 - f / R_max`` of
    it; theory §4d); 1 without a feed."""
    if f <= 0.0:
        return 1.0
    return R_max / (R_max - f) if R_max > f else math.inf
