"""The benchmarks' shared timers: the median wall time or the least CPU time of a call after one
warm-up call (numba's compilation, caches), and the runs of a script on two package trees in fresh
processes (the scripts' ``--against SRC``). Imported by the scripts of this folder (run as
``python benchmarks/...``)."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np


def _times(fn, repeat: int, clock) -> list:
    """``repeat`` timed calls of ``fn()`` by ``clock`` (seconds each), after one untimed call."""
    fn()
    ts = []
    for _ in range(repeat):
        t0 = clock()
        fn()
        ts.append(clock() - t0)
    return ts


def median_time(fn, repeat: int) -> float:
    """Median of ``repeat`` timed calls of ``fn()`` (wall seconds), after one untimed call."""
    return float(np.median(_times(fn, repeat, time.perf_counter)))


def best_cpu(fn, repeat: int) -> float:
    """The least CPU seconds of ``repeat`` calls of ``fn()``, after one untimed call."""
    return min(_times(fn, repeat, time.process_time))


def ref_tree(ref: str) -> str:
    """The ``src`` of the git ref ``ref`` of this repository, exported by ``git archive`` to a
    temporary folder (the scripts' ``--against REF``)."""
    root = Path(__file__).resolve().parents[1]
    dest = Path(tempfile.mkdtemp(prefix="impactbar-ref-"))
    tar = dest / "src.tar"
    with tar.open("wb") as fh:
        subprocess.run(["git", "-C", str(root), "archive", ref, "src"], stdout=fh, check=True)
    with tarfile.open(tar) as tf:
        tf.extractall(dest, filter="data")
    return str(dest / "src")


def fresh_runs(script, src, rounds: int = 3, args=()) -> dict:
    """``script --json`` (its last line of output a JSON object; ``args`` after it) on the package
    tree ``src`` and on this one, in fresh processes, alternately: ``{"baseline": [...], "new":
    [...]}``, ``rounds`` objects each."""
    script = Path(script).resolve()
    runs = {"baseline": [], "new": []}
    for _ in range(rounds):
        for name, path in (("baseline", str(src)), ("new", str(script.parents[1] / "src"))):
            env = dict(os.environ, PYTHONPATH=path + os.pathsep + str(script.parent))
            out = subprocess.run([sys.executable, str(script), "--json", *args], env=env, check=True,
                                 capture_output=True, text=True).stdout
            runs[name].append(json.loads(out.strip().splitlines()[-1]))
    return runs


def against_parser(doc: str, what: str, rounds: int) -> argparse.ArgumentParser:
    """The command line of a script timed per process and compared with another package tree
    (:func:`fresh_runs`): ``--reps`` (timed ``what`` per process), ``--rounds`` (processes per tree,
    default ``rounds``), ``--against SRC`` and the child's hidden ``--json``; described by the first
    paragraph of ``doc``."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--reps", type=int, default=2, help=f"timed {what} per process")
    parser.add_argument("--rounds", type=int, default=rounds, help="processes per tree with --against")
    parser.add_argument("--against", metavar="SRC", help="compare with the package tree SRC")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # (--against's child)
    return parser


def example_drifter(path):
    """The :class:`~impactbar.physical.CircuitDrifter` of the config file ``path``. A baseline tree
    older than a ``[rock]`` key the example names refuses it (a tree without the slot lattice,
    ``contact_events = "slots"``): there the example as that tree had it, the key left out."""
    import tomllib

    from impactbar.physical import CircuitDrifter

    with open(path, "rb") as f:
        cfg = tomllib.load(f)
    try:
        return CircuitDrifter.from_config(cfg)
    except ValueError as e:
        if "contact_events" not in str(e) or "contact_events" not in cfg.get("rock", {}):
            raise
        del cfg["rock"]["contact_events"]
        return CircuitDrifter.from_config(cfg)
