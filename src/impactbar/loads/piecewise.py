"""Loads constant on pieces of the period (paper eq. 34): :class:`PiecewiseConstantLoad`,
:class:`SquareWaveLoad`, integrated exactly piece by piece."""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from .._shared.schema import Field, Schema
from .._shared.validate import check_int, check_real
from ..dynamics.compiled_views import PIECEWISE, LoadKernelView
from ..dynamics.implementations import use_fast
from ..dynamics.modal import b_integral, c_integral, step_constant
from .abilities import LoadAbilities, LoadKernel, LoadTraits
from .base import TWO_PI, Load, _readonly

__all__ = ["PiecewiseConstantLoad", "SquareWaveLoad"]


class PiecewiseConstantLoad(Load):
    """A load constant on each of several pieces of the period; its modal response is integrated
    exactly piece by piece (no Fourier truncation).

    Parameters
    ----------
    breaks : array_like, shape (J,)
        Start times of the pieces in ``[0, 2 pi)``, strictly increasing, ``breaks[0] == 0``.
    levels : array_like, shape (J,)
        Load on each piece (dimensionless).

    Raises
    ------
    ValueError
        If the breaks are not increasing in ``[0, 2 pi)`` starting at 0, or a level is not finite.

    Examples
    --------
    >>> import numpy as np
    >>> from impactbar import PiecewiseConstantLoad
    >>> load = PiecewiseConstantLoad(breaks=[0.0, 2.0], levels=[1.0, -0.5])
    >>> load(np.array([1.0, 3.0]))
    array([ 1. , -0.5])
    >>> round(load.p0, 6)  # the mean, (2 - 0.5 (2 pi - 2)) / (2 pi)
    -0.022535
    """

    traits = LoadTraits(
        kind="piecewise", description="constant on pieces of the period",
        parameters=Schema(Field("breaks", "start times of the pieces in [0, 2 pi)", per="piece"),
                          Field("levels", "load on each piece", per="piece")))

    def __init__(self, breaks, levels):
        try:
            b = np.asarray(breaks, dtype=float).ravel()
            lv = np.asarray(levels, dtype=float).ravel()
        except (TypeError, ValueError, OverflowError) as exc:
            raise ValueError(f"breaks and levels must be 1-d sequences of real numbers; got "
                             f"{breaks!r}, {levels!r}") from exc
        if b.size == 0 or b.size != lv.size:
            raise ValueError("breaks and levels must be non-empty and of equal length")
        if not (np.all(np.isfinite(b)) and b[0] == 0.0 and np.all(np.diff(b) > 0) and b[-1] < TWO_PI):
            raise ValueError("breaks must increase strictly in [0, 2 pi) and start at 0")
        if not np.all(np.isfinite(lv)):
            raise ValueError("levels must be finite")
        T = np.diff(np.append(b, TWO_PI))
        with np.errstate(over="ignore", invalid="ignore"):
            p0 = float(np.dot(lv, T) / TWO_PI)
        if not math.isfinite(p0):
            raise ValueError(f"levels must be finite and small enough for their mean over the period to "
                             f"be (|levels| below about 1e307); got a largest of {np.abs(lv).max():g}")
        self._set(_b=_readonly(b), _lv=_readonly(lv), _T=_readonly(T), p0=p0)
        self._setup_rigid()

    def _key(self):
        return (self.p0, self._b.tobytes(), self._lv.tobytes())

    @cached_property
    def kernel_view(self) -> LoadKernelView:
        """The pieces as the compiled kernels read them (kind 1), built once."""
        return LoadKernelView.piecewise(self.p0, self._b, self._lv)

    @property
    def breaks(self) -> np.ndarray:
        """Start times of the pieces, shape ``(J,)``."""
        return self._b.copy()

    @property
    def levels(self) -> np.ndarray:
        """Load on each piece, shape ``(J,)``."""
        return self._lv.copy()

    @cached_property
    def abilities(self) -> LoadAbilities:
        """At most ``J`` one-impact orbits (the rigid velocity of eq. 14 is monotone on each piece,
        at least 2), its pieces and their jumps, its left limits, the compiled kernel
        (:data:`~impactbar.dynamics.compiled_views.PIECEWISE`) and its flow piece by piece."""
        return LoadAbilities(
            max_one_impact_orbits=max(2, self._b.size), square=self._square_form(),
            pieces=(self.breaks, self.levels),
            kernel=LoadKernel.declared(self, PiecewiseConstantLoad, PIECEWISE, self.kernel_view),
            flow=self.flow, left_limit=self.left_limit, jumps=self._boundaries)

    def _square_form(self):
        """``(q, kappa)`` where the load is the square wave of eq. 34, else ``None``."""
        return None

    def _index(self, t, left=False):
        tm = np.mod(np.asarray(t, dtype=float), TWO_PI)
        side = "left" if left else "right"
        idx = np.searchsorted(self._b, tm, side=side) - 1
        return np.where(idx < 0, self._b.size - 1, idx)

    def __call__(self, t):
        return self._lv[self._index(t)]

    def left_limit(self, t):
        return self._lv[self._index(t, left=True)]

    def harmonics(self, n: int | None = None) -> np.ndarray:
        if n is None:
            raise ValueError("n is required: a piecewise-constant load has infinitely many harmonics")
        n = check_int("n", n, lo=0)
        k = np.arange(1, n + 1, dtype=float)
        e0 = np.exp(-1j * np.outer(k, self._b))
        e1 = np.exp(-1j * np.outer(k, np.append(self._b[1:], TWO_PI)))
        # p_k = (1/pi) int p(t) exp(-i k t) dt
        return ((e0 - e1) / (1j * k[:, None]) @ self._lv) / math.pi

    @property
    def sup_abs(self) -> float:
        return float(np.max(np.abs(self._lv)))

    @property
    def sup_oscillation(self) -> float:
        return float(np.max(np.abs(self._lv - self.p0)))

    def variation(self, mid, half):
        mid = np.asarray(mid, dtype=float)
        half = np.asarray(half, dtype=float)
        center = self(mid)
        lo = (mid - half)[..., None]
        hi = (mid + half)[..., None]
        # a jump inside the interval: some break b + 2 pi k in (lo, hi] (counted per break, so a
        # jump just before the period's end is not hidden by the piece index wrapping around)
        b = self._b
        count = np.floor((hi - b) / TWO_PI) - np.floor((lo - b) / TWO_PI)
        jump = np.any(count > 0, axis=-1) | (2 * half >= TWO_PI)
        if b.size == 1:  # a constant load (kappa = 2): no jump at all
            jump = np.zeros_like(jump)
        spread = float(np.max(self._lv) - np.min(self._lv))
        return center, np.where(jump, spread, 0.0)

    def _boundaries(self, t0, t1):
        """Absolute times of the load jumps in ``(t0, t1)``, sorted."""
        n0 = math.floor(t0 / TWO_PI)
        n1 = math.floor(t1 / TWO_PI)
        per = np.arange(n0, n1 + 1)[:, None] * TWO_PI + self._b[None, :]
        per = per.ravel()
        return per[(per > t0) & (per < t1)]

    def propagate(self, w2, d, t0, q0, v0, t):
        w2 = np.asarray(w2, dtype=float)
        t = np.atleast_1d(np.asarray(t, dtype=float))
        M, T = w2.size, t.size
        q = np.empty((M, T))
        v = np.empty((M, T))
        if T == 0:
            return q, v
        if np.any(t < t0 - 1e-12):
            raise ValueError("propagate needs t >= t0")
        t_max = float(np.max(t))
        # the last node is the last time asked for, not beyond it: a piece ending past the next
        # jump would read its level at a midpoint on the far side of that jump
        nodes = np.concatenate(([t0], self._boundaries(t0, t_max), [max(t_max, t0)]))
        # the level of each piece is read at its midpoint: a node itself may round to either side
        levels = self(0.5 * (nodes[:-1] + nodes[1:]))
        qn = np.empty((M, nodes.size - 1))
        vn = np.empty((M, nodes.size - 1))
        qn[:, 0], vn[:, 0] = q0, v0
        for j in range(1, nodes.size - 1):
            qn[:, j], vn[:, j] = step_constant(w2, d, levels[j - 1], qn[:, j - 1], vn[:, j - 1],
                                               nodes[j] - nodes[j - 1])
        j = np.clip(np.searchsorted(nodes, t, side="right") - 1, 0, nodes.size - 2)
        for jj in np.unique(j):
            sel = j == jj
            level = levels[jj]
            q[:, sel], v[:, sel] = step_constant(w2, d, level, qn[:, jj], vn[:, jj],
                                                 np.maximum(t[sel] - nodes[jj], 0.0))
        return q, v

    def flow(self, w2, d, t0, q0, v0, horizon=TWO_PI):
        """Exact flow from one state: the states at the load's jumps in ``[t0, t0 + horizon]`` are
        computed once; each evaluation is then one vectorised constant-load step per time."""
        w2 = np.asarray(w2, dtype=float)
        q0 = np.asarray(q0, dtype=float)
        v0 = np.asarray(v0, dtype=float)
        t_end = t0 + horizon
        nodes = np.concatenate(([t0], self._boundaries(t0, t_end), [t_end]))
        levels = self(0.5 * (nodes[:-1] + nodes[1:]))  # the last piece ends at t_end, not beyond
        qn = np.empty((w2.size, nodes.size - 1))
        vn = np.empty_like(qn)
        qn[:, 0], vn[:, 0] = q0, v0
        for j in range(1, nodes.size - 1):
            qn[:, j], vn[:, j] = step_constant(w2, d, levels[j - 1], qn[:, j - 1], vn[:, j - 1],
                                               nodes[j] - nodes[j - 1])

        compiled = use_fast("loads.flow") and bool(np.all((w2 == 0.0) | (w2 - 0.25 * d * d > 0.0)))
        if compiled:  # flexible modes underdamped (the rule): the compiled step
            from ..dynamics.compiled import piecewise_flow

        def evaluate(t):
            t = np.atleast_1d(np.asarray(t, dtype=float))
            if t.size and float(np.max(t)) > t_end:
                return self.propagate(w2, d, t0, q0, v0, t)
            j = np.clip(np.searchsorted(nodes, t, side="right") - 1, 0, nodes.size - 2)
            if compiled and t.ndim == 1:
                return piecewise_flow(w2, float(d), levels[j], j, np.maximum(t - nodes[j], 0.0), qn, vn)
            return step_constant(w2, d, levels[j], qn[:, j], vn[:, j], np.maximum(t - nodes[j], 0.0))

        if compiled:  # for the compiled admissibility search
            evaluate.pieces = (nodes, levels, qn, vn)
        return evaluate

    def _setup_rigid(self):
        """Start value ``V(0)`` of the periodic zero-mean rigid velocity, per unit damping used."""
        self._set(_rigid_cache={})

    def _rigid_start(self, d):
        if d not in self._rigid_cache:
            alpha = self._lv - self.p0
            E = np.exp(-d * self._b)  # V_j = V_0 E_j + D_j
            D = np.zeros_like(self._b)
            for j in range(1, self._b.size):
                D[j] = D[j - 1] * math.exp(-d * self._T[j - 1]) + alpha[j - 1] * float(
                    b_integral(d, self._T[j - 1]))
            bT = b_integral(d, self._T)
            cT = c_integral(d, self._T)
            # zero mean: sum_j int V = sum_j (V_j b(T_j) + alpha_j c(T_j)) = 0
            v0 = -float(np.sum(D * bT + alpha * cT)) / float(np.sum(E * bT))
            self._rigid_cache[d] = (v0 * E + D, alpha)
            if len(self._rigid_cache) > 64:
                self._rigid_cache.pop(next(iter(self._rigid_cache)))
        return self._rigid_cache[d]

    def rigid_velocity(self, d, t):
        t = np.asarray(t, dtype=float)
        Vj, alpha = self._rigid_start(d)
        tm = np.mod(t, TWO_PI)
        j = self._index(tm)
        tau = tm - self._b[j]
        return Vj[j] * np.exp(-d * tau) + alpha[j] * b_integral(d, tau)


class SquareWaveLoad(PiecewiseConstantLoad):
    r"""Hydraulic-hammer load (eq. 34): a square wave, evaluated exactly.

    .. math:: p(t) = +q \text{ for } t \bmod 2\pi < \kappa\pi, \quad -q \text{ otherwise}

    Its mean is ``p0 = q (kappa - 1)`` and its harmonics
    ``p_k = (2 q / (pi k)) [sin(k kappa pi) + i (cos(k kappa pi) - 1)]``. The load factor is ``kappa``.

    Parameters
    ----------
    q : float
        Level of the square wave (dimensionless), ``q > 0``.
    kappa : float
        Fraction (times ``pi``) of the period at ``+q``, ``1 <= kappa <= 2``.

    Raises
    ------
    ValueError
        If ``q <= 0`` or ``kappa`` is outside ``[1, 2]``.

    Examples
    --------
    >>> import numpy as np
    >>> from impactbar import SquareWaveLoad
    >>> load = SquareWaveLoad(q=1.0, kappa=1.2)
    >>> load(np.array([0.5, 4.0]))
    array([ 1., -1.])
    >>> round(load.p0, 12)
    0.2
    """

    traits = LoadTraits(
        kind="square", description="hydraulic square wave, +q then -q (eq. 34)",
        parameters=Schema(Field("q", "level of the square wave, > 0"),
                          Field("kappa", "fraction of the period at +q times 2, in [1, 2]")),
        continuation_parameters=("q", "kappa"),
        parameter_ranges={"q": {"low": 0.0, "low_open": True}, "kappa": {"low": 1.0, "high": 2.0}})

    def __init__(self, q, kappa):
        q = check_real("q", q, lo=0.0, lo_open=True)
        kappa = check_real("kappa", kappa, lo=1.0, hi=2.0)
        self._set(q=q, kappa=kappa)
        if kappa == 2.0:
            super().__init__([0.0], [q])
        else:
            super().__init__([0.0, kappa * math.pi], [q, -q])
        self._set(p0=q * (kappa - 1.0))  # exact, not the quadrature of the pieces

    @property
    def load_factor(self) -> float:
        """``kappa`` (Section 4 of the paper)."""
        return self.kappa

    def _square_form(self):
        return self.q, self.kappa

    def harmonics(self, n: int | None = None) -> np.ndarray:
        if n is None:
            raise ValueError("n is required: a square wave has infinitely many harmonics")
        n = check_int("n", n, lo=0)
        k = np.arange(1, n + 1, dtype=float)
        a = k * self.kappa * math.pi
        return (2.0 * self.q / (math.pi * k)) * (np.sin(a) + 1j * (np.cos(a) - 1.0))
