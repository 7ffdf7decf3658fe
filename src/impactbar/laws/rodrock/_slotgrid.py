"""The slot lattice's operations on its slots (:mod:`._rockslots`, theory §11): the delayed waves'
slot averages and where they jump, the slots cut and gathered, the merges by least loss (a heap on a
linked list of the slots), and the slots' energies. Kernels that only the slot lattice's loop calls
(link-only, :func:`~impactbar._shared.wrappers.internal_kernels`)."""

from __future__ import annotations

import numba

from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE, sort_head

__all__: list = []


@numba.njit(cache=CACHE, nogil=True)
def _nb_delayed(prev, Wp, nWp, cur, W, nW, delta, edges, cum, out):
    """:func:`_delayed` with ``target = W``: ``out[:nW]`` (``np.interp``'s arithmetic)."""
    c = 0.0
    edges[0] = (0.0 + delta) - 1.0
    for m in range(nWp):
        c += Wp[m]
        edges[m + 1] = (c + delta) - 1.0
    c = 0.0
    for m in range(nW):
        c += W[m]
        edges[nWp + 1 + m] = c + delta
    ne = nWp + nW + 1
    cum[0] = 0.0
    s = 0.0
    for m in range(ne - 1):
        v = prev[m] if m < nWp else cur[m - nWp]
        s += v * (edges[m + 1] - edges[m])
        cum[m + 1] = s
    j = 0
    lo = 0.0
    c = 0.0
    for m in range(nW + 1):
        if m == 0:
            x = 0.0
        elif m == nW:
            x = 1.0
        else:
            c += W[m - 1]
            x = c
        if x > edges[ne - 1]:
            val = cum[ne - 1]
        elif x < edges[0]:
            val = cum[0]
        else:
            while j + 1 < ne and edges[j + 1] <= x:
                j += 1
            if j == ne - 1 or edges[j] == x:
                val = cum[j]
            else:
                slope = (cum[j + 1] - cum[j]) / (edges[j + 1] - edges[j])
                val = slope * (x - edges[j]) + cum[j]
        if m > 0:
            out[m - 1] = (val - lo) / W[m - 1]
        lo = val


@numba.njit(cache=CACHE, nogil=True)
def _nb_jump_cuts(prev, Wp, nWp, cur, W, nW, delta, thr, cuts, nc):
    """:func:`_jump_cuts` appended to ``cuts[nc:]``: the new count."""
    c = 0.0
    for m in range(nWp - 1):
        c += Wp[m]
        if abs(prev[m + 1] - prev[m]) > thr:
            e = (c + delta) - 1.0
            if e > 0.0:
                cuts[nc] = e
                nc += 1
    c = 0.0
    for m in range(nW - 1):
        c += W[m]
        if abs(cur[m + 1] - cur[m]) > thr:
            e = c + delta
            if e < 1.0:
                cuts[nc] = e
                nc += 1
    if abs(cur[0] - prev[nWp - 1]) > thr and 0.0 < delta < 1.0:
        cuts[nc] = delta
        nc += 1
    return nc


@numba.njit(cache=CACHE, nogil=True)
def _nb_refine(W, nW, cuts, ncut, eold, ubuf, idx):
    """:func:`_refine`'s new slots: ``W`` rewritten, ``idx[:n]`` each new slot's old one; the new count
    ``n`` (``nW``: unchanged)."""
    c = 0.0
    eold[0] = 0.0
    for m in range(nW):
        c += W[m]
        eold[m + 1] = c
    eold[nW] = 1.0
    n = nW + 1 + ncut
    for m in range(nW + 1):
        ubuf[m] = eold[m]
    for m in range(ncut):
        ubuf[nW + 1 + m] = cuts[m]
    srt = sort_head(ubuf, n)  # (in place: the compaction below writes no entry before it reads it)
    # np.unique, then the kept ones: a difference from the previous unique value above 1e-13
    nn = 1
    ubuf[0] = srt[0]
    prev_u = srt[0]
    for m in range(1, n):
        u = srt[m]
        if u != prev_u:
            if u - prev_u > 1e-13:
                ubuf[nn] = u
                nn += 1
            prev_u = u
    if ubuf[nn - 1] < 1.0:
        ubuf[nn - 1] = 1.0
    if nn == nW + 1:
        return nW
    i = 0
    for m in range(nn - 1):
        mid = 0.5 * (ubuf[m] + ubuf[m + 1])
        while i + 1 <= nW and eold[i + 1] <= mid:
            i += 1
        idx[m] = min(i, nW - 1)
    for m in range(nn - 1):
        W[m] = ubuf[m + 1] - ubuf[m]
    return nn - 1


@numba.njit(cache=CACHE, nogil=True)
def _nb_gather(x, idx, n, tmp):
    """``x[:n] = x[idx[:n]]`` (rows)."""
    for m in range(n):
        for j in range(x.shape[1]):
            tmp[m, j] = x[idx[m], j]
    for m in range(n):
        for j in range(x.shape[1]):
            x[m, j] = tmp[m, j]


@numba.njit(cache=CACHE, nogil=True)
def _nb_insert(x, k, nW):
    """A copy of row ``k`` inserted after it (rows ``k + 1 .. nW - 1`` moved down one)."""
    for m in range(nW, k, -1):
        for j in range(x.shape[1]):
            x[m, j] = x[m - 1, j]


@numba.njit(cache=CACHE, nogil=True)
def _nb_pair_loss(Fn, Gn, W, a, b):
    d2 = 0.0
    for j in range(Fn.shape[1]):
        d = Fn[b, j] - Fn[a, j]
        d2 += d * d
    for j in range(Gn.shape[1]):
        d = Gn[b, j] - Gn[a, j]
        d2 += d * d
    return d2 * W[a] * W[b] / (W[a] + W[b])


@numba.njit(cache=CACHE, nogil=True)
def _heap_less(hk, hi, a, b):
    return hk[a] < hk[b] or (hk[a] == hk[b] and hi[a] < hi[b])


@numba.njit(cache=CACHE, nogil=True)
def _heap_push(hk, hi, hv, n, key, i, v):
    hk[n], hi[n], hv[n] = key, i, v
    c = n
    while c > 0:
        p = (c - 1) // 2
        if _heap_less(hk, hi, c, p):
            hk[c], hk[p] = hk[p], hk[c]
            hi[c], hi[p] = hi[p], hi[c]
            hv[c], hv[p] = hv[p], hv[c]
            c = p
        else:
            break
    return n + 1


@numba.njit(cache=CACHE, nogil=True)
def _heap_pop(hk, hi, hv, n):
    """The root removed: the new count (the root's entry left at ``n - 1``)."""
    n -= 1
    hk[0], hk[n] = hk[n], hk[0]
    hi[0], hi[n] = hi[n], hi[0]
    hv[0], hv[n] = hv[n], hv[0]
    c = 0
    while True:
        lft, rgt, s = 2 * c + 1, 2 * c + 2, c
        if lft < n and _heap_less(hk, hi, lft, s):
            s = lft
        if rgt < n and _heap_less(hk, hi, rgt, s):
            s = rgt
        if s == c:
            break
        hk[c], hk[s] = hk[s], hk[c]
        hi[c], hi[s] = hi[s], hi[c]
        hv[c], hv[s] = hv[s], hv[c]
        c = s
    return n


@numba.njit(cache=CACHE, nogil=True)
def _nb_merge(W, nW, Fn, Gn, cap, nxt, prv, ver, hk, hi, hv):
    """The slots past ``cap`` merged, the adjacent pair whose average loses least first (the module's
    text), in ``W``, ``Fn``, ``Gn`` (rows ``:nW``): the new count and the merges made."""
    if nW <= cap:
        return nW, 0
    merges = 0
    for i in range(nW):
        nxt[i] = i + 1 if i + 1 < nW else -1
        prv[i] = i - 1
        ver[i] = 0
    nh = 0
    for i in range(nW - 1):
        nh = _heap_push(hk, hi, hv, nh, _nb_pair_loss(Fn, Gn, W, i, i + 1), i, 0)
    n = nW
    while n > cap:
        nh = _heap_pop(hk, hi, hv, nh)
        i, v = hi[nh], hv[nh]
        if v != ver[i] or nxt[i] < 0:
            continue  # a stale entry (its pair changed, or its left slot merged away: ver < 0)
        j = nxt[i]
        w = W[i] + W[j]
        for c in range(Fn.shape[1]):
            Fn[i, c] = (Fn[i, c] * W[i] + Fn[j, c] * W[j]) / w
        for c in range(Gn.shape[1]):
            Gn[i, c] = (Gn[i, c] * W[i] + Gn[j, c] * W[j]) / w
        W[i] = w
        nxt[i] = nxt[j]
        if nxt[j] >= 0:
            prv[nxt[j]] = i
        ver[j] = -1
        n -= 1
        merges += 1
        ver[i] += 1
        if nxt[i] >= 0:
            nh = _heap_push(hk, hi, hv, nh, _nb_pair_loss(Fn, Gn, W, i, nxt[i]), i, ver[i])
        if prv[i] >= 0:
            a = prv[i]
            ver[a] += 1
            nh = _heap_push(hk, hi, hv, nh, _nb_pair_loss(Fn, Gn, W, a, i), a, ver[a])
    pos, i = 0, 0
    while i >= 0:
        if i != pos:
            W[pos] = W[i]
            for c in range(Fn.shape[1]):
                Fn[pos, c] = Fn[i, c]
            for c in range(Gn.shape[1]):
                Gn[pos, c] = Gn[i, c]
        pos += 1
        i = nxt[i]
    return n, merges


@numba.njit(cache=CACHE, nogil=True)
def _nb_energy(F, G, W, n, Z, j0, j1):
    """``sum_k W_k sum_j (F_kj^2 + G_kj^2) / Z_j`` over the rows ``:n`` and the cells ``j0:j1`` (the
    waves' energy over a step's time, divided by the step)."""
    e = 0.0
    for k in range(n):
        ek = 0.0
        for j in range(j0, j1):
            ek += (F[k, j] * F[k, j] + G[k, j] * G[k, j]) / Z[j]
        e += ek * W[k]
    return e


@numba.njit(cache=CACHE, nogil=True)
def _nb_window(prev, Wp, nWp, cur, W, nWc, a, b):
    """``int_a^b s(t)^2 dt`` of the piecewise-constant ``s``: ``prev`` on its slots ``Wp`` over
    ``[-1, 0]``, ``cur`` on ``W[:nWc]`` from 0 (a delay's content, in steps)."""
    e, lo = 0.0, -1.0
    for m in range(nWp):
        hi = lo + Wp[m]
        e += prev[m] * prev[m] * max(min(hi, b) - max(lo, a), 0.0)
        lo = hi
    lo = 0.0
    for m in range(nWc):
        hi = lo + W[m]
        e += cur[m] * cur[m] * max(min(hi, b) - max(lo, a), 0.0)
        lo = hi
    return e


@numba.njit(cache=CACHE, nogil=True)
def _nb_absmax(x, rows, cols):
    """The largest ``|x[k, j]|`` over the first ``rows`` rows and ``cols`` columns (0 for none)."""
    big = 0.0
    for k in range(rows):
        for j in range(cols):
            big = max(big, abs(x[k, j]))
    return big


internal_kernels(globals())  # all link-only: the slot lattice's loop calls them
