"""A cushion (``Cushion``: the valve's return port drains through a node of oil and a port that
the piston's gap opens, ``q = K_max g(y) phi(p_cu - p_t)``, theory §11, *Parts of a drill's
circuit*) on the preset drifter.

- ``g = 1``, ``K_max`` large and the node small: the orbit tends to the preset's, at first order in
  ``1/K_max``.
- A cushion that shuts the port over the top of the return stroke: the orbit crosses its kinks, it
  repeats when ``simulate`` restarts it (20 periods), its energy account closes over a period, and the
  circuit's equations written out with numpy (``g`` by ``np.interp``: no mode), integrated by scipy's
  ``solve_ivp``, reproduce one period: the circuit's state and the port's loss.
- On the drill string and rock (``examples/circuit_drifter_rock.toml``): an admissible orbit whose
  account closes.
"""


import numpy as np
import pytest
from circuit_parts_reference import check_orbit, check_rock, with_parts

from impactbar.drives.circuit import Cushion
from impactbar.drives.circuit.layout import PRESET

CUSHION = Cushion(volume=0.05, coefficient=2.0, gaps=(0.06, 0.08, 0.1), openings=(1.0, 0.4, 0.1))


@pytest.fixture(scope="module")
def orbit(preset):
    model, drive, _ = preset
    return with_parts(model, drive, CUSHION)


def test_a_wide_open_cushion_tends_to_the_preset(preset):
    model, drive, want = preset
    err = []
    for K in (1e2, 1e3):
        c = Cushion(volume=1e-3, coefficient=K, gaps=(0.05,), openings=(1.0,))
        o = with_parts(model, drive, c)
        z, z0 = o.drive_states[0], want.drive_states[0]
        L = o.drive.layout
        err.append(max(abs(o.period / want.period - 1), abs(o.impact_velocity / want.impact_velocity - 1),
                       *(abs(z[L[k]] / z0[PRESET[k]] - 1) for k in ("front", "rear", "supply"))))
    assert err[1] < 3e-5
    assert 5 < err[0] / err[1] < 20  # (first order in 1/K)


def test_a_cushions_orbit_repeats_its_account_closes_and_numpy_reproduces_it(preset, orbit):
    _, _, want = preset
    assert orbit.period != pytest.approx(want.period, rel=1e-3)
    one = check_orbit(orbit)
    gap = orbit.drive.histories(one, np.linspace(0.0, orbit.period, 2001))["y"]
    assert gap.max() > CUSHION.gaps[-1]  # (every kink crossed: the port shut to its last opening)


@pytest.mark.slow  # (a topology's coupled blow compiled afresh: some 40 s of CPU)
def test_a_cushion_on_the_rock(rock_drifter):
    check_rock(*rock_drifter, CUSHION)


def test_a_cushion_refuses_bad_input():
    with pytest.raises(ValueError, match="gaps must be one or more increasing"):
        Cushion(volume=0.05, coefficient=1.0, gaps=(0.1, 0.05), openings=(1.0, 0.0))
    with pytest.raises(ValueError, match="openings must be"):
        Cushion(volume=0.05, coefficient=1.0, gaps=(0.1,), openings=(1.5,))
    with pytest.raises(ValueError, match="volume must be"):
        Cushion(volume=0.0, coefficient=1.0, gaps=(0.1,), openings=(1.0,))
