"""Sweep datasets (:func:`impactbar.sweeps.open_sweep`, reduced to one or two axes): stability charts,
fraction maps and bifurcation diagrams. Nothing is computed again; points not yet stored stay blank."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_stability_chart", "plot_efficiency_map", "plot_fraction_maps", "plot_bifurcation",
           "stability_category", "STABILITY_CATEGORIES"]

#: categories of the stability chart, in colour order
STABILITY_CATEGORIES = ("no orbit", "no admissible orbit", "admissible, none stable", "stable orbit",
                        "failed")
_CATEGORY_COLOURS = ("#ffffff", "#f4a582", "#92c5de", "#0571b0", "#444444")



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


def plot_efficiency_map(ds, dims, ax=None):
    """The efficiency of the blows of an ``orbits`` sweep under the rod-rock law (a store with the
    ``efficiency`` variable, :class:`impactbar.sweeps.SweepSpec`'s ``rock``), reduced to one or two
    axes: at each point, the largest efficiency of a stable orbit's blow (work on rock over the
    energy available to the blow, theory section 4d; blank where no orbit is stable).

    Parameters
    ----------
    ds : xarray.Dataset
        The store (:func:`impactbar.sweeps.open_sweep`) reduced to ``dims``
        (:func:`impactbar.sweeps.plot.reduce_axes`).
    dims : sequence of str
        One or two axes (two: the first is the chart's rows).
    ax : matplotlib.axes.Axes, optional
        Default: a new figure, 6.4 x 4.8 inches.

    Returns
    -------
    matplotlib.axes.Axes

    Raises
    ------
    ValueError
        If the store has no ``efficiency`` (not a rod-rock sweep), or ``dims`` is not one or two axes.
    """
    if "efficiency" not in ds.variables:
        raise ValueError("the sweep has no efficiency: it was not run under the rod-rock law "
                         "(a [rock] table in the spec)")
    if len(dims) not in (1, 2):
        raise ValueError(f"an efficiency map shows one or two axes; got {list(dims)}")
    fig, ax = _axes(ax)
    order = (*dims, "orbit")
    eff = np.asarray(ds["efficiency"].transpose(*order).values, dtype=float)
    stable = np.asarray(ds["stable"].transpose(*order).values, dtype=bool)
    best = np.max(np.where(stable & np.isfinite(eff), eff, -np.inf), axis=-1)
    best[~np.isfinite(best)] = np.nan
    if len(dims) == 2:
        y, x = dims
        mesh = ax.pcolormesh(ds[x].values, ds[y].values, np.ma.masked_invalid(best), cmap="viridis",
                             vmin=0.0, vmax=1.0, shading="nearest")
        fig.colorbar(mesh, ax=ax, label="efficiency of the blow")
        ax.set_xlabel(_axis_label(ds, x))
        ax.set_ylabel(_axis_label(ds, y))
    else:
        x = dims[0]
        ax.plot(ds[x].values, best, "o-", color="C0", ms=3, label="stable orbit")
        ax.set_xlabel(_axis_label(ds, x))
        ax.set_ylabel("efficiency of the blow")
        ax.set_ylim(0.0, 1.0)
        ax.legend(**_LEGEND)
    ax.set_title(" ".join(filter(None, ["blows on rock", _title(ds, dims)])))
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
