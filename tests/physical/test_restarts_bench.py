"""The restarted-searches benchmark (``benchmarks/bench_optimize_restarts.py``) survives a search whose
task kills its dask worker, and its 4-worker estimate is the designs' own seconds, the same whether
they were computed in the run or read from its cache (it was the run's wall less the cached designs'
seconds: negative from a cache)."""

import importlib.util
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

pytest.importorskip("distributed")

BENCH = Path(__file__).resolve().parents[2] / "benchmarks"


@pytest.fixture(scope="module")
def bench():
    sys.path.insert(0, str(BENCH))
    try:
        spec = importlib.util.spec_from_file_location("bench_optimize_restarts",
                                                      BENCH / "bench_optimize_restarts.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(BENCH))
    return module


class _Future:
    """A dask future's ``result()``: a value, or the exception its task ended in."""

    def __init__(self, value=None, error=None):
        self.value, self.error = value, error

    def result(self):
        if self.error is not None:
            raise self.error
        return self.value


def test_a_search_that_killed_its_worker_is_a_failed_search(bench):
    from distributed.scheduler import KilledWorker

    worker = SimpleNamespace(address="tcp://127.0.0.1:1")  # (the scheduler's WorkerState's address)
    s = bench.search_result(_Future(error=KilledWorker("restarted_search-20", worker, 3)))
    assert s["lost"] and not s["feasible"] and math.isnan(s["seconds"])
    assert s["error"].startswith("KilledWorker: ") and "restarted_search-20" in s["error"]
    done = {"result": 0.1, "feasible": True, "seconds": 2.0}
    assert bench.search_result(_Future(done)) is done


def test_the_four_worker_estimate_is_the_designs_own_seconds(bench):
    """Four sampled designs of 4 s (one without an operating point: 1 s and 3 s of its settle task)
    side by side on 4 workers, 4 s; a local search's two designs of 5 s after them, 10 s: 14 s, from a
    cache as from the run."""
    sample = [{"ok": True, "seconds": 4.0}, {"ok": True, "seconds": 4.0}, {"ok": True, "seconds": 4.0},
              {"ok": False, "seconds": 1.0, "motion_seconds": 3.0}]
    history = sample + [{"ok": True, "seconds": 5.0}, {"ok": True, "seconds": 5.0}]
    assert bench.four_worker_estimate(history, sample) == pytest.approx(14.0, rel=1e-15)
