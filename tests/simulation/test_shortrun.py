"""The short-run path of ``simulate`` gives the general driver's result to the bit:
runs it ends (at ``max_impacts`` or ``t_end``) and runs whose first block it hands over (chatter,
sustained contact, more impacts than the block holds)."""

import dataclasses
import importlib
import inspect
import math

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, InitialState, SquareWaveLoad, Trajectory, simulate
from impactbar.dynamics.implementations import use_reference

S = importlib.import_module("impactbar.simulation.simulate")
C = importlib.import_module("impactbar.simulation._core")

_RIGID, _BAR8 = BarModel(1.37, 0.02, 0.8, 0), BarModel(1.37, 0.02, 0.8, 8)
_PNEU = CosineLoad(1.2, 1.0)
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
    # runs to t_end, any number of impacts: none, one, a few, more than the first block
    (_RIGID, _PNEU, InitialState.rigid(-0.1, 0.0), 0.7, None),
    (_RIGID, _PNEU, InitialState.rigid(-0.1, 0.0), 2 * math.pi, None),
    (_RIGID, _PNEU, InitialState.rigid(-0.1, 0.0), 300.0, None),
    (_RIGID, _PNEU, InitialState.rigid(-0.1, 0.0), 2 * math.pi * 3000, None),
    (_RIGID, _PNEU, InitialState.rigid(-0.1, 0.0), 2 * math.pi * 3000, 1500),
    (_BAR8, _PNEU, InitialState.rigid(-0.1, 0.2, 8), 2 * math.pi, None),
    (_BAR8, _PNEU, InitialState.rigid(-0.1, 0.2, 8), 2 * math.pi * 1100, None),
    (BarModel(5.0, 0.1, 0.5, 3), SquareWaveLoad(1.0, 1.2), InitialState.rigid(-0.2, 0.0, 3), 40.0, None),
    (BarModel(1.0, 0.02, 0.5, 0), CosineLoad(0.8, 1.0), InitialState.rigid(-0.3, 0.0), 60.0, None),
    (BarModel(100, 0.0, 0.5, 0), SquareWaveLoad(1.0, 1.5), InitialState.rigid(-1.0, 0.3), 120.0, None),
    (BarModel(3.3, 0.05, 0.5, 8), CosineLoad(0.8, 1.0), InitialState.rigid(-0.3, 0.0, 8), 30.0, None),
]


def _same(a, b):
    assert type(a) is type(b)
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
    # every field set (read above), besides a short run's record of its kernel output
    assert vars(a).keys() - {"_rows"} == vars(b).keys() - {"_rows"}


@pytest.mark.parametrize("case", range(len(CASES)))
def test_short_run_is_the_general_drivers_result(case, monkeypatch):
    model, load, start, span, k = CASES[case]
    t0 = 0.3
    short = simulate(model, load, start, t0 + span, t0=t0, max_impacts=k)
    with use_reference("simulate.short_run"):  # the general driver only
        general = simulate(model, load, start, t0 + span, t0=t0, max_impacts=k)
    assert short.n_impacts >= (0 if span < 1.0 else 1)
    _same(short, general)


def test_a_run_at_t_end_ends_in_the_flows_state():
    """A run ended at ``t_end`` in flight: its final state, the kernel's, is the log's flow from the
    last impact evaluated at ``t_end``, to the bit (the short path no longer evaluates it again)."""
    for model, load, start, span, k in CASES:
        run = simulate(model, load, start, 0.3 + span, t0=0.3, max_impacts=k)
        if run.status != "t_end" or run.contact_intervals.size:
            continue
        q, v = run.modal_state([run.t_end])
        assert np.array_equal(q[:, 0], run.final_state.modal_displacement)
        assert np.array_equal(v[:, 0], run.final_state.modal_velocity)


def test_a_short_runs_impacts_state_and_log_are_made_when_first_read():
    """The short path leaves a run's impacts, final state and log to be made each on its first read
    (``Trajectory._deferred``), kept (read again: the same object), to the general driver's bits; a
    name that is no field is still an AttributeError."""
    deferred = {"impact_times", "impact_velocities", "final_state", "_segments"}
    for j in (1, 9):  # ended by max_impacts and by t_end
        model, load, start, span, k = CASES[j]
        short = simulate(model, load, start, 0.3 + span, t0=0.3, max_impacts=k)
        with use_reference("simulate.short_run"):
            general = simulate(model, load, start, 0.3 + span, t0=0.3, max_impacts=k)
        assert "_rows" in vars(short) and not deferred & vars(short).keys()
        state = short.final_state
        assert deferred & vars(short).keys() == {"final_state"}
        assert short.final_state is state and not state.modal_displacement.flags.writeable
        assert short.impact_times is short.impact_times
        _same(short, general)
        with pytest.raises(AttributeError, match="no_such_field"):
            short.no_such_field  # noqa: B018


def test_trajectory_constructor_takes_the_fields_in_their_order():
    """``Trajectory.__init__`` is written out (a frozen dataclass's generated one cost 4 us): its
    parameters must stay the dataclass's fields, in their order, with their defaults."""
    params = list(inspect.signature(Trajectory.__init__).parameters.values())[1:]
    fields = dataclasses.fields(Trajectory)
    assert [p.name for p in params] == [f.name for f in fields]
    for p, f in zip(params, fields, strict=True):
        assert p.default == (inspect.Parameter.empty if f.default is dataclasses.MISSING else f.default)
    run = simulate(*CASES[0][:3], 1e6, max_impacts=3)
    assert vars(dataclasses.replace(run, status="t_end")).keys() == vars(run).keys() - {"_rows"}


def test_short_run_path_is_taken_and_left(monkeypatch):
    """The path answers a run without contact and declines one with chatter (a check that the
    comparison above covers both)."""
    calls = []
    real = S.run_short

    def spy(*a):
        out = real(*a)
        calls.append(out[0] is not None)
        return out

    monkeypatch.setattr(S, "run_short", spy)
    for j in (0, 7):
        model, load, start, span, k = CASES[j]
        simulate(model, load, start, span, max_impacts=k)
    assert calls == [True, False]


def test_the_last_core_is_found_by_identity_and_forgotten_with_the_cache():
    model, load = BarModel(1.37, 0.02, 0.8, 0), CosineLoad(1.2, 1.0)
    core = C._core_for(model, load)
    assert C._core_for(model, load) is core
    assert C._core_for(BarModel(1.37, 0.02, 0.8, 0), CosineLoad(1.2, 1.0)) is core  # equal values
    assert C._core_for(model, CosineLoad(1.2, 3.0)) is not core
    assert C._core_for(model, load) is core
    for k in range(2 * C._CORES_MAX):  # the cache keeps its size
        C._core_for(model, CosineLoad(1.2, 1.0 + k))
    assert len(C._CORES) == C._CORES_MAX + 1 and C._LAST in C._CORES  # the pairs and the last call
    core = C._core_for(model, load)
    C._CORES.clear()
    assert C._core_for(model, load) is not core  # the last call's entry went with the cache
