"""The wave law's sustained contact (theory §4b): the piston pressed on the long rod.

When a contact window of the wave law ends with the struck end still moving into the rod, the
contact goes on. The rod is semi-infinite, so nothing returns from it: its end force and velocity
are tied by its impedance, ``F = Z u_t(1, t)``, ``Z = s (1 + R)/(1 - R)`` in the model's units
(``-s^2 u_x(1, t) = F``; the rod's area ratio ``A_s/A = (1 + R)/(1 - R)``). The struck end is a
dashpot. In the free-free modes (theory §2) the force at ``x = 1`` enters every mode:

    q_n'' + d q_n' + (s n pi)^2 q_n = p(t) - (-1)^n Z (c . q')

(a non-proportionally damped linear system, solved exactly through the eigenvectors of its
first-order matrix). Positions stay measured from the rod end, which moves with the struck end
(``c . q = 0``: ``q_0`` follows from the flexible modes), so the state is ``(q_1..q_N, q_0'..q_N')``.
The contact ends when the interface force ``F = Z c . q'`` would turn tensile (``c . q'`` crosses
zero downwards): the rod end then stops and the piston leaves it at rest.

The cost does not grow with ``s``: every eigenvalue decays at a rate of order ``s`` (at least
``s ln(1/R)/2`` for the flexible ones, the rate at which each round trip of a wave multiplies it
by ``R``; ``Z`` for the rigid piston), so the release is searched on a grid that is fine only over
the transients, and on the load's scale afterwards.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from .impact import modal_energy

__all__ = ["SustainedContact", "rod_impedance", "sustained_contact"]

TWO_PI = 2.0 * math.pi
#: a transient is dropped from the release search once its bound is below this (relative)
_TRANSIENT_TOL = 1e-15
#: samples of the release search per period of the fastest transient, and per load harmonic
_PER_PERIOD = 12


def rod_impedance(model) -> float:
    """The long rod's impedance in the model's units (theory §4b).

    Parameters
    ----------
    model : BarModel
        Its ``s`` and ``R`` (the rod's area ratio, ``A_s/A = (1 + R)/(1 - R)``).

    Returns
    -------
    float
        ``Z = s A_s/A = s (1 + R)/(1 - R)``: the rod end's force per unit velocity,
        ``F = Z u_t(1)`` with ``F = -s^2 u_x(1)`` (eq. 2's units); ``inf`` at ``R = 1``.
    """
    R = model.R
    return math.inf if R >= 1.0 else model.s * (1.0 + R) / (1.0 - R)


class _Piece:
    """The exact solution on a time interval where the load is one smooth expression."""

    def __init__(self, sys, ta, za, tb):
        self.sys, self.ta, self.tb = sys, ta, tb
        # a piecewise-constant load's level on this piece (its value at the ends may be the next)
        self.level = float(sys.load(0.5 * (ta + tb))) if sys._data.kind == 1 else None
        self.coef = sys.Vinv @ (za.astype(complex) - sys.particular(np.array([ta]), self.level)[:, 0])

    def states(self, t):
        """Reduced states at the times ``t`` (shape (T,)), shape (2N + 1, T)."""
        sys = self.sys
        dt = np.asarray(t, dtype=float) - self.ta
        tr = sys.V @ (self.coef[:, None] * np.exp(np.outer(sys.lam, dt)))
        return (tr + sys.particular(np.asarray(t, dtype=float), self.level)).real


class SustainedContact:
    """The piston pressed on the long rod from ``t0`` until the release (theory §4b).

    Made by :func:`sustained_contact`. Times are counted from ``t0`` (load time).

    Attributes
    ----------
    t0 : float
        Load time where the sustained contact starts (a contact window's end).
    duration : float
        Time to the release (or to the run's end, when the contact lasts beyond it).
    released : bool
        Whether the interface force turns tensile before the run's end.
    q_before, v_before : numpy.ndarray, shape (N + 1,)
        Free-free modal state at the start (positions from the rod end).
    q_after, v_after : numpy.ndarray, shape (N + 1,)
        State at the release (the end on the rod end at rest) or at the run's end.
    impedance : float
        ``Z = s (1 + R)/(1 - R)``.
    """

    def __init__(self, model, load, t0, q, v, t_end):
        self.model, self.load = model, load
        self.t0 = float(t0)
        self.q_before, self.v_before = np.array(q, dtype=float), np.array(v, dtype=float)
        N = model.n_modes
        self.N = N
        self.c = np.asarray(model.end_weights, dtype=float)
        self.impedance = Z = rod_impedance(model)
        w2 = model.frequencies**2
        M = N + 1
        e = np.where(np.arange(M) % 2 == 0, 1.0, -1.0)  # (-1)^n
        n2 = 2 * N + 1
        A = np.zeros((n2, n2))
        A[:N, N + 1:] = np.eye(N)  # q_n' = v_n, n >= 1
        A[N:, :N] = -np.diag(w2)[:, 1:]
        A[N:, N:] = -model.d * np.eye(M) - Z * np.outer(e, self.c)
        self.b = np.concatenate((np.zeros(N), np.ones(M)))
        self.A = A
        self.lam, self.V = np.linalg.eig(A)
        self.Vinv = np.linalg.inv(self.V)
        self.fv = (np.concatenate((np.zeros(N), self.c)) @ self.V)  # c . q' of each eigenvector
        self.kappa = np.where(np.arange(M) == 0, 1.0, 2.0)
        data = load.abilities.kernel.view
        self._data = data
        if data.kind == 0:
            ks = np.concatenate(([0.0], data.ks))
            pk = np.concatenate(([data.p0], data.pr + 1j * data.pim))
            self._ks = ks
            self._resp = np.stack([np.linalg.solve(1j * k * np.eye(n2) - A, self.b) * p
                                   for k, p in zip(ks, pk, strict=True)], axis=1)
        else:
            self._a_inv_b = -np.linalg.solve(A, self.b)
        self._pieces: list[_Piece] = []
        self._solve(self._reduced(self.q_before, self.v_before), float(t_end))
        self.q_after, self.v_after = self.state_at(self.duration)

    # ---- the linear system ---------------------------------------------------------------------
    def _reduced(self, q, v):
        return np.concatenate((q[1:], v))

    def _full(self, z):
        """Free-free states from reduced ones (shape (2N + 1, T)): ``q_0`` puts the end on the rod."""
        N = self.N
        qf = z[:N]
        q0 = -(self.c[1:] @ qf)
        return np.vstack((q0[None, :], qf)), z[N:]

    def particular(self, t, level=None):
        """The particular response at load times ``t`` (complex, real part meaningful); for a
        piecewise-constant load, to the constant ``level``."""
        t = np.asarray(t, dtype=float)
        if self._data.kind == 0:
            return self._resp @ np.exp(1j * np.outer(self._ks, t))
        return np.outer(self._a_inv_b, np.full(t.size, level)).astype(complex)

    def _edges(self, ta, tb):
        """Times in ``(ta, tb)`` where the load changes its expression."""
        D = self._data
        if D.kind == 0:
            return []
        m0, m1 = math.floor(ta / TWO_PI), math.floor(tb / TWO_PI)
        per = (np.arange(m0, m1 + 1)[:, None] * TWO_PI + D.breaks[None, :]).ravel()
        return sorted(float(x) for x in per[(per > ta) & (per < tb)])

    # ---- the release -----------------------------------------------------------------------------
    def _solve(self, z, t_end):
        lam_max = float(np.max(np.abs(self.lam))) if self.lam.size else 1.0
        decay = float(np.min(-self.lam.real)) if self.lam.size else 1.0
        kmax = float(np.max(self._data.ks)) if self._data.kind == 0 and self._data.ks.size else 0.0
        # on the transients: a geometric start resolves the fastest decay (the rigid piston's,
        # -Z), then steps resolve the fastest oscillation
        osc = float(np.max(np.abs(self.lam.imag))) if self.lam.size else 0.0
        h_tr = (1.0 / lam_max, TWO_PI / (_PER_PERIOD * osc) if osc > 0.0 else math.inf)
        h_ld = TWO_PI / (_PER_PERIOD * max(kmax, 1.0))  # on the load
        scale = max(self._data.psup / self.impedance, abs(float(self.c @ z[self.N:])), 1e-300)
        ta = self.t0
        while True:
            nxt = self._edges(ta, ta + TWO_PI + 1.0)
            tb = min(nxt[0] if nxt else ta + TWO_PI, t_end)
            piece = _Piece(self, ta, z, tb)
            self._pieces.append(piece)
            t_rel = self._search(piece, h_tr, h_ld, decay, scale)
            if t_rel is not None:
                self.released, self.duration = True, t_rel - self.t0
                piece.tb = t_rel
                return
            if tb >= t_end:
                self.released, self.duration = False, t_end - self.t0
                return
            z = piece.states(np.array([tb]))[:, 0]
            ta = tb

    def _search(self, piece, h_tr, h_ld, decay, scale):
        """First time in ``(ta, tb]`` where ``c . q'`` turns negative, or None. The samples go in
        chunks (bounded memory); a dip below zero between two samples (shorter than a twelfth of
        the fastest transient's period, or of the load's highest harmonic) is not seen."""
        ta, tb = piece.ta, piece.tb
        span = tb - ta
        # the transients: sampled finely until their bound is negligible
        big = float(np.sum(np.abs(self.fv * piece.coef)))
        t_tr = math.log(max(big / (_TRANSIENT_TOL * scale), 1.0)) / decay if big > 0 else 0.0
        t_tr = min(t_tr, span)
        h_fast, h_osc = h_tr
        h_osc = min(h_osc, max(t_tr / 16.0, h_fast))
        start = h_fast * 2.0 ** np.arange(0, max(1, math.ceil(math.log2(max(h_osc / h_fast, 1.0))) + 1))
        start = start[start < min(h_osc, t_tr)] if t_tr > 0 else start[:0]
        n_osc = math.ceil(max(t_tr - (start[-1] if start.size else 0.0), 0.0) / h_osc) if t_tr > 0 else 0
        n_ld = max(2, math.ceil((span - t_tr) / h_ld) + 1)

        def chunks():
            yield np.r_[ta, ta + start]
            base = ta + (start[-1] if start.size else 0.0)
            for i in range(0, n_osc, 4096):
                yield base + h_osc * np.arange(i + 1, min(i + 4096, n_osc) + 1)
            yield np.linspace(ta + t_tr, tb, n_ld)

        t_prev = f_prev = None
        for t in chunks():
            t = np.minimum(t, tb)
            f = self.fv_at(piece, t)
            if t_prev is not None:
                t, f = np.r_[t_prev, t], np.r_[f_prev, f]
            below = np.nonzero(f[1:] <= 0.0)[0]
            if below.size:
                i = int(below[0]) + 1
                a, b = t[i - 1], t[i]
                if f[i - 1] <= 0.0:  # at the piece's start already (a load turning tensile there)
                    return a
                return brentq(lambda x: self.fv_at(piece, np.array([x]))[0], a, b,
                              xtol=1e-15 * max(1.0, abs(b)), rtol=4 * np.finfo(float).eps)
            t_prev, f_prev = t[-1], f[-1]
        return None

    def fv_at(self, piece, t) -> np.ndarray:
        """``c . q'`` (the struck end's velocity) at the times ``t``: the row ``c . q'`` of the
        eigenvectors and of the particular response applied directly, ``O(N)`` per time (the
        whole state is ``O(N^2)``: at 256 modes it took minutes)."""
        t = np.asarray(t, dtype=float)
        dt = t - piece.ta
        tr = (self.fv * piece.coef) @ np.exp(np.outer(self.lam, dt))
        cv = np.concatenate((np.zeros(self.N), self.c))
        if self._data.kind == 0:
            part = (cv @ self._resp) @ np.exp(1j * np.outer(self._ks, t))
        else:
            part = float(cv @ self._a_inv_b) * piece.level
        return (tr + part).real

    # ---- outputs ---------------------------------------------------------------------------------
    def _piece_at(self, t_abs):
        for p in self._pieces:
            if t_abs <= p.tb:
                return p
        return self._pieces[-1]

    def state_at(self, tau):
        """Free-free modal state ``(q, q')`` at time ``tau`` after ``t0`` (positions from the rod end).

        Returns
        -------
        q, v : numpy.ndarray, shape (N + 1,)
        """
        t_abs = self.t0 + float(tau)
        z = self._piece_at(t_abs).states(np.array([t_abs]))
        q, v = self._full(z)
        return q[:, 0], v[:, 0]

    def force(self, tau) -> np.ndarray:
        """Interface force ``F = Z u_t(1)`` at times ``tau`` after ``t0`` (shape of ``tau``)."""
        tau = np.atleast_1d(np.asarray(tau, dtype=float))
        out = np.array([self.fv_at(self._piece_at(self.t0 + x), np.array([self.t0 + x]))[0]
                        for x in tau])
        return self.impedance * out

    def account(self, tau):
        """The energy balance up to time ``tau``.

        Returns
        -------
        drive_work, rod_energy, damping_loss, field_energy : float
            ``energy(t0) + drive_work = field_energy + rod_energy + damping_loss``, the integrals
            by Gauss-Legendre quadrature on panels fine over the transients (the integrands are
            sums of exponentials and of the load's harmonics: errors near rounding).
        """
        work, rod, damp, _ = self._integrals(tau)
        q, v = self.state_at(tau)
        return work, rod, damp, modal_energy(self.model.s, q, v)

    @property
    def advance(self) -> float:
        """Advance of the rod end over the whole sustained contact, ``int u_t(1) dt``."""
        *_, advance = self._integrals(self.duration)
        return advance

    def _integrals(self, tau):
        """``(drive_work, rod_energy, damping_loss, advance)`` from ``t0`` to ``t0 + tau``, in closed
        form (memoised: the account and the damping ask for the same ``tau``).

        On each piece the velocities are a sum of exponentials, ``v(t) = sum_j C_j e^{mu_j (t - ta)}``
        (the eigenvalues, their conjugates and the load's harmonics ``+-i k``, the real part written
        as half a sum with its conjugate), and so is the load; every integrand is linear or quadratic
        in them, so each integral is ``sum C_j C_l (e^{(mu_j + mu_l) L} - 1)/(mu_j + mu_l)``: ``O(J^2)``
        per piece, ``J = 2 (2 N + 1) + 2 K``, whatever ``s`` and the duration (Gauss-Legendre, as before,
        on panels as fine as the fastest transient took 12 s a load period at ``s = 50``, 40 modes)."""
        key = float(tau)
        memo = self.__dict__.setdefault("_integral_memo", {})
        if key not in memo:
            memo[key] = self._closed_integrals(self.t0 + key)
        return memo[key]

    def _closed_integrals(self, t_end):
        N, D = self.N, self._data
        kap, c = self.kappa, self.c
        work = rod = damp = adv = 0.0
        for p in self._pieces:
            a, b = p.ta, min(p.tb, t_end)
            if b <= a:
                break
            L = b - a
            # v(t) = Re(V_v (coef e^{lam (t - ta)}) + particular_v(t)) as sum_j C[:, j] e^{mu_j (t - ta)}
            trans = self.V[N:, :] * p.coef[None, :]
            if D.kind == 0:
                phase = np.exp(1j * self._ks * p.ta)
                part = self._resp[N:, :] * phase[None, :]
                mu = np.concatenate((self.lam, 1j * self._ks))
                C = np.concatenate((trans, part), axis=1)
                P = np.concatenate(([D.p0], D.pr + 1j * D.pim)) * phase  # load: Re(sum P e^{i k t})
                nu = 1j * self._ks
            else:
                mu = np.concatenate((self.lam, [0.0]))
                C = np.concatenate((trans, (self._a_inv_b[N:] * p.level)[:, None]), axis=1)
                P, nu = np.array([p.level], dtype=complex), np.zeros(1, dtype=complex)
            mu = np.concatenate((mu, mu.conj()))
            C = 0.5 * np.concatenate((C, C.conj()), axis=1)
            P, nu = 0.5 * np.concatenate((P, P.conj())), np.concatenate((nu, nu.conj()))
            kv, cv = kap @ C, c @ C  # rows: kappa . v and c . v
            work += _exp_integral(nu[:, None] + mu[None, :], L, np.outer(P, kv))
            rod += self.impedance * _exp_integral(mu[:, None] + mu[None, :], L, np.outer(cv, cv))
            damp += self.model.d * _exp_integral(mu[:, None] + mu[None, :], L,
                                                 C.T @ (kap[:, None] * C))
            adv += _exp_integral(mu, L, cv)
        return work, rod, damp, adv


def _exp_integral(mu, L, coef) -> float:
    """``Re sum coef * int_0^L e^{mu t} dt``, the integral ``expm1(mu L)/mu`` (``L`` at ``mu = 0``)."""
    mu = np.asarray(mu, dtype=complex)
    small = np.abs(mu) * L < 1e-300
    safe = np.where(small, 1.0, mu)
    phi = np.where(small, L, np.expm1(safe * L) / safe)
    return float(np.sum(coef * phi).real)


def sustained_contact(model, load, t0, q, v, t_end) -> SustainedContact:
    """The sustained contact of the wave law from ``(t0, q, v)`` (theory §4b).

    Parameters
    ----------
    model : BarModel
        ``R < 1`` (a finite rod impedance).
    load : FourierLoad or PiecewiseConstantLoad
    t0 : float
        Load time of the start (a contact window's end, the end still moving into the rod).
    q, v : numpy.ndarray, shape (N + 1,)
        Free-free modal state at ``t0``, the end on the rod end (``c . q = 0``).
    t_end : float
        Stop here if the contact lasts so long (finite: a load that presses for ever keeps the
        contact for ever; the search costs a few samples per load period).

    Returns
    -------
    SustainedContact
    """
    return SustainedContact(model, load, t0, q, v, t_end)
