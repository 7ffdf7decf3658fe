"""Loads of finitely many harmonics (paper eqs. 7, 33): :class:`FourierLoad`, :class:`CosineLoad`."""

from __future__ import annotations

import math
from functools import cached_property
from typing import NamedTuple

import numpy as np

from .._shared.bounded import remember
from .._shared.schema import Field, Schema
from .._shared.validate import check_complex_array, check_int, check_real
from ..dynamics.compiled_views import FOURIER, LoadKernelView
from ..dynamics.implementations import use_fast
from ..dynamics.modal import b_integral, c_integral, fundamental
from .abilities import LoadAbilities, LoadKernel, LoadTraits
from .base import TWO_PI, Load

__all__ = ["FourierLoad", "CosineLoad"]

#: ``H_nk p_k`` of :meth:`FourierLoad._transfer` by ``(d, w2, orders, p_k)``, read-only, the last
#: 64: the same floats for every load with these harmonics, whatever its mean load
_SHARED_TRANSFERS: dict = {}


#: :meth:`FourierLoad._flow_parts` by ``(d, w2, orders, p_k)``, the last 64: shared, never written
_SHARED_FLOW_PARTS: dict = {}


class _FlowParts(NamedTuple):
    """:meth:`FourierLoad.flow`'s parts that depend on ``w2, d`` and the harmonics alone."""

    hp: np.ndarray  # H_nk p_k, shape (M, K')
    hv: np.ndarray  # i k H_nk p_k
    rigid: np.ndarray  # w2 == 0
    flex: np.ndarray
    pos_at: object  # where w2 > 0: a slice where those modes are contiguous, else their indices
    w2_pos: np.ndarray  # w2[pos, None]
    w2_safe: np.ndarray  # w2 with 1 at the rigid modes
    w2f: np.ndarray  # w2[flex, None]
    rows: np.ndarray  # the flexible modes' indices
    take: object  # rows, or their slice where contiguous and folded
    folded: bool  # every flexible mode underdamped
    lam: np.ndarray | None  # their damped frequencies, shape (F, 1)
    kind: np.ndarray  # the compiled flow's kinds (2 rigid, 1 folded, 0 else)
    lamv: np.ndarray  # lam per mode, 0 elsewhere
    H: np.ndarray  # (hp.real, hp.imag, hv.real, hv.imag), shape (4, M, K')


def _as_slice(idx: np.ndarray):
    """The increasing indices ``idx`` as a slice where they are a contiguous run (a slice indexes
    faster, the same entries), else ``idx``."""
    if idx.size and int(idx.max()) - int(idx.min()) + 1 == idx.size:
        return slice(int(idx.min()), int(idx.max()) + 1)
    return idx


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

    traits = LoadTraits(
        kind="fourier", description="p0 + Re sum_k p_k exp(i k t), finitely many harmonics (eq. 7)",
        parameters=Schema(Field("p0", "mean load"),
                          Field("coefficients", "complex harmonics p_1, p_2, ... (eq. 7)", dtype="c16",
                                per="harmonic")),
        continuation_parameters=("p0",))

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

    @cached_property
    def abilities(self) -> LoadAbilities:
        """Its period ``2 pi / gcd(orders)``, at most ``2 K`` one-impact orbits (the phase equation,
        eq. 14, is a trigonometric polynomial of degree ``K``), its cosine form (eq. 33), its
        harmonics, the compiled kernel (:data:`~impactbar.dynamics.compiled_views.FOURIER`) and its
        closed-form flow and periodic response."""
        g = 0
        for k in self.orders.tolist():
            g = math.gcd(g, k)
        return LoadAbilities(
            period=TWO_PI / g if g else TWO_PI, max_one_impact_orbits=max(2, 2 * self._kmax),
            cosine=self._cosine_form(), orders=self.orders, amplitudes=self.amplitudes,
            kernel=LoadKernel.declared(self, FourierLoad, FOURIER, self.kernel_view),
            flow=self.flow, periodic_state=self.periodic_state)

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

    def _cosine_form(self):
        """``(p0, pk, k)`` where the load is ``p0 + pk cos(k t)`` with real ``pk``, else ``None``."""
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
        results are kept (read-only), since an orbit's computations ask for the same ones. They do
        not depend on the mean load ``p0``: loads that differ only in it (a chart's load factors,
        a new load each) share them (:data:`_SHARED_TRANSFERS`)."""
        cache = self.__dict__.setdefault("_transfer_cache", {})
        key = (float(d), w2.tobytes())
        hp = cache.get(key)
        if hp is not None:
            return hp
        shared = (*key, self._k.tobytes(), self._pk.tobytes())
        hp = _SHARED_TRANSFERS.get(shared)
        if hp is None:
            den = w2[:, None] + 1j * self._k[None, :] * d - self._k[None, :] ** 2
            if np.any(np.abs(den) <= 1e-12 * np.maximum(1.0, self._k[None, :] ** 2)):
                raise ValueError(
                    "undamped resonance: a mode frequency s*n*pi equals a load harmonic k (eq. 16); "
                    "use d > 0 or move s"
                )
            hp = self._pk[None, :] / den
            hp.flags.writeable = False
            remember(_SHARED_TRANSFERS, shared, hp, 64)
        remember(cache, key, hp, 8)
        return hp

    def periodic_state(self, w2, d, t):
        w2 = np.asarray(w2, dtype=float)
        return self._periodic_at(self._flow_parts(w2, d), t)

    def _periodic_at(self, parts, t):
        """:meth:`periodic_state` at the times ``t`` from the parts (:meth:`_flow_parts`) of its
        ``w2, d``: ``(H p e^{i k t}).real`` with the static deflection ``p0 / w2`` added."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        e = np.exp(1j * np.outer(self._k, t))  # (K', T)
        q = (parts.hp @ e).real
        v = (parts.hv @ e).real
        q[parts.pos_at] += self.p0 / parts.w2_pos
        return q, v

    def _flow_parts(self, w2, d) -> _FlowParts:
        """What :meth:`flow` and :meth:`periodic_state` take from ``w2, d`` and the harmonics alone,
        computed once for every load with these harmonics whatever its mean load (a chart's load
        factors, a new load each; :data:`_SHARED_FLOW_PARTS`): the same floats as computed per call.
        Raises at an undamped resonance (:meth:`_transfer`)."""
        key = (float(d), w2.tobytes(), self._k.tobytes(), self._pk.tobytes())
        parts = _SHARED_FLOW_PARTS.get(key)
        if parts is not None:
            return parts
        hp = self._transfer(w2, d)
        hv = hp * (1j * self._k)
        rigid = w2 == 0.0
        flex = ~rigid
        pos = w2 > 0
        w2f = w2[flex][:, None]
        rows = np.nonzero(flex)[0]
        lam2 = w2f[:, 0] - 0.25 * d * d
        folded = rows.size > 0 and bool(np.all(lam2 > 0.0))
        lam = np.sqrt(lam2)[:, None] if folded else None
        take = _as_slice(rows) if folded else rows  # contiguous rows: updated in place
        kind = np.where(rigid, 2, 0).astype(np.int64)
        lamv = np.zeros(w2.size)
        if folded:
            kind[flex] = 1
            lamv[flex] = lam[:, 0]
        # the compiled flow's harmonics: np.stack makes them contiguous and writable (a read-only
        # array would be another type to numba, and so another compilation; no kernel writes them)
        H = np.stack((hp.real, hp.imag, hv.real, hv.imag))  # (4, M, K)
        parts = _FlowParts(hp, hv, rigid, flex, _as_slice(np.nonzero(pos)[0]), w2[pos, None],
                           np.where(rigid, 1.0, w2), w2f, rows,
                           take, folded, lam, kind, lamv, H)
        return remember(_SHARED_FLOW_PARTS, key, parts, 64)

    def propagate(self, w2, d, t0, q0, v0, t):
        return self.flow(w2, d, t0, q0, v0)(t)

    def flow(self, w2, d, t0, q0, v0):
        w2 = np.asarray(w2, dtype=float)
        parts = self._flow_parts(w2, d)
        hp, hv, rigid, flex, rows = parts.hp, parts.hv, parts.rigid, parts.flex, parts.take
        qp0, vp0 = self._periodic_at(parts, [t0])
        dq = np.asarray(q0, dtype=float)[:, None] - qp0
        dv = np.asarray(v0, dtype=float)[:, None] - vp0
        static = np.where(rigid, 0.0, self.p0 / parts.w2_safe)[:, None]
        w2f = parts.w2f
        k = self._k
        folded = parts.folded
        if folded:
            # underdamped flexible modes (the rule): Phi(tau) applied to (dq, dv) folded into
            # e^{-d tau/2} (a cos(lam tau) + b sin(lam tau)), the coefficients computed once
            lam = parts.lam
            dqf, dvf = dq[rows], dv[rows]
            cq, sq = dqf, (0.5 * d * dqf + dvf) / lam
            cv, sv = dvf, -(w2f * dqf + 0.5 * d * dvf) / lam
        if use_fast("loads.flow") and (folded or parts.rows.size == 0):
            return self._compiled_flow(parts, t0, d, static, (cq, sq, cv, sv) if folded else None, dq, dv)

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

    def _compiled_flow(self, parts, t0, d, static, folded, dq, dv):
        """:meth:`flow`'s evaluation compiled (:mod:`impactbar.dynamics._load_flow`): the same
        closed form, for underdamped flexible modes and the rigid mode."""
        from ..dynamics.compiled import fourier_flow

        # the per-mode data in two arrays (three with kind), not fourteen: a kernel call counts a
        # reference to each array it is passed, and the certified search passes these once per
        # evaluation; the harmonics' H and the kinds are the parts' own (shared, never written)
        V = np.zeros((8, static.shape[0]))
        static_row, lam_row, *folded_rows, dq_row, dv_row = V  # (views: rows written in place)
        static_row[:], lam_row[:], dq_row[:], dv_row[:] = static[:, 0], parts.lamv, dq[:, 0], dv[:, 0]
        if folded is not None:  # cq, sq, cv, sv at the flexible modes
            for dst, src in zip(folded_rows, folded, strict=True):
                dst[parts.flex] = src[:, 0]
        args = (float(t0), float(d), float(self.p0), self.kernel_view.ks, parts.H, V, parts.kind)

        def evaluate(t):
            return fourier_flow(np.atleast_1d(np.asarray(t, dtype=float)).ravel(), args)

        evaluate.kernel_args = args  # for the compiled admissibility search
        return evaluate

    def rigid_velocity(self, d, t):
        t = np.asarray(t, dtype=float)
        e = np.exp(1j * np.multiply.outer(t, self._k))
        return (e @ (self._pk / (d + 1j * self._k))).real


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

    traits = LoadTraits(
        kind="cosine", description="pneumatic p0 + pk cos(k t) (eq. 33)",
        parameters=Schema(Field("p0", "mean load"), Field("pk", "amplitude of the harmonic"),
                          Field("k", "order of the harmonic, >= 1", "", dtype="i8")),
        continuation_parameters=("p0", "pk"), parameter_ranges={"k": {"low": 1, "high": 4096}})

    def __init__(self, p0, pk, k=1):
        self._set(p0=check_real("p0", p0), pk=check_real("pk", pk), k=check_int("k", k, lo=1, hi=4096))
        pks = np.zeros(self.k, dtype=complex)
        pks[-1] = self.pk
        self._set_sparse(np.arange(1.0, self.k + 1.0), pks)

    @property
    def load_factor(self) -> float:
        """``k p0 / pk`` (eq. 38), ``inf`` for ``pk = 0``."""
        return self.k * self.p0 / self.pk if self.pk != 0 else math.inf

    def _cosine_form(self):
        return self.p0, self.pk, self.k
