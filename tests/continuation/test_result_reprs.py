"""Short reprs of the big results and a notebook view of a branch."""

import math

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, InitialState, continue_orbit, periodic_orbits, simulate
from impactbar.continuation import continue_bifurcation


@pytest.fixture(scope="module")
def branch():
    model = BarModel(s=10.0, d=0.05, R=0.5, n_modes=0)
    start = next(o for o in periodic_orbits(model, CosineLoad(0.3, 1.0)) if math.cos(o.phase) < 0)
    return continue_orbit(start, "p0", to=1.2, max_step=0.01)  # many points, turns at the fold


def test_branch_repr_is_one_short_line(branch):
    assert len(branch) > 50
    text = repr(branch)
    assert "\n" not in text and len(text) < 200
    assert f"{len(branch)} points" in text and f"{branch.values[0]:.6g} -> " in text
    kinds = [str(e.kind) for e in branch.events]
    assert "fold" in kinds and all(k in text for k in kinds)
    assert repr(branch.status) in text
    html = branch._repr_html_()
    assert html.count("<tr>") == len(branch.events) + 1  # the header and one row per event
    assert "&gt;" in html and "<table>" in html


def test_curve_and_trajectory_reprs_do_not_grow_with_the_data(branch):
    fold = next(e for e in branch.events if e.kind == "fold")
    curve = continue_bifurcation(fold, "R", to=0.7, max_step=0.005)
    assert len(curve) > 30 and len(repr(curve)) < 200 and f"{len(curve)} points" in repr(curve)
    model = BarModel(s=10.0, d=0.05, R=0.5, n_modes=2)
    tr = simulate(model, CosineLoad(0.3, 1.0), InitialState.rigid(-0.01, 0.0, n_modes=2),
                  2 * np.pi * 200)
    assert tr.n_impacts > 100
    text = repr(tr)
    assert len(text) < 250 and f"{tr.n_impacts} impacts" in text and "\n" not in text
