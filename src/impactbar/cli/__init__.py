"""Command-line interface: ``impactbar SUBCOMMAND ...``.

Each subcommand lives in its own module ``impactbar.cli.<name>`` exposing
``add_parser(subparsers)`` (which registers the parser and sets ``func``); this file only
dispatches, so features can be added without touching each other. What every subcommand shares
(refusing options a mode ignores, JSON output, progress bars) is in ``impactbar.cli._common``.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import sys

from . import _common
from ._compiling import compile_note

__all__ = ["main"]

#: subcommand modules, in the order ``--help`` lists them
SUBCOMMANDS = ("paper", "orbits", "drifter", "continue_", "optimize", "experiment", "simulate", "sweep",
               "plot", "measure", "warmup")


class _OneLineParser(argparse.ArgumentParser):
    """A parser whose refusals (an unknown option, an invalid choice, options of a mutually
    exclusive group together, a required one missing) are one line on stderr with exit status 2,
    as every other bad input's, and say where the usage is; its subcommands' parsers are of this
    class too (``add_subparsers`` makes them so)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message}; see '{self.prog} --help'\n")


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every available subcommand registered."""
    from .._version import __version__

    parser = _OneLineParser(
        prog="impactbar",
        description="Impact vibration of an elastic bar (Bjorkenstam 1977): periodic impacting "
        "motions, their stability, simulation from any start.",
    )
    parser.add_argument("--version", action="version", version=f"impactbar {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMANDS:
        try:
            mod = importlib.import_module(f"impactbar.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"impactbar.cli.{name}":
                continue  # that feature is not installed in this build
            raise
        mod.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status.

    0 on success; 2 for bad input (one line on stderr: a value out of range, an option the chosen
    mode ignores, options that conflict, an output location that cannot be written, all checked
    before any computing); 1 when an optional dependency is missing (one line naming the extra to
    install) or a write fails (a full disk); 141 when the reader closed the pipe (``impactbar orbits
    --json | head``) or stdout is closed, as for other Unix tools ended by SIGPIPE, without a trace;
    130 on Ctrl-C, with one line.

    Examples
    --------
    >>> from impactbar.cli import main
    >>> main(["paper", "--dpi", "5000"])  # one line on stderr, before any computing
    2
    """
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    sub = _subparser(parser, args.command)
    if sub is not None:
        tail = argv[argv.index(args.command) + 1:] if args.command in argv else argv
        setattr(args, _common._GIVEN, _common.explicit_options(sub, tail))
    closed = sys.stdout is None  # started with stdout closed (``impactbar orbits >&-``)
    if closed:
        sys.stdout = _ClosedStdout()
    ctrl_c = _CtrlC()
    try:
        try:
            if sub is not None:
                _common.resolve_deprecated(sub, args, args.command)
            from ..physical.plausibility import warnings_once  # (an implausible value: one line, once)
            with ctrl_c, compile_note(name := f"impactbar {args.command}"), warnings_once(name):
                status = int(args.func(args) or 0)
            if ctrl_c.pressed:  # an interrupt that a library's compiled code swallowed
                raise KeyboardInterrupt
            sys.stdout.flush()  # a closed pipe or a full disk shows here, not at interpreter exit
            return status
        except Exception as exc:
            # an interrupt that a library turned into another error (matplotlib's drawing: a
            # ValueError; Python 3.11's __set_name__ during an import: a RuntimeError)
            if ctrl_c.pressed or isinstance(exc.__cause__, KeyboardInterrupt):
                raise KeyboardInterrupt from exc
            raise
    except BrokenPipeError:
        _silence_stdout()  # Python's own flush at exit would fail again
        return 141
    except KeyboardInterrupt:
        print(f"impactbar {args.command}: interrupted", file=sys.stderr)
        return 130
    except ValueError as exc:
        print(f"impactbar {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except ImportError as exc:
        hint = _common.missing_dependency_hint(exc)
        if hint is None:
            raise
        print(f"impactbar {args.command}: error: {hint}", file=sys.stderr)
        return 1
    except OSError as exc:  # a write that failed: a full disk, a file system gone read-only
        where = f": {exc.filename}" if getattr(exc, "filename", None) else ""
        print(f"impactbar {args.command}: error: {exc.strerror or exc}{where}", file=sys.stderr)
        _silence_stdout()
        return 1
    finally:
        if closed:
            sys.stdout = None


class _CtrlC:
    """While a command runs, Ctrl-C is remembered as well as raised (Python's own handler only
    raises): a library's compiled code may swallow the KeyboardInterrupt, or turn it into another
    error, and the command still ends as interrupted. Installed only over Python's default
    handler, in the main thread. A KeyboardInterrupt raised inside a C callback (numba's compiler
    caching an object through llvmlite's ctypes callback) cannot propagate: CPython reports it as
    "Exception ignored ..." with a traceback; after a Ctrl-C that report is dropped (the command
    ends as interrupted), any other goes to the hook as before. So is, after a Ctrl-C and until
    the process ends, the failure of a ``__del__`` (an object whose construction the interrupt cut
    short, collected later: pyparsing's ``Forward`` while matplotlib imports, at the interpreter's
    exit)."""

    def __init__(self):
        self.pressed = False
        self._old = None
        self._hook = None

    def _handler(self, signum, frame):
        self.pressed = True
        raise KeyboardInterrupt

    def _unraisable(self, unraisable):
        if self.pressed and (isinstance(unraisable.exc_value, KeyboardInterrupt) or _in_del(unraisable)):
            return
        self._hook(unraisable)

    def __enter__(self):
        import signal
        import threading

        if threading.current_thread() is threading.main_thread() and \
                signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            self._old = signal.signal(signal.SIGINT, self._handler)
            self._hook, sys.unraisablehook = sys.unraisablehook, self._unraisable
        return self

    def __exit__(self, *exc):
        if self._old is not None:
            import signal

            signal.signal(signal.SIGINT, self._old)
            hook = self._hook
            # (after a Ctrl-C, the half-built objects' __del__ failures are dropped to the end)
            sys.unraisablehook = hook if not self.pressed else \
                (lambda u: None if _in_del(u) else hook(u))
        return False


def _in_del(unraisable) -> bool:
    """Whether ``sys.unraisablehook``'s report is of an exception in a ``__del__``."""
    return getattr(unraisable.object, "__name__", None) == "__del__"


class _ClosedStdout:
    """Stands in for a closed stdout: the first write is a closed pipe (exit status 141)."""

    def write(self, text):
        raise BrokenPipeError(errno.EPIPE, "stdout is closed")

    def flush(self):
        pass


def _silence_stdout() -> None:
    """Point stdout at the null device, so that the interpreter's flush at exit cannot fail again."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def _subparser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser | None:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices.get(command)
    return None


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
