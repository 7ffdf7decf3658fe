"""A flight that starts at rest on the stop and pressed on it (theory §4, §8, §10).

With ``R = 0`` every impact leaves the bar at rest with the struck end on the stop, and under a
position-switched drive each impact ends a piece, so the next piece starts there. Where the elastic
deflection presses the end on the stop (``h'' > 0``) the end stays on it. A start a rounding error
short of the stop (``c . q ~ -1e-19``) used to fly a hair and return at about
``sqrt(2 |h| h'') ~ 1e-9``: a false impact that triggered the valve and started the next piece at
the same state again, an endless chain (the run below made 10,000 impacts within 4e-9 of one time).
"""

import importlib
import math

import numpy as np
import pytest

from impactbar import BarModel, FourierLoad, PositionSwitchedDrive, simulate
from impactbar.dynamics import _crossing as K
from impactbar.simulation import InitialState

sim_module = importlib.import_module("impactbar.simulation._core")


def _pressed_state(model, level, gap):
    """A state at rest whose end is ``gap`` from the stop (``c . q = -gap``) and whose flexible
    deflection presses it on the stop (``h'' > 0``) under the constant force ``level``; with the
    core of that load and ``h''``."""
    core = sim_module._core_for(model, FourierLoad(level, []))
    c, w2 = core.c, core.free.w2
    q = np.zeros(model.n_modes + 1)
    q[1:] = -0.002 * np.sign(c[1:]) / np.arange(1, model.n_modes + 1)  # -w2 q c > 0: pressed
    q[0] = -(float(c[1:] @ q[1:]) + gap) / c[0]
    h2 = float(c @ (level - w2 * q))
    return core, q, np.zeros_like(q), h2


def _search(core, q, v, t_lim=10.0):
    M = q.size
    qa, va = q.copy(), v.copy()
    htol = 1e-14 * float(np.sum(np.abs(core.c * qa)))
    work = (np.empty(M), np.empty(M), *(np.empty(M) for _ in range(4)))
    st, tc = K.find_crossing(tuple(core.data), tuple(core.free.view), core.c, 0.0, np.array([0.0]), qa, va,
                             t_lim, htol, work)
    return st, tc, float(core.c @ work[1])


@pytest.mark.parametrize("gap", [0.0, 1e-19, 5e-18])
def test_a_pressed_start_on_the_stop_is_a_touch(gap):
    """At rest, on the stop to rounding, pressed: the search reports a touch at the start (the
    driver then keeps the end on the stop), not an impact a hair later."""
    model = BarModel(s=10.0, d=0.05, R=0.0, n_modes=4)
    core, q, v, h2 = _pressed_state(model, -0.7, gap)
    assert h2 > 0.5
    assert -1e-17 < float(core.c @ q) <= 0.0
    st, tc, _ = _search(core, q, v)
    assert st == K.TOUCH and tc == 0.0


def test_a_start_clearly_off_the_stop_still_flies():
    """A start a real distance off the stop (1e-6), pressed toward it, reaches it after
    ``sqrt(2 gap / h'')`` at the speed ``sqrt(2 gap h'')`` (Taylor's expansion: the jerk term is
    a relative correction of order ``tau h''' / h''``)."""
    model = BarModel(s=10.0, d=0.05, R=0.0, n_modes=4)
    gap = 1e-6
    core, q, v, h2 = _pressed_state(model, -0.7, gap)
    st, tc, speed = _search(core, q, v)
    assert st == K.CROSS
    assert tc == pytest.approx(math.sqrt(2.0 * gap / h2), rel=0.05)
    assert speed == pytest.approx(math.sqrt(2.0 * gap * h2), rel=0.05)


def test_a_start_on_the_stop_that_is_pulled_away_leaves_it():
    """The same start with the deflection reversed pulls the end off the stop (``h'' < 0``): no
    touch; the end flies and comes back after a real flight."""
    model = BarModel(s=10.0, d=0.05, R=0.0, n_modes=4)
    core, q, v, h2 = _pressed_state(model, -0.7, 0.0)
    q[1:] = -q[1:]
    q[0] = -float(core.c[1:] @ q[1:]) / core.c[0]
    assert float(core.c @ (-0.7 - core.free.w2 * q)) < 0.0
    st, tc, speed = _search(core, q, v)
    assert st in (K.CROSS, K.NONE)
    assert tc > 1e-3


@pytest.mark.parametrize("n, d, delay", [(4, 0.05, 0.0), (4, 0.3, 0.3), (8, 0.1, 0.3)])
def test_plastic_impacts_under_the_valve_make_no_micro_impacts(n, d, delay):
    """``R = 0`` under a position-switched drive: every impact is a blow or a real rebound (the
    slowest above 1e-3 of the blow), the run reaches its end, and the piston sticks on the stop
    where it is pressed there (contact intervals of the pieces run by the driver). Before the
    fix the first case never reached t = 40 (10,000 impacts within 4e-9 of t = 19.897), and the
    others had 10 to 164 impacts of 1e-10 to 1e-8."""
    model = BarModel(s=10.0, d=d, R=0.0, n_modes=n)
    drive = PositionSwitchedDrive(stroke=1.3, ret=0.7, switch_out=0.8, delay=delay)
    run = simulate(model, drive, InitialState.rigid(-1.2, 0.4, n), 40.0, max_impacts=2000)
    assert run.status == "t_end" and run.t_end == 40.0
    speeds = np.abs(run.impact_velocities)
    assert 8 <= run.n_impacts < 60
    assert speeds.min() > 1e-3 * speeds.max()
    sticks = [iv for p in run.pieces if type(p).__name__ == "Trajectory" for iv in p.contact_intervals]
    assert any(b - a > 1e-3 for a, b in sticks)


def test_chatter_under_the_valve_is_summed():
    """``R > 0`` under a position-switched drive: each piece ends at its first impact, and the
    bounces of a chatter used to be followed one piece each, down to rounding (3,000 impacts by
    t = 11.38, the run stalled there). The bounces that accumulate within ``CHATTER_TAIL`` are now
    summed as in the time-periodic driver: the run reaches its end, and the bounces it follows
    fall off as the bouncing ball's, ``v_{k+1} = R v_k`` (the end's acceleration barely changes
    over a bounce)."""
    model = BarModel(s=8.0, d=0.035, R=0.1, n_modes=1)
    drive = PositionSwitchedDrive(stroke=1.57, ret=0.94, switch_out=0.85, delay=0.0)
    run = simulate(model, drive, InitialState.rigid(-1.0, 0.3, 1), 40.0, max_impacts=3000)
    assert run.status == "t_end" and run.n_impacts < 200
    t, v = run.impact_times, np.abs(run.impact_velocities)
    bounce = np.diff(t) < 0.01  # (the blow and its first rebound excepted)
    assert bounce.sum() >= 10
    np.testing.assert_allclose(v[1:][bounce] / v[:-1][bounce], 0.1, rtol=0.02)
