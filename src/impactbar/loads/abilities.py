"""What a load class declares (:class:`LoadTraits`) and what a load can do beyond the hooks every
load implements (:class:`LoadAbilities`, with :class:`LoadKernel`, what compiled code knows of it).

A solver asks a load its abilities once (``load.abilities``, beside the dispatch on the forcing's
family) and takes what is there: a form a special solver has closed forms for, the view the
compiled kernels read, a faster exact flow. The functions :func:`left_limit`, :func:`exact_flow`,
:func:`periodic_state` and :func:`jumps` give the load's own where it has one, else the general
answer from its required hooks, so that a load with the required hooks alone runs everywhere a
general load is taken.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from .._shared.schema import Schema
from ..dynamics.compiled_views import LoadKernelView
from ..dynamics.modal import fundamental

__all__ = ["LoadTraits", "LoadAbilities", "LoadKernel", "compiled_kind", "left_limit", "exact_flow",
           "periodic_state", "jumps"]

TWO_PI = 2.0 * math.pi

#: the evaluation methods compiled code may stand for (:meth:`LoadKernel.covers`)
EVALUATION = ("__call__", "variation", "propagate", "flow")


@dataclass(frozen=True)
class LoadTraits:
    """What a load class declares, once, in its body (``traits = LoadTraits(...)``): its entry in the
    table of loads and its parameters, read by the sweeps, the CLI, the records and the parameter
    protocol (:attr:`impactbar.Load.params`).

    Parameters
    ----------
    kind : str, optional
        Its name in the table :data:`impactbar.loads.LOADS`: a sweep spec's ``[load] kind``, the
        CLI's ``--load``, the ``"kind"`` of a record (empty for a load not in the table).
    description : str, optional
        What the load is, in a few words (the CLI's help).
    parameters : Schema, optional
        The constructor's parameters, in order, each with its long name and dtype.
    continuation_parameters : tuple of str, optional
        The parameters a branch of orbits can be continued in.
    parameter_ranges : mapping, optional
        Name -> keyword arguments of :class:`~impactbar.parameters.Parameter` (``low``, ``high``,
        ``low_open``, ...), the ranges a parameter record states; the constructor checks them again.

    Examples
    --------
    >>> from impactbar.loads import LOADS
    >>> LOADS["cosine"].traits.parameters.names
    ('p0', 'pk', 'k')
    """

    kind: str = ""
    description: str = ""
    parameters: Schema = Schema()
    continuation_parameters: tuple[str, ...] = ()
    parameter_ranges: Mapping[str, dict] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class LoadKernel:
    """What compiled code knows of a load: the kind of its view, the view, and the evaluation
    methods the compiled code stands for (those of the class that declares the kernel which the
    load's class has not redefined).

    Parameters
    ----------
    kind : int
        :data:`~impactbar.dynamics.compiled_views.FOURIER` or ``PIECEWISE``.
    view : LoadKernelView
        The load as the kernels read it.
    methods : frozenset of str
        The names (of ``EVALUATION``) compiled code may stand for.
    """

    kind: int
    view: LoadKernelView
    methods: frozenset[str]

    @classmethod
    def declared(cls, load, owner: type, kind: int, view: LoadKernelView) -> LoadKernel:
        """The kernel ``owner`` declares for ``load`` (an instance of ``owner`` or of a subclass):
        it stands for the evaluation methods ``load``'s class takes from ``owner`` unchanged."""
        own = frozenset(m for m in EVALUATION if getattr(type(load), m) is getattr(owner, m))
        return cls(kind, view, own)

    def covers(self, *methods: str) -> bool:
        """Whether compiled code may stand for all of ``methods`` (``"__call__"``, ``"flow"``, ...)."""
        return self.methods.issuperset(methods)

    def kind_for(self, *methods: str) -> int | None:
        """:attr:`kind` where compiled code stands for ``methods``, else ``None``."""
        return self.kind if self.covers(*methods) else None


@dataclass(frozen=True, eq=False)
class LoadAbilities:
    """What a load can do beyond its required hooks, each ``None`` (or the general value) where it
    cannot: returned by :attr:`impactbar.Load.abilities`, built once.

    Parameters
    ----------
    period : float, optional
        The fundamental period (dimensionless time), ``2 pi`` or a fraction of it.
    max_one_impact_orbits : int, optional
        A bound of the one-impact orbits (the roots of the phase equation, eq. 14, in a period).
    cosine : (float, float, int) or None
        ``(p0, pk, k)`` where the load is ``p0 + pk cos(k t)`` with real ``pk`` (eq. 33): the
        pneumatic closed forms.
    square : (float, float) or None
        ``(q, kappa)`` where the load is the square wave of eq. 34: the hydraulic closed forms.
    pieces : (numpy.ndarray, numpy.ndarray) or None
        ``(breaks, levels)``, shape ``(J,)`` each, where the load is constant on pieces.
    orders, amplitudes : numpy.ndarray or None
        The orders ``k`` (int) and complex ``p_k`` of the non-zero harmonics, where the load has
        finitely many.
    kernel : LoadKernel or None
        What compiled code knows of it (the simulator and the compiled searches need one).
    flow, periodic_state, left_limit, jumps : callable or None
        The load's own :func:`exact_flow`, :func:`periodic_state`, :func:`left_limit` and :func:`jumps`
        (the same signatures without the load), where it has faster or exact ones.
    """

    period: float = TWO_PI
    max_one_impact_orbits: int = 2
    cosine: tuple[float, float, int] | None = None
    square: tuple[float, float] | None = None
    pieces: tuple[np.ndarray, np.ndarray] | None = None
    orders: np.ndarray | None = None
    amplitudes: np.ndarray | None = None
    kernel: LoadKernel | None = None
    flow: Callable | None = None
    periodic_state: Callable | None = None
    left_limit: Callable | None = None
    jumps: Callable | None = None


#: the abilities of a load that declares none
NONE = LoadAbilities()


def compiled_kind(load, *methods: str) -> int | None:
    """The kind of the load's kernel (:data:`~impactbar.dynamics.compiled_views.FOURIER` or
    ``PIECEWISE``) where compiled code may stand for its ``methods`` (any kernel it has, with no
    ``methods``); ``None`` for a load without a kernel or whose class redefines one of them.

    Examples
    --------
    >>> from impactbar import CosineLoad
    >>> compiled_kind(CosineLoad(0.3, 1.0), "__call__", "flow")
    0
    """
    kernel = load.abilities.kernel
    return None if kernel is None else kernel.kind_for(*methods)


def left_limit(load, t) -> np.ndarray:
    """``p(t-)``, the load's own where it has jumps, else ``p(t)``.

    Examples
    --------
    >>> from impactbar import SquareWaveLoad
    >>> float(left_limit(SquareWaveLoad(1.0, 1.0), 0.0)), float(SquareWaveLoad(1.0, 1.0)(0.0))
    (-1.0, 1.0)
    """
    own = load.abilities.left_limit
    return own(t) if own is not None else load(t)


def jumps(load, t0: float, t1: float) -> np.ndarray:
    """Absolute times of the load's jumps in ``(t0, t1)``, sorted, shape ``(J,)`` (none for a
    load that declares none)."""
    own = load.abilities.jumps
    return own(t0, t1) if own is not None else np.empty(0)


def exact_flow(load, w2, d: float, t0: float, q0, v0):
    """The exact flow of ``q'' + d q' + w2 q = p(t)`` from one state, as a callable
    ``flow(t) -> (q, v)`` of shape ``(M, T)``: the load's own (precomputing what does not depend on
    ``t``), else ``load.propagate(w2, d, t0, q0, v0, t)``.
    """
    own = load.abilities.flow
    if own is not None:
        return own(w2, d, t0, q0, v0)
    w2 = np.asarray(w2, dtype=float)
    q0 = np.asarray(q0, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    return lambda t: load.propagate(w2, d, t0, q0, v0, t)


def periodic_state(load, w2, d: float, t):
    """The ``2 pi``-periodic response ``(q, v)`` of oscillators with ``w2 > 0`` at times ``t`` (the
    particular solution ``sum_k H_nk p_k exp(i k t)`` of eq. 8): the load's own closed form, else
    from one period of ``load.propagate``.

    Parameters
    ----------
    load : Load
    w2 : array_like, shape (M,)
        Squared frequencies, ``> 0``.
    d : float
        Damping.
    t : array_like, shape (T,)
        Times (load frame).

    Returns
    -------
    q, v : numpy.ndarray, shape (M, T)
        Displacements and velocities.

    Raises
    ------
    ValueError
        At an undamped resonance (a mode frequency equal to a load harmonic).
    """
    own = load.abilities.periodic_state
    if own is not None:
        return own(w2, d, t)
    w2 = np.asarray(w2, dtype=float)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    zeros = np.zeros_like(w2)
    qz = np.empty((w2.size, t.size))
    vz = np.empty_like(qz)
    for j, tj in enumerate(t):
        q1, v1 = load.propagate(w2, d, tj, zeros, zeros, [tj + TWO_PI])
        qz[:, j], vz[:, j] = q1[:, 0], v1[:, 0]
    p11, p12, p21, p22 = fundamental(w2[:, None], d, TWO_PI)
    a11, a12, a21, a22 = 1.0 - p11, -p12, -p21, 1.0 - p22
    det = a11 * a22 - a12 * a21
    if np.any(np.abs(det) < 1e-13):
        raise ValueError("undamped resonance: a mode frequency s*n*pi equals a load harmonic k")
    q = (a22 * qz - a12 * vz) / det
    v = (-a21 * qz + a11 * vz) / det
    return q, v
