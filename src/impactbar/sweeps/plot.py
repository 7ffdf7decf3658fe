"""Figures drawn from a stored sweep (:mod:`impactbar.sweeps`); matplotlib is imported lazily.

Everything here reads a finished (or partly finished) zarr store; nothing is computed again.
Points of chunks not yet stored are left blank.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plotting.sweeps import (  # the drawing; re-exported here for the old import path
    STABILITY_CATEGORIES,
    plot_bifurcation,
    plot_efficiency_map,
    plot_fraction_maps,
    plot_stability_chart,
    stability_category,
)

__all__ = ["plot_sweep", "reduce_axes", "plot_stability_chart", "plot_fraction_maps",
           "plot_bifurcation", "stability_category", "STABILITY_CATEGORIES"]

def reduce_axes(ds, select: dict | None, max_dims: int):
    """Fix axes at the grid values nearest ``select`` and drop axes of length one.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep store (:func:`impactbar.sweeps.open_sweep`).
    select : dict of str to float or str, optional
        Axis name -> value: a number (in the axis' SI unit for a drifter's design map), or for a
        design map's axis a quantity with its unit (``"85 L/min"``), converted to the axis' unit.
    max_dims : int
        Most axes allowed to remain.

    Returns
    -------
    ds : xarray.Dataset
        With ``point_done`` (bool) added and the axes reduced.
    dims : tuple of str
        The remaining axes, in spec order.

    Raises
    ------
    ValueError
        If ``select`` names something that is not an axis, or more than ``max_dims`` axes remain.
    """
    from .store import point_done, stored_spec

    spec = stored_spec(ds)
    axes = [a.name for a in spec.axes]
    ds = ds.assign(point_done=point_done(ds))
    units = {a.name: a.unit for a in spec.axes}  # SI, pint's spelling ("" dimensionless)
    for name, value in (select or {}).items():
        if name not in axes:
            raise ValueError(f"--select {name}: not an axis of this sweep; axes: {axes}")
        if isinstance(value, str):
            from ..physical.units import to_si

            value = to_si(f"--select {name}", value, units[name], repr(f"1 {units[name]}"),
                          what=f"in {units[name] or 'no unit'} as the axis")
        if not isinstance(value, int | float | np.integer | np.floating) or not np.isfinite(value):
            raise ValueError(f"--select {name}: VALUE must be a finite number or a quantity in "
                             f"{units[name] or 'no unit'}; got {value!r}")
        ds = ds.sel({name: value}, method="nearest")
    dims = tuple(a for a in axes if a in ds.dims and ds.sizes[a] > 1)
    ds = ds.squeeze([a for a in axes if a in ds.dims and ds.sizes[a] == 1], drop=False)
    if len(dims) > max_dims:
        raise ValueError(f"this chart shows at most {max_dims} axes; the sweep has {list(dims)}: fix "
                         "the others with --select AXIS=VALUE")
    return ds, dims


def held_axes(ds, spec, dims) -> str:
    """Where the axes fixed by a selection are held: ``"held at NAME = VALUE UNIT, ..."``, or ``""``;
    a design map's axis in the unit its config writes the key in, else the key table's display unit
    (:func:`~impactbar.physical.display_units.format_key`, as the map's edges are printed).

    Parameters
    ----------
    ds : xarray.Dataset
        A reduced sweep store (:func:`reduce_axes`): a fixed axis is a scalar coordinate.
    spec : SweepSpec
        The sweep's spec (:func:`~impactbar.sweeps.store.stored_spec`): its axes, in spec order.
    dims : tuple of str
        The axes the chart shows.

    Returns
    -------
    str
    """
    parts = [f"{ax.name} = {spec.axis_text(ax.name, ds[ax.name].values.item())}" for ax in spec.axes
             if ax.name not in dims and ax.name in ds.coords and ds[ax.name].ndim == 0]
    return "held at " + ", ".join(parts) if parts else ""


def plot_sweep(store, out, *, select: dict | None = None, dpi: int = 150,
               variable: str | None = None) -> Path:
    """Draw a sweep store into a file: a stability chart (``orbits``), fraction maps
    (``montecarlo``), a bifurcation diagram (``bifurcation``) or a drifter's design map
    (``operating_point`` and ``settle``: ``variable`` as a line or filled contours, its edges drawn over,
    :func:`impactbar.plotting.maps.plot_operating_map`).

    Parameters
    ----------
    store : str or os.PathLike
        A store written by :func:`impactbar.sweeps.run_sweep`.
    out : str or os.PathLike
        The figure file; its suffix picks the format.
    select : dict of str to float, optional
        Fix axes at the nearest grid value, down to two.
    dpi : int, optional
    variable : str, optional
        The variable of a design map to draw (default the blow frequency); only for one. A name an
        output had before reads the output's variable, with a ``DeprecationWarning``
        (:data:`~impactbar.physical.outputs.RENAMED_OUTPUTS`).

    Returns
    -------
    pathlib.Path
        ``out``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from impactbar import CosineLoad, plot_sweep, run_sweep  # needs matplotlib, xarray and zarr
    >>> from impactbar.sweeps import parse_spec
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> spec = parse_spec({"task": "orbits", "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
    ...                    "load": CosineLoad(0.5, 1.0).params.record(),
    ...                    "axes": {"R": {"values": [0.2, 0.9]}}})
    >>> _ = run_sweep(spec, folder / "r.zarr", progress=False)
    >>> plot_sweep(folder / "r.zarr", folder / "chart.png").name
    'chart.png'
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from ..physical.outputs import current_name
    from .store import open_sweep, stored_spec

    ds = open_sweep(store)
    variable = None if variable is None else current_name(variable, "--variable")
    task = ds.attrs["task"]
    if variable is not None and task not in ("operating_point", "settle"):
        raise ValueError(f"--variable is for a drifter's design map (task operating_point or settle); this "
                         f"store's task is {task}")
    out = Path(out)
    try:
        red, dims = reduce_axes(ds, select, 2)
        red = red.load()
    except ValueError:
        raise
    except Exception as exc:  # a damaged zarr chunk: zarr and its codecs raise many kinds
        raise ValueError(f"{store}: the stored data cannot be read ({type(exc).__name__}: {exc}); "
                         "rerun the sweep on this store to recompute the damaged chunks") from None
    if task == "orbits" and "efficiency" in red.variables:  # a rod-rock sweep: the blows' efficiency too
        fig, (left, right) = plt.subplots(1, 2, figsize=(12.0, 4.8), layout="constrained")
        plot_stability_chart(red, dims, ax=left)
        plot_efficiency_map(red, dims, ax=right)
    elif task == "orbits":
        fig = plot_stability_chart(red, dims).figure
    elif task == "montecarlo":
        fig = plot_fraction_maps(red, dims)
    elif task in ("operating_point", "settle"):
        from ..plotting.maps import plot_operating_map

        fig = plot_operating_map(red, dims, variable).figure
    else:
        fig = plot_bifurcation(red, dims).figure
    held = held_axes(red, stored_spec(ds), dims)
    if held:  # in the first panel's title, under any title it has
        ax = fig.axes[0]
        title = ax.get_title()
        ax.set_title(f"{title}\n{held}" if title else held, fontsize="small" if title else None)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out
