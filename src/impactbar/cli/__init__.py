"""Command-line interface: ``impactbar SUBCOMMAND ...``.

Each subcommand lives in its own module ``impactbar.cli.<name>`` exposing
``add_parser(subparsers)`` (which registers the parser and sets ``func``); this file only
dispatches, so features can be added without touching each other. What every subcommand shares
(refusing options a mode ignores, JSON output, progress bars) is in ``impactbar.cli._common``.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from . import _common

__all__ = ["main"]

#: subcommand modules, in the order ``--help`` lists them
SUBCOMMANDS = ("paper", "orbits", "continue_", "experiment", "simulate", "sweep", "plot")


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every available subcommand registered."""
    from .._version import __version__

    parser = argparse.ArgumentParser(
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
    mode ignores, options that conflict); 1 when an optional dependency is missing (one line naming
    the extra to install); 141 when the reader closed the pipe (``impactbar orbits --json | head``),
    as for other Unix tools ended by SIGPIPE, without a trace.
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
    try:
        status = int(args.func(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, not at interpreter exit
        return status
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # Python's own flush at exit would fail again
        return 141
    except ValueError as exc:
        print(f"impactbar {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except ImportError as exc:
        hint = _common.missing_dependency_hint(exc)
        if hint is None:
            raise
        print(f"impactbar {args.command}: error: {hint}", file=sys.stderr)
        return 1


def _subparser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser | None:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices.get(command)
    return None


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
