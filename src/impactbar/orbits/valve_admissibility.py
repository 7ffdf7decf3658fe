"""The admissibility of the valve's periodic orbits (theory §5, §10): the struck end off the stop
inside every flight, the return crossing the first one, and a forward impact; exact for the rigid
bar, sampled for a flexible one on a grid finer than its stiffest mode's period, a very long flight
checked by an energy bound that skips the spans where the end cannot reach the stop (the cost
bounded by ``_SAMPLE_BUDGET``). The problem it checks is :mod:`impactbar.orbits.valve_segment`."""

from __future__ import annotations

import math

import numpy as np

from .._shared.status import Admissibility
from ..drives.valve import RETURN, STROKE
from ..drives.valve.closed_forms import (
    end_max_sampled,
    first_rising_crossing,
    rate_zero,
    rigid_flight,
)
from ..dynamics.modal import step_constant
from ._valve_flow import _affine, _apply, _blocks, _legs, _w2

_DIRECT_SAMPLES = 200_000  # up to this many samples a flight is sampled whole (at most ~10 ms)
_SAMPLE_BUDGET = 20_000_000  # the most samples the bounded check may take per flight (~1 s)


def _end_max_grid(w2, d, p, c, z, h, n):
    """The largest end displacement ``c . q`` at the ``n - 2`` interior points of
    ``numpy.linspace(0, h, n)`` of a flight under ``p`` from ``z`` (compiled when every flexible mode
    is underdamped)."""
    M = w2.size
    if np.all(w2[1:] > 0.25 * d * d):
        return float(end_max_sampled(w2, d, p, c, z[:M], z[M:], h, n))
    q, _ = step_constant(w2, d, p, z[:M], z[M:], np.linspace(0.0, h, n)[1:-1])
    return float(np.max(c @ q))


def _end_bound(w2, d, p, c, z, h):
    """An upper bound of the end displacement ``c . q(t)`` over ``0 <= t <= h`` of a flight under
    ``p`` from ``z`` (theory §10): the rigid mode's largest value (at an end or at its one turning
    point), the flexible modes' static deflections ``p / w2``, and their deviations from it, each at
    most ``sqrt(E / w2)`` where ``E = e'^2 + w2 e^2`` never grows (``E' = -2 d e'^2``)."""
    M = w2.size
    q0, v0 = float(z[0]), float(z[M])
    times = [0.0, h]
    t_turn = rate_zero(d, v0, p)
    if 0.0 < t_turn < h:
        times.append(t_turn)
    rigid = max(c[0] * q for q, _ in (rigid_flight(d, q0, v0, p, t) for t in times))
    if M == 1:
        return rigid
    e = z[1:M] - p / w2[1:]
    energy = z[M + 1:] ** 2 + w2[1:] * e * e
    return rigid + float(c[1:] @ (p / w2[1:])) + float(np.abs(c[1:]) @ np.sqrt(energy / w2[1:]))


def _end_max_bounded(w2, d, p, c, z, h, density):
    """The flight's largest sampled end displacement at ``density`` samples per unit time, sampling
    only the spans where :func:`_end_bound` does not prove the end off the stop; spans proven off are
    skipped and doubled, spans not proven are halved down to a few fundamental periods and then
    sampled. Returns ``-inf`` when the whole flight is proven off the stop.

    Raises
    ------
    ValueError
        When the spans that need sampling would take more than ``_SAMPLE_BUDGET`` samples (the end
        hovers near the stop for longer than the check can follow).
    """
    M = w2.size
    base = 64.0 / math.sqrt(w2[1]) if M > 1 else h  # some ten fundamental periods
    worst, t0, span, taken = -math.inf, 0.0, base, 0
    while t0 < h:
        span = min(span, h - t0)
        if _end_bound(w2, d, p, c, z, span) < 0.0:
            pass
        elif span > base:
            span = max(base, 0.25 * span)
            continue
        else:
            n = max(3, int(density * span) + 2)
            taken += n
            if taken > _SAMPLE_BUDGET:
                raise ValueError(
                    f"the admissibility check of a flight of length {h:.6g} would take more than "
                    f"{_SAMPLE_BUDGET:.0e} samples: the struck end stays within its vibration's "
                    "amplitude of the stop for too long (a drive force or switch far from the bar's "
                    "scale); rescale the drive's stroke, ret and switch_out")
            worst = max(worst, _end_max_grid(w2, d, p, c, z, span, n))
        E = _blocks(w2, d, span)
        z = _apply(E, _affine(w2, d, p, span, E), z)
        t0 += span
        span *= 2.0
    return worst


def _admissibility(model, drive, z0, durations, samples: int = 400) -> Admissibility:
    """The end off the stop inside every flight, the return crossing the first one, and a forward
    impact (theory §5, §10): exact for the rigid bar (one turning point per flight), sampled on a
    grid finer than the stiffest mode's period for a flexible one."""
    M = model.n_modes + 1
    w2, d = _w2(model), model.d
    c = model.end_weights
    ps, pr = drive.level(STROKE), drive.level(RETURN)
    t_in, h1, t_out, h3 = durations
    za, zb, zc, zd = _legs(model, drive, z0, durations)
    if c @ zd[M:] <= 0.0:
        return Admissibility.BACKWARD_IMPACT
    # the crossing must be the first rising one of the gap in the return flight
    t_first = first_rising_crossing(d, -za[0], -za[M], -pr, drive.switch_out)
    if not math.isclose(t_first, h1, rel_tol=1e-8, abs_tol=1e-12):
        return Admissibility.PENETRATES
    flights = ((ps, z0, t_in), (pr, za, h1), (pr, zb, t_out), (ps, zc, h3))
    if M == 1:  # the rigid bar: q_0 has at most one turning point per flight (theory §10), exact
        for p, z, h in flights:
            if h <= 0.0:
                continue
            t_turn = rate_zero(d, float(z[1]), p)
            inner = [float(z[0])] if z is not z0 else []
            if 0.0 < t_turn < h:
                inner.append(float(_apply(_blocks(w2, d, t_turn), _affine(w2, d, p, t_turn,
                                                                          _blocks(w2, d, t_turn)), z)[0]))
            if inner and max(inner) > 1e-12 * drive.switch_out:
                return Admissibility.PENETRATES
        if c @ z0[M:] >= 0.0 and model.R > 0.0:
            return Admissibility.STICKS
        return Admissibility.ADMISSIBLE
    top = model.s * model.n_modes if model.piston is None else float(np.sqrt(w2[-1])) / math.pi
    n = max(samples, int(8 * top * sum(durations)))
    worst = -math.inf
    scale = max(drive.switch_out, float(np.max(np.abs(z0[:M]))))  # (lengths scale with the drive)
    if n > _DIRECT_SAMPLES:  # a long period: sample only where the energy bound cannot decide
        density = 8.0 * top
        for p, z, h in flights:
            if h > 0.0:
                worst = max(worst, _end_max_bounded(w2, d, p, c, z, h, density))
    else:
        for p, z, h in flights:
            if h > 0.0 and n >= 3:
                worst = max(worst, _end_max_grid(w2, d, p, c, z, h, n))
    if worst > 1e-12 * scale:
        return Admissibility.PENETRATES
    if c @ z0[M:] >= 0.0 and model.R > 0.0:
        return Admissibility.STICKS
    return Admissibility.ADMISSIBLE

