"""Sticking contacts of the rigid bar under the square-wave load end at the load's switch, to
rounding, and the flights after them follow the exact solution.

The reference is independent of the package: the rigid bar ``x'' = p(t)`` (``d = 0``) between
impacts is a parabola on each piece of the load, solved in 50-digit decimal arithmetic with the
true ``pi``; an impact maps ``v -> -R v``; a chatter whose remaining bounces last less than the
simulator's ``CHATTER_TAIL`` is summed to its accumulation point (as the simulator does); a bar at
rest on the stop is released at the first switch to a pulling level.

The regression: since 7c67706 (a start on the stop, at rest and pressed, is a touch) the flight
after a release found at a load jump could start in the piece before the jump (the jump time,
summed as ``m 2 pi + breaks[j]``, fell a rounding error short of the jump when its phase
``t - m 2 pi`` was formed again): the new flight saw the pressing level, the release was undone
and tried again ``1e-9`` later, and the impacts after it were off by ``1e-9`` times their
sensitivity to the release, which grows about threefold per impact.
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext

import numpy as np
import pytest

from impactbar import BarModel, InitialState, SquareWaveLoad, simulate
from impactbar.simulation.simulate import CHATTER_TAIL

PREC = 50
PI = Decimal("3.14159265358979323846264338327950288419716939937510")
TWO_PI = 2 * PI


def _exact_run(x, v, t0, t_end, R, switch):
    """Impacts ``[(t, arrival velocity)]`` and contact intervals of ``x'' = p(t)``, ``x <= 0``, under
    ``p = +1`` on ``[0, switch)`` and ``-1`` on ``[switch, 2 pi)`` of each period (Decimals)."""
    one = Decimal(1)

    def breaks_after(t):
        n = (t / TWO_PI).to_integral_value(rounding="ROUND_FLOOR")
        return min(b for b in (n * TWO_PI + switch, (n + 1) * TWO_PI, (n + 1) * TWO_PI + switch)
                   if b > t)

    def level_after(t):  # the level on the piece that starts at t (read at its midpoint)
        mid = (t + breaks_after(t)) / 2
        phase = mid - TWO_PI * (mid / TWO_PI).to_integral_value(rounding="ROUND_FLOOR")
        return one if phase < switch else -one

    impacts, contacts = [], []
    t = t0
    while t < t_end:
        te = min(breaks_after(t), t_end)
        p = level_after(t)
        tau = te - t
        # the first s in (0, tau] with x + v s + p s^2 / 2 = 0, arriving (v + p s > 0)
        disc = v * v - 2 * p * x
        roots = [] if disc < 0 else [(-v - disc.sqrt()) / p, (-v + disc.sqrt()) / p]
        roots = [s for s in roots if Decimal("1e-40") < s <= tau and v + p * s > 0]
        if not roots:
            x, v, t = x + v * tau + p * tau * tau / 2, v + p * tau, te
            continue
        s = min(roots)
        t += s
        arrival = v + p * s
        impacts.append((t, arrival))
        x, v = Decimal(0), -R * arrival
        tail = 2 * R * arrival / p / (1 - R) if p > 0 else None
        if tail is not None and tail < Decimal(CHATTER_TAIL):
            start = t + tail
            t = breaks_after(start)
            while level_after(t) > 0:  # at rest on the stop until the load pulls
                t = breaks_after(t)
            contacts.append((start, t))
            x, v = Decimal(0), Decimal(0)
    return impacts, contacts


MODEL = BarModel(s=100, d=0, R=0.5, n_modes=0)
LOAD = SquareWaveLoad(1.0, 1.5)


def _simulated():
    return simulate(MODEL, LOAD, InitialState.rigid(end_displacement=-1.0, velocity=0.3), 120.0)


def _ulp(t):
    return math.ulp(float(t))


def test_second_sticking_contact_released_at_the_switch():
    """A reported case: two sticking contacts, each released at ``2 pi n + 1.5 pi`` to rounding
    (the second was released at ``86.39379797 + 1.0e-9``). The second contact's start, the
    accumulation point of a chatter after an irregular stretch of impacts, is as exact as its
    sensitivity to the first release (1.5e6, from the reference) allows."""
    run = _simulated()
    with localcontext() as ctx:
        ctx.prec = PREC
        switch = Decimal("1.5") * PI
        _, contacts = _exact_run(Decimal(-1), Decimal("0.3"), Decimal(0), Decimal(120), Decimal("0.5"),
                                 switch)
        eps = Decimal("1e-25")
        _, moved = _exact_run(Decimal(0), Decimal(0), switch + eps, Decimal(120), Decimal("0.5"), switch)
        sens = float((moved[0][0] - contacts[1][0]) / eps)
    assert run.contact_intervals.shape == (2, 2) and len(contacts) == 2
    assert run.n_release_retries == 0
    for (_, end), (_, e_exact) in zip(run.contact_intervals, contacts, strict=True):
        assert abs(end - float(e_exact)) <= 4 * _ulp(e_exact)
    assert abs(run.contact_intervals[0, 0] - float(contacts[0][0])) <= 16 * _ulp(contacts[0][0])
    assert abs(sens) > 1e5  # (the irregular stretch between the contacts)
    tol = 4 * _ulp(switch) * abs(sens) + 16 * _ulp(contacts[1][0])
    assert abs(run.contact_intervals[1, 0] - float(contacts[1][0])) <= tol


def test_impacts_after_the_release_follow_the_exact_solution():
    """The impacts after the second release against the exact flights from the exact release: off
    by at most a few rounding errors of the release times their sensitivity to it (computed from
    the reference itself, by a perturbation of 1e-25), plus a few rounding errors of their own.
    (With the release 1e-9 late they were off by 2.4e-9, 7.0e-9, 3.3e-8, 5.7e-8, 1.4e-7.)"""
    run = _simulated()
    t_rel = run.contact_intervals[1, 1]
    later = run.impact_times > t_rel
    with localcontext() as ctx:
        ctx.prec = PREC
        exact_release = 13 * TWO_PI + Decimal("1.5") * PI
        args = (Decimal(0), Decimal(0))
        rest = (Decimal(120), Decimal("0.5"), Decimal("1.5") * PI)
        impacts, _ = _exact_run(*args, exact_release, *rest)
        eps = Decimal("1e-25")
        moved, _ = _exact_run(*args, exact_release + eps, *rest)
        sens = [float((b[0] - a[0]) / eps) for a, b in zip(impacts, moved, strict=True)]
    assert later.sum() == len(impacts) == 5
    t_exact = np.array([float(t) for t, _ in impacts])
    v_exact = np.array([float(v) for _, v in impacts])
    tol = 4 * _ulp(exact_release) * np.abs(sens) + 4 * np.array([_ulp(t) for t in t_exact])
    err = np.abs(run.impact_times[later] - t_exact)
    assert np.all(err <= tol), (err, tol)
    np.testing.assert_allclose(run.impact_velocities[later], v_exact, rtol=0, atol=float(tol.max()))


@pytest.mark.parametrize("R", [0.0, 0.3, 0.5])
@pytest.mark.parametrize("switch", [1.25, 1.5, 1.75, 1.9])
def test_every_sticking_contact_ends_at_a_switch(R, switch):
    """Over 60 periods, from three starts: every sticking contact of the rigid bar ends at a switch
    ``2 pi n + switch pi`` of the load (in 50 digits), released at the first try. To rounding: the
    release may be moved on by ``1e-15 (1 + t)`` where the load, read again at the jump in Python,
    rounds to the level before it (the reaction's sign is noise there; ``_Core._clearly_tensile``)."""
    model = BarModel(s=100, d=0, R=R, n_modes=0)
    load = SquareWaveLoad(1.0, switch)
    ends = []
    for e, v in ((-1.0, 0.3), (-0.2, 0.0), (-3.0, -0.5)):
        run = simulate(model, load, InitialState.rigid(e, v), 2 * math.pi * 60)
        assert run.n_release_retries == 0
        ends.extend(run.contact_intervals[:, 1][run.contact_intervals[:, 1] < run.t_end])
    assert ends, "no sticking contact ended: the case tests nothing"
    with localcontext() as ctx:
        ctx.prec = PREC
        at = Decimal(switch) * PI
        exact = [float(TWO_PI * round((Decimal(float(t)) - at) / TWO_PI) + at) for t in ends]
    ends = np.array(ends)
    np.testing.assert_array_less(np.abs(ends - exact), 1e-15 * (1 + ends) + 4 * np.spacing(ends))
