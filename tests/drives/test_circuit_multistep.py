"""CVODE's linear multistep method for the oil circuit's flights (the drive's ``multistep``): by
default Adams-Moulton for the plain flights of a piston with modes, BDF for the rigid piston and for
CVODE's variational flights. The flexible piston's orbit is checked against an independent
integration of the same vector field (scipy's ``DOP853`` at ``rtol = 1e-13``, a Newton step of its
own from the orbit found), and against the orbit by BDF's flights (the numbers before)."""

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import circuit_field_reference as K
from impactbar import find_orbit
from impactbar.drives.circuit import CircuitFlightSettings
from impactbar.drives.circuit import flight as F
from impactbar.physical import circuit_preset


@pytest.fixture(scope="module")
def case():
    """The preset's drive and its model with 4 modes."""
    d = circuit_preset("circuit-drifter")
    return d.drive(), d.model().with_(n_modes=4)


def _stiffer(drive, k):
    """``drive`` with its oil's bulk modulus times ``k``."""
    oil = dataclasses.replace(drive.oil, bulk_modulus=k * drive.oil.bulk_modulus)
    return dataclasses.replace(drive, oil=oil)


def _dop853(rtol):
    """A stand-in for the flights' integrators (:func:`.flight._integrate_compiled` and
    ``_integrate_binding``, whose last eight arguments it takes): scipy's DOP853 on the generated
    vector field and events, each event terminal in its direction."""

    def integrate(*args):
        code, par, settings, directions, y0, t, end, keep = args[-8:]
        n_events = len(directions)

        def f(tt, y):
            yp = np.empty_like(y)
            code.flight_rhs(tt, y, yp, par)
            return yp

        def event(i):
            def g(tt, y):
                out = np.empty(n_events)
                code.flight_events(tt, y, out, par)
                return out[i]

            g.terminal, g.direction = True, int(directions[i])
            return g

        sol = solve_ivp(f, (t, end), y0, method="DOP853", rtol=rtol, atol=1e-16,
                        events=[event(i) for i in range(n_events)])
        assert sol.status >= 0, sol.message
        hit = np.array([i for i in range(n_events) if sol.t_events[i].size], dtype=int)
        Y = sol.y.T
        return (2 if sol.status == 1 else 1), sol.message, sol.t, np.ascontiguousarray(Y[:, :keep]), \
            Y[-1].copy(), hit

    return integrate


def _patch(m, rtol):
    """Every plain flight by scipy's DOP853 at ``rtol`` (CVODE's and the compiled DOP853's)."""
    integrate = _dop853(rtol)
    m.setattr(F, "_integrate_compiled", integrate)
    m.setattr(F, "_integrate_binding", integrate)
    m.setattr(F, "_integrate_explicit", lambda code, par, settings, directions, y0, end, keep, spacing:
              integrate(code, par, settings, directions, y0, 0.0, end, keep))


def _reference(orbit, monkeypatch, rtol=1e-13):
    """The orbit's unknowns moved by one Newton step on the shooting residual of DOP853's flights
    (the Jacobian the drive's own: its error moves the step only to second order)."""
    problem = orbit._problem
    X = np.asarray(orbit._unknowns, dtype=float).copy()
    _, J = problem.residual(X)
    with monkeypatch.context() as m:
        _patch(m, rtol)
        problem._last = None  # (not the flight remembered)
        r = problem.value(X)
    problem._last = None
    return X + np.linalg.solve(J, -r)


def test_the_flexible_orbit_is_an_independent_integrations(case, monkeypatch):
    """Adams-Moulton's orbit and the compiled DOP853's (the default) within 1e-10 of scipy's DOP853's
    (measured 1.3e-12 and 6.7e-13); BDF's, the orbit before Adams, within 1e-8 of all (measured 6.9e-10
    from scipy's): Adams' and the compiled DOP853's the more accurate; DOP853's multipliers Adams'
    within 1e-7 (measured 1.3e-10)."""
    drive, model = case
    adams = find_orbit(model, drive, settings=CircuitFlightSettings(multistep="adams"))
    bdf = find_orbit(model, drive, settings=CircuitFlightSettings(multistep="bdf"))
    dop = find_orbit(model, drive)
    ref = _reference(adams, monkeypatch)
    Xa, Xb, Xd = (np.asarray(o._unknowns, dtype=float) for o in (adams, bdf, dop))
    assert np.max(np.abs(Xa - ref)) <= 1e-10
    assert np.max(np.abs(Xd - ref)) <= 1e-10
    assert np.max(np.abs(Xb - ref)) <= 1e-8
    assert np.max(np.abs(Xa - ref)) < 0.1 * np.max(np.abs(Xb - ref))
    assert np.max(np.abs(Xd - ref)) < 0.1 * np.max(np.abs(Xb - ref))
    assert adams.period == pytest.approx(bdf.period, rel=1e-9)
    assert adams.impact_velocity == pytest.approx(bdf.impact_velocity, rel=1e-8)
    np.testing.assert_allclose(adams.multipliers, bdf.multipliers, rtol=0, atol=1e-7)
    np.testing.assert_allclose(dop.multipliers, adams.multipliers, rtol=0, atol=1e-7)


def test_each_flight_takes_the_method_asked(case):
    """``"auto"``: the compiled DOP853 for the flexible piston's plain flights (those under Magnus'
    ``Phi`` too) where the oil is not stiff against its steps, Adams-Moulton where stiffer, BDF
    stiffer still, for the rigid piston's and for CVODE's variational flights; ``"cvode"``: the same
    without DOP853; ``"adams"``, ``"bdf"``: every flight; ``"dop853"``: every plain flight."""
    drive, model = case
    rigid = model.with_(n_modes=0)

    def method(m, multistep="auto", variational=False, sensitivity="auto", **kw):
        state = drive.start(m, np.zeros(m.n_modes + 1), np.zeros(m.n_modes + 1))
        settings = CircuitFlightSettings(multistep=multistep, sensitivity=sensitivity)
        fl = F.circuit_flight(drive, m, state, 0.0, np.zeros(m.n_modes + 1), np.zeros(m.n_modes + 1), 0.05,
                              settings, variational, **kw)
        assert fl.piece.t.size > 3
        return F.last_integrator()

    assert F.stiffness_ratio(drive, model) <= F.EXPLICIT_STIFFNESS
    assert method(model) == "dop853"
    assert method(model, variational=True) == "dop853"  # (the plain flight under Magnus' Phi)
    assert method(model, variational=True, sensitivity="cvode") == "bdf"
    assert method(model, "dop853", variational=True, sensitivity="cvode") == "bdf"
    assert method(rigid) == "bdf"
    assert method(rigid, "dop853") == "dop853"
    assert method(rigid, variational=True) == "bdf"
    assert method(model, "adams") == "adams"
    assert method(model, "bdf") == "bdf"
    assert method(rigid, "adams") == "adams"
    assert method(model, "cvode") == "adams"  # (the way before DOP853)
    assert method(model, "cvode", variational=True) == "adams"
    assert method(rigid, "cvode") == "bdf"
    with pytest.raises(ValueError, match="kernels=None"):
        method(model, "dop853", kernels=K.KERNELS)
    # oil stiffer: Adams between the thresholds, BDF beyond
    for k, want in ((5.0, "adams"), (100.0, "bdf")):
        stiff = _stiffer(case[0], k)
        ratio = F.stiffness_ratio(stiff, model)
        assert (F.EXPLICIT_STIFFNESS < ratio <= F.ADAMS_STIFFNESS) == (want == "adams")
        drive = stiff
        assert method(model) == want
        assert method(model, "cvode") == want
        assert method(model, "adams") == "adams"
        assert method(model, "dop853") == "dop853"


@pytest.mark.parametrize("n_modes", [4, 8, 16])
@pytest.mark.parametrize("k", [1.0, 100.0])
def test_the_stiffness_ratio_is_the_front_chambers_decay_over_the_highest_mode(case, n_modes, k):
    """Against closed forms: the front chamber's relaxation behind its opening at equal pressures,
    ``beta K_f / (V_f sqrt(p_tr))``, over the uniform piston's highest mode ``N pi s`` (measured within
    1e-3: the chamber's coupling to the piston and the supply)."""
    drive, model = case
    drive = _stiffer(drive, k)
    model = model.with_(n_modes=n_modes)
    decay = drive.oil.bulk_modulus * drive.supply.front_coefficient / (
        drive.chambers.front_volume * np.sqrt(drive.oil.transition_pressure))
    assert F.stiffness_ratio(drive, model) == pytest.approx(decay / (n_modes * np.pi * model.s), rel=2e-3)


def test_a_stroke_by_either_method_is_dop853s(case, monkeypatch):
    """One stroke of the flexible piston from the stop to the valve's switch, by Adams, by BDF, by
    the compiled DOP853 and by scipy's DOP853 at ``rtol = 1e-13``: the end time within 1e-12, the
    modal velocities within 1e-7 and the pressures within 3e-8 of scipy's each way (measured: Adams
    2.8e-14, 1.1e-8, 1.6e-9; BDF 5.6e-13, 6.4e-8, 1.0e-8; the compiled DOP853 4.5e-15, 4.5e-10,
    1.4e-10), Adams and the compiled DOP853 the nearer, Adams in fewer than half BDF's steps
    (measured 5,025 against 11,344)."""
    drive, model = case
    q, v = np.zeros(model.n_modes + 1), np.zeros(model.n_modes + 1)
    v[0] = -0.1
    state = drive.start(model, q, v)
    ends = {m: F.circuit_flight(drive, model, state, 0.0, q, v, 5.0, CircuitFlightSettings(multistep=m))
            for m in ("adams", "bdf", "dop853")}
    with monkeypatch.context() as m:
        _patch(m, 1e-13)
        ref = F.circuit_flight(drive, model, state, 0.0, q, v, 5.0)
    errors = {}
    for name, fl in ends.items():
        assert fl.end == ref.end and fl.events == ref.events and fl.events[0].name == "switch_out"
        errors[name] = (abs(fl.t - ref.t), np.max(np.abs(fl.v - ref.v)), np.max(np.abs(fl.z - ref.z)))
        assert np.all(np.array(errors[name]) <= (1e-12, 1e-7, 3e-8)), (name, errors[name])
    assert np.all(np.array(errors["adams"]) < np.array(errors["bdf"])), errors
    assert np.all(np.array(errors["dop853"]) < np.array(errors["bdf"])), errors
    assert ends["adams"].piece.t.size < 0.5 * ends["bdf"].piece.t.size


@pytest.mark.parametrize("bad", ["BDF", "gear", None, 1])
def test_a_bad_multistep_is_refused(bad):
    with pytest.raises(ValueError, match="multistep must be one of"):
        CircuitFlightSettings(multistep=bad)
