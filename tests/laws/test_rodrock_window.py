"""The rod-rock law's blow lasts ``RodRock.window``: on the lattice whole steps of its cell grid, so
that a periodic orbit's flight starts where the simulator's does (found by the drifter's drill
string, whose shank adapter and rod are not whole cells: the unrounded window put the orbit 3e-6 in
phase off the motion simulate settles on); on the exact scheme (the default) the window itself."""

import dataclasses
import tomllib
from pathlib import Path

import numpy as np
import pytest

import impactbar as ib
from impactbar.laws.rodrock.contact import BlowMap
from impactbar.physical import Drifter

EXAMPLE = Path(__file__).parents[2] / "examples" / "drifter_rock.toml"


@pytest.mark.parametrize("method", ["lattice", "exact"])
def test_window_is_the_simulated_blow_and_the_orbit_is_the_simulated_motion(method):
    with open(EXAMPLE, "rb") as f:
        model = Drifter.from_config(tomllib.load(f)).model().with_(d=0.5)
    model = model.with_(impact=dataclasses.replace(model.law, method=method))
    load = ib.CosineLoad(0.1, 0.5)
    law = model.law
    unrounded = 4.0 / model.s + 2.0 * sum(g.travel_time(model) for g in law.segments)
    if method == "lattice":
        blow = BlowMap(model, load, 0.0)
        assert law.window(model) == pytest.approx(blow.n_max * blow.grid.cell_time, rel=1e-15)
        assert law.window(model) - unrounded > 1e-5  # this drill string is not whole cells
    else:
        assert law.window(model) == unrounded
        tr = ib.simulate(model, load, ib.InitialState.rigid(-0.05, 0.0, 0), 3.0)
        assert tr.impacts[0].duration == unrounded
    (orbit,) = [o for o in ib.periodic_orbits(model, load) if o.stable]
    tr = ib.simulate(model, load, ib.InitialState.rigid(-0.05, 0.0, 0), 80 * 2 * np.pi)
    assert np.mod(tr.impact_times[-1], 2 * np.pi) == pytest.approx(orbit.phase, abs=1e-11)
    assert tr.impact_velocities[-1] == pytest.approx(orbit.impact_velocity, abs=1e-11)
