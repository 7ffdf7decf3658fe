"""Compiled valve loop of a position-switched drive (theory §10). Plain float arrays only.

Between events the force at ``x = 0`` is a constant level, ``+stroke`` or ``-ret``, so each flight
is a flight of the ordinary event search (:func:`impactbar.dynamics._event_loop.run_free`) under the
one-piece load of that level; the valve runs around it. The gap ``y = -q_0`` obeys
``y'' + d y' = -p`` alone (the flexible modes do not enter it), so its rising crossing of the switch
position is found in closed form (:func:`~impactbar.drives._crossing.first_rising_crossing`): the
gap's rate is monotone under a constant force, no crossing is missed, and it is refined to rounding.

:func:`run_switched` follows the valve through piece after piece in one call, doing in each piece
exactly what the drive's Python steps in :mod:`impactbar.simulation.driven` do (the same kernel
calls with the same arguments, hence the same numbers), and hands back to Python every piece it does
not resolve itself (a touch without an impact, a start through the stop, a full log): Python runs
that piece with the general driver (sustained contact and all) and calls it again
(:mod:`impactbar.drives.valve.loop`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..._shared.literals import plain_literals
from ...dynamics.compiled import CACHE, END, MAXIMP, propagate_views, run_free
from ...dynamics.compiled_views import LoadKernelView, ModalBasisView
from .._crossing import first_rising_crossing, gap, rate_zero, rigid_flight
from ._state import DriveKernelView

__all__ = ["gap", "rate_zero", "first_rising_crossing", "rigid_flight", "run_switched",
           "STROKE", "RETURN", "DONE", "MAX_IMPACTS", "FULL", "PYTHON"]


#: The valve's two states (indices of the levels ``(+stroke, -ret)``).
STROKE = 0
RETURN = 1

# statuses of run_switched
DONE = 0  # t_end reached
MAX_IMPACTS = 1  # max_impacts reached
FULL = 2  # a log is full: Python empties it and calls again
PYTHON = 3  # the next piece is Python's (a touch, a start through the stop, a full pending list)

# integer slots of the valve's state array ``ints``: the valve, the switches pending, the impacts
# done and the most, the rigid bar's closed forms (1: run them), the fast impact search (1)
INT_VALVE, INT_NPEND, INT_NIMP, INT_MAXIMP, INT_RIGID, INT_FAST = range(6)
INT_SIZE = 6
# counters of the logs (``logs[-1]``): impacts, switches, pieces logged
CNT_IMP, CNT_SW, CNT_PC = range(3)
CNT_SIZE = 3
# the clock's slots: the time reached, the end, the tail (the impacts' search's)
CLK_T, CLK_END, CLK_TAIL = range(3)
CLK_SIZE = 3
# a rebound shorter than this fraction of the time is rest on the stop (the Python loop's test)
_REST = 1e-13


@numba.njit(cache=CACHE, nogil=True)
def _rigid_piece(d, R, level, q, v, t, t_stop):
    """One constant-force piece of the rigid bar under the paper's law (the closed forms of
    ``impactbar.simulation.driven.rigid_piece``): ``(t_end, impacted, arrival velocity, q, v,
    at rest)``, the state at ``t_end`` (after the impact if there is one)."""
    q0, v0 = q, v
    resting = q0 >= 0.0 and abs(v0) <= _REST * (1.0 + abs(level)) and level > 0.0
    if resting:
        q0 = v0 = 0.0
        t_imp = math.inf
    else:
        t_imp = t + first_rising_crossing(d, q0, v0, level, 0.0)
    if t_imp < t_stop:
        _, vm = rigid_flight(d, q0, v0, level, t_imp - t)
        vp = -R * vm
        if level > 0.0 and abs(vp) * (2.0 / level) <= _REST * (1.0 + t_imp):
            vp = 0.0  # the rebound lasts less than rounding: the piston rests on the stop
        return t_imp, True, vm, 0.0, vp, resting
    if resting:
        return t_stop, False, 0.0, 0.0, 0.0, resting
    qe, ve = rigid_flight(d, q0, v0, level, t_stop - t)
    return t_stop, False, 0.0, min(qe, 0.0), ve, resting


@numba.njit(cache=CACHE, nogil=True)
def _rigid_cycle(d, R, drive, v):
    """The rigid piston's one-impact cycle from the arrival velocity ``v`` (theory §10): stroke for
    the delay, return until the gap rises through ``switch_out``, return for the delay, stroke until
    ``q_0`` rises through 0. Returns the next arrival velocity and the free flight times
    ``(h1, h3)`` (``inf`` where a crossing does not come). The delays: ``delay_in`` after the
    impact, ``delay_out`` after the crossing."""
    ps, pr = drive.stroke, drive.ret
    q, w = rigid_flight(d, 0.0, -R * v, ps, drive.delay_in)
    h1 = first_rising_crossing(d, -q, -w, pr, drive.switch_out)
    if not math.isfinite(h1):
        return math.nan, h1, math.inf
    q, w = rigid_flight(d, q, w, -pr, h1 + drive.delay_out)
    h3 = first_rising_crossing(d, q, w, ps, 0.0)
    if not math.isfinite(h3):
        return math.nan, h1, h3
    _, w = rigid_flight(d, q, w, ps, h3)
    return w, h1, h3


@numba.njit(cache=CACHE, nogil=True)
def rigid_fixed_point(d, R, drive, v0):
    """The rigid piston's one-impact orbit under a position-switched drive: the fixed point of the
    map of arrival velocities of :func:`_rigid_cycle`, by the secant method from ``v0`` (its
    derivative is about ``R^2``). Returns ``(v, h1, h3)``, ``v = nan`` where it fails. The start of
    Newton's method on the segment problem (``impactbar.orbits.driven``), which confirms it."""
    a = v0
    fa, h1, h3 = _rigid_cycle(d, R, drive, a)
    if not math.isfinite(fa):
        return math.nan, h1, h3
    ga = fa - a
    b = fa
    for _ in range(60):
        fb, h1, h3 = _rigid_cycle(d, R, drive, b)
        if not math.isfinite(fb):
            return math.nan, h1, h3
        gb = fb - b
        if gb == 0.0 or abs(gb) <= 1e-15 * abs(b):
            return b, h1, h3
        if gb == ga:
            return math.nan, h1, h3
        c = b - gb * (b - a) / (gb - ga)
        if not c > 0.0:
            return math.nan, h1, h3
        a, ga, b = b, gb, c
    return math.nan, h1, h3


@numba.njit(cache=CACHE, nogil=True)
def end_max_sampled(w2, d, p, c, q, v, h, n):
    """Largest end displacement ``c . q(t)`` at the interior samples ``t_j = j h / (n - 1)``,
    ``0 < j < n - 1``, of a flight under the constant force ``p`` from ``(q, v)`` (eq. 8; the
    samples of ``numpy.linspace(0, h, n)[1:-1]``), every flexible mode underdamped.

    Each flexible mode is ``q_s + e^{-d t / 2} (A cos(l t) + B sin(l t))`` with ``q_s = p / w2``,
    ``l^2 = w2 - d^2 / 4``; its cosine and sine are advanced from sample to sample by a rotation and
    evaluated afresh every 32 samples (rounding stays near the machine epsilon). The rigid mode is
    in closed form (theory §10).
    """
    M = w2.size
    step = h / (n - 1)
    lam = np.empty(M)
    A = np.empty(M)
    Bc = np.empty(M)
    cr = np.empty(M)
    sr = np.empty(M)
    cs = np.empty(M)
    sn = np.empty(M)
    static = 0.0
    for i in range(1, M):
        lam[i] = math.sqrt(w2[i] - 0.25 * d * d)
        qs = p / w2[i]
        static += c[i] * qs
        A[i] = q[i] - qs
        Bc[i] = (v[i] + 0.5 * d * A[i]) / lam[i]
        cr[i] = math.cos(lam[i] * step)
        sr[i] = math.sin(lam[i] * step)
    worst = -math.inf
    for j in range(1, n - 1):
        t = j * step
        fresh = (j - 1) % 32 == 0
        acc = 0.0
        for i in range(1, M):
            if fresh:
                cs[i] = math.cos(lam[i] * t)
                sn[i] = math.sin(lam[i] * t)
            else:
                a = cs[i] * cr[i] - sn[i] * sr[i]
                sn[i] = sn[i] * cr[i] + cs[i] * sr[i]
                cs[i] = a
            acc += c[i] * (A[i] * cs[i] + Bc[i] * sn[i])
        q0, _ = rigid_flight(d, q[0], v[0], p, t)
        val = c[0] * q0 + static + math.exp(-0.5 * d * t) * acc
        if val > worst:
            worst = val
    return worst


@numba.njit(cache=CACHE, nogil=True)
def _push(pend_t, pend_k, n, t, k):
    """Insert the switch ``(t, k)`` into the first ``n`` entries, kept sorted as Python sorts the
    tuples ``(t, k)``."""
    i = n
    while i > 0 and (pend_t[i - 1] > t or (pend_t[i - 1] == t and pend_k[i - 1] > k)):
        pend_t[i] = pend_t[i - 1]
        pend_k[i] = pend_k[i - 1]
        i -= 1
    pend_t[i] = t
    pend_k[i] = k
    return n + 1


@numba.njit(cache=CACHE, nogil=True)
def _run_switched(loads, B, drive, R, c, clock, state, ints, pending, logs):
    """The valve's loop (theory §10), piece by piece, from ``clock[CLK_T]`` to ``clock[CLK_END]``.

    ``loads`` are the plain tuples of the views of the two one-piece loads ``(+stroke, -ret)``, ``B`` that of
    the free-free basis (plain tuples: the flexible flights call the dispatcher
    :func:`~impactbar.dynamics._event_loop.run_free` with the types :func:`simulate` uses, so no second
    specialisation compiles), ``state = (q, v)`` the modal state (overwritten), ``ints`` the valve's integers
    (state, number of pending switches, impacts so far, the largest number, whether the rigid closed form
    runs, whether the fast impact search runs), ``pending = (times, kinds)`` the switches not yet in effect,
    sorted, and ``logs = (impact times, impact velocities, switch times, gaps, kinds, piece starts, piece
    ends, piece levels, piece start states q and v, counters)``.

    Returns
    -------
    int
        :data:`DONE`, :data:`MAX_IMPACTS`, :data:`FULL` or :data:`PYTHON`; ``clock[CLK_T]`` is where the
        loop stopped.
    """
    q, v = state
    pend_t, pend_k = pending
    imp_t, imp_v, sw_t, sw_y, sw_k, pc_t0, pc_t1, pc_lv, pc_q, pc_v, cnt = logs
    M = q.size
    B_t = B
    B = ModalBasisView(*B_t)
    d = B.d
    rigid = ints[INT_RIGID] != 0
    fast = ints[INT_FAST] != 0
    tail = clock[CLK_TAIL]
    qs = np.empty(M)
    vs = np.empty(M)
    out_t = np.empty(1)
    out_vel = np.empty(1)
    out_q = np.empty((1, M))
    out_v = np.empty((1, M))
    out = (out_t, out_vel, out_q, out_v)
    ts = np.empty(1)
    eq = np.empty((M, 1))
    ev = np.empty((M, 1))
    t = clock[CLK_T]
    t_end = clock[CLK_END]
    while t < t_end:
        n_pend = ints[INT_NPEND]
        if n_pend + 2 > pend_t.size:
            return PYTHON
        if cnt[CNT_IMP] >= imp_t.size or cnt[CNT_PC] >= pc_t0.size or cnt[CNT_SW] + n_pend + 2 > sw_t.size:
            return FULL
        valve = ints[INT_VALVE]
        # the next rising crossing of switch_out while the valve is (and stays) in return
        t_next = t_end
        if n_pend:
            t_next = min(t_next, pend_t[0])
        cross = math.inf
        stroke_pending = False
        for i in range(n_pend):
            if pend_k[i] == STROKE:
                stroke_pending = True
        if valve == RETURN and not stroke_pending:
            cross = t + first_rising_crossing(d, -q[0], -v[0], drive.ret, drive.switch_out)
            t_next = min(t_next, cross)
        level = drive.stroke if valve == STROKE else -drive.ret
        impacted = False
        rest = False
        if rigid:
            t1, impacted, vm, q0, v0, rest = _rigid_piece(d, R, level, q[0], v[0], t, t_next)
            if impacted:
                imp_t[cnt[CNT_IMP]] = t1
                imp_v[cnt[CNT_IMP]] = vm
            qs[0] = q[0]
            vs[0] = v[0]
            q[0] = q0
            v[0] = v0
        else:
            g = 0.0
            sc = 0.0
            for i in range(M):
                g += c[i] * q[i]
                sc += abs(c[i] * q[i])
            if g > 0.0 and g > 1e-12 * max(1.0, sc):
                return PYTHON  # a start through the stop: Python refuses it
            if g > 0.0:
                q[0] -= g
            for i in range(M):
                qs[i] = q[i]
                vs[i] = v[i]
            load_t = loads[valve]
            load = LoadKernelView(*load_t)
            n, st, tn = run_free(load_t, B_t, R, c, (t, q, v), t_next, 1, tail, out, None, fast)
            if st == MAXIMP:
                impacted = True
                t1 = tn
                imp_t[cnt[CNT_IMP]] = out_t[0]
                imp_v[cnt[CNT_IMP]] = out_vel[0]
                for i in range(M):
                    q[i] = out_q[0, i]
                    v[i] = out_v[0, i]
            elif st == END:  # no impact before t_next: the state there by the reference flow
                t1 = t_next
                ts[0] = t_next
                propagate_views(load, B, t, qs, vs, ts, eq, ev)
                for i in range(M):
                    q[i] = eq[i, 0]
                    v[i] = ev[i, 0]
            else:  # a touch, chatter or a failure: the general driver's piece, in Python
                for i in range(M):
                    q[i] = qs[i]
                    v[i] = vs[i]
                clock[CLK_T] = t
                return PYTHON
        k = cnt[CNT_PC]
        pc_t0[k] = t
        pc_t1[k] = t1
        pc_lv[k] = valve + (2 if rigid and rest else 0)  # + 2: the piston rests on the stop
        for i in range(M):
            pc_q[k, i] = qs[i]
            pc_v[k, i] = vs[i]
        cnt[CNT_PC] = k + 1
        t = t1
        clock[CLK_T] = t
        if impacted:
            cnt[CNT_IMP] += 1
            ints[INT_NIMP] += 1
            ints[INT_NPEND] = _push(pend_t, pend_k, ints[INT_NPEND], t + drive.delay_in, RETURN)
            if ints[INT_NIMP] >= ints[INT_MAXIMP]:
                return MAX_IMPACTS
        elif t >= t_end:
            break
        elif t == cross:  # the gap rose through switch_out: the switch to stroke is triggered
            ints[INT_NPEND] = _push(pend_t, pend_k, ints[INT_NPEND], cross + drive.delay_out, STROKE)
        while ints[INT_NPEND] and pend_t[0] <= t:  # the switches due now take effect
            kk = pend_k[0]
            n_pend = ints[INT_NPEND] - 1
            for i in range(n_pend):
                pend_t[i] = pend_t[i + 1]
                pend_k[i] = pend_k[i + 1]
            ints[INT_NPEND] = n_pend
            if kk != ints[INT_VALVE]:
                ints[INT_VALVE] = kk
                sw_t[cnt[CNT_SW]] = t
                sw_y[cnt[CNT_SW]] = -q[0]
                sw_k[cnt[CNT_SW]] = kk
                cnt[CNT_SW] += 1
    clock[CLK_T] = t
    return DONE


@numba.njit(cache=CACHE, nogil=True)
def rigid_orbit_start(d, R, drive, v0):
    """:func:`rigid_fixed_point` called from Python, with the drive's view as a plain tuple."""
    return rigid_fixed_point(d, R, DriveKernelView(*drive), v0)


@numba.njit(cache=CACHE, nogil=True)
def run_switched(loads, B, drive, R, c, clock, state, ints, pending, logs):
    """:func:`_run_switched` called from Python, with the views as plain tuples (``tuple(view)``:
    numba dispatches them several times faster than named tuples)."""
    return _run_switched(loads, B, DriveKernelView(*drive), R, c, clock, state, ints, pending, logs)


plain_literals(globals())  # one machine code per kernel for all constant arguments (_push's RETURN, STROKE)
