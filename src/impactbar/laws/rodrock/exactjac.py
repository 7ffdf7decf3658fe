r"""The exact blow map's Jacobian (theory §4d, "the exact blow's Jacobian"): the derivatives of the
state after an exact blow with respect to the state at impact and to the impact time, by tangent
runs of the exact solver along each direction, exact to rounding.

The primal blow logs its switches; each tangent run carries a direction's waves through the same
chain with the switches held, and the impulses that moving a re-contact sends
(:mod:`impactbar.laws.rodrock._exacttangent`). The directions: the modes' positions ``q_1 .. q_N``
and velocities ``q'_0 .. q'_N`` (the rigid position ``q_0`` only places the piston on the shank: its
column is zero) and the impact time (the drive moves under the blow: a Fourier load's harmonics
differentiated, a piecewise-constant load's jumps as impulses; a load of neither form by central
differences of two blows). ``2 N + 2`` tangent runs, each cheaper than a blow (no switch is
searched), instead of the ``4 N + 6`` blows of central differences.

The same runs give the derivative of the wave arriving at the piston's driven end over the blow
(``tangents``' ``arriving``: its smooth part, and the impulses a moving re-contact sends there), the
blow's part of the tangent of a blow whose drive answers that wave (theory §11, "The coupled blow").

Where the schedule cannot be held (a re-contact at zero closing speed, where the map has no
derivative; a switch search the primal gave up) :func:`exact_impact_map` returns ``None`` and the
caller falls back on central differences.
"""

from __future__ import annotations

import numpy as np

from . import _exacttangent as TG
from ._records import (  # the records' slots and the pool's columns
    CI_GIVEUP,
    CNT_PIECES,
    CNT_TERMS,
    END_COLS,
    END_GAP,
    END_PPERM,
    END_SEPS,
    END_SHANK,
    ICH_TAIL,
    IMP_COLS,
    IMP_DIR,
    PI_COUNT,
    PI_TERMS,
    PR_DRIVEN,
    PR_FEED,
    PR_FIXED,
    PR_K,
    PR_KU,
    PR_LB,
    PR_NODW,
    PR_P0,
    PR_RECORD,
    PR_TMAX,
    PR_WINDOW,
    PR_ZBIT,
    RD_FULL,
    RD_HEAD,
    TCUR_N,
    TCUR_SIZE,
    WS_CI,
    WS_CNT,
    WS_LAM,
    WS_NSI,
    WS_PR,
    WS_RC,
    WS_RD,
    WS_RT,
    WS_ST,
    WS_SZ,
)

__all__ = ["exact_impact_map", "kept_primal", "tangents"]

#: rows of the primal's switch log first asked for (doubled while it overflows)
LOG_ROWS = 64
#: the columns of an impulse of the arriving wave's derivative (``tangents``' ``pulses``): its arrival
#: time, its weight
PULSE_T, PULSE_W = 0, 1
#: the piston's first segment, among the segments' travel times
FIRST = 0


def _primal(bmap, q, v):
    """The primal blow with its switch log: ``(ws, scale)``, or None when a switch search was given
    up."""
    rows = LOG_ROWS
    while True:
        ws, scale = bmap.solve(q, v, lean=True, log=rows)
        RD, CI = ws[WS_RD], ws[WS_CI]
        if RD[RD_HEAD, RD_FULL].real == 0.0:
            break
        rows *= 4
    if CI[CI_GIVEUP] != 0:
        return None
    return ws, scale


def kept_primal(ws, scale, duration):
    """A primal blow's switch log kept from a run that logged its switches, for :func:`tangents`
    without solving the blow again (theory §11, "The coupled blow": the coupled blow's last force
    round, :mod:`~impactbar.laws.rodrock.coupled_exact`).

    Parameters
    ----------
    ws : tuple
        The run's workspace (:func:`~impactbar.laws.rodrock.exact.exact_blow`'s), its switch log
        written from the impact on.
    scale : float
        The run's force scale.
    duration : float
        The blow's end (model time from the impact), where the run was certified over: the tangent
        runs' horizon.

    Returns
    -------
    tuple or None
        ``(ws, scale)`` as :func:`_primal` gives them, ``ws`` the run's arrays copied but its pool's
        (``None``: the next blow's); None where the run logged nothing, its log overflowed or a
        switch search was given up (the primal then solved again, by :func:`_primal`).
    """
    RD, CI = ws[WS_RD], ws[WS_CI]
    if RD.shape[0] <= 1 or RD[RD_HEAD, RD_FULL].real != 0.0 or CI[CI_GIVEUP] != 0:
        return None
    light = (None,) * WS_CNT + tuple(x.copy() for x in ws[WS_CNT:])  # (the pool's arrays: before CNT)
    light[WS_PR][PR_TMAX] = duration  # (the tangent runs' horizon: the blow's end)
    return light, scale


def _bound(pieces, reach, spans=False):
    """Each direction's bound of its pieces (:func:`~impactbar.laws.rodrock.exact.exact_blow`'s
    scale): ``max over pieces of sum |c| max(L, 1)^d``, ``coefs`` of shape ``(K, n)``; with ``spans``
    (a drive's pieces, ``reach`` their spans) ``sum |c| L^d``, the sup over a piece's span, as the
    primal's drive takes it (a short piece's monomials' coefficients are large, up to 1e18 on the
    integrator's 6e-9 steps, and must not set the direction's size)."""
    reach = np.asarray(reach, dtype=float)
    if not spans:
        reach = np.maximum(reach, 1.0)
    # (the pieces of one shape and degrees at once: a drive's thousands of cubics in one product)
    groups: dict = {}
    for (_, d, c), r in zip(pieces, reach, strict=True):
        _, rs, cs = groups.setdefault((c.shape, np.asarray(d).tobytes()), (np.asarray(d), [], []))
        rs.append(r)
        cs.append(c)
    out = None
    for d, rs, cs in groups.values():
        C = np.stack(cs)
        r = np.asarray(rs).reshape((-1,) + (1,) * (C.ndim - 1))
        most = np.max(np.sum(np.abs(C) * r ** d, axis=-1), axis=0)
        out = most if out is None else np.maximum(out, most)
    return out


def tangents(bmap, ws, primal_scale, waves, drive=None, impulses=None, on_stop=False, arriving=None):
    """Tangent runs of a primal blow along ``K`` directions of its data, all in one compiled call
    (:func:`~impactbar.laws.rodrock._exacttangent.t_batch`), or one a direction where the wave
    arriving at the piston's driven end is wanted (``arriving``).

    Parameters
    ----------
    bmap : ExactBlowMap
    ws : tuple
        The primal's workspace, with its switch log (:func:`_primal`).
    primal_scale : float
        The primal's force scale.
    waves : list of 2 P tuples ``(exps, degs, coefs)``
        The directions' piston waves, ``coefs`` of shape ``(K, n)`` (:func:`initial_waves` of a
        batch).
    drive : tuple, optional
        ``(starts, [(exps, degs, coefs), ...])``: the directions' drives, ``coefs`` of shape
        ``(K, n_j)``.
    impulses : list of K lists of ``(t, w, jump)``, optional
        Each direction's impulses in the drive: the derivative ``w`` of a step ``jump`` of the drive
        at ``t`` (the step moves by ``-w/jump``).
    on_stop : bool
        Whether the primal's end was put back on the stop.
    arriving : array_like, shape (n,), optional
        Times from the impact (model units, in ``[0, T_0 + t_max]``, ``T_0`` the travel time of the
        piston's first segment) at which the derivative of the left-going wave ``G_0`` arriving at
        the piston's driven end is wanted (theory §11, "The coupled blow": the wave the drive meets,
        :mod:`~impactbar.laws.rodrock.coupled_exact`).

    Returns
    -------
    dq, dv : numpy.ndarray, shape (K, N + 1)
        The derivatives of the state after the blow.
    set_off : numpy.ndarray, shape (K, 2)
        The separations and the unloadings that a moving step set off, per run.
    dG : numpy.ndarray, shape (K, n)
        With ``arriving`` only: the derivative of ``G_0`` at those times, without its impulses.
    pulses : list of K arrays of shape (m, 2)
        With ``arriving`` only: the impulses (Dirac terms) of the derivative of ``G_0``, rows
        ``(arrival time at the driven end, weight)`` in time order: where a moving re-contact moves
        a jump of ``G_0`` by ``dt``, the weight is ``-[G_0] dt`` (the module's text).

    None where the schedule cannot be held.
    """
    from ._exactdata import _Data
    from .exact import _workspace
    from .exactmap import modal_state

    basis = bmap.basis
    M = basis.omega.size
    _, _, first = waves[0]
    K = first.shape[0]  # (the coefficients' directions)
    impulses = [[] for _ in range(K)] if impulses is None else impulses
    T, Z, lam, RT, RC, RD = ws[WS_ST], ws[WS_SZ], ws[WS_LAM], ws[WS_RT], ws[WS_RC], ws[WS_RD]
    n_p = basis.travel.size
    J = T.size
    scales = _bound(waves, np.repeat(basis.travel, 2))
    if drive is not None:
        starts, drive_pieces = drive
        spans = np.diff(np.append(starts, starts[-1] + 1.0))
        scales = np.maximum(scales, _bound(drive_pieces, spans, spans=True))
    scales = np.maximum(scales, [max((abs(w) for _, w, _ in x), default=0.0) for x in impulses])
    scales[scales == 0.0] = 1.0  # (a zero direction: zero)
    pieces = list(waves) + ([] if drive is None else list(drive_pieces))
    coefs = np.ascontiguousarray(np.concatenate([c for _, _, c in pieces], axis=-1) / scales[:, None])
    imps = np.array([(d, t, w / scales[d], jump / primal_scale) for d in range(K) for t, w, jump in
                     impulses[d]], dtype=float).reshape(-1, IMP_COLS)

    def ones(x):  # every term a slot of the template
        return [(e, d, np.ones(c.shape[-1], dtype=complex)) for e, d, c in x]

    template_drive = None if drive is None else (starts, ones(drive_pieces))
    terms = _Data(ones(waves), template_drive, T[:n_p], trusted=True).terms(lam, 1.0)
    PR = ws[WS_PR].copy()
    # no feed (a constant), the horizon, no record
    PR[PR_FEED], PR[PR_FIXED], PR[PR_P0], PR[PR_RECORD] = 0.0, 1.0, 0.0, 0.0
    PR[PR_DRIVEN] = 0.0 if drive is None else 1.0
    PR[PR_NODW] = 1.0  # (the drive's work is not wanted)
    CNT0 = ws[WS_CNT]
    pcap, tcap, icap = max(256, 2 * int(CNT0[CNT_PIECES])), max(2048, 2 * int(CNT0[CNT_TERMS])), 64
    travel = np.ascontiguousarray(basis.travel)
    om = np.ascontiguousarray(basis.omega)
    while True:
        wt = _workspace(T, Z, n_p, 0.0, 0.0, PR[PR_K], PR[PR_KU], lam, PR, RT, RC, RD, pcap, tcap, 4,
                        PR[PR_WINDOW], PR[PR_LB], PR[PR_ZBIT], terms)
        PF, PI, TK, TC, CNT, CHI = wt[:6]
        n0, nt0 = int(CNT[CNT_PIECES]), int(CNT[CNT_TERMS])
        template = (PF[:n0].copy(), PI[:n0].copy(), TK[:nt0].copy(), TC[:nt0].copy(), CNT.copy(),
                    CHI.copy(), wt[WS_NSI].copy())
        owners = list(range(2 * n_p)) + list(range(2 * J, n0))  # the piston's and the drive's
        slots = np.concatenate([np.arange(PI[c, PI_TERMS], PI[c, PI_TERMS] + PI[c, PI_COUNT])
                                for c in owners])
        tg = (np.zeros(icap), np.zeros(icap), np.zeros(icap), np.zeros(icap, dtype=np.int64),
              np.full((3 * J + 2, 2), -1, dtype=np.int64), np.zeros(TCUR_SIZE, dtype=np.int64))
        out = np.zeros((K, n_p, M, 2), dtype=complex)
        ends = np.zeros((K, END_COLS))
        if arriving is None:
            _, status = TG.t_batch(wt, tg, template, slots, coefs, imps, out, ends, travel, om)
        else:
            status, dG, pulses = _arriving_runs(wt, tg, template, slots, coefs, imps, out, ends, travel, om,
                                                np.asarray(arriving, dtype=float) - travel[FIRST])
        if status == 0:
            break
        if status == 3:
            return None
        if status == 1:
            pcap, tcap = 4 * pcap, 4 * tcap
        else:
            icap *= 4
    out *= scales[:, None, None, None]
    ends[:, :END_SEPS] *= scales[:, None]
    dq, dv = modal_state(basis, out, bmap._end(ends[:, END_SHANK], ends[:, END_GAP], ends[:, END_PPERM]))
    if on_stop:
        dq[:, 0] -= dq @ basis.end_weights
    if arriving is None:
        return dq, dv, ends[:, END_SEPS:].astype(int)
    for d in range(K):
        pulses[d][:, PULSE_T] += travel[FIRST]
        pulses[d][:, PULSE_W] *= scales[d]
    return dq, dv, ends[:, END_SEPS:].astype(int), dG * scales[:, None], pulses


def _arriving_runs(wt, tg, template, slots, coefs, imps, out, ends, travel, om, emitted):
    """:func:`~impactbar.laws.rodrock._exacttangent.t_batch` one direction at a time, and after each
    run its piston's first left-going wave (channel 1) at the times ``emitted`` (from its emission
    at the far end of segment 0) and that channel's impulses, ``(emission time, weight)`` rows (the
    run's own scale). Returns ``(status, dG, pulses)``: ``t_batch``'s status (nonzero: the caller's
    retry), the values, shape ``(K, n)``, and the K impulse arrays."""
    from .exactresult import _eval_channel

    K = coefs.shape[0]
    dG = np.zeros((K, emitted.size))
    pulses = []
    lamk = np.zeros(3)  # (the values only: no rock's force asked)
    for d in range(K):
        mine = imps[imps[:, IMP_DIR] == d].copy()
        mine[:, IMP_DIR] = 0.0
        _, status = TG.t_batch(wt, tg, template, slots, coefs[d:d + 1], mine, out[d:d + 1], ends[d:d + 1],
                               travel, om)
        if status != 0:
            return status, None, None
        PF, PI, TK, TC, _, CHI = wt[:6]
        # the pool keeps a wave channel's pieces from its first, the c-th piece (exactresult)
        dG[d] = _eval_channel((PF, PI, TK, TC, CHI, wt[WS_LAM], lamk), 1, emitted, 0, head=1)
        pulses.append(_channel_impulses(tg, 1))
    return 0, dG, pulses


def _channel_impulses(tg, c):
    """Every impulse emitted on channel ``c`` in a tangent run, received or not: ``(emission time,
    weight)`` rows in order (the queue's head moves on as they are received, its tail and the links
    stay: the chain walked back from the tail)."""
    IT, IW, _, IN, ICH, TCUR = tg
    n = int(TCUR[TCUR_N])
    before = np.full(n, -1, dtype=np.int64)
    links = IN[:n]
    has = links >= 0
    before[links[has]] = np.flatnonzero(has)
    chain = []
    i = int(ICH[c, ICH_TAIL])
    while i >= 0:
        chain.append(i)
        i = int(before[i])
    chain = np.array(chain[::-1], dtype=np.int64)
    return np.column_stack((IT[chain], IW[chain])) if chain.size else np.zeros((0, 2))


def _time_direction(bmap):
    """The impact time's direction of the drive: ``(drive pieces or None, impulses, p'(t0))``, or
    None for a load of no known form (central differences then)."""
    from ...dynamics.compiled_views import FOURIER, PIECEWISE
    from ...loads.abilities import compiled_kind

    kind = compiled_kind(bmap.load, "__call__")
    starts, pieces = bmap.drive
    if kind == FOURIER:
        exps, degs, coefs = pieces[0]
        d = coefs * exps  # d/dt0 of each harmonic e^{i k (t0 + s0)}
        lead = -float(starts[0])
        rate = float(np.sum(d * np.exp(exps * lead)).real)
        return ([float(starts[0])], [(exps, degs, d)]), [], rate
    if kind == PIECEWISE:
        levels = [float(np.real(c[0])) if c.size else 0.0 for _, _, c in pieces]  # (the constant's)
        imps = [(float(starts[j]), levels[j] - levels[j - 1], levels[j] - levels[j - 1])
                for j in range(1, len(starts)) if starts[j] > 0.0 and levels[j] != levels[j - 1]]
        return None, imps, 0.0
    return None


def exact_impact_map(bmap, y_minus, t):
    """The exact blow map's value and Jacobians (:meth:`RodRock.impact_map`'s), by tangent runs.

    Parameters
    ----------
    bmap : ExactBlowMap
        The map at load time ``t``.
    y_minus : array_like, shape (2 N + 2,)
        The arrival state.
    t : float
        The impact's load time (that of ``bmap``).

    Returns
    -------
    tuple or None
        ``(y_plus, jac_y, jac_t)`` (shapes ``(2 N + 2,)``, ``(2 N + 2, 2 N + 2)``, ``(2 N + 2,)``), or
        None where the map has no derivative the tangent can give (a grazing re-contact, a switch
        search given up): central differences are the caller's.
    """
    from .exactmap import initial_waves

    basis = bmap.basis
    M = basis.omega.size
    y = np.asarray(y_minus, dtype=float)
    c = basis.end_weights
    q = y[:M].copy()
    q[0] -= float(c @ q)
    v = y[M:].copy()
    primal = _primal(bmap, q, v)
    if primal is None:
        return None
    ws, scale = primal
    qa, va, on_stop = bmap.after_run(ws, scale)
    y_plus = np.concatenate((qa, va))
    # the directions: q_1 .. q_N, q'_0 .. q'_N, and the impact time where the load's form is known
    K = 2 * M - 1
    dq = np.zeros((K + 1, M))
    dv = np.zeros((K + 1, M))
    dq[np.arange(M - 1), np.arange(1, M)] = 1.0
    dv[np.arange(M - 1, K), np.arange(M)] = 1.0
    res = tangents(bmap, ws, scale, initial_waves(basis, dq[:K], dv[:K], np.zeros(K)), None, None,
                   on_stop)
    if res is None:
        return None
    jac = np.zeros((2 * M, 2 * M))
    dq_y, dv_y, _ = res
    jac[:, 1:] = np.concatenate((dq_y, dv_y), axis=1).T
    # the impact time apart (a drive in the tangent costs every run its exponents)
    timed = _time_direction(bmap)
    if timed is None:
        up, down = bmap.shifted([bmap.t0 + 1e-6, bmap.t0 - 1e-6])
        return y_plus, jac, (up(y) - down(y)) / 2e-6
    drive, imps, rate = timed
    if drive is not None:
        starts, drive_pieces = drive
        drive = (starts, [(e, d, c[None]) for e, d, c in drive_pieces])
    res = tangents(bmap, ws, scale, initial_waves(basis, dq[K:], dv[K:], np.array([rate])), drive, [imps],
                   on_stop)
    if res is None:
        return None
    dq_t, dv_t, _ = res  # (one direction: the impact time's)
    return y_plus, jac, np.concatenate((dq_t.ravel(), dv_t.ravel()))
