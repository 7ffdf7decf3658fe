"""The package with numba's JIT disabled (``NUMBA_DISABLE_JIT=1``, numba's way to debug its kernels as
Python): the kernels run as plain functions, with the compiled kernels' numbers; what needs compiled
code says so, naming the setting."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

#: a rigid simulate and an 8-mode periodic_orbits as Python, and the oil circuit's refusal
_RUN = r'''
import json, sys
import numba
from numba.core import config
from numba.core.dispatcher import Dispatcher

from impactbar import BarModel, CosineLoad, InitialState, periodic_orbits, simulate
from impactbar.dynamics import _flight

run = simulate(BarModel(5.0, 0.1, 0.5, 0), CosineLoad(0.6, 1.0), InitialState.rigid(-0.2, 0.0), 30.0)
orbits = periodic_orbits(BarModel(5.0, 0.1, 0.5, 8), CosineLoad(0.6, 1.0))
out = {"disabled": bool(config.DISABLE_JIT), "kernel": isinstance(_flight.load_value, Dispatcher),
       "times": run.impact_times.tolist(), "q": run.final_state.modal_displacement.tolist(),
       "v": run.final_state.modal_velocity.tolist(),
       "orbits": [(o.phases.tolist(), o.impact_velocities.tolist()) for o in orbits]}
if "circuit" in sys.argv:
    from impactbar import physical as ph

    cfg, _ = ph.read_config("circuit-drifter")
    try:
        ph.build(ph.with_values(cfg, {"model.n_modes": 4})).orbit()
    except RuntimeError as exc:
        out["circuit"] = str(exc)
    from impactbar.cli import main

    out["warmup"] = main(["warmup"])
print(json.dumps(out))
'''

#: the README's first blow as Python, exact and on the lattice: their efficiencies
_BLOW = r'''
from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow
law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
model = BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law)
print(*(single_blow(model, 1.0, t_max=39.0, method=m).efficiency.hex() for m in ("exact", "lattice")))
'''


def _python(code: str, *args: str) -> subprocess.CompletedProcess:
    """``code`` run in a new process with numba's JIT disabled."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), NUMBA_DISABLE_JIT="1")
    return subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True, text=True,
                          check=True, timeout=600)


def test_the_kernels_run_as_python_with_the_compiled_numbers_and_the_circuit_refuses():
    """A rigid ``simulate`` and an 8-mode ``periodic_orbits`` as Python give the compiled run's numbers
    (here: the same to 1e-12); the oil circuit's flight, whose C callbacks for CVODE must compile,
    raises a RuntimeError naming the setting, and ``impactbar warmup`` ends with 1 and one line."""
    from impactbar import BarModel, CosineLoad, InitialState, periodic_orbits, simulate

    done = _python(_RUN, "circuit")
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["disabled"] and not out["kernel"]  # (the kernels were plain functions)
    run = simulate(BarModel(5.0, 0.1, 0.5, 0), CosineLoad(0.6, 1.0), InitialState.rigid(-0.2, 0.0), 30.0)
    assert len(out["times"]) == len(run.impact_times) > 10
    np.testing.assert_allclose(out["times"], run.impact_times, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(out["q"], run.final_state.modal_displacement, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(out["v"], run.final_state.modal_velocity, rtol=1e-12, atol=1e-12)
    orbits = periodic_orbits(BarModel(5.0, 0.1, 0.5, 8), CosineLoad(0.6, 1.0))
    assert len(out["orbits"]) == len(orbits) > 0
    for (phases, velocities), o in zip(out["orbits"], orbits, strict=True):
        np.testing.assert_allclose(phases, o.phases, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(velocities, o.impact_velocities, rtol=1e-12, atol=1e-12)
    assert "oil circuit's flight" in out["circuit"] and "NUMBA_DISABLE_JIT=1" in out["circuit"]
    assert out["warmup"] == 1
    assert "impactbar warmup: error: NUMBA_DISABLE_JIT=1" in done.stderr


@pytest.mark.slow
def test_the_first_blow_runs_as_python_with_the_compiled_efficiency():
    """The README's first blow (``single_blow`` under ``RodRock``), exact and on the lattice, as
    Python: the compiled blows' efficiencies (to 1e-12), which differ from each other (the lattice's
    first order)."""
    from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow

    python = [float.fromhex(x) for x in _python(_BLOW).stdout.strip().splitlines()[-1].split()]
    law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
    model = BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law)
    compiled = [single_blow(model, 1.0, t_max=39.0, method=m).efficiency for m in ("exact", "lattice")]
    assert 0.0 < compiled[0] < 1.0 and compiled[0] != compiled[1]
    assert python == pytest.approx(compiled, rel=1e-12, abs=1e-12)


def test_the_compile_helpers_leave_plain_functions_as_they_are(monkeypatch):
    """With the JIT disabled, ``internal_kernels`` changes nothing (0 kernels), still refuses a name
    that is not one of the module's functions, and ``link_only`` and ``internal_jitable`` give the
    function back; ``require_jit`` names the setting."""
    from numba.core import config

    from impactbar._shared import wrappers as W

    def square(x):
        return x * x

    def area(a, b):
        return square(a) + square(b)

    ns = {"__name__": square.__module__, "square": square, "area": area, "np": np}
    monkeypatch.setattr(config, "DISABLE_JIT", True)
    assert W.jit_disabled()
    assert W.internal_kernels(ns, python=("area",)) == 0
    assert ns["area"] is area and area(3, 4) == 25
    with pytest.raises(ValueError, match=r"python names no kernel of .*\['np'\]"):
        W.internal_kernels(ns, python=("area", "np"))
    with pytest.raises(ValueError, match="from_python"):
        W.link_only(square, "never")
    assert W.link_only(square) is square and W.internal_jitable(square) is square
    with pytest.raises(RuntimeError, match="the thing needs compiled code, which NUMBA_DISABLE_JIT=1"):
        W.require_jit("the thing")
    monkeypatch.setattr(config, "DISABLE_JIT", False)
    W.require_jit("the thing")  # (compiled: nothing to refuse)
