"""The compiled DOP853 of the oil circuit's plain flights (``_dop853``, the generated ``dop853_fly``):
scipy's method, step for step, on a damped oscillator (closed form) and on a flight of the preset
``circuit-drifter``; its events located on the dense output as CVODE's root finding locates them."""

import numba as nb
import numpy as np
import pytest
from scipy.integrate import DOP853, solve_ivp

from impactbar.drives.circuit import CircuitFlightSettings
from impactbar.drives.circuit import _dop853 as DP
from impactbar.drives.circuit import flight as F
from impactbar.physical import circuit_preset

W2, DAMP = 4.0, 0.1  # the oscillator's y'' + DAMP y' + W2 y = 0


@nb.njit
def _rhs(t, y, yp, par):
    yp[0] = y[1]
    yp[1] = -par[0] * y[0] - par[1] * y[1]


@nb.njit
def _events(t, y, g, par):
    g[0] = y[0] - par[2]
    g[1] = y[1] - par[3]


@pytest.fixture(scope="module")
def oscillator():
    return DP.compile_driver(_rhs, _events)


def _f(t, y):
    return np.array([y[1], -W2 * y[0] - DAMP * y[1]])


def _exact(t):
    """The oscillator from ``(1, 0)``."""
    w = np.sqrt(W2 - DAMP ** 2 / 4)
    e = np.exp(-DAMP * t / 2)
    c, s = np.cos(w * t), np.sin(w * t)
    return np.array([e * (c + DAMP / (2 * w) * s), -e * (W2 / w) * s])


def _fly(code, y0, t_end, rtol, par, directions=(1, 1), spacing=0.0):
    return code.dop853_fly(0.0, np.asarray(y0, dtype=float), t_end, rtol, rtol * 1e-2,
                           np.asarray(directions, dtype=np.int32), par, len(y0), 100000, spacing)


@pytest.mark.parametrize("rtol", [1e-6, 1e-8])
def test_the_steps_are_scipys(oscillator, rtol):
    """The same steps and right-hand sides as ``solve_ivp(method="DOP853")``, the step sizes within
    1e-7 of each other (the first steps' error estimates are rounding, summed in another order:
    measured 4e-10 and 7e-9), each state within 1e-13 of scipy's dense output at its time, and
    within the tolerance of the closed form."""
    par = np.array([W2, DAMP, 10.0, 10.0])  # (events never met)
    flag, t, y, y_end, roots, counts = _fly(oscillator, [1.0, 0.0], 20.0, rtol, par)
    sol = solve_ivp(_f, (0.0, 20.0), [1.0, 0.0], method="DOP853", rtol=rtol, atol=rtol * 1e-2,
                    dense_output=True)
    assert flag == DP.DOP853_TSTOP and t[-1] == 20.0 and not roots.any()
    assert t.size == sol.t.size and counts[0] == t.size - 1
    assert counts[2] == sol.nfev - 3 * counts[0]  # (scipy's dense output: three stages a step)
    assert np.max(np.abs(np.diff(t) / np.diff(sol.t) - 1.0)) < 1e-7
    assert np.max(np.abs(y - sol.sol(t).T)) < 1e-13
    assert np.max(np.abs(y - _exact(t).T)) < 100 * rtol
    np.testing.assert_array_equal(y_end, y[-1])


def test_the_error_norm_and_first_step_are_scipys(oscillator):
    """The error norm on scipy's own stages (its steps' estimates well above rounding) and the first
    step, against scipy's ``DOP853``, to 1e-10 and 1e-12 (the sums in another order)."""
    code = DP.compile_driver(_rhs, _events)
    y0 = np.array([1.0, 0.0])
    s = DOP853(_f, 0.0, y0, 20.0, rtol=1e-6, atol=1e-8)
    f0 = _f(0.0, y0)
    h0, d1 = DP.first_guess(y0, f0, 1e-6, 1e-8, 20.0)
    assert DP.first_step(y0, f0, _f(h0, y0 + h0 * f0), h0, d1, 1e-6, 1e-8, 20.0) == pytest.approx(s.h_abs,
                                                                                              rel=1e-12)
    checked = 0
    for _ in range(20):
        y, t = s.y.copy(), s.t
        s.step()
        h = s.t - t
        scale = 1e-8 + np.maximum(np.abs(y), np.abs(s.y)) * 1e-6
        want = s._estimate_error_norm(s.K, h, scale)
        if want > 1e-3:
            got = code.dop853_error_norm(np.ascontiguousarray(s.K_extended), h, y, s.y, 1e-6, 1e-8)
            assert got == pytest.approx(want, rel=1e-10)
            checked += 1
    assert checked >= 10


def test_an_event_is_located_on_the_dense_output(oscillator):
    """The first crossing of ``y = 0.5`` downwards (the velocity's ``y' = 0.5`` upwards, met later,
    not reported): the state there on the level to 1e-15, its time the closed form's within the
    integration's tolerance (measured 3e-12) and scipy's event (its dense output's root) within
    1e-11, CVODE's root information (-1: come down); asked upwards, the level's next crossing."""
    par = np.array([W2, DAMP, 0.5, 0.5])
    flag, t, y, y_end, roots, counts = _fly(oscillator, [1.0, 0.0], 20.0, 1e-10, par, directions=(-1, 1))
    assert flag == DP.DOP853_ROOT
    np.testing.assert_array_equal(roots, [-1, 0])
    assert abs(y_end[0] - 0.5) < 1e-15
    np.testing.assert_array_equal(y_end, y[-1])
    from scipy.optimize import brentq

    exact = brentq(lambda s: _exact(s)[0] - 0.5, 0.1, 0.9, xtol=1e-15)
    assert t[-1] == pytest.approx(exact, abs=1e-10)
    down = lambda s, x: x[0] - 0.5  # noqa: E731
    down.terminal, down.direction = True, -1
    sol = solve_ivp(_f, (0.0, 20.0), [1.0, 0.0], method="DOP853", rtol=1e-10, atol=1e-12, events=down)
    assert t[-1] == pytest.approx(sol.t_events[0][0], abs=1e-11)
    # upwards only: the level's next crossing, a period on
    par[3] = 10.0
    flag, t2, y2, y_end2, roots2, _ = _fly(oscillator, [1.0, 0.0], 20.0, 1e-10, par, directions=(1, 1))
    np.testing.assert_array_equal(roots2, [1, 0])
    assert abs(y_end2[0] - 0.5) < 1e-15 and 1.5 < t2[-1] < 3.2


def test_an_event_zero_at_the_start_is_not_a_root(oscillator):
    """A function zero at the start (the level ``y = 1`` of the start itself, left downwards) is set
    aside as CVODE's ``cvRcheck1`` sets it aside: the flight runs to its end (the damped oscillator
    never again at 1); a level a little below is met at once."""
    par = np.array([W2, DAMP, 1.0, 10.0])
    flag, t, y, y_end, roots, _ = _fly(oscillator, [1.0, 0.0], 20.0, 1e-10, par, directions=(-1, 1))
    assert flag == DP.DOP853_TSTOP and t[-1] == 20.0 and not roots.any()
    par[2] = 1.0 - 1e-9
    flag, t, y, y_end, roots, _ = _fly(oscillator, [1.0, 0.0], 20.0, 1e-10, par, directions=(-1, 1))
    assert flag == DP.DOP853_ROOT and roots[0] == -1 and t[-1] == pytest.approx(np.sqrt(2e-9 / W2), rel=1e-3)


def test_the_events_are_checked_at_each_kept_point(oscillator):
    """The level ``y = -0.92`` just above the first minimum (-0.924), crossed down and back up within
    0.093, inside one step at ``rtol = 1e-6`` (1.31 to 1.83): missed where the events are checked at
    the steps only (``spacing = 0``, as CVODE checks them at its own), found with samples 0.01 apart,
    at the closed form's crossing within the tolerance's error (measured 4e-6)."""
    from scipy.optimize import brentq

    par = np.array([W2, DAMP, -0.92, 10.0])
    flag, t, _, _, roots, _ = _fly(oscillator, [1.0, 0.0], 20.0, 1e-6, par, directions=(-1, 1))
    assert flag == DP.DOP853_TSTOP and not roots.any() and np.any((t[:-1] < 1.47) & (t[1:] > 1.57))
    flag, t, y, y_end, roots, _ = _fly(oscillator, [1.0, 0.0], 20.0, 1e-6, par, directions=(-1, 1),
                                       spacing=0.01)
    assert flag == DP.DOP853_ROOT and roots[0] == -1 and abs(y_end[0] + 0.92) < 1e-15
    exact = brentq(lambda s: _exact(s)[0] + 0.92, 1.3, 1.57, xtol=1e-15)
    assert t[-1] == pytest.approx(exact, abs=2e-5)


def test_the_samples_are_the_dense_output(oscillator):
    """With ``spacing`` the kept points at most that apart, the samples within a step the closed form
    to the tolerance, and the steps those without samples, to the bit."""
    par = np.array([W2, DAMP, 10.0, 10.0])
    plain = _fly(oscillator, [1.0, 0.0], 20.0, 1e-10, par)
    flag, t, y, _, _, counts = _fly(oscillator, [1.0, 0.0], 20.0, 1e-10, par, spacing=0.01)
    assert np.max(np.diff(t)) <= 0.01 * (1 + 1e-12) and t.size > 2000
    assert np.max(np.abs(y - _exact(t).T)) < 1e-8
    assert np.isin(plain[1], t).all() and counts[0] == plain[5][0]
    np.testing.assert_array_equal(y[np.isin(t, plain[1])], plain[2])


@pytest.fixture(scope="module")
def stroke():
    """The first flight of the preset's piston with 4 modes from its start: its generated code,
    parameters, start, event directions and CVODE's end (Adams at ``rtol = 1e-12``)."""
    d = circuit_preset("circuit-drifter")
    drive, model = d.drive(), d.model().with_(n_modes=4)
    M = model.n_modes + 1
    state = drive.start(model, np.zeros(M), np.zeros(M))
    settings = CircuitFlightSettings(rtol=1e-12, atol=1e-14, multistep="adams")
    cvode = F.circuit_flight(drive, model, state, 0.0, np.zeros(M), np.zeros(M), 1.0, settings)
    net, code = drive._compiled_network(state.mode)
    par = np.concatenate((drive._par(model, state.mode, False), net))
    y0 = cvode.piece.y[0].copy()
    return code, par, y0, np.asarray(drive._directions(state.mode), dtype=np.int32), cvode


def test_a_circuit_flight_takes_scipys_steps_to_cvodes_event(stroke):
    """The stroke by the generated driver at ``rtol = 1e-8`` takes scipy's steps (scipy with the
    flight's events, each terminal in its direction), and at
    ``rtol = 1e-12`` ends at CVODE's event within 1e-11 in time, its state within 1e-8 (measured
    3e-13 and 1e-9)."""
    code, par, y0, directions, cvode = stroke

    def f(t, y):
        yp = np.empty_like(y)
        code.flight_rhs(t, y, yp, par)
        return yp

    flag, t, y, y_end, roots, counts = code.dop853_fly(0.0, y0, 1.0, 1e-8, 1e-10, directions, par, y0.size,
                                                       100000, 0.0)
    assert flag == DP.DOP853_ROOT
    def event(i):
        def g(tt, yy):
            out = np.empty(directions.size)
            code.flight_events(tt, yy, out, par)
            return out[i]

        g.terminal, g.direction = True, int(directions[i])
        return g

    sol = solve_ivp(f, (0.0, 1.0), y0, method="DOP853", rtol=1e-8, atol=1e-10,
                    events=[event(i) for i in range(directions.size)])
    assert sol.status == 1 and t.size == sol.t.size
    assert np.max(np.abs(np.diff(t[:-1]) / np.diff(sol.t[:-1]) - 1.0)) < 1e-6
    assert t[-1] == pytest.approx(sol.t[-1], abs=1e-12)
    scale = np.abs(sol.y[:, -1]) + 1e-3
    assert np.max(np.abs(y_end - sol.y[:, -1]) / scale) < 1e-7

    flag, t, y, y_end, roots, counts = code.dop853_fly(0.0, y0, 1.0, 1e-12, 1e-14, directions, par, y0.size,
                                                       100000, 0.0)
    assert flag == DP.DOP853_ROOT
    hit = F.ARRIVAL_EV if cvode.end == F.ARRIVAL else None
    assert hit is None or roots[hit] != 0
    assert t[-1] == pytest.approx(cvode.t, abs=1e-11)
    n = cvode.q.size
    assert np.max(np.abs(y_end[2 * n:2 * n + cvode.z.size] - cvode.z) / (np.abs(cvode.z) + 1e-3)) < 1e-8
    assert np.max(np.abs(y_end[:n] - cvode.q)) < 1e-8


def _written_out(first, last, indent):
    """The stages ``first`` to ``last - 1`` written out term by term with scipy's coefficients (stage
    12, the solution's weights, into ``y_new``): the straight-line form of the driver's stage loop."""
    out = []
    for s in range(first, last):
        terms = " + ".join(f"K[{j}, i] * {float(DP.A[s, j])!r}" for j in range(s) if DP.A[s, j] != 0.0)
        into = "y_new" if s == DP.N_STAGES else "ys"
        out += ["for i in range(N):", f"    {into}[i] = y[i] + ({terms}) * h",
                f"flight_rhs(t + {float(DP.C[s])!r} * h, {into}, K[{s}], par)"]
    return "\n".join(indent + line for line in out)


def test_the_stage_loop_is_the_written_out_stages_to_the_bit(oscillator, monkeypatch):
    """The driver's stages, one loop over the stages (one call of the vector field to compile, not
    15), give the numbers of the stages written out with their coefficients, to the bit: each sum
    taken term by term in the same order over the same nonzero coefficients, on long flights with and
    without dense samples and on one that ends at an event."""
    source = (DP._SOURCE.replace("@E5@", DP._sum(DP.E5)).replace("@E3@", DP._sum(DP.E3))
              .replace("@DENSE@", "\n".join(f"        F[{3 + r}, i] = ({DP._sum(DP.D[r])}) * h"
                                            for r in range(DP.N_DENSE - 3)))
              .replace("@STEP@", _written_out(1, DP.N_STAGES + 1, " " * 12))
              .replace("@EXTRA@", _written_out(DP.N_STAGES + 1, DP.N_EXTENDED, " " * 12)))
    assert source != DP.SOURCE
    monkeypatch.setattr(DP, "SOURCE", source)
    written = DP.compile_driver(_rhs, _events)
    cases = [([1.0, 0.0], 40.0, 1e-10, (10.0, 10.0), 0.0), ([1.0, 0.0], 40.0, 1e-12, (10.0, 10.0), 0.05),
             ([0.3, -2.0], 30.0, 1e-9, (-0.5, 10.0), 0.02)]
    for y0, t_end, rtol, levels, spacing in cases:
        par = np.array([W2, DAMP, *levels])
        a = _fly(oscillator, y0, t_end, rtol, par, spacing=spacing)
        b = _fly(written, y0, t_end, rtol, par, spacing=spacing)
        assert a[0] == b[0] and a[5][0] > 5
        for x, z in zip(a[1:], b[1:], strict=True):
            assert x.dtype == z.dtype and x.tobytes() == z.tobytes()
