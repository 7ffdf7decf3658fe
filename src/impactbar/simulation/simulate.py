"""Event-driven simulation from any start, impact after impact (paper Section 5, theory §8).

Between impacts the bar moves in closed form (theory §2, eq. 8), so there is no
time-stepping error; a piecewise-constant load (the hydraulic square wave, eq. 34) is integrated
exactly piece by piece. The next impact, the first ``t`` with ``u(1,t) = c . q(t) = 0`` and
``u_t(1,t) > 0``, is found with a guaranteed search (bounds on ``|u_tt(1,t)|`` and
``|u_ttt(1,t)|`` from the modal energies exclude every step it takes), then refined to rounding;
after an impact the rigid bar under one harmonic and flexible bars under a Fourier load take
specialised searches with the same guarantee (switch ``"simulate.impact_search"`` of
:mod:`impactbar.dynamics.implementations`).
At an impact ``u_t(x) -> -R u_t(x)`` (eqs. 10, 11); under the wave law (``BarModel(impact="wave")``,
theory §4b) each impact is instead a contact window of length ``2/s`` with the long rod, solved by
characteristics (:func:`impactbar.dynamics.impact.wave_impact`), after which the flight resumes.

With ``R < 1`` and a load pressing the end on the stop the bounces shrink geometrically and
accumulate in finite time; the simulation jumps to the accumulation point, where the velocity field
has gone to zero, and follows the bar fixed at ``x = 1`` (fixed-free modes
``r_m = int_0^1 u cos((m - 1/2) pi x) dx``, theory §8) until the stop's reaction
``F_stop = p - q_0'' - d q_0'`` would turn tensile; then the state is projected back on the
free-free modes and the free motion resumes.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .. import _tables
from .._validate import check_int, check_real
from ..dynamics import _kernel as K
from ..dynamics import _wavekernel as WK
from ..dynamics.impact import wave_impact
from ..dynamics.implementations import use_fast
from ..dynamics.kernelview import LoadKernelView, ModalBasisView
from ..loads import Load
from ..model import MAX_MODES, BarModel

__all__ = ["InitialState", "Trajectory", "EnergyAccount", "simulate"]

TWO_PI = 2.0 * math.pi

#: Chatter: jump to the accumulation point once the remaining bounces last less than this.
CHATTER_TAIL = 1e-9
#: First extra dwell in contact when the free and the fixed-free bases disagree at a release.
DWELL_START = 1e-9
#: Largest such dwell (it grows fourfold while the disagreement lasts).
DWELL_MAX = 1e-2
#: A flight after a release that ends back on the stop within this time (bounces included) is a
#: disagreement between the truncated bases, not a motion: the release is undone.
MICRO_FLIGHT = 1e-6

# Implementations (impactbar.dynamics.implementations): "simulate.impact_search" searches the
# impacts after an impact by the kernel's specialised certified searches (the rigid bar under one
# harmonic in scalars, ``rigid1_crossing``; flexible modes under a Fourier load in folded form,
# ``modal_crossing``), the reference being the general search ``find_crossing`` (the same impacts, to
# rounding); "simulate.wave_separation" solves the wave law's contact windows that lose contact by
# the compiled characteristics solver (``dynamics._wavekernel.wave_contact``), the reference being
# the Python solver (:func:`~impactbar.dynamics.impact.wave_impact`).

#: Largest ``|t0|``, ``|t_end|`` and ``t_end - t0`` accepted by :func:`simulate` (about 1.6e7 periods).
MAX_TIME = 1e8
#: Largest quadrature work (nodes times modes) :attr:`Trajectory.energy` may take (time bound).
MAX_ENERGY_WORK = 3e8
#: Largest ``s * n_modes`` :func:`simulate` accepts: the guaranteed event search steps on the
#: scale of the stiffest mode's period, so beyond it a run does not finish in bounded time.
MAX_SIMULATE_STIFFNESS = 1e5

_FREE, _CONTACT, _WAVE = 0, 1, 2  # _WAVE: a contact window of the wave law (free-free modes)


# --------------------------------------------------------------------------------------------------
# initial state
# --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class InitialState:
    """Modal state of the free-free bar (theory §2).

    ``u(x) = q_0 + 2 sum_{n>=1} q_n cos(n pi x)`` and the same for the velocity field.

    Parameters
    ----------
    modal_displacement : array_like, shape (N + 1,)
        ``q_0..q_N`` (dimensionless).
    modal_velocity : array_like, shape (N + 1,)
        ``q_0'..q_N'``.

    Raises
    ------
    ValueError
        If the arrays are not 1-d, of different lengths, empty, or not finite.
    """

    modal_displacement: np.ndarray
    modal_velocity: np.ndarray

    def __post_init__(self) -> None:
        q = _real_vector("modal_displacement", self.modal_displacement)
        v = _real_vector("modal_velocity", self.modal_velocity)
        if q.size != v.size:
            raise ValueError(
                f"modal_velocity must have the length of modal_displacement ({q.size}); "
                f"got {v.size}"
            )
        q.setflags(write=False)
        v.setflags(write=False)
        object.__setattr__(self, "modal_displacement", q)
        object.__setattr__(self, "modal_velocity", v)

    @classmethod
    def _trusted(cls, q: np.ndarray, v: np.ndarray) -> InitialState:
        """A state from arrays the simulator made (finite, 1-d, of one length): no checks, no copy."""
        self = object.__new__(cls)
        q.setflags(write=False)
        v.setflags(write=False)
        object.__setattr__(self, "modal_displacement", q)
        object.__setattr__(self, "modal_velocity", v)
        return self

    @property
    def n_modes(self) -> int:
        """Flexible modes ``N`` the state carries."""
        return self.modal_displacement.size - 1

    @classmethod
    def rigid(cls, end_displacement, velocity, n_modes: int = 0) -> InitialState:
        """An undeformed bar with its struck end at ``end_displacement`` moving at ``velocity``.

        Parameters
        ----------
        end_displacement : float
            ``u(1)``, ``<= 0`` (the stop is at 0).
        velocity : float
            Uniform velocity (positive towards the stop).
        n_modes : int, optional
            Flexible modes to carry (all zero). A one-mode state is also accepted by
            :func:`simulate` for any model and padded with zeros.

        Raises
        ------
        ValueError
            If ``end_displacement > 0`` (the start would penetrate the stop).
        """
        e = check_real("end_displacement", end_displacement, hi=0.0)
        vel = check_real("velocity", velocity)
        n_modes = check_int("n_modes", n_modes, lo=0, hi=MAX_MODES)
        q = np.zeros(n_modes + 1)
        v = np.zeros(n_modes + 1)
        q[0] = e
        v[0] = vel
        return cls(q, v)

    @classmethod
    def from_fields(cls, u0, v0, model: BarModel) -> InitialState:
        """Project displacement and velocity fields on the free-free modes (eq. 5).

        Parameters
        ----------
        u0, v0 : callable
            Vectorised functions of ``x`` in ``[0, 1]`` giving ``u(x, t0)`` and ``u_t(x, t0)``.
        model : BarModel
            Gives the number of modes ``N``.

        Returns
        -------
        InitialState
            ``q_n = int_0^1 u0(x) cos(n pi x) dx`` (Gauss-Legendre, exact for polynomials of
            degree below 64 per panel), ``n = 0..N``.

        Raises
        ------
        ValueError
            If a field is not callable or returns non-finite values, or ``u0(1) > 0``.
        """
        if not isinstance(model, BarModel):
            raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
        for name, f in (("u0", u0), ("v0", v0)):
            if not callable(f):
                raise ValueError(f"{name} must be a callable of x; got {type(f).__name__}")
        panels = max(8, model.n_modes // 4 + 1)
        xg, wg = np.polynomial.legendre.leggauss(32)
        edges = np.linspace(0.0, 1.0, panels + 1)
        half = 0.5 * (edges[1:] - edges[:-1])[:, None]
        x = (half * (xg[None, :] + 1.0) + edges[:-1, None]).ravel()
        w = (half * wg[None, :]).ravel()
        basis = np.cos(np.pi * np.outer(x, np.arange(model.n_modes + 1)))
        out = []
        for name, f in (("u0", u0), ("v0", v0)):
            vals = np.broadcast_to(np.asarray(f(x), dtype=float), x.shape)
            if not np.all(np.isfinite(vals)):
                raise ValueError(f"{name} must return finite values on [0, 1]")
            out.append((w * vals) @ basis)
        end = float(np.asarray(u0(np.array([1.0])), dtype=float).ravel()[0])
        if end > 0.0:
            raise ValueError(f"u0 must keep the struck end off the stop, u0(1) <= 0; got {end}")
        return cls(out[0], out[1])


def _real_vector(name, value) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float, copy=True)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a 1-d array of real numbers; got {value!r}") from exc
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-d array; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got {arr}")
    return arr


# --------------------------------------------------------------------------------------------------
# energy account
# --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class EnergyAccount:
    """Energy balance of a run (all dimensionless, per ``M L^3 Omega^2``).

    ``work = (final - initial) + damping_loss + impact_loss + chatter_loss - projection``, where

    - ``work = int p(t) u_t(0, t) dt`` is the work of the load at the driven end,
    - ``initial``, ``final`` are kinetic plus strain energy
      ``(1/2) int u_t^2 dx + (s^2/2) int u_x^2 dx`` at the start and the end,
    - ``damping_loss = d int int u_t^2 dx dt``,
    - ``impact_loss = sum (1 - R^2) T_before`` over the impacts (the whole velocity field is
      reversed and scaled by ``R``),
    - ``chatter_loss`` is the kinetic energy left when the simulation jumps to the accumulation
      point of a chatter sequence (the bounces it skips would have dissipated it),
    - ``projection`` is what the changes of modal basis at the start and end of permanent contact
      add (a truncated projection does not conserve energy; theory §8).
    """

    work: float
    initial: float
    final: float
    damping_loss: float
    impact_loss: float
    chatter_loss: float
    projection: float

    @property
    def residual(self) -> float:
        """``work - (final - initial) - damping_loss - impact_loss - chatter_loss + projection``."""
        return (self.work - (self.final - self.initial) - self.damping_loss - self.impact_loss
                - self.chatter_loss + self.projection)

    @property
    def scale(self) -> float:
        """The largest term, for a relative residual."""
        return max(abs(self.work), self.initial, self.final, self.damping_loss, self.impact_loss,
                   self.chatter_loss, abs(self.projection), 1e-300)

    @property
    def relative_residual(self) -> float:
        """``|residual| / scale``."""
        return abs(self.residual) / self.scale


# --------------------------------------------------------------------------------------------------
# precomputed model + load data for the kernel
# --------------------------------------------------------------------------------------------------
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
    """The load's one kernel view (:attr:`impactbar.Load.kernel_view`); a load the kernels do not
    know is refused."""
    view = load.kernel_view if isinstance(load, Load) else None
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


_CORES: dict = {}  # (model, load) -> core, the most recent _CORES_MAX pairs
_CORES_MAX = 16
_CORES_LOCK = threading.Lock()


def _core_for(model: BarModel, load: Load) -> _Core:
    """The kernel's data for this model and load, built once and reused by later runs (a short
    run's fixed cost; the Monte Carlo experiments run thousands with the same pair). Keyed by the
    model's value and the load's value (both are frozen, so an entry never goes stale); a core is
    never modified."""
    key = (model, load)
    with _CORES_LOCK:
        hit = _CORES.get(key)
    if hit is not None:
        return hit
    core = _Core(model, load)
    with _CORES_LOCK:
        if len(_CORES) >= _CORES_MAX:
            _CORES.pop(next(iter(_CORES)))
        _CORES[key] = core
    return core


class _Core:
    """Everything the driver needs about one (model, load) pair."""

    def __init__(self, model: BarModel, load: Load):
        self.model = model
        self.load = load
        self.N = model.n_modes
        self.d = model.d
        self.R = model.R
        self.data = _load_view(load)
        self.c = np.ascontiguousarray(model.end_weights)
        self.free = _Basis(model.frequencies**2, model.d, self.data)
        m = np.arange(1, self.N + 1, dtype=float)
        self.mu = (m - 0.5) * np.pi
        self.contact = _Basis((model.s * self.mu) ** 2, model.d, self.data)
        # stop reaction F = p (1 - sum a) + sum a_m w2_m r_m, a_m = 2 (-1)^(m+1) / mu_m
        self.a = 2.0 * (-1.0) ** (m + 1) / self.mu if self.N else np.zeros(0)
        self.f_alpha = 1.0 - float(np.sum(self.a))
        self.f_wts = np.ascontiguousarray(self.a * self.contact.w2)
        n = np.arange(self.N + 1, dtype=float)
        ov = _overlap(n, m)  # (N+1, N)
        kappa = np.where(n == 0, 1.0, 2.0)
        self.to_contact = np.ascontiguousarray((kappa[:, None] * ov).T)  # r = P q, (N, N+1)
        self.to_free = np.ascontiguousarray(2.0 * ov)  # q = P r, (N+1, N)
        self.kappa = kappa

    # ---- energies ----------------------------------------------------------------------------
    def energy(self, basis: int, q: np.ndarray, v: np.ndarray) -> float:
        """Kinetic plus strain energy of a modal state."""
        if basis == _FREE:
            k = self.kappa
            return float(0.5 * np.sum(k * v * v) + 0.5 * np.sum(k * self.free.w2 * q * q))
        return float(np.sum(v * v) + np.sum(self.contact.w2 * q * q))

    def kinetic(self, v: np.ndarray) -> float:
        return float(0.5 * np.sum(self.kappa * v * v))

    # ---- kernel calls ------------------------------------------------------------------------
    def run_free(self, t, q, v, t_end, max_imp, out_q, out_v):
        """Free flight with impacts (the kernel's ``run_free``); the states after the impacts go
        into the rows of ``out_q, out_v`` (shape (cap, N + 1)), at most ``cap`` of them."""
        D, B = self.data, self.free
        cap = out_q.shape[0]
        out_t = np.empty(cap)
        out_vel = np.empty(cap)
        n, st, tn = K.run_free(tuple(D), tuple(B.view), self.R, self.c, float(t), q, v, float(t_end),
                               int(max_imp), CHATTER_TAIL, (out_t, out_vel, out_q, out_v),
                               use_fast("simulate.impact_search"))
        return n, st, tn, out_t[:n], out_vel[:n]

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


# --------------------------------------------------------------------------------------------------
# result
# --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Segment:
    t: float
    basis: int
    q: np.ndarray
    v: np.ndarray
    entry: str  # 'start', 'impact', 'chatter', 'touch', 'release'
    frozen: object = None  # the free state (q, 0) frozen at a chatter jump; a window's WaveImpact


_ENTRIES = ("start", "impact", "chatter", "touch", "release")


class _Segments:
    """The pieces of closed-form motion of a run, stored as arrays (one row per piece); indexing
    gives a :class:`_Segment`."""

    def __init__(self, n_modes, t, basis, entry, q, v, frozen):
        self.n_modes = n_modes
        self.t = t
        self.basis = basis
        self.entry = entry
        self.q = q
        self.v = v
        self.frozen = frozen

    def __len__(self) -> int:
        return self.t.size

    def __getitem__(self, j) -> _Segment:
        j = range(len(self))[j]
        b = int(self.basis[j])
        m = self.n_modes if b == _CONTACT else self.n_modes + 1
        return _Segment(float(self.t[j]), b, self.q[j, :m], self.v[j, :m],
                        _ENTRIES[self.entry[j]], self.frozen.get(j))


class _SegmentLog:
    """Builds :class:`_Segments` in arrays grown in place (``realloc``, by an eighth at least): the
    kernel writes each block of impacts straight into the next rows (:meth:`impact_rows`), so a
    long run holds its trajectory once, not once per block and again when joined."""

    def __init__(self, n_modes, capacity=0):
        self.M = n_modes + 1
        self.frozen = {}
        self.count = 0
        self.t = np.empty(capacity)
        self.basis = np.empty(capacity, dtype=np.int8)
        self.entry = np.empty(capacity, dtype=np.int8)
        self.q = np.empty((capacity, self.M))
        self.v = np.empty((capacity, self.M))

    def _reserve(self, k):
        """Room for ``k`` more rows. The arrays are resized in place: no view of them may be
        alive across this call (the kernel's views from :meth:`impact_rows` are dropped first)."""
        need = self.count + k
        cap = self.t.size
        if need <= cap:
            return
        cap = max(need, cap + cap // 8, 16)
        for a in (self.t, self.basis, self.entry):
            a.resize((cap,), refcheck=False)
        for a in (self.q, self.v):
            a.resize((cap, self.M), refcheck=False)

    def add(self, t, basis, q, v, entry, frozen=None):
        self._reserve(1)
        i = self.count
        self.t[i] = t
        self.basis[i] = basis
        self.entry[i] = _ENTRIES.index(entry)
        if q.size < self.M:  # a contact state, one coordinate short
            self.q[i, q.size:] = 0.0
            self.v[i, v.size:] = 0.0
        self.q[i, :q.size] = q
        self.v[i, :v.size] = v
        if frozen is not None:
            self.frozen[self.count] = frozen
        self.count += 1

    def impact_rows(self, k):
        """Views of the next ``k`` rows of ``q`` and ``v`` for the kernel to write impacts into;
        :meth:`add_impacts` then counts the rows written."""
        self._reserve(k)
        return self.q[self.count:self.count + k], self.v[self.count:self.count + k]

    def add_impacts(self, ts):
        k = ts.size
        i = self.count
        self.t[i:i + k] = ts
        self.basis[i:i + k] = 0
        self.entry[i:i + k] = 1
        self.count += k

    def truncate(self, count):
        """Drop the pieces from index ``count`` on."""
        self.count = min(self.count, count)
        # the keys were added in increasing order: drop from the end (linear over a run, where a
        # rescan of every stored chatter state on each undone release made long runs quadratic)
        while self.frozen and next(reversed(self.frozen)) >= count:
            self.frozen.popitem()

    def last(self) -> _Segment:
        i = self.count - 1
        bb = int(self.basis[i])
        m = self.M - 1 if bb == _CONTACT else self.M
        return _Segment(float(self.t[i]), bb, self.q[i, :m].copy(), self.v[i, :m].copy(),
                        _ENTRIES[self.entry[i]], self.frozen.get(i))

    def finish(self) -> _Segments:
        """The pieces, in arrays shrunk in place to their length."""
        n = self.count
        if n != self.t.size:
            for a in (self.t, self.basis, self.entry):
                a.resize((n,), refcheck=False)
            for a in (self.q, self.v):
                a.resize((n, self.M), refcheck=False)
        return _Segments(self.M - 1, self.t, self.basis, self.entry, self.q, self.v, dict(self.frozen))


@dataclass(frozen=True, eq=False)
class Trajectory:
    """The result of :func:`simulate`.

    Attributes
    ----------
    model : BarModel
    load : Load
    t0, t_end : float
        Start and end of the run (``t_end`` is the time of the last impact when the run stopped at
        ``max_impacts``).
    impact_times : numpy.ndarray, shape (I,)
        Times of the impacts (load frame, dimensionless); under the wave law the starts of the
        contact windows (each lasts ``2/s``; see :attr:`impacts`).
    impact_velocities : numpy.ndarray, shape (I,)
        Velocity ``u_t(1, t-)`` of the struck end just before each impact, ``> 0``.
    contact_intervals : numpy.ndarray, shape (m, 2)
        Start and end of each interval of permanent contact (the end is ``t_end`` while still in
        contact).
    final_state : InitialState
        Free-free modal state at ``t_end`` (projected from the fixed-free basis when in contact).
    status : str
        Why the run stopped: ``"t_end"`` or ``"max_impacts"``.
    energy : EnergyAccount
        The energy balance of the run (computed on first access).
    n_release_retries : int
        Releases undone because the free motion pressed straight back onto the stop (within
        ``MICRO_FLIGHT``): the truncated free-free and fixed-free bases disagreed on the sign of
        the reaction; the contact was then prolonged by a growing dwell (from ``1e-9``, fourfold
        each time, at most ``1e-2``).

    Methods ``end_displacement(t)``, ``end_velocity(t)``, ``displacement(x, t)`` and
    ``modal_state(t)`` evaluate the closed-form motion at any times in ``[t0, t_end]``.
    """

    model: BarModel
    load: Load
    t0: float
    t_end: float
    impact_times: np.ndarray
    impact_velocities: np.ndarray
    contact_intervals: np.ndarray
    final_state: InitialState
    status: str
    _core: _Core = field(repr=False)
    _segments: _Segments = field(repr=False)
    n_release_retries: int = 0

    @property
    def n_impacts(self) -> int:
        return int(self.impact_times.size)

    @property
    def in_contact_at_end(self) -> bool:
        return bool(self.contact_intervals.size and self.contact_intervals[-1, 1] == self.t_end
                    and self._segments[-1].basis == _CONTACT)

    def _check_times(self, t) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if t.ndim != 1 or not np.all(np.isfinite(t)):
            raise ValueError("t must be a finite 1-d array of times")
        if np.any(t < self.t0) or np.any(t > self.t_end):
            raise ValueError(f"t must lie in [t0, t_end] = [{self.t0}, {self.t_end}]")
        return t

    def _modal(self, t):
        """Yield ``(mask, basis, q, v)`` with the modal states at the times ``t``."""
        segs = self._segments
        starts = segs.t
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)
        chatter = _ENTRIES.index("chatter")
        for j in np.unique(idx):
            sel = idx == j
            s = segs[j]
            if s.basis == _WAVE:  # inside a contact window: the characteristics solution
                states = [s.frozen.state_at(min(tt - s.t, s.frozen.duration)) for tt in t[sel]]
                yield sel, _FREE, np.array([a for a, _ in states]).T, np.array([b for _, b in states]).T
                continue
            q, v = self._core.propagate(s.basis, s.t, s.q, s.v, t[sel])
            if s.basis == _FREE and j + 1 < len(segs) and segs.entry[j + 1] == chatter:
                # the bounces up to the chatter's accumulation point were skipped (each lower
                # than the last, all below the search's resolution): the flight from the last
                # impact would pass through the stop after its first bounce, so the end is held
                # at the stop there by a rigid shift (the deformation is unchanged)
                c = self._core.c
                over = np.maximum(c @ q, 0.0)
                q[0] -= over
                v[0] -= np.where(over > 0.0, c @ v, 0.0)
            yield sel, s.basis, q, v

    @property
    def impacts(self) -> tuple:
        """Under the wave law, the contact of each impact (:class:`~impactbar.WaveImpact`: force
        wave, rod energy, peak stresses, efficiency, advance of the rod end), in order; empty under
        the paper's law."""
        segs = self._segments
        return tuple(segs.frozen[j].resolve() for j in np.flatnonzero(segs.basis == _WAVE))

    def end_displacement(self, t) -> np.ndarray:
        """``u(1, t)``, the struck end, ``<= 0``: a positive value within the rounding noise of the
        closed form (``1e-14 sum |c_n| (|q_n| + |q_pn|)``, the event search's own tolerance) is
        reported as 0, and so is the end during the bounces skipped at a chatter jump.

        Parameters
        ----------
        t : array_like, shape (T,)
            Times in ``[t0, t_end]``.

        Returns
        -------
        numpy.ndarray, shape (T,)
        """
        return self._end(t, velocity=False)

    def end_velocity(self, t) -> np.ndarray:
        """``u_t(1, t)``, shape (T,) (right limit at an impact)."""
        return self._end(t, velocity=True)

    def _end(self, t, velocity):
        """``u(1, t)`` or ``u_t(1, t)``: ``c . q`` (or ``c . q'``) in flight, 0 in contact."""
        scalar = np.ndim(t) == 0
        t = self._check_times(t)
        out = np.zeros(t.size)
        c = self._core.c
        for sel, basis, q, v in self._modal(t):
            if basis != _FREE:
                continue
            if velocity:
                out[sel] = c @ v
            else:
                # a positive value within the rounding noise of the closed form (the event
                # search's own tolerance, 1e-14 sum |c_n| (|q_n| + |q_pn|)) is no penetration:
                # reported as 0
                u = c @ q
                noise = 1e-14 * (np.abs(c) @ (np.abs(q) + self._core.free.qpb[:, None]))
                out[sel] = np.where((u > 0.0) & (u <= noise), 0.0, u)
        return out[0] if scalar else out

    def displacement(self, x, t) -> np.ndarray:
        """``u(x, t)`` on a grid.

        Parameters
        ----------
        x : array_like, shape (X,)
            Positions in ``[0, 1]``.
        t : array_like, shape (T,)
            Times in ``[t0, t_end]``.

        Returns
        -------
        numpy.ndarray, shape (T, X)
        """
        x = np.atleast_1d(np.asarray(x, dtype=float))
        phi_free = self.model.shape_functions(x)  # (X, N+1)
        phi_contact = 2.0 * np.cos(np.outer(x, self._core.mu))  # (X, N)
        t = self._check_times(t)
        out = np.zeros((t.size, x.size))
        for sel, basis, q, _ in self._modal(t):
            out[sel] = (phi_free @ q).T if basis == _FREE else (phi_contact @ q).T
        return out

    def modal_state(self, t):
        """Free-free modal state ``(q, v)`` at times ``t``, shape ``(N + 1, T)`` each (projected
        from the fixed-free basis while in contact)."""
        t = self._check_times(t)
        Q = np.zeros((self.model.n_modes + 1, t.size))
        V = np.zeros_like(Q)
        for sel, basis, q, v in self._modal(t):
            if basis == _FREE:
                Q[:, sel], V[:, sel] = q, v
            elif self.model.n_modes:
                Q[:, sel], V[:, sel] = self._core.to_free @ q, self._core.to_free @ v
        return Q, V

    @cached_property
    def energy(self) -> EnergyAccount:
        """The energy account of the run (:class:`EnergyAccount`), computed on first access by
        Gauss-Legendre quadrature of the closed-form motion on every segment.

        Raises
        ------
        ValueError
            If the quadrature would take more than ``MAX_ENERGY_WORK`` (3e8) node-modes; the work
            grows as ``s * n_modes^2 * (t_end - t0)``.
        """
        return _energy_account(self)

    def to_dataframe(self):
        """The impacts of the run as a table.

        Returns
        -------
        pandas.DataFrame
            Index ``impact`` (0, 1, ...), columns ``time`` (load frame) and ``velocity`` (of the
            struck end just before the impact), dimensionless (eq. 2); ``attrs`` holds the model,
            the load, ``t0``, ``t_end``, ``status``, the contact intervals and each column's
            ``long_name`` and ``units``.
        """
        return _tables.frame(
            {"impact": np.arange(self.n_impacts), "time": self.impact_times,
             "velocity": self.impact_velocities},
            {"impact": ("impact number", "1"), "time": ("time of the impact (load frame)", "1"),
             "velocity": ("velocity u_t(1, t-) of the struck end before the impact", "1")},
            index="impact",
            attrs={"model": repr(self.model), "load": repr(self.load), "t0": self.t0,
                   "t_end": self.t_end, "status": self.status,
                   "contact_intervals": self.contact_intervals.tolist()})

    def to_xarray(self, n: int = 0):
        """The run as an ``xarray.Dataset``: the impacts, and the struck end's motion sampled.

        Parameters
        ----------
        n : int, optional
            Also sample ``end_displacement`` and ``end_velocity`` at ``n`` equally spaced times in
            ``[t0, t_end]`` (dimension ``t``). Default 0: impacts only.

        Returns
        -------
        xarray.Dataset
            ``impact_time`` and ``impact_velocity`` along ``impact``; with ``n``, the sampled end
            motion along ``t``; every variable with ``long_name`` and ``units``.

        Raises
        ------
        ModuleNotFoundError
            xarray is not installed (extra ``data``).
        """
        n = int(n)
        if n < 0:
            raise ValueError(f"n must be an integer >= 0; got {n}")
        ds = _tables.to_xarray(self.to_dataframe()).rename(
            {"time": "impact_time", "velocity": "impact_velocity"})
        ds.attrs.pop("contact_intervals", None)
        if n:
            t = np.linspace(self.t0, self.t_end, n)
            end = _tables.to_xarray(_tables.frame(
                {"t": t, "end_displacement": self.end_displacement(t),
                 "end_velocity": self.end_velocity(t)},
                {"t": ("time (load frame)", "1"),
                 "end_displacement": ("displacement u(1, t) of the struck end", "1"),
                 "end_velocity": ("velocity u_t(1, t) of the struck end", "1")}, index="t"))
            for name in ("end_displacement", "end_velocity"):
                ds[name] = end[name]
        return ds


# --------------------------------------------------------------------------------------------------
# energy account by quadrature
# --------------------------------------------------------------------------------------------------
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)


def _segment_integrals(core: _Core, seg: _Segment, tb: float):
    """Work, damping loss and the end state of one segment ``[seg.t, tb]``."""
    ta = seg.t
    if seg.basis == _CONTACT and core.N == 0:
        return 0.0, 0.0, seg.q, seg.v
    w2 = core.free.w2 if seg.basis == _FREE else core.contact.w2
    if tb <= ta:
        return 0.0, 0.0, seg.q, seg.v
    edges = [ta, tb]
    if core.data.kind == 1:
        m0, m1 = math.floor(ta / TWO_PI), math.floor(tb / TWO_PI)
        per = (np.arange(m0, m1 + 1)[:, None] * TWO_PI + core.data.breaks[None, :]).ravel()
        edges = np.concatenate(([ta], per[(per > ta) & (per < tb)], [tb]))
    wmax = math.sqrt(float(np.max(w2))) if w2.size else 0.0
    kmax = float(np.max(core.data.ks)) if core.data.ks.size else 0.0
    hmax = 1.5 / (wmax + kmax + 1.0)
    nodes, weights = [], []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        n = max(1, math.ceil((b - a) / hmax))
        e = np.linspace(a, b, n + 1)
        half = 0.5 * (e[1:] - e[:-1])
        nodes.append((half[:, None] * (_GL_X[None, :] + 1.0) + e[:-1, None]).ravel())
        weights.append((half[:, None] * _GL_W[None, :]).ravel())
    nodes = np.concatenate(nodes)
    weights = np.concatenate(weights)
    work = 0.0
    damp = 0.0
    chunk = max(64, 2_000_000 // (core.N + 1))  # bounded memory: chunk x modes states at a time
    if seg.basis == _FREE:
        kap = core.kappa
    else:
        kap = np.full(core.N, 2.0)
    for i in range(0, nodes.size, chunk):
        tt = nodes[i:i + chunk]
        _, v = core.propagate(seg.basis, ta, seg.q, seg.v, tt)
        ut0 = kap @ v  # u_t(0, t): v0 + 2 sum v_n, or 2 sum r_m'
        work += float(np.sum(weights[i:i + chunk] * core.load(tt) * ut0))
        if core.d:
            damp += core.d * float(np.sum(weights[i:i + chunk] * (kap @ (v * v))))
    qe, ve = core.propagate(seg.basis, ta, seg.q, seg.v, [tb])
    return work, damp, qe[:, 0], ve[:, 0]


def _energy_nodes(core: _Core, span: float, n_segments: int) -> float:
    """An upper bound of the quadrature nodes :func:`_segment_integrals` uses over a run."""
    w2 = np.concatenate((core.free.w2, core.contact.w2))
    wmax = math.sqrt(float(np.max(w2))) if w2.size else 0.0
    kmax = float(np.max(core.data.ks)) if core.data.ks.size else 0.0
    jumps = core.data.breaks.size * (span / TWO_PI + 1.0) if core.data.kind == 1 else 0.0
    return _GL_X.size * (span * (wmax + kmax + 1.0) / 1.5 + n_segments + jumps)


def _energy_account(tr: Trajectory) -> EnergyAccount:
    core = tr._core
    segs = tr._segments
    work = _energy_nodes(core, tr.t_end - tr.t0, len(segs)) * (core.N + 1)
    if work > MAX_ENERGY_WORK:
        raise ValueError(
            f"energy: the quadrature would take about {work:.3g} node-modes (at most "
            f"{MAX_ENERGY_WORK:.0e}); it grows with s * n_modes^2 * (t_end - t0): use a shorter run, "
            f"fewer modes or a smaller s (here s = {tr.model.s:g}, n_modes = {tr.model.n_modes})"
        )
    work = damp = imp = chat = proj = 0.0
    first = segs[0]
    initial = core.energy(first.basis, first.q, first.v)
    final = initial
    for j, seg in enumerate(segs):
        tb = segs[j + 1].t if j + 1 < len(segs) else tr.t_end
        if seg.basis == _WAVE:  # a contact window: drive work, rod energy, projection
            window = seg.frozen
            dt = min(tb - seg.t, window.duration)
            w, rod, field_energy = window.account(dt)
            if dt >= window.duration:
                qe, ve = window.q_after, window.v_after
            else:
                qe, ve = window.state_at(dt)
            work += w
            imp += rod
            proj += core.energy(_FREE, qe, ve) - field_energy
            if j + 1 == len(segs):
                final = core.energy(_FREE, qe, ve)
            continue
        w, dl, qe, ve = _segment_integrals(core, seg, tb)
        work += w
        damp += dl
        if j + 1 < len(segs):
            nxt = segs[j + 1]
            if nxt.entry == "impact" and nxt.basis == _WAVE:
                pass  # the window's own account; its start only shifts the mean displacement
            elif nxt.entry == "impact":
                imp += (1.0 - core.R**2) * core.kinetic(ve)
            elif nxt.entry == "chatter":
                frozen = nxt.frozen
                e_frozen = core.energy(_FREE, frozen, np.zeros_like(frozen))
                chat += core.energy(_FREE, qe, ve) - e_frozen
                proj += core.energy(_CONTACT, nxt.q, nxt.v) - e_frozen
            elif nxt.entry in ("touch", "release"):
                proj += core.energy(nxt.basis, nxt.q, nxt.v) - core.energy(seg.basis, qe, ve)
        else:
            final = core.energy(seg.basis, qe, ve)
    return EnergyAccount(work=work, initial=initial, final=final, damping_loss=damp,
                         impact_loss=imp, chatter_loss=chat, projection=proj)


# --------------------------------------------------------------------------------------------------
# the driver
# --------------------------------------------------------------------------------------------------
def simulate(model: BarModel, load: Load, initial: InitialState, t_end, *, t0=0.0,
             max_impacts=None) -> Trajectory:
    r"""Follow the bar from ``initial`` through impact after impact (paper Section 5).

    Between impacts every mode obeys ``q_n'' + d q_n' + (s n pi)^2 q_n = p(t)`` (eq. 6) and is
    advanced in closed form; at an impact (``u(1,t) = 0``, ``u_t(1,t) > 0``)
    ``u_t(x, t+) = -R u_t(x, t-)`` (eqs. 10, 11). Chatter is jumped over to its accumulation point,
    after which the bar stays on the stop (fixed at ``x = 1``, theory §8) until the stop's
    reaction would turn tensile.

    Parameters
    ----------
    model : BarModel
        The bar: ``s``, ``d``, ``R`` and ``N`` flexible modes.
    load : FourierLoad or PiecewiseConstantLoad
        The load at ``x = 0``, evaluated at absolute time (an impact at ``t`` has load phase
        ``t mod 2 pi``).
    initial : InitialState
        Free-free modal state at ``t0``, ``N + 1`` modes (a one-mode state is padded with zeros).
    t_end : float
        End of the run (dimensionless time), ``t0 < t_end <= t0 + 1e8`` and ``|t_end| <= 1e8``
        (``MAX_TIME``: beyond, impact times are not resolved in double precision, and the run would
        not end in bounded time).
    t0 : float, optional
        Start time, ``|t0| <= 1e8``. Default 0.
    max_impacts : int, optional
        Stop at this many impacts (``>= 1``); ``t_end`` of the result is then the last impact (under
        the wave law the end of its contact window).

    Returns
    -------
    Trajectory

    Raises
    ------
    ValueError
        On a bad parameter (named in the message), a start that penetrates the stop
        (``u(1, t0) > 0``), an undamped resonance between a mode and a load harmonic, or a bar too
        stiff for the guaranteed event search, ``s * n_modes > 1e5`` (``MAX_SIMULATE_STIFFNESS``: the
        search steps on the scale of the stiffest mode's period).
    """
    if not isinstance(model, BarModel):
        raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
    if not isinstance(initial, InitialState):
        raise ValueError(f"initial must be an InitialState; got {type(initial).__name__}")
    # beyond |t| = 1e8 an impact time is resolved to worse than 1e-8 in double precision, and a run
    # of that many periods does not finish in bounded time: refused
    t0 = check_real("t0", t0, lo=-MAX_TIME, hi=MAX_TIME)
    t_end = check_real("t_end", t_end, lo=t0, hi=t0 + MAX_TIME, lo_open=True)
    if abs(t_end) > MAX_TIME:
        raise ValueError(f"t_end must be in [-{MAX_TIME:g}, {MAX_TIME:g}]; got {t_end}")
    if max_impacts is None:
        max_imp = np.iinfo(np.int64).max
    else:
        max_imp = check_int("max_impacts", max_impacts, lo=1)
    N = model.n_modes
    if N and model.s * N > MAX_SIMULATE_STIFFNESS:
        raise ValueError(
            f"model: s * n_modes must be at most {MAX_SIMULATE_STIFFNESS:g} for simulate (the event search "
            f"resolves the stiffest mode, frequency s n_modes pi); got s = {model.s:g}, "
            f"n_modes = {N}: use fewer modes (a stiff bar moves as a rigid one, n_modes = 0)"
        )
    q = np.array(initial.modal_displacement, dtype=float)
    v = np.array(initial.modal_velocity, dtype=float)
    if q.size == 1 and N > 0:
        q = np.concatenate((q, np.zeros(N)))
        v = np.concatenate((v, np.zeros(N)))
    if q.size != N + 1:
        raise ValueError(
            f"initial must have n_modes + 1 = {N + 1} modal coordinates; got {q.size}"
        )
    core = _core_for(model, load)
    g = float(core.c @ q)
    if g > 0.0 and g > 1e-12 * max(1.0, float(np.sum(np.abs(core.c * q)))):
        raise ValueError(f"initial penetrates the stop: u(1, t0) = {g:.3e} > 0")
    if g > 0.0:
        q[0] -= g
    if model.impact == "wave":
        return _run_wave(core, q, v, t0, t_end, max_imp)
    return _run(core, q, v, t0, t_end, max_imp)


def _run(core: _Core, q, v, t0, t_end, max_imp) -> Trajectory:
    segs = _SegmentLog(core.N, min(max_imp, 1024) + 1)  # a short run's pieces without a resize
    segs.add(t0, _FREE, q, v, "start")
    times: list[np.ndarray] = []
    vels: list[np.ndarray] = []
    contacts: list[list[float]] = []
    n_imp = 0
    t = t0
    mode = _FREE
    status = "t_end"
    dwell = 0.0
    retries = 0
    last_release = None  # (time, contact segment index, len(times), n_imp) for undoing
    cap = 1024
    while True:
        if mode == _FREE:
            left = max_imp - n_imp
            if left <= 0:  # pragma: no cover - run_free stops at max_imp itself
                status = "max_impacts"
                break
            # the kernel writes into the log's next rows; at most an eighth more than the log
            # holds, so the run's peak memory stays near its stored trajectory
            oq, ovv = segs.impact_rows(min(cap, left, max(1024, segs.count // 8)))
            n, st, tn, ot, ov = core.run_free(t, q, v, t_end, left, oq, ovv)
            del oq, ovv  # no view of the log may outlive the call (it is resized in place)
            cap = min(cap * 2, 1 << 16)
            if n:  # (views of the kernel's fresh output, copied where it is mostly unused)
                times.append(ot if 2 * n >= ot.base.size else ot.copy())
                vels.append(ov if 2 * n >= ov.base.size else ov.copy())
                segs.add_impacts(ot)
                n_imp += n
            if st == K.FAILED:  # pragma: no cover - defensive
                raise ValueError(f"impact search did not converge at t = {tn}: the model is too "
                                 f"stiff for the event search (s = {core.model.s:g}, n_modes = "
                                 f"{core.N}); use fewer modes")
            if st == K.END:
                t = t_end
                break
            if st == K.MAXIMP:
                t = tn
                status = "max_impacts"
                break
            if st == K.FULL:
                t = tn
                continue
            # CHATTER or CONTACT: the end stays on the stop from tn
            micro = last_release is not None and tn - last_release[0] <= MICRO_FLIGHT
            if micro:
                # the free motion presses straight back (at once, or after a few bounces too
                # small to matter): the bases disagree on the sign of the reaction here. Undo
                # the release and stay in contact a little longer (fourfold) before asking again.
                t_rel, seg_index, k_times, n_saved = last_release
                segs.truncate(seg_index + 1)
                del times[k_times:]
                del vels[k_times:]
                n_imp = n_saved
                contacts[-1][1] = math.nan
                dwell = min(max(4.0 * dwell, DWELL_START), DWELL_MAX)
                retries += 1
                cseg = segs.last()
                t = t_rel
                mode = _CONTACT
                r, rv = _contact_at(core, cseg, t_rel + dwell, t_end)
                if r is None:
                    contacts[-1][1] = t_end
                    t = t_end
                    break
                t = t_rel + dwell
                last_release = None
            else:
                dwell = 0.0
                if st == K.CHATTER:
                    frozen = q.copy()
                    r, rv = core.contact_state(q, np.zeros_like(v))
                    t = min(tn, t_end)
                    segs.add(t, _CONTACT, r, rv, "chatter", frozen)
                else:
                    r, rv = core.contact_state(q, v)
                    t = tn
                    segs.add(t, _CONTACT, r, rv, "touch")
                contacts.append([t, math.nan])
                mode = _CONTACT
                if t >= t_end:
                    contacts[-1][1] = t_end
                    break
        # ---- in contact: from (t, r, rv) find the release ----
        st, tr, rr, rrv = core.find_release(t, r, rv, t_end)
        if st == K.FAIL:  # pragma: no cover - defensive
            raise ValueError(f"release search did not converge at t = {tr}: the model is too "
                             f"stiff for the event search (s = {core.model.s:g}, n_modes = "
                             f"{core.N}); use fewer modes")
        if st == K.NONE:
            contacts[-1][1] = t_end
            t = t_end
            break
        contacts[-1][1] = tr
        q, v = core.release_state(rr, rrv)
        last_release = (tr, segs.count - 1, len(times), n_imp)
        segs.add(tr, _FREE, q, v, "release")
        t = tr
        mode = _FREE
    # ---- final state ----
    i = segs.count - 1
    if t == segs.t[i] and segs.basis[i] == _FREE:  # the run ended on a piece's start (max_impacts)
        qe, ve = segs.q[i].copy(), segs.v[i].copy()
        last = None
    else:
        last = segs.last()
        qe, ve = core.propagate(last.basis, last.t, last.q, last.v, [t])
        qe, ve = qe[:, 0], ve[:, 0]
        if last.basis == _CONTACT:
            qe, ve = core.release_state(qe, ve)
    imp_t = _joined(times)
    imp_v = _joined(vels)
    ci = np.array(contacts, dtype=float).reshape(-1, 2)
    return Trajectory(model=core.model, load=core.load, t0=t0, t_end=t,
                      impact_times=imp_t, impact_velocities=imp_v, contact_intervals=ci,
                      final_state=InitialState._trusted(qe, ve), status=status, _core=core,
                      _segments=segs.finish(), n_release_retries=retries)


def _joined(blocks: list) -> np.ndarray:
    """The blocks of a run's impact data as one array (the block itself when there is one)."""
    if len(blocks) == 1:
        return blocks[0]
    return np.concatenate(blocks) if blocks else np.zeros(0)


def _contact_at(core: _Core, seg: _Segment, t: float, t_end: float):
    """Contact state at ``t`` on the contact segment ``seg`` (None when ``t >= t_end``)."""
    if t >= t_end:
        return None, None
    r, rv = core.propagate(_CONTACT, seg.t, seg.q, seg.v, [t])
    return r[:, 0], rv[:, 0]


def _run_wave(core: _Core, q, v, t0, t_end, max_imp) -> Trajectory:
    """The driver under the wave law (theory §4b): each flight by the compiled kernel up to the next
    arrival at the rod end, each contact by :func:`wave_impact` over its window ``2/s``; positions
    stay measured from the rod end, which every blow advances."""
    model = core.model
    window = 2.0 / model.s
    c = core.c
    D = core.data
    ks = D.ks
    rate = float(np.max(ks)) / model.s if D.kind == 0 and ks.size else 0.0
    segs = _SegmentLog(core.N)
    segs.add(t0, _FREE, q, v, "start")
    times: list[float] = []
    vels: list[float] = []
    t = t0
    status = "t_end"
    oq, ov = np.empty((1, q.size)), np.empty((1, q.size))  # the kernel's state after its one impact
    contact = np.empty((WK.MAX_INTERVALS, 2))  # the contact intervals of a separating window
    while True:
        qa, va = q.copy(), v.copy()
        n, st, tn, ot, _ = core.run_free(t, q, v, t_end, 1, oq, ov)
        if st == K.FAILED:  # pragma: no cover - defensive
            raise RuntimeError(f"impact search did not converge at t = {tn}")
        if st == K.END:
            t = t_end
            break
        # an impact (MAXIMP after one), or a touch at zero speed (CONTACT): a contact window
        ti = float(ot[0]) if n else float(tn)
        if n and core.R >= 0.01:  # the kernel's state after eq. 10's reversal, undone
            qm, vm = oq[0].copy(), ov[0] / -core.R
        else:
            qm, vm = (a[:, 0] for a in core.propagate(_FREE, t, qa, va, [ti]))
        qm[0] -= float(c @ qm)  # the end exactly on the rod end
        arrival = float(c @ vm)
        if arrival < 0.0:  # a touch whose speed rounded below zero
            vm[0] -= arrival
            arrival = 0.0
        q, v = np.empty_like(qm), np.empty_like(vm)
        if K.wave_window(tuple(D), model.s, model.R, c, rate, ti, qm, vm, _GL20_X, _GL20_W, q, v):
            imp = _Window(model, core.load, ti, qm, vm, q.copy(), v.copy())  # solved when asked
        elif use_fast("simulate.wave_separation") and WK.wave_contact(
                tuple(D), model.s, model.R, rate, ti, qm, vm, _GL20_X, _GL20_W, q, v, contact) >= 0:
            # contact lost inside the window
            imp = _Window(model, core.load, ti, qm, vm, q.copy(), v.copy())
        else:  # the full characteristics solution in Python
            imp = wave_impact(model, core.load, ti, qm, vm)
            q, v = imp.q_after.copy(), imp.v_after.copy()
        times.append(ti)
        vels.append(arrival)
        segs.add(ti, _WAVE, qm, vm, "impact", imp)
        t = ti + window
        if t >= t_end:  # the run ends inside the window
            t = t_end
            break
        segs.add(t, _FREE, q, v, "release")
        if len(times) >= max_imp:
            status = "max_impacts"
            break
    last = segs.last()
    if last.basis == _WAVE:
        qe, ve = last.frozen.state_at(min(t - last.t, last.frozen.duration))
    else:
        qe, ve = (a[:, 0] for a in core.propagate(_FREE, last.t, last.q, last.v, [t]))
    return Trajectory(model=model, load=core.load, t0=t0, t_end=t,
                      impact_times=np.array(times), impact_velocities=np.array(vels),
                      contact_intervals=np.zeros((0, 2)), final_state=InitialState(qe, ve),
                      status=status, _core=core, _segments=segs.finish())


_GL20_X, _GL20_W = np.polynomial.legendre.leggauss(20)


class _Window:
    """A contact window the compiled kernel found without separation: its post-contact state is
    known; the full :class:`~impactbar.WaveImpact` (force wave, energies) is solved on first use."""

    def __init__(self, model, load, t0, q, v, q_after, v_after):
        self._args = (model, load, t0, q, v)
        self._impact = None
        self.duration = 2.0 / model.s
        self.q_after, self.v_after = q_after, v_after

    def resolve(self):
        if self._impact is None:
            self._impact = wave_impact(*self._args)
        return self._impact

    def __getattr__(self, name):
        return getattr(self.resolve(), name)
