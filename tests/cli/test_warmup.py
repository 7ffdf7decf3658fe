"""``impactbar warmup`` (issue 20): after it, a new process's first calls compile nothing."""

import os
import subprocess
import sys

import pytest

#: first calls of every kind a user makes, in a new process: the names of the kernels numba compiles
_FIRST_CALLS = r"""
import numpy as np
from numba.core import event

compiled = []


class Listener(event.Listener):
    def on_start(self, ev):
        pass

    def on_end(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__qualname__)


event.register("numba:compile", Listener())
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
print(compiled)
"""


@pytest.mark.slow  # about 3 minutes (every kernel compiled into an empty cache): run by .ci/run
def test_after_warmup_a_new_process_compiles_nothing(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    cmd = [sys.executable, "-m", "impactbar.cli", "warmup"]
    first = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout
    lines = first.strip().splitlines()
    assert "periodic orbits, wave law" in first and "position-switched drive" in first
    assert int(lines[-1].split()[0]) > 50  # "N kernels compiled in ... s of CPU time; ..."
    # other parameters, loads and sizes than the warm-up's: the same kernels, one signature each
    out = subprocess.run([sys.executable, "-c", _FIRST_CALLS], env=env, capture_output=True, text=True,
                         check=True).stdout
    assert out.strip().splitlines()[-1] == "[]"
    again = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout
    assert again.strip().splitlines()[-1].startswith("0 kernels compiled")
