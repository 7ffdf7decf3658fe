"""A one-line note on stderr while numba compiles kernels for long (the first run on a machine).

numba compiles each kernel on its first use and caches it on disk; a first run can spend seconds
to tens of seconds there with nothing on the terminal. :func:`compile_note` watches numba's compile
events and, once kernels have been compiling for ``after`` seconds, prints one line (once per
process). Nothing is printed when every kernel comes from the cache.
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time

__all__ = ["compile_note"]


@contextlib.contextmanager
def compile_note(prog: str = "impactbar", *, after: float = 2.0, stream=None):
    """Print ``"<prog>: compiling kernels (...)..."`` to ``stream`` (stderr) if numba compiles for
    more than ``after`` seconds (wall time) inside the block.

    Parameters
    ----------
    prog : str
        The name the line starts with.
    after : float
        Seconds of compiling before the note, > 0.
    stream : file-like, optional
        Where the note goes; ``sys.stderr`` (looked up when the note is printed) by default.

    Examples
    --------
    >>> import io
    >>> out = io.StringIO()
    >>> with compile_note(stream=out):
    ...     pass
    >>> out.getvalue()
    ''
    """
    if not after > 0.0:
        raise ValueError(f"after must be > 0 seconds, got {after!r}")
    try:
        from numba.core import event
    except ImportError:  # pragma: no cover - numba is a dependency; nothing to watch without it
        yield
        return
    watch = type("CompileWatch", (_Watch, event.Listener), {})(prog, after, stream)
    event.register("numba:compile", watch)
    try:
        yield
    finally:
        event.unregister("numba:compile", watch)
        watch.stop()


class _Watch:
    """numba compile-event listener: a timer runs while the outermost compile is in progress."""

    def __init__(self, prog, after, stream):
        self.prog, self.after, self.stream = prog, after, stream
        self.depth = 0
        self.spent = 0.0  # seconds spent compiling so far (outermost compiles)
        self.since = 0.0
        self.timer = None
        self.said = False
        self.lock = threading.Lock()

    # numba.core.event.Listener's methods (mixed in with it when the note is wanted, so that this
    # module imports numba only then)
    def on_start(self, ev=None):
        with self.lock:
            self.depth += 1
            if self.depth == 1 and not self.said:
                self.since = time.perf_counter()
                self.timer = threading.Timer(max(self.after - self.spent, 0.0), self._say)
                self.timer.daemon = True
                self.timer.start()

    def on_end(self, ev=None):
        with self.lock:
            self.depth = max(self.depth - 1, 0)
            if self.depth == 0 and self.timer is not None:
                self.timer.cancel()
                self.timer = None
                self.spent += time.perf_counter() - self.since

    def _say(self):
        with self.lock:
            if self.said or self.depth == 0:
                return
            self.said = True
        stream = self.stream if self.stream is not None else sys.stderr
        try:
            print(f"{self.prog}: compiling kernels (first run on this machine only, usually 10-40 s; "
                  "cached afterwards)...", file=stream, flush=True)
        except (OSError, ValueError):  # pragma: no cover - stderr closed
            pass

    def stop(self):
        with self.lock:
            if self.timer is not None:
                self.timer.cancel()
                self.timer = None
