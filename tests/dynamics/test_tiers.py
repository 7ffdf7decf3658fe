"""Tiered first calls (``impactbar.dynamics._tiers``): with an empty numba cache a first
call runs the kernels' Python source while a child process compiles them, and gives the machine
code's results to the bit; later calls take the machine code; functions not of impactbar's are
numba's as before; a twin that meets an overflow Python refuses hands the call to the machine code
with its arguments as they came."""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, InitialState, SquareWaveLoad, periodic_orbits, simulate
from impactbar.dynamics import _tiers

SRC = str(Path(__file__).resolve().parents[2] / "src")
#: what the expressions of CALLS see
NAMES = {"BarModel": BarModel, "CosineLoad": CosineLoad, "InitialState": InitialState,
         "SquareWaveLoad": SquareWaveLoad, "periodic_orbits": periodic_orbits, "simulate": simulate}

# the first calls, each as (name, expression); the subprocess evaluates them with the tier on and an
# empty cache, this process with the machine code
CALLS = {
    "rigid simulate": "simulate(BarModel(5.0, 0.1, 0.5, 0), CosineLoad(0.6, 1.0), "
                      "InitialState.rigid(-0.2, 0.0), 30.0)",
    "rigid sticking under the square wave": "simulate(BarModel(100, 0, 0.5, 0), SquareWaveLoad(1.0, 1.5), "
                                            "InitialState.rigid(-1.0, 0.3), 120.0)",
    "8-mode simulate": "simulate(BarModel(5.0, 0.1, 0.5, 8), CosineLoad(0.6, 1.0), "
                       "InitialState.rigid(-0.2, 0.0, 8), 30.0)",
    "wave-law simulate": "simulate(BarModel(5.0, 0.1, 0.5, 4, impact='wave'), CosineLoad(0.6, 1.0), "
                         "InitialState.rigid(-0.2, 0.0, 4), 12.0)",
    "8-mode periodic_orbits": "periodic_orbits(BarModel(5.0, 0.1, 0.5, 8), CosineLoad(0.6, 1.0))",
    "square-wave periodic_orbits": "periodic_orbits(BarModel(5.0, 0.1, 0.5, 3), SquareWaveLoad(1.0, 1.2))",
}


def _digest(x):
    """The bits of a result: a trajectory's impacts, contacts and final state; orbits' phases,
    multipliers, clearances and admissibility."""
    if isinstance(x, list):
        return [[o.phase, *np.abs(o.multipliers).tolist(), o.clearance, bool(o.admissible)] for o in x]
    return [x.impact_times.tolist(), x.impact_velocities.tolist(), x.contact_intervals.tolist(),
            x.final_state.modal_displacement.tolist(), x.final_state.modal_velocity.tolist()]


# a subprocess's preamble: the names of the kernels numba compiles there, in ``compiled``
_COUNT = r"""
import json, sys
from numba.core import event
compiled = []
class Count(event.Listener):
    def on_start(self, ev): pass
    def on_end(self, ev): compiled.append(ev.data["dispatcher"].py_func.__name__)
event.register("numba:compile", Count())
"""

_FIRST_CALLS = _COUNT + r"""
import numba
from impactbar.dynamics import _tiers
sys.path.insert(0, sys.argv[1])
from test_tiers import CALLS, NAMES, _digest
out = {name: _digest(eval(expr, dict(NAMES))) for name, expr in CALLS.items()}
kernels = list(compiled)

@numba.njit
def users_own(x):
    return 2.0 * x

users_own(1.5)  # a function not of impactbar's: numba's, compiled here at once
print(json.dumps({"results": out, "compiled": kernels, "users_own": len(users_own.signatures),
                  "tiered": _tiers.enabled(), "requests": len(_tiers._REQUESTED)}))
"""


@pytest.fixture(scope="module")
def first_calls(tmp_path_factory):
    cache = tmp_path_factory.mktemp("numba-cache")
    env = dict(os.environ, IMPACTBAR_TIERED="1", NUMBA_CACHE_DIR=str(cache),
               PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-c", _FIRST_CALLS, str(Path(__file__).parent)], env=env,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2 if hasattr(os, "sched_getaffinity") else False,
                    reason="the tier needs two CPUs")
def test_first_calls_run_interpreted_and_give_the_machine_codes_bits(first_calls):
    assert first_calls["tiered"] and first_calls["requests"] > 0
    assert first_calls["compiled"] == []  # no kernel compiled in the process that called
    for name, expr in CALLS.items():
        assert first_calls["results"][name] == _digest(eval(expr, dict(NAMES))), name


def test_functions_not_of_impactbar_are_numbas(first_calls):
    assert first_calls["users_own"] == 1


def test_the_hook_leaves_a_call_with_machine_code_alone():
    """A kernel numba holds machine code for never reaches the hook (its dispatcher calls the
    machine code): the hook only sees cold calls."""
    run = simulate(BarModel(5.0, 0.1, 0.5, 0), CosineLoad(0.6, 1.0), InitialState.rigid(-0.2, 0.0), 30.0)
    assert run.n_impacts > 0
    from impactbar.dynamics import _event_loop as K

    assert K.run_free_rigid.signatures  # compiled (tier off in the test process)


@numba.njit
def _overflows(a):
    a[0] = 7.0  # (the twin writes this before it fails: the call must start again from a[0] = 0)
    return math.exp(a[1]), a[0]


def test_a_twin_that_overflows_hands_the_call_to_the_machine_code():
    """``math.exp(1000)`` is inf in machine code and OverflowError in Python: the twin's call is
    run again by the machine code, from the arguments as they came."""
    a = np.array([0.0, 1000.0])
    with pytest.raises(OverflowError):
        _tiers.twin(_overflows)(a.copy())
    value, first = _tiers._Twin(_overflows)(a)
    assert value == math.inf and first == 7.0 and a[0] == 7.0
    assert _overflows.signatures  # numba compiled it for the call


def test_twins_call_twins_and_round_hypot_as_numba_does():
    from impactbar.dynamics import _crossing as C
    from impactbar.dynamics import _event_loop as K

    t = _tiers.twin(K.run_free)
    assert t.__globals__["find_crossing"] is _tiers.twin(C.find_crossing)
    assert t.__globals__["math"].hypot(3e-300, 4e-300) == numba.njit(lambda x, y: math.hypot(x, y))(3e-300,
                                                                                                     4e-300)
    rng = np.random.default_rng(5)
    xy = rng.normal(size=(2000, 2)) * 10.0 ** rng.integers(-8, 8, size=(2000, 2))
    hyp = numba.njit(lambda x, y: math.hypot(x, y))
    assert all(t.__globals__["math"].hypot(x, y) == hyp(x, y) for x, y in xy)


def test_fast_math_kernels_are_never_interpreted():
    from impactbar.dynamics import _aberth as A

    fast = [d for d in vars(A).values() if isinstance(d, numba.core.registry.CPUDispatcher)
            and d.targetoptions.get("fastmath")]
    assert fast and not any(_tiers._exact(d) for d in fast)


@numba.njit(cache=False)
def _weighted(a, w):
    s = 0.0
    for i in range(a.size):
        s += math.sin(a[i]) * w
    return s


def test_interpreted_first_runs_the_twin_until_its_budget_is_spent(monkeypatch):
    """A kernel without machine code runs interpreted (the machine code's bits, nothing compiled)
    until its twin's calls have cost the budget; then, or once compiled, or with every kernel
    compiled at once (``impactbar warmup``), the dispatcher itself runs."""
    monkeypatch.setattr(_tiers, "_FIRST", {})
    a = np.random.default_rng(3).normal(size=500) * 1e3
    first = _tiers.interpreted_first(_weighted, budget=60.0)
    assert isinstance(first, _tiers._Twin)
    value = first(a, 0.3)
    assert not _weighted.signatures  # nothing compiled
    assert 0.0 < _tiers._FIRST[_weighted] < 60.0
    monkeypatch.setattr(_tiers._PROCESS, "eager", True)
    assert _tiers.interpreted_first(_weighted, budget=60.0) is _weighted
    monkeypatch.setattr(_tiers._PROCESS, "eager", False)
    assert _tiers.interpreted_first(_weighted, budget=_tiers._FIRST[_weighted]) is _weighted
    assert _tiers.interpreted_first(_weighted, budget=0.0) is _weighted
    assert _weighted(a, 0.3) == value  # the machine code's bits
    assert _tiers.interpreted_first(_weighted, budget=60.0) is _weighted  # compiled now
    with pytest.raises(ValueError, match="budget"):
        _tiers.interpreted_first(_weighted, budget=-1.0)


_SEARCH_FIRST = _COUNT + r"""
from impactbar import BarModel, SquareWaveLoad
from impactbar.orbits.one_impact import _periodic_orbits_general
orbits = _periodic_orbits_general(BarModel(5.0, 0.1, 0.5, 3), SquareWaveLoad(1.0, 1.2))
print(json.dumps({"orbits": [[o.phase, o.clearance, o.clearance_error, o.admissibility] for o in orbits],
                  "compiled": compiled}))
"""


def test_a_first_orbit_search_with_an_empty_cache_does_not_compile_the_admissibility_search(
        tmp_path, monkeypatch):
    """With an empty numba cache, a process's first orbits take the admissibility search's twin
    (its compile is the largest of a first computation's): it compiles no search, and its verdicts,
    clearances and error bounds are the machine code's to the bit."""
    from impactbar.orbits.one_impact import _periodic_orbits_general

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), IMPACTBAR_TIERED="0",
               PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-c", _SEARCH_FIRST], env=env, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    first = json.loads(out.stdout.strip().splitlines()[-1])
    assert "admissibility_search" not in first["compiled"]  # (on main: it and 13 callees of its own)
    monkeypatch.setattr(_tiers._PROCESS, "eager", True)  # here: the machine code
    orbits = _periodic_orbits_general(BarModel(5.0, 0.1, 0.5, 3), SquareWaveLoad(1.0, 1.2))
    assert len(orbits) > 0
    assert first["orbits"] == [[o.phase, o.clearance, o.clearance_error, o.admissibility] for o in orbits]


@numba.njit(cache=False)
def _counts_then_overflows(a, work):
    a[0] += 1.0
    work[0] += 1.0
    return math.exp(a[1])


def test_a_twins_work_buffers_are_not_put_back():
    """Arguments named scratch (work buffers the kernel writes before it reads) are not copied for
    the twin's call: where the machine code takes the call over, they keep what the twin wrote,
    while the others start again as they came."""
    a, work = np.array([0.0, 1000.0]), np.zeros(1)
    assert _tiers._Twin(_counts_then_overflows, first=True, scratch=(1,))(a, work) == math.inf
    assert a[0] == 1.0 and work[0] == 2.0
