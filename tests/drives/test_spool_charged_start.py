"""The spool drill's start nearer its orbit (``examples/circuit_drill_spool.toml``, rigid piston): where
the chord's plain flights are the orbit's root's (``_closing.root_settings``), the motion to Newton's
start is followed from rest with the supply charged to the relief valve's setting
(``HydraulicCircuitDrive.charged_start``, ``_closing.settle_start``) rather than at the pre-charge, and
the chord's second step, the first from the root's flights after a first step from the steering
flight's residual, ends it where the contraction's bound (``_closing.loose_contraction``) times its
size is below the tolerance. The orbit is the one from rest, within the root's tolerance."""

import dataclasses

import numpy as np
import pytest
from test_spool_settle_handover import SPOOL, _counted  # this folder's: the orbit and its flights counted

import impactbar.orbits._closing as C
import impactbar.orbits.shooting as S
from impactbar.drives.orbitproblem import chord
from impactbar.physical import circuit_preset, load


@pytest.fixture(scope="module")
def spool():
    d = load(SPOOL)
    return d.model(), d.drive()


def _rest_start(problem, q, v):
    return problem.drive.start(problem.model, q, v)


def _same(a, b) -> bool:
    return a.mode == b.mode and np.array_equal(a.z, b.z)


def _distance(X, R):
    X, R = np.asarray(X), np.asarray(R)
    return float(np.max(np.abs(X - R) / np.maximum(np.abs(R), 1e-2)))


def test_the_charged_start_is_the_rest_start_with_the_supply_at_the_relief_setting(spool):
    """The supply and the front chamber (fed from it) at the relief valve's setting, every other state
    and the spool's target as from rest; the accumulator's flag set (above its pre-charge), the relief
    valve's not (it opens above its setting). None where the user gave the start's pressures."""
    model, drive = spool
    q, v = np.zeros(1), np.zeros(1)
    rest, charged = drive.start(model, q, v), drive.charged_start(model, q, v)
    L, relief = drive.layout, drive.supply.relief_pressure
    assert charged.z[L["supply"]] == charged.z[L["front"]] == relief
    assert rest.z[L["supply"]] == rest.z[L["front"]] == drive.accumulator.precharge
    others = [i for i in range(L.n_states) if i not in (L["supply"], L["front"])]
    assert np.array_equal(charged.z[others], rest.z[others])
    assert charged.mode == rest.mode  # (the accumulator's flag set at its pre-charge already)
    given = dataclasses.replace(drive, start_pressures=tuple(float(x) for x in rest.z[:-1]))
    assert given.charged_start(model, q, v) is None
    problem = S.ShootingProblem(model, drive)
    assert _same(C.settle_start(problem, q, v), charged)
    d = circuit_preset("circuit-drifter")  # (its chord's flights are not the root's: the rest start)
    preset = S.ShootingProblem(d.model().with_(n_modes=0), d.drive())
    assert _same(C.settle_start(preset, q, v), d.drive().start(preset.model, q, v))


def test_the_spool_drill_from_the_charged_start_follows_five_impacts_and_one_fine_period(spool,
                                                                                         monkeypatch):
    """From the charged start: 4 impacts followed (the fewest the hand-over allows there,
    ``_closing.least_impacts``; from rest 8, four of them charging the supply before its drift is
    carried to the relief's setting) and one plain period at the root's tolerance (29 flights; without
    the contraction's bound two: the chord's second step, 2.3e-7, measures the steering residual's
    error, and the prediction from the first, 1.6e-5, read a contraction of 0.014 where the bound
    allows 2.6e-3; handed over at the fifth impact, 1.5e-6 and 0.15 against a third step of 1.1e-5).
    The orbit within 1e-9 of the one from rest (measured 2.9e-11 of the unknowns, 2.2e-11 in the
    multipliers)."""
    model, drive = spool
    orbit, impacts, fine = _counted(monkeypatch, model, drive)
    assert impacts == 4
    assert fine == 29
    monkeypatch.setattr(C, "loose_contraction", lambda problem: None)
    _, impacts, fine = _counted(monkeypatch, model, drive)
    assert (impacts, fine) == (4, 58)
    monkeypatch.setattr(C, "settle_start", _rest_start)
    rest, impacts, fine = _counted(monkeypatch, model, drive)
    assert (impacts, fine) == (8, 29)
    assert _distance(orbit._unknowns, rest._unknowns) < 1e-9
    np.testing.assert_allclose(np.sort_complex(orbit.multipliers), np.sort_complex(rest.multipliers),
                               rtol=0, atol=5e-9)


def test_a_supply_below_the_relief_setting_discharges_to_the_same_orbit(spool, monkeypatch):
    """At 50 L/min of pump flow the orbit's supply pressure (24.3 MPa) lies below the relief valve's
    setting (25 MPa): the motion from the charged start discharges toward it (the supply's multiplier
    0.56) and reaches the orbit from rest within 1e-9 (measured 7.7e-11 of the unknowns, handed over
    at the fifth impact), following 5 impacts where from rest 56 were followed."""
    model, drive = spool
    slow = dataclasses.replace(drive, supply=dataclasses.replace(drive.supply,
                                                                 pump_flow=drive.supply.pump_flow * 5 / 7))
    orbit, impacts, _ = _counted(monkeypatch, model, slow)
    L = slow.layout
    assert orbit.drive_states[0][L["supply"]] < 0.98 * slow.supply.relief_pressure
    monkeypatch.setattr(C, "settle_start", _rest_start)
    rest, from_rest, _ = _counted(monkeypatch, model, slow)
    assert impacts <= 6 < 5 * impacts <= from_rest
    assert _distance(orbit._unknowns, rest._unknowns) < 1e-9


def test_the_chords_second_step_after_a_looser_first_residual_ends_it_by_the_bound():
    """``chord``'s ``first_bound`` on a linear system whose first residual is off by 2e-7 of the
    unknowns (a looser flight's) and whose Jacobian is off by 1e-5: the second step measures that
    error, and with the bound (``1e-3 + 100 s1``, the closing module's) times it below the tolerance
    the iteration ends there, within the tolerance of the root; without it the prediction from the
    first step asks one residual more."""
    A = np.array([[3.0, 1.0], [0.5, 2.0]])
    root = np.array([1.0, 2.0])
    J = A * (1.0 + 1e-5)
    X0 = root * (1.0 + 1.5e-6)
    calls = []

    def value(X):
        calls.append(X.copy())
        return A @ (X - root)

    def jac(X):
        raise AssertionError("the first Jacobian steers every step")

    first = A @ (X0 - root) + A @ (2e-7 * root)
    X = chord(value, jac, X0.copy(), np.zeros(0, dtype=np.int64), 1e-9, 10, first=J, first_value=first,
              first_here=True, first_bound=lambda s1: 1e-3 + 100.0 * s1)
    assert len(calls) == 1
    assert np.max(np.abs(X - root) / np.abs(root)) < 1e-9
    calls.clear()
    X = chord(value, jac, X0.copy(), np.zeros(0, dtype=np.int64), 1e-9, 10, first=J, first_value=first,
              first_here=True)
    assert len(calls) == 2
    assert np.max(np.abs(X - root) / np.abs(root)) < 1e-12
