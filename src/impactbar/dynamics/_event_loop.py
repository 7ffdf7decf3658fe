"""Compiled core of the event-driven simulator (theory §2, §4, §8). Plain float arrays only.

Between events every mode obeys ``q'' + d q' + w2 q = p(t)`` and is advanced in closed form from an
*anchor* (the last impact, or for a piecewise-constant load the last load jump):

- harmonic load (``kind = 0``): ``q = Phi(t - ta) (y_a - y_p(ta)) + y_p(t)`` with the periodic
  particular solution ``y_p = p0/w2 + Re sum_k H_nk p_k exp(i k t)`` (eq. 8); the rigid mode adds
  the mean-load terms ``p0 c(tau)``, ``p0 b(tau)``;
- piecewise-constant load (``kind = 1``): the same with the static deflection ``level / w2`` of
  the current piece; the search stops at every jump and re-anchors there, so nothing is truncated.

The event search, certified, is :mod:`impactbar.dynamics._crossing`.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .._shared.literals import plain_literals
from .._shared.wrappers import internal_kernels
from ._crossing import (  # the certified event search, below this module
    FAIL,
    NONE,
    TOUCH,
    _modal_crossing,
    find_crossing,
    flow_scratch,
    rigid1_crossing,
)
from ._flight import (  # the closed-form flight and the certified step, below this module
    CACHE,
    advance,
    first_piece,
    functional,
    load_value,
    next_piece,
    piece_end,
    piece_of,
)
from .compiled_views import LoadKernelView, ModalBasisView

# statuses of run_free
END = 0
MAXIMP = 1
CHATTER = 2
CONTACT = 3
FULL = 4
FAILED = 5

#: the rows of the modal search's blocks in :func:`_run_free`, by name (a row of a block taken by an
#: integer is a C array; unpacking the block gives arrays of any layout, more compilations)
MB_LAM, MB_WSQ, MB_CA, MB_CB, MB_CVA, MB_CVB = range(6)
KB_HCR, KB_HCI, KB_HWR, KB_HWI = range(4)


def _run_free(load_t, B_t, R, c, start, t_end, max_imp, tail_tol, out, rigid_fast, modal_fast):
    """Free flight with impacts from ``start = (t, q, v)`` in the free-free basis ``B_t`` (the plain
    tuple of a :class:`~impactbar.dynamics.compiled_views.ModalBasisView`) under ``load_t`` (that of a
    :class:`~impactbar.dynamics.compiled_views.LoadKernelView`: numba dispatches plain tuples several
    times faster than named tuples); ``q, v`` are overwritten with the final state. Compiled twice
    from this one source, as :func:`run_free` (flexible bars: ``rigid_fast`` is ``None``) and
    :func:`run_free_rigid` (``modal_fast`` is ``None``), each with one signature and no wrapper
    kernel (a wrapper compiles its callees' code again).

    Every impact (``c . q = 0`` reached with ``c . v > 0``) applies ``v -> -R v`` (eqs. 10, 11); its
    time, the arrival velocity ``c . v`` and the state just after are written to
    ``out = (out_t, out_vel, out_q, out_v)``. Stops at
    ``t_end`` (END), after ``max_imp`` impacts (MAXIMP), when the buffers are full (FULL), when the
    bounces accumulate (CHATTER: the returned time is the accumulation point, ``v = 0``; with
    ``R > 0`` tested before the count, so the last impact asked for may end in CHATTER too, its
    bounces summed) or the end arrives tangentially and pressed (CONTACT).

    With ``rigid_fast`` true the flights that follow an impact (or start
    clearly off the stop, or leaving it) are searched by :func:`rigid1_crossing` (the rigid bar under
    one harmonic), with ``modal_fast`` true by :func:`modal_crossing` (flexible modes under a
    Fourier load, all underdamped): the same impacts, to rounding. A flight from rest on the stop (a release),
    where rounding decides whether the end leaves, and every other case are searched by
    :func:`find_crossing`. Either flag may be ``None``: numba then drops that search from the
    compiled code (a rigid run compiles no flexible search, and the other way round).

    Returns
    -------
    n, status, t : int, int, float
    """
    load = LoadKernelView(*load_t)
    B = ModalBasisView(*B_t)
    kind, p0, ks, pr, pim = load.kind, load.p0, load.ks, load.pr, load.pim
    breaks, levels = load.breaks, load.levels
    w2, d, hpr, hpi, vpb = B.w2, B.d, B.hpr, B.hpi, B.vpb
    out_t, out_vel, out_q, out_v = out
    t, q, v = start
    M = w2.size
    qa, va, qp, vp, qpa, vpa, anchor, _ = flow_scratch(q, v)
    anchor[0] = t
    n = 0
    cap = out_t.size
    rigid1 = False
    if rigid_fast is not None:
        rigid1 = rigid_fast and kind == 0 and M == 1 and w2[0] == 0.0 and ks.size <= 1
    k1 = pr1 = pim1 = hr1 = hi1 = 0.0
    if rigid1 and ks.size == 1:
        k1, pr1, pim1, hr1, hi1 = ks[0], pr[0], pim[0], hpr[0, 0], hpi[0, 0]
    habs1 = math.hypot(hr1, hi1)
    h1 = (k1, pr1, pim1, hr1, hi1, habs1)
    qp1 = p1t = 0.0
    work = (q, v, qp, vp, qpa, vpa)
    # the free-free bar under a Fourier load, every flexible mode underdamped: modal_crossing (its
    # data set up only where it is compiled: a rigid run allocates and sums none of it)
    modal = False
    if modal_fast is not None:
        modal = modal_fast and kind == 0 and M > 1 and w2[0] == 0.0
        K = ks.size
        mblk = np.empty((6, M))  # (one allocation: a short run's fixed cost; rows by name, C arrays)
        lam, wsq, ca, cb = mblk[MB_LAM], mblk[MB_WSQ], mblk[MB_CA], mblk[MB_CB]
        cva, cvb = mblk[MB_CVA], mblk[MB_CVB]
        kblk = np.zeros((4, K))
        hcr, hci, hwr, hwi = kblk[KB_HCR], kblk[KB_HCI], kblk[KB_HWR], kblk[KB_HWI]
        nq0 = 0.0
        nv0 = 0.0
        for i in range(M):
            lam2 = w2[i] - 0.25 * d * d
            if i > 0 and lam2 <= 0.0:
                modal = False
            lam[i] = math.sqrt(abs(lam2))
            wsq[i] = math.sqrt(w2[i])
            hs = 0.0
            for j in range(ks.size):
                hs += math.hypot(hpr[i, j], hpi[i, j])
            nq0 += 2.0 * abs(c[i]) * (hs + (abs(p0) / w2[i] if i > 0 else 0.0))
            nv0 += 2.0 * abs(c[i]) * vpb[i]
        for i in range(M):
            for j in range(K):
                hcr[j] += c[i] * hpr[i, j]
                hci[j] += c[i] * hpi[i, j]
                hwr[j] += c[i] * w2[i] * hpr[i, j]
                hwi[j] += c[i] * w2[i] * hpi[i, j]
        fold = (lam, wsq, hcr, hci, hwr, hwi, nq0, nv0)
        mwork = (qpa, vpa, ca, cb, cva, cvb)
        anc = (qa, va, qpa, vpa)  # (the arrays are updated in place: the tuples are built once)
        stt = (q, v, qp, vp)
    while True:
        htol = 0.0
        for i in range(M):
            htol += abs(c[i] * qa[i])
        htol *= 1e-14
        # a flight after an impact, or from a start clearly off the stop or leaving it; from a
        # release (or a start) at rest on the stop rounding decides whether the end leaves: those
        # flights take the reference search
        off = n > 0
        if not off and (rigid1 or modal):
            hs = vs = hm = vm = 0.0
            for i in range(M):
                hs += c[i] * qa[i]
                vs += c[i] * va[i]
                hm += abs(c[i] * qa[i])
                vm += abs(c[i] * va[i])
            off = hs < -1e-9 * hm or vs < -1e-9 * vm
        fast1 = rigid1 and off
        st = NONE
        tc = t_end
        if rigid_fast is not None:  # (the branches on None are dropped at compile time)
            if fast1:
                st, tc, q[0], v[0], qp1, p1t = rigid1_crossing(d, c[0], p0, h1, anchor[0], qa[0],
                                                               va[0], t_end, htol)
        if modal_fast is not None:
            if modal and off:
                st, tc = _modal_crossing(load, B, c, fold, anchor[0], qa, va, t_end, htol, mwork)
                # the state there by the reference flow (qpa, vpa hold the anchor's particular state)
                advance(load, B, 0.0, anchor[0], anc, tc, stt)
        if not (fast1 or (modal and off)):
            st, tc = find_crossing(load_t, B_t, c, 0.0, anchor, qa, va, t_end, htol, work)
        if st == NONE:
            return n, END, t_end
        if st == FAIL:
            return n, FAILED, tc
        vend = 0.0
        for i in range(M):
            vend += c[i] * v[i]
        if st == TOUCH or vend <= 0.0:
            return n, CONTACT, tc
        out_t[n] = tc
        out_vel[n] = vend
        g = 0.0
        for i in range(M):
            v[i] = -R * v[i]
            g += c[i] * q[i]
        q[0] -= g  # the end exactly on the stop (a shift of the mean: no energy)
        for i in range(M):
            out_q[n, i] = q[i]
            out_v[n, i] = v[i]
        n += 1
        # With R > 0 the chatter test comes before the count's: the bounces that accumulate after
        # the last impact asked for are its own, not impacts of their own. (R = 0 leaves the end at
        # rest on the stop, no bounce to sum; R < 0: the kernel applies no law, the law's contact
        # step does, one arrival per call.)
        if n >= max_imp and R <= 0.0:
            return n, MAXIMP, tc
        if fast1:  # functional(...) of the rigid bar, term by term
            ddh = c[0] * (p1t - d * v[0])
            noise = 1e-14 * (abs(c[0]) * (abs(q[0]) + abs(qp1)))
        else:
            if kind == 1:
                mm, jj = piece_of(breaks, tc)
                level = levels[jj]
            else:
                level = 0.0
            p, dp, ddp = load_value(load, level, tc)
            h, dh, ddh, noise, dnoise = functional(w2, d, c, 0.0, p, dp, ddp, q, v, qp, vp)
        if ddh > 0.0 and R >= 0.0:  # (R = 0: the end stays on the stop, tail 0)
            # R < 1: the bounces accumulate at tc + tail. R = 1: they do not accumulate, but
            # damping shrinks them without end (ever more impacts per unit time)
            tail = 2.0 * R * vend / ddh / (1.0 - R) if R < 1.0 else math.inf
            # the next bounce is lost in rounding when its height (R v)^2 / (2 h'') is near
            # the noise of c . q: its time and velocity are then noise, so jump (for R = 1 to
            # contact now: bounces below the rounding noise are contact)
            height = 0.5 * (R * vend) ** 2 / ddh
            if tail < tail_tol or height < 1e3 * noise:
                for i in range(M):
                    v[i] = 0.0
                return n, CHATTER, tc + (tail if R < 1.0 else 0.0)
        if n >= max_imp:
            return n, MAXIMP, tc
        if n >= cap:
            return n, FULL, tc
        t = tc
        anchor[0] = tc
        for i in range(M):
            qa[i] = q[i]
            va[i] = v[i]


#: :func:`_run_free` for flexible bars (``run_free(load, B, R, c, (t, q, v), t_end, max_imp,
#: tail_tol, out, None, fast)``: the modal search where ``fast``, no rigid one compiled)
run_free = numba.njit(cache=CACHE, nogil=True)(_run_free)
#: :func:`_run_free` for the rigid bar (``..., fast, None)``: the search in scalars where ``fast``,
#: no flexible search compiled)
run_free_rigid = numba.njit(cache=CACHE, nogil=True)(_run_free)


def _propagate(load_t, B_t, ta, qa, va, ts, out_q, out_v):
    """Exact states at the sorted times ``ts >= ta`` from ``(ta, qa, va)`` into ``out_q, out_v``
    (shape (M, T)); a piecewise-constant load is followed jump by jump, by piece index (no
    rounding of a jump time into the wrong piece). ``load_t`` and ``B_t``: a
    :class:`~impactbar.dynamics.compiled_views.LoadKernelView` and a
    :class:`~impactbar.dynamics.compiled_views.ModalBasisView`, or their plain tuples. Compiled twice
    from this one source, as :func:`propagate_many` (called from Python with plain tuples: numba
    dispatches them several times faster than named tuples) and ``_propagate_many`` (called from
    compiled code with the views), each with one signature and no wrapper kernel (a wrapper
    compiles its callees' code again)."""
    load = LoadKernelView(*load_t)
    B = ModalBasisView(*B_t)
    kind, breaks = load.kind, load.breaks
    w2 = B.w2
    M = w2.size
    qa, va, qp, vp, qpa, vpa, q, v = flow_scratch(qa, va)
    anchor = (qa, va, qpa, vpa)
    state = (q, v, qp, vp)
    m, j, level = first_piece(load, B, ta, qpa, vpa)
    for i in range(ts.size):
        t = ts[i]
        if kind == 1:
            while True:
                te = piece_end(breaks, m, j)
                if t < te:
                    break
                ta, m, j, level = next_piece(load, B, level, ta, te, m, j, anchor, state)
        advance(load, B, level, ta, anchor, t, state)
        for n in range(M):
            out_q[n, i] = q[n]
            out_v[n, i] = v[n]


#: :func:`_propagate` called from Python (``load`` and ``B`` as plain tuples)
propagate_many = numba.njit(cache=CACHE, nogil=True)(_propagate)
#: :func:`_propagate` called from compiled code (``load`` and ``B`` as the views)
_propagate_many = numba.njit(cache=CACHE, nogil=True)(_propagate)

plain_literals(globals())  # one machine code per kernel for all constant arguments (run_free's max_imp 1)
# the kernels Python calls keep their wrapper and cache entry; the other (propagate_views) is
# link-only, for kernels
internal_kernels(globals(), python=("run_free", "run_free_rigid", "propagate_many"))

