"""Running a sweep on ``dask.distributed``: farm out chunks, write each as it arrives, resume."""

from __future__ import annotations

import os
import sys
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._validate import check_int
from .spec import SweepSpec
from .store import _prepare_store, _write_chunk, _write_done
from .tasks import compute_chunk

#: the local cluster's HTTP servers: no dashboard, loopback, a free port
LOCAL_CLUSTER_HTTP = {"dashboard_address": "127.0.0.1:0", "scheduler_kwargs": {"dashboard": False},
                      "worker_dashboard_address": None}
#: dask configuration while the local cluster starts: its HTTP servers serve nothing
LOCAL_HTTP_CONFIG = {"distributed.scheduler.http.routes": [], "distributed.worker.http.routes": []}


# ------------------------------------------------------------------------------------------------
# the driver
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SweepRun:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    store : pathlib.Path
    n_chunks : int
        Chunks in the sweep.
    already_done : int
        Chunks found finished in the store (resumed).
    computed : int
        Chunks computed by this run.
    seconds : float
        Wall time of the computation (s), cluster start-up excluded.
    """

    store: Path
    n_chunks: int
    already_done: int
    computed: int
    seconds: float

    @property
    def complete(self) -> bool:
        return self.already_done + self.computed == self.n_chunks


def default_workers() -> int:
    """Worker processes of the default local cluster: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def run_sweep(spec: SweepSpec, store, *, client=None, scheduler: str | None = None,
              n_workers: int | None = None, overwrite: bool = False, progress: bool = True) -> SweepRun:
    """Compute a sweep into a zarr store, resuming whatever an earlier run finished.

    Parameters
    ----------
    spec : SweepSpec
    store : str or os.PathLike
        Folder of the zarr store; created if absent, resumed if it holds the same sweep.
    client : distributed.Client, optional
        Use this client's cluster.
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:port``); its workers must be able to import
        impactbar.
    n_workers : int, optional
        Size of the local cluster started when neither ``client`` nor ``scheduler`` is given
        (processes of one thread each); default the number of cores.
    overwrite : bool, optional
        Replace a store holding another sweep (or one from another impactbar version).
    progress : bool, optional
        Show a progress bar (chunks done, rate, time left) on stderr.

    Returns
    -------
    SweepRun

    Raises
    ------
    ValueError
        If the store holds another sweep and ``overwrite`` is false, or ``store`` is a folder that
        is not a sweep store; nothing is computed then.
    """
    if not isinstance(spec, SweepSpec):
        raise ValueError(f"spec must be a SweepSpec; got {type(spec).__name__}")
    if sum(x is not None for x in (client, scheduler, n_workers)) > 1:
        raise ValueError("give at most one of client, scheduler, n_workers")
    if n_workers is not None:
        n_workers = check_int("n_workers", n_workers, lo=1)
    path = Path(store)
    done = _prepare_store(spec, path, overwrite)
    todo = [int(i) for i in np.flatnonzero(done == 0)]
    already = spec.n_chunks - len(todo)
    if not todo:
        return SweepRun(path, spec.n_chunks, already, 0, 0.0)
    if client is not None:
        return _drive(spec, path, done, todo, client, progress)
    from distributed import Client, LocalCluster

    if scheduler is not None:
        with Client(scheduler) as cl:
            return _drive(spec, path, done, todo, cl, progress)
    import logging

    import dask

    n = default_workers() if n_workers is None else n_workers
    # No dashboard: distributed always starts an HTTP server in the scheduler, so it gets no routes,
    # the loopback interface and a free port (not 8787, which another cluster may hold).
    with (dask.config.set(LOCAL_HTTP_CONFIG),
          LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                       **LOCAL_CLUSTER_HTTP, silence_logs=logging.ERROR) as cluster,
          Client(cluster) as cl):
        return _drive(spec, path, done, todo, cl, progress)


def _drive(spec, path, done, todo, client, progress) -> SweepRun:
    from distributed import as_completed
    from tqdm import tqdm

    already = spec.n_chunks - len(todo)
    tag = uuid.uuid4().hex[:8]
    t_start = time.perf_counter()
    futures = [client.submit(compute_chunk, spec, i, key=f"impactbar-{spec.task}-{tag}-{i}",
                             pure=False) for i in todo]
    chunk_of = {f.key: i for f, i in zip(futures, todo, strict=True)}
    computed = 0
    bar = tqdm(total=len(todo), unit="chunk", file=sys.stderr, disable=not progress,
               desc=f"{spec.task} ({already}/{spec.n_chunks} stored before)", smoothing=0.1)
    try:
        for fut in as_completed(futures):
            result = fut.result()  # a task error propagates; every finished chunk is stored
            i = chunk_of[fut.key]
            _write_chunk(spec, path, i, result)
            done[i] = 1
            _write_done(path, done)  # after the data: a kill in between loses only this chunk
            fut.release()
            computed += 1
            bar.update(1)
    finally:
        bar.close()
        for f in futures:
            if not f.done():
                f.cancel()
    return SweepRun(path, spec.n_chunks, already, computed, time.perf_counter() - t_start)
