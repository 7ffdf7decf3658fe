"""The oil circuit's flights by CVODE driven from compiled code (``drives.circuit._cvode``) against
the same CVODE through scikit-sundae's Python interface (the way before, kept as the fallback).

Both run the same SUNDIALS library with the same options and the same compiled vector field, so the
steps must agree to the bit: a difference in an option, a callback or the root handling shows.
"""

import sys
import threading

import numpy as np
import pytest

from impactbar import BarModel, InitialState, find_orbit, simulate
from impactbar.drives import DriveState
from impactbar.drives.circuit import (
    Accumulator,
    Chambers,
    CircuitFlightSettings,
    HydraulicCircuitDrive,
    Oil,
    Supply,
    Valve,
    _sundials,
)
from impactbar.drives.circuit import flight as F
from impactbar.drives.circuit.drive import _rate_model
from impactbar.drives.flight import ARRIVAL, EVENT

RIGID = BarModel(s=52, d=0, R=0.215, n_modes=0)
FLEX = RIGID.with_(n_modes=2)


def pumped():
    return HydraulicCircuitDrive(
        Chambers(area_ratio=0.5, rear_volume=0.4, front_volume=0.2),
        Valve(switch_out=0.048, coefficient=2.0, switching_time=0.05),
        Supply(pump_flow=0.07, hose_volume=1.0, front_coefficient=2.0, tank_pressure=0.03,
               relief_pressure=1.5, relief_coefficient=0.5),
        Oil(bulk_modulus=70.0, transition_pressure=0.01),
        Accumulator(precharge=0.5, volume=2.0))


def start(model):
    """The struck end at rest 0.08 past the stop, the valve opening from 0.3 (a ramp, then the
    stroke): a flight that ends at the ramp's end."""
    M = model.n_modes + 1
    q, v = np.zeros(M), np.zeros(M)
    q[0] = -0.08
    return q, v, DriveState((1, 1, 1, 0), np.array([0.9, 0.9, 0.9, 0.3]))


def both(fn):
    """``fn(True)`` (by the compiled driver, the default), then ``fn(False)`` (through
    scikit-sundae's interface)."""
    return fn(True), fn(False)


def flies(compiled, **options):
    """The circuit's settings, compiled or not (:class:`CircuitFlightSettings`)."""
    return CircuitFlightSettings(compiled=compiled, **options)


def test_the_libraries_bind_here():
    if sys.platform != "linux":
        pytest.skip("scikit-sundae's Linux wheels are the layout checked here")
    assert _sundials.available(), _sundials.reason()
    assert F._compiled_driver() is not None


@pytest.mark.parametrize("model", [RIGID, FLEX], ids=["rigid", "2 modes"])
def test_a_flight_is_the_bindings_to_the_bit(model):
    if not _sundials.available():
        pytest.skip(_sundials.reason())
    drive = pumped()
    q, v, state = start(model)
    fl, ref = both(lambda c: F.circuit_flight(drive, model, state, 0.3, q, v, 50.0, flies(c)))
    assert fl.end == ref.end == EVENT and fl.events[0].name == "ramp_end"
    assert fl.piece.t.size > 100
    assert np.array_equal(fl.piece.t, ref.piece.t)
    assert np.array_equal(fl.piece.y, ref.piece.y)
    for a, b in ((fl.q, ref.q), (fl.v, ref.v), (fl.z, ref.z)):
        assert np.array_equal(a, b)
    # CVODE's own counters: every step is kept (and the start)
    from impactbar.drives.circuit import _cvode

    stats = _cvode.last_workspace().statistics()
    assert stats["steps"] == fl.piece.t.size - 1
    assert stats["rhs"] >= stats["steps"] and stats["jacobians"] >= 1


@pytest.mark.parametrize("model", [RIGID, FLEX], ids=["rigid", "2 modes"])
def test_a_variational_flight_by_the_band_solver_is_the_dense_ones(model):
    """The variational flights' Newton systems solved by the band solver (half-bandwidths n - 1,
    ``Phi`` stored by columns) against scikit-sundae's dense solver: the same to rounding."""
    if not _sundials.available():
        pytest.skip(_sundials.reason())
    drive = pumped()
    q, v, state = start(model)
    fl, ref = both(lambda c: F.circuit_flight(drive, model, state, 0.3, q, v, 50.0,
                                              flies(c, sensitivity="cvode"), variational=True))
    from impactbar.drives.circuit import _cvode

    assert _cvode.last_workspace() is not None and _cvode.last_workspace().band == 2 * model.n_modes + 5
    assert fl.end == ref.end == EVENT
    assert fl.t == pytest.approx(ref.t, rel=1e-12, abs=0.0)
    assert np.allclose(fl.z, ref.z, rtol=1e-11, atol=0.0)
    assert np.allclose(fl.v, ref.v, rtol=1e-10, atol=1e-12)
    scale = np.max(np.abs(ref.sensitivity))
    assert np.allclose(fl.sensitivity, ref.sensitivity, rtol=1e-9, atol=1e-9 * scale)
    # and the fundamental matrix is what it is: central differences of plain flights' end states
    plain = F.circuit_flight(drive, model, state, 0.3, q, v, 50.0)
    h = 1e-4
    M = q.size
    for j in (0, 2 * M + 1):  # the struck end's position, the rear pressure
        ends = []
        for sign in (1, -1):
            y = np.concatenate((q, v, state.z))
            y[j] += sign * h
            f = F.circuit_flight(drive, model, DriveState(state.mode, y[2 * M:]), 0.3, y[:M], y[M:2 * M],
                                 50.0)
            assert f.end == EVENT and f.t == pytest.approx(plain.t, rel=1e-12)  # the ramp's end: fixed
            ends.append(np.concatenate((f.q, f.v, f.z)))
        # (the flights' noise of 1e-10 over 2h: some 1e-6 against entries up to 1)
        assert np.allclose((ends[0] - ends[1]) / (2 * h), fl.sensitivity[:, j], rtol=1e-4, atol=1e-5 * scale)


def test_runs_and_orbits_are_the_bindings_to_the_bit(monkeypatch):
    """The settings' ``compiled`` option reaches every flight of a run and of an orbit's search (each
    through the binding with ``compiled=False``, none with the default), the drive the same."""
    if not _sundials.available():
        pytest.skip(_sundials.reason())
    drive = pumped()
    slow = flies(False)
    assert slow != drive.integrator == flies(True)
    with pytest.raises(ValueError, match="compiled must be True or False"):
        flies(1)

    through = []
    binding = F._integrate_binding
    monkeypatch.setattr(F, "_integrate_binding", lambda *a: through.append(1) or binding(*a))

    run = simulate(RIGID, drive, InitialState.rigid(0.0, 0.0), 8.0)
    assert through == []
    ref = simulate(RIGID, drive, InitialState.rigid(0.0, 0.0), 8.0, settings=slow)
    assert len(through) >= run.n_impacts
    assert run.n_impacts >= 3
    assert np.array_equal(run.impact_times, ref.impact_times)
    assert np.array_equal(run.impact_velocities, ref.impact_velocities)
    assert drive.energy(run) == drive.energy(ref)
    through.clear()
    o = find_orbit(RIGID, drive)
    assert through == []
    oref = find_orbit(RIGID, drive, settings=slow)
    assert len(through) > 0 and oref.drive == o.drive and oref.problem.settings == slow
    assert o.period == oref.period and np.array_equal(o.multipliers, oref.multipliers)


def test_flights_in_threads_are_the_serial_ones():
    """Each thread has its own CVODE workspace (the compiled loop releases the GIL)."""
    drive = pumped()
    state = DriveState((1, 0, 1, 0), np.array([0.9, 0.9, 0.9, 1.0]))
    starts = [-0.06 - 0.01 * k for k in range(4)]

    def one(x):
        return F.circuit_flight(drive, RIGID, state, 0.0, np.array([x]), np.array([0.0]), 50.0)

    serial = [one(x) for x in starts]
    out = [None] * len(starts)

    def work(k):
        for _ in range(3):
            out[k] = one(starts[k])

    threads = [threading.Thread(target=work, args=(k,)) for k in range(len(starts))]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    for a, b in zip(out, serial, strict=True):
        assert a.end == ARRIVAL and a.t == b.t and np.array_equal(a.piece.y, b.piece.y)


def test_without_the_libraries_the_flights_go_through_the_binding(monkeypatch):
    drive = pumped()
    state = DriveState((1, 0, 1, 0), np.array([0.9, 0.9, 0.9, 1.0]))
    fl = F.circuit_flight(drive, RIGID, state, 0.0, np.array([-0.08]), np.array([0.0]), 50.0)
    monkeypatch.setattr(_sundials, "_BINDING", None)
    monkeypatch.setattr(_sundials, "_paths", lambda: None)
    assert not _sundials.available() and "not found" in _sundials.reason()
    assert F._compiled_driver() is None
    ref = F.circuit_flight(drive, RIGID, state, 0.0, np.array([-0.08]), np.array([0.0]), 50.0)
    assert ref.end == ARRIVAL and ref.t == fl.t and np.array_equal(ref.piece.y, fl.piece.y)


def test_a_failure_is_reported_not_printed(capfd):
    """CVODE's failure reaches the caller as the ValueError's reason; SUNDIALS prints nothing (its
    error handlers are cleared in the compiled driver's workspace)."""
    with pytest.raises(ValueError, match="could not be integrated \\(Convergence tests failed"):
        F.circuit_flight(pumped(), RIGID, DriveState((1, 0, 1, 0), np.array([0.9, 0.9, -50.0, 1.0])), 0.0,
                         np.array([-0.08]), np.array([0.0]), 50.0)
    out, err = capfd.readouterr()
    assert "CVODE" not in out + err and "cvHandleFailure" not in out + err


def test_a_step_that_collapses_is_not_printed(capfd):
    """Where CVODE's step falls below the rounding of its time (``t + h = t``: a piston of 0.135 mm
    diameter, 1/3000 of the preset's area, whose oil is far stiffer than its mass) SUNDIALS would print
    a warning line per step (ten a flight); the library's answer is the refusal, and nothing is
    printed (``CVodeSetMaxHnilWarns(-1)`` in the compiled driver's workspace)."""
    from impactbar import physical as ph

    cfg = ph.with_values(ph.read_config("circuit-drifter")[0], {"bar.diameter": "0.135 mm"})
    with pytest.raises(ValueError, match="no periodic orbit"):
        ph.build(cfg).orbit()
    out, err = capfd.readouterr()
    assert "WARNING" not in out + err and "t + h = t" not in out + err


def test_a_flight_past_its_step_bound_says_so(monkeypatch):
    """A flight that runs out of steps is named as that (the bound and the modes), not as a chamber
    or a pump that cannot move the piston; the same flight with the bound restored arrives. (Compiled:
    scikit-sundae's interface steps CVODE one step a call, so its bound is a call's.)"""
    compiled = True
    state = DriveState((1, 0, 1, 0), np.array([0.9, 0.9, 0.9, 1.0]))
    args = (pumped(), RIGID, state, 0.0, np.array([-0.08]), np.array([0.0]), 50.0)
    assert F.circuit_flight(*args, flies(compiled)).end == ARRIVAL
    monkeypatch.setattr(F, "_MAX_STEPS", 20)
    with pytest.raises(ValueError, match="took more than 20 steps without an event .*0 modes") as err:
        F.circuit_flight(*args, flies(compiled))
    assert "rear_volume" not in str(err.value)


def test_a_stroke_flights_steps_are_the_error_controls_not_failures():
    """Theory §11's counts: on a stroke flight of the preset (from rest 60 mm out, the supply at
    22 MPa) CVODE takes about 380 steps, fewer than 5 % rejected by the error test, with 1.3 Newton
    iterations a step and no convergence failure."""
    if not _sundials.available():
        pytest.skip(_sundials.reason())
    from impactbar.drives.circuit import _cvode
    from impactbar.physical import circuit_preset

    d = circuit_preset("circuit-drifter")
    fl = F.circuit_flight(d.drive(), d.model(), DriveState((1, 0, 1, 0), np.array([2.2, 2.2, 2.2, 1.0])), 0.0,
                          np.array([-0.06 / d.bar.length_m]), np.array([0.0]), 50.0)
    assert fl.end == ARRIVAL
    st = _cvode.last_workspace().statistics()
    assert 340 <= st["steps"] <= 420
    assert st["error_test_failures"] < 0.05 * st["steps"] and st["newton_failures"] == 0
    assert round(st["newton_iterations"] / st["steps"], 1) == 1.3


def test_the_pressures_carry_the_flexible_modes_oscillations():
    """Theory §11's reason why a flexible piston stays slow: on the preset with eight modes the rear
    chamber's pressure oscillates at each mode's frequency ``s n pi``, about 1e-4 at the first and
    1e-5 at the eighth (of a level of 2), far above the flights' tolerance (1e-10)."""
    from impactbar.physical import circuit_preset

    d = circuit_preset("circuit-drifter")
    drive = d.drive()
    o = find_orbit(d.model(), drive)
    z = np.asarray(o.drive_states[0])
    v = float(np.atleast_1d(o.states_after_impact[0][1])[0])
    restart = HydraulicCircuitDrive(*(getattr(drive, f) for f in ("chambers", "valve", "supply", "oil",
                                                                   "accumulator")), start_pressures=tuple(z))
    model = d.model().with_(n_modes=8)
    run = simulate(model, restart, InitialState.rigid(0.0, v, 8), 2.2 * o.period)
    t0, t1 = run.impact_times[0], run.impact_times[1]  # a period after an impact
    N = 2**18
    t = np.linspace(t0, t1, N, endpoint=False)
    pr = restart.histories(run, t)["p_r"]
    assert 2.0 < np.max(pr) < 2.5
    spectrum = np.abs(np.fft.rfft((pr - pr.mean()) * np.hanning(N))) * 4 / N  # a sine's amplitude
    omega = np.fft.rfftfreq(N, d=(t1 - t0) / N) * 2 * np.pi
    amp = []
    for n in (1, 8):
        k = int(np.argmin(np.abs(omega - model.s * n * np.pi)))
        amp.append(spectrum[k - 20:k + 20].max())
    assert 10**-4.5 < amp[0] < 10**-3.5 and 10**-5.5 < amp[1] < 10**-4.5, amp


@pytest.mark.slow  # 10 s: the circuit's kernels compiled in a new process, in memory
def test_an_unwritable_numba_cache_compiles_the_circuit_in_memory():
    """Where numba cannot write its cache (a read-only install, no NUMBA_CACHE_DIR), the circuit's
    kernels and CVODE's callbacks compile in memory, as the simulator's do: they asked for a cache
    and failed at import ("cannot cache function 'phi': no locator available")."""
    import subprocess
    import textwrap

    script = textwrap.dedent("""
        import numba.core.caching as C
        def fail(self):
            raise OSError("read-only")
        C._CacheLocator.ensure_cache_path = fail
        from impactbar import find_orbit
        from impactbar.physical import circuit_preset
        from impactbar.drives.circuit import flight
        d = circuit_preset("circuit-drifter")
        print(find_orbit(d.model(), d.drive()).period, flight._compiled_driver() is not None)
    """)
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    period, compiled = r.stdout.split()[-2:]
    assert float(period) == pytest.approx(1.0262627571, rel=1e-8)
    assert compiled == str(_sundials.available())


def test_the_circuit_during_a_blow_is_the_bindings_to_the_bit(monkeypatch):
    """The circuit over a stretch of a blow (the lattice's steps: the arriving wave constant on each
    interval) by the compiled driver against scikit-sundae's interface: the same steps, events and
    impulses, to the bit; a wave that varies within an interval goes through the binding."""
    if not _sundials.available():
        pytest.skip(_sundials.reason())
    from impactbar.drives.circuit import endflight as EF

    drive = pumped()
    state = DriveState((1, 1, 1, 0), np.array([0.9, 0.9, 0.9, 0.3]))  # the valve's ramp: an event inside
    breaks = np.linspace(0.0, 0.4, 9)
    waves = [0.3, -0.2, 0.1, 0.0, 0.2, -0.1, 0.05, 0.0]

    calls, original = [], EF._solver
    monkeypatch.setattr(EF, "_solver", lambda *args: calls.append(1) or original(*args))

    def stretch(compiled):
        calls.clear()
        out = EF.circuit_end_flight(drive, RIGID, state, breaks, 0.0, waves, 52.0, flies(compiled),
                                    one_mode=_rate_model(1))
        return out, len(calls)

    (a, through_a), (b, through_b) = both(stretch)
    assert through_a == 0 and through_b > 0  # the compiled driver, then the binding
    assert a.events and [(t, e.name, m) for t, e, m in a.events] == [(t, e.name, m) for t, e, m in b.events]
    assert len(a.pieces) == len(b.pieces) > breaks.size - 1
    assert all(np.array_equal(p.t, q.t) and np.array_equal(p.y, q.y) and np.array_equal(p.f, q.f)
               for p, q in zip(a.pieces, b.pieces, strict=True))
    assert np.array_equal(a.impulses, b.impulses) and a.w == b.w and np.array_equal(a.state.z, b.state.z)
    calls.clear()
    smooth = EF.circuit_end_flight(drive, RIGID, state, breaks[:2], 0.0, [lambda t: 0.3 + 0.0 * t], 52.0,
                                   one_mode=_rate_model(1))
    assert calls and np.array_equal(smooth.pieces[0].y, b.pieces[0].y)



@pytest.mark.parametrize("w0, which", [(0.4001, "rear"), (-0.8001, "front")])
def test_a_chamber_emptied_during_a_blow_is_refused_the_same_either_way(w0, which):
    """The driven end past a chamber's volume (rear 0.4, front 0.2 / 0.5) over a short stretch of a
    blow: the compiled stretches and scikit-sundae's interface refuse it with the same message (the
    stretch's start)."""
    if not _sundials.available():
        pytest.skip(_sundials.reason())
    from impactbar.drives.circuit import endflight as EF

    state = DriveState((1, 1, 1, 0), np.array([0.9, 0.9, 0.9, 0.3]))
    breaks = np.array([0.0, 1e-7, 2e-7])

    def refusal(compiled):
        with pytest.raises(ValueError, match=f"the {which} chamber empties") as err:
            EF.circuit_end_flight(pumped(), RIGID, state, breaks, w0, [0.0] * 2, 52.0, flies(compiled),
                                  one_mode=_rate_model(1))
        return str(err.value)

    a, b = both(refusal)
    assert a == b and "near t = 0:" in a
