r"""The tangent of the coupled exact blow (theory §11, "The coupled blow"): the derivative of the
state after a blow of :func:`~impactbar.laws.rodrock.coupled_exact.driven_exact_contact` along
directions of the state at the arrival, the piston's modes and the drive's state.

The blow is a fixed point of two causal maps, the exact blow under the drive's force and the drive's
flight under the wave ``a`` the blow sends to the piston's driven end (:mod:`.coupled_exact`). Its
tangent is the fixed point of their tangents, iterated as the force is:

- the exact blow's tangent runs (:func:`~impactbar.laws.rodrock.exactjac.tangents`) along the
  directions, with the force's derivative as their drive's direction, give the state after the blow
  and the derivative of the wave arriving at the driven end: its smooth part at the samples of ``a``
  (the same samples, a cubic spline through them on each interval between the breaks) and its
  impulses, where a moving re-contact moves a jump of ``a``;
- the drive's variational equations along the last flight, with that derivative of ``a`` (the drive's
  ability ``end_tangent``), give the force's derivative over the blow, one cubic Hermite piece on
  each piece of the direction (the derivative and its rate at the piece's ends, each from its own
  side), the next round's drive direction. Its pieces are the primal drive's integrator steps
  thinned to some :data:`DIRECTION_STEPS` a travel time ``T_0`` (kept at the breaks of ``a``, and
  where the thinned cubic misses the derivative at a step it passes over by :data:`THIN_TOL`): the
  tangent runs' cost is in their drive's pieces.

The tangent runs' schedule is the primal blow's switch log, the one its last iterate logged (each
iterate logs from the impact on, going on from its predecessor's snapshot with the log so far:
:func:`~impactbar.laws.rodrock.exactjac.kept_primal`), so that the blow is not solved again; where
no log was kept (the plain iteration, a log that overflowed) the primal is solved again for its own.
By causality the ``k``-th round is right over ``[0, 2 k T_0]``; the rounds end when the derivatives
after the blow change by less than :data:`TANGENT_TOL` of their size, or when what is left of them
to the fixed point, estimated from the contraction of the last two rounds, is (:func:`_settled`).
The drive's map at the blow's end (its :meth:`~impactbar.Drive.impact`, which writes values or
keeps them) is taken by central differences of the map alone. Not covered (``None``: the caller
differences the blow): a drive without ``end_tangent``, a blow without its coupling data, the
drive's events inside the blow (a saltation each), a switch log given up, rounds that do not settle.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["coupled_blow_tangent", "TANGENT_TOL"]

#: The rounds end when the derivatives after the blow change by less than this of their size, or
#: when what is left of them to the fixed point is estimated below it (:func:`_settled`).
TANGENT_TOL = 1e-10
#: Rounds beyond the causal bound ``duration / (2 T_0) + 1``.
EXTRA_ROUNDS = 4
#: The drive's direction's pieces: about this many a travel time ``T_0`` of the piston's first
#: segment (the primal's integrator steps, down to 1e-6 of it, thinned: the tangent runs' cost is in
#: their drive's pieces), refined where their cubic misses the derivative by :data:`THIN_TOL`.
#: Measured on the example's blow: 1,661 pieces to 678, the tangent 6.8e-10 of its size from the
#: unthinned one's (the central differences agree to 1e-7), its runs half the time.
DIRECTION_STEPS = 64
#: Of the force derivative's size: the thinned direction's largest miss at a start it passes over.
THIN_TOL = 1e-5


def coupled_blow_tangent(model, drive, res, after, state, settings=None):
    """The Jacobian of the coupled exact blow's map ``(q, q', z)`` at the arrival ``->`` after the blow
    and the drive's map (module docstring), in the layout of
    :func:`~impactbar.orbits.coupled.blow_jacobian`.

    Parameters
    ----------
    model : BarModel
        Under :class:`~impactbar.RodRock` with exact blows.
    drive : Drive
        The drive with state (its abilities ``end_flight`` and ``end_tangent``).
    res : DrivenContact
        The blow (:func:`~impactbar.simulation.blows.driven_blow`'s), its record an
        :class:`~impactbar.laws.rodrock.exactmap.ExactRockContact` with its ``coupling``.
    after : DriveState
        The drive's state after its map at the blow's end.
    state : DriveState
        The drive's state at the arrival.
    settings : FlightSettings, optional
        Unused (the drive's flight is the blow's own); kept for the blow's signature.

    Returns
    -------
    numpy.ndarray, shape (2 N + 2 + k, 2 N + 2 + k), or None
        ``None`` where the tangent does not cover the blow (module docstring).
    """
    from . import exactjac as EJ
    from .coupled_exact import INSIDE
    from .exactmap import initial_waves

    rec = res.record
    coupling = getattr(rec, "coupling", None)
    make = drive.abilities.end_tangent
    if coupling is None or make is None or res.events:
        return None
    bmap = rec._map
    q, v = np.asarray(rec.q_before, dtype=float), np.asarray(rec.v_before, dtype=float)
    primal, on_stop = getattr(rec, "switch_log", None) or (None, None)
    if primal is None:  # (no log kept: the primal solved again for its own)
        primal = EJ._primal(bmap, q, v)
        if primal is None:
            return None
        _, _, on_stop = bmap.after_run(*primal)
    ws, scale = primal
    t0 = float(bmap.t0)
    et = make(res.pieces, res.events, state.mode, coupling.breaks, coupling.splines, coupling.impedance, t0)
    basis = bmap.basis
    T0, Z0 = float(basis.travel[0]), float(coupling.impedance)
    M, k = q.size, state.z.size
    n = 2 * M + k
    c = np.asarray(model.end_weights, dtype=float)
    cols = [j for j in range(n) if not (j == 0 and float(c[0]) == 1.0)]
    E = np.eye(n)[cols]
    dq0 = E[:, :M].copy()
    dq0[:, 0] -= dq0 @ c  # (the arrival's end put on the stop, as the blow does)
    dv0, dz0 = E[:, M:2 * M], E[:, 2 * M:]
    x0 = et.start(-(dq0 @ np.asarray(model.drive_weights, dtype=float)), dz0)
    dp0 = et.force(x0)
    waves = initial_waves(basis, dq0, dv0, dp0)
    # the samples of the primal's a, a hair inside their intervals (its callables')
    xs = [x + (ts - t0) for x, _, ts in coupling.splines]
    inside = [np.concatenate(([INSIDE * T0], np.zeros(x.size - 2), [-INSIDE * T0])) for x in xs]
    allx = np.concatenate([x + d for x, d in zip(xs, inside, strict=True)])
    cuts = np.cumsum([x.size for x in xs])[:-1]
    starts, pieces = bmap.drive
    D = float(rec.duration)
    thin = _thinned(starts, T0 / DIRECTION_STEPS, np.asarray(coupling.breaks, dtype=float) - t0)
    drv = _held_direction(starts[thin], [pieces[j] for j in thin], dp0)
    rounds = math.ceil(D / (2.0 * T0)) + 1 + EXTRA_ROUNDS
    prev, last = None, math.inf
    for _ in range(rounds):
        out = EJ.tangents(bmap, ws, scale, waves, drv, None, on_stop, arriving=allx)
        if out is None:
            return None
        dq_a, dv_a, _, dG, pulses = out
        da = [_spline(x, vals) for x, vals in zip(xs, np.split(-2.0 * dG / Z0, cuts, axis=1), strict=True)]
        times = np.array([tp for p in pulses for tp, _ in p])
        grid = et.grid(np.concatenate((starts, times[(times > 0.0) & (times < D)])))
        kicks = np.zeros((grid.size, len(cols)))
        for d, p in enumerate(pulses):
            for tp, wp in p:
                if 0.0 < tp < D:
                    kicks[min(np.searchsorted(grid, tp), grid.size - 1), d] += -2.0 * wp / Z0
        X, R = et.solve(grid, x0, da, kicks)
        now = np.concatenate((dq_a, dv_a, et.state_after(X)), axis=1)
        if prev is not None:
            change = float(np.max(np.abs(now - prev))) / max(float(np.max(np.abs(now))), 1e-300)
            if _settled(change, last):
                break
            last = change
        prev = now
        drv = _thin_direction(starts, pieces, thin, et.force_ends(grid, X, R, starts[:-1], starts[1:]), dp0)
    else:
        return None
    G = np.zeros((n, n))
    G[:, cols] = now.T
    G[2 * M:] = _impact_jacobian(drive, res) @ G[2 * M:]
    return G


def _settled(change, last):
    """Whether the rounds end: the derivatives' last ``change`` (of their size) below
    :data:`TANGENT_TOL`, or what is left of them to the fixed point estimated below it, ``change rho /
    (1 - rho)`` for a contraction by ``rho = change / last`` a round (``last`` the change before; the
    rounds contract faster each round, by causality, so that the estimate from the last two bounds
    the next: on the example's blow 1.7e-2, 8.8e-5, 6.6e-8, then 2.4e-11 where 4.9e-11 is estimated)."""
    if change <= TANGENT_TOL:
        return True
    rho = change / last if 0.0 < last < math.inf else math.inf  # (no change before: no estimate)
    return rho < 1.0 and change * rho / (1.0 - rho) <= TANGENT_TOL


def _spline(x, values):
    """The cubic spline through ``values`` (shape ``(K, m)``) at ``x``, as the primal's wave is."""
    from scipy.interpolate import CubicSpline

    return CubicSpline(x, values, axis=1)


def _thinned(starts, gap, keep):
    """The indices of the primal drive's ``starts`` the drive's direction starts its pieces at: the
    first two (before and at the impact), the last, the times ``keep`` (the breaks of ``a``, where
    the force's rate jumps) and the first start in each ``gap`` after the impact."""
    bins = np.floor(starts[1:-1] / gap)
    _, first = np.unique(bins, return_index=True)
    at = np.searchsorted(starts, keep)
    at = at[(at > 0) & (at < starts.size) & (starts[np.minimum(at, starts.size - 1)] == keep)]
    return np.unique(np.concatenate(([0, 1, starts.size - 1], first + 1, at)))


def _thin_direction(starts, pieces, thin, ends, dp0):
    """The drive's direction of :func:`_hermite_direction` on the starts ``thin`` of ``starts``
    (:func:`_thinned`), and on every start of a thinned piece where its cubic misses the force's
    derivative at a start it passes over by more than :data:`THIN_TOL` of the derivative's size (a
    direction's fast change, the circuit's stiff transients); ``ends`` the derivative and its rate at
    every piece's ends (``force_ends`` at ``starts[:-1]`` and ``starts[1:]``)."""
    ya, fa, yb, fb = ends
    size = np.maximum(np.max(np.abs(ya), axis=0), 1e-300)

    def direction(k):
        return _hermite_direction(starts[k], [pieces[j] for j in k],
                                  (ya[k[:-1]], fa[k[:-1]], yb[k[1:] - 1], fb[k[1:] - 1]), dp0)

    drv = direction(thin)
    j = np.setdiff1d(np.arange(1, starts.size - 1), thin)  # the starts passed over
    if j.size == 0:
        return drv
    i = np.searchsorted(thin, j) - 1  # (their thinned piece)
    _, drv_pieces = drv
    c = np.stack([cp for _, _, cp in drv_pieces[1:-1]])  # (pieces, K, 4): the cubics
    s = (starts[j] - starts[thin[i]])[:, None]
    val = np.polynomial.polynomial.polyval(s, np.moveaxis(c[i - 1].real, -1, 0), tensor=False)
    bad = np.unique(i[np.any(np.abs(val - ya[j]) > THIN_TOL * size, axis=1)])
    if bad.size == 0:
        return drv
    more = j[np.isin(i, bad)]
    return direction(np.union1d(thin, more))


def _held_direction(starts, pieces, dp0):
    """The drive's direction held at ``dp0`` (shape ``(K,)``) on the primal drive's pieces."""
    held = dp0[:, None].astype(complex)
    cubic = np.zeros((dp0.size, 4), dtype=complex)
    cubic[:, 0] = dp0
    coefs = [held, *[cubic] * (len(pieces) - 2), held]
    return starts, [(exps, degs, c) for (exps, degs, _), c in zip(pieces, coefs, strict=True)]


def _hermite_direction(starts, pieces, ends, dp0):
    """The drive's direction from the force's derivative and its rate at each piece's ends, from its
    own side (``ends``: :meth:`~impactbar.drives.circuit.endtangent.EndTangent.force_ends` at
    ``starts[:-1]`` and ``starts[1:]``): the first piece (before the impact) held at ``dp0``, a cubic
    Hermite piece on each of the primal's pieces between, the last held at the end's value."""
    ya, fa, yb, fb = (e[1:] for e in ends)  # (the pieces after the first)
    h = (starts[2:] - starts[1:-1])[:, None]
    slope = (yb - ya) / h
    tt = (fa + fb - 2.0 * slope) / h
    cubic = np.stack((ya, fa, (slope - fa) / h - tt, tt / h), axis=2).astype(complex)  # (pieces, K, 4)
    _, _, y_end, _ = ends
    coefs = [dp0[:, None].astype(complex), *cubic, y_end[-1][:, None].astype(complex)]
    return starts, [(exps, degs, c) for (exps, degs, _), c in zip(pieces, coefs, strict=True)]


def _impact_jacobian(drive, res):
    """The Jacobian of the drive's map at the blow's end in its state ``z`` (central differences of
    the map alone: it writes values or keeps them, so that they are exact away from a switch)."""
    end = res.drive_state
    z = np.asarray(end.z, dtype=float)
    k = z.size
    # (a power of two some 1e-6 of the largest component: z +- h and their difference exact)
    _, e = math.frexp(max(float(np.max(np.abs(z))), 1e-300))
    h = math.ldexp(1.0, e - 20)
    out = np.zeros((k, k))
    for j in range(k):
        zp, zm = z.copy(), z.copy()
        zp[j] += h
        zm[j] -= h
        a = drive.impact(end.mode, zp, res.t_release, res.q_after, res.v_after).z
        b = drive.impact(end.mode, zm, res.t_release, res.q_after, res.v_after).z
        out[:, j] = (np.asarray(a) - np.asarray(b)) / (2.0 * h)
    return out
