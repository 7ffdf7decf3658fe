"""The optimiser's cache (:func:`~impactbar.physical.optimize_drifter`): the designs evaluated, as a
JSON file written after each, and the chain of operating points they were continued along, so
that a run stopped part-way and started again visits the same designs with the same figures, to
the bit, as one that was never stopped.

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
from pathlib import Path

__all__ = ["read_cache", "read_gradients", "write_cache", "dumps", "OrbitChain"]


def read_cache(path, tag: str) -> dict:
    """The designs a cache file holds for the problem ``tag`` by id (``{}``: no file, or another
    problem's); a figure or constraint stored under a name its output had before is read under the
    name now, with a ``DeprecationWarning``.

    Raises
    ------
    ValueError
        A file that is not readable JSON, in one line.
    """
    return {r["id"]: _current(r) for r in _document(path, tag).get("evaluations", [])}


def _current(record: dict) -> dict:
    """A stored design's record with its figures and constraints under the outputs' names now
    (a name an output had before: :data:`~impactbar.physical.outputs.RENAMED_OUTPUTS`, a
    ``DeprecationWarning``)."""
    from .outputs import current_keys

    for part in ("objectives", "constraints"):
        if isinstance(record.get(part), dict):
            record[part] = current_keys(record[part], f"cached {part[:-1]}")
    return record


def read_gradients(path, tag: str) -> dict:
    """The designs' gradients a cache file holds for the problem ``tag``, by ``(id, kind)`` (``kind``
    ``"default"`` at the default step, ``"refined"`` the step refined where it meets a border), each
    ``{"objective": list, "constraints": list of lists}`` (``{}``: none, no file, or another problem's).

    Raises
    ------
    ValueError
        A file that is not readable JSON, in one line.
    """
    return {(g["id"], g["kind"]): g for g in _document(path, tag).get("gradients", [])}


def _document(path, tag: str) -> dict:
    """The cache file's document where it holds the problem ``tag`` (``{}``: no file, or another
    problem's); a file that is not readable JSON raises a ``ValueError`` in one line."""
    if path is None or not Path(path).exists():
        return {}
    try:
        doc = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise ValueError(f"cache {str(path)!r} is not a readable JSON file: {exc}") from exc
    return doc if isinstance(doc, dict) and doc.get("problem") == tag else {}


def write_cache(path: Path, tag: str, store: dict, gradients: dict | None = None) -> None:
    """Write the designs and the gradients computed of them (``{(id, kind): {"objective",
    "constraints"}}``; a file beside it, then renamed: a stop mid-write leaves the last one)."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    kept = [dict(g, id=rid, kind=kind) for (rid, kind), g in (gradients or {}).items()]
    tmp.write_text(dumps({"problem": tag, "evaluations": list(store.values()), "gradients": kept}))
    tmp.replace(path)


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
