"""The compiled valve loop (``simulate.valve_loop``, theory §10) against the valve's loop in
Python, piece by piece (the reference): the same pieces, impacts, switches and final state. On the
flexible bar both run the same kernel calls with the same arguments, so they agree to the last bit;
the rigid bar's closed forms agree to rounding (numpy's and the compiled ``expm1``). The pieces the
compiled loop hands back to Python (a touch without an impact: ``R = 0`` and a valve delay leave the
piston pressed on the stop) are exercised, and so are a full log, ``max_impacts`` and a start through
the stop."""

import numpy as np
import pytest

from impactbar import BarModel, PositionSwitchedDrive, find_orbit, simulate
from impactbar.drives.valve import _compiled_loop as SK
from impactbar.simulation import InitialState

CASES = [  # n_modes, d, R, delay
    (0, 0.1, 0.5, 0.2), (0, 0.0, 0.215, 0.0), (0, 0.3, 0.0, 0.3), (4, 0.05, 0.215, 0.0),
    (4, 0.3, 0.0, 0.3), (8, 0.1, 0.6, 0.5), (3, 0.0, 0.3, 0.1),
]


def _pair(choose, model, drive, start, t_end, **kw):
    fast = simulate(model, drive, start, t_end, **kw)
    choose("simulate.valve_loop", False)
    return fast, simulate(model, drive, start, t_end, **kw)


def _first_difference(fast, ref):
    """The first impact at which two runs differ in a bit (time or velocity), or ``None``."""
    n = min(fast.n_impacts, ref.n_impacts)
    for i in range(n):
        if (fast.impact_times[i] != ref.impact_times[i]
                or fast.impact_velocities[i] != ref.impact_velocities[i]):
            return i
    return None if fast.n_impacts == ref.n_impacts else n


@pytest.mark.parametrize("n, d, R, delay", CASES)
def test_compiled_valve_loop_matches_the_python_loop(n, d, R, delay, choose):
    model = BarModel(s=10.0, d=d, R=R, n_modes=n)
    drive = PositionSwitchedDrive(stroke=1.3, ret=0.7, switch_out=0.8, delay=delay)
    fast, ref = _pair(choose, model, drive, InitialState.rigid(-1.2, 0.4, n), 40.0)
    exact = n > 0
    tol = 0.0 if exact else 1e-12
    if exact:  # (R = 0 included: no micro-impact of a piston pressed on the stop to part them)
        assert _first_difference(fast, ref) is None
    assert fast.n_impacts == ref.n_impacts > 5
    assert fast.switch_kinds == ref.switch_kinds and len(fast.switch_kinds) > 5
    assert len(fast.pieces) == len(ref.pieces)
    for a, b in ((fast.impact_times, ref.impact_times), (fast.impact_velocities, ref.impact_velocities),
                 (fast.switch_times, ref.switch_times), (fast.switch_positions, ref.switch_positions),
                 (fast.pieces.starts, ref.pieces.starts),
                 (fast.final_state.modal_displacement, ref.final_state.modal_displacement),
                 (fast.final_state.modal_velocity, ref.final_state.modal_velocity)):
        np.testing.assert_allclose(a, b, rtol=tol, atol=tol)
    assert fast.t_end == pytest.approx(ref.t_end, abs=tol) and fast.final_valve == ref.final_valve
    t = np.linspace(0.0, 40.0, 801)
    np.testing.assert_allclose(fast.end_displacement(t), ref.end_displacement(t), rtol=0, atol=1e-12)
    np.testing.assert_allclose(fast.end_velocity(t), ref.end_velocity(t), rtol=0, atol=1e-11)
    if R == 0.0 and n:  # pressed on the stop: the general driver's pieces, run by Python
        assert any(type(p).__name__ == "Trajectory" for p in fast.pieces)


def test_compiled_loop_stops_at_max_impacts_and_refills_its_logs(choose, monkeypatch):
    model = BarModel(s=10.0, d=0.05, R=0.4, n_modes=2)
    drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0, delay=0.1)
    start = InitialState.rigid(-0.5, 0.0, 2)
    full = simulate(model, drive, start, 200.0)
    cut = simulate(model, drive, start, 200.0, max_impacts=7)
    assert cut.n_impacts == 7 and cut.status == "max_impacts"
    assert cut.t_end == full.impact_times[6]
    np.testing.assert_array_equal(cut.impact_times, full.impact_times[:7])
    # logs of 1 impact per call: many calls, the same run
    import impactbar.drives.valve.loop as S

    calls = []
    real = SK.run_switched

    def counted(*args):
        calls.append(1)
        return real(*args)

    monkeypatch.setattr(S.SK, "run_switched", counted)
    monkeypatch.setattr(S, "_FIRST_CAP", 1)
    small = simulate(model, drive, start, 200.0)
    assert len(calls) >= 5  # logs of 1, 2, 4, ... impacts
    np.testing.assert_array_equal(small.impact_times, full.impact_times)
    np.testing.assert_array_equal(small.switch_times, full.switch_times)


def test_compiled_loop_refuses_a_start_through_the_stop():
    model = BarModel(s=10.0, d=0.05, R=0.4, n_modes=2)
    drive = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    with pytest.raises(ValueError, match="penetrates"):
        simulate(model, drive, InitialState([0.01, 0.0, 0.0], [0.0, 0.0, 0.0]), 10.0)


def test_compiled_crossing_and_pending_order():
    """The compiled crossing is the rigid coordinate's (closed form, d = 0: y = w0 t - a t^2 / 2
    reaches the level), and the pending switches stay sorted as Python sorts (time, kind)."""
    assert SK.first_rising_crossing(0.0, 0.0, 2.0, -1.0, 1.5) == pytest.approx(1.0, rel=1e-15)
    assert SK.first_rising_crossing(0.0, 0.0, 1.0, -1.0, 1.5) == np.inf  # turns at 0.5
    pt, pk = np.empty(6), np.empty(6, dtype=np.int64)
    n = 0
    entries = [(2.0, 1), (1.0, 1), (2.0, 0), (0.5, 0), (1.0, 0)]
    for tp, kp in entries:
        n = SK._push(pt, pk, n, tp, kp)
    assert list(zip(pt[:n].tolist(), pk[:n].tolist(), strict=True)) == sorted(entries)


@pytest.mark.parametrize("n", [0, 6])
def test_pieces_take_the_specialised_impact_search_with_the_same_impacts(n, choose):
    """Each piece's constant force is a Fourier load of its mean alone, so the flights after an impact
    or a switch take the specialised certified searches (``simulate.impact_search``): the same
    impacts and switches, to rounding, as the general search (``find_crossing``)."""
    choose("simulate.valve_rigid", False)
    model = BarModel(s=10.0, d=0.1, R=0.5, n_modes=n)
    drive = PositionSwitchedDrive(stroke=1.3, ret=0.7, switch_out=0.8, delay=0.2)
    start = InitialState.rigid(-1.2, 0.4, n)
    fast = simulate(model, drive, start, 60.0)
    choose("simulate.impact_search", False)
    ref = simulate(model, drive, start, 60.0)
    assert fast.n_impacts == ref.n_impacts > 10 and fast.switch_kinds == ref.switch_kinds
    np.testing.assert_allclose(fast.impact_times, ref.impact_times, rtol=0, atol=1e-10)
    np.testing.assert_allclose(fast.impact_velocities, ref.impact_velocities, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(fast.switch_times, ref.switch_times, rtol=0, atol=1e-10)


@pytest.mark.parametrize("M, d", [(9, 0.05), (33, 0.3), (5, 0.0)])
def test_sampled_end_maximum_matches_the_numpy_flow(M, d, rng):
    """The admissibility check's compiled sampling (rotations, re-evaluated every 32 samples)
    against the numpy closed form :func:`impactbar.dynamics.modal.step_constant` on the same grid."""
    from impactbar.dynamics.modal import step_constant

    w2 = (10.0 * np.pi * np.arange(M)) ** 2
    c = BarModel(s=10.0, d=d, R=0.5, n_modes=M - 1).end_weights
    q, v = rng.normal(size=M), rng.normal(size=M)
    for h, n in ((3.7, 2917), (0.2, 3), (1.0, 400)):
        Q, _ = step_constant(w2, d, 0.7, q, v, np.linspace(0.0, h, n)[1:-1])
        ref = float(np.max(c @ Q))
        assert SK.end_max_sampled(w2, d, 0.7, c, q, v, h, n) == pytest.approx(ref, rel=0, abs=1e-12 * M)


@pytest.mark.parametrize("d, delay, R", [(0.0, 0.0, 0.215), (0.2, 0.0, 0.5), (0.1, 0.15, 0.3),
                                         (0.05, 0.0, 0.9)])
def test_rigid_fixed_point_is_the_orbit(d, delay, R):
    """The rigid start of find_orbit (secant on the map of arrival velocities) is the orbit: the
    closed form of theory §10 without damping and delay, and Newton's fixed point (one step, below
    the tolerance) with them; the non-trivial multiplier of the 2x2 shortcut is the QR split's."""
    from impactbar.drives.orbitproblem import split_multipliers as _split_multipliers

    drive = PositionSwitchedDrive(stroke=1.2, ret=0.8, switch_out=0.9, delay=delay)
    v, h1, h3 = SK.rigid_orbit_start(d, R, tuple(drive.kernel_view), 1.0)
    o = find_orbit(BarModel(s=10.0, d=d, R=R, n_modes=0), drive)
    assert v == pytest.approx(o.impact_velocity, rel=1e-13)
    assert (h1, h3) == pytest.approx((o.durations[1], o.durations[3]), rel=1e-12)
    if d == 0.0 and delay == 0.0:
        closed = drive.rigid_orbit(R)
        assert v == pytest.approx(closed["impact_velocity"], rel=1e-14)
    Phi = o._monodromy
    f = np.linalg.eig(Phi)[1][:, np.argmin(np.abs(np.linalg.eig(Phi)[0] - 1.0))].real
    trivial, mu = _split_multipliers(Phi, f)
    assert sorted([trivial, mu[0]]) == pytest.approx(sorted(np.linalg.eigvals(Phi).real), abs=1e-13)
