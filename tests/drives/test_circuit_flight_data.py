"""What every flight of the oil circuit in one mode shares, made once (``_flight_cache.flight_data``),
and the chambers' least volumes from the extremes of the displacement (``Chambers.least_volumes``):
the Python around each of the spool drill's flights (``examples/circuit_drill_spool.toml``, 415 an
orbit) without its repeated work, the same numbers to the bit.

Checked against independent numbers: the kept parameters against the drive's ``_par`` with the
network after it made afresh, the least volumes against the least of the volumes' arrays, and the
orbit of a drive whose caches are cleared after every flight.
"""

from pathlib import Path

import numpy as np
import pytest

from impactbar import find_orbit
from impactbar.drives.circuit import drive as D
from impactbar.drives.circuit import flight as F
from impactbar.drives.circuit.parts import Chambers
from impactbar.physical import load

SPOOL = Path(__file__).resolve().parents[2] / "examples" / "circuit_drill_spool.toml"


@pytest.fixture(scope="module")
def spool():
    d = load(SPOOL)
    return d.model(), d.drive()


def test_a_warm_orbit_makes_no_flights_parameters_again(spool, monkeypatch):
    """Once an orbit has flown, a second one makes no parameter vector (``_par``): each flight reads
    the one kept for its bar, mode and kind (on the way before, every one of its 415 flights made its
    own); and the kept ones are the drive's ``_par`` with the network after it, to the bit."""
    model, drive = spool
    find_orbit(model, drive)
    made = []
    real = D.HydraulicCircuitDrive._par
    monkeypatch.setattr(D.HydraulicCircuitDrive, "_par", lambda self, *a: made.append(a) or real(self, *a))
    find_orbit(model, drive)
    assert made == []
    monkeypatch.undo()
    assert len(drive._flights) >= 4  # (an orbit's modes, plain and variational)
    for (m, mode, variational), data in drive._flights.items():
        fresh = np.concatenate((drive._par(m, mode, variational), drive._network(mode)))
        assert data.par.dtype == fresh.dtype and np.array_equal(data.par, fresh)
        assert data.directions.tolist() == list(drive._directions(mode))
        assert data.code is drive._compiled_network(mode)[1]


def test_the_orbit_is_the_same_to_the_bit_with_every_cache_made_afresh(spool, monkeypatch):
    """The spool drill's orbit with the drive's kept data (flights' parameters, events by mode) cleared
    before every flight, against the orbit with them kept: the same period, state and multipliers."""
    model, drive = spool
    kept = find_orbit(model, drive)
    import impactbar.drives.circuit.flight as FL

    real = FL.circuit_flight

    def afresh(drv, *a, **k):
        drv._flights.clear()
        drv._per_mode.clear()
        return real(drv, *a, **k)

    monkeypatch.setattr(FL, "circuit_flight", afresh)
    fresh = find_orbit(model, drive)
    assert (fresh.period, fresh.impact_velocity) == (kept.period, kept.impact_velocity)
    assert np.array_equal(fresh.drive_states[0], kept.drive_states[0])
    assert np.array_equal(fresh.multipliers, kept.multipliers)


def test_the_events_of_a_mode_are_made_once_and_are_those_made_afresh(spool):
    model, drive = spool
    mode = drive.start(model, np.zeros(1), np.zeros(1)).mode
    first = drive.events(mode)
    assert drive.events(list(mode)) is first
    assert [(e.name, e.direction) for e in first] == [(e.name, e.direction) for e in drive._events(mode)]


@pytest.mark.parametrize("seed", range(5))
def test_the_least_volumes_are_the_least_of_the_volumes_to_the_bit(seed):
    """The least of ``V_r = V_r0 - w`` and ``V_f = V_f0 + alpha w`` over the steps, taken at the
    greatest and the least ``w`` (rounding is monotone), equal the least entries of those arrays
    exactly, over displacements of every sign and size."""
    rng = np.random.default_rng(seed)
    ch = Chambers(float(rng.uniform(0.05, 0.95)), float(rng.uniform(0.1, 2.0)), float(rng.uniform(0.1, 2.0)))
    w = rng.normal(0.0, 10.0 ** rng.uniform(-12, 1), size=int(rng.integers(1, 400)))
    rear, front = ch.least_volumes(w)
    assert rear == np.min(ch.rear_volume - w)
    assert front == np.min(ch.front_volume + ch.area_ratio * w)
    assert ch.least_volumes(w[:1]) == (ch.rear_volume - w[0], ch.front_volume + ch.area_ratio * w[0])


@pytest.mark.parametrize("seed", range(6))
def test_a_rigid_pistons_volume_check_decides_as_the_volumes_arrays(seed):
    """A rigid piston's flight checks its chambers from its coordinate's extremes
    (``flight._displacements``, two displacements, not the array of all): the least volumes the same
    to the bit as over the whole array ``w = -(weight x)``, so the same verdict, a chamber emptied
    exactly (volume 0) among them; a weight it cannot tell (``<= 0``) and a flexible piston take the
    whole array."""
    rng = np.random.default_rng(seed)
    ch = Chambers(float(rng.uniform(0.05, 0.95)), float(rng.uniform(0.1, 2.0)), float(rng.uniform(0.1, 2.0)))
    weight = float(rng.choice([1.0, rng.uniform(0.1, 3.0)]))
    x = rng.normal(0.0, 10.0 ** rng.uniform(-3, 0.5), size=int(rng.integers(1, 300)))
    lowest = -ch.rear_volume / weight  # (on the rear chamber's emptying, exactly where weight is 1)
    highest = ch.front_volume / (ch.area_ratio * weight)
    verdicts = []
    for xs in (x, np.append(x, lowest), np.append(x, highest), np.append(x, 2 * lowest),
               np.append(x, 2 * highest)):
        w = -(xs[:, None] @ np.array([weight]))
        empties = np.min(ch.rear_volume - w) <= 0.0 or np.min(ch.front_volume + ch.area_ratio * w) <= 0.0
        two = F._displacements(xs[:, None], np.array([weight]))
        assert two.size == 2 and ch.least_volumes(two) == ch.least_volumes(w)
        assert (min(ch.least_volumes(two)) > 0.0) is (not empties)
        verdicts.append(empties)
    assert verdicts[3] and verdicts[4]  # (twice beyond: both chambers' emptying seen)
    for weights in (np.array([-weight]), np.zeros(1)):
        assert np.array_equal(F._displacements(x[:, None], weights), -(x[:, None] @ weights))
    flexible = np.column_stack((x, x[::-1]))
    assert np.array_equal(F._displacements(flexible, np.array([weight, 0.5])),
                          -(flexible @ np.array([weight, 0.5])))
