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

Where the schedule cannot be held (a re-contact at zero closing speed, where the map has no
derivative; a switch search the primal gave up) :func:`exact_impact_map` returns ``None`` and the
caller falls back on central differences.
"""

from __future__ import annotations

import numpy as np

from . import _exacttangent as TG
from ._exactmodal import piston_integrals

__all__ = ["exact_impact_map"]

#: rows of the primal's switch log first asked for (doubled while it overflows)
LOG_ROWS = 64


def _primal(bmap, q, v):
    """The primal blow with its switch log: ``(ws, scale)``, or None when a switch search was given
    up."""
    rows = LOG_ROWS
    while True:
        ws, scale = bmap.solve(q, v, lean=True, log=rows)
        RD, CI = ws[22], ws[24]
        if RD[0, 1].real == 0.0:
            break
        rows *= 4
    if CI[4] != 0:
        return None
    return ws, scale


def _plus(bmap, ws, scale):
    """The state after the primal blow (:meth:`ExactBlowMap.__call__`'s), and whether the end was put
    back on the stop."""
    from .exactmap import project

    PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam = ws[:9]
    NSF, BS = ws[16], ws[18]
    n_p = bmap.basis.travel.size
    end = bmap._end(scale * NSF[n_p, 1], scale * NSF[n_p, 0], scale * BS[5])
    qa, va = project(bmap.basis, (scale, (PF, PI, TK, TC, CHI, lam, None)), float(ws[25][0]), end)
    over = float(bmap.basis.end_weights @ qa)
    if over > 0.0:
        qa[0] -= over
    return qa, va, over > 0.0


def _tangent(bmap, ws, primal_scale, initial, drive, impulses, on_stop):
    """One tangent run of the primal workspace ``ws`` (its forces over ``primal_scale``) along the
    direction whose piston waves are ``initial``, drive ``drive`` (pieces or None) and drive impulses
    ``impulses`` (``(t, w, jump)``: the derivative ``w`` of a step ``jump`` of the drive at ``t``):
    ``(dq, dv)``, or None where the schedule cannot be held."""
    from .exact import _binomials, _Data, _workspace
    from .exactmap import modal_state

    basis = bmap.basis
    PR0 = ws[13]
    T, Z, lam, RT, RC, RD = ws[15], ws[14], ws[8], ws[20], ws[21], ws[22]
    n_p = int(PR0[21])
    J = T.size
    data = _Data(initial, drive, T[:n_p], trusted=True)
    scale = max(data.scale, max((abs(w) for _, w, _ in impulses), default=0.0))
    M = basis.omega.size
    if scale == 0.0:
        return np.zeros(M), np.zeros(M)
    PR = PR0.copy()
    PR[3] = 0.0  # no feed: a constant
    PR[6] = 1.0  # the primal's horizon
    PR[20] = 0.0
    PR[22] = 1.0 if drive is not None else 0.0
    PR[23] = 0.0  # nothing recorded
    CNT0 = ws[4]
    pcap, tcap, ecap, icap = max(256, 2 * int(CNT0[0])), max(2048, 2 * int(CNT0[1])), 4, 64
    terms = data.terms(lam, scale)
    nch = 3 * J + 2
    while True:
        wt = _workspace(T, Z, n_p, 0.0, 0.0, PR[0], PR[1], lam, PR, RT, RC, RD, pcap, tcap, ecap, PR[17],
                        PR[8], PR[4], terms)
        tg = (np.zeros(icap), np.zeros(icap), np.zeros(icap), np.zeros(icap, dtype=np.int64),
              np.full((nch, 2), -1, dtype=np.int64), np.zeros(7, dtype=np.int64))
        for t, w, jump in impulses:
            TG.imp_emit(tg, 2 * J, t, w / scale, jump / primal_scale)
        TG.t_run(wt, tg)
        status = int(wt[24][0])
        if status == 0:
            break
        if status == 3:
            return None
        if status == 1:
            pcap, tcap = 4 * pcap, 4 * tcap
        else:
            icap *= 4
    NSF, BS, CHI, CH_T = wt[16], wt[18], wt[5], wt[6]
    end = scale * bmap._end(NSF[n_p, 1], NSF[n_p, 0], BS[5])
    t_end = float(wt[25][0])
    out = np.zeros((n_p, M, 2), dtype=complex)
    travel = np.ascontiguousarray(basis.travel)
    om = np.ascontiguousarray(basis.omega)
    piston_integrals((wt[0], wt[1], wt[2], wt[3], lam, _binomials()), CHI[: 2 * n_p, 1].copy(), travel,
                     t_end, om, out)
    TG.impulse_integrals(tg, travel, CH_T, t_end, om, out)
    out *= scale
    dq, dv = modal_state(basis, out, end)
    if on_stop:
        dq[0] -= float(basis.end_weights @ dq)
    return dq, dv


def _state_columns(bmap, ws, primal_scale, on_stop):
    """The Jacobian's columns of the state directions ``q_1 .. q_N``, ``q'_0 .. q'_N`` (shape
    ``(2 N + 2, 2 N + 1)``), by :func:`~._exacttangent.t_batch`: one workspace, every run in one
    call; None where the schedule cannot be held."""
    from .exact import _Data, _workspace
    from .exactmap import initial_waves, modal_state

    basis = bmap.basis
    M = basis.omega.size
    K = 2 * M - 1
    dq = np.zeros((K, M))
    dv = np.zeros((K, M))
    dq[np.arange(M - 1), np.arange(1, M)] = 1.0
    dv[np.arange(M - 1, K), np.arange(M)] = 1.0
    waves = initial_waves(basis, dq, dv, np.zeros(K))
    T, Z, lam, RT, RC, RD = ws[15], ws[14], ws[8], ws[20], ws[21], ws[22]
    n_p = basis.travel.size
    J = T.size
    # each direction's scale (exact_blow's: the bound of its waves), its coefficients over it
    reach = np.maximum(np.repeat(basis.travel, 2), 1.0)
    scales = np.max([np.sum(np.abs(c) * r ** d, axis=-1) for (_, d, c), r in zip(waves, reach, strict=True)],
                    axis=0)
    coefs = np.ascontiguousarray(np.concatenate([c for _, _, c in waves], axis=-1) / scales[:, None])
    ones = [(e, d, np.ones(c.shape[-1], dtype=complex)) for e, d, c in waves]  # every term a slot
    PR = ws[13].copy()
    PR[3], PR[6], PR[20], PR[22], PR[23] = 0.0, 1.0, 0.0, 0.0, 0.0  # no feed, the horizon, no drive
    CNT0 = ws[4]
    pcap, tcap, icap = max(256, 2 * int(CNT0[0])), max(2048, 2 * int(CNT0[1])), 64
    terms = _Data(ones, None, T[:n_p], trusted=True).terms(lam, 1.0)
    travel = np.ascontiguousarray(basis.travel)
    om = np.ascontiguousarray(basis.omega)
    while True:
        wt = _workspace(T, Z, n_p, 0.0, 0.0, PR[0], PR[1], lam, PR, RT, RC, RD, pcap, tcap, 4, PR[17],
                        PR[8], PR[4], terms)
        PF, PI, TK, TC, CNT, CHI = wt[:6]
        n0, nt0 = int(CNT[0]), int(CNT[1])
        template = (PF[:n0].copy(), PI[:n0].copy(), TK[:nt0].copy(), TC[:nt0].copy(), CNT.copy(),
                    CHI.copy(), wt[17].copy())
        slots = np.concatenate([np.arange(PI[c, 1], PI[c, 1] + PI[c, 2]) for c in range(2 * n_p)])
        tg = (np.zeros(icap), np.zeros(icap), np.zeros(icap), np.zeros(icap, dtype=np.int64),
              np.full((3 * J + 2, 2), -1, dtype=np.int64), np.zeros(7, dtype=np.int64))
        out = np.zeros((K, n_p, M, 2), dtype=complex)
        ends = np.zeros((K, 3))
        _, status = TG.t_batch(wt, tg, template, slots, coefs, out, ends, travel, om)
        if status == 0:
            break
        if status == 3:
            return None
        if status == 1:
            pcap, tcap = 4 * pcap, 4 * tcap
        else:
            icap *= 4
    out *= scales[:, None, None, None]
    ends *= scales[:, None]
    dq, dv = modal_state(basis, out, bmap._end(ends[:, 0], ends[:, 1], ends[:, 2]))
    if on_stop:
        dq[:, 0] -= dq @ basis.end_weights
    return np.concatenate((dq, dv), axis=1).T


def _time_direction(bmap):
    """The impact time's direction of the drive: ``(drive pieces or None, impulses, p'(t0))``, or
    None for a load of no known form (central differences then)."""
    from ...dynamics.kernelview import FOURIER, PIECEWISE

    kind = bmap.load.compiled_kind("__call__")
    starts, pieces = bmap.drive
    if kind == FOURIER:
        exps, degs, coefs = pieces[0]
        d = coefs * exps  # d/dt0 of each harmonic e^{i k (t0 + s0)}
        lead = -float(starts[0])
        rate = float(np.sum(d * np.exp(exps * lead)).real)
        return ([float(starts[0])], [(exps, degs, d)]), [], rate
    if kind == PIECEWISE:
        levels = [float(np.real(p[2][0])) if p[2].size else 0.0 for p in pieces]
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
    qa, va, on_stop = _plus(bmap, ws, scale)
    y_plus = np.concatenate((qa, va))
    jac = np.zeros((2 * M, 2 * M))
    zero = np.zeros(M)
    cols = _state_columns(bmap, ws, scale, on_stop)
    if cols is None:
        return None
    jac[:, 1:] = cols
    direction = _time_direction(bmap)
    if direction is None:
        up, down = bmap.shifted([bmap.t0 + 1e-6, bmap.t0 - 1e-6])
        jt = (up(y) - down(y)) / 2e-6
    else:
        drive, imps, rate = direction
        res = _tangent(bmap, ws, scale, initial_waves(basis, zero, zero, rate), drive, imps, on_stop)
        if res is None:
            return None
        jt = np.concatenate(res)
    return y_plus, jac, jt
