"""A short run's fixed cost (issue 20): the driver's path for a run under an instantaneous law that
stops at ``max_impacts`` or ``t_end`` in flight, with no contact, in one call of the compiled
kernel. It builds the run's log of pieces straight from the kernel's output (the start and one
free flight per impact) instead of through the general driver's growing log, and gives the same
result to the bit; any other run (chatter, a touch, more impacts than one block holds) is left to
the general driver, which computes it from the start again."""

from __future__ import annotations

import numpy as np

from .._shared.status import RunStatus
from ..dynamics import _kernel as K
from .trajectory import _FREE, Trajectory, _Segments

#: the most impacts a run may ask for (``max_impacts``) to take this path: a run that meets a
#: contact is computed again by the general driver, so at most this many impacts are done twice
SHORT_RUN_IMPACTS = 256

# the pieces' kinds, shared read-only by every short run's log: a run of n impacts gets _KINDS[n],
# views of the first n + 1 (made once: slicing them per run was a short run's cost)
_BASIS = np.full(SHORT_RUN_IMPACTS + 1, _FREE, dtype=np.int8)  # all free flights
_ENTRY = np.ones(SHORT_RUN_IMPACTS + 1, dtype=np.int8)  # 'impact' ...
_ENTRY[0] = 0  # ... after the 'start'
_BASIS.setflags(write=False)
_ENTRY.setflags(write=False)
_KINDS = [(_BASIS[:n + 1], _ENTRY[:n + 1]) for n in range(SHORT_RUN_IMPACTS + 1)]

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


def run_short(core, q, v, t0, t_end, max_imp, state) -> Trajectory | None:
    """The run from ``(t0, q, v)`` as :func:`~impactbar.simulate`'s general driver gives it, when the
    kernel's one call ends it in flight (status ``END`` or ``MAXIMP``); None otherwise, with ``q,
    v`` as they came. ``state`` makes the final state from two arrays (``InitialState._trusted``);
    ``t0, t_end`` are floats and ``max_imp`` an int (the kernel's entry point takes no others)."""
    M = q.size
    Q = np.empty((max_imp + 1, M))
    V = np.empty((max_imp + 1, M))
    Q[0] = q
    V[0] = v
    # (the kernel overwrites its start with the final state)
    n, st, tn, ot, ov = core.run_free(t0, q, v, t_end, max_imp, Q[1:], V[1:], direct=True)
    if st == K.MAXIMP:  # ended on the last impact: the state after it is in q, v (and Q[n])
        t, status = tn, RunStatus.MAX_IMPACTS
    elif st == K.END:
        t, status = t_end, RunStatus.T_END
        Q, V = Q[:n + 1], V[:n + 1]
    else:
        q[:] = Q[0]
        v[:] = V[0]
        return None
    ts = np.empty(n + 1)
    ts[0] = t0
    ts[1:] = ot
    if st == K.MAXIMP:
        qe, ve = q, v
    elif t == ts[n]:  # the last impact at t_end itself
        qe, ve = Q[n].copy(), V[n].copy()
    else:
        qe, ve = core.propagate(_FREE, ts[n], Q[n], V[n], [t])
        qe, ve = qe[:, 0], ve[:, 0]
    segs = _Segments(M - 1, ts, *_KINDS[n], Q, V, {})
    whole = 2 * n >= max_imp  # (ot, ov: the first n of the kernel's max_imp; copied where mostly unused)
    # the dataclass's fields set at once (its __init__ sets them one by one: a short run's cost)
    traj = object.__new__(Trajectory)
    traj.__dict__.update(model=core.model, load=core.load, t0=t0, t_end=t,
                         impact_times=ot if whole else ot.copy(),
                         impact_velocities=ov if whole else ov.copy(),
                         contact_intervals=np.zeros((0, 2)), final_state=state(qe, ve), status=status,
                         _core=core, _segments=segs, n_release_retries=0)
    return traj
