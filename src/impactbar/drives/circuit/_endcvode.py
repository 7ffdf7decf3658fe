r"""The circuit during a blow driven by CVODE from compiled code (theory §11, "The coupled blow"): what
the generated modules of :mod:`._endgen` share (their vector field, Jacobian and events as compiled C
callbacks, flown by :func:`._cvode.fly` stretch after stretch in one compiled loop,
``fly_intervals``, so that no Python runs between the circuit's events): the callbacks' user data,
the splines of the arriving wave and the loop's flags.

CVODE's user data is one array ``(len(par), a, 1/Z, par..., work...)``: the wave ``a`` arriving at
the driven end, constant over the stretch (the lattice's steps), the driven end's admittance ``1/Z``,
the kernels' parameters and the callbacks' room for their intermediate values (no allocation a
call). Where ``a`` varies within an interval as a cubic spline (the coupled exact blow's callables,
which carry it as their ``spline``), the spline of the interval follows the callbacks' room in the
user data (its knots and its coefficients, :func:`spline_data`) and ``SPLINE_CALLBACKS``' vector
field sets ``a`` from it at each call, by the Python callable's own arithmetic (:func:`spline_at`);
another callable goes
through scikit-sundae's Python interface instead (:func:`.endflight.circuit_end_flight`). The options
are those of :class:`._cvode.Workspace` (scikit-sundae's defaults), so either way takes the same
steps.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ..._shared.literals import plain_literals
from ...dynamics.compiled import CACHE
from . import _cvode as CV  # noqa: F401  (the SUNDIALS libraries bound: a module that imports this flies compiled)
from . import _endgen as EK

__all__ = ["spline_data", "user_data", "spline_at"]

#: the user data's header: ``len(par)``, then ``ext`` (:mod:`._endgen`: ``a, 1/Z``)
HD_NPAR, HD_EXT = 0, 1
_HEAD = HD_EXT + EK.EXT_SIZE


@nb.njit(cache=CACHE, nogil=True)
def spline_at(ud, base, t):
    """The wave ``a`` at the time ``t`` from the spline at ``ud[base:]`` (:func:`spline_data`):
    the Python callable's arithmetic (:func:`impactbar.laws.rodrock.coupled_exact._spline_callable`: its
    interval as ``bisect_right``'s, the end ones extended)."""
    m = int(ud[base])
    t0 = ud[base + 1]
    xs = ud[base + 2:base + 2 + m]
    c = base + 2 + m
    n = m - 1
    tt = t - t0
    i = min(max(np.searchsorted(xs, tt, side="right") - 1, 0), n - 1)
    s = tt - xs[i]
    s2 = s * s
    return ((ud[c + 3 * n + i] + ud[c + 2 * n + i] * s) + ud[c + n + i] * s2) + ud[c + i] * (s2 * s)


def spline_data(incoming):
    """The splines of the callables ``incoming`` (one an interval, each with its ``spline``: knots ``x``,
    scipy's coefficients ``c`` of shape ``(4, m - 1)``, ``(x - x_i)^3`` first, and the time ``t0`` it
    is shifted by: :func:`impactbar.laws.rodrock.coupled_exact._spline_callable`'s) as one array and
    each one's offset in it (shape ``(n + 1,)``): a spline's block ``(m, t0, x..., c[0]..., c[1]...,
    c[2]..., c[3]...)``."""
    blocks = []
    for a in incoming:
        x, c, t0 = a.spline
        blocks.append(np.concatenate(([float(x.size), t0], x, c.ravel())))
    offsets = np.concatenate(([0], np.cumsum([b.size for b in blocks]))).astype(np.int64)
    return np.concatenate(blocks), offsets


def user_data(par: np.ndarray, a: float, impedance: float, scratch: int, room: int = 0) -> np.ndarray:
    """The user data of the callbacks: ``(len(par), a, 1/Z, par..., work...)``, shape
    ``(3 + len(par) + scratch + room,)``, ``scratch`` the callbacks' room for their intermediate
    values (the generated module's ``SCRATCH``), ``room`` that of an interval's spline (the generated
    ``fly_intervals``)."""
    head = np.empty(_HEAD)
    head[HD_NPAR], head[HD_EXT + EK.EXT_A], head[HD_EXT + EK.EXT_IZ] = par.size, a, 1.0 / float(impedance)
    return np.concatenate((head, par, np.zeros(scratch + room)))


#: the generated ``fly_intervals``' returns besides CVODE's flags: a state not finite at a stretch's end, a
#: chamber emptied (``V <= 0``) in the stretch
NOT_FINITE, REAR_EMPTY, FRONT_EMPTY = -1000, -1001, -1002


@nb.njit(cache=CACHE, nogil=True)
def _grow(T, Y, F, k, need):
    """``T, Y, F`` with room for ``need`` rows (doubled), their first ``k`` rows kept."""
    cap = T.size
    if need <= cap:
        return T, Y, F
    while cap < need:
        cap *= 2
    T2, Y2, F2 = np.empty(cap), np.empty((cap, Y.shape[1])), np.empty((cap, Y.shape[1]))
    for r in range(k):  # (element by element: a slice assignment compiles numba's shape-error message)
        T2[r] = T[r]
        for i in range(Y.shape[1]):
            Y2[r, i] = Y[r, i]
            F2[r, i] = F[r, i]
    return T2, Y2, F2


plain_literals(globals())  # one machine code per kernel for all constant arguments (_grow's first row 0)
