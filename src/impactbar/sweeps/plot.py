"""Figures drawn from a stored sweep (:mod:`impactbar.sweeps`); matplotlib is imported lazily.

Everything here reads a finished (or partly finished) zarr store; nothing is computed again.
Points of chunks not yet stored are left blank.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_sweep", "reduce_axes", "plot_stability_chart", "plot_fraction_maps",
           "plot_bifurcation"]

#: categories of the stability chart, in colour order
STABILITY_CATEGORIES = ("no orbit", "no admissible orbit", "admissible, none stable", "stable orbit",
                        "failed")
_CATEGORY_COLOURS = ("#ffffff", "#f4a582", "#92c5de", "#0571b0", "#444444")


def reduce_axes(ds, select: dict | None, max_dims: int):
    """Fix axes at the grid values nearest ``select`` and drop axes of length one.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep store (:func:`impactbar.sweeps.open_sweep`).
    select : dict of str to float, optional
        Axis name -> value.
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
    for name, value in (select or {}).items():
        if name not in axes:
            raise ValueError(f"--select {name}: not an axis of this sweep; axes: {axes}")
        if not isinstance(value, int | float | np.integer | np.floating) or not np.isfinite(value):
            raise ValueError(f"--select {name}: VALUE must be a finite number; got {value!r}")
        ds = ds.sel({name: value}, method="nearest")
    dims = tuple(a for a in axes if a in ds.dims and ds.sizes[a] > 1)
    ds = ds.squeeze([a for a in axes if a in ds.dims and ds.sizes[a] == 1], drop=False)
    if len(dims) > max_dims:
        raise ValueError(f"this chart shows at most {max_dims} axes; the sweep has {list(dims)}: fix "
                         "the others with --select AXIS=VALUE")
    return ds, dims


def _axes(ax, figsize=(6.4, 4.8)):
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=figsize, layout="constrained")
        return fig, ax
    return ax.figure, ax


#: where every legend goes: outside the axes, on the right, off the data
_LEGEND = {"loc": "upper left", "bbox_to_anchor": (1.02, 1.0), "borderaxespad": 0.0, "fontsize": "small"}


def _axis_label(ds, name: str) -> str:
    """``long_name (name)`` from the store's attributes, or the bare name for older stores."""
    long = ds[name].attrs.get("long_name") if name in ds.variables else None
    return f"{long} ({name})" if long and long != name else name


def _title(ds, dims) -> str:
    fixed = [f"{d} = {float(ds[d]):g}" for d in ds.coords
             if ds[d].ndim == 0 and d not in ("orbit", "motion", "impact")]
    return ", ".join(fixed)


def stability_category(ds) -> np.ndarray:
    """Per point: index into :data:`STABILITY_CATEGORIES` (NaN where not stored).

    Returns
    -------
    numpy.ndarray of float, shape of the grid
    """
    n = np.asarray(ds["n_orbits"].values)
    adm = np.asarray(ds["admissible"].values).any(axis=-1)
    stab = np.asarray(ds["stable"].values).any(axis=-1)
    cat = np.where(n == 0, 0, np.where(~adm, 1, np.where(~stab, 2, 3))).astype(float)
    cat[np.asarray(ds["failed"].values)] = 4
    cat[~np.asarray(ds["point_done"].values)] = np.nan
    return cat


def plot_stability_chart(ds, dims, ax=None):
    """The stability chart of an ``orbits`` sweep reduced to one or two axes.

    Two axes: each point coloured by :func:`stability_category` (the paper's Figs. 5, 6, 8 as a
    grid). One axis: the phase of every orbit against the axis (the impact velocity of the rigid
    bar is the same for all its orbits), filled where stable, hollow where admissible but
    unstable, a cross where not admissible.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    fig, ax = _axes(ax)
    if len(dims) == 2:
        y, x = dims
        cat = stability_category(ds.transpose(y, x, ...))
        cmap = ListedColormap(_CATEGORY_COLOURS)
        norm = BoundaryNorm(np.arange(-0.5, len(_CATEGORY_COLOURS) + 0.5), cmap.N)
        ax.pcolormesh(ds[x].values, ds[y].values, np.ma.masked_invalid(cat), cmap=cmap, norm=norm,
                      shading="nearest")
        ax.set_xlabel(_axis_label(ds, x))
        ax.set_ylabel(_axis_label(ds, y))
        present = sorted({int(c) for c in cat[np.isfinite(cat)].ravel()})
        ax.legend(handles=[Patch(facecolor=_CATEGORY_COLOURS[c], edgecolor="k", label=STABILITY_CATEGORIES[c])
                           for c in present], **_LEGEND)
    else:
        if len(dims) == 1:
            x = dims[0]
            xv = np.broadcast_to(ds[x].values[:, None], ds["phase"].shape)
        else:
            x = "point"
            xv = np.zeros(ds["phase"].shape)
        ok = np.asarray(ds["point_done"].values)[..., None]
        v = np.asarray(ds["phase"].values)
        adm = np.asarray(ds["admissible"].values) & ok
        st = np.asarray(ds["stable"].values) & ok
        ax.plot(xv[st], v[st], "o", color="C0", ms=3, label="stable")
        sel = adm & ~st
        ax.plot(xv[sel], v[sel], "o", mfc="none", color="C1", ms=3, label="admissible, unstable")
        sel = ~adm & ok & np.isfinite(v)
        ax.plot(xv[sel], v[sel], "x", color="C3", ms=3, label="not admissible")
        ax.set_xlabel(_axis_label(ds, x) if x in ds.variables else x)
        ax.set_ylabel("phase (rad)")
        ax.legend(**_LEGEND)
    ax.set_title(" ".join(filter(None, ["one-impact orbits", _title(ds, dims)])))
    return ax


def plot_fraction_maps(ds, dims, fig=None):
    """Fractions of the long-run motions of a ``montecarlo`` sweep reduced to one or two axes.

    Two axes: one map per motion class that occurs. One axis: one curve per class.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    frac = ds["fraction"].where(ds["point_done"])
    present = [str(m) for m in ds["motion"].values if bool((frac.sel(motion=m) > 0).any())]
    if not present:
        present = [str(ds["motion"].values[0])]
    if len(dims) == 2:
        y, x = dims
        ncol = min(3, len(present))
        nrow = -(-len(present) // ncol)
        if fig is None:
            fig = plt.figure(figsize=(4.2 * ncol, 3.4 * nrow), layout="constrained")
        axs = fig.subplots(nrow, ncol, squeeze=False)
        for ax, m in zip(axs.ravel(), present, strict=False):
            img = frac.sel(motion=m).transpose(y, x).values
            pc = ax.pcolormesh(ds[x].values, ds[y].values, np.ma.masked_invalid(img), vmin=0.0,
                               vmax=1.0, cmap="viridis", shading="nearest")
            ax.set_title(m)
            ax.set_xlabel(_axis_label(ds, x))
            ax.set_ylabel(_axis_label(ds, y))
            fig.colorbar(pc, ax=ax, label="fraction")
        for ax in axs.ravel()[len(present):]:
            ax.set_visible(False)
    else:
        if fig is None:
            fig = plt.figure(figsize=(7.2, 4.8), layout="constrained")
        ax = fig.subplots()
        if dims:
            x = dims[0]
            for m in present:
                ax.plot(ds[x].values, frac.sel(motion=m).values, "o-", ms=3, label=m)
            ax.set_xlabel(_axis_label(ds, x))
        else:
            ax.bar(present, [float(frac.sel(motion=m)) for m in present])
        ax.set_ylabel("fraction of random starts")
        ax.set_ylim(-0.02, 1.02)
        if dims:
            ax.legend(**_LEGEND)
    fig.suptitle(" ".join(filter(None, ["long-run motion", _title(ds, dims)])))
    if fig.get_layout_engine() is None:  # a figure passed in
        fig.tight_layout()
    return fig


def plot_bifurcation(ds, dims, ax=None):
    """Brute-force bifurcation diagram of a ``bifurcation`` sweep: the stored impact velocities
    of each point against the first remaining axis; a second axis (at most 8 values) is drawn in
    colours.

    Returns
    -------
    matplotlib.axes.Axes
    """
    fig, ax = _axes(ax)
    v = ds["impact_velocity"].where(ds["point_done"])
    if len(dims) == 2 and ds.sizes[dims[1]] > 8:
        raise ValueError(f"a bifurcation diagram colours at most 8 values of its second axis; "
                         f"{dims[1]} has {ds.sizes[dims[1]]}: fix it with --select AXIS=VALUE")
    groups = [(None, v)] if len(dims) < 2 else [
        (f"{dims[1]} = {float(c):g}", v.sel({dims[1]: c})) for c in ds[dims[1]].values]
    for j, (label, vj) in enumerate(groups):
        vals = np.asarray(vj.transpose(*(d for d in dims[:1]), "impact").values)
        xv = (np.broadcast_to(ds[dims[0]].values[:, None], vals.shape) if dims
              else np.zeros(vals.shape))
        ok = np.isfinite(vals)
        ax.plot(xv[ok], vals[ok], ".", color="k" if label is None else f"C{j}", ms=1.5, alpha=0.6,
                label=label)
    if dims:
        ax.set_xlabel(dims[0])
    if len(groups) > 1:
        ax.legend(markerscale=4, **_LEGEND)
    ax.set_ylabel("impact velocity (last impacts)")
    ax.set_title(" ".join(filter(None, ["bifurcation diagram", _title(ds, dims)])))
    return ax


def plot_sweep(store, out, *, select: dict | None = None, dpi: int = 150) -> Path:
    """Draw a sweep store into a file: a stability chart (``orbits``), fraction maps
    (``montecarlo``) or a bifurcation diagram (``bifurcation``).

    Parameters
    ----------
    store : str or os.PathLike
        A store written by :func:`impactbar.sweeps.run_sweep`.
    out : str or os.PathLike
        The figure file; its suffix picks the format.
    select : dict of str to float, optional
        Fix axes at the nearest grid value, down to two.
    dpi : int, optional

    Returns
    -------
    pathlib.Path
        ``out``.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from .store import open_sweep

    ds = open_sweep(store)
    task = ds.attrs["task"]
    out = Path(out)
    try:
        red, dims = reduce_axes(ds, select, 2)
        red = red.load()
    except ValueError:
        raise
    except Exception as exc:  # a damaged zarr chunk: zarr and its codecs raise many kinds
        raise ValueError(f"{store}: the stored data cannot be read ({type(exc).__name__}: {exc}); "
                         "rerun the sweep on this store to recompute the damaged chunks") from None
    if task == "orbits":
        fig = plot_stability_chart(red, dims).figure
    elif task == "montecarlo":
        fig = plot_fraction_maps(red, dims)
    else:
        fig = plot_bifurcation(red, dims).figure
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out
