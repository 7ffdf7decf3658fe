"""The zarr store of a sweep: created whole up front, written chunk by chunk, done flags, reading back."""

from __future__ import annotations

import json
import os
import shutil
import uuid
import warnings
import zlib
from pathlib import Path

import numpy as np

from ..dynamics.implementations import use_fast
from .spec import _ATTR_SPEC, _ATTR_VERSION, _DONE, _EXTRA_DIM, _SUM, SweepSpec, motion_classes, parse_spec
from .tasks import chunk_slices

# ------------------------------------------------------------------------------------------------
# the store
# ------------------------------------------------------------------------------------------------
#: units of the stored variables and axes (CF convention: "1" for dimensionless numbers, eq. 2;
#: flags, counts and names carry ""); a variable not listed is dimensionless
UNITS = {  # (the variables' own are declared with them: impactbar.sweeps.SweepSpec.variables)
    "motion": "",
    _DONE: "",
}

def _var_attrs(name: str, description: str, units: str | None = None) -> dict:
    """``long_name``, ``units`` and ``description`` of a stored variable."""
    units = UNITS.get(name, "1") if units is None else units
    return {"long_name": description.split(" (")[0], "units": units, "description": description}


def _template(spec: SweepSpec):
    """The dataset to create the store from: lazy (dask) fill values, coordinates, attributes."""
    import dask.array as da
    import xarray as xr

    from .._version import __version__

    dims = tuple(a.name for a in spec.axes)
    extra_dim = _EXTRA_DIM.get(spec.task)
    chunks = spec.chunk_shape
    data_vars = {}
    for f in spec.variables():
        extra = f.per is not None
        shape = spec.shape + ((spec.extra_size,) if extra else ())
        ch = chunks + ((spec.extra_size,) if extra else ())
        arr = da.full(shape, f.fill, dtype=f.dtype, chunks=ch)
        data_vars[f.name] = xr.Variable(dims + ((extra_dim,) if extra else ()), arr,
                                        attrs=_var_attrs(f.name, f.long_name, f.units))
    data_vars[_DONE] = xr.Variable(("chunk",), da.zeros(spec.n_chunks, dtype=np.int8,
                                                          chunks=spec.n_chunks),
                                   attrs=_var_attrs(_DONE, "1 once the work chunk is stored"))
    data_vars[_SUM] = xr.Variable(("chunk",), da.full(spec.n_chunks, -1, dtype=np.int64,
                                                      chunks=spec.n_chunks),
                                  attrs=_var_attrs(_SUM, "CRC-32 of the work chunk's data "
                                                         "(-1 before it is stored)"))
    coords = {a.name: xr.Variable((a.name,), np.asarray(a.values), attrs=spec.axis_attrs(a.name))
              for a in spec.axes}
    if spec.task == "montecarlo":
        coords["motion"] = xr.Variable(("motion",), np.asarray(motion_classes(), dtype=object),
                                       attrs={"long_name": "long-run motion", "units": ""})
    attrs = {
        _ATTR_SPEC: spec.to_json(),
        _ATTR_VERSION: __version__,
        "task": spec.task,
        "chunk_shape": list(spec.chunk_shape),
    }
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


# "sweeps.create_store" (impactbar.dynamics.implementations): the fast implementation (default) writes
# the store's metadata and coordinates with zarr alone, without importing xarray and dask.array (about
# 0.5 s of a short sweep); the reference creates it through xarray (``_template(spec).to_zarr``); a
# test checks that both give identical stores


def _store_arrays(spec: SweepSpec) -> list:
    """Every array of the store of :func:`_template` as xarray's ``to_zarr(compute=False,
    zarr_format=3, consolidated=True)`` writes it (the same ``zarr.json`` documents, coordinates and
    the ``_FillValue`` attribute of floating-point variables): ``(name, values or None, dtype,
    shape, chunks, fill, dimension names, attributes)`` each, ``values`` given for the coordinates."""
    import base64

    def attrs(desc_attrs: dict, dtype, fill) -> dict:
        out = dict(desc_attrs)
        if np.dtype(dtype).kind == "f":  # xarray's CF encoding of a floating-point fill value
            out["_FillValue"] = base64.standard_b64encode(np.asarray(fill, dtype="<f8").tobytes()).decode()
        return out

    dims = tuple(a.name for a in spec.axes)
    extra_dim = _EXTRA_DIM.get(spec.task)
    arrays = []
    for f in spec.variables():
        extra, dtype = f.per is not None, np.dtype(f.dtype)
        tail = (spec.extra_size,) if extra else ()
        arrays.append((f.name, None, dtype, spec.shape + tail, spec.chunk_shape + tail, f.fill,
                       dims + ((extra_dim,) if extra else ()),
                       attrs(_var_attrs(f.name, f.long_name, f.units), dtype, f.fill)))
    arrays.append((_DONE, None, np.dtype(np.int8), (spec.n_chunks,), (spec.n_chunks,), 0, ("chunk",),
                   _var_attrs(_DONE, "1 once the work chunk is stored")))
    arrays.append((_SUM, None, np.dtype(np.int64), (spec.n_chunks,), (spec.n_chunks,), 0, ("chunk",),
                   _var_attrs(_SUM, "CRC-32 of the work chunk's data (-1 before it is stored)")))
    for a in spec.axes:
        values = np.asarray(a.values)
        arrays.append((a.name, values, values.dtype, values.shape, values.shape,
                       np.nan if values.dtype.kind == "f" else 0, (a.name,),
                       attrs(spec.axis_attrs(a.name), values.dtype, np.nan)))
    if spec.task == "montecarlo":
        classes = np.asarray(motion_classes(), dtype=object)
        arrays.append(("motion", classes, str, classes.shape, classes.shape, "", ("motion",),
                       {"long_name": "long-run motion", "units": ""}))
    return arrays


def _create_arrays(root, arrays, overwrite: bool = False) -> None:
    """Create ``arrays`` (:func:`_store_arrays`) in a zarr group, writing the coordinates' values."""
    for name, values, dtype, shape, chunks, fill, dim_names, attributes in arrays:
        arr = root.create_array(name, shape=shape, dtype=dtype, chunks=chunks, fill_value=fill,
                                dimension_names=dim_names, attributes=attributes, overwrite=overwrite)
        if values is not None:
            arr[...] = values


def _create_with_zarr(spec: SweepSpec, folder: Path) -> None:
    """The store of :func:`_template`, with zarr alone (:func:`_store_arrays`)."""
    import zarr

    from .._version import __version__

    root = zarr.create_group(store=str(folder), zarr_format=3, attributes={
        _ATTR_SPEC: spec.to_json(), _ATTR_VERSION: __version__, "task": spec.task,
        "chunk_shape": list(spec.chunk_shape)})
    _create_arrays(root, _store_arrays(spec))
    zarr.consolidate_metadata(str(folder))


def _metadata_doc(arr) -> str:
    return json.dumps(arr.metadata.to_dict(), sort_keys=True, default=str)


def _repair_store(spec: SweepSpec, path: Path) -> list:
    """Check every array of a store against its spec before a resume: recreate each whose metadata
    (``NAME/zarr.json``) is missing, unreadable or not what the spec makes (its chunks are then
    recomputed: their checksums no longer match), write the coordinates from the spec again, and
    consolidate the metadata afresh (the root's copy may list arrays that are gone).

    Returns
    -------
    list of str
        The arrays recreated.

    Raises
    ------
    ValueError
        A store that cannot be written (one line: how to recover).
    """
    import zarr

    arrays = _store_arrays(spec)
    reference = zarr.create_group(store=zarr.storage.MemoryStore(), zarr_format=3)
    _create_arrays(reference, [(n, None, *rest) for n, _, *rest in arrays])
    repaired = []
    try:
        root = zarr.open_group(store=str(path), mode="r+", use_consolidated=False)
        for item in arrays:
            name, values, *_ = item
            try:
                ok = (_metadata_doc(zarr.open_array(store=str(path), path=name, mode="r"))
                      == _metadata_doc(reference[name]))
            except Exception:  # a missing or damaged zarr.json (zarr and json raise many kinds)
                ok = False
            if not ok:
                _create_arrays(root, [item], overwrite=True)
                repaired.append(name)
            elif values is not None:  # a coordinate: from the spec, whatever the store holds
                root[name][...] = values
        zarr.consolidate_metadata(str(path))
    except OSError as exc:
        raise ValueError(f"--out {path} is damaged and cannot be repaired ({exc.strerror or exc}); "
                         "use --overwrite to recompute it") from None
    return repaired


def _is_sweep_store(path: Path) -> bool:
    return (path / "zarr.json").is_file() and _ATTR_SPEC in _read_attrs(path)


def _read_attrs(path: Path) -> dict:
    try:
        doc = json.loads((path / "zarr.json").read_text())
    except (OSError, ValueError):
        return {}
    return doc.get("attributes", {}) or {}


def _create_store(spec: SweepSpec, path: Path) -> None:
    """Create the full store in a temporary folder next to ``path`` and rename it into place
    (removing what a run killed during this step left behind)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"--out {path}: cannot create its folder: {exc.strerror or exc}") from None
    for stale in path.parent.glob(f".{path.name}.creating-*"):
        shutil.rmtree(stale, ignore_errors=True)
    tmp = path.with_name(f".{path.name}.creating-{uuid.uuid4().hex}")
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
            # text variables (a drifter map's failure reasons): fixed-length UTF-32, read back by zarr
            warnings.filterwarnings("ignore", message=".*does not have a Zarr V3 specification.*")
            if not use_fast("sweeps.create_store"):
                _template(spec).to_zarr(tmp, mode="w-", compute=False, zarr_format=3, consolidated=True)
            else:
                _create_with_zarr(spec, tmp)
        os.rename(tmp, path)
    except OSError as exc:  # a read-only or full file system, a path that is taken meanwhile
        raise ValueError(f"--out {path}: cannot create the store: {exc.strerror or exc}") from None
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def _prepare_store(spec: SweepSpec, path: Path, overwrite: bool):
    """Create the store or check that it holds this sweep; return the verified done flags and the
    checksums, shape ``(n_chunks,)`` each (see :func:`_verified_done`)."""
    from .._version import __version__

    if path.exists():
        if not _is_sweep_store(path):
            raise ValueError(f"--out {path} exists and is not an impactbar sweep store; "
                             "choose another path")
        if overwrite:
            shutil.rmtree(path)
        else:
            attrs = _read_attrs(path)
            if attrs.get(_ATTR_SPEC) != spec.to_json():
                stored = json.loads(attrs.get(_ATTR_SPEC, "{}"))
                new = spec.to_dict()
                diff = sorted(k for k in set(stored) | set(new) if stored.get(k) != new.get(k))
                raise ValueError(f"--out {path} holds a different sweep (differs in {diff}); "
                                 "use --overwrite to replace it, or another --out")
            if attrs.get(_ATTR_VERSION) != __version__:
                raise ValueError(f"--out {path} was computed by impactbar {attrs.get(_ATTR_VERSION)}, "
                                 f"this is {__version__}; use --overwrite to recompute it")
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
                warnings.filterwarnings("ignore", message=".*does not have a Zarr V3 specification.*")
                _repair_store(spec, path)  # every array as the spec makes it, the coordinates rewritten
            done, sums, flags = _verified_done(spec, path)
            if flags is None or not np.array_equal(done, flags):
                _write_done(path, done, sums)  # repair the flags before any work starts
            return done, sums
    _create_store(spec, path)
    return np.zeros(spec.n_chunks, dtype=np.int8), np.full(spec.n_chunks, -1, dtype=np.int64)


def _checksum(spec: SweepSpec, result: dict) -> int:
    """CRC-32 of a chunk's data, every variable cast to its stored dtype, in a fixed order."""
    crc = 0
    for f in spec.variables():
        crc = zlib.crc32(np.ascontiguousarray(result[f.name], dtype=f.dtype).tobytes(), crc)
    return crc


def _stored_checksum(spec: SweepSpec, group, chunk: int) -> int:
    """CRC-32 of what the store holds for a chunk (raises if a zarr chunk cannot be read)."""
    slices = chunk_slices(spec, chunk)
    data = {}
    for f in spec.variables():
        data[f.name] = group[f.name][slices + ((slice(None),) if f.per is not None else ())]
    return _checksum(spec, data)


def _verified_done(spec: SweepSpec, path: Path):
    """The done flags of a store, each checked against the data.

    A chunk counts as done only if its flag is set (or the flag file cannot be read) and its data,
    read back, match its stored checksum; a deleted, truncated or corrupted chunk is recomputed,
    not trusted.

    Returns
    -------
    done : numpy.ndarray of int8, shape (n_chunks,)
    sums : numpy.ndarray of int64, shape (n_chunks,)
        The checksums of the chunks found done, -1 elsewhere.
    flags : numpy.ndarray of int8 or None
        The stored flags as read (None if they cannot be read).
    """
    import zarr

    n = spec.n_chunks
    try:
        flags = _read_done(path, n)
    except Exception:  # an empty or damaged flag file (zarr and its codecs raise many kinds)
        flags = None
    try:
        sums = np.asarray(zarr.open_array(store=str(path), path=_SUM, mode="r")[:], dtype=np.int64)
    except Exception:
        sums = None
    done = np.zeros(n, dtype=np.int8)
    if sums is None or sums.shape != (n,):  # no checksums to trust: recompute everything
        return done, np.full(n, -1, dtype=np.int64), flags
    candidates = np.flatnonzero((sums >= 0) & (flags != 0 if flags is not None else True))
    group = zarr.open_group(store=str(path), mode="r", use_consolidated=False)
    for i in candidates:
        try:
            ok = _stored_checksum(spec, group, int(i)) == int(sums[i])
        except Exception:  # an unreadable zarr chunk (truncated, corrupted)
            ok = False
        done[i] = 1 if ok else 0
    return done, np.where(done == 1, sums, -1), flags


def _read_done(path: Path, n_chunks: int) -> np.ndarray:
    import zarr

    done = np.asarray(zarr.open_array(store=str(path), path=_DONE, mode="r")[:], dtype=np.int8)
    if done.shape != (n_chunks,):  # pragma: no cover - the spec check makes this impossible
        raise ValueError(f"{path}: chunk_done has shape {done.shape}, expected ({n_chunks},)")
    return done


def _open_group(path: Path):
    """The store's zarr group, opened once per run for the chunk writes."""
    import zarr

    return zarr.open_group(path, mode="r+")


def _zarr_sync():
    """zarr's runner of its async API on its own event loop (``zarr.core.sync.sync``), or ``None``
    where a zarr version lacks it or ``Array.async_array`` (zarr 3.1.3 has neither in that form):
    the writes then go one by one through the public API."""
    import zarr

    try:
        from zarr.core.sync import sync
    except ImportError:
        return None
    return sync if hasattr(zarr.Array, "async_array") else None


def _write_chunks(spec: SweepSpec, path: Path, items, group=None) -> None:
    """Write computed chunks (``(chunk, result)`` pairs) into their regions of every variable,
    straight into the zarr arrays, all at once: one round trip to zarr's event loop for every
    array of every chunk (the dtypes and fill values were fixed when the store was made, so
    nothing is encoded here; xarray's region writes cost some 20 ms a chunk, one write per array
    about 13 ms, this 5-8 ms)."""
    import asyncio

    g = _open_group(path) if group is None else group
    sync = _zarr_sync()
    if sync is None:  # zarr without its (internal) event-loop runner: one plain write per array
        for chunk, result in items:
            region = chunk_slices(spec, chunk)
            for name, arr in result.items():
                g[name][region + (slice(None),) * (arr.ndim - len(region))] = arr
        return
    arrays = {}
    writes = []
    for chunk, result in items:
        region = chunk_slices(spec, chunk)
        for name, arr in result.items():
            if name not in arrays:
                arrays[name] = g[name].async_array
            writes.append(arrays[name].setitem(region + (slice(None),) * (arr.ndim - len(region)), arr))

    async def gather():
        await asyncio.gather(*writes)

    sync(gather())


def _write_chunk(spec: SweepSpec, path: Path, chunk: int, result: dict, group=None) -> None:
    """Write one computed chunk into its region of every variable (see :func:`_write_chunks`)."""
    _write_chunks(spec, path, [(chunk, result)], group)


def _write_done(path: Path, done: np.ndarray, sums: np.ndarray, group=None) -> None:
    """Write the chunks' checksums, then their done flags (a kill in between only recomputes)."""
    g = _open_group(path) if group is None else group
    sync = _zarr_sync()
    if sync is None:
        g[_SUM][:] = sums
        g[_DONE][:] = done
        return
    sum_array, done_array = g[_SUM].async_array, g[_DONE].async_array

    async def write():
        await sum_array.setitem(slice(None), sums)
        await done_array.setitem(slice(None), done)

    sync(write())


def open_sweep(path):
    """Open a sweep store as an ``xarray.Dataset`` (lazily; ``xarray.open_zarr`` does the same); a
    variable of an output stored under a name it had before holds the name now
    (:data:`~impactbar.physical.outputs.RENAMED_OUTPUTS`, with a ``DeprecationWarning``).

    Raises
    ------
    ValueError
        If ``path`` is not an impactbar sweep store.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from impactbar import CosineLoad, open_sweep, run_sweep  # needs xarray and zarr (extra distributed)
    >>> from impactbar.sweeps import Axis, SweepSpec
    >>> spec = SweepSpec(task="orbits", model={"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
    ...                  load=CosineLoad(0.5, 1.0).params.record(), axes=(Axis("R", (0.0, 0.45, 0.9)),))
    >>> store = pathlib.Path(tempfile.mkdtemp()) / "r.zarr"
    >>> _ = run_sweep(spec, store, progress=False)
    >>> ds = open_sweep(store)
    >>> dict(ds.sizes)["R"], "impact_velocity" in ds
    (3, True)
    """
    import xarray as xr

    from ..physical.outputs import current_name

    path = Path(path)
    if not _is_sweep_store(path):
        raise ValueError(f"{path} is not an impactbar sweep store")
    ds = xr.open_zarr(path)
    # a store written before an output was renamed: its variable under the name now (a DeprecationWarning)
    renamed = {n: new for n in ds.data_vars if (new := current_name(n, f"{path.name}: variable")) != n}
    return ds.rename(renamed) if renamed else ds


def stored_spec(ds) -> SweepSpec:
    """The spec of a sweep store, from the attributes of its dataset (:func:`open_sweep`)."""
    if _ATTR_SPEC not in ds.attrs:
        raise ValueError("the dataset is not an impactbar sweep store (no spec attribute)")
    return parse_spec(json.loads(ds.attrs[_ATTR_SPEC]))


def point_done(ds):
    """Which grid points are stored: ``chunk_done`` spread over the grid.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep store (:func:`open_sweep`).

    Returns
    -------
    xarray.DataArray of bool, shape of the grid
        Dimensions and coordinates of the axes.
    """
    import xarray as xr

    spec = stored_spec(ds)
    flags = np.asarray(ds[_DONE].values, dtype=bool).reshape(spec.chunk_grid)
    grid = flags
    for axis, c in enumerate(spec.chunk_shape):
        grid = np.repeat(grid, c, axis=axis)
    grid = grid[tuple(slice(0, n) for n in spec.shape)]
    dims = tuple(a.name for a in spec.axes)
    return xr.DataArray(grid, dims=dims, coords={d: ds[d] for d in dims})  # keeps the axes' attrs


def sweep_progress(path) -> tuple[int, int]:
    """``(chunks done, chunks in all)`` of a sweep store, from its done flags."""
    path = Path(path)
    if not _is_sweep_store(path):
        raise ValueError(f"{path} is not an impactbar sweep store")
    spec = parse_spec(json.loads(_read_attrs(path)[_ATTR_SPEC]))
    done = _read_done(path, spec.n_chunks)
    return int(done.sum()), int(done.size)


