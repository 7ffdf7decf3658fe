"""The spool drill's start for the chord (``examples/circuit_drill_spool.toml``, rigid piston): where the
chord's plain flights are the orbit's root's (``_closing.root_settings``), the motion followed from
rest is handed over at ``ROOT_HANDOVER`` and the chord's first step takes the steering flight's
residual (``_closing.first_residual``), so that two periods at the loose tolerance and one plain
period at the root's tolerance are not flown; the orbit stays within its root tolerance of the one
found the way before and as near one at ``rtol = 1e-12``."""

from pathlib import Path

import numpy as np
import pytest

import impactbar.drives.circuit.flight as FL
import impactbar.orbits._closing as C
import impactbar.orbits.shooting as S
from impactbar import find_orbit
from impactbar.drives.circuit.settings import CircuitFlightSettings, circuit_settings
from impactbar.physical import circuit_preset, load

SPOOL = Path(__file__).resolve().parents[2] / "examples" / "circuit_drill_spool.toml"


@pytest.fixture(scope="module")
def spool():
    d = load(SPOOL)
    return d.model(), d.drive()


def _counted(monkeypatch, model, drive):
    """The orbit, the impacts followed to its start and the chord's plain flights at the root's
    tolerance (``drive.root_settings``)."""
    rtol = drive.root_settings(model).rtol
    impacts, fine = [0], [0]
    follow, flight = S.ShootingProblem._follow, FL.circuit_flight

    def followed(self, *args):
        impacts[0] += 1
        return follow(self, *args)

    def flown(*args, **kwargs):
        settings = kwargs.get("settings", args[7] if len(args) > 7 else None)
        variational = kwargs.get("variational", args[8] if len(args) > 8 else False)
        if not variational and circuit_settings(settings).rtol == rtol:
            fine[0] += 1
        return flight(*args, **kwargs)

    monkeypatch.setattr(S.ShootingProblem, "_follow", followed)
    monkeypatch.setattr(FL, "circuit_flight", flown)
    orbit = find_orbit(model, drive)
    monkeypatch.undo()
    return orbit, impacts[0], fine[0]


def test_the_spool_drill_hands_over_two_impacts_sooner_and_flies_one_fine_period(spool, monkeypatch):
    """At most 8 impacts followed (from rest: its supply pressure carried to the relief valve's setting
    at the fifth, where the check valve's flag of the two first impacts no longer stops it, then
    three; from the supply charged to that setting, ``_closing.settle_start``, 4) and one plain
    period at the root's tolerance (29 flights), where the way before (the hand-over at
    ``SETTLE_HANDOVER``, the chord's first residual a flight of its own: measured 10 impacts and 58
    flights on main) flew more. The two orbits within the root's tolerance (1e-9 of the unknowns;
    measured 2.4e-11, and 6.7e-11 in the multipliers; from rest 1.7e-11 and 2.8e-10), each as near an
    orbit at ``rtol = 1e-12`` (measured 1.5e-10 and 1.2e-10; from rest 1.3e-10 and 1.1e-10)."""
    model, drive = spool
    orbit, impacts, fine = _counted(monkeypatch, model, drive)
    assert impacts <= 8
    assert fine == 29
    monkeypatch.setattr(C, "ROOT_HANDOVER", S.SETTLE_HANDOVER)
    monkeypatch.setattr(C, "LOOSE_FIRST", np.inf)
    before = find_orbit(model, drive)
    monkeypatch.undo()
    X, Xb = np.asarray(orbit._unknowns), np.asarray(before._unknowns)
    assert np.max(np.abs(X - Xb) / np.maximum(np.abs(Xb), 1e-2)) < 1e-9
    np.testing.assert_allclose(np.sort_complex(orbit.multipliers), np.sort_complex(before.multipliers),
                               rtol=0, atol=5e-9)
    ref = find_orbit(model, drive, settings=CircuitFlightSettings(rtol=1e-12, atol=1e-14))
    R = np.asarray(ref._unknowns)
    for Y in (X, Xb):
        assert np.max(np.abs(Y - R) / np.maximum(np.abs(R), 1e-2)) < 1.7e-10


def test_the_first_residual_is_the_steering_flights_only_where_the_chord_flies_the_roots(spool):
    """``first_residual``: on the spool drill the steering flight's residual where it is above
    ``LOOSE_FIRST`` of the unknowns (and ``None`` below: the chord's tolerance far under its error);
    on the preset's rigid piston never (its steering flight's state is not its plain flights')."""
    model, drive = spool
    problem = S.ShootingProblem(model, drive)
    X = np.ones(problem.n)
    steer = problem._steer(C.loose_settings(problem.settings))
    r = np.full(problem.n, 10.0 * C.LOOSE_FIRST)
    assert C.first_residual(problem, X, steer, r) is r
    assert C.first_residual(problem, X, steer, 0.1 * r) is None
    d = circuit_preset("circuit-drifter")
    preset = S.ShootingProblem(d.model().with_(n_modes=0), d.drive())
    steer = preset._steer(C.loose_settings(preset.settings))
    assert C.first_residual(preset, X[:preset.n], steer, r[:preset.n]) is None
    assert C.settle_handover(preset, S.SETTLE_HANDOVER) == S.SETTLE_HANDOVER
    assert C.settle_handover(problem, S.SETTLE_HANDOVER) == C.ROOT_HANDOVER


def _followed(monkeypatch, model, drive):
    """The impact velocities of the motion followed to the orbit's start and the tolerances of its
    flights."""
    speeds, tolerances = [], set()
    follow, flight = S.ShootingProblem._follow, FL.circuit_flight

    def followed(self, tau, mode, y, settings):
        tolerances.add((settings.rtol, settings.atol))
        out = follow(self, tau, mode, y, settings)
        speeds.append(out[4])
        return out

    monkeypatch.setattr(S.ShootingProblem, "_follow", followed)
    monkeypatch.setattr(FL, "circuit_flight", flight)
    find_orbit(model, drive)
    monkeypatch.undo()
    return np.array(speeds), tolerances


def test_the_spool_drills_motion_to_its_start_is_followed_at_the_looser_tolerance(spool, monkeypatch):
    """Where the chord's plain flights are the root's, the motion followed to the start takes
    ``ROOT_SETTLE_RTOL`` (``atol`` scaled as much; the preset keeps ``SETTLE_RTOL``): the same 4
    impacts from the supply charged to the relief valve's setting as at ``SETTLE_RTOL`` (8 from rest),
    their impact velocities within 5e-5 of those (relative; measured 0.90e-5 to 1.0e-5, from rest 0.8e-5
    to 3.0e-5), far inside the hand-over's 3e-4, and each step between impacts within 2e-5 of the finer
    motion's (measured 0.9e-6, from rest 1.3e-5)."""
    model, drive = spool
    speeds, tolerances = _followed(monkeypatch, model, drive)
    assert len(tolerances) == 1
    assert tolerances.pop() == pytest.approx((C.ROOT_SETTLE_RTOL, C.ROOT_SETTLE_RTOL * 1e-2), rel=1e-12)
    monkeypatch.setattr(C, "ROOT_SETTLE_RTOL", C.SETTLE_RTOL)
    fine, tolerances = _followed(monkeypatch, model, drive)
    assert len(tolerances) == 1
    assert tolerances.pop() == pytest.approx((C.SETTLE_RTOL, C.SETTLE_RTOL * 1e-2), rel=1e-12)
    assert speeds.size == fine.size == 4
    assert np.max(np.abs(speeds / fine - 1.0)) < 5e-5
    assert np.max(np.abs(np.diff(speeds / fine))) < 2e-5
    d = circuit_preset("circuit-drifter")
    preset = S.ShootingProblem(d.model().with_(n_modes=0), d.drive())
    loose = C.loose_settings(preset.settings)
    assert C.settle_settings(preset, loose) is loose
    assert C.settle_settings(preset, None) is None
