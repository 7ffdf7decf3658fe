r"""The circuit during a blow driven by CVODE from compiled code (theory §11, "The coupled blow"): the
vector field, Jacobian and events of :mod:`._endkernel` as compiled C callbacks, flown by
:func:`._cvode.fly` stretch after stretch in one compiled loop (:func:`fly_intervals`), so that no
Python runs between the circuit's events.

CVODE's user data is one array ``(len(par), a, 1/Z, par..., work...)``: the wave ``a`` arriving at
the driven end, constant over the stretch (the lattice's steps), the driven end's admittance ``1/Z``,
the kernels' parameters and the callbacks' room for their intermediate values (no allocation a
call). Where ``a`` varies within an interval as a cubic spline (the coupled exact blow's callables,
which carry it as their ``spline``), the spline of the interval follows the callbacks' room in the
user data (its knots and its coefficients, :func:`spline_data`) and :data:`SPLINE_CALLBACKS`' vector
field sets ``a`` from it at each call, by the Python callable's own arithmetic (:func:`spline_at`);
another callable goes
through scikit-sundae's Python interface instead (:func:`.endflight.circuit_end_flight`). The options
are those of :class:`._cvode.Workspace` (scikit-sundae's defaults), so either way takes the same
steps.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ...dynamics.kernels import CACHE
from . import _cvode as CV
from . import _endkernel as EK
from ._cvode import _c, _d, _dp, _p

__all__ = ["CALLBACKS", "SPLINE_CALLBACKS", "fly_intervals", "spline_data", "user_data"]

#: the user data's header: ``len(par)``, then ``ext`` (:mod:`._endkernel`: ``a, 1/Z``)
HD_NPAR, HD_EXT = 0, 1
_HEAD = HD_EXT + EK.EXT_SIZE


@nb.cfunc(_c(_d, _p, _p, _dp), cache=CACHE)
def _rhs_c(t, y, yp, user_data):
    """CVODE's ``CVRhsFn``: :func:`._endkernel.rhs`."""
    n = int(nb.carray(user_data, 1)[HD_NPAR])
    ud = nb.carray(user_data, _HEAD + n + EK.SCRATCH)
    EK.rhs_in(nb.carray(CV._nv_data(y), EK.N_STATE), nb.carray(CV._nv_data(yp), EK.N_STATE),
              ud[_HEAD:_HEAD + n], ud[HD_EXT:_HEAD], ud[_HEAD + n:])
    return 0


@nb.cfunc(_c(_d, _p, _p, _p, _dp, _p, _p, _p), cache=CACHE)
def _jac_c(t, y, fy, J, user_data, tmp1, tmp2, tmp3):
    """CVODE's ``CVLsJacFn``: :func:`._endkernel.jac` into the dense matrix (stored by columns)."""
    n = int(nb.carray(user_data, 1)[HD_NPAR])
    ud = nb.carray(user_data, _HEAD + n + EK.SCRATCH)
    JJ = nb.carray(CV._dense_data(J), (EK.N_STATE, EK.N_STATE)).T
    EK.jac_in(nb.carray(CV._nv_data(y), EK.N_STATE), JJ, ud[_HEAD:_HEAD + n], ud[HD_EXT:_HEAD],
              ud[_HEAD + n:])
    return 0


@nb.cfunc(_c(_d, _p, _dp, _dp), cache=CACHE)
def _events_c(t, y, g, user_data):
    """CVODE's ``CVRootFn``: :func:`._endkernel.events`."""
    n = int(nb.carray(user_data, 1)[HD_NPAR])
    ud = nb.carray(user_data, _HEAD + n)
    EK.events(nb.carray(CV._nv_data(y), EK.N_STATE), nb.carray(g, EK.N_EVENTS), ud[_HEAD:_HEAD + n])
    return 0


#: the callbacks of :func:`._cvode.workspace` for the circuit during a blow
CALLBACKS = (_rhs_c, _jac_c, _events_c, EK.N_EVENTS)


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


@nb.cfunc(_c(_d, _p, _p, _dp), cache=CACHE)
def _rhs_spline_c(t, y, yp, user_data):
    """CVODE's ``CVRhsFn`` with ``a`` from the interval's spline: :func:`._endkernel.rhs`."""
    n = int(nb.carray(user_data, 1)[HD_NPAR])
    base = _HEAD + n + EK.SCRATCH
    m = int(nb.carray(user_data, base + 1)[base])
    ud = nb.carray(user_data, base + 2 + m + 4 * (m - 1))
    ud[HD_EXT + EK.EXT_A] = spline_at(ud, base, t)
    EK.rhs_in(nb.carray(CV._nv_data(y), EK.N_STATE), nb.carray(CV._nv_data(yp), EK.N_STATE),
              ud[_HEAD:_HEAD + n], ud[HD_EXT:_HEAD], ud[_HEAD + n:base])
    return 0


#: the callbacks of :func:`._cvode.workspace` for the circuit during a blow, ``a`` a spline an interval
#: (the Jacobian's ``a`` the vector field's last, as scikit-sundae's Python callbacks share it)
SPLINE_CALLBACKS = (_rhs_spline_c, _jac_c, _events_c, EK.N_EVENTS)


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


def user_data(par: np.ndarray, a: float, impedance: float, room: int = 0) -> np.ndarray:
    """The user data of the callbacks: ``(len(par), a, 1/Z, par..., work...)``, shape
    ``(3 + len(par) + SCRATCH + room,)``, ``SCRATCH`` the callbacks' room for their intermediate
    values (:func:`._endkernel.rhs_in`), ``room`` that of an interval's spline (:func:`fly_intervals`)."""
    head = np.empty(_HEAD)
    head[HD_NPAR], head[HD_EXT + EK.EXT_A], head[HD_EXT + EK.EXT_IZ] = par.size, a, 1.0 / float(impedance)
    return np.concatenate((head, par, np.zeros(EK.SCRATCH + room)))


#: :func:`fly_intervals`' returns besides CVODE's flags: a state not finite at a stretch's end, a
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
    T2[:k], Y2[:k], F2[:k] = T[:k], Y[:k], F[:k]
    return T2, Y2, F2


@nb.njit(cache=CACHE, nogil=True)
def fly_intervals(mem, yvec, breaks, k, t, w, z, incoming, rtol, atol, directions, data, max_steps,
                  volumes, impulses, splines, offsets):
    r"""The stretches of :func:`.endflight.circuit_end_flight` from interval ``k`` at ``t`` (the
    driven end at ``w``, the circuit at ``z``) on through the intervals of ``breaks``, each a call of
    :func:`._cvode.fly` (CVODE re-initialised at each interval's start, the same steps), until the
    last break, a root of an event in ``directions`` (the caller jumps the circuit's mode and calls
    again), a failure or a chamber emptying.

    Parameters
    ----------
    mem, yvec : int
        The workspace of :data:`CALLBACKS` (:func:`._cvode.workspace`).
    breaks : numpy.ndarray, shape (n + 1,)
    k : int
        The interval to start in.
    t, w : float
    z : numpy.ndarray, shape (4,)
    incoming : numpy.ndarray, shape (n,)
        The wave ``a`` on each interval (written into the header's ``a`` in turn).
    rtol, atol : float
    directions : numpy.ndarray of int32, shape (3,)
    data : numpy.ndarray
        :func:`user_data` of the mode.
    max_steps : int
    volumes : numpy.ndarray, shape (3,)
        The rear and the front chamber's volumes and the area ratio.
    impulses : numpy.ndarray, shape (n,)
        ``int p dt`` over each interval, added to in place.
    splines, offsets : numpy.ndarray
        :func:`spline_data` (``offsets`` of size ``n + 1``): ``a`` on interval ``k`` the spline of
        block ``k``, copied after the callbacks' room in ``data`` (large enough: :func:`user_data`'s
        ``room``; the workspace's callbacks :data:`SPLINE_CALLBACKS`), ``incoming`` not read. Empty:
        ``a`` from ``incoming``.

    Returns
    -------
    flag : int
        1 the last break reached, 2 a root, CVODE's negative flag, or :data:`NOT_FINITE`,
        :data:`REAR_EMPTY`, :data:`FRONT_EMPTY`.
    k : int
        The interval where it stopped (``n`` at the last break).
    t : float
        The time there (the failing stretch's start where ``flag < 0``).
    T, Y, F : numpy.ndarray, shapes (S,), (S, 14), (S, 14)
        The pieces' steps, states and rates, one after the other (the repeated times dropped).
    starts : numpy.ndarray of int64, shape (P + 1,)
        Piece ``i`` at rows ``starts[i]:starts[i + 1]``.
    roots : numpy.ndarray of int32, shape (3,)
        CVODE's root information at a root.
    """
    n = breaks.size - 1
    N = EK.N_STATE
    T, Y, F = np.empty(256), np.empty((256, N)), np.empty((256, N))
    starts = np.zeros(n + 1, np.int64)
    P, S = 0, 0
    flag = 1
    roots = np.zeros(EK.N_EVENTS, np.int32)
    y0 = np.zeros(N)
    npar = int(data[HD_NPAR])
    par = data[_HEAD:_HEAD + npar]
    base = _HEAD + npar + EK.SCRATCH
    work = data[_HEAD + npar:base]
    spline = offsets.size > 0
    while k < n:
        t1 = breaks[k + 1]
        if not t < t1:
            k += 1
            continue
        if spline:
            size = offsets[k + 1] - offsets[k]
            data[base:base + size] = splines[offsets[k]:offsets[k + 1]]
        else:
            data[HD_EXT + EK.EXT_A] = incoming[k]
        y0[:] = 0.0
        y0[0] = w
        y0[1:5] = z
        flag, ts, ys, _, roots = CV.fly(mem, yvec, t, y0, t1, rtol, atol, directions, data, N, max_steps)
        ok = flag >= 0
        if ok:
            for j in range(N):
                if not np.isfinite(ys[ys.shape[0] - 1, j]):
                    ok = False
        if not ok:
            return flag if flag < 0 else NOT_FINITE, k, t, T[:S], Y[:S], F[:S], starts[:P + 1], roots
        T, Y, F = _grow(T, Y, F, S, S + ts.size)
        s0 = S
        for i in range(ts.size):
            if i == 0 or ts[i] - ts[i - 1] > 0.0:
                T[S] = ts[i]
                Y[S] = ys[i]
                S += 1
        for i in range(s0, S):
            if spline:
                data[HD_EXT + EK.EXT_A] = spline_at(data, base, T[i])
            EK.rhs_in(Y[i], F[i], par, data[HD_EXT:_HEAD], work)
        if P + 1 == starts.size:
            st2 = np.zeros(2 * starts.size, np.int64)
            st2[:P + 1] = starts[:P + 1]
            starts = st2
        P += 1
        starts[P] = S
        wmax, wmin = Y[s0, 0], Y[s0, 0]
        for i in range(s0 + 1, S):
            wmax = max(wmax, Y[i, 0])
            wmin = min(wmin, Y[i, 0])
        if volumes[0] - wmax <= 0.0:
            return REAR_EMPTY, k, t, T[:S], Y[:S], F[:S], starts[:P + 1], roots
        if volumes[1] + volumes[2] * wmin <= 0.0:
            return FRONT_EMPTY, k, t, T[:S], Y[:S], F[:S], starts[:P + 1], roots
        impulses[k] += Y[S - 1, 5]
        w = Y[S - 1, 0]
        z = Y[S - 1, 1:5].copy()
        te = T[S - 1]
        t = te if te < t1 else t1
        if flag == CV.CV_ROOT_RETURN:
            hit = False
            for i in range(EK.N_EVENTS):
                if roots[i] != 0:
                    hit = True
            if hit:
                return flag, k, t, T[:S], Y[:S], F[:S], starts[:P + 1], roots
    return 1, k, t, T[:S], Y[:S], F[:S], starts[:P + 1], roots
