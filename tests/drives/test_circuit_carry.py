"""The variational flights carrying the Jacobian so far (``CircuitFlightSettings.carry``) on the spool
drill (``examples/circuit_drill_spool.toml``, rigid piston): each flight's variational equations
started from the product of the flights and saltations before it instead of the identity.

Checked against independent numbers: the shooting Jacobian at the orbit against central differences
of the same plain flights, and against the Jacobian composed after each flight (``carry=False``, the
way before); the cost: CVODE's steps over the variational period. Such a circuit's orbit is the root
of plain flights at a finer tolerance (``root_settings``), with no closing step by a variational
flight: checked against an orbit at a hundred times finer tolerance.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import impactbar.drives.circuit.flight as FL
from impactbar import find_orbit
from impactbar.drives.circuit import CircuitFlightSettings, _cvode
from impactbar.drives.circuit.settings import circuit_settings
from impactbar.physical import circuit_preset, load

SPOOL = Path(__file__).resolve().parents[2] / "examples" / "circuit_drill_spool.toml"


@pytest.fixture(scope="module")
def spool():
    d = load(SPOOL)
    return d.model(), d.drive()


@pytest.fixture(scope="module")
def orbit(spool):
    return find_orbit(*spool)


def _jacobian(problem, X, carry):
    settings = dataclasses.replace(problem.settings, carry=carry) if carry is not None else None
    return problem.residual(X, settings)


def test_auto_carries_for_the_spools_rigid_piston_only(spool):
    model, drive = spool
    assert drive.carries(model)
    assert not drive.carries(model.with_(n_modes=2))  # (Magnus' fundamental matrix: nothing to carry)
    assert not drive.carries(model, CircuitFlightSettings(carry=False))
    preset = circuit_preset("circuit-drifter")
    assert not preset.drive().carries(preset.model())  # (no part of mechanical state: as before)
    assert preset.drive().carries(preset.model(), CircuitFlightSettings(carry=True))
    with pytest.raises(ValueError, match="carry must be one of"):
        CircuitFlightSettings(carry="yes")


def test_the_carried_jacobian_is_the_central_differences_and_the_one_composed_after(orbit):
    """At the spool drill's orbit: the residual's Jacobian carried against central differences of the
    plain flights (as the uncarried one is checked, ``test_circuit.py``) and against the Jacobian
    composed after each flight, to the flights' accuracy (measured 1.8e-10 of its largest entry; both
    4.2e-6 off the differences)."""
    problem = orbit._problem
    X = np.asarray(orbit._unknowns, dtype=float)
    r, J = _jacobian(problem, X, True)
    _, J0 = _jacobian(problem, X, False)
    assert np.max(np.abs(r)) < 1e-8
    scale = np.max(np.abs(J))
    assert np.max(np.abs(J - J0)) <= 1e-8 * scale
    problem.variational = False
    try:
        _, Jfd = problem.residual(X)
    finally:
        problem.variational = True
    assert np.allclose(J, Jfd, rtol=1e-4, atol=1e-5 * scale)
    mu = np.sort(np.abs(np.linalg.eigvals(Jfd + np.eye(X.size))))[::-1]
    assert mu[0] == pytest.approx(abs(orbit.multipliers[0]), rel=1e-4)


def test_carrying_spends_the_fast_transients_once_a_period(orbit, monkeypatch):
    """CVODE's steps over the spool drill's variational period (29 flights): started at the identity
    each flight spends some 760 steps on the fast transients of its stiff columns; carried, some 230
    (measured 22,155 against 6,668 steps a period)."""
    steps = []
    flight = FL.circuit_flight

    def counted(*args, **kwargs):
        out = flight(*args, **kwargs)
        steps.append(_cvode.last_workspace().statistics()["steps"])
        return out

    monkeypatch.setattr(FL, "circuit_flight", counted)
    problem = orbit._problem
    X = np.asarray(orbit._unknowns, dtype=float)
    count = {}
    for carry in (True, False):
        steps.clear()
        _jacobian(problem, X, carry)
        count[carry] = sum(steps)
    assert len(steps) > 20
    assert count[True] < count[False] / 2, count


def test_the_spools_orbit_is_its_finer_plain_flights_root_without_a_closing_step(spool, orbit, monkeypatch):
    """The chord's plain flights at ``ROOT_TOLERANCE`` times the drive's tolerance (only where the
    variational flights carry: not on the preset, nor with ``carry=False``): their root is the orbit,
    one variational period at the drive's tolerance flown (the orbit's data and multipliers) where a
    closing Newton step flew another. Nearer an orbit at ``rtol = 1e-12`` than that closing step's root
    (measured against main's reference: 1.3e-10 of the unknowns and 8.4e-10 of the multipliers, the
    closing step's 2.1e-10 and 1.2e-9)."""
    model, drive = spool
    fine = drive.root_settings(model)
    assert (fine.rtol, fine.atol) == pytest.approx((3e-11, 3e-13), rel=1e-12)
    assert drive.root_settings(model, CircuitFlightSettings(carry=False)) is None
    assert drive.root_settings(model.with_(n_modes=2)) is None
    preset = circuit_preset("circuit-drifter")
    assert preset.drive().root_settings(preset.model()) is None
    flights = []
    flight = FL.circuit_flight

    def counted(*args, **kwargs):
        settings = kwargs.get("settings", args[7] if len(args) > 7 else None)
        variational = kwargs.get("variational", args[8] if len(args) > 8 else False)
        if variational and circuit_settings(settings).rtol == 1e-10:
            flights.append(1)
        return flight(*args, **kwargs)

    monkeypatch.setattr(FL, "circuit_flight", counted)
    again = find_orbit(model, drive)
    monkeypatch.undo()
    assert len(flights) == 29  # (one period: the closing step's would make 58)
    assert np.array_equal(again._unknowns, orbit._unknowns)
    ref = find_orbit(model, drive, settings=CircuitFlightSettings(rtol=1e-12, atol=1e-14))
    X, R = np.asarray(orbit._unknowns), np.asarray(ref._unknowns)
    assert np.max(np.abs(X - R) / np.maximum(np.abs(R), 1e-2)) < 1.7e-10
    mu, mu_ref = (np.sort(np.abs(np.asarray(o.multipliers)))[::-1][:2] for o in (orbit, ref))
    assert np.allclose(mu, mu_ref, rtol=1e-9, atol=0.0)
