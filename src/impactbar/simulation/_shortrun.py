"""A run's fixed cost: the first block of impacts of a run under an instantaneous
law, done by one call of the compiled kernel with the least Python around it. When that call ends
the run in flight (at ``max_impacts`` or ``t_end``, with no contact) the run's log of pieces is
built straight from the kernel's output (the start and one free flight per impact) and its final
state is the kernel's own (at ``t_end`` the kernel's flight stops there, in the arithmetic of the
flow the log evaluates); otherwise (chatter, a touch, more impacts than the block holds) the block
is handed to the general driver, which goes on from where the kernel stopped. Either way the result
is the general driver's, to the bit (``tests/simulation/test_shortrun.py``; the switch
``"simulate.short_run"`` of :mod:`impactbar.dynamics.implementations` runs the general driver from
the start)."""

from __future__ import annotations

import threading
from typing import NamedTuple

import numpy as np

from .._shared.status import RunStatus
from ..dynamics import compiled as K
from .trajectory import _FREE, Trajectory, _Segments

#: a run that asks for at most this many impacts (``max_impacts``) takes no Ctrl-C handler, however
#: long its span (:func:`~impactbar.simulate`)
SHORT_RUN_IMPACTS = 256
#: the impacts of a run's first block: the general driver's first block (its log's first rows), so
#: that a run's blocks, and with them its bits, are the same on both paths
FIRST_BLOCK = 1024
#: the rows of a block's log ``TV``: the pieces' times, the impacts' arrival velocities
TV_T, TV_V = 0, 1

# the pieces' kinds, shared read-only by every short run's log: a run of n impacts gets _KINDS[n],
# views of the first n + 1 (made once: slicing them per run was a short run's cost)
_BASIS = np.full(FIRST_BLOCK + 1, _FREE, dtype=np.int8)  # all free flights
_ENTRY = np.ones(FIRST_BLOCK + 1, dtype=np.int8)  # 'impact' ...
_ENTRY[0] = 0  # ... after the 'start'
_BASIS.setflags(write=False)
_ENTRY.setflags(write=False)
_KINDS = [(_BASIS[:n + 1], _ENTRY[:n + 1]) for n in range(FIRST_BLOCK + 1)]

_ENTRY_POINTS: dict = {}  # dispatcher -> the compiled entry point for Python's argument types


def entry_point(dispatcher, args):
    """The compiled entry point of a numba dispatcher for the types of ``args`` (called without
    typing its arguments: every later call passes the same types), else the dispatcher itself (not
    compiled for those types yet, or numba's JIT disabled). The types are checked on the first
    call only; the dispatcher may also hold overloads compiled for other callers, such as a kernel
    that passes a literal (``run_free`` called by the valve's loop with ``max_imp`` the literal 1),
    whose entry point would read these arguments with that other signature."""
    hit = _ENTRY_POINTS.get(dispatcher)
    if hit is not None:
        return hit
    overloads = getattr(dispatcher, "overloads", None)
    if not overloads:
        return dispatcher
    from numba import typeof

    compiled = overloads.get(tuple(typeof(a) for a in args))
    if compiled is None:
        return dispatcher
    _ENTRY_POINTS[dispatcher] = compiled.entry_point
    return compiled.entry_point


class FirstBlock(NamedTuple):
    """The kernel's first call of a run it did not end: what the general driver goes on from."""

    n: int  # impacts done
    status: int  # the kernel's status (CHATTER, CONTACT, FULL, FAILED)
    t: float  # where it stopped
    times: np.ndarray  # (n,) the impacts' times and arrival velocities
    velocities: np.ndarray
    q: np.ndarray  # (n + 1, N + 1): the start's state and the states after the impacts
    v: np.ndarray


#: runs of at most this many modal coordinates reuse their thread's buffers for the first block
#: (2 x 1025 x M floats: 4 MB at 256; one set per thread, for the last M it ran); a larger run
#: allocates its own for the rows it may use
POOLED_MODES = 256
_POOL = threading.local()


class _Block:
    """Buffers for a run's first block of ``FIRST_BLOCK`` impacts, ``M`` modal coordinates: ``QV``
    the states (``[0]`` displacements, ``[1]`` velocities; row 0 the start), ``TV`` the pieces'
    times (``[0]``: the start's, then the impacts') and the impacts' arrival velocities (``[1]``,
    from column 1), the kernel's output views of them, made once, and views of their first rows
    (:meth:`first`), made once each."""

    __slots__ = ("M", "QV", "TV", "q0", "v0", "out", "_first")

    def __init__(self, M, rows=FIRST_BLOCK):
        self.M = M
        self.QV = np.empty((2, rows + 1, M))
        self.TV = np.empty((2, rows + 1))
        Q, V = self.QV
        self.q0, self.v0 = Q[0], V[0]
        self.out = (self.TV[TV_T, 1:], self.TV[TV_V, 1:], Q[1:], V[1:])
        self._first = [None] * (rows + 2)

    def first(self, k):
        """Views ``TV[:, :k], QV[:, :k]`` of the first ``k`` rows (each made once: slicing costs
        0.2 us an array)."""
        views = self._first[k]
        if views is None:
            views = self._first[k] = (self.TV[:, :k], self.QV[:, :k])
        return views


def _block(M, max_imp) -> _Block:
    """This thread's buffers for ``M`` modal coordinates, made anew where the last run's had
    another ``M``; beyond ``POOLED_MODES``, fresh ones of ``min(max_imp, FIRST_BLOCK)`` rows."""
    if M > POOLED_MODES:
        return _Block(M, min(max_imp, FIRST_BLOCK))
    b = _POOL.block = _Block(M)
    return b


def run_short(core, q, v, t0, t_end, max_imp, state) -> tuple[Trajectory | None, FirstBlock | None]:
    """The run from ``(t0, q, v)`` as :func:`~impactbar.simulate`'s general driver gives it when the
    kernel's first call ends it in flight (status ``END`` or ``MAXIMP``): ``(trajectory, None)``;
    otherwise ``(None, block)``, with ``q, v`` the kernel's state where it stopped. ``state`` makes
    the final state from two arrays (``InitialState._trusted``); ``t0, t_end`` are floats and
    ``max_imp`` an int (the kernel's entry point takes no others).

    The kernel writes into buffers of ``FIRST_BLOCK`` impacts whatever ``max_imp`` (below it, it
    stops at ``max_imp``, ``MAXIMP``, before the buffers are full, as in the general driver's first
    block of ``max_imp`` rows); the rows used are copied out."""
    M = q.size
    b = getattr(_POOL, "block", None)
    if b is None or b.M != M:
        b = _block(M, max_imp)
    b.q0[...] = q  # (faster than Q[0] = q)
    b.v0[...] = v
    TV = b.TV
    TV[TV_T, 0] = t0
    # (the kernel overwrites its start with its state where it stops)
    n, st, tn = core.run_block(t0, q, v, t_end, max_imp, b.out, True)
    k = n + 1
    if st == K.MAXIMP:  # ended on the last impact: the state after it is in q, v (and row n)
        t, status = tn, RunStatus.MAX_IMPACTS
    elif st == K.END:  # q, v: the flight's state at t_end, as the log's flow gives it
        t, status = t_end, RunStatus.T_END
        if n and TV[TV_T, n] == t_end:  # the last impact at t_end itself: the state after it
            q, v = b.QV[0, n].copy(), b.QV[1, n].copy()
    else:  # the rows the general driver goes on from (copies: the buffers serve the next run)
        tv, qv = (a.copy() for a in b.first(k))
        return None, FirstBlock(n, st, tn, tv[TV_T, 1:], tv[TV_V, 1:], qv[0], qv[1])
    # the rows used, copied (both states in one copy, and no unpacking: iterating a numpy array costs
    # 2 us; a compiled copy returning the arrays costs more than these, 0.5 us per array returned);
    # the result's arrays are made from them when first read
    tv, qv = b.first(k)
    rows = (_field, n, tv.copy(), qv.copy(), q, v, state)  # (a tuple: a NamedTuple costs 0.3 us)
    return Trajectory._deferred(core.model, core.load, t0, t, _NO_CONTACTS, status, core, rows), None


def _field(name, n, tv, qv, q, v, state):
    """The :class:`~impactbar.Trajectory` field ``name`` a short run leaves to its first read
    (``Trajectory._deferred``), from the kernel's output copied out of the buffers: ``tv`` the
    pieces' times and the ``n`` impacts' arrival velocities (as ``_Block.TV``), ``qv`` the pieces'
    start states (as ``_Block.QV``), ``q, v`` the final state, ``state`` what makes it an
    ``InitialState``."""
    if name == "impact_times":
        return tv[TV_T, 1:].copy()  # (not a view of the log's times)
    if name == "impact_velocities":
        return tv[TV_V, 1:]
    if name == "final_state":
        return state(q, v)
    basis, entry = _KINDS[n]
    return _Segments(qv.shape[2] - 1, tv[TV_T], basis, entry, qv[0], qv[1], {})


_NO_CONTACTS = np.zeros((0, 2))
_NO_CONTACTS.setflags(write=False)
