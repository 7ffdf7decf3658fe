r"""The bar's share of the circuit's compiled kernels (theory §11): the layout of the parameter vector
``par`` the drive writes (:meth:`HydraulicCircuitDrive._par <.drive.HydraulicCircuitDrive>`), the
piston's driven end and the bar's events, and the assembly of the variational equations, which the
code generated for every network's topology (:mod:`._netgen`, :mod:`._endgen`) calls.

The integrated state of a flight is ``Y = (q_0..q_N, q_0'..q_N', z, E[, Phi])``: the bar's modes
(eq. 6), the circuit's states ``z`` (its nodes' pressures, then the spool's opening), the energy
quadratures and, for the variational equations, the fundamental matrix ``Phi`` of the first ``n``
components, stored by columns (column ``j`` at ``n + n_E + j n``: each column's equations couple only
its own ``n`` components, so that the Newton matrix is banded, of half-bandwidth ``n - 1``),
``Phi' = A Phi`` with ``A`` the Jacobian of the vector field.

``par`` holds the few scalars the kernels read besides the network (indices below: the area ratio of
the blow's force, the valve's switches and whether each is armed, the bar's damping, its mode count
and whether the flight is variational), then from :data:`HEAD` the struck end's weights, the squared
frequencies and the driven end's weights (``M`` each), then the circuit's network of part records
(:mod:`._network`), which holds every part's own parameters.
"""

from __future__ import annotations

import numba as nb

from ..._shared.literals import plain_literals
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE

__all__ = ["end_motion", "bar_events", "phi_rate", "jac_blocks"]

# parameter indices in ``par``: the area ratio, the valve's switches and their arming, the bar's
ALPHA, XOUT, XIN, ARMO, ARMI, DAMP, NM, VAR = range(8)
HEAD = 8  # then the struck end's weights (M), the squared frequencies (M) and the driven end's (M)

#: the preset circuit's energy quadratures and its flight's events (the bar's three, then the
#: circuit's from :data:`RAMP_EV`)
N_ENERGY = 8
N_EVENTS = 6
ARRIVAL_EV, OUT_EV, IN_EV, RAMP_EV, ACC_EV, REL_EV = range(N_EVENTS)

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")  # (in memory where no cache is writable)


@nb.njit(**_JIT)
def end_motion(y, par, M):
    """The piston's driven end at ``y``: its displacement ``w`` away from where it is on the stop and
    its rate ``w'``, ``-sum e_i q_i`` and ``-sum e_i q_i'`` with the driven end's weights ``e``."""
    w = 0.0
    wd = 0.0
    for i in range(M):
        e = par[HEAD + 2 * M + i]
        w -= e * y[i]
        wd -= e * y[M + i]
    return w, wd


@nb.njit(**_JIT)
def phi_rate(A, y, yp, off):
    """``Phi' = A Phi`` into ``yp`` from ``Phi`` in ``y`` (another array), stored by columns from
    ``off`` (``n`` the order of ``A``)."""
    n = A.shape[0]
    # each entry of A Phi the sum over its row's nonzeros of A (some 9 M + 10 of n^2), from 0 in
    # increasing column (its zeros skipped), in place in yp: no scratch arrays
    for i in range(n):
        for j in range(n):
            yp[off + j * n + i] = 0.0
    for i in range(n):
        for k in range(n):
            a = A[i, k]
            if a != 0.0:
                for j in range(n):
                    yp[off + j * n + i] += a * y[off + j * n + k]


@nb.njit(**_JIT)
def jac_blocks(A, JJ, off):
    """``JJ`` zero but ``A`` in its leading block and, where ``off >= 0``, into the block of each column of
    ``Phi`` (stored by columns from ``off``): CVODE's Jacobian for its Newton iteration, the term in
    ``dA/dy Phi`` left out (the iteration matrix need not be exact), zero rows for the energy
    quadratures (they feed nothing back)."""
    N = JJ.shape[0]
    for i in range(N):
        for j in range(N):
            JJ[i, j] = 0.0
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            JJ[i, j] = A[i, j]
    if off >= 0:
        for col in range(n):  # Phi[:, col] at off + col n
            c = off + col * n
            for i in range(n):
                for k in range(n):
                    JJ[c + i, c + k] = A[i, k]


@nb.njit(**_JIT)
def bar_events(y, par, M, g):
    """The bar's and the valve's switches' event functions into ``g[:RAMP_EV]``: the arrival at the
    stop ``c . q``, the gap through ``switch_out`` and ``switch_in`` (where armed, else 1)."""
    s = 0.0
    for i in range(M):
        s += par[HEAD + i] * y[i]
    g[ARRIVAL_EV] = s
    g[OUT_EV] = -y[0] - par[XOUT] if par[ARMO] > 0.5 else 1.0
    g[IN_EV] = -y[0] - par[XIN] if par[ARMI] > 0.5 else 1.0


plain_literals(globals())  # one machine code per kernel for all constant arguments (end_motion's M = 1)
internal_kernels(globals(), from_python="compile")  # the generated kernels call them: link-only
