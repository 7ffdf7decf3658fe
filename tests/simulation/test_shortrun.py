"""The short-run path of ``simulate`` (issue 20) gives the general driver's result to the bit."""

import importlib

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, InitialState, SquareWaveLoad, simulate

S = importlib.import_module("impactbar.simulation.simulate")

CASES = [  # model, load, start, t_end, max_impacts
    (BarModel(1.37, 0.02, 0.8, 0), CosineLoad(1.2, 1.0), InitialState.rigid(-0.1, 0.0), 1e6, 1),
    (BarModel(1.37, 0.02, 0.8, 0), CosineLoad(1.2, 1.0), InitialState.rigid(-0.1, 0.0), 1e6, 37),
    (BarModel(1.37, 0.02, 0.8, 0), CosineLoad(1.2, 1.0), InitialState.rigid(-0.1, 0.0), 9.0, 200),
    (BarModel(1.37, 0.02, 0.8, 8), CosineLoad(1.2, 1.0), InitialState.rigid(-0.1, 0.2, 8), 1e6, 1),
    (BarModel(1.37, 0.02, 0.8, 8), CosineLoad(1.2, 1.0), InitialState.rigid(-0.1, 0.2, 8), 1e6, 20),
    (BarModel(1.37, 0.02, 0.8, 8), CosineLoad(1.2, 1.0), InitialState.rigid(-0.1, 0.2, 8), 0.5, 5),
    (BarModel(5.0, 0.1, 0.5, 3), SquareWaveLoad(1.0, 1.2), InitialState.rigid(-0.2, 0.0, 3), 1e4, 12),
    # chatter and sustained contact: the general driver takes over
    (BarModel(1.0, 0.02, 0.5, 0), CosineLoad(0.8, 1.0), InitialState.rigid(-0.3, 0.0), 60.0, 100),
    (BarModel(3.3, 0.05, 0.5, 8), CosineLoad(0.8, 1.0), InitialState.rigid(-0.3, 0.0, 8), 30.0, 50),
]


def _same(a, b):
    assert type(a) is type(b) and vars(a).keys() == vars(b).keys()  # every field set
    assert a.t0 == b.t0 and a.t_end == b.t_end and a.status == b.status
    assert a.n_release_retries == b.n_release_retries
    for name in ("impact_times", "impact_velocities", "contact_intervals"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.shape == y.shape and x.dtype == y.dtype and np.array_equal(x, y), name
    assert np.array_equal(a.final_state.modal_displacement, b.final_state.modal_displacement)
    assert np.array_equal(a.final_state.modal_velocity, b.final_state.modal_velocity)
    sa, sb = a._segments, b._segments
    assert len(sa) == len(sb)
    for name in ("t", "basis", "entry", "q", "v"):
        x, y = getattr(sa, name), getattr(sb, name)
        assert x.shape == y.shape and x.dtype == y.dtype and np.array_equal(x, y), name
    assert sa.frozen.keys() == sb.frozen.keys()
    ts = np.linspace(a.t0, a.t_end, 7)
    assert np.array_equal(a.end_displacement(ts), b.end_displacement(ts))
    ea, eb = a.energy, b.energy
    assert ea == eb


@pytest.mark.parametrize("case", range(len(CASES)))
def test_short_run_is_the_general_drivers_result(case, monkeypatch):
    model, load, start, span, k = CASES[case]
    t0 = 0.3
    short = simulate(model, load, start, t0 + span, t0=t0, max_impacts=k)
    monkeypatch.setattr(S, "SHORT_RUN_IMPACTS", 0)  # the general driver only
    general = simulate(model, load, start, t0 + span, t0=t0, max_impacts=k)
    assert short.n_impacts >= (0 if span < 1.0 else 1)
    _same(short, general)


def test_short_run_path_is_taken_and_left(monkeypatch):
    """The path answers a run without contact and declines one with chatter (a check that the
    comparison above covers both)."""
    calls = []
    real = S.run_short

    def spy(*a):
        out = real(*a)
        calls.append(out is not None)
        return out

    monkeypatch.setattr(S, "run_short", spy)
    for j in (0, 7):
        model, load, start, span, k = CASES[j]
        simulate(model, load, start, span, max_impacts=k)
    assert calls == [True, False]


def test_the_last_core_is_found_by_identity_and_forgotten_with_the_cache():
    model, load = BarModel(1.37, 0.02, 0.8, 0), CosineLoad(1.2, 1.0)
    core = S._core_for(model, load)
    assert S._core_for(model, load) is core
    assert S._core_for(BarModel(1.37, 0.02, 0.8, 0), CosineLoad(1.2, 1.0)) is core  # equal values
    assert S._core_for(model, CosineLoad(1.2, 3.0)) is not core
    assert S._core_for(model, load) is core
    for k in range(2 * S._CORES_MAX):  # the cache keeps its size
        S._core_for(model, CosineLoad(1.2, 1.0 + k))
    assert len(S._CORES) == S._CORES_MAX + 1 and S._LAST in S._CORES  # the pairs and the last call
    core = S._core_for(model, load)
    S._CORES.clear()
    assert S._core_for(model, load) is not core  # the last call's entry went with the cache
