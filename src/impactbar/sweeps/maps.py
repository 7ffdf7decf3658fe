"""Running a drifter map (:func:`run_map`) and storing its edges (:func:`map_edges`)."""

from __future__ import annotations

import math
import warnings

import numpy as np

from .map_task import EDGE_FLAGS, EDGE_RTOL, find_edges, refine_edge


# ------------------------------------------------------------------------------------------------
def run_map(spec, store, *, refine: bool | None = None, **kwargs):
    """Compute a sweep or a drifter map into a zarr store (:func:`impactbar.sweeps.run_sweep`: chunks
    stored as they finish, a rerun resumes), then a map's edges (:func:`map_edges`; a sweep of the
    dimensionless bar has none).

    Parameters
    ----------
    spec : SweepSpec
    store : path-like
        The zarr store (a folder).
    refine : bool, optional
        Refine the edges by bisection; default the spec's ``refine_edges``.
    **kwargs
        Passed to :func:`impactbar.sweeps.run_sweep` (``n_workers``, ``executor``, ``progress``,
        ``overwrite``, ...).

    Returns
    -------
    SweepRun
    """
    from .run import run_sweep

    res = run_sweep(spec, store, **kwargs)
    if res.complete:
        sweep_edges(spec, store, refine)
    return res


def sweep_edges(spec, store, refine: bool | None = None) -> list:
    """The edges (:func:`map_edges`'s list) of a complete ``store`` of ``spec`` where its machine
    has them (a drifter's design map), refined as the spec's ``refine_edges`` says unless ``refine``
    is given; none (and nothing written) for a sweep of the dimensionless bar."""
    if not spec.space.edges:
        return []
    return map_edges(store, refine=spec.options["refine_edges"] if refine is None else refine)


def map_edges(store, *, refine: bool = False) -> list:
    """Find a finished map's edges and store them (``edge_*`` variables along ``edge``); with
    ``refine``, each bisected to :data:`EDGE_RTOL` (``edge_value``, else NaN).

    Parameters
    ----------
    store : path-like
        A complete drifter map store.
    refine : bool
        Bisect each edge to :data:`EDGE_RTOL`; without it, an edge refined by an earlier call keeps
        its refined value.

    Returns
    -------
    list of dict
        ``axis`` (the key), ``index`` (the lower point), ``flag``, ``low``, ``high`` (the grid values
        around it, SI) and ``value`` (the refined one, or NaN).

    Raises
    ------
    ValueError
        A store that is not a drifter map, or one with chunks left to compute.
    """
    from .store import open_sweep, stored_spec

    ds = open_sweep(store)
    spec = stored_spec(ds)
    if not spec.space.edges:
        raise ValueError(f"{store} is not a drifter map (task {spec.task}); edges are a map's")
    done = np.asarray(ds["chunk_done"].values)
    if not np.all(done == 1):
        raise ValueError(f"{store}: {int(np.sum(done != 1))} of {done.size} chunks are not stored yet; rerun "
                         "the sweep to finish it before its edges are found")
    names = [f for f in EDGE_FLAGS if f in ds]
    data = {n: ds[n].values for n in (*names, "status")}
    kept = {}  # edges refined before keep their values where they are found again without refining
    if "edge_value" in ds and ds["edge_value"].size:
        for a, i, f, v in zip(ds["edge_axis"].values, ds["edge_index"].values, ds["edge_flag"].values,
                              ds["edge_value"].values, strict=True):
            kept[(int(a), tuple(int(x) for x in np.atleast_1d(i)), str(f))] = float(v)
    edges = []
    for axis, index, flag in find_edges(data, names):
        ax = spec.axes[axis]
        low, high = float(ax.values[index[axis]]), float(ax.values[index[axis] + 1])
        value = kept.get((axis, tuple(int(x) for x in index), flag), math.nan)
        if refine:
            try:
                a, b = refine_edge(spec, axis, index, flag)
                value = 0.5 * (a + b)
            except ValueError:
                value = math.nan
        edges.append({"axis": ax.name, "axis_number": axis, "index": index, "flag": flag, "low": low,
                      "high": high, "value": value})
    n, d = len(edges), len(spec.axes)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*does not have a Zarr V3 specification.*")
        warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
        _write_edges(str(store), edges, n, d, refine or bool(kept), tuple(a.name for a in spec.axes))
    return edges


def _write_edges(store: str, edges: list, n: int, d: int, refine: bool, names: tuple) -> None:
    import zarr

    root = zarr.open_group(store, mode="r+")
    arrays = {
        "edge_axis": (np.array([e["axis_number"] for e in edges], dtype=np.int8).reshape(n), ("edge",),
                      "axis along which the flag changes (0 the first)", ""),
        "edge_index": (np.array([e["index"] for e in edges], dtype=np.int32).reshape(n, d), ("edge", "axis"),
                       "grid index of the point below the edge", ""),
        "edge_flag": (np.array([e["flag"] for e in edges], dtype="U24").reshape(n), ("edge",),
                      "the flag that changes", ""),
        "edge_low": (np.array([e["low"] for e in edges], dtype=float).reshape(n), ("edge",),
                     "axis value of the point below the edge (SI)", ""),
        "edge_high": (np.array([e["high"] for e in edges], dtype=float).reshape(n), ("edge",),
                      "axis value of the point above the edge (SI)", ""),
        "edge_value": (np.array([e["value"] for e in edges], dtype=float).reshape(n), ("edge",),
                       f"the edge refined by bisection to {EDGE_RTOL:g} relative (SI; NaN: not refined)", ""),
    }
    for name, (values, dims, long_name, units) in arrays.items():
        if name in root:
            del root[name]
        shape = values.shape
        chunks = tuple(max(1, s) for s in shape)
        fill = "" if values.dtype.kind == "U" else (np.nan if values.dtype.kind == "f" else 0)
        arr = root.create_array(name, shape=shape, dtype=values.dtype, chunks=chunks, fill_value=fill,
                                dimension_names=dims, attributes={"long_name": long_name,
                                                                  "units": units or "1"})
        if values.size:
            arr[...] = values
    root.attrs["edges_refined"] = bool(refine)
    root.attrs["axes"] = list(names)
    zarr.consolidate_metadata(store)
