"""A drifter's design map (:func:`impactbar.sweeps.run_map`, reduced to one or two axes): one variable
as a line or filled contours, the stability edge, the border-collision edges and the cavitation
region drawn over it, the axes labelled in a designer's units (L/min, MPa, L, mm, ms, kW: the store
keeps SI). Nothing is computed again."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_operating_map", "DEFAULT_MAP_VARIABLE"]

#: the variable drawn when none is named
DEFAULT_MAP_VARIABLE = "blow_frequency"
#: the flags drawn over a map: variable, colour, legend label
_FLAGS = (("stable", "red", "stability edge (a multiplier crosses the unit circle)"),
          ("relief_opens", "magenta", "relief valve starts to open"),
          ("accumulator_empties", "orange", "accumulator starts to empty"))


#: the units a designer reads a map's SI values in (the store keeps SI): SI unit -> (shown, factor)
DISPLAY_UNITS = {"m3/s": ("L/min", 6e4), "m^3/s": ("L/min", 6e4), "m**3/s": ("L/min", 6e4),
                 "Pa": ("MPa", 1e-6), "m3": ("L", 1e3), "m^3": ("L", 1e3), "m**3": ("L", 1e3),
                 "m": ("mm", 1e3), "s": ("ms", 1e3), "W": ("kW", 1e-3), "m2": ("cm^2", 1e4),
                 "m^2": ("cm^2", 1e4), "m**2": ("cm^2", 1e4)}


def _label(ds, name: str) -> str:
    """``name [units]`` in the units of :data:`DISPLAY_UNITS` (else SI, from the store's
    attributes; no unit for a pure number)."""
    units = ds[name].attrs.get("units", "")
    units, _ = DISPLAY_UNITS.get(units, (units, 1.0))
    return name if units in ("", "1") else f"{name} [{units}]"


def _shown(ds, name: str, axis) -> None:
    """Ticks of ``axis`` (an x or y axis, or a colour bar's) in the units of :func:`_label`."""
    from matplotlib.ticker import FuncFormatter

    _, factor = DISPLAY_UNITS.get(ds[name].attrs.get("units", ""), ("", 1.0))
    if factor != 1.0:
        axis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v * factor:.6g}"))


def plot_operating_map(ds, dims, variable: str | None = None, ax=None):
    """Draw one variable of a design map over its one or two remaining axes.

    Parameters
    ----------
    ds : xarray.Dataset
        A drifter map store (:func:`impactbar.sweeps.open_sweep`), reduced to ``dims``, loaded.
    dims : tuple of str
        One axis (a line; the points without an orbit left out, unstable ones marked) or two (filled
        contours, the first axis across; each flag's 0.5-contour drawn over, the cavitating points
        hatched).
    variable : str, optional
        A stored variable (default :data:`DEFAULT_MAP_VARIABLE`).
    ax : matplotlib.axes.Axes, optional
        Where to draw; by default on a new figure of 7.2 x 4.8 inches.

    Returns
    -------
    matplotlib.axes.Axes
        The map's axes (its colour bar, for two axes, on the same figure).

    Raises
    ------
    ValueError
        An unknown variable (the stored ones listed), or other than one or two axes.
    """
    import matplotlib.pyplot as plt

    name = DEFAULT_MAP_VARIABLE if variable is None else variable
    grid_vars = [v for v in ds.data_vars if ds[v].dims == tuple(dims) and ds[v].dtype.kind in "fbi"]
    if name not in grid_vars:
        raise ValueError(f"--variable {name!r} is not a variable of this map; choose one of "
                         f"{sorted(grid_vars)}")
    if len(dims) not in (1, 2):
        raise ValueError(f"a map is drawn over one or two axes; {len(dims)} remain: fix the others with "
                         "--select AXIS=VALUE")
    if ax is None:
        _, ax = plt.subplots(figsize=(7.2, 4.8), layout="constrained")
    ok = np.asarray(ds["status"]) == 0
    if "point_done" in ds:
        ok &= np.asarray(ds["point_done"], dtype=bool)
    z = np.where(ok, np.asarray(ds[name], dtype=float), np.nan)
    if len(dims) == 1:
        x = np.asarray(ds[dims[0]], dtype=float)
        ax.plot(x, z, "o-", ms=3, color="C0")
        if "stable" in ds:
            bad = ok & ~np.asarray(ds["stable"], dtype=bool)
            if np.any(bad):
                ax.plot(x[bad], z[bad], "rx", label="not stable")
        if "cavitates" in ds:
            cav = ok & np.asarray(ds["cavitates"], dtype=bool)
            if np.any(cav):
                ax.plot(x[cav], z[cav], "ks", mfc="none", label="cavitates")
        ax.set_xlabel(_label(ds, dims[0]))
        ax.set_ylabel(_label(ds, name))
        _shown(ds, dims[0], ax.xaxis)
        _shown(ds, name, ax.yaxis)
        handles, _ = ax.get_legend_handles_labels()
        if handles:
            ax.legend(fontsize="small")
        return ax
    y_dim, x_dim = dims  # the first axis slowest: rows
    x = np.asarray(ds[x_dim], dtype=float)
    y = np.asarray(ds[y_dim], dtype=float)
    X, Y = np.meshgrid(x, y)
    if np.any(np.isfinite(z)) and np.nanmax(z) > np.nanmin(z):
        filled = ax.contourf(X, Y, np.ma.masked_invalid(z), levels=14, cmap="viridis")
    else:
        filled = ax.pcolormesh(X, Y, np.ma.masked_invalid(z), cmap="viridis", shading="nearest")
    bar = ax.figure.colorbar(filled, ax=ax, label=_label(ds, name))
    _shown(ds, name, bar.ax.yaxis)
    handles = []
    for flag, colour, text in _FLAGS:
        if flag not in ds:
            continue
        f = np.where(ok, np.asarray(ds[flag], dtype=float), np.nan)
        if np.nanmin(f, initial=np.inf) < 0.5 < np.nanmax(f, initial=-np.inf):
            ax.contour(X, Y, np.ma.masked_invalid(f), levels=[0.5], colors=colour, linewidths=1.6)
            handles.append(plt.Line2D([], [], color=colour, lw=1.6, label=text))
    if "cavitates" in ds:
        cav = np.where(ok, np.asarray(ds["cavitates"], dtype=float), np.nan)
        if np.nanmax(cav, initial=0.0) > 0.5:
            ax.contourf(X, Y, np.ma.masked_invalid(cav), levels=[0.5, 1.5], colors="none", hatches=["xx"])
            handles.append(plt.Rectangle((0, 0), 1, 1, fc="none", hatch="xx", label="cavitates"))
    missing = ~ok
    if np.any(missing):
        ax.plot(X[missing], Y[missing], "k.", ms=3)
        handles.append(plt.Line2D([], [], color="k", marker=".", ls="", label="no orbit"))
    if "edge_value" in ds:  # the refined edges: where each lies between its two grid points
        value, axis, index = (np.asarray(ds[k]) for k in ("edge_value", "edge_axis", "edge_index"))
        names = list(ds.attrs.get("axes", []))
        pts = []
        for v, k, idx in zip(value, axis, index, strict=True):
            if np.isfinite(v) and names and names[int(k)] in (x_dim, y_dim):
                other = y_dim if names[int(k)] == x_dim else x_dim
                j = names.index(other)
                o = float(np.asarray(ds[other])[idx[j]]) if ds[other].ndim else None
                if o is not None:
                    pts.append((v, o) if names[int(k)] == x_dim else (o, v))
        if pts:
            # on the map's border half a diamond would be clipped: drawn whole, over the frame
            ax.plot(*np.transpose(pts), "wD", mec="k", ms=4, clip_on=False, zorder=5)
            handles.append(plt.Line2D([], [], color="w", mec="k", marker="D", ls="", ms=4,
                                      label="edge refined by bisection"))
    ax.set_title(ds[name].attrs.get("long_name", name), fontsize="medium")
    ax.set_xlabel(_label(ds, x_dim))
    ax.set_ylabel(_label(ds, y_dim))
    _shown(ds, x_dim, ax.xaxis)
    _shown(ds, y_dim, ax.yaxis)
    if handles:
        ax.legend(handles=handles, fontsize="small", loc="upper left", bbox_to_anchor=(0.0, -0.14),
                  ncols=2, frameon=False)
    return ax
