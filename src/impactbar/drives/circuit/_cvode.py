r"""CVODE driven from compiled code: one flight of the circuit in one call of machine code (theory §11).

The flight's loop (:func:`fly`: ``CVode`` in one-step mode, each step's state kept) is compiled by
numba and calls SUNDIALS' CVODE (bound by :mod:`._sundials`), which calls back the vector field,
its Jacobian and the event functions of the code generated for the circuit's network
(:mod:`._netgen`'s ``CALLBACKS``, :mod:`._endgen`'s) as compiled C callbacks (:func:`numba.cfunc`):
no Python runs between a flight's start and its end. CVODE's options are scikit-sundae's defaults
(BDF of orders 1 to 5, Newton's method with a direct solver and the
analytic Jacobian, at most 3 Newton iterations a step, 10 convergence failures), so that a flight
takes the same steps as through scikit-sundae's interface, to the bit (a test); the variational
flights take the band solver where scikit-sundae's takes the dense one, the same to rounding, its
LU and solve taken on the Newton matrix's blocks (:class:`Workspace`'s ``blocks``: the band
solver's operations on each block, the same steps to the bit).

Each thread keeps one CVODE workspace per system size and solver (:func:`workspace`),
re-initialised at each flight (``CVodeReInit``) rather than built anew.
"""

from __future__ import annotations

import ctypes
import threading
import weakref

import numba as nb
import numpy as np
from numba import types

from ..._shared.literals import plain_literals
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from . import _sundials as S
from ._dop853 import keep_row

if not S.bind():  # pragma: no cover - imported only where available (flight.py)
    raise ImportError(f"CVODE cannot be driven from compiled code here: {S.reason()}")

__all__ = ["fly", "fly_split", "workspace", "last_workspace", "Workspace", "Callback", "callback",
           "CV_ROOT_RETURN", "CV_TSTOP_RETURN", "CV_TOO_MUCH_WORK"]

CV_ADAMS, CV_BDF, CV_ONE_STEP = 1, 2, 2
CV_SUCCESS, CV_TSTOP_RETURN, CV_ROOT_RETURN, CV_TOO_MUCH_WORK = 0, 1, 2, -1

_p, _c, _d = types.intp, types.intc, types.double  # pointers as integers of their size
_dp = types.CPointer(types.double)


def _ext(name, sig):
    return types.ExternalFunction(S.PREFIX + name, sig)


_nv_data = _ext("N_VGetArrayPointer", _dp(_p))
_dense_data = _ext("SUNDenseMatrix_Data", _dp(_p))
_band_data = _ext("SUNBandMatrix_Data", _dp(_p))
_band_ldim = _ext("SUNBandMatrix_LDim", types.int64(_p))
_band_smu = _ext("SUNBandMatrix_StoredUpperBandwidth", types.int64(_p))
_band_ml = _ext("SUNBandMatrix_LowerBandwidth", types.int64(_p))
_band_mu = _ext("SUNBandMatrix_UpperBandwidth", types.int64(_p))
_band_cols = _ext("SUNBandMatrix_Columns", types.int64(_p))
_reinit = _ext("CVodeReInit", _c(_p, _d, _p))
_tolerances = _ext("CVodeSStolerances", _c(_p, _d, _d))
_vector_tolerances = _ext("CVodeSVtolerances", _c(_p, _d, _p))
_user_data = _ext("CVodeSetUserData", _c(_p, _p))
_root_direction = _ext("CVodeSetRootDirection", _c(_p, _p))
_stop_time = _ext("CVodeSetStopTime", _c(_p, _d))
_clear_stop = _ext("CVodeClearStopTime", _c(_p))
_step = _ext("CVode", _c(_p, _d, _p, _p, _c))
_root_info = _ext("CVodeGetRootInfo", _c(_p, _p))


class Callback:
    """A C callback (:func:`numba.cfunc`) compiled where its :attr:`address` is first read (a flight's
    workspace: :class:`Workspace`), not where it is defined: a flight that takes one Jacobian (the
    dense one or the band one) compiles only that one.

    Parameters
    ----------
    signature : numba signature
        The C signature, as :func:`numba.cfunc` takes it.
    pyfunc : callable
        The callback's Python function.
    cache : bool
        Whether numba caches its machine code.
    """

    def __init__(self, signature, pyfunc, cache: bool):
        self._args = (signature, pyfunc, bool(cache))
        self._cfunc = None
        self._lock = threading.Lock()

    @property
    def address(self) -> int:
        """The compiled callback's address (compiled, or loaded from numba's cache, on first use)."""
        if self._cfunc is None:
            with self._lock:
                if self._cfunc is None:
                    signature, pyfunc, cache = self._args
                    self._cfunc = nb.cfunc(signature, cache=cache)(pyfunc)
        return self._cfunc.address

    @property
    def cfunc(self):
        """numba's compiled callback (:class:`numba.core.ccallback.CFunc`), ``None`` before first use."""
        return self._cfunc


def callback(signature, cache: bool):
    """Decorator: the function as a :class:`Callback` of the C signature ``signature`` (compiled on
    first use; numba's cache as ``cache`` says: the caller passes its module's ``cache=`` option, so
    that a cache folder found unwritable at import compiles in memory)."""
    return lambda pyfunc: Callback(signature, pyfunc, cache)


_LOW32 = 0xFFFFFFFF  # a sunindextype result: the low 32 bits hold it whether it is int or int64_t


@nb.njit(inline="always")
def band_blocks(A, J, N, n_energy):
    """The band matrix ``J`` (``N x N``) zero but ``A`` (``n x n``) on the state's block and on each
    column of ``Phi``'s (from ``n + n_energy``: ``(N - n - n_energy) / n`` of them, none in a plain
    flight), element ``(i, j)`` at ``data[j ldim + smu + i - j]``."""
    n = A.shape[0]
    ldim = _band_ldim(J) & _LOW32
    smu = _band_smu(J) & _LOW32
    data = nb.carray(_band_data(J), N * ldim)
    data[:] = 0.0
    for blk in range(1 + (N - n - n_energy) // n):  # the state, then each column of Phi
        base = 0 if blk == 0 else n + n_energy + (blk - 1) * n
        for j in range(n):
            col = (base + j) * ldim + smu - j
            for i in range(n):
                data[col + i] = A[i, j]


@nb.njit(cache=CACHE, nogil=True)
def _block_factor(data, n, ldim, smu):
    """SUNDIALS' band LU (``SUNDlsMat_bandGBTRF``: partial pivoting, the multipliers stored negated)
    of the leading ``n x n`` block of the band matrix ``data`` (element ``(i, j)`` at
    ``data[j ldim + smu + i - j]``), in place, its pivots kept (as numbers) in the storage of column
    ``n`` above its band; 0, or ``k + 1`` at a zero pivot in column ``k``. On the variational
    flights' block-diagonal Newton matrix (the state's block, the energies' identity, each column of
    ``Phi``'s block equal to the state's) the band LU of the whole matrix takes on each block the
    operations taken here, in the same order, the entries outside the blocks staying zero."""
    piv = n * ldim
    for k in range(n):
        ck = k * ldim + smu - k  # (i, k) at ck + i
        l = k
        big = abs(data[ck + k])
        for i in range(k + 1, n):
            if abs(data[ck + i]) > big:
                l = i
                big = abs(data[ck + i])
        data[piv + k] = l
        if data[ck + l] == 0.0:
            return k + 1
        if k == n - 1:
            break
        if l != k:
            tmp = data[ck + l]
            data[ck + l] = data[ck + k]
            data[ck + k] = tmp
        mult = -1.0 / data[ck + k]
        for i in range(k + 1, n):
            data[ck + i] *= mult
        for j in range(k + 1, n):
            cj = j * ldim + smu - j
            a_kj = data[cj + l]
            if l != k:
                data[cj + l] = data[cj + k]
                data[cj + k] = a_kj
            if a_kj != 0.0:
                for i in range(k + 1, n):
                    data[cj + i] += a_kj * data[ck + i]
    return 0


@nb.njit(cache=CACHE, nogil=True)
def _block_solve(data, n, ldim, smu, x, n_energy, m):
    """SUNDIALS' band solve (``SUNDlsMat_bandGBTRS``) with :func:`_block_factor`'s LU on the state's
    ``n`` components of ``x`` and each column of ``Phi``'s (from ``n + n_energy``), in place: the
    ``m`` right-hand sides (``n + 1`` in a variational flight, the state's alone in a plain one) side by
    side (each row's contiguous), each component given the band solve's operations in its order (the
    same products, the same sums); ``n_energy`` the energies' rows between the state and ``Phi``."""
    B = np.empty((n, m))
    for c in range(m):
        start = 0 if c == 0 else n + n_energy + (c - 1) * n
        for i in range(n):
            B[i, c] = x[start + i]
    piv = n * ldim
    for k in range(n - 1):
        l = int(data[piv + k])
        if l != k:
            for c in range(m):
                tmp = B[l, c]
                B[l, c] = B[k, c]
                B[k, c] = tmp
        ck = k * ldim + smu - k
        for i in range(k + 1, n):
            lik = data[ck + i]
            for c in range(m):
                B[i, c] += B[k, c] * lik
    for k in range(n - 1, -1, -1):
        ck = k * ldim + smu - k
        ukk = data[ck + k]
        for c in range(m):
            B[k, c] /= ukk
        for i in range(k):
            uik = data[ck + i]
            for c in range(m):
                B[i, c] += (-B[k, c]) * uik
    for c in range(m):
        start = 0 if c == 0 else n + n_energy + (c - 1) * n
        for i in range(n):
            x[start + i] = B[i, c]


# the C callbacks below call them (compiled at their definition): link-only, their machine code the callbacks'
internal_kernels(globals(), from_python="compile")


@nb.cfunc(_c(_p, _p), cache=CACHE)
def _block_setup_c(S, A):
    """``SUNLinearSolver``'s ``setup`` for the variational flights' band matrix: :func:`_block_factor`
    of its state's block (half-bandwidths ``n - 1``); positive at a zero pivot (recoverable, as the
    band solver's failure)."""
    ldim = _band_ldim(A) & _LOW32
    n = (_band_ml(A) & _LOW32) + 1
    data = nb.carray(_band_data(A), (_band_cols(A) & _LOW32) * ldim)
    return 8 if _block_factor(data, n, ldim, _band_smu(A) & _LOW32) else 0  # (SUNLS_LUFACT_FAIL)


@nb.cfunc(_c(_p, _p, _p, _p, _d), cache=CACHE)
def _block_solve_c(S, A, x, b, tol):
    """``SUNLinearSolver``'s ``solve``: ``x`` from ``b`` by :func:`_block_solve` on the state's block
    and each column of ``Phi``'s (the energies' rows: the identity's); a plain flight's matrix (its
    upper bandwidth ``n``, one more than its lower: :class:`Workspace`'s ``plain``) on the state's
    block alone."""
    N = _band_cols(A) & _LOW32
    ldim = _band_ldim(A) & _LOW32
    smu = _band_smu(A) & _LOW32
    n = (_band_ml(A) & _LOW32) + 1
    data = nb.carray(_band_data(A), N * ldim)
    xx = nb.carray(_nv_data(x), N)
    bb = nb.carray(_nv_data(b), N)
    for i in range(N):
        xx[i] = bb[i]
    plain = (_band_mu(A) & _LOW32) >= n
    _block_solve(data, n, ldim, smu, xx, N - n if plain else N - n - n * n, 1 if plain else n + 1)
    return 0


@nb.njit(cache=CACHE, nogil=True)
def fly(mem, yvec, t0, y0, t_end, rtol, atol, directions, par, keep, max_steps):
    """One flight: CVODE from ``y0`` at ``t0`` to its first root (a terminal event in
    ``directions``) or ``t_end``, every step kept.

    Parameters
    ----------
    mem, yvec : int
        The workspace's CVODE memory and state vector (:class:`Workspace`), its size ``y0.size``.
    t0, t_end : float
    y0 : numpy.ndarray, shape (N,)
    rtol, atol : float
    directions : numpy.ndarray of int32, shape (E,)
        Each event's direction (CVODE's root directions; as many as the workspace's events).
    par : numpy.ndarray
        The kernels' parameters (:mod:`._bar`, the network after them).
    keep : int
        The leading components kept at each step.
    max_steps : int

    Returns
    -------
    flag : int
        CVODE's last return: 2 a root, 1 ``t_end`` reached, negative a failure (-1 ``max_steps``).
    t : numpy.ndarray, shape (S,)
    y : numpy.ndarray, shape (S, keep)
    y_end : numpy.ndarray, shape (N,)
    roots : numpy.ndarray of int32, shape (E,)
        CVODE's root information at a root (nonzero where an event function crossed), else 0.
    """
    y = nb.carray(_nv_data(yvec), y0.size)
    for i in range(y0.size):
        y[i] = y0[i]
    flag = _reinit(mem, t0, yvec)
    if flag == 0:
        flag = _tolerances(mem, rtol, atol)
    return _steps(mem, yvec, flag, t0, y0, t_end, directions, par, keep, max_steps)


@nb.njit(cache=CACHE, nogil=True)
def fly_split(mem, yvec, t0, y0, t_end, rtol, atol, split, atol_after, atol_vec, directions, par, keep,
              max_steps):
    """:func:`fly` with CVODE's absolute tolerance ``atol`` on the components before ``split`` and
    ``atol_after`` from it (``CVodeSVtolerances``; a variational flight's fundamental matrix from
    ``split``), written into ``atol_vec`` (the workspace's :attr:`Workspace.atol`, of ``y0.size``):
    arguments and returns otherwise :func:`fly`'s."""
    N = y0.size
    y = nb.carray(_nv_data(yvec), N)
    for i in range(N):
        y[i] = y0[i]
    weights = nb.carray(_nv_data(atol_vec), N)
    weights[:split] = atol
    weights[split:] = atol_after
    flag = _reinit(mem, t0, yvec)
    if flag == 0:
        flag = _vector_tolerances(mem, rtol, atol_vec)
    return _steps(mem, yvec, flag, t0, y0, t_end, directions, par, keep, max_steps)


@nb.njit(inline="always")
def _steps(mem, yvec, flag, t0, y0, t_end, directions, par, keep, max_steps):
    """:func:`fly`'s loop after CVODE's re-initialisation and tolerances (``flag`` theirs)."""
    N = y0.size
    y = nb.carray(_nv_data(yvec), N)
    roots = np.zeros(directions.size, np.int32)
    if flag == 0:
        flag = _user_data(mem, par.ctypes.data)
    if flag == 0:
        flag = _root_direction(mem, directions.ctypes.data)
    if flag == 0:
        flag = _stop_time(mem, t_end)
    T, Y = keep_row(np.empty(512), np.empty((512, keep)), 0, t0, y0)
    k = 1
    tret = np.zeros(1)
    while flag >= 0:
        flag = _step(mem, t_end, yvec, tret.ctypes.data, CV_ONE_STEP)
        if flag < 0:
            break
        T, Y = keep_row(T, Y, k, tret[0], y)
        k += 1
        if flag == CV_ROOT_RETURN:
            _root_info(mem, roots.ctypes.data)
            break
        if flag == CV_TSTOP_RETURN:
            break
        if k > max_steps:
            flag = CV_TOO_MUCH_WORK
            break
    _clear_stop(mem)
    return flag, T[:k].copy(), Y[:k].copy(), y.copy(), roots


plain_literals(globals())  # one machine code per kernel for all constant arguments (fly's keep: NE)


def _swap_ops(LS, ctx) -> bool:
    """Replace the band solver ``LS``'s setup and solve by :func:`_block_setup_c` and
    :func:`_block_solve_c` in its operations table, where that table is found as SUNDIALS 7 lays it
    out (the structure's field before its context ``ctx``: ``(content, ops, sunctx)`` in 7.0,
    ``(content, python, ops, sunctx)`` later; in it SUNDIALS' band setup followed by its solve,
    looked for from the start): else nothing changes. Whether they were replaced."""
    vp = ctypes.POINTER(ctypes.c_void_p)
    fields = ctypes.cast(LS, vp)
    at = next((i for i in (2, 3) if fields[i] == ctx), None)
    if at is None or not fields[at - 1]:
        return False
    table = ctypes.cast(fields[at - 1], vp)
    setup, solve = (ctypes.cast(S.function(name), ctypes.c_void_p).value
                    for name in ("SUNLinSolSetup_Band", "SUNLinSolSolve_Band"))
    for i in range(16):  # (stops at the first match: never read past the table)
        if table[i] == setup:
            if table[i + 1] != solve:
                return False
            table[i], table[i + 1] = _block_setup_c.address, _block_solve_c.address
            return True
    return False


def _free(ctx, mem, y, A, LS, atol):
    f = S.function
    f("CVodeFree")(ctypes.byref(ctypes.c_void_p(mem)))
    f("SUNLinSolFree")(LS)
    f("SUNMatDestroy")(A)
    for vector in (y, atol):
        if vector:
            f("N_VDestroy")(vector)
    f("SUNContext_Free")(ctypes.byref(ctypes.c_void_p(ctx)))


class Workspace:
    """One CVODE memory for systems of size ``N``: BDF (or, with ``adams``, Adams-Moulton of orders
    1 to 12), Newton's method with the dense direct solver or, with ``band`` (the variational flights:
    ``N = n + n_E + n^2``), the band solver of half-bandwidths ``n - 1`` (``n^2`` times fewer operations
    a factorisation than the dense one), ``callbacks``, ``(rhs, jac, events, number of events)``, the
    compiled C callbacks of the vector field, the Jacobian (dense, or in band storage with ``band``:
    :func:`band_blocks`) and the events (a flight's generated module's, :mod:`._netgen`, or the
    circuit's during a blow, :mod:`._endgen`), SUNDIALS' error messages silenced (a failure's reason
    reaches the caller as its return flag). With ``blocks`` (the variational flights: the Newton
    matrix block-diagonal, the state's block repeated for each
    column of ``Phi``), the band solver's setup and solve are replaced by :func:`_block_setup_c` and
    :func:`_block_solve_c`: one LU of the ``n x n`` block, applied to each block, the band LU's
    operations on each block in its order (the same steps, to the bit) for about ``n`` times fewer
    a factorisation and three times fewer a solve; ``blocks`` says whether they were (the band
    solver's table as SUNDIALS 7 lays it out, checked, else the band solver's own). With ``plain``
    (a plain flight, ``N = n + n_E``: the Newton matrix the state's block and the energies' identity,
    which the dense solver's LU and solve leave apart to the bit: its pivots never in the energies'
    zero rows, their updates all of zeros) the band matrix's upper bandwidth is ``band + 1``, which
    tells :func:`_block_solve_c` that there is no ``Phi``. Freed when collected.

    Attributes
    ----------
    mem, y : int
        The addresses :func:`fly` takes.
    atol : int
        The address of a vector of ``N`` that :func:`fly_split` takes (its absolute tolerances).
    """

    def __init__(self, N: int, band: int, callbacks, blocks: bool = False, adams: bool = False,
                 plain: bool = False):
        f = S.function
        ctx = ctypes.c_void_p()
        if f("SUNContext_Create")(0, ctypes.byref(ctx)) != 0:
            raise MemoryError("SUNContext_Create failed")
        f("SUNContext_ClearErrHandlers")(ctx)
        y = f("N_VNew_Serial")(N, ctx)
        atol = f("N_VNew_Serial")(N, ctx)
        upper = band + 1 if plain and band else band
        if band:
            A = f("SUNBandMatrix")(N, upper, band, ctx)
            LS = f("SUNLinSol_Band")(y, A, ctx) if y and A else None
        else:
            A = f("SUNDenseMatrix")(N, N, ctx)
            LS = f("SUNLinSol_Dense")(y, A, ctx) if y and A else None
        mem = f("CVodeCreate")(CV_ADAMS if adams else CV_BDF, ctx)
        self.ctx, self.mem, self.y, self.N, self.band, self.adams = ctx.value, mem, y, N, band, bool(adams)
        self.atol = atol
        self.plain = bool(plain and band)
        self._finalizer = weakref.finalize(self, _free, ctx.value, mem, y, A, LS, atol)
        if not (y and atol and A and LS and mem):
            raise MemoryError("SUNDIALS could not allocate a CVODE workspace")
        if band:  # the storage the Jacobian writes (SUNBandMatrix: smu = mu + ml, or min(N - 1, mu + ml))
            smu = f("SUNBandMatrix_StoredUpperBandwidth")(A) & _LOW32
            if smu not in (upper + band, min(N - 1, upper + band)) or \
                    f("SUNBandMatrix_LDim")(A) & _LOW32 != smu + band + 1:
                raise RuntimeError("SUNDIALS' band matrix is not stored as documented")
        self.blocks = bool(blocks and band and _swap_ops(LS, ctx.value))
        rhs, jac, events, n_events = callbacks
        ok = (f("CVodeInit")(mem, rhs.address, 0.0, y) == 0
              and f("CVodeSStolerances")(mem, 1e-10, 1e-12) == 0
              and f("CVodeSetLinearSolver")(mem, LS, A) == 0
              and f("CVodeSetJacFn")(mem, jac.address) == 0
              and f("CVodeSetMaxHnilWarns")(mem, -1) == 0  # ("t + h = t": the refusal says it)
              and f("CVodeRootInit")(mem, n_events, events.address) == 0)
        if not ok:
            raise RuntimeError("CVODE's set-up failed")

    def statistics(self) -> dict:
        """CVODE's counters over the last flight: steps, right-hand sides, error-test failures,
        Newton iterations and convergence failures, Jacobians, linear-solver set-ups, event-function
        evaluations."""
        out = {}
        for key, name in (("steps", "CVodeGetNumSteps"), ("rhs", "CVodeGetNumRhsEvals"),
                          ("error_test_failures", "CVodeGetNumErrTestFails"),
                          ("newton_iterations", "CVodeGetNumNonlinSolvIters"),
                          ("newton_failures", "CVodeGetNumNonlinSolvConvFails"),
                          ("jacobians", "CVodeGetNumJacEvals"), ("setups", "CVodeGetNumLinSolvSetups"),
                          ("event_evaluations", "CVodeGetNumGEvals")):
            v = ctypes.c_long()
            S.function(name)(self.mem, ctypes.byref(v))
            out[key] = int(v.value)
        return out


_LOCAL = threading.local()


def workspace(N: int, band: int, callbacks, blocks: bool = False, adams: bool = False,
              plain: bool = False) -> Workspace:
    """This thread's workspace for systems of size ``N`` (with the band solver of half-bandwidths
    ``band``, or dense for 0; with ``blocks``, its setup and solve on the blocks; with ``adams``,
    Adams-Moulton's method instead of BDF; with ``plain``, a plain flight's: :class:`Workspace`) and
    the compiled C callbacks ``callbacks``, ``(rhs, jac, events, number of events)``, made on first
    use."""
    spaces = getattr(_LOCAL, "spaces", None)
    if spaces is None:
        spaces = _LOCAL.spaces = {}
    key = (N, band, callbacks[0].address, bool(blocks and band), bool(adams), bool(plain and band))
    ws = spaces.get(key)
    if ws is None:
        ws = spaces[key] = Workspace(N, band, callbacks, blocks, adams, plain)
    _LOCAL.last = ws
    return ws


def last_workspace() -> Workspace | None:
    """The workspace of this thread's last flight (its :meth:`Workspace.statistics`)."""
    return getattr(_LOCAL, "last", None)
