"""Laminar leakage (``LaminarLeak``: ``q = G (p_a - p_b)``, theory §11, *Parts of a drill's
circuit*), the piston's clearance from the rear chamber to the front, on the preset drifter.

- ``G = 0``: the preset's orbit to the bit (the loss pooled into the preset's ``orifices``
  integrand, so that the integrated state is the preset's size).
- A leak: the orbit repeats when ``simulate`` restarts it (20 periods), its energy account closes
  over a period with the leak's loss ``int G dp^2 dt`` in it, and the circuit's equations written
  out with numpy (``circuit_parts_reference``), integrated by scipy's ``solve_ivp``, reproduce one
  period: the circuit's state and the leak's loss.
- On the drill string and rock (``examples/circuit_drifter_rock.toml``): an admissible orbit whose
  account closes.
"""

import dataclasses

import numpy as np
import pytest
from circuit_parts_reference import check_orbit, check_rock, with_parts

from impactbar import find_orbit
from impactbar.drives.circuit import LaminarLeak
from impactbar.physical import circuit_preset

G = 0.005  # (the leak takes some 4 % of the pump's flow)


class PooledLeak(LaminarLeak):
    """:class:`LaminarLeak` with its loss in the preset's ``orifices`` integrand."""

    energies = ()


@pytest.fixture(scope="module")
def orbit(preset):
    model, drive, _ = preset
    return with_parts(model, drive, LaminarLeak("rear", "front", G))


def test_no_conductance_gives_the_presets_orbit_to_the_bit(preset):
    model, drive, want = preset
    got = with_parts(model, drive, PooledLeak("rear", "front", 0.0))
    assert got.drive.layout == drive.layout
    assert got.period == want.period and got.impact_velocity == want.impact_velocity
    assert np.array_equal(got.drive_states[0], want.drive_states[0])
    assert np.array_equal(got.multipliers, want.multipliers)


def test_a_leaks_orbit_repeats_its_account_closes_and_numpy_reproduces_it(preset, orbit):
    _, _, want = preset
    assert orbit.period > 1.001 * want.period
    one = check_orbit(orbit)
    account = orbit.drive.energy(one)
    total = sum(p.energies() for p in one.pieces if hasattr(p, "energies"))
    loss = total[orbit.drive.layout.energy["leak"]]
    assert 0.01 * account["orifices"] < loss < account["orifices"]


@pytest.mark.slow  # (a topology's coupled blow compiled afresh: some 40 s of CPU)
def test_a_leak_on_the_rock(rock_drifter):
    model, drive = rock_drifter
    orbit = check_rock(model, drive, LaminarLeak("rear", "front", G))
    assert orbit.period > 1.001 * find_orbit(model, drive).period


def test_a_leak_refuses_bad_input():
    with pytest.raises(ValueError, match="conductance must be"):
        LaminarLeak("rear", "front", -1.0)
    with pytest.raises(ValueError, match="two nodes"):
        LaminarLeak("rear", "rear", 1.0)
    d = circuit_preset("circuit-drifter")
    drive = dataclasses.replace(d.drive(), extra_parts=(LaminarLeak("rear", "nowhere", 1.0),))
    with pytest.raises(ValueError, match="names the node 'nowhere'"):
        drive.layout  # noqa: B018
        drive._network((0, 0, 0, 0))
