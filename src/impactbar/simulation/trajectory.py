"""The result of a simulation (paper Section 5, theory §8): :class:`Trajectory`, its log of
closed-form pieces of motion, and its :class:`EnergyAccount` computed by quadrature.

A run is stored as pieces, each the closed-form motion from a start state in one modal basis: the
free-free modes in flight (``_FREE``), the fixed-free modes while the bar is held on the stop
(``_CONTACT``), or a law's contact step (``_WINDOW``, the motion held by the blow's record, e.g. the
wave law's characteristics solution). :func:`impactbar.simulation.simulate.simulate` writes them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from .._shared import tables as _tables
from .._shared.columns import IV_HI
from .._shared.schema import END_MOTION, Field, Schema
from ..loads import Load
from ..model import BarModel

if TYPE_CHECKING:
    from ._core import _Core
    from .simulate import InitialState

__all__ = ["Trajectory", "EnergyAccount"]

TWO_PI = 2.0 * math.pi

#: Largest quadrature work (nodes times modes) :attr:`Trajectory.energy` may take (time bound).
MAX_ENERGY_WORK = 3e8

_FREE, _CONTACT, _WINDOW = 0, 1, 2  # _WINDOW: a law's contact step (its record holds the motion)
#: the fields of a :class:`Trajectory` that :meth:`Trajectory._deferred` makes on first access
_DEFERRED = frozenset({"impact_times", "impact_velocities", "final_state", "_segments"})


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

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, InitialState, simulate
    >>> run = simulate(BarModel(s=10.0, d=0.05, R=0.5, n_modes=2), CosineLoad(0.3, 1.0),
    ...                InitialState.rigid(-0.01, 0.0, n_modes=2), 125.0)
    >>> run.energy.work > run.energy.impact_loss > 0, run.energy.relative_residual < 1e-8
    (True, True)
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

    __slots__ = ("n_modes", "t", "basis", "entry", "q", "v", "frozen")

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


@dataclass(frozen=True, eq=False, init=False)
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
        Times of the impacts (load frame, dimensionless): the arrivals at the stop, under the wave
        law the starts of the contact windows (each lasts ``2/s``; see :attr:`impacts`).
    impact_velocities : numpy.ndarray, shape (I,)
        Velocity ``u_t(1, t-)`` of the struck end just before each impact, ``> 0``.
    contact_intervals : numpy.ndarray, shape (m, 2)
        Start and end of each interval of sustained contact, the same under every impact law: the
        bar held on the stop (fixed at ``x = 1``, theory §8) after chatter or a touch, until the
        stop's reaction turns tensile (the end is ``t_end`` while still in contact). The impacts'
        own contact is not included: it lasts no time under the paper's law (eq. 10) and is each
        impact's window under the wave law, ``impacts[j].t0`` to ``impacts[j].t0 +
        impacts[j].duration``; under the wave law, whose arrivals all open a window, it is empty.
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

    Examples
    --------
    >>> from impactbar import BarModel, InitialState, SquareWaveLoad, simulate
    >>> start = InitialState.rigid(-0.01, 0.0, n_modes=1)
    >>> run = simulate(BarModel(s=10.0, d=0.05, R=0.5, n_modes=1), SquareWaveLoad(1.0, 1.2), start, 60.0)
    >>> run  # a short repr: the model, the load, the time span, the impacts, why it stopped
    Trajectory(BarModel(s=10.0, d=0.05, R=0.5, n_modes=1, impact='paper'), SquareWaveLoad(q=1.0,
               kappa=1.2), t 0 -> 60, 26 impacts, status 't_end')
    >>> run.impact_times.shape == run.impact_velocities.shape == (run.n_impacts,)
    True
    >>> bool(run.end_displacement(run.impact_times[-1]) > -1e-9)  # at the stop when it strikes
    True
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

    def __init__(self, model: BarModel, load: Load, t0: float, t_end: float, impact_times: np.ndarray,
                 impact_velocities: np.ndarray, contact_intervals: np.ndarray, final_state: InitialState,
                 status: str, _core: _Core, _segments: _Segments, n_release_retries: int = 0):
        # the fields at once: a frozen dataclass's generated __init__ sets them one by one through
        # object.__setattr__ (4 us, a third of a 1-impact run's cost); the parameters are the fields
        # in their order (tests/simulation/test_shortrun.py holds them to dataclasses.fields)
        self.__dict__.update(model=model, load=load, t0=t0, t_end=t_end, impact_times=impact_times,
                             impact_velocities=impact_velocities, contact_intervals=contact_intervals,
                             final_state=final_state, status=status, _core=_core, _segments=_segments,
                             n_release_retries=n_release_retries)

    @classmethod
    def _deferred(cls, model: BarModel, load: Load, t0: float, t_end: float, contact_intervals: np.ndarray,
                  status: str, _core: _Core, rows) -> Trajectory:
        """A run whose impacts, final state and log (:data:`_DEFERRED`) are each made on its first
        read, by ``rows[0](name, *rows[1:])`` (from a short run's kernel output, :mod:`._shortrun`;
        see :class:`_Deferred`): a run whose caller reads only its status or end does not pay for
        them (2 us, a sixth of a 1-impact run's cost), one that reads its final state only for it."""
        self = object.__new__(cls)
        self.__dict__.update(model=model, load=load, t0=t0, t_end=t_end, contact_intervals=contact_intervals,
                             status=status, _core=_core, n_release_retries=0, _rows=rows)
        return self

    def __repr__(self) -> str:
        """One line: model, load, time span, impacts, status (not the arrays)."""
        return f"{type(self).__name__}({', '.join(self._repr_items())})"

    def _repr_items(self) -> list[str]:
        """The items of the repr, in order; a subclass extends the list (its own numbers)."""
        return [repr(self.model), repr(self.load), f"t {self.t0:.6g} -> {self.t_end:.6g}",
                f"{self.impact_times.size} impacts", f"status {str(self.status)!r}"]

    #: the declared fields, one value per impact: the columns of :meth:`to_dataframe` (``time``,
    #: ``velocity``) and the variables of :meth:`to_xarray` (``impact_time``, ``impact_velocity``)
    fields: ClassVar[Schema] = Schema(
        Field("impact_times", "time of the impact (load frame)", per="impact", element="time",
              views={"table"}),
        Field("impact_velocities", "velocity u_t(1, t-) of the struck end before the impact",
              per="impact", element="velocity", views={"table"}))

    @property
    def n_impacts(self) -> int:
        return int(self.impact_times.size)

    @property
    def in_contact_at_end(self) -> bool:
        return bool(self.contact_intervals.size and self.contact_intervals[-1, IV_HI] == self.t_end
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
            if s.basis == _WINDOW:  # inside a contact window: the characteristics solution
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
        """The record of each impact, in order, one per :attr:`impact_times`: the law's per-blow
        output (:meth:`impactbar.laws.ContactLaw.contact`). Under the wave law a
        :class:`~impactbar.WaveImpact` (force wave, rod energy, peak stresses, efficiency, advance of
        the rod end); under the paper's law an :class:`~impactbar.laws.InstantImpact` (impact
        velocity, impulse, energy loss), built on access from the states the run logged."""
        segs = self._segments
        model, law = self.model, self.model.law
        entry = _ENTRIES.index("impact")
        out = []
        for j in np.flatnonzero(segs.entry == entry):
            if segs.basis[j] == _WINDOW:
                out.append(segs.frozen[j].resolve())
                continue
            prev = segs[j - 1]  # the flight that arrived: its state just before the impact
            qm, vm = self._core.propagate(prev.basis, prev.t, prev.q, prev.v, [segs.t[j]])
            _, _, _, record = law.contact(model, self.load, float(segs.t[j]), qm[:, 0], vm[:, 0])
            out.append(record)
        return tuple(out)

    def plot(self, ax=None, n: int = 4000):
        """Draw the end displacement over the run, impacts marked, on ``ax`` (a new figure's axes
        if omitted) at ``n`` times: :func:`impactbar.plotting.plot_trajectory`, which returns the
        axes."""
        from ..plotting.simulation import plot_trajectory

        return plot_trajectory(self, ax, n)

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
        phi_contact = self._core.contact_shapes(x)  # (X, N)
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
        table = self.fields.select("table")
        return _tables.frame(
            {"impact": np.arange(self.n_impacts), **{f.item: f.get(self) for f in table}},
            {"impact": ("impact number", "1"), **{f.item: (f.long_name, f.units) for f in table}},
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
            {f.item: f"impact_{f.item}" for f in self.fields.select("table")})
        ds.attrs.pop("contact_intervals", None)
        if n:
            t = np.linspace(self.t0, self.t_end, n)
            end = _tables.to_xarray(_tables.frame(
                {"t": t, "end_displacement": self.end_displacement(t), "end_velocity": self.end_velocity(t)},
                {"t": ("time (load frame)", "1"), **END_MOTION.meta()}, index="t"))
            for name in END_MOTION.names:
                ds[name] = end[name]
        return ds


# --------------------------------------------------------------------------------------------------
# energy account by quadrature
# --------------------------------------------------------------------------------------------------


class _Deferred:
    """A field of :class:`Trajectory` that :meth:`Trajectory._deferred` leaves to its first read,
    like :func:`functools.cached_property`: a non-data descriptor, so the value in the instance's
    ``__dict__`` (every run's, once made) is found first; the first read makes it from the
    instance's ``_rows`` (``rows[0](name, *rows[1:])``) and stores it."""

    def __init__(self, name: str):
        self.name = name

    def __get__(self, obj, cls=None):
        if obj is None:
            return self
        d = obj.__dict__
        rows = d.get("_rows")
        if rows is None:
            raise AttributeError(f"{type(obj).__name__!r} object has no attribute {self.name!r}")
        return d.setdefault(self.name, rows[0](self.name, *rows[1:]))  # (a thread's first keeps it)


for _name in sorted(_DEFERRED):  # (set on the class after the dataclass: not fields' defaults)
    setattr(Trajectory, _name, _Deferred(_name))
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
        e = _panels(a, b, hmax, core.d)
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
        kap = core.contact_kappa
    for i in range(0, nodes.size, chunk):
        tt = nodes[i:i + chunk]
        _, v = core.propagate(seg.basis, ta, seg.q, seg.v, tt)
        ut0 = kap @ v  # u_t(0, t): v0 + 2 sum v_n, or 2 sum r_m'
        work += float(np.sum(weights[i:i + chunk] * core.load(tt) * ut0))
        if core.d:
            damp += core.d * float(np.sum(weights[i:i + chunk] * (kap @ (v * v))))
    qe, ve = core.propagate(seg.basis, ta, seg.q, seg.v, [tb])
    return work, damp, qe[:, 0], ve[:, 0]


def _panels(a: float, b: float, hmax: float, d: float) -> np.ndarray:
    """The quadrature panels' edges on ``[a, b]``: width ``hmax`` (the modes' and the load's fastest
    oscillation), and where the damping's decay is faster (``d > 1.5 / hmax``: the transient that a
    jump of the state or the load at ``a`` starts falls as ``exp(-d (t - a))``) widths from
    ``1.5 / d`` doubling up to ``hmax`` first, so that each 16-point Gauss panel sees at most a few
    e-folds of a transient not yet negligible (``hmax`` alone left a relative error of 2e-8 in the
    damping loss of a rigid bar at ``d = 30``)."""
    head = [a]
    h = 1.5 / d if d > 0.0 else math.inf
    while h < hmax and head[-1] + h < b:
        head.append(head[-1] + h)
        h *= 2.0
    n = max(1, math.ceil((b - head[-1]) / hmax))
    return np.concatenate((head[:-1], np.linspace(head[-1], b, n + 1)))


def _energy_nodes(core: _Core, span: float, n_segments: int) -> float:
    """An upper bound of the quadrature nodes :func:`_segment_integrals` uses over a run."""
    w2 = np.concatenate((core.free.w2, core.contact.w2))
    wmax = math.sqrt(float(np.max(w2))) if w2.size else 0.0
    kmax = float(np.max(core.data.ks)) if core.data.ks.size else 0.0
    jumps = core.data.breaks.size * (span / TWO_PI + 1.0) if core.data.kind == 1 else 0.0
    ratio = core.d / (wmax + kmax + 1.0)  # (_panels' doubling widths: at most ceil(log2 ratio) an interval)
    graded = 1.0 + (math.ceil(math.log2(ratio)) if ratio > 1.0 else 0.0)
    return _GL_X.size * (span * (wmax + kmax + 1.0) / 1.5 + (n_segments + jumps) * graded)


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
        if seg.basis == _WINDOW:  # a contact window: drive work, rod energy, projection
            window = seg.frozen
            dt = min(tb - seg.t, window.duration)
            w, rod, field_energy = window.account(dt)
            damp += window.damping(dt) if hasattr(window, "damping") else 0.0  # a sustained contact
            if dt >= window.duration:
                qe, ve = window.q_after, window.v_after
            else:
                qe, ve = window.state_at(dt)
            work += w
            imp += rod
            # the window starts from the modes plus the static correction (theory §4c): its energy
            # is a change of basis too
            proj += core.energy(_FREE, qe, ve) - field_energy + window.energy_before - \
                core.energy(_FREE, seg.q, seg.v)
            if j + 1 == len(segs):
                final = core.energy(_FREE, qe, ve)
            continue
        w, dl, qe, ve = _segment_integrals(core, seg, tb)
        work += w
        damp += dl
        if j + 1 < len(segs):
            nxt = segs[j + 1]
            if nxt.entry == "impact" and nxt.basis == _WINDOW:
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
