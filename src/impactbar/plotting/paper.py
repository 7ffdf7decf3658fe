"""The drawing of the paper's Figs. 4-8 from the data :mod:`impactbar.paper` computes."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["fig4_plot", "fig5_plot", "fig6_plot", "fig7_plot", "fig8_plot", "R_CURVES", "STYLE"]

TWO_PI = 2.0 * math.pi
#: the restitutions drawn as one curve each in Figs. 4 and 7
R_CURVES = np.round(np.arange(0.0, 0.95, 0.1), 1)


#: text sizes of every figure (points): nothing below 8
STYLE = {"font.size": 9.0, "axes.titlesize": 9.5, "axes.labelsize": 9.0, "legend.fontsize": 8.0,
         "xtick.labelsize": 8.5, "ytick.labelsize": 8.5, "legend.title_fontsize": 8.0}
#: the two dampings of Figs. 5 and 8: colour, line style, marker
DAMPING_STYLE = {"0": dict(color="k", marker=None), "0.03": dict(color="tab:blue", marker="o")}


def _styled(func):
    """Draw under :data:`STYLE` (text sizes are fixed when each text is made)."""
    import functools  # noqa: PLC0415

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        import matplotlib.pyplot as plt  # noqa: PLC0415

        with plt.rc_context(STYLE):
            return func(*args, **kwargs)

    return wrapper


def _new_axes(ax, figsize=(6.4, 4.6), *, nrows: int = 1, height_ratios=None):
    import matplotlib.pyplot as plt  # noqa: PLC0415

    if ax is not None:
        return ax
    fig, axes = plt.subplots(nrows, 1, figsize=figsize, layout="constrained", sharex=nrows > 1,
                             height_ratios=height_ratios, squeeze=False)
    return axes[0, 0] if nrows == 1 else tuple(axes[:, 0])


def _R_colours():
    """A colour per curve of ``R_CURVES`` and the matching norm and colormap (for a colorbar)."""
    import matplotlib as mpl  # noqa: PLC0415

    cmap = mpl.colors.ListedColormap(mpl.colormaps["viridis"](np.linspace(0.0, 0.85, len(R_CURVES))))
    step = float(R_CURVES[1] - R_CURVES[0])
    norm = mpl.colors.BoundaryNorm(np.append(R_CURVES, R_CURVES[-1] + step) - step / 2, cmap.N)
    return {float(R): cmap(norm(R)) for R in R_CURVES}, norm, cmap


def _phase_plot(ax, rows, xlabel: str):
    """Phase against the load factor for every ``R`` of ``R_CURVES``: one colour per ``R`` (a
    colorbar names them), stable solid, unstable dashed, inadmissible orbits crossed; the legend
    lists only what occurs and sits above the axes."""
    from matplotlib.lines import Line2D  # noqa: PLC0415

    colours, norm, cmap = _R_colours()
    seen = {"stable": False, "unstable": False, "inadmissible": False}
    for R in R_CURVES:
        col = colours[float(R)]
        sub = [r for r in rows if r["R"] == R]
        for br in sorted({r["branch"] for r in sub}):
            pts = sorted((r["x"], r["phase"], r["stable"], r["admissible"]) for r in sub
                         if r["branch"] == br)
            x, y, st, ad = (np.array(c) for c in zip(*pts, strict=True))
            y = np.where(np.abs(np.diff(y, prepend=y[0])) > 1.0, np.nan, y)  # wrap at 2 pi
            ax.plot(x, np.where(st & ad, y, np.nan), "-", color=col, lw=1.8)
            ax.plot(x, np.where(~st & ad, y, np.nan), "--", color=col, lw=1.0)
            seen["stable"] |= bool(np.any(st & ad))
            seen["unstable"] |= bool(np.any(~st & ad))
        bad = [(r["x"], r["phase"]) for r in sub if not r["admissible"]]
        if bad:
            seen["inadmissible"] = True
            x, y = np.array(bad).T
            ax.plot(x, y, "x", color="tab:red", ms=3, mew=0.7)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("phase φ (rad)")
    ax.set_ylim(0, TWO_PI)
    ax.set_yticks(np.arange(5) * math.pi / 2, ["0", "π/2", "π", "3π/2", "2π"])
    handles = {
        "stable": Line2D([], [], color="0.2", lw=1.8, label="stable (exact multipliers)"),
        "unstable": Line2D([], [], color="0.2", lw=1.0, ls="--", label="unstable"),
        "inadmissible": Line2D([], [], color="tab:red", marker="x", ls="", label="inadmissible"),
    }
    ax.legend(handles=[h for k, h in handles.items() if seen[k]], loc="upper center",
              bbox_to_anchor=(0.5, -0.13), ncol=3, frameon=False)
    import matplotlib as mpl  # noqa: PLC0415

    cb = ax.figure.colorbar(mpl.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, ticks=R_CURVES,
                            pad=0.02, fraction=0.05)
    cb.set_label("restitution R (one curve each)")
    return ax


@_styled
def fig4_plot(rows: list[dict], ax=None):
    """Draw Fig. 4 from :func:`fig4_data` rows: phase against ``k p0/pk`` (log scale), one colour per
    ``R``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _new_axes(ax)
    _phase_plot(ax, rows, "load factor k p0 / pk")
    ax.set_xscale("log")
    ax.set_title("Fig. 4: pneumatic, d = 0, rigid bar")
    return ax


@_styled
def fig7_plot(rows: list[dict], ax=None):
    """Draw Fig. 7 from :func:`fig7_data` rows: phase against ``kappa``, one colour per ``R``
    (every orbit unstable, eq. 41).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _new_axes(ax)
    _phase_plot(ax, rows, "κ (fraction of the period at +q, times 2)")
    ax.set_xlim(1.0, 2.0)
    ax.set_title("Fig. 7: hydraulic, d = 0, rigid bar (every orbit unstable, eq. 41)")
    return ax


@_styled
def fig5_plot(data: dict, axes=None):
    """Draw Fig. 5 from :func:`fig5_data`: the stable band of ``p0/p1`` against ``R`` for both
    dampings (top), how far damping moves its edges (bottom left), and the band at ``R = 0`` with the
    part where the end sticks (bottom right).

    Parameters
    ----------
    data : dict
        What :func:`fig5_data` returns.
    axes : sequence of three matplotlib.axes.Axes, optional
        Created when not given.

    Returns
    -------
    tuple of three matplotlib.axes.Axes
        The band, the shift, the ``R = 0`` band.
    """
    if axes is None:
        import matplotlib.pyplot as plt  # noqa: PLC0415

        fig = plt.figure(figsize=(7.0, 6.4), layout="constrained")
        m = fig.subplot_mosaic([["band", "band"], ["shift", "r0"]], height_ratios=(2.0, 1.0),
                               width_ratios=(1.5, 1.0))
        axes = (m["band"], m["shift"], m["r0"])
    ax, ax2, ax3 = axes
    R = data["R"]
    for tag, st in DAMPING_STYLE.items():
        mk = dict(marker=st["marker"], markevery=4, ms=4, mfc="none") if st["marker"] else {}
        ax.plot(R, data[f"existence_2pid={tag}"], "-", color=st["color"], lw=1.4, **mk,
                label=f"existence edge (fold), 2πd = {tag}")
        ax.plot(R, data[f"stability_exact_2pid={tag}"], "--", color=st["color"], lw=1.4, **mk,
                label=f"stability edge, 2πd = {tag}")
        if f"stability_wave_2pid={tag}" in data:
            ax.plot(R, data[f"stability_wave_2pid={tag}"], "-.", color=st["color"], lw=1.0, alpha=0.8,
                    label=f"stability edge, wave law (sπ = 157), 2πd = {tag}")
    ax.fill_between(R, data["stability_exact_2pid=0"], data["existence_2pid=0"], color="0.9",
                    lw=0, label="stable band")
    a, b = data["sticks_from_2pid=0"], data["sticks_to_2pid=0"]
    m = np.isfinite(a)
    if np.any(m):
        ax.vlines(R[m], a[m], b[m], color="tab:red", lw=6,
                  label="stable by the paper, but the end sticks (R = 0, lower right)")
    ax.set_xlabel("restitution R")
    ax.set_ylabel("p0 / p1")
    ax.set_yscale("log")
    ax.legend(loc="upper left", frameon=False)
    ax.set_title("Fig. 5: stable band, pneumatic, k = 1 (exact multipliers = paper, rigid bar)")
    for kind, ls in (("existence", "-"), ("stability_exact", "--")):
        shift = 100 * (data[f"{kind}_2pid=0.03"] / data[f"{kind}_2pid=0"] - 1)
        ax2.plot(R, shift, ls, color=DAMPING_STYLE["0.03"]["color"],
                 label=f"{'existence' if kind == 'existence' else 'stability'} edge")
    ax2.axhline(0.0, color="k", lw=0.6)
    ax2.set_xlabel("restitution R")
    ax2.set_ylabel("shift by 2πd = 0.03 (%)")
    ax2.legend(loc="lower left", frameon=False)
    for j, tag in enumerate(DAMPING_STYLE):
        lo, hi = data[f"stability_exact_2pid={tag}"][0], data[f"existence_2pid={tag}"][0]
        s0 = data[f"sticks_from_2pid={tag}"][0]
        s0 = hi if not np.isfinite(s0) else s0
        ax3.barh(j, s0 - lo, left=lo, height=0.55, color="0.65",
                 label="stable, admissible" if j == 0 else None)
        ax3.barh(j, hi - s0, left=s0, height=0.55, color="tab:red",
                 label="stable by the paper, end sticks" if j == 0 else None)
    ax3.set_yticks([0, 1], [f"2πd = {t}" for t in DAMPING_STYLE])
    ax3.set_ylim(-0.5, 2.4)
    ax3.set_xlabel("p0 / p1 at R = 0")
    ax3.legend(loc="upper left", frameon=False)
    return ax, ax2, ax3


@_styled
def fig6_plot(data: dict, ax=None):
    """Draw Fig. 6 from :func:`fig6_data`: the lower stability edge for ``k = 10``, the paper's
    criterion (dashed) against the exact multipliers (solid with dots) and the exact multipliers
    under the wave impact law (dash-dotted with crosses, theory §4b), one colour per ``s pi``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _new_axes(ax, figsize=(6.4, 5.0))
    ax.plot(data["R"], data["existence"], "-", color="0.5", lw=3, alpha=0.6,
            label="existence edge (eq. 38)")
    for tag, col in (("inf", "k"), ("10.1", "tab:blue"), ("10.01", "tab:orange")):
        name = "∞" if tag == "inf" else tag
        ax.plot(data["R"], data[f"paper_spi={tag}"], "--", color=col, lw=1.3,
                label=f"sπ = {name}: paper (eqs. 37, 39)")
        ax.plot(data["R"], data[f"exact_spi={tag}"], "-", marker=".", ms=5, lw=1.0, color=col,
                label=f"sπ = {name}: exact multipliers")
        if f"wave_spi={tag}" in data:
            ax.plot(data["R"], data[f"wave_spi={tag}"], "-.", marker="x", ms=4, lw=1.0, color=col,
                    alpha=0.8, label=f"sπ = {'157' if tag == 'inf' else name}: wave law")
    ax.set_xlabel("restitution R")
    ax.set_ylabel("k p0 / pk")
    ax.set_yscale("log")
    ax.legend(loc="upper left", bbox_to_anchor=(0.0, -0.13), ncol=2, frameon=False)
    ax.set_title("Fig. 6: lower stability edge, k = 10 (8-mode bar)")
    return ax


@_styled
def fig8_plot(data: dict, axes=None):
    """Draw Fig. 8 from :func:`fig8_data`: the ``kappa`` above which no one-impact orbit exists
    (top; the closed form under the root-found curve), and what damping changes (bottom).

    Returns
    -------
    tuple of two matplotlib.axes.Axes
    """
    ax, ax2 = _new_axes(axes, figsize=(6.4, 5.6), nrows=2, height_ratios=(2.2, 1.0))
    R = data["R"]
    ax.fill_between(R, data["existence_2pid=0"], 2.0, color="0.88", lw=0, label="no solutions")
    ax.plot(R, data["closed_form_2pid=0"], "-", color="tab:orange", lw=6, alpha=0.45,
            label="closed form (2R + √(2 + 2R²)) / (1 + R), 2πd = 0")
    ax.plot(R, data["existence_2pid=0"], "-", color="k", lw=1.2, label="root-found edge, 2πd = 0")
    ax.plot(R, data["existence_2pid=0.03"], "--", color="tab:blue", marker="o", markevery=4, ms=4,
            mfc="none", lw=1.2, label="root-found edge, 2πd = 0.03")
    ax.text(0.22, 1.3, "one-impact orbits exist,\nall unstable (eq. 41)", ha="center", fontsize=9)
    ax.text(0.2, 1.85, "no one-impact orbit", ha="center", fontsize=9)
    ax.set_ylabel("κ")
    ax.set_ylim(1, 2)
    ax.legend(loc="lower right", frameon=False)
    ax.set_title("Fig. 8: hydraulic, existence of one-impact orbits")
    ax2.plot(R, data["existence_2pid=0.03"] - data["existence_2pid=0"], "--", color="tab:blue",
             label="edge(2πd = 0.03) - edge(2πd = 0)")
    ax2.axhline(0.0, color="k", lw=0.6)
    ax2.set_xlabel("restitution R")
    ax2.set_ylabel("shift of κ*")
    ax2.legend(loc="lower left", frameon=False)
    return ax, ax2


def _save(fig, path: Path, *, dpi: int = 130) -> None:
    """Write the figure (its format from the suffix) and close it: the same last steps for every
    figure.

    A PNG's constrained layout is made here, at the file's resolution, and the layout engine then
    removed: matplotlib's ``savefig`` would otherwise draw the whole figure twice, once with its
    drawing switched off only to run the layout, then for the file (the same pixels either way)."""
    engine = fig.get_layout_engine()
    if engine is not None and path.suffix == ".png":
        fig.dpi = dpi  # (the layout's text extents at the file's resolution, as savefig measures them)
        engine.execute(fig)
        fig.set_layout_engine(None)
    fig.savefig(path, dpi=dpi)
    import matplotlib.pyplot as plt  # noqa: PLC0415

    plt.close(fig)
