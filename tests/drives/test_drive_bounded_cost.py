"""Bounded cost of a flexible bar's orbit under the position-switched drive: the
admissibility of a very long flight (a drive force or switch far from the bar's scale) is checked by
an energy bound that skips the spans where the end cannot reach the stop, and samples only the rest.
Before, ``find_orbit`` sampled every flight at ``8 s N T`` points: 1.5e9 for ``stroke = 1e-5``,
``ret = 1e5`` (over 60 s), and without end for ``switch_out = 1e12``."""

import math

import numpy as np
import pytest

from impactbar import BarModel, PositionSwitchedDrive, find_orbit
from impactbar.dynamics.modal import step_constant
from impactbar.orbits import valve_admissibility as segment


@pytest.fixture
def counted(monkeypatch):
    """Count the samples of every sampled flight; one call asking for more than the budget fails
    at once (it is what made the old check hang)."""
    taken = []
    inner = segment.end_max_sampled

    def wrapper(w2, d, p, c, q, v, h, n):
        assert n <= segment._SAMPLE_BUDGET, f"a flight sampled at {n} points"
        taken.append(n)
        return inner(w2, d, p, c, q, v, h, n)

    monkeypatch.setattr(segment, "end_max_sampled", wrapper)
    return taken


@pytest.mark.parametrize("stroke, ret, switch_out, admissible", [
    (1e-5, 1e5, 0.5, False), (1e-6, 1e6, 0.5, False), (1.0, 0.5, 1e12, True)])
def test_extreme_drives_answer_at_bounded_cost(counted, stroke, ret, switch_out, admissible):
    orbit = find_orbit(BarModel(3, 0.1, 0.6, 2), PositionSwitchedDrive(stroke, ret, switch_out))
    assert sum(counted) <= 4 * segment._SAMPLE_BUDGET
    assert orbit.admissible is admissible
    assert orbit.period > 1e7  # a long period indeed: the old check's 8 s N T samples
    if admissible:  # the piston comes back at its terminal speed stroke / d
        assert orbit.impact_velocities[0] == pytest.approx(stroke / 0.1, rel=1e-9)


def _dense_max(w2, d, p, c, z, h, n=200_001):
    M = w2.size
    q, _ = step_constant(w2, d, p, z[:M], z[M:], np.linspace(0.0, h, n)[1:-1])
    return float(np.max(c @ q))


@pytest.mark.parametrize("seed", range(12))
def test_energy_bound_is_an_upper_bound(seed):
    """The bound of a span is above the end's largest displacement on a dense grid (independent:
    the modal flow of ``step_constant``), for random states, forces and damping."""
    rng = np.random.default_rng(seed)
    model = BarModel(float(rng.uniform(1, 6)), float(rng.choice([0.0, 0.05, 0.5])), 0.5, 3)
    w2, c = segment._w2(model), model.end_weights
    z = rng.normal(size=2 * w2.size) * np.r_[1.0, 0.1 * np.ones(w2.size - 1), 1.0,
                                              np.ones(w2.size - 1)]
    p, h = float(rng.normal()), float(rng.uniform(0.1, 20.0))
    assert segment._end_bound(w2, model.d, p, c, z, h) >= _dense_max(w2, model.d, p, c, z, h)


@pytest.mark.parametrize("d", [0.0, 0.1])
def test_bounded_sampling_finds_what_the_grid_finds(d):
    """A flight that ends far away but touches the stop in its middle: the bounded check skips the
    spans far off and finds the touch (the same largest value as the whole grid, to its spacing)."""
    model = BarModel(3.0, d, 0.5, 2)
    w2, c = segment._w2(model), model.end_weights
    M = w2.size
    z = np.zeros(2 * M)
    z[0], z[M], z[M + 1] = -50.0, 10.0, 2.0  # rising to the stop, a flexible mode ringing
    p = -1.0 if d == 0.0 else -0.2
    h = 40.0
    grid = segment._end_max_grid(w2, d, p, c, z, h, int(8 * 3 * 2 * h) * 50)
    assert grid > 0.0
    bounded = segment._end_max_bounded(w2, d, p, c, z, h, 8 * 3 * 2 * 50)
    assert bounded == pytest.approx(grid, abs=1e-3)
    # and a flight that stays off the stop is proven off without one sample
    z[0] = -1e6
    assert segment._end_max_bounded(w2, d, p, c, z, h, 48) == -math.inf


@pytest.mark.parametrize("name", ["stroke", "ret", "switch_out"])
def test_levels_beyond_1e100_are_refused(name):
    """ret = 1e308 overflowed inside a run and was refused as "release search did not converge at
    t = nan"; now the drive refuses it by name, and 1e100 is answered."""
    kw = {"stroke": 1.0, "ret": 0.5, "switch_out": 1.0}
    with pytest.raises(ValueError, match=rf"{name} must be in \(0, 1e\+100\]; got 1e\+308"):
        PositionSwitchedDrive(**{**kw, name: 1e308})
    assert getattr(PositionSwitchedDrive(**{**kw, name: 1e100}), name) == 1e100
