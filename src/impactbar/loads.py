"""Periodic loads of period ``2 pi`` at the driven end (theory §3, paper eqs. 7, 33, 34).

A load is ``p(t) = Re sum_{k>=0} p_k exp(i k t)`` in its own time frame; an impact at phase ``phase``
sees ``p(t + phase)`` (eq. 7). Each load also knows the exact motion of a modal oscillator
``q'' + d q' + w2 q = p(t)`` that it drives (eq. 8), which is all the rest of the package needs.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import FrozenInstanceError
from functools import cached_property
from typing import ClassVar

import numpy as np

from ._shared.schema import Field, Schema
from ._shared.validate import check_complex_array, check_int, check_real
from .dynamics.implementations import use_fast
from .dynamics.kernelview import FOURIER, PIECEWISE, LoadKernelView
from .dynamics.modal import b_integral, c_integral, fundamental, step_constant

__all__ = ["Load", "FourierLoad", "CosineLoad", "PiecewiseConstantLoad", "SquareWaveLoad", "LOADS"]

TWO_PI = 2.0 * math.pi



def _readonly(a):
    """A private copy of ``a`` that cannot be written (a frozen load's arrays)."""
    a = np.array(a)
    a.flags.writeable = False
    return a


class Load(ABC):
    """A periodic load of period ``2 pi`` (eq. 7), frozen. Subclasses give the exact modal response.

    A load is immutable: its parameters are validated once by the constructor, and assigning or
    deleting any attribute afterwards raises :class:`dataclasses.FrozenInstanceError` (an
    ``AttributeError``), so that everything computed from a load (the simulator's cached kernel
    data, the compiled flows) stays valid. Loads compare and hash by value.

    What a drive must provide (a new drive, e.g. a position-switched one, implements these):

    - ``p0`` (the mean load) and :meth:`__call__` (the load at given times), :meth:`left_limit` at
      jumps, and :meth:`harmonics` (the complex ``p_k`` of eq. 7);
    - the bounds used by the certified searches: :attr:`sup_abs`, :attr:`sup_oscillation`,
      :meth:`variation`;
    - the exact modal response: :meth:`propagate` (and optionally a faster :meth:`flow`),
      :meth:`rigid_velocity`, :meth:`periodic_state`;
    - :attr:`kernel_view`: the one :class:`~impactbar.dynamics.kernelview.LoadKernelView` the
      compiled code reads (the only path from a load into compiled code), or ``None`` for a drive
      the kernels do not know; the simulator and the compiled searches then need a view, the
      numpy reference paths only the methods above;
    - :meth:`_key`: the values that identify it (equality, hashing, caches).

    What the solvers, sweeps, the SI layer and the CLI ask of a load, declared by each class (a
    load class with a :attr:`kind` is an entry of the table :data:`LOADS`):

    - :attr:`kind`, :attr:`description`, :attr:`parameters` (its constructor's, with long names
      and dtypes) and :attr:`continuation_parameters`; :meth:`to_record`, :meth:`from_record` and
      :meth:`with_` (a copy with parameters changed);
    - :attr:`period` (its fundamental period), :attr:`max_one_impact_orbits` (a bound of the roots
      of the phase equation, eq. 14);
    - the forms a special solver recognises: :meth:`cosine_form` (the rigid closed forms,
      pneumatic), :meth:`square_form` (the rigid closed forms, hydraulic), :meth:`pieces` (the
      jumps of a piecewise-constant load);
    - :attr:`kernel_kind` and :meth:`compiled_kind`: the kind of its kernel view, where compiled
      code may stand for the load's methods.

    Attributes
    ----------
    p0 : float
        Mean load (dimensionless, eq. 2).

    Examples
    --------
    >>> from impactbar import CosineLoad, Load
    >>> isinstance(CosineLoad(0.3, 1.0), Load)
    True
    >>> CosineLoad(0.3, 1.0) == CosineLoad(0.3, 1.0)  # loads compare by value
    True
    """

    p0: float

    #: the load's name in the table :data:`LOADS`: a sweep spec's ``[load] kind``, the CLI's
    #: ``--load``, the ``"kind"`` of :meth:`to_record` (empty for a load not in the table)
    kind: ClassVar[str] = ""
    #: what the load is, in a few words (the CLI's help)
    description: ClassVar[str] = ""
    #: the constructor's parameters, in order, each with its long name and dtype
    parameters: ClassVar[Schema] = Schema()
    #: the parameters a branch of orbits can be continued in (:func:`impactbar.continue_orbit`)
    continuation_parameters: ClassVar[tuple[str, ...]] = ()
    #: the ``kind`` of the :attr:`kernel_view` the class declares (``None``: it declares none)
    kernel_kind: ClassVar[int | None] = None

    # -- frozen, compared by value ------------------------------------------------------------
    def __setattr__(self, name, value):
        raise FrozenInstanceError(f"cannot assign to field {name!r}: {type(self).__name__} is frozen")

    def __delattr__(self, name):
        raise FrozenInstanceError(f"cannot delete field {name!r}: {type(self).__name__} is frozen")

    def _set(self, **fields):
        """Set attributes in the constructor (the only writes a load accepts)."""
        for name, value in fields.items():
            object.__setattr__(self, name, value)

    def _key(self) -> tuple:
        """The parameters that identify the load (its value)."""
        return (id(self),)  # pragma: no cover - every concrete load overrides it

    def __eq__(self, other):
        if other is self:
            return True
        if type(other) is not type(self):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self):
        h = self.__dict__.get("_hash")
        if h is None:
            h = self.__dict__["_hash"] = hash((type(self).__qualname__, self._key()))
        return h

    def __getstate__(self):
        # the cached hash is not carried to another process (hashes of bytes differ between them)
        return {k: v for k, v in self.__dict__.items() if k != "_hash"}

    @property
    def kernel_view(self) -> LoadKernelView | None:
        """The load as compiled code reads it (built once), or ``None`` for a load the kernels do not
        know (the numpy reference paths then evaluate it through its methods)."""
        return None

    # -- evaluation -------------------------------------------------------------------------
    @abstractmethod
    def __call__(self, t) -> np.ndarray:
        """Load ``p(t)`` (right-continuous at jumps).

        Parameters
        ----------
        t : array_like, shape (...)
            Times in the load's frame (dimensionless, period ``2 pi``).

        Returns
        -------
        numpy.ndarray, shape (...)
        """

    def left_limit(self, t) -> np.ndarray:
        """``p(t-)``; equal to ``p(t)`` for a continuous load."""
        return self(t)

    @abstractmethod
    def harmonics(self, n: int | None = None) -> np.ndarray:
        """Complex harmonics ``p_1..p_K`` (eq. 7), shape ``(K,)``; ``n`` truncates or pads
        (required for loads with infinitely many harmonics)."""

    # -- bounds used by the certified root searches -------------------------------------------
    @property
    @abstractmethod
    def sup_abs(self) -> float:
        """An upper bound of ``|p(t)|`` over the period."""

    @property
    @abstractmethod
    def sup_oscillation(self) -> float:
        """An upper bound of ``|p(t) - p0|`` over the period."""

    @abstractmethod
    def variation(self, mid, half):
        """Bound the load on intervals ``[mid - half, mid + half]``.

        Returns ``(center, delta)`` arrays with ``|p(t) - center| <= delta`` on each interval.
        """

    # -- exact modal response -----------------------------------------------------------------
    @abstractmethod
    def propagate(self, w2, d: float, t0: float, q0, v0, t):
        """Exact state of the oscillators ``q'' + d q' + w2 q = p(t)`` at times ``t >= t0``.

        Parameters
        ----------
        w2 : array_like, shape (M,)
            Squared undamped frequencies ``(s n pi)^2`` (0 for the rigid mode).
        d : float
            Damping, ``>= 0``.
        t0 : float
            Start time (load frame).
        q0, v0 : array_like, shape (M,)
            Displacements and velocities at ``t0``.
        t : array_like, shape (T,)
            Times, each ``>= t0``.

        Returns
        -------
        q, v : numpy.ndarray, shape (M, T)

        Raises
        ------
        ValueError
            At an undamped resonance ``w2 = k^2`` of a harmonic the load contains (eq. 16).
        """

    def flow(self, w2, d: float, t0: float, q0, v0):
        """The exact flow from one state, as a callable ``flow(t) -> (q, v)`` of shape ``(M, T)``.

        Equivalent to ``propagate(w2, d, t0, q0, v0, t)``; subclasses precompute what does not depend
        on ``t`` so that repeated evaluations (root searches along one orbit) are cheap.
        """
        w2 = np.asarray(w2, dtype=float)
        q0 = np.asarray(q0, dtype=float)
        v0 = np.asarray(v0, dtype=float)
        return lambda t: self.propagate(w2, d, t0, q0, v0, t)

    @abstractmethod
    def rigid_velocity(self, d: float, t) -> np.ndarray:
        """``V(t)``: the periodic, zero-mean solution of ``V' + d V = p(t) - p0``.

        It equals ``Re sum_{k>=1} H_0k p_k (i k) exp(i k t)`` of eq. 14, so the phase equation is
        ``(1 + R) V(phase) = p0 G(d, R)``.
        """

    def periodic_state(self, w2, d: float, t):
        """The ``2 pi``-periodic response ``(q, v)`` of oscillators with ``w2 > 0`` at times ``t``
        (the particular solution ``sum_k H_nk p_k exp(i k t)`` of eq. 8).

        Parameters
        ----------
        w2 : array_like, shape (M,)
            Squared frequencies, ``> 0``.
        d : float
            Damping.
        t : array_like, shape (T,)

        Returns
        -------
        q, v : numpy.ndarray, shape (M, T)
        """
        w2 = np.asarray(w2, dtype=float)
        t = np.atleast_1d(np.asarray(t, dtype=float))
        zeros = np.zeros_like(w2)
        qz = np.empty((w2.size, t.size))
        vz = np.empty_like(qz)
        for j, tj in enumerate(t):
            q1, v1 = self.propagate(w2, d, tj, zeros, zeros, [tj + TWO_PI])
            qz[:, j], vz[:, j] = q1[:, 0], v1[:, 0]
        p11, p12, p21, p22 = fundamental(w2[:, None], d, TWO_PI)
        a11, a12, a21, a22 = 1.0 - p11, -p12, -p21, 1.0 - p22
        det = a11 * a22 - a12 * a21
        if np.any(np.abs(det) < 1e-13):
            raise ValueError("undamped resonance: a mode frequency s*n*pi equals a load harmonic k")
        q = (a22 * qz - a12 * vz) / det
        v = (-a21 * qz + a11 * vz) / det
        return q, v

    # -- what the solvers, sweeps, the SI layer and the CLI ask of a load ------------------------
    def to_record(self) -> dict:
        """The load as JSON-ready data, ``{"kind": ..., <each of its parameters>}`` (a sweep spec's
        ``[load]`` table); :meth:`from_record` reads it back.

        Raises
        ------
        ValueError
            For a load that is not in the table :data:`LOADS` (no :attr:`kind`).

        Examples
        --------
        >>> from impactbar import CosineLoad, Load
        >>> CosineLoad(0.3, 1.0).to_record()
        {'kind': 'cosine', 'p0': 0.3, 'pk': 1.0, 'k': 1}
        >>> Load.from_record({'kind': 'square', 'q': 1.0, 'kappa': 1.2})
        SquareWaveLoad(q=1.0, kappa=1.2)
        """
        if not self.kind:
            raise ValueError(f"a {type(self).__name__} has no kind: it is not in the table of loads")
        return {"kind": self.kind, **self.parameters.record(self)}

    @staticmethod
    def from_record(record: Mapping) -> Load:
        """The load of a record ``{"kind": ..., <parameters>}`` (:meth:`to_record`); complex
        parameters as ``[re, im]`` pairs, complex or real numbers.

        Raises
        ------
        ValueError
            Naming the missing or unknown key, an unknown kind, or a parameter out of its range.
        """
        if not isinstance(record, Mapping):
            raise ValueError(f"a load record must be a mapping; got {record!r}")
        if "kind" not in record:
            raise ValueError(f"missing key 'kind' (one of {list(LOADS)})")
        kind = record["kind"]
        if not isinstance(kind, str) or kind not in LOADS:
            raise ValueError(f"kind must be one of {list(LOADS)}; got {kind!r}")
        cls = LOADS[kind]
        names = cls.parameters.names
        unknown = [k for k in record if k != "kind" and k not in names]
        if unknown:
            raise ValueError(f"unknown key(s) {unknown} for kind = {kind!r}; allowed: {list(names)}")
        missing = [k for k in names if k not in record]
        if missing:
            raise ValueError(f"missing key(s) {missing} for kind = {kind!r}")
        args = {}
        for f in cls.parameters:
            v = record[f.name]
            if f.dtype == "c16" and isinstance(v, list | tuple):
                v = [complex(*c) if isinstance(c, list | tuple) else c for c in v]
            args[f.name] = v
        return cls(**args)

    def with_(self, **changes) -> Load:
        """A copy with some :attr:`parameters` changed (validated again by the constructor).

        Raises
        ------
        ValueError
            For a name that is not a parameter of this load, or a value out of its range.

        Examples
        --------
        >>> from impactbar import CosineLoad
        >>> CosineLoad(0.3, 1.0).with_(pk=2.0)
        CosineLoad(p0=0.3, pk=2.0, k=1)
        """
        names = self.parameters.names
        if not names or not all(k in names for k in changes):
            unknown = [k for k in changes if k not in names] or list(changes)
            raise ValueError(f"{unknown} not parameter(s) of {type(self).__name__}; it has {list(names)}")
        return type(self)(**{n: changes[n] if n in changes else getattr(self, n) for n in names})

    @property
    def period(self) -> float:
        """The load's fundamental period (dimensionless time): ``2 pi``, or ``2 pi / g`` for a load
        of harmonics whose orders have the greatest common divisor ``g``."""
        return TWO_PI

    @property
    def max_one_impact_orbits(self) -> int:
        """A bound of the one-impact orbits the load admits (the roots of the phase equation,
        eq. 14, in a period); the default is a sweep's width of 2."""
        return 2

    def cosine_form(self) -> tuple[float, float, int] | None:
        """``(p0, pk, k)`` where the load is ``p0 + pk cos(k t)`` with real ``pk`` (eq. 33), the
        form of the pneumatic closed forms; ``None`` otherwise."""
        return None

    def square_form(self) -> tuple[float, float] | None:
        """``(q, kappa)`` where the load is the square wave of eq. 34, the form of the hydraulic
        closed forms; ``None`` otherwise."""
        return None

    def pieces(self) -> tuple[np.ndarray, np.ndarray] | None:
        """``(breaks, levels)`` where the load is constant on pieces (its jumps at ``breaks``, shape
        ``(J,)``); ``None`` for a continuous load."""
        return None

    def compiled_kind(self, *methods: str) -> int | None:
        """The kind of :attr:`kernel_view` (:data:`~impactbar.dynamics.kernelview.FOURIER` or
        ``PIECEWISE``) where compiled code may stand for the load's ``methods``: they are those of
        the class that declares the view. A subclass that redefines one of them (its own
        evaluation) gets ``None``, and the numpy paths evaluate it through its methods. The view
        itself is not built.

        Parameters
        ----------
        *methods : str
            Names of the methods the compiled code replaces (``"__call__"``, ``"flow"``, ...).
        """
        owner = next((c for c in type(self).__mro__ if "kernel_view" in c.__dict__), Load)
        if owner is Load or any(getattr(type(self), m) is not getattr(owner, m) for m in methods):
            return None
        return owner.kernel_kind

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._repr_args()})"

    def _repr_args(self) -> str:  # pragma: no cover - overridden
        return ""


class FourierLoad(Load):
    r"""A load given by finitely many harmonics (eq. 7).

    .. math:: p(t) = p_0 + \mathrm{Re} \sum_{k=1}^{K} p_k e^{i k t}

    Parameters
    ----------
    p0 : float
        Mean load (dimensionless).
    coefficients : array_like of complex, shape (K,)
        ``coefficients[j]`` is the complex harmonic ``p_{j+1}``.

    Raises
    ------
    ValueError
        If ``p0`` or a coefficient is not finite, or there are more than 4096 harmonics.

    Examples
    --------
    >>> from impactbar import FourierLoad
    >>> load = FourierLoad(0.2, [0.5, 0.1j])  # p(t) = 0.2 + 0.5 cos t - 0.1 sin 2t
    >>> float(load(0.0))
    0.7
    """

    kind = "fourier"
    description = "p0 + Re sum_k p_k exp(i k t), finitely many harmonics (eq. 7)"
    parameters = Schema(Field("p0", "mean load"),
                        Field("coefficients", "complex harmonics p_1, p_2, ... (eq. 7)", dtype="c16",
                              per="harmonic"))
    continuation_parameters = ("p0",)
    kernel_kind = FOURIER

    def __init__(self, p0, coefficients):
        self._set(p0=check_real("p0", p0))
        coefficients = check_complex_array("coefficients", coefficients)
        if coefficients.size > 4096:
            raise ValueError(f"coefficients must have at most 4096 entries; got {coefficients.size}")
        self._set_sparse(np.arange(1, coefficients.size + 1), coefficients)

    def _set_sparse(self, ks, pks):
        keep = pks != 0
        k = np.asarray(ks, dtype=float)[keep]  # (boolean indexing: private copies already)
        pk = np.asarray(pks, dtype=complex)[keep]
        k.flags.writeable = pk.flags.writeable = False
        self._set(_k=k, _pk=pk, _kmax=int(ks[-1]) if len(ks) else 0)

    def _key(self):
        return (self.p0, self._kmax, self._k.tobytes(), self._pk.tobytes())

    @cached_property
    def kernel_view(self) -> LoadKernelView:
        """The harmonics as the compiled kernels read them (kind 0), built once."""
        return LoadKernelView.fourier(self.p0, self._k, self._pk)

    @property
    def orders(self) -> np.ndarray:
        """Orders ``k`` of the non-zero harmonics, shape ``(K',)``."""
        return self._k.astype(int)

    @property
    def amplitudes(self) -> np.ndarray:
        """Complex ``p_k`` of the non-zero harmonics, shape ``(K',)``."""
        return self._pk.copy()

    @property
    def coefficients(self) -> np.ndarray:
        """The complex harmonics ``p_1 .. p_K`` (the constructor's ``coefficients``), shape
        ``(K,)``."""
        return self.harmonics()

    @property
    def period(self) -> float:
        g = 0
        for k in self.orders.tolist():
            g = math.gcd(g, k)
        return TWO_PI / g if g else TWO_PI

    @property
    def max_one_impact_orbits(self) -> int:
        """``2 K``: the phase equation (eq. 14) is a trigonometric polynomial of degree ``K`` (at
        least 2)."""
        return max(2, 2 * self._kmax)

    def cosine_form(self):
        if self._k.size != 1 or self._pk[0].imag != 0.0:
            return None
        return self.p0, float(self._pk[0].real), int(self._k[0])

    def harmonics(self, n: int | None = None) -> np.ndarray:
        K = self._kmax if n is None else check_int("n", n, lo=0)
        out = np.zeros(K, dtype=complex)
        sel = self._k <= K
        out[self._k[sel].astype(int) - 1] = self._pk[sel]
        return out

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        e = np.exp(1j * np.multiply.outer(t, self._k))
        return self.p0 + (e @ self._pk).real

    @property
    def sup_abs(self) -> float:
        return abs(self.p0) + float(np.sum(np.abs(self._pk)))

    @property
    def sup_oscillation(self) -> float:
        return float(np.sum(np.abs(self._pk)))

    def variation(self, mid, half):
        lip = float(np.sum(self._k * np.abs(self._pk)))
        half = np.asarray(half, dtype=float)
        return self(mid), np.minimum(lip * half, 2.0 * self.sup_oscillation)

    def _transfer(self, w2, d):
        """``H_nk p_k``, shape (M, K'), raising at an undamped resonance (eq. 16); the last few
        results are kept (read-only), since an orbit's computations ask for the same ones."""
        cache = self.__dict__.setdefault("_transfer_cache", {})
        key = (float(d), w2.tobytes())
        hp = cache.get(key)
        if hp is not None:
            return hp
        den = w2[:, None] + 1j * self._k[None, :] * d - self._k[None, :] ** 2
        if np.any(np.abs(den) <= 1e-12 * np.maximum(1.0, self._k[None, :] ** 2)):
            raise ValueError(
                "undamped resonance: a mode frequency s*n*pi equals a load harmonic k (eq. 16); "
                "use d > 0 or move s"
            )
        hp = self._pk[None, :] / den
        hp.flags.writeable = False
        if len(cache) >= 8:  # bounded; clear() is atomic, so threads sharing a load are safe
            cache.clear()
        cache[key] = hp
        return hp

    def periodic_state(self, w2, d, t):
        w2 = np.asarray(w2, dtype=float)
        t = np.atleast_1d(np.asarray(t, dtype=float))
        hp = self._transfer(w2, d)
        e = np.exp(1j * np.outer(self._k, t))  # (K', T)
        q = (hp @ e).real
        v = ((hp * (1j * self._k)) @ e).real
        pos = w2 > 0
        q[pos] += self.p0 / w2[pos, None]
        return q, v

    def propagate(self, w2, d, t0, q0, v0, t):
        return self.flow(w2, d, t0, q0, v0)(t)

    def flow(self, w2, d, t0, q0, v0):
        w2 = np.asarray(w2, dtype=float)
        hp = self._transfer(w2, d)  # (M, K')
        hv = hp * (1j * self._k)
        qp0, vp0 = self.periodic_state(w2, d, [t0])
        dq = np.asarray(q0, dtype=float)[:, None] - qp0
        dv = np.asarray(v0, dtype=float)[:, None] - vp0
        rigid = w2 == 0.0
        flex = ~rigid
        static = np.where(rigid, 0.0, self.p0 / np.where(rigid, 1.0, w2))[:, None]
        w2f = w2[flex][:, None]
        k = self._k
        rows = np.nonzero(flex)[0]
        lam2 = w2f[:, 0] - 0.25 * d * d
        folded = rows.size > 0 and bool(np.all(lam2 > 0.0))
        if folded:
            # underdamped flexible modes (the rule): Phi(tau) applied to (dq, dv) folded into
            # e^{-d tau/2} (a cos(lam tau) + b sin(lam tau)), the coefficients computed once
            lam = np.sqrt(lam2)[:, None]
            dqf, dvf = dq[rows], dv[rows]
            cq, sq = dqf, (0.5 * d * dqf + dvf) / lam
            cv, sv = dvf, -(w2f * dqf + 0.5 * d * dvf) / lam
            if rows[-1] - rows[0] + 1 == rows.size:  # contiguous rows: update in place
                rows = slice(int(rows[0]), int(rows[-1]) + 1)
        if use_fast("loads.flow") and (folded or rows.size == 0):
            return self._compiled_flow(w2, d, t0, hp, hv, static, rigid, lam if folded else None,
                                       (cq, sq, cv, sv) if folded else None, dq, dv)

        def evaluate(t):
            t = np.atleast_1d(np.asarray(t, dtype=float))
            tau = (t - t0)[None, :]
            e = np.exp(1j * np.outer(k, t))
            q = (hp @ e).real + static
            v = (hv @ e).real
            if folded:
                x = lam * tau
                C, S = np.cos(x), np.sin(x)
                qf = cq * C
                qf += sq * S
                vf = cv * C
                vf += sv * S
                if d:
                    ed = np.exp(-0.5 * d * tau)
                    qf *= ed
                    vf *= ed
                q[rows] += qf
                v[rows] += vf
            else:
                p11, p12, p21, p22 = fundamental(w2f, d, tau)
                q[flex] += p11 * dq[flex] + p12 * dv[flex]
                v[flex] += p21 * dq[flex] + p22 * dv[flex]
            if np.any(rigid):  # rigid mode: closed form, with the mean load added exactly
                b = b_integral(d, tau[0])
                q[rigid] += dq[rigid] + b * dv[rigid] + self.p0 * c_integral(d, tau[0])
                v[rigid] += np.exp(-d * tau[0]) * dv[rigid] + self.p0 * b
            return q, v

        return evaluate

    def _compiled_flow(self, w2, d, t0, hp, hv, static, rigid, lam, folded, dq, dv):
        """:meth:`flow`'s evaluation compiled (:mod:`impactbar.dynamics._flowkernel`): the same
        closed form, for underdamped flexible modes and the rigid mode."""
        from .dynamics._flowkernel import fourier_flow

        M = w2.size
        kind = np.where(rigid, 2, 0).astype(np.int64)
        zeros = np.zeros(M)
        lamv, cq, sq, cv, sv = zeros, zeros, zeros, zeros, zeros
        if folded is not None:
            flex = ~rigid
            kind[flex] = 1
            lamv, cq, sq, cv, sv = (np.zeros(M) for _ in range(5))
            lamv[flex] = lam[:, 0]
            for dst, src in zip((cq, sq, cv, sv), folded, strict=True):
                dst[flex] = src[:, 0]

        # the per-mode data in two arrays (three with kind), not fourteen: a kernel call counts a
        # reference to each array it is passed, and the certified search passes these once per
        # evaluation. np.stack makes them fresh, contiguous and writable (a read-only view, as
        # the cached transfer functions are, would be another type to numba, and so another
        # compilation of every kernel that takes it)
        H = np.stack((hp.real, hp.imag, hv.real, hv.imag))  # (4, M, K)
        V = np.stack((static[:, 0], lamv, cq, sq, cv, sv, dq[:, 0], dv[:, 0]))  # (8, M)
        args = (float(t0), float(d), float(self.p0), self.kernel_view.ks, H, V, kind)

        def evaluate(t):
            return fourier_flow(np.atleast_1d(np.asarray(t, dtype=float)).ravel(), args)

        evaluate.kernel_args = args  # for the compiled admissibility search
        return evaluate

    def rigid_velocity(self, d, t):
        t = np.asarray(t, dtype=float)
        e = np.exp(1j * np.multiply.outer(t, self._k))
        return (e @ (self._pk / (d + 1j * self._k))).real

    def _repr_args(self):
        return f"p0={self.p0!r}, coefficients={self.harmonics().tolist()!r}"


class CosineLoad(FourierLoad):
    r"""Pneumatic-hammer load (eq. 33): one harmonic of order ``k`` on a mean load.

    .. math:: p(t) = p_0 + p_k \cos(k t)

    For ``k > 1`` the load period is ``2 pi / k`` and a one-impact orbit strikes once every ``k``
    load periods. The load factor is ``k p0 / pk``.

    Parameters
    ----------
    p0 : float
        Mean load (dimensionless).
    pk : float
        Amplitude of the harmonic (dimensionless, real).
    k : int, optional
        Order of the harmonic, ``1 <= k <= 4096``. Default 1.

    Raises
    ------
    ValueError
        If ``p0`` or ``pk`` is not a finite real, or ``k`` is not an integer in range.

    Examples
    --------
    >>> from impactbar import CosineLoad
    >>> load = CosineLoad(p0=0.3, pk=1.0)
    >>> load
    CosineLoad(p0=0.3, pk=1.0, k=1)
    >>> float(load(0.0))  # p0 + pk at t = 0
    1.3
    """

    kind = "cosine"
    description = "pneumatic p0 + pk cos(k t) (eq. 33)"
    parameters = Schema(Field("p0", "mean load"), Field("pk", "amplitude of the harmonic"),
                        Field("k", "order of the harmonic, >= 1", "", dtype="i8"))
    continuation_parameters = ("p0", "pk")

    def __init__(self, p0, pk, k=1):
        self._set(p0=check_real("p0", p0), pk=check_real("pk", pk), k=check_int("k", k, lo=1, hi=4096))
        pks = np.zeros(self.k, dtype=complex)
        pks[-1] = self.pk
        self._set_sparse(np.arange(1.0, self.k + 1.0), pks)

    @property
    def load_factor(self) -> float:
        """``k p0 / pk`` (eq. 38), ``inf`` for ``pk = 0``."""
        return self.k * self.p0 / self.pk if self.pk != 0 else math.inf

    def cosine_form(self):
        return self.p0, self.pk, self.k

    def _repr_args(self):
        return f"p0={self.p0!r}, pk={self.pk!r}, k={self.k!r}"


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

    kind = "piecewise"
    description = "constant on pieces of the period"
    parameters = Schema(Field("breaks", "start times of the pieces in [0, 2 pi)", per="piece"),
                        Field("levels", "load on each piece", per="piece"))
    kernel_kind = PIECEWISE

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
        self._set(_b=_readonly(b), _lv=_readonly(lv), _T=_readonly(T), p0=float(np.dot(lv, T) / TWO_PI))
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

    @property
    def max_one_impact_orbits(self) -> int:
        """``J`` (at least 2): the rigid velocity of eq. 14 is monotone on each piece."""
        return max(2, self._b.size)

    def pieces(self):
        return self.breaks, self.levels

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
            from .dynamics._flowkernel import piecewise_flow

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

    def _repr_args(self):
        return f"breaks={self._b.tolist()!r}, levels={self._lv.tolist()!r}"


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

    kind = "square"
    description = "hydraulic square wave, +q then -q (eq. 34)"
    parameters = Schema(Field("q", "level of the square wave, > 0"),
                        Field("kappa", "fraction of the period at +q times 2, in [1, 2]"))
    continuation_parameters = ("q", "kappa")

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

    def square_form(self):
        return self.q, self.kappa

    def harmonics(self, n: int | None = None) -> np.ndarray:
        if n is None:
            raise ValueError("n is required: a square wave has infinitely many harmonics")
        n = check_int("n", n, lo=0)
        k = np.arange(1, n + 1, dtype=float)
        a = k * self.kappa * math.pi
        return (2.0 * self.q / (math.pi * k)) * (np.sin(a) + 1j * (np.cos(a) - 1.0))

    def _repr_args(self):
        return f"q={self.q!r}, kappa={self.kappa!r}"


#: The table of loads: kind -> class, every load a sweep spec, a record and the CLI can name.
LOADS: dict[str, type[Load]] = {cls.kind: cls for cls in
                                (CosineLoad, SquareWaveLoad, FourierLoad, PiecewiseConstantLoad)}
