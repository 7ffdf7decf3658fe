"""A one-line note on stderr while numba compiles impactbar's kernels for long.

numba compiles each kernel on its first use and caches it on disk; a first run with an empty cache
can spend tens of seconds there with nothing on the terminal, in a script as on the command line.
:func:`watch_compiles`, called once when the kernels' module is imported, listens to numba's
compile events for the whole process: once impactbar's kernels have been compiling for 2 s it
prints one line, once per process, and nothing when every kernel comes from the cache or compiles
quickly. :func:`compile_note` does the same inside a block, under a program's name (the command
line's ``impactbar paper: compiling ...``), and takes the process's one line for itself.

The line goes through ``tqdm.write`` when tqdm is loaded, which clears the progress bars on the
stream, writes the line and draws them again, so that a bar is not broken in two.

The same process-wide listener pauses Python's cyclic garbage collector while impactbar's kernels
compile (:class:`_GcPause`): numba's compiler makes millions of objects, most of them alive until the
compile ends, and the collector walked them again and again, some 12 % of the first exact blow's
compile. The collector runs again once the outermost compile ends (its garbage then collected as
usual), and is left alone where the program had turned it off.
"""

from __future__ import annotations

import contextlib
import gc
import sys
import threading
import time

__all__ = ["compile_note", "watch_compiles", "NOTE"]

#: the note, after the program's name
NOTE = ("compiling numba kernels (first run with this cache, often 10-60 s of CPU time; "
        "later runs load them from the cache)...")

_LOCK = threading.Lock()


class _Process:
    """The note in this process, one instance (:data:`_PROCESS`), written under :data:`_LOCK`:
    ``said`` (the note printed: one line per process), ``blocks`` (the :func:`compile_note` blocks
    running) and ``watching`` (:func:`watch_compiles` registered)."""

    __slots__ = ("said", "blocks", "watching")

    def __init__(self):
        self.said, self.blocks, self.watching = False, 0, False


_PROCESS = _Process()


def _ours(ev) -> bool:
    """Whether a compile event is one of impactbar's kernels (a user's own numba code is not)."""
    data = getattr(ev, "data", None) or {}
    func = getattr(data.get("dispatcher"), "py_func", None)
    return getattr(func, "__module__", "").startswith("impactbar")


class _Outermost:
    """numba compile-event listener: :meth:`_begin` when the outermost compile of one of impactbar's
    kernels starts, :meth:`_finish` when it ends (both under ``self.lock``)."""

    def __init__(self):
        self.depth = 0
        self.lock = threading.Lock()

    # numba.core.event.Listener's methods (mixed in with it when wanted, so that this module imports
    # numba only then)
    def on_start(self, ev=None):
        if ev is not None and not _ours(ev):
            return
        with self.lock:
            self.depth += 1
            if self.depth == 1:
                self._begin()

    def on_end(self, ev=None):
        if ev is not None and not _ours(ev):
            return
        with self.lock:
            self.depth = max(self.depth - 1, 0)
            if self.depth == 0:
                self._finish()


class _Watch(_Outermost):
    """numba compile-event listener: a timer runs while the outermost compile of one of
    impactbar's kernels is in progress, and prints the note when it fires."""

    def __init__(self, prog, after, stream, deferring):
        super().__init__()
        self.prog, self.after, self.stream = prog, after, stream
        self.deferring = deferring  # the process-wide watch: silent while a compile_note block runs
        self.spent = 0.0  # seconds spent compiling so far (outermost compiles)
        self.since = 0.0
        self.timer = None

    def _begin(self):
        if not _PROCESS.said:
            self.since = time.perf_counter()
            self.timer = threading.Timer(max(self.after - self.spent, 0.0), self._say)
            self.timer.daemon = True
            self.timer.start()

    def _finish(self):
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None
            self.spent += time.perf_counter() - self.since

    def _say(self):
        with self.lock:
            if self.depth == 0:
                return
        with _LOCK:
            if _PROCESS.said or (self.deferring and _PROCESS.blocks):
                return
            _PROCESS.said = True
        _write(f"{self.prog}: {NOTE}", self.stream if self.stream is not None else sys.stderr)

    def stop(self):
        with self.lock:
            if self.timer is not None:
                self.timer.cancel()
                self.timer = None


class _GcPause(_Outermost):
    """numba compile-event listener: Python's cyclic garbage collector off while the outermost
    compile of one of impactbar's kernels runs (if it was on), on again when it ends."""

    def __init__(self):
        super().__init__()
        self.paused = False

    def _begin(self):
        if gc.isenabled():
            gc.disable()
            self.paused = True

    def _finish(self):
        if self.paused:
            self.paused = False
            gc.enable()


def _write(line: str, stream) -> None:
    """``line`` on ``stream``, through tqdm's ``write`` when tqdm is loaded (its bars cleared and
    drawn again around it)."""
    tqdm = sys.modules.get("tqdm")
    try:
        if tqdm is not None and hasattr(tqdm, "tqdm"):
            tqdm.tqdm.write(line, file=stream)
            stream.flush()
        else:
            print(line, file=stream, flush=True)
    except (OSError, ValueError):  # pragma: no cover - stderr closed
        pass


def _listener(prog, after, stream, deferring):
    from numba.core import event

    return type("CompileWatch", (_Watch, event.Listener), {})(prog, after, stream, deferring)


def _check_after(after) -> None:
    if not after > 0.0:
        raise ValueError(f"after must be > 0 seconds, got {after!r}")


def watch_compiles(prog: str = "impactbar", *, after: float = 2.0) -> None:
    """Listen, for the rest of the process, to numba's compiles of impactbar's kernels, and print
    ``"<prog>: compiling numba kernels (...)"`` on stderr once they have run for ``after`` seconds
    (wall time), once per process; Python's cyclic garbage collector pauses while they compile
    (:class:`_GcPause`). Called when the kernels are first imported; a second call does nothing.

    Parameters
    ----------
    prog, after : str, float
        As for :func:`compile_note`: the program's name that starts the line, and the seconds of
        compiling before the note.

    Raises
    ------
    ValueError
        ``after`` not positive.
    """
    _check_after(after)
    with _LOCK:
        if _PROCESS.watching:
            return
        _PROCESS.watching = True
    from numba.core import event

    event.register("numba:compile", _listener(prog, after, None, True))
    event.register("numba:compile", type("CompileGcPause", (_GcPause, event.Listener), {})())


@contextlib.contextmanager
def compile_note(prog: str = "impactbar", *, after: float = 2.0, stream=None):
    """Print ``"<prog>: compiling numba kernels (...)"`` to ``stream`` (stderr) if impactbar's
    kernels compile for more than ``after`` seconds (wall time) inside the block; the process-wide
    note of :func:`watch_compiles` keeps silent meanwhile. One line per process in all.

    Parameters
    ----------
    prog : str
        The name the line starts with.
    after : float
        Seconds of compiling before the note, > 0.
    stream : file-like, optional
        Where the note goes; ``sys.stderr`` (looked up when the note is printed) by default.

    Raises
    ------
    ValueError
        ``after`` not positive.

    Examples
    --------
    >>> import io
    >>> out = io.StringIO()
    >>> with compile_note(stream=out):
    ...     pass
    >>> out.getvalue()
    ''
    """
    _check_after(after)
    try:
        from numba.core import event
    except ImportError:  # pragma: no cover - numba is a dependency; nothing to watch without it
        yield
        return
    watch = _listener(prog, after, stream, False)
    event.register("numba:compile", watch)
    with _LOCK:
        _PROCESS.blocks += 1
    try:
        yield
    finally:
        event.unregister("numba:compile", watch)
        watch.stop()
        with _LOCK:
            _PROCESS.blocks -= 1
