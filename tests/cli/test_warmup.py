"""``impactbar warmup``: after it, a new process's first calls compile nothing."""

import os
import re
import subprocess
import sys
from pathlib import Path

import numba
import pytest

from impactbar.cli import main, warmup
from impactbar.cli.warmup import (
    KERNELS,
    KERNELS_NUMBA,
    LINE_AFTER,
    LINE_COST,
    _tasks,
    default_jobs,
    kernel_count,
)

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
    # the parallel warm-up's schedule has a measured cost for each line (a line without one goes first)
    assert set(LINE_COST) == set(KERNELS) and all(t > 0 for t in LINE_COST.values())


def test_a_free_worker_makes_the_longest_line_whose_lines_before_have_finished(monkeypatch):
    """The parallel warm-up's schedule, on lines of made-up costs: the longest ready line; none while
    the lines a line reuses run (its worker waits); a line that waits for a line not made (pint
    missing) does not wait; a line of no measured cost goes first."""
    monkeypatch.setattr(warmup, "LINE_COST", {"a": 1.0, "b": 5.0, "c": 9.0, "d": 3.0})
    monkeypatch.setattr(warmup, "LINE_AFTER", {"c": ("a",), "d": ("a", "b")})
    labels = ["a", "b", "c", "d"]
    assert warmup._next_line(labels, [], labels) == "b"  # (c, the longest, reuses a)
    assert warmup._next_line(["a", "c", "d"], ["b"], labels) == "a"
    assert warmup._next_line(["c", "d"], ["b"], labels) is None  # (a runs)
    assert warmup._next_line(["c", "d"], ["b"], labels, wait=False) == "c"  # (none runs: no deadlock)
    assert warmup._next_line(["c", "d"], ["b", "a"], labels) == "c"
    assert warmup._next_line(["d"], [], ["b", "d"]) is None
    assert warmup._next_line(["d"], [], ["d"]) == "d"
    assert warmup._next_line(["a", "e"], [], labels + ["e"]) == "e"
    # the lines' own: each line waits only for lines before it (the order --jobs 1 keeps)
    order = list(KERNELS)
    assert all(order.index(before) < order.index(line) for line, lines in LINE_AFTER.items()
               for before in lines)


def test_jobs_default_to_the_cores_and_refuse_fewer_than_one(capsys):
    """Without ``--jobs`` the warm-up starts a worker a core this process may run on; ``--jobs 0``, or
    a word, is one line on stderr and status 2, before anything compiles."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    assert default_jobs() == cores >= 1
    for bad in ("0", "-2", "two"):
        with pytest.raises(SystemExit) as exit_:
            main(["warmup", "--jobs", bad])
        assert exit_.value.code == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--jobs must be an integer of at least 1" in err[0], err


@pytest.mark.slow  # about 5 minutes each (every kernel compiled into an empty cache): run by .ci/run
@pytest.mark.timeout(2400)  # three processes, the first compiling: 20 minutes and more at load 9 on 2 cores
@pytest.mark.parametrize("jobs", ["1", "2"])
def test_after_warmup_a_new_process_compiles_nothing(tmp_path, jobs):
    """One kind after another in one process (``--jobs 1``), or in two worker processes writing one
    cache at once: a new process's first calls of every kind then compile nothing."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    cmd = [sys.executable, "-m", "impactbar.cli", "warmup", "--jobs", jobs]
    first = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout
    lines = first.strip().splitlines()
    for label in ("periodic orbits, wave law", "position-switched drive", "rod and rock orbits, exact blows",
                  "oil circuit", "oil circuit on rod and rock", "piston optimiser"):
        assert label in first
    # each line's kernels ("label  T s CPU  N kernels compiled") and their sum, as the warm-up declares
    # them without compiling (the sum is the figure the documentation quotes)
    counts = {m[1]: int(m[2]) for m in re.finditer(r"^(.+?) +[0-9.]+ s CPU +([0-9]+) kernels compiled$",
                                                    first, re.MULTILINE)}
    declared = ".".join(numba.__version__.split(".")[:2]) == KERNELS_NUMBA  # (numba's own overloads count)
    if jobs == "1":
        assert list(counts) == list(KERNELS) and all(n > 0 for n in counts.values())
        assert int(lines[-1].split()[0]) == sum(counts.values())  # "N kernels compiled in ... s of CPU time"
        if declared:
            assert counts == KERNELS
    else:  # the lines as they finish; a kernel two workers needed at once compiles in both ("N kernels
        # compiled in W s, C s of CPU time in 2 worker processes (D of the T compiles a kernel that
        # another worker compiled too)"), once in N: at most the one process's count, since numba's
        # own overloads, not cached, that it compiled more than once may be split between the workers
        assert sorted(counts) == sorted(KERNELS) and all(n >= 0 for n in counts.values())
        summary = re.fullmatch(r"([0-9]+) kernels compiled in [0-9.]+ s, [0-9.]+ s of CPU time in 2 worker "
                               r"processes \(([0-9]+) of the ([0-9]+) compiles .*", lines[-1])
        assert summary is not None, lines[-1]
        distinct, again, total = map(int, summary.groups())
        assert total == sum(counts.values()) and distinct == total - again > 300
        if declared:
            assert distinct <= kernel_count() <= total
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


_ONE_LINE = r"""
import sys
from impactbar.cli import warmup

warmup._start(in_worker=False)
print(len(warmup._line(sys.argv[1])[3]))
"""


@pytest.mark.slow  # about a minute of CPU: the parallel warm-up until its first line finishes
@pytest.mark.timeout(1200)
def test_ctrl_c_ends_a_parallel_warmup_and_keeps_what_finished(tmp_path):
    """Ctrl-C (SIGINT to the terminal's process group: the command and its workers) while the
    workers compile: status 130, one line saying how many kinds finished, no worker left, and a
    finished kind's kernels cached (a new process's call of that kind compiles nothing)."""
    import signal
    import time

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONUNBUFFERED="1")
    # (started as a terminal starts a command, Ctrl-C not ignored: a child inherits an ignored SIGINT,
    # and the tests may run ignoring it, as a background job of a shell without job control does, so
    # that the command, as Python does, would keep ignoring it)
    proc = subprocess.Popen([sys.executable, "-m", "impactbar.cli", "warmup", "--jobs", "2"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    labels = "|".join(re.escape(label) for label in KERNELS)
    first = None
    for line in proc.stdout:
        if (m := re.match(rf"^({labels}) +[0-9.]+ s CPU", line)):
            first = m[1]
            break
    assert first is not None
    sent = time.monotonic()
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=600)
    # (what the command printed after the first line, and how long it ran on: where a Ctrl-C was
    # missed, the lines it went on with say when)
    assert proc.returncode == 130, (err, out, f"{time.monotonic() - sent:.1f} s after the Ctrl-C")
    said = rf"impactbar warmup: [0-9]+ of {len(KERNELS)} kinds finished, their kernels cached"
    assert re.search(said, err), err
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:  # (no process of the command's group left)
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.5)
    else:
        raise AssertionError("a worker outlived the interrupted warm-up")
    again = subprocess.run([sys.executable, "-c", _ONE_LINE, first], env=env, capture_output=True, text=True,
                           check=True)
    assert again.stdout.strip().splitlines()[-1] == "0", (first, again.stdout)
