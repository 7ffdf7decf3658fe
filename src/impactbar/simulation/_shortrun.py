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


def run_short(core, q, v, t0, t_end, max_imp, state) -> Trajectory | None:
    """The run from ``(t0, q, v)`` (``q, v`` left unchanged) as :func:`~impactbar.simulate`'s
    general driver gives it, when the kernel's one call ends it in flight (status ``END`` or
    ``MAXIMP``); None otherwise. ``state`` makes the final state from two arrays
    (``InitialState._trusted``)."""
    M = q.size
    Q = np.empty((max_imp + 1, M))
    V = np.empty((max_imp + 1, M))
    Q[0] = q
    V[0] = v
    qk, vk = q.copy(), v.copy()  # the kernel overwrites its start with the final state
    n, st, tn, ot, ov = core.run_free(t0, qk, vk, t_end, max_imp, Q[1:], V[1:])
    if st == K.END:
        t, status = t_end, RunStatus.T_END
    elif st == K.MAXIMP:
        t, status = tn, RunStatus.MAX_IMPACTS
    else:
        return None
    ts = np.empty(n + 1)
    ts[0] = t0
    ts[1:] = ot
    if t == ts[n]:  # the run ended on a piece's start (max_impacts)
        qe, ve = Q[n].copy(), V[n].copy()
    else:
        qe, ve = core.propagate(_FREE, ts[n], Q[n], V[n], [t])
        qe, ve = qe[:, 0], ve[:, 0]
    entry = np.ones(n + 1, dtype=np.int8)  # 'impact'
    entry[0] = 0  # 'start'
    segs = _Segments(M - 1, ts, np.zeros(n + 1, dtype=np.int8), entry, Q[:n + 1], V[:n + 1], {})
    return Trajectory(model=core.model, load=core.load, t0=t0, t_end=t,
                      impact_times=ot if 2 * n >= ot.base.size else ot.copy(),
                      impact_velocities=ov if 2 * n >= ov.base.size else ov.copy(),
                      contact_intervals=np.zeros((0, 2)),
                      final_state=state(qe, ve), status=status, _core=core,
                      _segments=segs, n_release_retries=0)
