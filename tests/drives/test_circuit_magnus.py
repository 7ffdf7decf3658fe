"""The circuit's fundamental matrix by Magnus' method over the plain flight's steps (the default for a
flexible piston) against CVODE's variational flights: a flight's ``Phi`` against a variational flight
at a hundred times finer tolerance, the method's order, its exponential against scipy's, and the
orbit it gives against the orbit of the variational flights."""

import math

import numpy as np
import pytest
from scipy.linalg import expm as scipy_expm

from impactbar import find_orbit
from impactbar.drives.base import DriveState
from impactbar.drives.circuit import CircuitFlightSettings, _magnus
from impactbar.physical import circuit_preset

#: CVODE's variational flights (the way before Magnus), at the drive's tolerance and at rtol 1e-12
CVODE = CircuitFlightSettings(sensitivity="cvode")
FINE_CVODE = CircuitFlightSettings(rtol=1e-12, atol=1e-14, sensitivity="cvode")


@pytest.fixture(scope="module")
def case():
    """The preset's drive, its model with 4 modes, the orbit (Magnus, the default) and the start of
    its first flight ``(state, t, q, v)``."""
    d = circuit_preset("circuit-drifter")
    model, drive = d.model().with_(n_modes=4), d.drive()
    orbit = find_orbit(model, drive)
    problem, X = orbit._problem, np.asarray(orbit._unknowns, dtype=float)
    M, n = problem.M, problem.n
    tau, mode = problem.blocks[0]
    y = X[:n]
    return drive, model, orbit, (DriveState(mode, y[2 * M:]), tau, y[:M], y[M:2 * M])


@pytest.mark.parametrize("size", [1e-5, 0.04, 0.2, 0.5, 0.9, 1.09, 2.0, 30.0])
def test_the_exponential_is_scipys(size):
    """Each of the Taylor degrees by the norm it is chosen for (4, 8, 12, then 18 over the Magnus
    steps' norms about 1 and to its bound 1.09), and with squarings past it, against scipy's Pade
    exponential."""
    rng = np.random.default_rng(7)
    for _ in range(5):
        A = rng.standard_normal((22, 22))
        A *= size / np.max(np.sum(np.abs(A), axis=0))
        E, ref = _magnus.expm(A), scipy_expm(A)
        assert np.max(np.abs(E - ref)) <= 1e-13 * max(1.0, np.max(np.abs(ref)))


def test_the_magnus_steps_are_the_formula(case):
    """``magnus_phi`` over a flight against the same steps written out here (Blanes, Casas & Ros' sixth
    order in three commutators, in the original coordinates) with scipy's exponential, scipy's cubic
    Hermite spline of the steps and numpy's products (the network's Jacobian the only part shared): to
    1e-12 of the largest entry."""
    from scipy.interpolate import CubicHermiteSpline

    drive, model, _, (state, *rest) = case
    fl = drive.flight(model, state, *rest, math.inf, None, False)
    piece = fl.piece
    net, code = drive._compiled_network(state.mode)
    par = np.concatenate((drive._par(model, state.mode, False), net))
    n, M = piece.layout.size(piece.M), piece.M
    own = np.ascontiguousarray(piece.t - piece.t[0])
    d = _magnus.balance(code.jac_base, piece.y[piece.t.size // 2], par, M, n)
    Phi, steps = code.magnus_phi(own, piece.y, piece.f, par, M, _magnus.DEFAULT_THETA, d)
    spline = CubicHermiteSpline(own, piece.y, piece.f)
    D, Dinv = np.diag(d), np.diag(1.0 / d)

    def jac(t):
        A = np.empty((n, n))
        code.jac_base(np.ascontiguousarray(spline(t)), par, M, A)
        return A

    def comm(X, Y):
        return X @ Y - Y @ X

    ref, t0, A3, count = np.eye(n), 0.0, jac(0.0), 0
    g = (0.5 - math.sqrt(15.0) / 10.0, 0.5, 0.5 + math.sqrt(15.0) / 10.0)
    while True:
        h = _magnus.DEFAULT_THETA / np.max(np.sum(np.abs(Dinv @ A3 @ D), axis=0))
        last = 1.25 * h >= own[-1] - t0
        h = own[-1] - t0 if last else h
        A1, A2, A3 = (jac(t0 + c * h) for c in g)
        a1, a2, a3 = h * A2, math.sqrt(15.0) * h / 3.0 * (A3 - A1), 10.0 * h / 3.0 * (A3 - 2.0 * A2 + A1)
        C1 = comm(a1, a2)
        C2 = -comm(a1, 2.0 * a3 + C1) / 60.0
        Om = a1 + a3 / 12.0 + comm(-20.0 * a1 - a3 + C1, a2 + C2) / 240.0
        ref = scipy_expm(Dinv @ Om @ D) @ ref
        t0, count = t0 + h, count + 1
        if last:
            break
    ref = D @ ref @ Dinv
    assert steps == count
    assert np.max(np.abs(Phi - ref)) <= 1e-12 * np.max(np.abs(ref)), np.max(np.abs(Phi - ref))


def test_a_flights_phi_is_the_fine_variational_flights(case):
    """Magnus' ``Phi`` over the orbit's first flight against CVODE's variational flight at rtol 1e-12
    (measured 3.7e-9 of its largest entry, and allowed 1e-8; the fourth-order method of before 4.6e-8;
    CVODE's variational flight at the drive's tolerance 1.2e-7; the reference converged: 3e-9 from the
    same at rtol 1e-13), the flight's end state the same to the integrators' tolerances."""
    drive, model, _, start = case
    ref = drive.flight(model, *start, math.inf, FINE_CVODE, True)
    fl = drive.flight(model, *start, math.inf, None, True)
    assert fl.t == pytest.approx(ref.t, rel=1e-11)
    assert np.max(np.abs(fl.q - ref.q)) <= 1e-10
    err = np.max(np.abs(fl.sensitivity - ref.sensitivity)) / np.max(np.abs(ref.sensitivity))
    assert err <= 1e-8, err


def test_magnus_is_of_order_six(case):
    """Over the same steps, ``theta`` 1, 1/2 and 1/4 against 1/16: the error falls some 64 times a
    halving (measured 62 and 68; the fourth-order method of before, 13 and 14). The steps are BDF's:
    over Adams-Moulton's, two to three times as long, the state's cubic Hermite interpolant (continuous
    in its first derivative only) has kinks that Magnus' steps resolve as they shrink, and the ratios
    scatter."""
    drive, model, _, start = case
    bdf = CircuitFlightSettings(rtol=1e-13, atol=1e-15, sensitivity="cvode", multistep="bdf")
    fl = drive.flight(model, *start, math.inf, bdf, False)
    piece, (state, *_) = fl.piece, start
    net, code = drive._compiled_network(state.mode)
    par = np.concatenate((drive._par(model, state.mode, False), net))
    n = piece.layout.size(piece.M)
    d = _magnus.balance(code.jac_base, piece.y[piece.t.size // 2], par, piece.M, n)
    own = piece.t - piece.t[0]
    ref = code.magnus_phi(own, piece.y, piece.f, par, piece.M, 1.0 / 16, d)[0]
    errors = [np.max(np.abs(code.magnus_phi(own, piece.y, piece.f, par, piece.M, th, d)[0] - ref))
              for th in (1.0, 0.5, 0.25)]
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 40.0) & (ratios < 100.0)), (errors, ratios)


def test_the_orbit_is_the_variational_flights(case):
    """The orbit with Magnus' ``Phi`` against the orbit of CVODE's variational flights (the way
    before): the same period and impact velocity to 1e-8 (measured 2e-11 and 3.0e-9: the variational
    flights' error at the drive's tolerance, their state among CVODE's ``n^2 + n`` unknowns; the orbit
    over Adams-Moulton's plain flights is 4e-11 from the flights at rtol 1e-12, the slow test), the
    multipliers within the variational flights' own error at the drive's tolerance (2.9e-6 against a
    flight at rtol 1e-12; Magnus' 4e-7)."""
    drive, model, orbit, _ = case
    before = find_orbit(model, drive, settings=CVODE)
    assert orbit.period == pytest.approx(before.period, rel=1e-8)
    assert orbit.impact_velocity == pytest.approx(before.impact_velocity, rel=1e-8)
    assert np.max(np.abs(orbit.multipliers - before.multipliers)) <= 1e-5
    assert orbit.stable and before.stable


@pytest.mark.slow  # about 30 s: the orbit's period of flights at rtol 1e-12
def test_the_multipliers_are_nearer_the_fine_flights_than_cvodes(case):
    """The multipliers against the orbit's at rtol 1e-12 (CVODE's variational flights): Magnus' within
    1e-6 (measured 5.9e-8; the fourth-order method of before 6.7e-8), and nearer than the variational
    flights' at the drive's tolerance (3.0e-6); the orbit's impact velocity within 1e-9 of its
    (measured 2.1e-11; over BDF's plain flights 1.3e-9)."""
    drive, model, orbit, _ = case
    ref = find_orbit(model, drive, settings=FINE_CVODE)
    before = find_orbit(model, drive, settings=CVODE)
    err_magnus = np.max(np.abs(orbit.multipliers - ref.multipliers))
    err_cvode = np.max(np.abs(before.multipliers - ref.multipliers))
    assert err_magnus <= 1e-6 and err_magnus < err_cvode, (err_magnus, err_cvode)
    assert abs(orbit.impact_velocity - ref.impact_velocity) <= 1e-9


def test_the_rigid_piston_keeps_cvodes_flights(case):
    drive, model, _, _ = case
    rigid = model.with_(n_modes=0)
    a = find_orbit(rigid, drive)
    b = find_orbit(rigid, drive, settings=CVODE)
    assert a.period == b.period and np.array_equal(a.multipliers, b.multipliers)


def test_sensitivity_must_be_named(case):
    drive, _, _, _ = case
    with pytest.raises(ValueError, match="sensitivity must be"):
        CircuitFlightSettings(sensitivity="exact")
