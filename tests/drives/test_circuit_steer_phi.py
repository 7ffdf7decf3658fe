"""The chord's steering flight of the spool drill with its fundamental matrix at a tolerance of its
own (``CircuitFlightSettings.phi_atol``, ``_closing.STEER_PHI_ATOL``; theory §11): CVODE's error test
on the state alone where the matrix only steers the chord."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import impactbar.drives.circuit.flight as FL
from impactbar import find_orbit
from impactbar.drives.circuit import CircuitFlightSettings, _cvode
from impactbar.orbits import _closing as C
from impactbar.physical import circuit_preset, load

SPOOL = Path(__file__).resolve().parents[2] / "examples" / "circuit_drill_spool.toml"


@pytest.fixture(scope="module")
def spool():
    d = load(SPOOL)
    model, drive = d.model(), d.drive()
    return model, drive, find_orbit(model, drive)


@pytest.mark.parametrize("value", [0.0, -1e-5, math.inf, math.nan, True, "1e-5"])
def test_phi_atol_positive_and_finite_or_none(value):
    assert CircuitFlightSettings(phi_atol=None).phi_atol is None
    with pytest.raises(ValueError, match="phi_atol must be positive and finite"):
        CircuitFlightSettings(phi_atol=value)


def test_only_the_spools_steering_flight_takes_it(spool):
    _, _, orbit = spool
    loose = C.loose_settings(orbit._problem.settings)
    assert C.steer_settings(orbit._problem, loose) == dataclasses.replace(loose, phi_atol=C.STEER_PHI_ATOL)
    preset = circuit_preset("circuit-drifter")
    other = find_orbit(preset.model(), preset.drive())._problem
    loose = C.loose_settings(other.settings)
    assert C.steer_settings(other, loose) is loose


def test_the_matrix_at_the_states_tolerance_is_the_scalar_tolerances_flight(spool):
    """``phi_atol`` equal to ``atol``: CVODE's vector tolerances weigh each component as its scalar
    ones, the same residual and Jacobian to the bit; at ``STEER_PHI_ATOL`` the Jacobian stays within
    1e-5 of its largest entry (measured 1.7e-6) and the residual within the loose flights' error."""
    _, _, orbit = spool
    X, problem = np.asarray(orbit._unknowns), orbit._problem
    base = CircuitFlightSettings(rtol=1e-7, atol=1e-9)
    r0, J0 = problem.residual(X, settings=base, steer=True)
    r1, J1 = problem.residual(X, settings=dataclasses.replace(base, phi_atol=1e-9), steer=True)
    assert np.array_equal(r0, r1) and np.array_equal(J0, J1)
    r2, J2 = problem.residual(X, settings=dataclasses.replace(base, phi_atol=C.STEER_PHI_ATOL), steer=True)
    assert np.max(np.abs(J2 - J0)) < 1e-5 * np.max(np.abs(J0))
    assert np.max(np.abs(r2 - r0) / np.maximum(1.0, np.abs(X))) < 1e-5


def test_the_steering_period_takes_the_states_steps(spool, monkeypatch):
    """The steering period's CVODE steps (the variational flights at the loose tolerance): 2,625 with
    the matrix in the error test, 1,705 without; the orbit the same to its accuracy (1.4e-10 of an
    orbit at ``rtol = 1e-12``: ``test_circuit_carry.py``)."""
    model, drive, orbit = spool
    steps = []
    plain = FL._integrate_compiled

    def counted(cv, band, blocks, adams, n_energy, code, par, settings, directions, y0, *rest):
        out = plain(cv, band, blocks, adams, n_energy, code, par, settings, directions, y0, *rest)
        if y0.size > rest[-1] and settings.rtol == C.SETTLE_RTOL:  # (variational: the steering flights)
            steps.append(_cvode.last_workspace().statistics()["steps"])
        return out

    monkeypatch.setattr(FL, "_integrate_compiled", counted)
    again = find_orbit(model, drive)
    monkeypatch.undo()
    assert len(steps) == 29
    assert sum(steps) < 2000
    assert np.array_equal(again._unknowns, orbit._unknowns)
