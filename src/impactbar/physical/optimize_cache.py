"""The optimiser's cache (:func:`~impactbar.physical.optimize_drifter`): the designs evaluated and the
gradients computed of them, a log with one JSON line a record appended as each is finished, and the
chain of operating points they were continued along, so that a run stopped part-way and started
again visits the same designs with the same figures, to the bit, as one that was never stopped.

The file (:class:`DesignCache`) is a first line naming the problem, then one line a design
(``{"design": record}``) or a gradient (``{"gradient": {...}}``), each written whole and flushed
when it is finished: a run stopped at any point has lost no finished design, and a line cut short
by the stop (the last, without its end of line) is ignored on reading and cut off before the next
is written. A design written again (its record changed: a border score added) replaces the one
before it. Writing a design costs its line, not the whole file's (a file rewritten after each
design costs the square of their number). A file in the format before the log (one JSON document,
``{"problem", "evaluations", "gradients"}``) is read, and written once as a log on its first write.

Each design's operating point is Newton from the nearest design evaluated before it (its
``guess``, recorded by id with the scaled variables ``u`` it was asked at). A design read from the
file carries its figures, not its orbit; where a new design's nearest is one, that orbit is solved
again as the first run solved it, from its own guess, back along the chain to a design whose orbit
this run holds or that the default chain found (:class:`OrbitChain`): the same Newton from the same
start gives the same orbit, so the new design's figures, and the optimiser's next steps, are the
uninterrupted run's.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

__all__ = ["read_cache", "read_gradients", "DesignCache", "dumps", "OrbitChain"]

#: The first line's key of a cache log, its value the format's version.
LOG_FORMAT = "impactbar_optimize_cache"


def read_cache(path, tag: str) -> dict:
    """The designs a cache file holds for the problem ``tag`` by id (``{}``: no file, or another
    problem's); a figure or constraint stored under a name its output had before is read under the
    name now, with a ``DeprecationWarning``.

    Parameters
    ----------
    path : str, os.PathLike or None
        The cache file, a log (:class:`DesignCache`) or the document of the format before it.
    tag : str
        The problem's fingerprint.

    Returns
    -------
    dict
        Each design's record by its id, in the order first written.

    Raises
    ------
    ValueError
        A file that is neither a log nor a JSON document, or a log with a line not readable JSON
        before its last, in one line naming the file.
    """
    return DesignCache(path, tag).designs


def read_gradients(path, tag: str) -> dict:
    """The designs' gradients a cache file holds for the problem ``tag``, by ``(id, kind)`` (``kind``
    ``"default"`` at the default step, ``"refined"`` the step refined where it meets a border), each
    ``{"objective": list, "constraints": list of lists}`` (``{}``: none, no file, or another problem's).

    Parameters
    ----------
    path : str, os.PathLike or None
        The cache file (:func:`read_cache`'s).
    tag : str
        The problem's fingerprint.

    Returns
    -------
    dict
        ``{(id, kind): {"objective", "constraints", "id", "kind"}}``, in the order written.

    Raises
    ------
    ValueError
        Where the file is not readable (:func:`read_cache`).
    """
    return DesignCache(path, tag).gradients


def _current(record: dict) -> dict:
    """A stored design's record with its figures and constraints under the outputs' names now
    (a name an output had before: :data:`~impactbar.physical.outputs.RENAMED_OUTPUTS`, a
    ``DeprecationWarning``)."""
    from .outputs import current_keys

    for part in ("objectives", "constraints"):
        if isinstance(record.get(part), dict):
            record[part] = current_keys(record[part], f"cached {part[:-1]}")
    return record


def _unreadable(path, what: str, exc: Exception) -> ValueError:
    return ValueError(f"cache {str(path)!r} {what}: {exc}; delete the file (or give another) to start the "
                      f"search afresh")


class DesignCache:
    """A problem's cache file: the designs and gradients it holds, read on opening, and a log each
    new one is appended to (module docstring).

    Parameters
    ----------
    path : str, os.PathLike or None
        The file (``None``: nothing read or written). A log of another problem, or a file in the
        format before the log, is replaced, atomically, on the first write: by an empty log of this
        problem, by a log of what the old file held of this problem.
    tag : str
        The problem's fingerprint (the config, the variables and bounds, the objective, the
        constraints).

    Attributes
    ----------
    designs : dict
        The designs' records by id, those read and those added, in the order first written.
    gradients : dict
        The gradients by ``(id, kind)``, each ``{"objective", "constraints", "id", "kind"}``.

    Raises
    ------
    ValueError
        A file that is neither a log nor a JSON document, or a log with a line not readable JSON
        before its last, in one line naming the file and what to do.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "cache.json"
    >>> cache = DesignCache(path, "p")
    >>> cache.add({"id": "a", "ok": True})
    >>> cache.add_gradient("a", "default", {"objective": [1.5], "constraints": [[0.25]]})
    >>> cache.close()
    >>> again = DesignCache(path, "p")
    >>> list(again.designs), again.gradients[("a", "default")]["objective"], DesignCache(path, "q").designs
    (['a'], [1.5], {})
    """

    def __init__(self, path, tag: str) -> None:
        self.path = None if path is None else Path(path)
        self.tag = tag
        self.designs: dict = {}
        self.gradients: dict = {}
        self._keep = 0  # the bytes of the file's whole lines, where it is this problem's log
        self._log = None  # the file open for appending
        self._changed: dict = {}  # records changed since written, by id: written with the next line
        if self.path is not None and self.path.exists():
            self._read()

    def _read(self) -> None:
        try:
            data = self.path.read_bytes()
        except OSError as exc:
            raise _unreadable(self.path, "cannot be read", exc) from exc
        end = data.rfind(b"\n") + 1  # (the bytes after the last end of line: a line cut short)
        first = data[:data.find(b"\n") + 1] if end else b""
        try:
            head = json.loads(first) if first.startswith(b'{"' + LOG_FORMAT.encode()) else None
        except ValueError:
            head = None
        if head is None and not data.strip():  # (an empty file: nothing kept)
            return
        if head is None:  # the format before the log: one JSON document
            try:
                doc = json.loads(data)
            except ValueError as exc:
                raise _unreadable(self.path, "is neither a cache log nor a readable JSON file", exc) from exc
            if isinstance(doc, dict) and doc.get("problem") == self.tag:
                for r in doc.get("evaluations", []):
                    self.designs[r["id"]] = _current(r)
                self.gradients.update({(g["id"], g["kind"]): g for g in doc.get("gradients", [])})
            return
        if head.get("problem") != self.tag:
            return
        for n, line in enumerate(data[len(first):end].splitlines(), start=2):
            try:
                entry = json.loads(line)
            except ValueError as exc:
                raise _unreadable(self.path, f"line {n} is not readable JSON", exc) from exc
            if "design" in entry:
                self.designs[entry["design"]["id"]] = _current(entry["design"])
            else:
                g = entry["gradient"]
                self.gradients[(g["id"], g["kind"])] = g
        self._keep = end

    def add(self, record: dict) -> None:
        """Keep a design's record (by its ``id``) and append it to the file."""
        self.designs[record["id"]] = record
        self._changed.pop(record["id"], None)
        self._write({"design": record})

    def add_gradient(self, rid: str, kind: str, gradient: dict) -> None:
        """Keep a design's gradients of kind ``kind`` (``{"objective", "constraints"}``) and append
        them to the file."""
        self.gradients[(rid, kind)] = g = dict(gradient, id=rid, kind=kind)
        self._write({"gradient": g})

    def changed(self, record: dict) -> None:
        """A kept design's record changed in place: written again with the next line written."""
        if self.path is not None:
            self._changed[record["id"]] = record

    def rewrite(self) -> None:
        """The file written anew, atomically (a file beside it, then renamed): the problem, each
        design once, the gradients."""
        if self.path is None:
            return
        self.close()
        self._changed.clear()
        tmp = self.path.with_suffix(self.path.suffix + ".tmp")
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(_line({LOG_FORMAT: 2, "problem": self.tag}))
            f.writelines(_line({"design": r}) for r in self.designs.values())
            f.writelines(_line({"gradient": g}) for g in self.gradients.values())
        os.replace(tmp, self.path)
        self._keep = self.path.stat().st_size

    def _write(self, entry: dict) -> None:
        if self.path is None:
            return
        if self._log is None:
            if not self._keep:  # no log of this problem yet: one of what was read and this entry
                self.rewrite()
                return
            self._log = open(self.path, "r+b")  # noqa: SIM115  (open until close())
            self._log.truncate(self._keep)  # (a line cut short by a stop)
            self._log.seek(self._keep)
        text = "".join([*(_line({"design": r}) for r in self._changed.values()), _line(entry)])
        self._changed.clear()
        data = text.encode()
        self._log.write(data)
        self._log.flush()
        self._keep += len(data)

    def close(self) -> None:
        """Close the file (a later write opens it again)."""
        if self._log is not None:
            self._log.close()
            self._log = None


def _line(entry: dict) -> str:
    return json.dumps(_plain(entry), allow_nan=False, separators=(",", ":")) + "\n"


def _plain(obj):
    """``obj`` as strict-JSON data: non-finite floats as ``None``, numpy values as Python's."""
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_plain(v) for v in obj]
    if hasattr(obj, "tolist") and not isinstance(obj, str):
        return _plain(obj.tolist())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def dumps(doc) -> str:
    """``doc`` as strict JSON (non-finite numbers as null; floats by their repr, read back exact)."""
    return json.dumps(_plain(doc), indent=1, allow_nan=False)


class OrbitChain:
    """The operating points of a run's designs by id, each solved from its recorded guess.

    Parameters
    ----------
    store : dict
        The designs' records by id (the cache's and the run's): ``changes``, and ``guess`` (the id
        of the design its orbit was continued from, ``None``: the default chain).
    solve : callable
        ``solve(changes, guess_orbit)``: the design's orbit, Newton from ``guess_orbit`` where given
        and it converges, else the default chain (what the run itself does).

    Examples
    --------
    >>> chain = OrbitChain({"a": {"changes": 1, "guess": None}, "b": {"changes": 2, "guess": "a"}},
    ...                    lambda changes, guess: (guess or 0) * 10 + changes)
    >>> chain.orbit("b"), chain.solved
    (12, 2)
    """

    def __init__(self, store: dict, solve) -> None:
        self.store = store
        self.solve = solve
        self.orbits: dict = {}
        self.solved = 0

    def add(self, rid: str, orbit) -> None:
        """Hold a design's orbit, solved by the run."""
        self.orbits[rid] = orbit

    def orbit(self, rid: str):
        """The orbit of design ``rid``: held, or solved again along its chain of guesses."""
        asked, todo = rid, []
        while rid is not None and rid not in self.orbits:
            todo.append(rid)
            rid = self.store[rid].get("guess")
        for r in reversed(todo):
            guess = self.store[r].get("guess")
            guess = None if guess is None else self.orbits[guess]
            self.orbits[r] = self.solve(self.store[r]["changes"], guess)
            self.solved += 1
        return self.orbits[asked]
