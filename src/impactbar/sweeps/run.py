"""Running a sweep on ``dask.distributed`` (or, for cheap closed-form work, in threads of the
driver): farm out chunks, write each as it arrives, resume."""

from __future__ import annotations

import contextlib
import os
import sys
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._shared.validate import check_int, check_real
from .numba_cache import cache_folder, use_numba_cache
from .spec import SweepSpec, closed_form_task
from .store import _checksum, _open_group, _prepare_store, _write_chunks, _write_done
from .tasks import compute_chunk

#: where :func:`run_sweep` computes the chunks without a ``client`` or ``scheduler``
EXECUTORS = ("auto", "threads", "dask")

#: How long :func:`run_sweep` waits for a ``scheduler`` to answer
CONNECT_TIMEOUT = "10s"
#: what :func:`run_sweep` does when its cluster has had no worker for ``worker_timeout`` seconds
NO_WORKERS = ("wait", "stop")
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
              n_workers: int | None = None, overwrite: bool = False, progress: bool = True,
              executor: str = "auto", worker_timeout: float | None = 60.0,
              no_workers: str = "wait", numba_cache=None) -> SweepRun:
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
        Workers computing chunks at once when neither ``client`` nor ``scheduler`` is given:
        processes of one thread each in a local cluster, or threads of this process (see
        ``executor``); default the number of cores.
    overwrite : bool, optional
        Replace a store holding another sweep (or one from another impactbar version).
    progress : bool, optional
        Show a progress bar (chunks done, rate, time left) on stderr.
    executor : {"auto", "threads", "dask"}, optional
        Where the chunks are computed when neither ``client`` nor ``scheduler`` is given:
        ``"dask"``, a local ``dask.distributed`` cluster of ``n_workers`` processes; ``"threads"``,
        ``n_workers`` threads of this process, without dask (for cheap work: the threads share one
        interpreter); ``"auto"`` (default), threads for a sweep whose every point takes the rigid
        bar's vectorised closed forms (:func:`impactbar.sweeps.spec.closed_form_task`, where
        starting a cluster costs more than the whole work), a local cluster otherwise. The store,
        its checksums, flags and lock, resumption and the progress bar are the same either way.
    worker_timeout : float or None, optional
        On a dask cluster: when it has had no worker for this many seconds (the last one died or
        left) while chunks remain, say so on stderr (one line: the time, the chunks left, what
        happens next), and again when workers are back; ``None``: never. Default 60 s, ``> 0``.
    no_workers : {"wait", "stop"}, optional
        What follows that message: ``"wait"`` (default) keeps waiting for workers to join;
        ``"stop"`` cancels the chunks left and raises :class:`NoWorkersError` (the chunks finished
        are stored; rerunning resumes).
    numba_cache : str or os.PathLike, optional
        A numba cache folder the dask workers share, filled once by ``NUMBA_CACHE_DIR=FOLDER
        impactbar warmup``: the workers load their kernels from it instead of each compiling them
        (a local cluster's workers start with ``NUMBA_CACHE_DIR`` set; a ``client``'s or
        ``scheduler``'s restart with it, :func:`impactbar.sweeps.use_numba_cache`). Not for a
        sweep computed in threads of this process (set ``NUMBA_CACHE_DIR`` before starting Python).

    Returns
    -------
    SweepRun

    Raises
    ------
    ValueError
        If the store holds another sweep and ``overwrite`` is false, ``store`` is a file or a
        folder that is not a sweep store, its folder cannot be written, another driver holds the
        store's lock, ``scheduler`` does not answer within ``CONNECT_TIMEOUT``, ``n_workers``
        is outside ``[1, max_workers()]``, or ``executor`` is unknown or ``"threads"`` with a
        ``client`` or ``scheduler``, or ``worker_timeout`` or ``no_workers`` is out of range, or
        ``numba_cache`` is not a folder path or is given for a sweep computed in threads;
        nothing is computed (or left behind) then.
    NoWorkersError
        With ``no_workers="stop"``, when the cluster has had no worker for ``worker_timeout``
        seconds.

    Notes
    -----
    On resume every chunk flagged done is read back and checked against its stored CRC-32; a
    missing, truncated or corrupted chunk is recomputed.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from impactbar import CosineLoad, run_sweep  # a zarr store: needs xarray and zarr (extra distributed)
    >>> from impactbar.sweeps import parse_spec
    >>> load = CosineLoad(p0=0.5, pk=1.0, k=1)
    >>> spec = parse_spec({"task": "orbits", "load": load.params.record(),
    ...                    "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
    ...                    "axes": {"R": {"start": 0.0, "stop": 0.9, "num": 10}}})
    >>> run = run_sweep(spec, pathlib.Path(tempfile.mkdtemp()) / "r.zarr", progress=False)
    >>> run.complete, run.computed  # the rigid closed forms: in threads of this process, no cluster
    (True, 1)
    """
    if not isinstance(spec, SweepSpec):
        raise ValueError(f"spec must be a SweepSpec; got {type(spec).__name__}")
    if sum(x is not None for x in (client, scheduler, n_workers)) > 1:
        raise ValueError("give at most one of client, scheduler, n_workers")
    if n_workers is not None:
        n_workers = check_int("n_workers", n_workers, lo=1, hi=max_workers())
    if executor not in EXECUTORS:
        raise ValueError(f"executor must be one of {EXECUTORS}; got {executor!r}")
    if worker_timeout is not None:
        worker_timeout = check_real("worker_timeout", worker_timeout, lo=0.0, lo_open=True)
    if no_workers not in NO_WORKERS:
        raise ValueError(f"no_workers must be one of {NO_WORKERS}; got {no_workers!r}")
    remote = client is not None or scheduler is not None
    if executor == "threads" and remote:
        raise ValueError("executor='threads' computes in this process; it takes no client or scheduler")
    threads = not remote and (executor == "threads" or (executor == "auto" and closed_form_task(spec)))
    if numba_cache is not None:
        if threads:
            raise ValueError("numba_cache sets a dask cluster's workers' numba cache; this sweep is "
                             "computed in threads of this process (set NUMBA_CACHE_DIR before starting "
                             "Python instead)")
        numba_cache = cache_folder(numba_cache)
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
            if client is None and not threads:
                client = stack.enter_context(_connect(scheduler, n_workers, numba_cache))
            elif client is not None and numba_cache is not None:  # the caller's own client
                use_numba_cache(client, numba_cache)
            if not resume:
                done, sums = _prepare_store(spec, path, overwrite)
            todo = [int(i) for i in np.flatnonzero(done == 0)]
            if threads:
                results = _thread_results(spec, todo, default_workers() if n_workers is None else n_workers)
            else:
                watchdog = None if worker_timeout is None else _WorkerWatchdog(
                    lambda: _count_workers(client), worker_timeout, no_workers)
                results = _dask_results(spec, todo, client, watchdog)
            return _drive(spec, path, done, sums, todo, results, progress)
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
def _connect(scheduler, n_workers, numba_cache=None):
    """A ``distributed.Client``: to ``scheduler``, or to a local cluster of ``n_workers``; its workers
    with the numba cache folder ``numba_cache`` if given."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            cl = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            raise ValueError(f"--scheduler {scheduler!r}: cannot connect within "
                             f"{CONNECT_TIMEOUT} ({exc})") from None
        with cl:
            if numba_cache is not None:
                use_numba_cache(cl, numba_cache)
            yield cl
        return
    import logging

    import dask

    n = default_workers() if n_workers is None else n_workers
    env = {} if numba_cache is None else {"env": {"NUMBA_CACHE_DIR": numba_cache}}
    # No dashboard: distributed always starts an HTTP server in the scheduler, so it gets no routes,
    # the loopback interface and a free port (not 8787, which another cluster may hold).
    with (dask.config.set(LOCAL_HTTP_CONFIG),
          LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                       **LOCAL_CLUSTER_HTTP, silence_logs=logging.ERROR,
                       **env) as cluster,
          Client(cluster) as cl):
        yield cl


def _drive(spec, path, done, sums, todo, results, progress) -> SweepRun:
    """Store the chunks as ``results`` (a generator of lists of ``(chunk, data)``: the chunks
    finished since the last list, in any order) yields them: their data, then their checksums and
    flags; the generator is closed (its pending work cancelled) however this ends."""
    from tqdm import tqdm

    already = spec.n_chunks - len(todo)
    t_start = time.perf_counter()
    group = _open_group(path)
    computed = 0
    bar = tqdm(total=len(todo), unit="chunk", file=sys.stderr, disable=not progress,
               desc=f"{spec.task} ({already}/{spec.n_chunks} stored before)", smoothing=0.1)
    try:
        with contextlib.closing(results):
            for batch in results:  # a task error propagates; every finished chunk is stored
                _write_chunks(spec, path, batch, group)
                for i, result in batch:
                    done[i] = 1
                    sums[i] = _checksum(spec, result)
                # after the data: a kill in between loses these chunks only
                _write_done(path, done, sums, group)
                computed += len(batch)
                bar.update(len(batch))
    finally:
        bar.close()
    return SweepRun(path, spec.n_chunks, already, computed, time.perf_counter() - t_start)


def _dask_results(spec, todo, client, watchdog=None):
    """The chunks ``todo`` computed on a dask cluster: lists of ``(chunk, data)``, each list the
    chunks that finished since the previous one; ``watchdog`` (a :class:`_WorkerWatchdog`) watches
    the workers meanwhile."""
    from distributed import as_completed

    tag = uuid.uuid4().hex[:8]
    futures = [client.submit(compute_chunk, spec, i, key=f"impactbar-{spec.task}-{tag}-{i}",
                             pure=False) for i in todo]
    chunk_of = {f.key: i for f, i in zip(futures, todo, strict=True)}
    left = [len(futures)]
    if watchdog is not None:
        watchdog.pending = lambda: left[0]
        watchdog.on_stop = lambda: client.cancel([f for f in futures if not f.done()])
        watchdog.start()
    try:
        for finished in as_completed(futures).batches():
            left[0] -= len(finished)
            yield from _finished_batches([(chunk_of[fut.key], fut) for fut in finished])
            for fut in finished:
                fut.release()
        if watchdog is not None and watchdog.stopped:
            raise NoWorkersError(watchdog.message)
    except BaseException:
        if watchdog is not None and watchdog.stopped:
            raise NoWorkersError(watchdog.message) from None
        raise
    finally:
        if watchdog is not None:
            watchdog.close()
        for f in futures:
            if not f.done():
                f.cancel()


class NoWorkersError(RuntimeError):
    """A sweep stopped because its dask cluster had no worker for ``worker_timeout`` seconds
    (``run_sweep(..., no_workers="stop")``); the chunks finished are stored."""


def _count_workers(client) -> int:
    """Workers connected to ``client``'s scheduler (0 when the scheduler does not answer)."""
    try:
        return len(client.nthreads())
    except Exception:  # noqa: BLE001 - a scheduler gone counts as no worker
        return 0


class _WorkerWatchdog:
    """Says on stderr when a cluster has had no worker for ``timeout`` seconds while chunks wait,
    and again when workers are back; with ``action="stop"`` it then calls ``on_stop`` (which
    cancels the chunks left) and sets ``stopped``.

    ``check(now)`` is the whole logic (a clock value in, the line printed, if any, out); a daemon
    thread calls it every ``poll`` seconds between :meth:`start` and :meth:`close`.
    """

    def __init__(self, count_workers, timeout: float, action: str = "wait", *, poll: float = 1.0,
                 out=None):
        self.count_workers, self.timeout, self.action, self.poll = count_workers, timeout, action, poll
        self.out = out
        self.pending = lambda: 0
        self.on_stop = lambda: None
        self.since = None  # when the workers were first seen gone
        self.warned = False
        self.stopped = False
        self.message = ""
        self._thread = None
        self._event = None

    def check(self, now: float) -> str | None:
        """Look at the workers once at clock ``now`` (s); returns the line printed, if any."""
        if self.stopped:
            return None
        n = self.count_workers()
        if n > 0:
            line = None
            if self.warned:
                line = f"impactbar sweep: {n} worker(s) back; the sweep goes on"
                self._say(line)
            self.since, self.warned = None, False
            return line
        if self.since is None:
            self.since = now
            return None
        waited = now - self.since
        if waited < self.timeout or self.warned:
            return None
        self.warned = True
        head = (f"impactbar sweep: warning: no worker for {waited:.0f} s (timeout {self.timeout:g} s); "
                f"{self.pending()} chunk(s) left")
        if self.action == "stop":
            self.stopped = True
            self.message = (f"no worker for {waited:.0f} s: stopped; the chunks finished are stored, "
                            "rerun the same command to resume")
            self._say(head + "; stopping")
            self.on_stop()
            return head + "; stopping"
        self._say(head + "; still waiting for workers (Ctrl-C stops; rerunning resumes)")
        return head + "; still waiting for workers (Ctrl-C stops; rerunning resumes)"

    def _say(self, line: str) -> None:
        print(line, file=self.out or sys.stderr, flush=True)

    def start(self) -> None:
        import threading

        self._event = threading.Event()

        def loop():
            while not self._event.wait(self.poll):
                self.check(time.monotonic())

        self._thread = threading.Thread(target=loop, name="impactbar-sweep-watchdog", daemon=True)
        self._thread.start()

    def close(self) -> None:
        if self._thread is not None:
            self._event.set()
            self._thread.join()
            self._thread = None


def _thread_results(spec, todo, n_threads):
    """The chunks ``todo`` computed by ``n_threads`` threads of this process: lists of
    ``(chunk, data)``, each list the chunks that finished since the previous one; at most
    ``2 n_threads`` chunks are queued or held at a time."""
    from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

    from .._shared.threads import single_threaded_blas

    pending = {}
    left = iter(todo)
    # one BLAS limit around the whole pool: the threads' own limits (inside the library) then
    # save and restore the same value
    with single_threaded_blas(), ThreadPoolExecutor(n_threads, thread_name_prefix="impactbar-sweep") as pool:
        def fill():
            for i in left:
                pending[pool.submit(compute_chunk, spec, i)] = i
                if len(pending) >= 2 * n_threads:
                    return
        try:
            fill()
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                pairs = [(pending.pop(fut), fut) for fut in finished]
                fill()  # keep the threads busy while these chunks are written
                yield from _finished_batches(pairs)
        finally:
            for fut in pending:
                fut.cancel()


def _finished_batches(pairs):
    """Yield the results of finished futures (``(chunk, future)`` pairs) as one list of
    ``(chunk, data)``, then raise the first task error among them, if any: the chunks that did
    finish are stored before the error stops the sweep."""
    batch, error = [], None
    for chunk, fut in pairs:
        try:
            batch.append((chunk, fut.result()))
        except BaseException as exc:  # a task's error, even KeyboardInterrupt, after the others
            if error is None:
                error = exc
    if batch:
        yield batch
    if error is not None:
        raise error
