"""The exact blow's runs that go on from a snapshot of an earlier run
(:func:`~impactbar.laws.rodrock.exact.exact_blow`'s ``_keep``): the coupled blow's iterates
(:mod:`~impactbar.laws.rodrock.coupled_exact`), each solved from where the last one's drive was its
own rather than from the impact (theory §11, "The coupled blow")."""

from __future__ import annotations

import math

import numpy as np

from . import _exactloop as K
from . import _exactpieces as P
from . import _records as S

__all__: list[str] = []


def pool_bytes(pcap, tcap):
    """The memory of a pool of ``pcap`` pieces (``PF``, ``PI``: 72 bytes each) and ``tcap`` terms
    (``TK``, ``TC``: 24 bytes each) of the exact solver's workspace."""
    return pcap * 72 + tcap * 24


def run_kernel(ws, t_account):
    """:func:`~._exactloop.run` of ``ws`` (``t_account``: its own), by its interpreted twin in a
    process's first blows (:func:`~impactbar.dynamics.compiled.interpreted_first`: the machine code's
    bits, without its compile), by its machine code once they have spent the twin's budget."""
    from ...dynamics.compiled import interpreted_first

    interpreted_first(K.run)(ws, t_account)


def _run(ws, t_max, stops, h, snaps, scale):
    """The run of ``ws`` to ``t_max`` (``None``: its end), stopped at the last window boundary before
    each of ``stops`` (increasing; those it is past skipped) for a snapshot (:func:`_take`, appended
    to ``snaps``): the same windows as one run (a stop ends a window as ``t_max`` does, and the next
    window starts where it ended). A run that ends or fills its pool before a stop ends there."""
    PR, CI, CT = ws[S.WS_PR], ws[S.WS_CI], ws[S.WS_CT]
    end = math.inf if t_max is None else t_max
    for s in stops:
        w = math.ceil(s / h) - 1
        stop = w * h  # (the window boundary as the kernel computes it)
        if w <= CI[S.CI_WIN] or stop >= end:
            continue
        PR[S.PR_TMAX] = stop
        run_kernel(ws, -1.0)
        if CI[S.CI_STATUS] != 0 or CI[S.CI_END] != P.TMAX or CT[S.CT_T] != stop:
            PR[S.PR_TMAX] = end
            return
        snaps.append(_take(ws, scale))
    PR[S.PR_TMAX] = end
    run_kernel(ws, -1.0)


def _take(ws, scale):
    """A snapshot of a stopped run (its state but for the pool, of which what the run goes on to
    change: the counts and the channels' last pieces, which it links on or replaces) and its scale:
    where a run with a drive the same up to there goes on from (:func:`_resumed`). The pool's other
    pieces stay as they are (a piece once followed by another is only read on, its whole integrals
    cached once), so that the snapshot holds while the pool's arrays are this blow's alone."""
    PF, PI = ws[S.WS_PF], ws[S.WS_PI]
    tails = ws[S.WS_CHI][:, S.CHI_TAIL].copy()
    tails = tails[tails >= 0]
    return ws[:4], tuple(x.copy() for x in ws[4:]), tails, PF[tails].copy(), PI[tails].copy(), scale


def _chain(PI, first, last, most):
    """The rows of a channel's pieces from ``first`` to ``last`` along their links (runs of rows one
    after another, each found at once), or ``None`` where ``last`` is not within ``most`` of them."""
    parts, r, n = [], first, 0
    while n < most:
        stop = min(PI.shape[0], r + most - n)
        off = np.flatnonzero(PI[r:stop, S.PI_NEXT] != np.arange(r + 1, stop + 1))
        end = r + (int(off[0]) if off.size else stop - r - 1)  # (the run's last row)
        if r <= last <= end:
            parts.append(np.arange(r, last + 1))
            return np.concatenate(parts)
        parts.append(np.arange(r, end + 1))
        n += end + 1 - r
        r = int(PI[end, S.PI_NEXT])
        if r < 0:
            return None
    return None


def _resumed(snaps, drive, scale, lam, PR, pcap, tcap, force_new=False, *, bound):
    """A workspace going on from the latest of the snapshots ``snaps`` (:func:`_take`) whose run read
    the same drive as ``drive`` (:meth:`_Data.terms`' ``(starts, keys, coefs, sizes)``: the pieces up
    to the one it was in, and the next one's start, equal to the bit) under the same parameters
    ``PR`` (but its horizon and the energy at impact, the snapshot's) and ``scale``: the snapshot's
    pool (in place, or copied to a larger one where it holds less than ``pcap`` pieces and ``tcap``
    terms) set back to it, ``drive``'s later pieces appended and linked after that one. ``None``
    where none did (the blow then solved from its start)."""
    starts, keys, coefs, sizes = drive
    nz = coefs != 0.0
    k_nz, c_nz = keys[nz], coefs[nz]
    before = np.concatenate(([0], np.cumsum(nz)))[np.concatenate(([0], np.cumsum(sizes)))]  # (nonzero
    counts = np.diff(before)  # terms before each piece, and each one's)
    same = np.ones(PR.size, dtype=bool)
    same[[S.PR_TMAX, S.PR_E0]] = False
    for pool, small, tails, tail_f, tail_i, s_scale in reversed(snaps):
        PF0, PI0, TK0, TC0 = pool
        CNT0, CHI0 = small[S.WS_CNT - 4], small[S.WS_CHI - 4]
        if s_scale != scale or not np.array_equal(small[S.WS_LAM - 4], lam) or \
                not np.array_equal(small[S.WS_PR - 4][same], PR[same]):
            continue
        c = 2 * small[S.WS_SZ - 4].size  # the drive's channel, its first piece row c (_workspace)
        cur = int(CHI0[c, S.CHI_HEAD])  # the drive's piece the run was in, and the chain up to the next one
        rows = _chain(PI0, c, cur, starts.size)
        nxt = int(PI0[cur, S.PI_NEXT]) if cur not in tails else -1
        if rows is None or nxt < 0 or rows.size >= starts.size:
            continue
        i = rows.size - 1
        n_old = PI0[rows, S.PI_COUNT]
        at = np.repeat(PI0[rows, S.PI_TERMS] - np.concatenate(([0], np.cumsum(n_old)[:-1])), n_old) + \
            np.arange(int(n_old.sum()))
        if not (np.array_equal(PF0[rows, S.PF_START], starts[:i + 1])
                and PF0[nxt, S.PF_START] == starts[i + 1] and np.array_equal(n_old, counts[:i + 1])
                and np.array_equal(TK0[at], k_nz[:at.size]) and np.array_equal(TC0[at], c_nz[:at.size])):
            continue
        npc, nt = int(CNT0[S.CNT_PIECES]), int(CNT0[S.CNT_TERMS])
        new, new_t = starts.size - (i + 1), int(before[-1] - before[i + 1])
        # the pool in place where it holds half of the hint ``pcap, tcap`` (the map's, from its last
        # blow: twice what that took, grown with the horizon) or of twice what it has, the larger (a
        # pool that fills: the caller goes on from the snapshot again on a larger one), else one of
        # twice that (the next rounds on in place; the pages not written not taken), at most 8 times
        # what it has where that is more (a hint for a far horizon: the coupled blow's last rounds)
        rows, terms = max(pcap, 2 * (npc + new)), max(tcap, 2 * (nt + new_t))
        if PF0.shape[0] >= rows // 2 and TK0.size >= terms // 2 and not force_new:
            PF, PI, TK, TC = PF0, PI0, TK0, TC0
        else:
            more = (min(2 * rows, max(rows, 8 * (npc + new))), min(2 * terms, max(terms, 8 * (nt + new_t))))
            if pool_bytes(*more) <= bound:
                rows, terms = more
            PF, PI = np.empty((rows, 5)), np.empty((rows, 4), dtype=np.int64)
            TK, TC = np.empty(terms, dtype=np.int64), np.empty(terms, dtype=complex)
            PF[:npc], PI[:npc], TK[:nt], TC[:nt] = PF0[:npc], PI0[:npc], TK0[:nt], TC0[:nt]
        PF[tails], PI[tails] = tail_f, tail_i
        r = slice(npc, npc + new)
        PF[r, S.PF_START], PF[r, S.PF_VALID], PF[r, S.PF_REF] = starts[i + 1:], math.inf, 0.0
        PF[r, S.PF_INT:] = math.nan
        PI[r, S.PI_NEXT] = np.arange(npc + 1, npc + new + 1)
        PI[npc + new - 1, S.PI_NEXT] = -1
        PI[r, S.PI_TERMS] = nt + before[i + 1:-1] - before[i + 1]
        PI[r, S.PI_COUNT] = counts[i + 1:]
        PI[r, S.PI_FLAG] = 0
        TK[nt:nt + new_t], TC[nt:nt + new_t] = k_nz[before[i + 1]:], c_nz[before[i + 1]:]
        PI[cur, S.PI_NEXT] = npc  # (the snapshot's later pieces of the drive left unlinked)
        ws = (PF, PI, TK, TC, *(x.copy() for x in small))
        ws[S.WS_CHI][c, S.CHI_TAIL] = npc + new - 1
        ws[S.WS_CNT][S.CNT_PIECES], ws[S.WS_CNT][S.CNT_TERMS] = npc + new, nt + new_t
        return ws
    return None
