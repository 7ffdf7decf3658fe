"""Command-line interface: ``impactbar SUBCOMMAND ...``.

Each subcommand lives in its own module ``impactbar.cli.<name>`` exposing
``add_parser(subparsers)`` (which registers the parser and sets ``func``); this file only
dispatches, so features can be added without touching each other.
"""

from __future__ import annotations

import argparse
import importlib
import sys

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
    """Run the command line; returns the exit status (2 for bad input)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except ValueError as exc:
        print(f"impactbar {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
