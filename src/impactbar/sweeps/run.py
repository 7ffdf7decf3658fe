"""Running a sweep on ``dask.distributed``: farm out chunks, write each as it arrives, resume."""

from __future__ import annotations

import contextlib
import os
import sys
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._validate import check_int
from .spec import SweepSpec
from .store import _checksum, _open_group, _prepare_store, _write_chunk, _write_done
from .tasks import compute_chunk

#: How long :func:`run_sweep` waits for a ``scheduler`` to answer
CONNECT_TIMEOUT = "10s"
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
        If the store holds another sweep and ``overwrite`` is false, ``store`` is a file or a
        folder that is not a sweep store, its folder cannot be written, another driver holds the
        store's lock, ``scheduler`` does not answer within ``CONNECT_TIMEOUT``, or ``n_workers``
        is outside ``[1, max_workers()]``; nothing is computed (or left behind) then.

    Notes
    -----
    On resume every chunk flagged done is read back and checked against its stored CRC-32; a
    missing, truncated or corrupted chunk is recomputed.
    """
    if not isinstance(spec, SweepSpec):
        raise ValueError(f"spec must be a SweepSpec; got {type(spec).__name__}")
    if sum(x is not None for x in (client, scheduler, n_workers)) > 1:
        raise ValueError("give at most one of client, scheduler, n_workers")
    if n_workers is not None:
        n_workers = check_int("n_workers", n_workers, lo=1, hi=max_workers())
    path = Path(store)
    _check_out(path)
    created = _missing_parents(path)
    try:
        with _StoreLock(path), contextlib.ExitStack() as stack:
            # a new store is created only once the cluster answers: a dead scheduler leaves
            # nothing behind; an existing one is verified first (nothing to do: no cluster)
            resume = path.exists() and not overwrite
            if resume:
                done, sums = _prepare_store(spec, path, overwrite)
                if not np.any(done == 0):
                    return SweepRun(path, spec.n_chunks, spec.n_chunks, 0, 0.0)
            if client is None:
                client = stack.enter_context(_connect(scheduler, n_workers))
            if not resume:
                done, sums = _prepare_store(spec, path, overwrite)
            todo = [int(i) for i in np.flatnonzero(done == 0)]
            return _drive(spec, path, done, sums, todo, client, progress)
    except BaseException:
        for p in created:  # folders this call made and left empty
            try:
                p.rmdir()
            except OSError:
                pass
        raise


def max_workers() -> int:
    """Largest local cluster :func:`run_sweep` starts: four processes per core (at least 4)."""
    return max(4, 4 * default_workers())


def _check_out(path: Path) -> None:
    """Refuse an ``--out`` that cannot become a store, before anything is created."""
    if path.exists() and not path.is_dir():
        raise ValueError(f"--out {path} is an existing file, not a sweep store; choose a folder path")
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise ValueError(f"--out {path}: {parent} is a file, not a folder")
            if not os.access(parent, os.W_OK | os.X_OK):
                raise ValueError(f"--out {path}: the folder {parent} is not writable")
            break


def _missing_parents(path: Path) -> list:
    """The ancestors of ``path`` that do not exist yet, deepest first."""
    out = []
    for parent in path.parents:
        if parent.exists():
            break
        out.append(parent)
    return out


class _StoreLock:
    """An exclusive lock on a store (``fcntl.flock`` on ``.NAME.lock`` next to it), held while a
    driver writes it; the kernel drops it when the process dies, even by SIGKILL."""

    def __init__(self, path: Path):
        self.path = path
        self.lock = path.with_name(f".{path.name}.lock")
        self.fd = None

    def __enter__(self):
        import fcntl

        try:
            self.lock.parent.mkdir(parents=True, exist_ok=True)
            self.fd = os.open(self.lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise ValueError(f"--out {self.path}: cannot create the store there: "
                             f"{exc.strerror or exc}") from None
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(self.fd)
            self.fd = None
            raise ValueError(f"--out {self.path} is being written by another impactbar sweep; wait "
                             "for it to finish, or choose another --out") from None
        return self

    def __exit__(self, *exc):
        try:
            os.unlink(self.lock)
        except OSError:
            pass
        os.close(self.fd)
        return False


@contextlib.contextmanager
def _connect(scheduler, n_workers):
    """A ``distributed.Client``: to ``scheduler``, or to a local cluster of ``n_workers``."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            cl = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            raise ValueError(f"--scheduler {scheduler!r}: cannot connect within "
                             f"{CONNECT_TIMEOUT} ({exc})") from None
        with cl:
            yield cl
        return
    import logging

    import dask

    n = default_workers() if n_workers is None else n_workers
    # No dashboard: distributed always starts an HTTP server in the scheduler, so it gets no routes,
    # the loopback interface and a free port (not 8787, which another cluster may hold).
    with (dask.config.set(LOCAL_HTTP_CONFIG),
          LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                       **LOCAL_CLUSTER_HTTP, silence_logs=logging.ERROR) as cluster,
          Client(cluster) as cl):
        yield cl


def _drive(spec, path, done, sums, todo, client, progress) -> SweepRun:
    from distributed import as_completed
    from tqdm import tqdm

    already = spec.n_chunks - len(todo)
    tag = uuid.uuid4().hex[:8]
    t_start = time.perf_counter()
    group = _open_group(path)
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
            _write_chunk(spec, path, i, result, group)
            done[i] = 1
            sums[i] = _checksum(spec, result)
            _write_done(path, done, sums, group)  # after the data: a kill in between loses this chunk only
            fut.release()
            computed += 1
            bar.update(1)
    finally:
        bar.close()
        for f in futures:
            if not f.done():
                f.cancel()
    return SweepRun(path, spec.n_chunks, already, computed, time.perf_counter() - t_start)
