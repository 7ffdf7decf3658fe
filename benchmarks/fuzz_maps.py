"""The fuzz campaign's categories of a drifter's design maps (imported by ``fuzz_campaign.py``, whose
``case`` runs each in a forked child with a time limit).

- ``map_stores``: a finished 2 x 2 map of the rigid valve drifter (computed once), copied and
  damaged at random (an array's ``zarr.json`` deleted or garbled, its folder deleted, a chunk
  deleted, overwritten with random bytes or with other values, the coordinates' among them), then
  resumed in process: the rerun must end complete with every array (variables, flags, checksums,
  coordinates, edges) equal to the undamaged store's, or refuse in one ``ValueError``.
- ``map_axes``: axes over the integer keys (``model.n_modes``) with random integers, integer-valued
  floats, fractions, ranges and weird values: an integer-valued axis is taken (its values ints, the
  stored spec reading back the same), anything else refused with a ``ValueError``.
- ``grid_size``: 1 to 3 axes of random lengths (up to 20,000 values) and ``chunk_points``, of a map
  and of a dimensionless sweep: refused exactly where the grid exceeds ``MAX_GRID_POINTS`` points or
  ``MAX_CHUNKS`` chunks, taken otherwise, and parsed within the time limit.
"""

from __future__ import annotations

import math
import shutil
import sys
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

# the cheapest map (the rigid valve drifter, 2 x 2 points in 2 chunks), run and read as its tests do
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "sweeps"))
from test_map_store import _arrays, _run  # noqa: E402
from test_map_store import _spec as _map_spec  # noqa: E402

_STATE = {}


def _reference() -> Path:
    """The undamaged store, computed once per campaign, in a forked child: zarr's event-loop thread
    must not be started in the parent, or the children forked after it hang on it."""
    if "store" not in _STATE:
        import multiprocessing as mp

        store = Path(tempfile.mkdtemp(prefix="fuzz-maps-")) / "ref.zarr"
        p = mp.get_context("fork").Process(target=_run, args=(_map_spec(), store))
        p.start()
        p.join()
        _STATE["store"] = store
    return _STATE["store"]


def _damage(rng, store: Path) -> str:
    """One random damage to a store's arrays; returns what was done."""
    folders = sorted(p for p in store.iterdir() if p.is_dir())
    target = folders[rng.integers(len(folders))]
    chunks = sorted(p for p in (target / "c").rglob("*") if p.is_file()) if (target / "c").exists() else []
    hows = ["meta deleted", "meta garbled", "folder deleted", "chunk deleted", "chunk garbage"]
    how = hows[rng.integers(len(hows))]
    if how.startswith("chunk") and not chunks:
        how = "meta deleted"
    if how == "meta deleted":
        (target / "zarr.json").unlink(missing_ok=True)  # (an earlier damage may have taken it)
    elif how == "meta garbled":
        (target / "zarr.json").write_bytes(rng.bytes(int(rng.integers(0, 64))))
    elif how == "folder deleted":
        shutil.rmtree(target)
    else:
        chunk = chunks[rng.integers(len(chunks))]
        chunk.unlink() if how == "chunk deleted" else chunk.write_bytes(rng.bytes(int(rng.integers(1, 80))))
    return f"{how} {target.name}"


def map_store_calls(rng, n, slow, case):
    c = Counter()
    ref = _reference()
    for _ in range(n):
        seed = int(rng.integers(2**31))

        def one(seed=seed):
            r = np.random.default_rng(seed)
            with tempfile.TemporaryDirectory() as tmp:
                store = Path(tmp) / "damaged.zarr"
                shutil.copytree(ref, store)
                what = [_damage(r, store) for _ in range(int(r.integers(1, 4)))]
                res = _run(_map_spec(), store)
                if not res.complete:
                    return [f"BAD incomplete after {what}"]
                got, want = _arrays(store), _arrays(ref)
                if got.keys() != want.keys():
                    return [f"BAD arrays {sorted(set(want) ^ set(got))} after {what}"]
                for name, w in want.items():
                    if got[name].dtype != w.dtype or got[name].tobytes() != w.tobytes():
                        return [f"BAD {name} differs after {what}"]
            return ["ok"]

        case(c, one, slow)
    return c


def map_axis_calls(rng, n, slow, case):
    c = Counter()
    pool = [0, 1, 2, 3, 8, 1.0, 2.0, 2.5, -1, 1025, True, "2", None, math.nan, 1e300, np.int64(4),
            np.float64(3.0), 0.1]
    for _ in range(n):
        if rng.random() < 0.3:
            table = {"start": pool[rng.integers(len(pool))], "stop": pool[rng.integers(len(pool))],
                     "num": int(rng.integers(1, 6))}
        else:
            table = {"values": [pool[i] for i in rng.integers(len(pool), size=rng.integers(1, 4))]}

        def one(table=table):
            import json

            from impactbar.sweeps import parse_spec

            spec = _map_spec({"valve.supply_pressure": {"values": ["20 MPa"]}, "model.n_modes": table})
            values = spec.axes[1].values
            if not all(type(v) is int for v in values):
                return [f"BAD non-integer values {values!r}"]
            if parse_spec(json.loads(spec.to_json())) != spec:
                return ["BAD the stored spec reads back otherwise"]
            return ["ok"]

        case(c, one, slow)
    return c


def grid_size_calls(rng, n, slow, case):
    from impactbar.sweeps.grid import MAX_CHUNKS, MAX_GRID_POINTS

    c = Counter()
    for _ in range(n):
        sizes = [int(x) for x in 10 ** rng.uniform(0, math.log10(20_000), size=rng.integers(1, 4))]
        chunk_points = None if rng.random() < 0.5 else int(10 ** rng.uniform(0, 6))
        dimensionless = bool(rng.random() < 0.5)

        def one(sizes=sizes, chunk_points=chunk_points, dimensionless=dimensionless):
            from impactbar.sweeps import parse_spec

            extra = {} if chunk_points is None else {"chunk_points": chunk_points}
            if dimensionless:
                names = [("R", 0.0, 0.9), ("s", 1.0, 100.0), ("d", 0.0, 0.1)]
                doc = {"task": "orbits", "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
                       "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0}}
            else:
                names = [("valve.supply_pressure", "18 MPa", "20 MPa"), ("valve.delay", "0 ms", "0.1 ms"),
                         ("stop.restitution", 0.1, 0.3)]
                doc = {"task": "operating_point", "config": "hydraulic-drifter"}
            doc["axes"] = {k: {"start": a, "stop": b, "num": m}
                           for (k, a, b), m in zip(names[:len(sizes)], sizes, strict=True)}
            try:
                spec = parse_spec({**doc, **extra})
            except ValueError as exc:
                if (math.prod(sizes) > MAX_GRID_POINTS) != ("grid points; the limit" in str(exc)):
                    return [f"BAD refused {sizes}: {exc}"]
                return ["ValueError"]
            if spec.n_points > MAX_GRID_POINTS or spec.n_chunks > MAX_CHUNKS:
                return [f"BAD taken: {spec.n_points} points in {spec.n_chunks} chunks"]
            return ["ok"]

        case(c, one, slow)
    return c
