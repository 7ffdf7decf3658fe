"""The compiled simulation's data for one bar under one load: its two modal bases and the kernel's
calls (private; theory §8).

A :class:`_Core` holds what the event-driven run (:func:`impactbar.simulation.simulate`) needs about
one (model, load) pair: the free-free modes' and the fixed-free contact modes' frequencies and
particular responses (eqs. 8, 16), the projections between the two bases (the overlaps
``int_0^1 cos(n pi x) cos((m - 1/2) pi x) dx``), the stop's reaction, and the calls of the compiled
flight kernel, release search and exact propagation. Cores are built once per pair and kept
(:func:`_core_for`).
"""

from __future__ import annotations

import threading

import numpy as np

from .._shared.forcing import of_family
from ..dynamics import compiled as K
from ..dynamics.compiled_views import LoadKernelView, ModalBasisView
from ..dynamics.implementations import use_fast
from ..loads import Load
from ..model import BarModel
from ._shortrun import entry_point
from .trajectory import _CONTACT, _FREE

#: Chatter: jump to the accumulation point once the remaining bounces last less than this.
CHATTER_TAIL = 1e-9


class _Basis:
    """Frequencies, weights and particular-response data of one modal basis under one load."""

    def __init__(self, w2: np.ndarray, d: float, data: LoadKernelView):
        self.w2 = np.ascontiguousarray(w2, dtype=float)
        M = self.w2.size
        ks = data.ks
        if data.kind == 0 and ks.size:
            den = self.w2[:, None] + 1j * ks[None, :] * d - ks[None, :] ** 2
            if np.any(np.abs(den) <= 1e-12 * np.maximum(1.0, ks[None, :] ** 2)):
                raise ValueError(
                    "load: undamped resonance, a mode frequency equals a load harmonic k "
                    "(eq. 16); use d > 0 or move s"
                )
            hp = (data.pr + 1j * data.pim)[None, :] / den
        else:
            hp = np.zeros((M, ks.size), dtype=complex)
        self.hpr = np.ascontiguousarray(hp.real)
        self.hpi = np.ascontiguousarray(hp.imag)
        ah = np.abs(hp)
        self.vpb = np.ascontiguousarray(ah @ ks) if ks.size else np.zeros(M)
        self.apb = np.ascontiguousarray(ah @ ks**2) if ks.size else np.zeros(M)
        self.jpb = np.ascontiguousarray(ah @ ks**3) if ks.size else np.zeros(M)
        # a bound of the particular state |q_p| (static deflection plus harmonic response): the
        # closed form adds and cancels it, so it sets the rounding noise of a mode's displacement
        static = np.where(self.w2 > 0.0, data.psup / np.where(self.w2 > 0.0, self.w2, 1.0), 0.0)
        self.qpb = static + (ah.sum(axis=1) if ks.size else 0.0)
        self.view = ModalBasisView(self.w2, float(d), self.hpr, self.hpi, self.vpb, self.apb, self.jpb)


def _load_view(load: Load) -> LoadKernelView:
    """The load's one kernel view (its abilities' :class:`~impactbar.loads.LoadKernel`); a load the
    kernels do not know is refused."""
    kernel = load.abilities.kernel if of_family(load, "load") else None
    view = kernel.view if kernel is not None else None
    if view is None:
        raise ValueError(
            f"load must be a FourierLoad (CosineLoad) or a PiecewiseConstantLoad "
            f"(SquareWaveLoad); got {type(load).__name__}"
        )
    return view


def _overlap(n: np.ndarray, m: np.ndarray) -> np.ndarray:
    """``int_0^1 cos(n pi x) cos((m - 1/2) pi x) dx = (S(n - m + 1/2) + S(n + m - 1/2)) / 2`` with
    ``S(c) = sin(c pi) / (c pi)`` (theory §8), shape ``(len(n), len(m))``."""
    a = n[:, None] - m[None, :] + 0.5
    b = n[:, None] + m[None, :] - 0.5
    return 0.5 * (np.sinc(a) + np.sinc(b))


_CORES: dict = {}  # (model, load) -> core, the most recent _CORES_MAX pairs; and _LAST
_CORES_MAX = 16
_CORES_LOCK = threading.Lock()
_LAST = "last"  # _CORES[_LAST]: (model, load, core) of the last call (cleared with the cache)


def _core_for(model: BarModel, load: Load) -> _Core:
    """The kernel's data for this model and load, built once and reused by later runs (a short run's
    fixed cost; the Monte Carlo experiments run thousands with one pair). Keyed by the values of the
    model and the load (both frozen: an entry never goes stale), the last call's found by identity."""
    last = _CORES.get(_LAST)
    if last is not None:
        last_model, last_load, core = last
        if last_model is model and last_load is load:
            return core
    key = (model, load)
    with _CORES_LOCK:
        core = _CORES.get(key)
    if core is None:
        core = _Core(model, load)
    with _CORES_LOCK:
        if key not in _CORES and len(_CORES) - (_LAST in _CORES) >= _CORES_MAX:  # the oldest pair goes
            _CORES.pop(next(k for k in _CORES if k is not _LAST))
        _CORES[key] = core
        _CORES[_LAST] = (model, load, core)
    return core


class _Core:
    """Everything the driver needs about one (model, load) pair."""

    def __init__(self, model: BarModel, load: Load):
        self.model = model
        self.load = load
        self.N = model.n_modes
        self.d = model.d
        self.R = model.law.traits.kernel_restitution(model)  # -1 (v -> v): the law's contact step acts
        self.data = _load_view(load)
        self.c = np.ascontiguousarray(model.end_weights)
        self.free = _Basis(model.frequencies**2, model.d, self.data)
        m = np.arange(1, self.N + 1, dtype=float)
        sticking = model.sticking  # a stepped piston's fixed-free modes (theory §12), or None
        self.mu = (m - 0.5) * np.pi if sticking is None else sticking.wavenumbers
        self.contact = _Basis((model.s * self.mu) ** 2, model.d, self.data)
        # stop reaction F = p (1 - sum a) + sum a_m w2_m r_m, a_m = 2 (-1)^(m+1) / mu_m
        if sticking is not None:
            self.a = np.array(sticking.reaction_weights)
        else:
            self.a = 2.0 * (-1.0) ** (m + 1) / self.mu if self.N else np.zeros(0)
        self.f_alpha = 1.0 - float(np.sum(self.a))
        self.f_wts = np.ascontiguousarray(self.a * self.contact.w2)
        n = np.arange(self.N + 1, dtype=float)
        kappa = model.drive_weights  # (1, 2, .., 2), or a stepped piston's phi_n(0)^2
        if sticking is None:
            ov = _overlap(n, m)  # (N+1, N)
            self.to_contact = np.ascontiguousarray((kappa[:, None] * ov).T)  # r = P q, (N, N+1)
            self.to_free = np.ascontiguousarray(2.0 * ov)  # q = P r, (N+1, N)
            self.contact_kappa = np.full(self.N, 2.0)
        else:
            self.to_contact = np.ascontiguousarray(sticking.to_contact)
            self.to_free = np.ascontiguousarray(sticking.to_free)
            self.contact_kappa = np.array(sticking.contact_weights)
        self.kappa = kappa
        self.sticking = sticking
        self.free_args = (tuple(self.data), tuple(self.free.view), self.R, self.c)  # built once
        self.instant = model.law.traits.restitution_in_kernel
        # the kernel for a flight of this bar, compiled without the other kind's search
        self.kernel = K.run_free_rigid if self.N == 0 else K.run_free
        self._entry = None

    # ---- energies ----------------------------------------------------------------------------
    def energy(self, basis: int, q: np.ndarray, v: np.ndarray) -> float:
        """Kinetic plus strain energy of a modal state."""
        if basis == _FREE:
            k = self.kappa
            return float(0.5 * np.sum(k * v * v) + 0.5 * np.sum(k * self.free.w2 * q * q))
        k = self.contact_kappa
        return float(0.5 * np.sum(k * v * v) + 0.5 * np.sum(k * self.contact.w2 * q * q))

    def kinetic(self, v: np.ndarray) -> float:
        return float(0.5 * np.sum(self.kappa * v * v))

    # ---- kernel calls ------------------------------------------------------------------------
    def run_free(self, t, q, v, t_end, max_imp, out_q, out_v, direct=False):
        """Free flight with impacts (the kernel's ``run_free``); the states after the impacts go
        into the rows of ``out_q, out_v`` (shape (cap, N + 1)), at most ``cap`` of them. ``direct``: by
        the kernel's entry point for these argument types, untyped (numba's typing of 11 arguments
        costs 2 us), once it is compiled for them."""
        out_t, out_vel = np.empty(out_q.shape[0]), np.empty(out_q.shape[0])
        n, st, tn = self.run_block(float(t), q, v, float(t_end), int(max_imp),
                                   (out_t, out_vel, out_q, out_v), direct)
        return n, st, tn, out_t[:n], out_vel[:n]

    def run_block(self, t, q, v, t_end, max_imp, out, direct=False):
        """:meth:`run_free` into ``out = (out_t, out_vel, out_q, out_v)`` (``t, t_end`` floats,
        ``max_imp`` an int): ``n, status, t``."""
        fast = use_fast("simulate.impact_search")
        D, B, R, c = self.free_args
        # a rigid run compiles no modal search, a flexible one no rigid search
        if self.N == 0:
            args = (D, B, R, c, (t, q, v), t_end, max_imp, CHATTER_TAIL, out, fast, None)
        else:
            args = (D, B, R, c, (t, q, v), t_end, max_imp, CHATTER_TAIL, out, None, fast)
        if not direct:
            return self.kernel(*args)
        run = self._entry
        if run is None:  # (the entry point once compiled, found once per core)
            run = entry_point(self.kernel, args)
            if run is not self.kernel:
                self._entry = run
        return run(*args)

    def find_release(self, t, r, rv, t_end):
        """First time after ``t`` when the stop reaction turns tensile; state there."""
        D, B = self.data, self.contact
        qa = np.array(r, dtype=float)
        va = np.array(rv, dtype=float)
        M = self.N
        q = np.empty(M)
        v = np.empty(M)
        scratch = [np.empty(M) for _ in range(4)]
        anchor = np.array([float(t)])
        st, tr = K.find_crossing(tuple(D), tuple(B.view), -self.f_wts, -self.f_alpha, anchor, qa, va,
                                 float(t_end), 0.0, (q, v, *scratch))
        if st == K.CROSS:
            tr, q, v = self._clearly_tensile(tr, q, v, t_end)
        return st, tr, q, v

    def _clearly_tensile(self, tr, r, rv, t_end):
        """Move a release a rounding error on, to where the reaction is negative beyond its
        rounding noise: exactly at ``F = 0`` the free motion's first sign is noise."""
        scale = abs(self.f_alpha) * self.data.psup + float(np.sum(np.abs(self.f_wts * r)))
        target = -1e-12 * scale
        if self.stop_force(tr, r) <= target:
            return tr, r, rv
        step = 1e-15 * (1.0 + abs(tr))
        while step <= 1e-9 * (1.0 + abs(tr)) and tr + step < t_end:
            r2, rv2 = self.propagate(_CONTACT, tr, r, rv, [tr + step])
            if self.stop_force(tr + step, r2[:, 0]) <= target:
                return tr + step, r2[:, 0], rv2[:, 0]
            step *= 2.0
        return tr, r, rv

    def release_state(self, r, rv):
        """Free-free state from a contact state: projected, end put exactly on the stop at rest."""
        if self.N == 0:
            return np.zeros(1), np.zeros(1)
        q = self.to_free @ r
        v = self.to_free @ rv
        q[0] -= float(self.c @ q)  # a shift of the mean displacement: no energy
        v[0] -= float(self.c @ v)  # the end at rest, as in contact; its energy goes to `projection`
        for x in (q, v):  # rounding must not leave the end a hair inside the stop or moving in
            e = float(self.c @ x)
            if e > 0.0:
                x[0] -= 2.0 * e
        return q, v

    def contact_shapes(self, x) -> np.ndarray:
        """The fixed-free shapes at positions ``x`` (shape ``(X,)``): ``u = shapes @ r``, shape ``(X, N)``."""
        if self.sticking is not None:
            return self.sticking.shapes(x)
        return 2.0 * np.cos(np.outer(x, self.mu))

    def contact_state(self, q, v):
        return self.to_contact @ q, self.to_contact @ v

    def stop_force(self, t, r):
        """``F_stop`` at time ``t`` for the contact state ``r`` (theory §8)."""
        return self.f_alpha * float(self.load(t)) + float(self.f_wts @ r)

    def propagate(self, basis, t0, q, v, t):
        """Exact state at times ``t >= t0`` (shape (T,)) from ``(t0, q, v)`` in a basis, shape
        (M, T) each. (The compiled kernel's flow; ``Load.propagate`` is the independent reference
        the tests hold it to.)"""
        if basis == _CONTACT and self.N == 0:
            z = np.zeros((0, np.size(t)))
            return z, z
        B = self.free if basis == _FREE else self.contact
        D = self.data
        t = np.atleast_1d(np.asarray(t, dtype=float))
        order = np.argsort(t, kind="stable")
        ts = np.ascontiguousarray(t[order])
        Q = np.empty((B.w2.size, ts.size))
        V = np.empty_like(Q)
        K.propagate_many(tuple(D), tuple(B.view), float(t0), np.ascontiguousarray(q, dtype=float),
                         np.ascontiguousarray(v, dtype=float), ts, Q, V)
        out_q = np.empty_like(Q)
        out_v = np.empty_like(V)
        out_q[:, order] = Q
        out_v[:, order] = V
        return out_q, out_v
