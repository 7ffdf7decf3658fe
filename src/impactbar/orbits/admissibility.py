"""Admissibility of an orbit (theory §5): the struck end stays off the stop between impacts
and leaves it after the impact, decided with certified bounds, not by sampling."""

from __future__ import annotations

import math

import numpy as np

from .._shared.columns import IV_HI, IV_LO
from .._shared.status import Admissibility
from ..dynamics.certified import enclose_zeros
from ..dynamics.compiled_views import FOURIER
from ..dynamics.implementations import use_fast
from ..loads import CosineLoad
from ..loads.abilities import compiled_kind, exact_flow
from ._rigid_scalar import cosine_clearance

TWO_PI = 2.0 * math.pi

# implementations (impactbar.dynamics.implementations): "admissibility.search", the whole certified
# search (enclosure, Newton steps, branch and bound) by the compiled kernel
# :mod:`impactbar.orbits._admissibility_search` where the load's flow is compiled; "admissibility.bound", the
# bounds of the numpy search by the compiled kernel. Their references are the numpy paths.
# "admissibility.rigid_cosine": the rigid bar's flights under a cosine load from the zeros of its
# velocity, one per arc of constant load sign (_rigid_scalar.cosine_clearance); its reference is the
# certified search.
#: intervals tried first by the branch and bound on the stationary values (see _stationary_values)
SEEDS = 4
#: pieces into which the branch and bound splits an interval it searches again (then halved down
#: to a 64th of the widest): most such intervals hold no zero of ``g'`` and are excluded after one
#: split, so 2 pieces cost a quarter of 8 there, and at most 5 % more where the search goes deep
RETRY_PIECES = 2
#: with the end leaving the stop at rest, the samples of the search before this time do not bound
#: the clearance (the stationary point at the departure is not one of its values)
_SAMPLE_FLOOR = 0.05


def _window_departure(status, at_rest, v_dep, separates):
    """The verdict of a flight that starts where a contact window closes (the wave law, theory
    §4b): contact lost inside the window is ``separates``; an end still moving into the rod when the
    window closes is ``sticks`` (the rod then goes on absorbing the piston's push as a dashpot of its
    impedance, the sustained contact of theory §4b), whatever the flight's certified search says of
    the penetration that this departure starts; a backward arrival keeps its verdict."""
    if status == Admissibility.BACKWARD_IMPACT:
        return status
    if separates and status == Admissibility.ADMISSIBLE:
        return Admissibility.SEPARATES
    if not at_rest and v_dep > 0.0:
        return Admissibility.STICKS
    return status


def _admissibility(model, load, phase, y_plus, v_imp, horizon=TWO_PI, at_rest=None, flow=None):
    """Decide admissibility (theory §5) with certified bounds, over the flight
    ``[phase, phase + horizon]`` from ``y_plus``; ``at_rest`` (default ``R == 0``) says the end
    leaves the stop at rest, so that its departure is decided by its acceleration.

    The stationary points of ``g(t) = u(1, t)`` are the zeros of ``g' = c . q'``; they are enclosed
    with a bound of ``|g''|`` on each interval, built from each mode's energy about the static
    deflection under the local load: ``sqrt(v^2 + w^2 (q - P/w^2)^2)`` grows at most by the load's
    variation times the time elapsed (and by ``e^{d h}`` going backwards), and
    ``|q''| <= delta + (d + w) sqrt(E)``.

    ``duration`` is the flight time after the impact at load time ``phase`` (``2 pi`` for a
    one-impact orbit; the flights of a multi-impact motion differ). ``flow``, if given, is
    ``exact_flow(load, w2, d, phase, q0, v0)`` of this flight, already built by the caller.
    """
    M = model.n_modes + 1
    w2 = model.frequencies**2
    w = np.sqrt(w2)
    d, R = model.d, model.R
    c = model.end_weights
    absc = np.abs(c)
    psup = load.sup_abs
    q0, v0 = y_plus[:M], y_plus[M:]
    scale = max(abs(v_imp), psup, 1e-300)
    if at_rest is None:
        at_rest = R == 0.0
    found = None
    # the departure: for R = 0 every velocity is zero just after impact, so t = 0 is a stationary
    # point of g; the end leaves the stop iff its acceleration there points away from the stop.
    if at_rest:
        acc0 = float(c @ (float(load(phase)) - d * v0 - w2 * q0))
    # (a rigid flight that starts pressed on the stop sticks: the searches' clearances differ there
    # only in what the departure's neighbourhood counts, and the certified search's is the one kept)
    # (fast-path guard: the rigid cosine flight's closed form, for a load that declares itself the
    # cosine (its kind) and evaluates as CosineLoad does, whose clearance it fixes to the last bit;
    # a subclass with its own evaluation or another load takes the certified search)
    if (M == 1 and load.traits.kind == CosineLoad.traits.kind and compiled_kind(load, "__call__") == FOURIER
            and q0[0] == 0.0 and not (at_rest and not acc0 < 0.0) and use_fast("admissibility.rigid_cosine")):
        p0, pk, k = load.abilities.cosine
        found = (cosine_clearance(float(d), p0, pk, k, float(phase), float(v0[0]),
                                  float(horizon), bool(at_rest)), 0.0)
    if found is None and use_fast("admissibility.search"):
        found = _compiled_search(load, w2, float(d), float(phase), q0, v0, c, absc, float(psup),
                                 float(horizon), bool(at_rest), 1e-13 * scale, flow)
    if found is None:
        found = _numpy_search(load, w, w2, d, c, absc, psup, phase, q0, v0, horizon, at_rest, scale,
                              flow)
    clearance, err_b = found
    # rounding of the values themselves: relative to the problem's scale (linear in the load), so
    # that every verdict is invariant under load -> L load
    err = err_b + 1e-12 * (scale + (abs(clearance) if clearance > -math.inf else 0.0))
    tol = max(err, 1e-11 * scale)
    if not v_imp > 1e-12 * scale:
        status = Admissibility.GRAZING if abs(v_imp) <= 1e-12 * scale else Admissibility.BACKWARD_IMPACT
    elif at_rest and not acc0 < 0.0:
        status = Admissibility.STICKS
    elif clearance > tol:
        status = Admissibility.PENETRATES
    elif clearance >= -tol:
        status = Admissibility.GRAZING
    else:
        status = Admissibility.ADMISSIBLE
    return status, clearance, err


def _compiled_search(load, w2, d, phase, q0, v0, c, absc, psup, horizon, at_rest, atol, flow=None):
    """``(clearance, err)`` of :func:`_numpy_search` by the compiled kernel, or
    ``None`` where it does not apply (a load or flow it does not know: the numpy path then runs)."""
    kind = compiled_kind(load, "__call__", "variation", "flow")
    if kind is None:
        return None
    own = load.abilities
    if kind == FOURIER:
        if flow is None:
            flow = own.flow(w2, d, phase, q0, v0)
        args = getattr(flow, "kernel_args", None)
        if args is None:
            return None
        F = args
        P = _NO_PIECES
    else:  # piecewise constant
        # one period and a margin: a midpoint of the search may fall just past the flight's end
        pieces = getattr(own.flow(w2, d, phase, q0, v0, horizon=TWO_PI + 1.0), "pieces", None)
        if pieces is None:
            return None
        nodes, levels, qn, vn = pieces
        P = (w2, d, nodes, np.ascontiguousarray(levels, dtype=float), qn, vn)
        F = _NO_FOURIER
    from ..dynamics.compiled import interpreted_first
    from ._admissibility_search import admissibility_search, phase_buffers

    # (its twin for the first calls of a process with an empty cache: the same bits, no compile)
    search = interpreted_first(admissibility_search, scratch=(8,))  # (8: the phases, work buffers)
    code, v_max, err = search(phase, horizon, at_rest, atol, SEEDS, RETRY_PIECES,
                              _SAMPLE_FLOOR if at_rest else 0.0, (c, absc, w2, d, psup),
                              phase_buffers(c.size), (tuple(own.kernel.view), F, P))
    if code:
        raise RuntimeError("zero search did not converge (Lipschitz bound too loose)")
    return float(v_max), float(err)


_E1, _E2 = np.zeros(0), np.zeros((1, 0))
_NO_FOURIER = (0.0, 0.0, 0.0, _E1, np.zeros((4, 1, 0)), np.zeros((8, 0)), np.zeros(0, dtype=np.int64))
_NO_PIECES = (_E1, 0.0, _E1, _E1, _E2, _E2)


def _numpy_search(load, w, w2, d, c, absc, psup, phase, q0, v0, horizon, at_rest, scale, flow=None):
    """The certified search by numpy (the reference): ``(clearance, err)``, the largest stationary
    value of ``g = u(1, t)`` over the flight (``-inf`` without one) and the bound on its error (see
    :func:`_stationary_values`)."""
    if flow is None:
        flow = exact_flow(load, w2, d, phase, q0, v0)

    def states(t):
        return flow(phase + np.asarray(t, dtype=float))

    last = {}  # g at the points of the latest evaluation, and the best lower bound so far

    def gprime_and_bound(mid, half):
        q, v = states(mid)
        last["g"] = c @ q
        center, delta = load.variation(phase + mid, half)
        if use_fast("admissibility.bound") and q.ndim == 2:
            from ..dynamics.compiled import end_velocity_bound

            T = q.shape[1]
            return end_velocity_bound(c, absc, w2, float(d), float(psup), q, v,
                                      *(_column(x, T) for x in (center, delta, half)))
        grow = np.exp(d * np.asarray(half))
        bound = np.empty_like(q)
        flex = w2 > 0
        wc = w[flex, None]
        sqrtE = np.sqrt(v[flex] ** 2 + (wc * q[flex] - center / wc) ** 2)
        Eb = (sqrtE + delta * half) * grow
        bound[flex] = delta + (d + wc) * Eb
        vb = (np.abs(v[~flex]) + psup * half) * grow
        bound[~flex] = psup + d * vb
        return c @ v, absc @ bound

    atol = 1e-13 * scale
    floor = _SAMPLE_FLOOR if at_rest else 0.0
    last["best"] = -math.inf

    def prune_below(mids, half, g1, L2, best):
        """Branch and bound in an enclosure: ``(keep, best)``, the intervals where ``g`` may reach
        ``best`` (a lower bound of the largest stationary value, first raised by this level's
        samples) and that bound."""
        g = last["g"]
        best = max(best, _sample_bound(mids, g, g1, atol, floor))
        return g + (np.abs(g1) + 0.5 * L2 * half) * half >= best, best

    def prune(mids, half, g1, L2):
        """Branch and bound already in the first enclosure (its lower bound kept in ``last``)."""
        keep, last["best"] = prune_below(mids, half, g1, L2, last["best"])
        return keep

    slope = _load_slope(load)

    def single_zero(ts, lo, hi):
        """Where ``|g''(ts)| > L3 r`` (``L3`` a bound of the third derivative of ``g`` on
        ``[lo, hi]``, ``r`` the distance from ``ts`` to its far end), ``g''`` keeps its sign on
        ``[lo, hi]``: ``ts`` is the only zero of ``g'`` there."""
        if slope is None:
            return np.zeros(ts.size, dtype=bool)
        bound_slope, smooth_only = slope
        mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        q, v = states(mid)
        center, delta = load.variation(phase + mid, half)
        L3 = _third_bound(w, w2, d, absc, psup, q, v, center, delta, half, bound_slope)
        qs, vs = states(ts)
        g2 = c @ (load(phase + ts)[None, :] - d * vs - w2[:, None] * qs)
        smooth = np.asarray(delta) == 0.0 if smooth_only else True
        return smooth & (np.abs(g2) > L3 * np.maximum(ts - lo, hi - ts))

    clusters = enclose_zeros(None, None, 0.0, horizon, n0=64, min_width=6e-3,
                             joint=gprime_and_bound, merge=False, atol=atol, prune=prune)
    if at_rest:  # t = 0 is a stationary point, decided by the departure's acceleration
        clusters = [cl for cl in clusters if cl[0] > 1e-6]
    # the stationary points that can carry the largest value are refined to full precision
    values, err_b = _stationary_values(states, gprime_and_bound, load, phase, c, w2, d, clusters,
                                       atol=atol, horizon=horizon, floor=floor, best=last["best"],
                                       single=single_zero, prune=prune_below)
    return max(values, default=-math.inf), err_b


def _load_slope(load):
    """``(bound of |p'|, only without a jump)`` where the load is smooth between its jumps: a
    Fourier load's ``sum k |p_k|``; 0 for a piecewise-constant load, on an interval without a jump;
    ``None`` for another load (no certificate of a single zero)."""
    kind = compiled_kind(load, "__call__", "variation")
    if kind is None:
        return None
    return (load.abilities.kernel.view.p1, False) if kind == FOURIER else (0.0, True)


def _third_bound(w, w2, d, absc, psup, q, v, center, delta, half, slope):
    """A bound of the third derivative of ``g`` on ``[mid - half, mid + half]`` from the states at
    the midpoints: ``q''' = p' - d q'' - w2 q'`` with ``|q'| <= sqrt(E)`` and ``|q''|`` bounded as
    in the search's bound of ``|g''|`` (``|p'| <= slope``)."""
    grow = np.exp(d * np.asarray(half))
    t3 = np.empty_like(q)
    flex = w2 > 0
    wc = w[flex, None]
    Eb = (np.sqrt(v[flex] ** 2 + (wc * q[flex] - center / wc) ** 2) + delta * half) * grow
    t3[flex] = slope + d * (delta + (d + wc) * Eb) + w2[flex, None] * Eb
    vb = (np.abs(v[~flex]) + psup * half) * grow
    t3[~flex] = slope + d * (psup + d * vb)
    return absc @ t3


def _column(x, T):
    """``x`` as a contiguous float array of shape ``(T,)`` (broadcast only where it must be)."""
    x = np.asarray(x, dtype=float)
    if x.shape == (T,) and x.flags.c_contiguous:
        return x
    return np.ascontiguousarray(np.broadcast_to(x, (T,)))


def _newton_stationary(states, load, phase, c, w2, d, lo, hi):
    """Vectorised Newton for zeros of ``g' = c . q'`` on intervals ``[lo, hi]``, with
    ``g'' = c . (p - d q' - w2 q)``, from the midpoints. Returns the final points and which
    converged inside. An interval leaves the iteration once its step is below 1e-12 (converged)
    or leaves the interval (failed: the branch and bound splits it and tries again), so that the
    intervals without a zero, which most are, cost one evaluation each."""
    t = 0.5 * (lo + hi)
    ok = np.zeros(t.size, dtype=bool)
    active = np.ones(t.size, dtype=bool)
    for _ in range(8):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        ta, la, ha = t[idx], lo[idx], hi[idx]
        q, v = states(ta)
        g1 = c @ v
        g2 = c @ (load(phase + ta)[None, :] - d * v - w2[:, None] * q)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(g2 != 0.0, g1 / g2, np.inf)
        step = np.nan_to_num(step, nan=np.inf)
        t_new = ta - np.where(np.isfinite(step), step, 0.0)
        inside = (t_new >= la) & (t_new <= ha) & np.isfinite(step)
        t[idx] = np.clip(t_new, la, ha)
        ok[idx] = inside & (np.abs(step) < 1e-12)
        active[idx] = inside & ~ok[idx]
    return t, ok


def _sample_bound(mid, gm, g1, atol, floor):
    """A lower bound of the largest stationary value of ``g`` from samples ``gm = g(mid)``,
    ``g1 = g'(mid)`` at sorted times ``mid``: if ``g' > 0`` at ``a`` and ``g' < 0`` at a later
    ``b``, the largest value of ``g`` on ``[a, b]`` is at neither end, so at a stationary point
    inside, and it is at least every sample between them. Signs are trusted beyond ``atol``,
    samples before ``floor`` are not used (``-inf`` where no such pair exists)."""
    pos = np.flatnonzero((g1 > atol) & (mid > floor))
    neg = np.flatnonzero((g1 < -atol) & (mid > floor))
    if pos.size == 0 or neg.size == 0 or neg[-1] <= pos[0]:
        return -math.inf
    return float(np.max(gm[pos[0]:neg[-1] + 1])) - atol


def _stationary_values(states, bound, load, phase, c, w2, d, intervals, rounds=8, atol=0.0,
                       horizon=TWO_PI, floor=0.0, best=-math.inf, single=None, prune=None):
    """Largest values of ``g = c . q`` at its stationary points, by branch and bound.

    Every narrow interval that may hold a zero of ``g'`` has an upper bound of ``g`` on it,
    ``g(mid) + (|g'(mid)| + L h / 2) h``. Best first: the :data:`SEEDS` intervals with the largest
    bounds get a Newton iteration; the best value found prunes every interval whose bound cannot
    beat it, and the others get a vectorised Newton iteration. A converged zero ``t*`` of ``g'``
    gives a stationary value; as ``g <= g(t*) + L r^2 / 2`` on its interval (``r`` the distance to
    the far end), an interval where that bound can still beat the best value may hide a second
    zero (two close zeros in one narrow interval) and is searched again, as is an interval where
    Newton fails: both are split 64-fold by the certified exclusion and tried again. Where that
    cannot go on (a zero of ``g'`` of high order, whose enclosure does not shrink), the upper
    bounds themselves are used.

    ``best``, if given, is a known lower bound of the largest stationary value (from the samples
    of the enclosure, :func:`_sample_bound`); the midpoint samples of ``intervals`` raise it.
    ``single(t, lo, hi)``, if given, says where ``t`` is certainly the only zero of ``g'`` in
    ``[lo, hi]`` (``g''`` keeps its sign there): such an interval is not searched again.
    ``prune(mids, half, g'(mids), L, best) -> (keep, best)``, if given, is a branch and bound for
    the enclosures (``keep`` the intervals where ``g`` may reach ``best``, which the level's samples
    may raise): the intervals searched again are split with it, so that the pieces where ``g``
    stays below the best value found are dropped as they are split (the ringing that a contact
    window leaves makes many pieces hold a zero of ``g'``), not only once they are narrow.

    Returns
    -------
    values : list of float
        Stationary values (not all of them: those that cannot be the largest may be pruned), or
        upper bounds of them.
    err : float
        Bound on the error of the largest value (0 up to rounding when every stationary point
        that matters was located; otherwise the spread of the bounds on the unresolved intervals,
        whose upper end is reported).
    """
    def value_bounds(iv):
        """``g`` at the midpoints and its upper bound on each interval."""
        mid = 0.5 * (iv[:, IV_LO] + iv[:, IV_HI])
        half = 0.5 * (iv[:, IV_HI] - iv[:, IV_LO])
        q, _ = states(mid)
        gm = c @ q
        g1, L2 = bound(mid, half)
        return gm, gm + (np.abs(g1) + 0.5 * L2 * half) * half, g1

    values: list[float] = []
    err = 0.0
    cur = np.array(intervals, dtype=float).reshape(-1, 2)
    gm, upper, g1 = value_bounds(cur) if cur.size else (np.empty(0),) * 3
    if cur.size:
        best = max(best, _sample_bound(0.5 * (cur[:, IV_LO] + cur[:, IV_HI]), gm, g1, atol, floor))
    for _ in range(rounds):
        keep = upper >= best
        cur, gm, upper = cur[keep], gm[keep], upper[keep]
        if cur.size == 0:
            break
        n = cur.shape[0]
        lo, hi = cur[:, IV_LO], cur[:, IV_HI]
        t = np.empty(n)
        ok = np.zeros(n, dtype=bool)
        vals = np.full(n, -math.inf)
        # best first: the most promising intervals, then every one their values do not prune
        seeds = np.argsort(-upper, kind="mergesort")[:SEEDS]
        tried = np.zeros(n, dtype=bool)
        for batch in (seeds, None):
            if batch is None:
                batch = np.flatnonzero(~tried & (upper >= best))
                if batch.size == 0:
                    break
            tried[batch] = True
            tb, okb = _newton_stationary(states, load, phase, c, w2, d, lo[batch], hi[batch])
            t[batch], ok[batch] = tb, okb
            if np.any(okb):
                qb, _ = states(tb[okb])
                vb = c @ qb
                vals[batch[okb]] = vb
                values.extend(float(x) for x in vb)
                best = max(best, float(np.max(vb)))
        again = np.zeros(n, dtype=bool)
        if np.any(ok):
            # a second zero of g' may share the interval with the one found: since g'(t*) = 0,
            # g <= g(t*) + L r^2 / 2 on the interval, with L the bound of |g''| and r the distance
            # from t* to its far end
            _, L2 = bound(0.5 * (lo[ok] + hi[ok]), 0.5 * (hi[ok] - lo[ok]))
            r = np.maximum(t[ok] - lo[ok], hi[ok] - t[ok])
            taylor = vals[ok] + 0.5 * L2 * r * r
            again[ok] = taylor > best + atol
            if single is not None and np.any(again):  # unless g'' keeps its sign there
                idx = np.flatnonzero(again)
                again[idx[single(t[idx], lo[idx], hi[idx])]] = False
            # the Taylor bounds about the found zeros are the sharper ones
            gm[again], upper[again] = vals[again], taylor[again[ok]]
        retry = tried & (~ok | again) & (upper >= best)
        rest, gm, upper = cur[retry], gm[retry], upper[retry]
        cur = rest
        if rest.size == 0:
            break
        width = float(np.max(rest[:, IV_HI] - rest[:, IV_LO]))
        level = None
        if prune is not None:
            found = [best]

            def level(mids, half, g1, L2, found=found):
                keep, found[0] = prune(mids, half, g1, L2, found[0])
                return keep
        try:
            cur = np.array(enclose_zeros(None, None, 0.0, horizon, n0=RETRY_PIECES, min_width=width / 64.0,
                                         joint=bound, intervals=rest, merge=False,
                                         max_intervals=20_000, atol=atol, prune=level)).reshape(-1, 2)
            if prune is not None:
                best = found[0]
        except RuntimeError:  # a zero of high order: the enclosure no longer shrinks
            lower = 2.0 * gm - upper  # gm - slack
            values.append(float(np.max(upper)))  # conservative: never below the true value
            err = max(err, float(np.max(upper) - np.min(lower)))
            cur = np.empty((0, 2))
            break
        gm, upper, _ = value_bounds(cur) if cur.size else (np.empty(0),) * 3
    if cur.size:  # rounds exhausted: bound what is left
        if float(np.max(upper)) >= best:
            values.append(float(np.max(upper)))  # conservative: never below the true value
            err = max(err, float(np.max(upper) - np.min(2.0 * gm - upper)))
    return values, err
