"""The base of every load: :class:`Load`, what a load provides and declares (theory §3)."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import FrozenInstanceError
from typing import ClassVar

import numpy as np

from .._shared.parameters import Parameter
from .._shared.registry import register
from .._shared.schema import Schema
from ..dynamics.kernelview import LoadKernelView
from ..dynamics.modal import fundamental

__all__ = ["Load", "LOADS", "register_load"]

TWO_PI = 2.0 * math.pi

#: The table of loads: kind -> class, every load a sweep spec, a record and the CLI can name (filled
#: by :mod:`impactbar.loads` with the package's loads, in the order they are listed)
LOADS: dict[str, type[Load]] = {}


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
      and dtypes), :attr:`continuation_parameters` and :attr:`parameter_ranges` (its parameter
      records, :meth:`parameter_table`, changed by :meth:`with_parameter`: the parameter protocol
      of :mod:`impactbar.parameters`); :meth:`to_record`, :meth:`from_record` and :meth:`with_` (a
      copy with parameters changed);
    - :attr:`period` (its fundamental period), :attr:`max_one_impact_orbits` (a bound of the roots
      of the phase equation, eq. 14);
    - the forms a special solver recognises: :meth:`cosine_form` (the rigid closed forms,
      pneumatic), :meth:`square_form` (the rigid closed forms, hydraulic), :meth:`pieces` (the
      jumps of a piecewise-constant load), :attr:`orders` (the harmonics of a load of finitely
      many) and ``_boundaries`` (the jumps in a window, where the wave law's quadratures split);
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

    #: The members a load must implement (abstract here, besides ``p0`` and ``_key``): with them alone
    #: it runs through the numpy reference paths (``tests/laws/test_law_hooks.py``'s minimal load);
    #: the simulator and the compiled searches need :attr:`kernel_view` too.
    REQUIRED_HOOKS: ClassVar[tuple[str, ...]] = (
        "__call__", "harmonics", "sup_abs", "sup_oscillation", "variation", "propagate", "rigid_velocity")
    #: Every other member the solvers call: declarations and members with a default.
    OPTIONAL_HOOKS: ClassVar[tuple[str, ...]] = (
        "kind", "description", "parameters", "continuation_parameters", "parameter_ranges", "kernel_kind",
        "family", "kernel_view", "left_limit", "flow", "periodic_state", "to_record", "from_record",
        "parameter_table", "with_parameter", "with_parameters", "with_", "period", "max_one_impact_orbits",
        "cosine_form", "square_form", "pieces", "orders", "compiled_kind")

    #: the load's name in the table :data:`LOADS`: a sweep spec's ``[load] kind``, the CLI's
    #: ``--load``, the ``"kind"`` of :meth:`to_record` (empty for a load not in the table)
    kind: ClassVar[str] = ""
    #: what the load is, in a few words (the CLI's help)
    description: ClassVar[str] = ""
    #: the constructor's parameters, in order, each with its long name and dtype
    parameters: ClassVar[Schema] = Schema()
    #: the parameters a branch of orbits can be continued in (:func:`impactbar.continue_orbit`)
    continuation_parameters: ClassVar[tuple[str, ...]] = ()
    #: the ranges of its numbers, where a record (:meth:`parameter_table`) should state them: name ->
    #: keyword arguments of :class:`~impactbar.parameters.Parameter` (``low``, ``high``, ``low_open``,
    #: ...); the constructor checks them again
    parameter_ranges: ClassVar[dict[str, dict]] = {}
    #: the ``kind`` of the :attr:`kernel_view` the class declares (``None``: it declares none)
    kernel_kind: ClassVar[int | None] = None
    #: the forcing family, by which each entry point chooses its solver once (a drive's is
    #: ``"drive"``)
    family: ClassVar[str] = "load"

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

    def parameter_table(self) -> tuple[Parameter, ...]:
        """The load's numbers as parameter records (:func:`impactbar.parameters.parameters`), from
        its declaration in the class body: the scalar fields of :attr:`parameters` (their long names
        the descriptions, an integer dtype an integer parameter), continuable where named in
        :attr:`continuation_parameters`, with the ranges of :attr:`parameter_ranges`.

        Returns
        -------
        tuple of Parameter

        Examples
        --------
        >>> from impactbar import CosineLoad
        >>> [(p.name, p.value, p.continuable) for p in CosineLoad(0.3, 1.0).parameter_table()]
        [('p0', 0.3, True), ('pk', 1.0, True), ('k', 1, False)]
        """
        out = []
        for f in self.parameters:
            if f.per is not None:
                continue
            integer = f.dtype.startswith("i")
            value = getattr(self, f.name)
            out.append(Parameter(f.name, int(value) if integer else float(value), description=f.long_name,
                                 continuable=f.name in self.continuation_parameters, integer=integer,
                                 **self.parameter_ranges.get(f.name, {})))
        return tuple(out)

    def with_parameter(self, name: str, value) -> Load:
        """A copy with one of :meth:`parameter_table` changed (validated again by the constructor).

        Parameters
        ----------
        name : str
            One of the names of :meth:`parameter_table`.
        value : float or int
            Its new value (an int for an integer field).

        Returns
        -------
        Load

        Raises
        ------
        ValueError
            For a name that is not a parameter of this load, or a value out of its range.
        """
        return self.with_(**{name: value})

    def with_parameters(self, changes: dict) -> Load:
        """A copy with several of :meth:`parameter_table` changed at once (:meth:`with_`, the result
        validated once)."""
        return self.with_(**changes)

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

    @property
    def orders(self) -> np.ndarray | None:
        """Orders ``k`` of the non-zero harmonics where the load has finitely many (a Fourier load's,
        shape ``(K',)``, with its ``amplitudes``); ``None`` otherwise."""
        return None

    def _boundaries(self, t0: float, t1: float) -> np.ndarray:
        """Absolute times of the load's jumps in ``(t0, t1)``, sorted, shape ``(J,)``: none here (a
        piecewise-constant load has its own)."""
        return np.empty(0)

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


def register_load(cls: type[Load]) -> type[Load]:
    """Enter a load class in the table :data:`LOADS` by its :attr:`~Load.kind`, so that a sweep
    spec's ``[load] kind``, :meth:`Load.from_record` and the sweeps' axes know it (usable as a class
    decorator).

    Parameters
    ----------
    cls : type
        A subclass of :class:`Load` with a non-empty ``kind``.

    Returns
    -------
    type
        ``cls``.

    Raises
    ------
    ValueError
        For a class that is not a load, without a ``kind``, or whose ``kind`` another class holds.

    Examples
    --------
    >>> from impactbar.loads import CosineLoad, register_load
    >>> register_load(CosineLoad) is CosineLoad  # already there: registering again changes nothing
    True
    """
    return register(LOADS, cls, Load, "kind", "load")
