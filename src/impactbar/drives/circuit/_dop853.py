r"""The explicit Dormand-Prince 8(5,3) integrator of the circuit's plain flights, compiled (theory §11).

scipy's ``solve_ivp(method="DOP853")`` takes its steps in Python; :data:`SOURCE` is the same
method as one compiled loop: scipy's own coefficients
(:mod:`scipy.integrate._ivp.dop853_coefficients`), its first step (Hairer, Norsett & Wanner,
*Solving ODEs I*, II.4), its error norm (the 5th- and 3rd-order estimates combined as in Hairer's
``DOP853``) and its step-size control (safety 0.9, factors 0.2 to 10, no growth after a rejected
step), so that on the same problem it takes scipy's steps, to rounding (``tests/drives``' check on
a damped oscillator and on a circuit flight).

The flight keeps each step's end and, inside each step, dense-output samples at most ``spacing``
apart, so that the cubic Hermite interpolant the circuit's pieces take between kept points
(:class:`.flight.CircuitPiece`, Magnus' ``state_at``) is as fine as over CVODE's steps. Events are
located as CVODE's root finding locates them (``cvRcheck1``, ``cvRootfind``: the event functions
checked at each of its steps, the first crossing of any in its direction found by the Illinois
method, a function zero at the start set aside until it leaves zero), here checked at each kept
point (an explicit step spans several of CVODE's: a function that crosses and crosses back within
one is then found where CVODE would find it), located on the step's 7th-order dense output to
:data:`ROOT_ULPS` roundings of the time instead of CVODE's hundred.

The driver calls the vector field and the event functions of a network's generated module, so its
source is compiled with that module (:mod:`._netgen`: numba caches a function only where the
functions it calls are its module's globals); :func:`compile_driver` compiles it, uncached, on any
other vector field (the tests' closed forms). This module holds what the driver calls. Arrays are
copied element by element in these kernels: numba's slice assignment compiles its shape-mismatch
message (string routines) for each caller's options.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numba as nb
import numpy as np
from scipy.integrate._ivp import dop853_coefficients as _co

from ..._shared.literals import plain_literals
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE

__all__ = ["SOURCE", "compile_driver", "DOP853_TOO_MUCH_WORK", "DOP853_TOO_SMALL_STEP", "MESSAGES",
           "ROOT_ULPS"]

#: scipy's Butcher tableau (``A``: the 12 stages, the 13th row the weights ``B`` of the solution,
#: then the 3 stages of the dense output), nodes, error weights and dense-output weights.
A = np.ascontiguousarray(_co.A, dtype=float)
C = np.ascontiguousarray(_co.C, dtype=float)
E3 = np.ascontiguousarray(_co.E3, dtype=float)
E5 = np.ascontiguousarray(_co.E5, dtype=float)
D = np.ascontiguousarray(_co.D, dtype=float)
N_STAGES = _co.N_STAGES  # 12 (the 13th, the new point's rate, shared with the next step)
N_EXTENDED = _co.N_STAGES_EXTENDED  # 16
N_DENSE = _co.INTERPOLATOR_POWER  # 7

#: scipy's step-size control (``scipy.integrate._ivp.rk``).
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
ERROR_EXPONENT = -1.0 / 8.0  # (the error estimator's order 7, plus one)

#: An event's time is located to ``ROOT_ULPS`` roundings of ``|t| + |h|`` (CVODE: 100).
ROOT_ULPS = 4.0

#: The driver's flags: as CVODE's (``_cvode``): 2 an event, 1 the end time; negative a failure.
DOP853_ROOT, DOP853_TSTOP, DOP853_TOO_MUCH_WORK, DOP853_TOO_SMALL_STEP = 2, 1, -1, -3

#: The failures' messages.
MESSAGES = {DOP853_TOO_MUCH_WORK: "DOP853 took its most steps before the flight's end",
            DOP853_TOO_SMALL_STEP: "DOP853's step fell below the spacing of the time's numbers "
                                   "(the vector field not finite, or far stiffer than the step)"}

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")


@nb.njit(**_JIT)
def _rms_scaled(x, y0, rtol, atol):
    s = 0.0
    for i in range(x.size):
        v = x[i] / (atol + abs(y0[i]) * rtol)
        s += v * v
    return math.sqrt(s) / math.sqrt(x.size)


@nb.njit(**_JIT)
def first_guess(y0, f0, rtol, atol, interval):
    """scipy's ``select_initial_step``, its first half: ``(h0, d1)``, the trial step and the rate's
    norm."""
    d0 = _rms_scaled(y0, y0, rtol, atol)
    d1 = _rms_scaled(f0, y0, rtol, atol)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    return min(h0, interval), d1


@nb.njit(**_JIT)
def first_step(y0, f0, f1, h0, d1, rtol, atol, interval):
    """scipy's ``select_initial_step``, its second half, from the rate ``f1`` at ``y0 + h0 f0``."""
    s = 0.0
    for i in range(y0.size):
        v = (f1[i] - f0[i]) / (atol + abs(y0[i]) * rtol)
        s += v * v
    d2 = math.sqrt(s) / math.sqrt(y0.size) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1, interval)


@nb.njit(**_JIT)
def step_factor(err, rejected):
    """scipy's factor on ``|h|`` after a step of error norm ``err`` (accepted where below 1); a
    norm not a number rejects the step by the least factor."""
    if err < 1.0:
        if err == 0.0:
            factor = MAX_FACTOR
        else:
            factor = SAFETY * err ** ERROR_EXPONENT
            if not factor < MAX_FACTOR:
                factor = MAX_FACTOR
        if rejected and factor > 1.0:
            factor = 1.0
        return factor
    factor = SAFETY * err ** ERROR_EXPONENT
    return factor if factor > MIN_FACTOR else MIN_FACTOR


@nb.njit(**_JIT)
def dense_at(F, y, x, out):
    """The dense output at ``x = (t - t_old) / h`` (scipy's ``Dop853DenseOutput``: its Horner
    scheme in ``x`` and ``1 - x``, written out in its order)."""
    u = 1.0 - x
    for i in range(y.size):
        v = F[6, i] * x
        v = (v + F[5, i]) * u
        v = (v + F[4, i]) * x
        v = (v + F[3, i]) * u
        v = (v + F[2, i]) * x
        v = (v + F[1, i]) * u
        v = (v + F[0, i]) * x
        out[i] = v + y[i]


@nb.njit(**_JIT)
def crossing(glo, ghi, active, directions):
    """CVODE's test for a root between two values of the event functions (``cvRootfind``):
    ``(i, zero)``, ``i`` the active function that crossed in its direction with the largest
    ``|ghi / (ghi - glo)|`` (-1 none), ``zero`` whether one is zero at ``ghi``'s end, come from its
    direction's side."""
    imax = -1
    maxfrac = 0.0
    zero = False
    for i in range(glo.size):
        if not active[i]:
            continue
        if ghi[i] == 0.0:
            if directions[i] * glo[i] <= 0.0:
                zero = True
        elif glo[i] * ghi[i] < 0.0 and directions[i] * glo[i] <= 0.0:
            frac = abs(ghi[i] / (ghi[i] - glo[i]))
            if frac > maxfrac:
                maxfrac = frac
                imax = i
    return imax, zero


@nb.njit(**_JIT)
def illinois_next(tlo, thi, glo_i, ghi_i, alpha, ttol):
    """CVODE's next trial time of the Illinois method (``cvRootfind``), kept half a tolerance
    inside the bracket."""
    tmid = thi - (thi - tlo) * ghi_i / (ghi_i - alpha * glo_i)
    if abs(tmid - tlo) < 0.5 * ttol:
        fracint = abs(thi - tlo) / ttol
        tmid = tlo + (0.1 if fracint > 5.0 else 0.5 / fracint) * (thi - tlo)
    if abs(thi - tmid) < 0.5 * ttol:
        fracint = abs(thi - tlo) / ttol
        tmid = thi - (0.1 if fracint > 5.0 else 0.5 / fracint) * (thi - tlo)
    return tmid


@nb.njit(**_JIT)
def mark_roots(glo, ghi, active, directions, roots):
    """CVODE's root information at a root: ``-1`` for a function come down to it, ``1`` up."""
    for i in range(glo.size):
        if active[i] and directions[i] * glo[i] <= 0.0 and (ghi[i] == 0.0 or glo[i] * ghi[i] < 0.0):
            roots[i] = -1 if glo[i] > 0.0 else 1


@nb.njit(**_JIT)
def keep_row(T, Y, k, t, y):
    """``(T, Y)`` with row ``k`` set to ``t`` and ``y[:keep]``, doubled where full."""
    if k == T.size:  # (element by element: a slice assignment compiles numba's shape-error message)
        T2 = np.empty(2 * T.size)
        Y2 = np.empty((2 * T.size, Y.shape[1]))
        for r in range(k):
            T2[r] = T[r]
            for i in range(Y.shape[1]):
                Y2[r, i] = Y[r, i]
        T, Y = T2, Y2
    T[k] = t
    for i in range(Y.shape[1]):
        Y[k, i] = y[i]
    return T, Y


def _sum(coefficients) -> str:
    """``K[j, i] * c_j + ...`` over the nonzero coefficients, in ``j``'s order (scipy's ``np.dot``'s
    terms), the literals exact (``repr``)."""
    terms = [f"K[{j}, i] * {float(c)!r}" for j, c in enumerate(coefficients) if c != 0.0]
    return " + ".join(terms) if terms else "0.0"


def _stage_table():
    """Each stage's nonzero coefficients ``A[s, j]`` (``j < s``), in ``j``'s order: ``(row, col,
    coef)``, stage ``s``'s at ``row[s]`` to ``row[s + 1]`` of ``col`` and ``coef``."""
    row, col, coef = [0, 0], [], []
    for s in range(1, N_EXTENDED):
        js = [j for j in range(s) if A[s, j] != 0.0]
        if not js:  # (scipy's tableau has none; the loop below starts each sum with a term)
            raise ValueError(f"DOP853's stage {s} has no nonzero coefficient")
        col += js
        coef += [float(A[s, j]) for j in js]
        row.append(len(col))
    return np.array(row, np.int64), np.array(col, np.int64), np.array(coef)


#: the stages' coefficients as :func:`_stage_table` lists them (the driver's stage loop)
STAGE_ROW, STAGE_COL, STAGE_COEF = _stage_table()


def _stages(first: int, last: int, indent: str) -> str:
    """The stages ``first`` to ``last - 1`` (``ys = y + h sum_j A[s, j] K[j]``, then its rate into
    ``K[s]``; stage :data:`N_STAGES`, the solution's weights ``A[12] = B``, into ``y_new``) as one
    loop over the stages with one call of the vector field: each component's sum taken term by term
    in ``j``'s order over the nonzero coefficients (scipy's ``np.dot``'s terms, as the sum written out
    with its literals took them, the same numbers), each term over all components at once."""
    lines = [f"for s in range({first}, {last}):",
             "    into = y_new if s == DP.N_STAGES else ys",
             "    p = DP.STAGE_ROW[s]",
             "    j = DP.STAGE_COL[p]",
             "    c = DP.STAGE_COEF[p]",
             "    for i in range(N):",
             "        into[i] = K[j, i] * c",
             "    for p in range(DP.STAGE_ROW[s] + 1, DP.STAGE_ROW[s + 1]):",
             "        j = DP.STAGE_COL[p]",
             "        c = DP.STAGE_COEF[p]",
             "        for i in range(N):",
             "            into[i] = into[i] + K[j, i] * c",
             "    for i in range(N):",
             "        into[i] = y[i] + into[i] * h",
             "    flight_rhs(t + DP.C[s] * h, into, K[s], par)"]
    return "\n".join(indent + line for line in lines)


def _source() -> str:
    """The driver's source (:data:`SOURCE`): the error norm and the dense output's coefficients
    written out with scipy's coefficients, the stages as one loop each (:func:`_stages`: one call of
    the vector field in each, where the 15 stages written out made 15 to compile)."""
    dense = "\n".join(f"        F[{3 + r}, i] = ({_sum(D[r])}) * h" for r in range(N_DENSE - 3))
    return (_SOURCE.replace("@E5@", _sum(E5)).replace("@E3@", _sum(E3)).replace("@DENSE@", dense)
            .replace("@STEP@", _stages(1, N_STAGES + 1, " " * 12))
            .replace("@EXTRA@", _stages(N_STAGES + 1, N_EXTENDED, " " * 12)))


_SOURCE = """
# -- the explicit flights (_dop853: DOP853 with scipy's coefficients, written out) --
@nb.njit(**_JIT)
def dop853_error_norm(K, h, y, y_new, rtol, atol):
    \"\"\"scipy's ``DOP853._estimate_error_norm``: the 5th- and 3rd-order estimates over the scale
    ``atol + max(|y|, |y_new|) rtol``, combined.\"\"\"
    n = y.size
    e5 = 0.0
    e3 = 0.0
    for i in range(n):
        sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
        a5 = (@E5@) / sc
        a3 = (@E3@) / sc
        e5 += a5 * a5
        e3 += a3 * a3
    if e5 == 0.0 and e3 == 0.0:
        return 0.0
    return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * n)


@nb.njit(**_JIT)
def dop853_dense(K, h, y, y_new, F):
    \"\"\"scipy's ``DOP853._dense_output_impl`` (the extra stages ``K[13:16]`` taken): the dense
    output's coefficients ``F`` (7 rows; ``_dop853.dense_at``).\"\"\"
    for i in range(y.size):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[12, i] + K[0, i])
@DENSE@


@nb.njit(**_JIT)
def dop853_fly(t0, y0, t_end, rtol, atol, directions, par, keep, max_steps, spacing):
    \"\"\"One flight by DOP853 (``_dop853``) from ``y0`` at ``t0`` to the first root of the event
    functions in ``directions`` or ``t_end``: each step's end kept, and dense-output samples inside
    each step at most ``spacing`` apart (none for ``spacing <= 0``). Returns ``_cvode.fly``'s
    ``(flag, t, y[:, :keep], y_end, roots)`` and the counts of steps, rejected steps, right-hand
    sides and event evaluations.\"\"\"
    N = y0.size
    E = directions.size
    K = np.empty((DP.N_EXTENDED, N))
    F = np.empty((DP.N_DENSE, N))
    y = y0.copy()
    y_new = np.empty(N)
    ys = np.empty(N)
    ym = np.empty(N)
    glo = np.empty(E)
    gend = np.empty(E)
    ghi = np.empty(E)
    gmid = np.empty(E)
    active = np.ones(E, np.bool_)
    roots = np.zeros(E, np.int32)
    counts = np.zeros(4, np.int64)
    T = np.empty(512)
    Y = np.empty((512, keep))
    T, Y = DP.keep_row(T, Y, 0, t0, y0)
    k = 1
    flight_rhs(t0, y, K[0], par)
    interval = abs(t_end - t0)
    h_abs = 0.0
    if interval > 0.0:
        h0, d1 = DP.first_guess(y0, K[0], rtol, atol, interval)
        for i in range(N):
            ys[i] = y0[i] + h0 * K[0, i]
        flight_rhs(t0 + h0, ys, K[1], par)
        h_abs = DP.first_step(y0, K[0], K[1], h0, d1, rtol, atol, interval)
    counts[2] = 2
    # the event functions at the start: those zero there set aside while zero a little later (cvRcheck1)
    flight_events(t0, y, glo, par)
    counts[3] = 1
    zero = False
    for i in range(E):
        if glo[i] == 0.0:
            active[i] = False
            zero = True
    if zero and h_abs > 0.0:
        ratio = max((abs(t0) + h_abs) * DP.ROOT_ULPS * 2.220446049250313e-16 / h_abs, 0.1)
        for i in range(N):
            ys[i] = y0[i] + ratio * h_abs * K[0, i]
        flight_events(t0 + ratio * h_abs, ys, gmid, par)
        counts[3] += 1
        for i in range(E):
            if not active[i] and gmid[i] != 0.0:
                active[i] = True
                glo[i] = gmid[i]
    t = t0
    flag = DP.DOP853_TSTOP if interval == 0.0 else 0
    while flag == 0:
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs < min_step:
            h_abs = min_step
        rejected = False
        while True:
            if h_abs < min_step:
                flag = DP.DOP853_TOO_SMALL_STEP
                break
            t_new = t + h_abs
            if t_new - t_end > 0.0:
                t_new = t_end
            h = t_new - t
            h_abs = abs(h)
@STEP@
            counts[2] += 12
            err = dop853_error_norm(K, h, y, y_new, rtol, atol)
            h_abs *= DP.step_factor(err, rejected)
            if err < 1.0:
                break
            rejected = True
            counts[1] += 1
        if flag != 0:
            break
        counts[0] += 1
        m = 1
        if spacing > 0.0:
            m = max(1, min(int(math.ceil(h / spacing)), 4096))
        flight_events(t_new, y_new, gend, par)
        counts[3] += 1
        imax, zero = DP.crossing(glo, gend, active, directions)
        if m > 1 or imax >= 0 or zero:  # the dense output: three more stages
@EXTRA@
            counts[2] += 3
            dop853_dense(K, h, y, y_new, F)
        # the samples and the step's end, each a point of the events' check (CVODE's, at its steps)
        tlo = t
        for j in range(1, m + 1):
            if j < m:
                t_hi = t + (j / m) * h
                DP.dense_at(F, y, j / m, ys)
                flight_events(t_hi, ys, ghi, par)
                counts[3] += 1
            else:
                t_hi = t_new
                for i in range(N):
                    ys[i] = y_new[i]
                for i in range(E):
                    ghi[i] = gend[i]
            imax, zero = DP.crossing(glo, ghi, active, directions)
            if imax >= 0 or zero:  # CVODE's Illinois search on (tlo, t_hi]
                moved = False
                side = 0
                sideprev = -1
                alpha = 1.0
                ttol = (abs(t_new) + h_abs) * DP.ROOT_ULPS * 2.220446049250313e-16
                while imax >= 0 and abs(t_hi - tlo) > ttol:
                    if sideprev == side:
                        alpha = alpha * 2.0 if side == 2 else alpha * 0.5
                    else:
                        alpha = 1.0
                    tmid = DP.illinois_next(tlo, t_hi, glo[imax], ghi[imax], alpha, ttol)
                    DP.dense_at(F, y, (tmid - t) / h, ym)
                    flight_events(tmid, ym, gmid, par)
                    counts[3] += 1
                    sideprev = side
                    imid, zmid = DP.crossing(glo, gmid, active, directions)
                    if imid >= 0 or zmid:
                        t_hi = tmid
                        for i in range(E):
                            ghi[i] = gmid[i]
                        moved = True
                        side = 1
                        imax = imid
                        continue
                    tlo = tmid
                    for i in range(E):
                        glo[i] = gmid[i]
                    side = 2
                DP.mark_roots(glo, ghi, active, directions, roots)
                if moved:
                    DP.dense_at(F, y, (t_hi - t) / h, ys)
                flag = DP.DOP853_ROOT
            T, Y = DP.keep_row(T, Y, k, t_hi, ys)
            k += 1
            if flag == DP.DOP853_ROOT:
                break
            for i in range(E):
                if not active[i] and ghi[i] != 0.0:
                    active[i] = True
            for i in range(E):
                glo[i] = ghi[i]
            tlo = t_hi
        if flag == DP.DOP853_ROOT:
            for i in range(N):
                y[i] = ys[i]
            break
        y, y_new = y_new, y
        for i in range(N):
            K[0, i] = K[12, i]
        t = t_new
        if t_new == t_end:
            flag = DP.DOP853_TSTOP
        elif counts[0] >= max_steps:
            flag = DP.DOP853_TOO_MUCH_WORK
    return flag, T[:k], Y[:k], y.copy(), roots, counts
"""

#: The driver's source, compiled with the vector field ``flight_rhs(t, y, yp, par)`` and the event
#: functions ``flight_events(t, y, g, par)`` as globals of its module (``nb``, ``np``, ``math``, this
#: module as ``DP`` and numba's options ``_JIT`` beside them): ``dop853_fly``, ``dop853_error_norm``
#: and ``dop853_dense``.
SOURCE = _source()


def compile_driver(rhs, events):
    """:data:`SOURCE`'s ``dop853_fly`` compiled on a vector field ``rhs(t, y, yp, par)`` and event
    functions ``events(t, y, g, par)`` (numba functions), uncached: what the tests check against
    scipy on closed forms (a network's flights take the driver compiled with its generated module,
    :mod:`._netgen`).

    Parameters
    ----------
    rhs, events : numba.core.registry.CPUDispatcher
        Compiled with ``numba.njit``; ``events`` writes as many values as the driver's
        ``directions`` has.

    Returns
    -------
    types.SimpleNamespace
        ``dop853_fly(t0, y0, t_end, rtol, atol, directions, par, keep, max_steps, spacing)``,
        ``dop853_error_norm(K, h, y, y_new, rtol, atol)`` and ``dop853_dense(K, h, y, y_new, F)``.
    """
    import sys

    ns = {"__name__": f"{__name__}_driver", "nb": nb, "np": np, "math": math, "DP": sys.modules[__name__],
          "flight_rhs": rhs, "flight_events": events, "_JIT": dict(nogil=True, error_model="numpy")}
    exec(compile(SOURCE, "<dop853_fly>", "exec"), ns)
    return SimpleNamespace(**{k: ns[k] for k in ("dop853_fly", "dop853_error_norm", "dop853_dense")})


plain_literals(globals())  # one machine code per kernel for all constant arguments (keep_row's row 0)
internal_kernels(globals(), from_python="compile")  # kernels call them (the flights' loops): link-only
