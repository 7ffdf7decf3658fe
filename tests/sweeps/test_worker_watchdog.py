"""A distributed sweep whose workers are all gone says so after a stated time, then waits or stops
as asked."""

import io
import logging
import threading
import time

import pytest

from impactbar.sweeps import NoWorkersError, parse_spec, run_sweep, sweep_progress
from impactbar.sweeps.run import _WorkerWatchdog


class _Workers:
    def __init__(self, n):
        self.n = n

    def __call__(self):
        return self.n


def test_watchdog_warns_once_after_the_timeout_and_when_workers_are_back():
    workers, out = _Workers(2), io.StringIO()
    w = _WorkerWatchdog(workers, 30.0, "wait", out=out)
    w.pending = lambda: 7
    assert w.check(0.0) is None
    workers.n = 0
    assert w.check(10.0) is None  # first seen gone at t = 10
    assert w.check(39.9) is None  # 29.9 s without a worker
    line = w.check(40.0)
    assert line.startswith("impactbar sweep: warning: no worker for 30 s (timeout 30 s); 7 chunk(s)")
    assert "still waiting" in line and not w.stopped
    assert w.check(100.0) is None  # said once
    workers.n = 1
    assert w.check(101.0) == "impactbar sweep: 1 worker(s) back; the sweep goes on"
    workers.n = 0
    assert w.check(102.0) is None and w.check(131.0) is None
    assert "no worker for 30 s" in w.check(132.0)  # gone again: a new warning after a new wait
    assert out.getvalue().count("\n") == 3


def test_watchdog_stop_cancels_and_records_why():
    workers, out, cancelled = _Workers(0), io.StringIO(), []
    w = _WorkerWatchdog(workers, 5.0, "stop", out=out)
    w.on_stop = lambda: cancelled.append(True)
    assert w.check(0.0) is None and w.check(4.0) is None
    assert w.check(5.0).endswith("; stopping") and w.stopped and cancelled == [True]
    assert "rerun the same command to resume" in w.message
    assert w.check(60.0) is None  # stopped: nothing more


def test_run_sweep_checks_the_watchdog_options(tmp_path):
    spec = parse_spec({"task": "orbits", "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
                       "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
                       "axes": {"R": {"values": [0.2, 0.5]}}})
    with pytest.raises(ValueError, match="worker_timeout"):
        run_sweep(spec, tmp_path / "a.zarr", worker_timeout=0.0)
    with pytest.raises(ValueError, match="no_workers must be one of"):
        run_sweep(spec, tmp_path / "a.zarr", no_workers="later")
    assert not (tmp_path / "a.zarr").exists()


def test_a_cluster_without_workers_is_reported_then_stopped_or_awaited(tmp_path, capsys):
    """A real (in-process) dask cluster whose workers are gone: ``stop`` raises after the timeout
    with nothing stored; ``wait`` says so, and finishes once a worker joins."""
    pytest.importorskip("xarray")
    distributed = pytest.importorskip("distributed")
    spec = parse_spec({"task": "orbits", "model": {"s": 10.0, "d": 0.05, "R": 0.5, "n_modes": 1},
                       "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
                       "axes": {"R": {"values": [0.2, 0.5]}}, "chunk_points": 1})
    with (distributed.LocalCluster(n_workers=0, processes=False, dashboard_address="127.0.0.1:0",
                                   scheduler_kwargs={"dashboard": False},
                                   silence_logs=logging.ERROR) as cluster,
          distributed.Client(cluster) as client):
        t0 = time.monotonic()
        with pytest.raises(NoWorkersError, match=r"no worker for \d+ s: stopped"):
            run_sweep(spec, tmp_path / "stop.zarr", client=client, progress=False,
                      worker_timeout=0.5, no_workers="stop")
        assert time.monotonic() - t0 < 30
        err = capsys.readouterr().err
        assert "no worker for" in err and "2 chunk(s) left; stopping" in err
        assert sweep_progress(tmp_path / "stop.zarr") == (0, 2)

        def join_when_warned():
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline and not said.is_set():
                time.sleep(0.05)
            cluster.scale(1)

        said = threading.Event()
        real_say = _WorkerWatchdog._say

        def say(self, line):
            real_say(self, line)
            said.set()

        _WorkerWatchdog._say = say
        try:
            threading.Thread(target=join_when_warned, daemon=True).start()
            res = run_sweep(spec, tmp_path / "wait.zarr", client=client, progress=False,
                            worker_timeout=0.5)
        finally:
            _WorkerWatchdog._say = real_say
        assert res.complete and res.computed == 2
        err = capsys.readouterr().err
        assert "still waiting for workers" in err  # (the line when they are back: the unit test)


def test_cli_options(tmp_path, capsys, monkeypatch):
    from impactbar.cli import main
    from impactbar.sweeps import run as run_module

    spec = tmp_path / "spec.toml"
    spec.write_text('task = "orbits"\n[model]\ns = 100.0\nd = 0.0\nR = 0.5\nn_modes = 0\n'
                    '[load]\nkind = "cosine"\np0 = 0.5\npk = 1.0\nk = 1\n'
                    '[axes]\nR = { values = [0.2, 0.5] }\n')
    assert main(["sweep", str(spec), "--out", str(tmp_path / "s.zarr"), "--worker-timeout", "-1"]) == 2
    assert "--worker-timeout must be >= 0" in capsys.readouterr().err
    seen = {}

    def fake(spec, store, **kw):
        seen.update(kw)
        raise NoWorkersError("no worker for 61 s: stopped; the chunks finished are stored, rerun")

    monkeypatch.setattr(run_module, "run_sweep", fake)
    import impactbar.sweeps as sweeps

    monkeypatch.setattr(sweeps, "run_sweep", fake)
    assert main(["sweep", str(spec), "--out", str(tmp_path / "s.zarr"), "--worker-timeout", "0",
                 "--no-workers", "stop"]) == 1
    assert seen["worker_timeout"] is None and seen["no_workers"] == "stop"
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == ("impactbar sweep: error: no worker for 61 s: stopped; the chunks finished "
                       "are stored, rerun")
