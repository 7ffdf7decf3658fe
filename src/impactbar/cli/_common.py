"""Pieces every subcommand shares: options given on the command line, refusing the ones a mode
ignores or that conflict, JSON output, progress bars, and hints for missing optional dependencies.

Conventions of the whole command line (documented on the docs site, "Getting started"):

- Bad input is one line on stderr, ``impactbar COMMAND: error: ...``, and exit status 2; that
  includes an option the chosen mode would ignore (``--R`` with ``--preset``) and options that
  conflict.
- JSON output is strict JSON: a non-finite number (an infinite clearance, a NaN statistic) is
  written as ``null``; numpy scalars become plain numbers.
- Every output location (``--out``) and every size-like option (``--dpi``) is checked before any
  computing (:func:`output_folder`, :func:`output_file`, :func:`check_dpi`): a location that cannot
  be written is bad input, one line and exit status 2.
- A missing optional dependency is one line naming the extra to install, exit status 1; the extras
  a subcommand will need are checked before it computes (:func:`require`).
- A write that fails (a full disk, ``OSError``) is one line and exit status 1.
- A reader that closes the pipe early (``impactbar orbits --json | head``), or a closed stdout, ends
  the command quietly with exit status 141; Ctrl-C is one line and exit status 130.
- Progress bars go to stderr, only when it is a terminal, and never with ``--quiet``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import sys
import tempfile
from collections.abc import Iterable
from pathlib import Path

__all__ = ["UsageError", "given", "refuse", "refuse_together", "json_ready", "print_json",
           "progress_bar", "add_quiet_argument", "explicit_options", "OPTIONAL_EXTRAS",
           "missing_dependency_hint", "docs_page", "output_folder", "output_file", "check_dpi",
           "require", "MAX_DPI", "add_figure_arguments"]

#: optional top-level modules -> the extra that installs them
OPTIONAL_EXTRAS = {
    "matplotlib": "plot",
    "pint": "units",
    "xarray": "data",
    "dask": "distributed",
    "distributed": "distributed",
    "zarr": "distributed",
}

#: Largest ``--dpi``: a figure of about 8 x 6 inches at 1200 dpi is some 70 megapixels, the most a
#: raster image can usefully hold; beyond, rendering runs out of memory (``MemoryError``).
MAX_DPI = 1200

#: attribute of the parsed namespace holding the destinations given on the command line
_GIVEN = "_impactbar_given"


class UsageError(ValueError):
    """An option the chosen mode ignores, or options that conflict (exit status 2)."""


def docs_page(title: str) -> str:
    """How help texts point at a page of the documentation site (an installed package has no
    ``docs/`` folder): ``"the impactbar documentation, page 'TITLE'"``."""
    return f"the impactbar documentation, page '{title}'"


def explicit_options(parser: argparse.ArgumentParser, argv: list[str]) -> frozenset[str]:
    """The destinations of the options that ``argv`` gives explicitly to ``parser``.

    Parses ``argv`` again with every default suppressed, so an option given with its default value
    still counts as given (``--R 0.5``), and abbreviations (``--pres``) are resolved as argparse
    resolves them.
    """
    saved = [(a, a.default) for a in parser._actions]
    saved_defaults = dict(parser._defaults)
    try:
        for a, _ in saved:
            a.default = argparse.SUPPRESS
        parser._defaults.clear()
        ns, _ = parser.parse_known_args(argv, argparse.Namespace())
    finally:
        for a, d in saved:
            a.default = d
        parser._defaults.update(saved_defaults)
    return frozenset(vars(ns))


class _DeprecatedAlias(argparse.Action):
    """The old spelling of an option: stores its value apart (hidden from ``--help``);
    :func:`resolve_deprecated` moves it to the new option with a warning."""

    def __init__(self, option_strings, dest, *, new: str, new_dest: str, **kwargs):
        super().__init__(option_strings, dest, help=argparse.SUPPRESS, **kwargs)
        self.new, self.new_dest = new, new_dest

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, True if self.nargs == 0 else values)


def add_deprecated_alias(parser, old: str, new: str, new_dest: str, *, flag: bool = False,
                         **kwargs) -> None:
    """Keep ``old`` working as a deprecated spelling of the option ``new`` (destination
    ``new_dest``): given, it sets ``new_dest`` and :func:`resolve_deprecated` prints
    ``warning: OLD is deprecated; use NEW``; given with ``new`` it is refused. ``flag``: a switch
    without a value; ``kwargs`` (``type``, ``metavar``) as for ``add_argument``."""
    dest = "_deprecated_" + old.lstrip("-").replace("-", "_")
    parser.add_argument(old, dest=dest, default=None, action=_DeprecatedAlias, new=new,
                        new_dest=new_dest, nargs=0 if flag else None, **kwargs)


def resolve_deprecated(parser: argparse.ArgumentParser, args: argparse.Namespace,
                       command: str) -> None:
    """Move the values of the deprecated spellings given (:func:`add_deprecated_alias`) to their
    new options, one warning line each on stderr.

    Raises
    ------
    UsageError
        The old and the new spelling given together.
    """
    for a in parser._actions:
        if not isinstance(a, _DeprecatedAlias) or getattr(args, a.dest, None) is None:
            continue
        old = a.option_strings[0]
        if given(args, a.new_dest):
            raise UsageError(f"{a.new} and {old} cannot be used together: {old} is the old name "
                             f"of {a.new}")
        print(f"impactbar {command}: warning: {old} is deprecated; use {a.new}", file=sys.stderr)
        setattr(args, a.new_dest, getattr(args, a.dest))
        record = getattr(args, _GIVEN, None)
        if record is not None:
            setattr(args, _GIVEN, record | {a.new_dest})


def given(args: argparse.Namespace, dest: str) -> bool:
    """Whether the option with destination ``dest`` was given on the command line.

    Without the record :func:`impactbar.cli.main` attaches (a namespace parsed or built elsewhere),
    a default cannot be told from a value given, so nothing counts as given and nothing is refused.
    """
    record = getattr(args, _GIVEN, None)
    return record is not None and dest in record


def _flag(dest: str) -> str:
    return dest if dest in ("config",) else "--" + dest.replace("_", "-")


def refuse(args: argparse.Namespace, dests: Iterable[str], *, because: str) -> None:
    """Refuse the options ``dests`` if any was given, saying ``because`` (the mode that ignores it).

    Raises
    ------
    UsageError
        Naming the first offending option, e.g. ``--R cannot be used with --preset: the hammer's
        stop sets R``.
    """
    bad = [d for d in dests if given(args, d)]
    if bad:
        names = ", ".join(_flag(d) for d in bad)
        verb = "is" if len(bad) == 1 else "are"
        raise UsageError(f"{names} {verb} ignored {because}; drop {'it' if len(bad) == 1 else 'them'}")


def refuse_together(args: argparse.Namespace, first: str, second: str, *, because: str = "") -> None:
    """Refuse two options given together."""
    if given(args, first) and given(args, second):
        tail = f": {because}" if because else ""
        raise UsageError(f"{_flag(first)} and {_flag(second)} cannot be used together{tail}")


def json_ready(obj):
    """``obj`` made strict-JSON ready: non-finite floats become ``None`` (``null``), numpy scalars
    and arrays become Python numbers and lists, tuples become lists."""
    if isinstance(obj, dict):
        return {str(k): json_ready(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_ready(v) for v in obj]
    if hasattr(obj, "tolist") and not isinstance(obj, str):  # numpy arrays and scalars
        obj = obj.tolist()
        if isinstance(obj, list):
            return json_ready(obj)
    if isinstance(obj, complex):
        return [json_ready(obj.real), json_ready(obj.imag)]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def load_record(load) -> dict:
    """A load as JSON-ready structured data: its record (``load.params.record()``), ``{"kind": ...,
    <its constructor's parameters>}``, the kinds and field names of a sweep spec's ``[load]``; for
    an object the table of loads does not know, its class name as ``kind`` and its ``repr``.

    Examples
    --------
    >>> from impactbar import SquareWaveLoad
    >>> from impactbar.cli._common import load_record
    >>> load_record(SquareWaveLoad(1.0, 1.2)) == SquareWaveLoad(1.0, 1.2).params.record()
    True
    """
    if getattr(load, "traits", None) is not None and load.traits.kind:
        return json_ready(load.params.record())
    return {"kind": type(load).__name__, "repr": repr(load)}


def print_json(doc, *, file=None) -> None:
    """Print ``doc`` as indented strict JSON (see :func:`json_ready`)."""
    print(json.dumps(json_ready(doc), indent=2, allow_nan=False), file=file or sys.stdout)


def add_quiet_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--quiet`` (no progress bar)."""
    parser.add_argument("--quiet", action="store_true", help="no progress bar on stderr")


def progress_bar(total: int, *, desc: str, unit: str, quiet: bool = False):
    """A tqdm progress bar on stderr; disabled with ``quiet`` or when stderr is not a terminal."""
    from tqdm import tqdm

    enabled = not quiet and hasattr(sys.stderr, "isatty") and sys.stderr.isatty()
    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, disable=not enabled,
                leave=False, dynamic_ncols=True)


class _Stages:
    """The bar :func:`stage_bar` returns: ``stage(name)`` finishes the current stage and names the
    next; a thread refreshes the elapsed time while a stage runs."""

    def __init__(self, bar, interval: float):
        import threading

        self.bar = bar
        self._stop = threading.Event()
        self._thread = None
        if not bar.disable:
            self._thread = threading.Thread(target=self._tick, args=(interval,), daemon=True)
            self._thread.start()

    def _tick(self, interval):
        while not self._stop.wait(interval):
            self.bar.refresh()

    def stage(self, name: str, *, done: bool = True) -> None:
        """Finish the stage running (``done``) and show ``name`` as the one now running."""
        if done:
            self.bar.update(1)
        self.bar.set_postfix_str(name, refresh=True)

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        self.bar.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def stage_bar(total: int, *, desc: str, first: str, quiet: bool = False,
              interval: float = 0.5) -> _Stages:
    """A progress bar on stderr over the ``total`` stages of a computation that reports nothing
    while a stage runs (a simulation, a continuation): the stages done, the one running (``first``
    to begin with) and the time elapsed, refreshed every ``interval`` seconds. Disabled with
    ``quiet`` or when stderr is not a terminal, as :func:`progress_bar`."""
    bar = progress_bar(total, desc=desc, unit="stage", quiet=quiet)
    bar.bar_format = "{desc}: {n_fmt}/{total_fmt} stages done{postfix} [{elapsed}]"  # no rate, no ETA
    out = _Stages(bar, interval)
    out.stage(first, done=False)
    return out


def missing_dependency_hint(exc: ImportError) -> str | None:
    """The one-line hint for an optional dependency that is not installed, or ``None``."""
    name = (getattr(exc, "name", None) or "").split(".")[0]
    if name in OPTIONAL_EXTRAS:
        extra = OPTIONAL_EXTRAS[name]
        return f"this needs {name}, which is not installed: pip install 'impactbar[{extra}]'"
    msg = str(exc)
    if "pip install 'impactbar[" in msg:  # the library's own hint
        return msg.splitlines()[0]
    return None


def output_folder(path, *, option: str = "--out") -> Path:
    """Check, before any computing, that the folder ``path`` can be written; create it if missing.

    Parameters
    ----------
    path : str or os.PathLike
        The folder the subcommand will write into.
    option : str
        The option that named it, for the message.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    UsageError
        ``path`` is a file, lies under a file, or cannot be created or written (a read-only or
        virtual file system, no permission); the message names the option and the reason.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from impactbar.cli._common import output_folder
    >>> tmp = pathlib.Path(tempfile.mkdtemp())
    >>> output_folder(tmp / "figures").is_dir()
    True
    >>> _ = (tmp / "notes.txt").write_text("a file")
    >>> output_folder(tmp / "notes.txt" / "figures")
    Traceback (most recent call last):
    ...
    impactbar.cli._common.UsageError: --out ...: cannot write there (Not a directory)
    """
    if not str(path).strip():  # Path("") is the working directory: never meant
        raise UsageError(f"{option}: an empty path; give a folder")
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise UsageError(f"{option} {path}: exists and is not a folder")
    try:
        p.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=p):  # writable: not read-only, not a virtual file system
            pass
    except OSError as exc:
        raise UsageError(f"{option} {path}: cannot write there ({exc.strerror or exc})") from None
    return p


def output_file(path, *, option: str = "--out") -> Path:
    """Check, before any computing, that the file ``path`` can be written (its folder is created if
    missing, as by :func:`output_folder`; an existing file is replaced).

    Raises
    ------
    UsageError
        ``path`` is a folder, its folder cannot be written, or it is a file that cannot be replaced.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from impactbar.cli._common import output_file
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     output_file(pathlib.Path(tmp) / "new" / "fig.png").parent.is_dir()
    True
    """
    if not str(path).strip():
        raise UsageError(f"{option}: an empty path; give a file name")
    p = Path(path)
    if p.is_dir():
        raise UsageError(f"{option} {path}: is a folder; give a file name")
    output_folder(p.parent, option=f"{option} {path}: the folder")
    if p.exists() and not os.access(p, os.W_OK):
        raise UsageError(f"{option} {path}: the file exists and cannot be replaced (no permission)")
    return p


def check_dpi(dpi, *, option: str = "--dpi") -> int:
    """Refuse a resolution outside ``[1, MAX_DPI]`` before anything is drawn.

    Raises
    ------
    UsageError

    Examples
    --------
    >>> from impactbar.cli._common import check_dpi
    >>> check_dpi(150)
    150
    """
    if not 1 <= dpi <= MAX_DPI:
        raise UsageError(f"{option} must be in [1, {MAX_DPI}] dots per inch; got {dpi}")
    return int(dpi)


def add_figure_arguments(parser: argparse.ArgumentParser, *, dpi: int) -> None:
    """Add ``--dpi`` (checked by :func:`check_dpi`) and ``--format png|pdf|svg`` for the figures."""
    parser.add_argument("--dpi", type=int, default=dpi,
                        help=f"resolution of raster figures, 1 to {MAX_DPI} (default {dpi})")
    parser.add_argument("--format", choices=("png", "pdf", "svg"), default="png",
                        help="file format of the figures (default png)")


def require(*modules: str) -> None:
    """Check, before any computing, that the optional ``modules`` are installed.

    Raises
    ------
    ModuleNotFoundError
        For the first missing one, with its ``name`` (the command line turns it into the one-line
        hint of :func:`missing_dependency_hint`, exit status 1).
    """
    for name in modules:
        if importlib.util.find_spec(name) is None:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
