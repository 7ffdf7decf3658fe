"""A drifter map killed midway keeps its finished chunks and resumes to a store bitwise equal to an
uninterrupted one: the driver killed (SIGKILL to it and everything it started), or one of its
workers killed while the driver goes on."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("zarr")
pytest.importorskip("xarray")
pytest.importorskip("distributed")
psutil = pytest.importorskip("psutil")

from impactbar.sweeps import load_spec, run_map, sweep_progress  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")

SRC = Path(__file__).resolve().parents[2] / "src"
SPEC = ('task = "operating_point"\nconfig = "circuit-drifter"\nchain = "continue"\n[axes]\n'
        '"supply.pump_flow" = { values = ["60 L/min", "75 L/min", "90 L/min"] }\n'
        '"accumulator.precharge" = { values = ["6 MPa", "12 MPa"] }\n')


def _done(path: Path) -> int:
    try:
        return sweep_progress(path)[0]
    except (ValueError, OSError, KeyError):
        return 0


def _start(spec_file: Path, out: Path) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=str(SRC))
    cmd = [sys.executable, "-m", "impactbar.cli", "sweep", str(spec_file), "--out", str(out), "--workers",
           "1", "--quiet"]
    return subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True)


def _wait_for(proc, out: Path, n_done: int) -> None:
    deadline = time.monotonic() + 180
    while _done(out) < n_done:
        assert proc.poll() is None, proc.stderr.read().decode()
        assert time.monotonic() < deadline, "the map made no progress"
        time.sleep(0.01)


def _arrays(path: Path) -> dict:
    import zarr

    g = zarr.open_group(str(path), mode="r")
    return {name: np.asarray(a[...]) for name, a in g.arrays()}


def _assert_bitwise(a_path: Path, b_path: Path) -> None:
    a, b = _arrays(a_path), _arrays(b_path)
    assert a.keys() == b.keys()
    for name in a:
        assert a[name].dtype == b[name].dtype and a[name].shape == b[name].shape, name
        assert a[name].tobytes() == b[name].tobytes(), name


@pytest.fixture(scope="module")
def spec_and_reference(tmp_path_factory):
    """The map's spec file and its uninterrupted store (computed in threads of this process)."""
    folder = tmp_path_factory.mktemp("map")
    spec_file = folder / "map.toml"
    spec_file.write_text(SPEC)
    spec = load_spec(spec_file)
    assert spec.n_chunks == 3
    ref = folder / "ref.zarr"
    res = run_map(spec, ref, executor="threads", n_workers=1, progress=False)
    assert res.complete
    return spec_file, ref


def test_a_driver_killed_midway_resumes_to_the_uninterrupted_store(spec_and_reference, tmp_path):
    spec_file, ref = spec_and_reference
    out = tmp_path / "killed.zarr"
    proc = _start(spec_file, out)
    try:
        _wait_for(proc, out, 1)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    killed_at = _done(out)
    assert 1 <= killed_at < 3, "killed too late to test resumption"
    res = subprocess.run([sys.executable, "-m", "impactbar.cli", "sweep", str(spec_file), "--out", str(out),
                          "--workers", "1", "--quiet"], env=dict(os.environ, PYTHONPATH=str(SRC)),
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert int(res.stdout.split("(")[1].split(" found")[0]) == killed_at
    assert sweep_progress(out) == (3, 3)
    _assert_bitwise(ref, out)


def test_a_worker_killed_midway_loses_nothing(spec_and_reference, tmp_path):
    """The worker process SIGKILLed once a chunk is stored: its nanny starts another, the lost
    chunk is computed again, and the driver finishes the same store."""
    spec_file, ref = spec_and_reference
    out = tmp_path / "worker.zarr"
    proc = _start(spec_file, out)
    try:
        _wait_for(proc, out, 1)
        # the worker: the process its nanny (in the driver) spawned, not the resource tracker
        kids = psutil.Process(proc.pid).children(recursive=True)
        workers = [p for p in kids if any("spawn_main" in a for a in p.cmdline())]
        assert workers, [p.cmdline() for p in kids]
        killed = _done(out)
        for p in workers:
            os.kill(p.pid, signal.SIGKILL)
        rc = proc.wait(timeout=300)
        assert rc == 0, proc.stderr.read().decode()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert killed < 3, "the worker was killed after the map had finished"
    assert sweep_progress(out) == (3, 3)
    _assert_bitwise(ref, out)
