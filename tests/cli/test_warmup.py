"""``impactbar warmup``: after it, a new process's first calls compile nothing."""

import os
import re
import subprocess
import sys
from pathlib import Path

import numba
import pytest

from impactbar.cli.warmup import KERNELS, KERNELS_NUMBA, _tasks, kernel_count

EXAMPLE = Path(__file__).parents[2] / "examples" / "circuit_drifter_rock.toml"

#: first calls of every kind a user makes, in a new process: the names of the kernels numba compiles
_FIRST_CALLS = r"""
import math
import sys
import tomllib

import numpy as np
from numba.core import event
from numba.core.ccallback import CFunc

compiled = []


class Listener(event.Listener):
    def on_start(self, ev):
        pass

    def on_end(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__qualname__)


event.register("numba:compile", Listener())
_uncached = CFunc._compile_uncached  # a C callback (the circuit's) compiles without the event


def _count_callback(self):
    compiled.append(self._pyfunc.__qualname__)
    return _uncached(self)


CFunc._compile_uncached = _count_callback
from impactbar import (BarModel, BilinearRock, CosineLoad, InitialState, PositionSwitchedDrive, RodRock,
                       RodSegment, SquareWaveLoad, find_orbit, periodic_orbits, simulate, single_blow)
from impactbar.orbits.rigid import rigid_square_orbits

for n in (0, 8, 48):
    for law in ("paper", "wave"):
        model = BarModel(3.0, 0.05, 0.6, n, impact=law)
        for load in (CosineLoad(0.5, 1.0), SquareWaveLoad(1.0, 1.3)):
            periodic_orbits(model, load)
            simulate(model, load, InitialState.rigid(-0.3, 0.1, n), 20.0)
piston, drive = BarModel(10.0, 0.0, 0.3, 2), PositionSwitchedDrive(stroke=1.0, ret=0.8, switch_out=0.9)
simulate(piston, drive, InitialState.rigid(-0.4, 0.0, 2), 30.0)
find_orbit(piston.with_(n_modes=0), drive)
law = RodRock(segments=[RodSegment(length=20.0, impedance=1.0)], rock=BilinearRock(k=3.0, k_u=30.0))
single_blow(BarModel(2.0, 0.0, 0.0, 0, impact=law), 1.5, t_max=25.0)
n = 7
rigid_square_orbits(np.full(n, 0.1), np.full(n, 0.5), np.full(n, 1.0), np.full(n, 1.2))
# the rod-rock law's orbits (Newton on the blow's tangents), exact blows and on the lattice
for method in ("exact", "lattice"):
    law = RodRock(segments=[RodSegment(length=2.0, impedance=2.0)], rock=BilinearRock(k=20.0, k_u=200.0),
                  method=method)
    model, load = BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law), CosineLoad(0.3, 1.0)
    run = simulate(model, load, InitialState.rigid(-0.1, 0.0, n_modes=4), 200.0)
    find_orbit(model, load, impacts=2, periods=2, guess=run)
# impactbar.physical: the oil circuit (README), on a rod and rock (the example), the piston's optimiser
from impactbar.physical import CircuitDrifter, circuit_preset, optimize_piston
from impactbar.physical.rock import RodPiece

drifter = circuit_preset("circuit-drifter", supply={"pump_flow": "75 L/min"})
drifter.orbit()
drifter.simulate(0.02)
find_orbit(drifter.model().with_(n_modes=3), drifter.drive())  # (a flexible piston: Magnus' Phi)
with open(sys.argv[1], "rb") as f:
    on_rock = CircuitDrifter.from_config(tomllib.load(f))
on_rock.orbit()
on_rock.simulate(0.02)
rod = [RodPiece(length_m=1.8, area_m2=1e-3, E_Pa=2.1e11, density_kg_m3=7850.0)]
optimize_piston(rod, (2e8, 2e9), mass=2.355, length=0.3, max_stress=math.inf, impact_velocity=10.0,
                segments=3, max_evaluations=2)
print(compiled)
"""


def test_the_declared_kernels_are_the_warmups_calls():
    """:data:`KERNELS` names the warm-up's first calls, in their order (pint, which the oil circuit's
    three need, is installed with the test extras), and their sum is the count the documentation
    quotes; whether each count is what the call compiles, the slow test below checks."""
    assert [label for label, _ in _tasks()] == list(KERNELS)
    assert kernel_count() == sum(KERNELS.values()) > 300
    assert all(n > 0 for n in KERNELS.values())


@pytest.mark.slow  # about 5 minutes (every kernel compiled into an empty cache): run by .ci/run
@pytest.mark.timeout(2400)  # three processes, the first compiling: 20 minutes and more at load 9 on 2 cores
def test_after_warmup_a_new_process_compiles_nothing(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    cmd = [sys.executable, "-m", "impactbar.cli", "warmup"]
    first = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout
    lines = first.strip().splitlines()
    for label in ("periodic orbits, wave law", "position-switched drive", "rod and rock orbits, exact blows",
                  "oil circuit", "oil circuit on rod and rock", "piston optimiser"):
        assert label in first
    # each line's kernels ("label  T s CPU  N kernels compiled") and their sum, as the warm-up declares
    # them without compiling (the sum is the figure the documentation quotes)
    counts = {m[1]: int(m[2]) for m in re.finditer(r"^(.+?) +[0-9.]+ s CPU +([0-9]+) kernels compiled$",
                                                    first, re.MULTILINE)}
    assert list(counts) == list(KERNELS) and all(n > 0 for n in counts.values())
    assert int(lines[-1].split()[0]) == sum(counts.values())  # "N kernels compiled in ... s of CPU time"
    if ".".join(numba.__version__.split(".")[:2]) == KERNELS_NUMBA:  # (numba's own overloads count too)
        assert counts == KERNELS
    # other parameters, loads and sizes than the warm-up's: the same kernels, one signature each; and
    # the warm-up again. The two only read the cache when they compile nothing (what is asserted), so
    # they run side by side (on CI's 2 cores, the second costs no wall time of its own)
    runs = [subprocess.Popen(args, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            for args in ([sys.executable, "-c", _FIRST_CALLS, str(EXAMPLE)], cmd)]
    (out, err), (again, err_again) = (p.communicate() for p in runs)
    assert runs[0].returncode == 0, err
    assert runs[1].returncode == 0, err_again
    assert out.strip().splitlines()[-1] == "[]"
    assert again.strip().splitlines()[-1].startswith("0 kernels compiled")


_ONE_SIGNATURE = r"""
import gc
import sys
from numba.core.dispatcher import Dispatcher
from impactbar.cli.warmup import _tasks

for label, call in _tasks():
    if label in sys.argv[1:]:
        call()
for obj in gc.get_objects():
    if isinstance(obj, Dispatcher) and obj.py_func.__module__.startswith("impactbar"):
        print(obj.py_func.__module__ + "." + obj.py_func.__name__, len(obj.signatures))
"""


@pytest.mark.slow  # about 25 s of CPU: three of the warm-up's calls compiled into an empty cache
def test_the_warmups_bar_valve_and_chunk_kernels_take_one_signature_each(tmp_path):
    """The warm-up's calls of 40 modes, the position-switched drive and the rigid sweep's chunks in a new
    process with an empty cache: each of the package's kernels (a dispatcher: ``run_free`` and
    ``run_free_rigid`` are two of one function, the second not called here) compiles one signature,
    among them those that a constant or a float argument compiled twice (``_aberth._cdiv`` of one,
    the valve loop's ``_push`` and ``run_free`` with its constants, the rigid chunks' ``_verdict``
    with ``ng = 0``)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    env.pop("NUMBA_DISABLE_JIT", None)
    labels = ["periodic orbits, 40 modes and more", "position-switched drive", "rigid sweep chunks"]
    done = subprocess.run([sys.executable, "-c", _ONE_SIGNATURE, *labels], env=env, capture_output=True,
                          text=True, check=True)
    counts = {}
    for line in done.stdout.strip().splitlines():
        kernel, n = line.split()
        counts.setdefault(kernel, []).append(int(n))
    for kernel in ("impactbar.dynamics._aberth._cdiv", "impactbar.drives.valve._compiled_loop._push",
                   "impactbar.dynamics._event_loop._run_free", "impactbar.orbits._rigid_scalar._verdict"):
        assert max(counts.get(kernel, [0])) == 1, (kernel, counts.get(kernel))
    assert {k: n for k, n in counts.items() if max(n) > 1} == {}
