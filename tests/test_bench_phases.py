"""``benchmarks/bench_optimize_drifter.py``'s account of the multistart's phases: the projection on N
free workers is each phase's CPU here plus, in a phase with tasks on the workers, its workers' CPU
over N plus the measured overheads (a closed form on made-up figures), and the workers' CPU it
reads (``client.run(time.process_time)``) counts a task's CPU on a worker (a task that spins for a
known CPU time)."""

import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import bench_optimize_drifter as bench  # noqa: E402


def _walls(figures: dict, startup: list, probe: dict) -> dict:
    walls = {f"{p}{w}": 0 if w in (" tasks", " flights") else 0.0 for p in bench.PHASES
             for w in ("", " CPU", " workers CPU", " tasks", " flights")}
    for phase, (wall, cpu, wcpu, tasks, flights) in figures.items():
        walls.update({phase: wall, f"{phase} CPU": cpu, f"{phase} workers CPU": wcpu,
                      f"{phase} tasks": tasks, f"{phase} flights": flights})
    workers = bench._Workers()
    workers.startup, workers.probe = startup, probe
    walls["workers"] = workers
    return walls


def test_projection_is_serial_cpu_plus_spread_cpu_over_n_plus_overheads():
    probe = {"workers": 2, "flight s": 0.01, "task s": 0.004}
    figures = {"cluster start": (3.0, 0.2, 1.5, 0, 0), "sample": (150.0, 2.0, 260.0, 256, 1),
               "local searches": (80.0, 64.0, 0.5, 0, 0), "polish": (350.0, 33.0, 500.0, 324, 27),
               "classification": (30.0, 28.0, 0.1, 0, 0), "certificate": (18.0, 1.2, 30.0, 12, 1),
               "cluster close": (1.5, 0.1, 0.0, 0, 0)}
    walls = _walls(figures, [0.7, 0.8], probe)
    wall, cpu = 650.0, 140.0
    for n in (1, 2, 4, 8):
        rows = {r[0]: r for r in bench.projection(walls, wall, cpu, n)}
        for phase in ("sample", "local searches", "polish", "classification", "certificate"):
            _, c, wc, tasks, flights = figures[phase]
            expected = c + (wc / n + tasks * 0.004 / n + flights * 0.01 if tasks else 0.0)
            assert rows[phase][-1] == pytest.approx(expected, rel=1e-12)
            assert rows[phase][1] == ("spread" if tasks else "serial")
        assert rows["cluster start"][-1] == pytest.approx(0.2 + 0.8)
        assert rows["cluster close"][-1] == pytest.approx(1.5)
        rest_cpu = cpu - sum(f[1] for f in figures.values())
        assert rows["the rest"][-1] == pytest.approx(rest_cpu)
        assert rows["the rest"][2] == pytest.approx(wall - sum(f[0] for f in figures.values()))
    # more workers: the spread phases shorter, the serial ones the same
    two, eight = ({r[0]: r[-1] for r in bench.projection(walls, wall, cpu, n)} for n in (2, 8))
    assert eight["sample"] < two["sample"] and eight["local searches"] == two["local searches"]


def _spin(seconds: float) -> float:
    t = time.process_time()
    while time.process_time() - t < seconds:
        pass
    return seconds


@pytest.mark.slow
def test_workers_cpu_counts_a_task_on_a_worker():
    distributed = pytest.importorskip("distributed")
    with (distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                   dashboard_address=None) as cluster,
          distributed.Client(cluster) as client):
        workers = bench._Workers()
        run = workers.count(client, lambda fn, items: client.gather(client.map(fn, items, pure=False)))
        before = workers.cpu()
        c0 = time.process_time()
        assert run(_spin, [0.3, 0.3]) == [0.3, 0.3]
        here = time.process_time() - c0
        spent = workers.cpu() - before
        assert 0.6 <= spent < 1.2  # (the two tasks' 0.6 s and the worker's own bookkeeping)
        assert here < 0.3  # (the spinning was not in this process)
        assert (workers.tasks, workers.flights) == (2, 1)
        workers.measure_overhead(rounds=1)
        assert workers.probe["workers"] == 1 and 0.0 < workers.probe["task s"] < 1.0
