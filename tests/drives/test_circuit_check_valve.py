"""A check valve (``CheckValve``: ``q = K_cv o(dp) phi(dp)``, its opening ``o = clip((dp -
p_crack) / dp_open, 0, 1)``, theory §11, *Parts of a drill's circuit*) on the preset drifter, from
the front chamber to the supply: it passes the oil that the stroke pushes out of the front chamber
back to the supply beside the front's orifice.

- ``K_cv = 0``: the preset's orbit (the valve's kinks still split the flights: to the integrator's
  tolerance, not to the bit).
- A valve that cracks and opens fully during the stroke: the orbit crosses both kinks, it repeats when
  ``simulate`` restarts it (20 periods), its energy account closes over a period, and the circuit's
  equations written out with numpy (the opening clipped: no mode), integrated by scipy's
  ``solve_ivp``, reproduce one period: the circuit's state and the valve's loss.
- On the drill string and rock (``examples/circuit_drifter_rock.toml``): an admissible orbit whose
  account closes.
"""

import dataclasses

import numpy as np
import pytest
from circuit_parts_reference import check_orbit, check_rock, with_parts

from impactbar.drives.circuit import CheckValve

VALVE = CheckValve("front", "supply", coefficient=1.0, cracking_pressure=0.005, opening_span=0.005)


@pytest.fixture(scope="module")
def orbit(preset):
    model, drive, _ = preset
    return with_parts(model, drive, VALVE)


def test_a_shut_check_valve_gives_the_presets_orbit(preset):
    model, drive, want = preset
    shut = dataclasses.replace(VALVE, coefficient=0.0)
    got = with_parts(model, drive, shut)
    assert got.period == pytest.approx(want.period, rel=1e-9)
    assert got.impact_velocity == pytest.approx(want.impact_velocity, rel=1e-9)
    assert np.allclose(got.drive_states[0], want.drive_states[0], rtol=1e-9, atol=0.0)


def test_a_check_valves_orbit_repeats_its_account_closes_and_numpy_reproduces_it(preset, orbit):
    _, _, want = preset
    assert orbit.impact_velocity != pytest.approx(want.impact_velocity, rel=1e-4)
    one = check_orbit(orbit)
    h = orbit.drive.histories(one, np.linspace(0.0, orbit.period, 4001))
    dp = h["p_f"] - h["p_s"]
    assert dp.max() > VALVE.cracking_pressure + VALVE.opening_span  # (both kinks crossed)
    total = sum(p.energies() for p in one.pieces if hasattr(p, "energies"))
    assert total[orbit.drive.layout.energy["check"]] > 0.0


@pytest.mark.slow  # (a topology's coupled blow compiled afresh: some 40 s of CPU)
def test_a_check_valve_on_the_rock(rock_drifter):
    check_rock(*rock_drifter, VALVE)


def test_a_check_valve_refuses_bad_input():
    with pytest.raises(ValueError, match="opening_span must be"):
        CheckValve("front", "supply", coefficient=1.0, cracking_pressure=0.0, opening_span=0.0)
    with pytest.raises(ValueError, match="cracking_pressure must be"):
        CheckValve("front", "supply", coefficient=1.0, cracking_pressure=-0.1, opening_span=0.1)
    with pytest.raises(ValueError, match="two nodes"):
        CheckValve("front", "front", coefficient=1.0, cracking_pressure=0.0, opening_span=0.1)
