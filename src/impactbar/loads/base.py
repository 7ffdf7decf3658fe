"""The base of every load: :class:`Load`, what a load provides and declares (theory §3)."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import FrozenInstanceError
from functools import cached_property
from typing import ClassVar

import numpy as np

from .._shared.registry import register
from .abilities import NONE, LoadAbilities, LoadTraits
from .params import LoadParameters

__all__ = ["Load", "LOADS", "register_load", "load_from_record"]

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

    The members, and no more (a solver asks nothing else of a load):

    - what every load implements (abstract here, besides ``p0``): :meth:`__call__` (the load at
      given times), :meth:`harmonics` (the complex ``p_k`` of eq. 7), the bounds used by the
      certified searches (:attr:`sup_abs`, :attr:`sup_oscillation`, :meth:`variation`), and the
      exact modal response (:meth:`propagate`, :meth:`rigid_velocity`); with these alone a load
      runs on the numpy reference paths;
    - :attr:`abilities`: what it can do beyond them (a
      :class:`~impactbar.loads.abilities.LoadAbilities`, built once): its period, the forms a
      special solver has closed forms for, a :class:`~impactbar.loads.abilities.LoadKernel` (the
      view compiled code reads, which the simulator and the compiled searches need), a faster
      exact flow; none by default;
    - :attr:`traits`: what its class declares (a
      :class:`~impactbar.loads.abilities.LoadTraits`: its ``kind`` in the table :data:`LOADS`, its
      parameters), and :attr:`params`, its parameters and record read from them (the parameter
      protocol of :mod:`impactbar.parameters`);
    - :attr:`family` (``"load"``), by which each entry point chooses its solver once;
    - :meth:`_key` (the values that identify it: equality, hashing, caches) and :meth:`_set` (the
      constructor's writes).

    Attributes
    ----------
    p0 : float
        Mean load (dimensionless, eq. 2).

    Examples
    --------
    >>> from impactbar.loads import LOADS, Load
    >>> cosine = LOADS["cosine"]
    >>> isinstance(cosine(0.3, 1.0), Load), cosine(0.3, 1.0) == cosine(0.3, 1.0)  # compared by value
    (True, True)
    >>> cosine(0.3, 1.0).abilities.cosine, cosine(0.3, 1.0).abilities.square
    ((0.3, 1.0, 1), None)
    """

    p0: float

    #: what the class declares: its kind in the table :data:`LOADS`, its description and parameters
    traits: ClassVar[LoadTraits] = LoadTraits()
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
        # the cached hash is not carried to another process (hashes of bytes differ between them),
        # nor the abilities (built again there: they hold the load's own methods)
        return {k: v for k, v in self.__dict__.items() if k not in ("_hash", "abilities")}

    def __repr__(self) -> str:
        args = ", ".join(f"{f.name}={_plain(getattr(self, f.name))!r}" for f in self.traits.parameters)
        return f"{type(self).__name__}({args})"

    @cached_property
    def abilities(self) -> LoadAbilities:
        """What the load can do beyond its required hooks (none here), built once."""
        return NONE

    @property
    def params(self) -> LoadParameters:
        """The load's parameters, its copies with some changed and its record, from its
        :attr:`traits` (:class:`~impactbar.loads.params.LoadParameters`)."""
        return LoadParameters(self)

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

    @abstractmethod
    def rigid_velocity(self, d: float, t) -> np.ndarray:
        """``V(t)``: the periodic, zero-mean solution of ``V' + d V = p(t) - p0``.

        It equals ``Re sum_{k>=1} H_0k p_k (i k) exp(i k t)`` of eq. 14, so the phase equation is
        ``(1 + R) V(phase) = p0 G(d, R)``.
        """


def _plain(value):
    """A parameter's value as its record shows it (an array as a list)."""
    return value.tolist() if isinstance(value, np.ndarray) else value


def load_from_record(record: Mapping) -> Load:
    """The load of a record ``{"kind": ..., <parameters>}`` (:meth:`LoadParameters.record
    <impactbar.loads.params.LoadParameters.record>`); complex parameters as ``[re, im]`` pairs,
    complex or real numbers.

    Raises
    ------
    ValueError
        Naming the missing or unknown key, an unknown kind, or a parameter out of its range.

    Examples
    --------
    >>> load = load_from_record({'kind': 'square', 'q': 1.0, 'kappa': 1.2})
    >>> load.params.record(), load.abilities.square
    ({'kind': 'square', 'q': 1.0, 'kappa': 1.2}, (1.0, 1.2))
    """
    if not isinstance(record, Mapping):
        raise ValueError(f"a load record must be a mapping; got {record!r}")
    if "kind" not in record:
        raise ValueError(f"missing key 'kind' (one of {list(LOADS)})")
    kind = record["kind"]
    if not isinstance(kind, str) or kind not in LOADS:
        raise ValueError(f"kind must be one of {list(LOADS)}; got {kind!r}")
    cls = LOADS[kind]
    names = cls.traits.parameters.names
    unknown = [k for k in record if k != "kind" and k not in names]
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} for kind = {kind!r}; allowed: {list(names)}")
    missing = [k for k in names if k not in record]
    if missing:
        raise ValueError(f"missing key(s) {missing} for kind = {kind!r}")
    args = {}
    for f in cls.traits.parameters:
        v = record[f.name]
        if f.dtype == "c16" and isinstance(v, list | tuple):
            v = [complex(*c) if isinstance(c, list | tuple) else c for c in v]
        args[f.name] = v
    return cls(**args)


def register_load(cls: type[Load]) -> type[Load]:
    """Enter a load class in the table :data:`LOADS` by its ``traits.kind``, so that a sweep
    spec's ``[load] kind``, :func:`load_from_record` and the sweeps' axes know it (usable as a
    class decorator).

    Parameters
    ----------
    cls : type
        A subclass of :class:`Load` whose ``traits`` has a non-empty ``kind``.

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
    >>> from impactbar.loads import LOADS, register_load
    >>> register_load(LOADS["cosine"]) is LOADS["cosine"]  # already there: registering again changes nothing
    True
    """
    return register(LOADS, cls, Load, "traits.kind", "load")
