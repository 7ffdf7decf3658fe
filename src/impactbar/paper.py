"""The paper's Figs. 4-8, recomputed, with what the paper could not show (``impactbar paper``).

Each ``figN_data`` function computes the plotted data (plain arrays, no matplotlib); ``figN_plot``
draws it; :func:`reproduce` writes every figure as PNG with a CSV of its data and returns a summary.

- Fig. 4: phase against ``k p0/pk``, pneumatic, ``d = 0``, ``R = 0..0.9``: stable solid, unstable
  dashed (exact multipliers, rigid bar), inadmissible orbits marked.
- Fig. 5: stable band of ``p0/p1`` against ``R``, ``k = 1``, ``2 pi d = 0`` and ``0.03``; the
  admissible part of the band marked (at small ``R`` the end sticks, theory §5).
- Fig. 6: the same for ``k = 10`` with ``s pi -> inf``, ``10.1`` and ``10.01``: the paper's criterion
  (eqs. 37, 39) against the exact multipliers of an 8-mode bar.
- Figs. 5 and 6 also draw the stability edge under the wave impact law (the stop as a long rod,
  theory §4b), where the contact lasts ``2/s`` (``s pi = 157`` stands for the rigid limit).
- Fig. 7: phase against ``kappa``, hydraulic, ``R = 0..0.9`` (all unstable, eq. 41).
- Fig. 8: the ``kappa`` above which no one-impact orbit exists, against ``R``, ``2 pi d = 0`` and
  ``0.03``, with the closed form ``kappa* = (2 R + sqrt(2 + 2 R^2)) / (1 + R)`` at ``d = 0``.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from .loads import CosineLoad, SquareWaveLoad
from .model import BarModel
from .orbits.charts import (
    hydraulic_existence_edge,
    pneumatic_existence_edge,
    pneumatic_stability_curve,
)
from .orbits.one_impact import periodic_orbits
from .orbits.wave import wave_existence_edge

__all__ = ["reproduce", "fig4_data", "fig5_data", "fig6_data", "fig7_data", "fig8_data", "fig4_plot",
           "fig5_plot", "fig6_plot", "fig7_plot", "fig8_plot",
           "hydraulic_edge_closed_form"]

TWO_PI = 2.0 * math.pi
R_CURVES = np.round(np.arange(0.0, 0.95, 0.1), 1)
RIGID = BarModel(s=50.0, d=0.0, R=0.0, n_modes=0)  # the paper's s -> infinity limit


def _orbit_rows(model, load, x, R):
    rows = []
    orbits = periodic_orbits(model, load)
    for i, o in enumerate(orbits):
        if isinstance(load, CosineLoad):  # branch 0: load falling through its mean at impact
            branch = 0 if math.cos(load.k * o.phase) * load.pk < 0 else 1
        else:
            branch = i
        rows.append({"R": R, "x": x, "branch": branch, "phase": o.phase, "stable": o.stable,
                     "schur_stable": o.schur_stable, "admissible": o.admissible,
                     "admissibility": o.admissibility, "max_abs_multiplier": o.max_abs_multiplier})
    return rows


def fig4_data(n: int = 120) -> list[dict]:
    """Fig. 4 rows: ``R, x = k p0/pk, phase, stable, schur_stable, admissible, ...`` (rigid bar)."""
    rows = []
    for R in R_CURVES:
        edge = pneumatic_existence_edge(R)
        for x in np.linspace(edge / n, edge * (1 - 1e-9), n):
            rows += _orbit_rows(RIGID.with_(R=float(R)), CosineLoad(x, 1.0), x, float(R))
    return rows


def fig7_data(n: int = 100) -> list[dict]:
    """Fig. 7 rows: ``R, x = kappa, phase, stable, ...`` for the hydraulic load (rigid bar)."""
    rows = []
    for R in R_CURVES:
        model = RIGID.with_(R=float(R))
        top = hydraulic_existence_edge(model)
        for x in np.linspace(1.0 + 1e-6, top - 1e-9, n):
            rows += _orbit_rows(model, SquareWaveLoad(1.0, x), x, float(R))
    return rows


def _inadmissible_segment(model, lo, hi, k=1, n_scan=12):
    """The part ``(a, b)`` of the stable band ``[lo, hi]`` where the stable-branch orbit is not
    admissible, with its ends found by bisection on the admissibility flag; ``(nan, nan)`` if none.
    """
    from .orbits.charts import _stable_branch_phase, admissibility_edges  # noqa: PLC0415

    def make(x):
        return CosineLoad(x / k, 1.0, k)

    def select(orbits):
        if not orbits:
            return None
        ph = _stable_branch_phase(model, orbits[0].load)
        if ph is None:
            return None
        return next((o for o in orbits if abs(o.phase - ph) < 1e-9), None)

    a, b = lo * (1 + 1e-9), hi * (1 - 1e-7)
    edges = admissibility_edges(model, make, a, b, select, n_scan=n_scan)
    pts = [a, *edges, b]
    bad = []
    for x0, x1 in zip(pts[:-1], pts[1:], strict=True):
        o = select(periodic_orbits(model, make(0.5 * (x0 + x1))))
        if o is not None and not o.admissible:
            bad.append((x0, x1))
    if not bad:
        return math.nan, math.nan
    return bad[0][0], bad[-1][1]


def fig5_data(n: int = 40) -> dict:
    """Fig. 5 curves for ``k = 1``: ``R``, and for each ``2 pi d`` in ``{0, 0.03}`` the existence edge,
    the stability edge (exact; the paper's coincides for the rigid bar) and the edge of admissibility
    on the stable branch."""
    R = np.linspace(0.0, 0.95, n)
    out = {"R": R}
    for tag, d in (("0", 0.0), ("0.03", 0.03 / TWO_PI)):
        model = RIGID.with_(d=d)
        upper = pneumatic_existence_edge(R, d)
        lower = pneumatic_stability_curve(model, R).y
        paper = pneumatic_stability_curve(model, R, criterion="paper").y
        seg = np.array([
            _inadmissible_segment(model.with_(R=float(r)), lo, up) if np.isfinite(lo) else (np.nan,) * 2
            for r, lo, up in zip(R, lower, upper, strict=True)
        ]).reshape(-1, 2)
        out[f"existence_2pid={tag}"] = upper
        out[f"stability_exact_2pid={tag}"] = lower
        out[f"stability_paper_2pid={tag}"] = paper
        out[f"sticks_from_2pid={tag}"] = seg[:, 0]
        out[f"sticks_to_2pid={tag}"] = seg[:, 1]
        wave = model.with_(impact="wave")
        out[f"existence_wave_2pid={tag}"] = np.array([wave_existence_edge(wave.with_(R=float(r)))
                                                      for r in R])
        out[f"stability_wave_2pid={tag}"] = pneumatic_stability_curve(wave, R).y
    return out


def fig6_data(n: int = 24, n_modes: int = 8) -> dict:
    """Fig. 6 curves for ``k = 10``: existence edge, and the stability edge by the paper's criterion
    and by the exact multipliers for ``s pi`` in ``{inf, 10.1, 10.01}``."""
    k = 10
    R = np.linspace(0.0, 0.9, n)
    out = {"R": R, "existence": pneumatic_existence_edge(R, 0.0, k)}
    for tag, model in (("inf", RIGID), ("10.1", BarModel(10.1 / math.pi, 0.0, 0.0, n_modes)),
                       ("10.01", BarModel(10.01 / math.pi, 0.0, 0.0, n_modes))):
        out[f"paper_spi={tag}"] = pneumatic_stability_curve(model, R, k, criterion="paper").y
        out[f"exact_spi={tag}"] = pneumatic_stability_curve(model, R, k).y
        out[f"wave_spi={tag}"] = pneumatic_stability_curve(model.with_(impact="wave"), R, k).y
    return out


def hydraulic_edge_closed_form(R):
    """``kappa*`` at ``d = 0``: the zero-mean triangle ``V`` peaks at ``(2 - kappa) kappa pi / 2``, and
    ``(1 + R) V_max = (kappa - 1) pi (1 - R)`` gives ``kappa* = (2 R + sqrt(2 + 2 R^2)) / (1 + R)``."""
    R = np.asarray(R, dtype=float)
    return (2 * R + np.sqrt(2 + 2 * R * R)) / (1 + R)


def fig8_data(n: int = 40) -> dict:
    """Fig. 8 curves: the existence edge ``kappa*(R)`` for ``2 pi d = 0`` and ``0.03``."""
    R = np.linspace(0.0, 0.95, n)
    out = {"R": R, "closed_form_2pid=0": hydraulic_edge_closed_form(R)}
    for tag, d in (("0", 0.0), ("0.03", 0.03 / TWO_PI)):
        out[f"existence_2pid={tag}"] = np.array(
            [hydraulic_existence_edge(RIGID.with_(R=float(r), d=d)) for r in R])
    return out


# ------------------------------------------------------------------ output ------------------------
def _write_rows(path: Path, rows: list[dict]) -> None:
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def _write_columns(path: Path, cols: dict) -> None:
    keys = list(cols)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(keys)
        for i in range(len(cols[keys[0]])):
            w.writerow([f"{float(cols[k][i]):.12g}" for k in keys])


# ------------------------------------------------------------------ drawing -----------------------
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


def _save(fig, path: Path) -> None:
    """Write the PNG and close the figure: the same last steps for every figure."""
    fig.savefig(path, dpi=130)
    import matplotlib.pyplot as plt  # noqa: PLC0415

    plt.close(fig)


def reproduce(out_dir, *, quick: bool = False, progress=None) -> list[tuple[str, str, str]]:
    """Compute and write Figs. 4-8 as ``figN.png`` and ``figN.csv`` in ``out_dir``.

    Parameters
    ----------
    out_dir : str or path-like
        Created if missing.
    quick : bool
        Fewer points per curve (for tests).
    progress : callable, optional
        Called with the figure's name (``"fig4"``, ...) when that figure is done.

    Returns
    -------
    list of (str, str, str)
        Summary rows ``(figure, quantity, value)``.
    """
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    f = 0.3 if quick else 1.0
    summary: list[tuple[str, str, str]] = []

    def done(name):
        if progress is not None:
            progress(name)

    # Fig. 4
    rows4 = fig4_data(max(10, int(120 * f)))
    _write_rows(out / "fig4.csv", rows4)
    ax = fig4_plot(rows4)
    _save(ax.figure, out / "fig4.png")
    r0 = [r for r in rows4 if r["R"] == 0.0 and r["stable"]]
    summary.append(("4", "R=0: stable orbits that stick (paper counts them)",
                    f"{sum(not r['admissible'] for r in rows4 if r['R'] == 0.0 and r['schur_stable'])}"
                    f" of {sum(r['schur_stable'] for r in rows4 if r['R'] == 0.0)} sampled"))
    summary.append(("4", "R=0: admissible stable orbits sampled", str(len(r0))))
    done("fig4")

    # Fig. 5
    d5 = fig5_data(max(8, int(40 * f)))
    _write_columns(out / "fig5.csv", d5)
    ax, _, _ = fig5_plot(d5)
    _save(ax.figure, out / "fig5.png")
    summary.append(("5", "R=0, 2pid=0: stable band p0/p1",
                    f"{d5['stability_exact_2pid=0'][0]:.6f} .. {d5['existence_2pid=0'][0]:.6f}"))
    summary.append(("5", "R=0, 2pid=0: inadmissible (sticks) for p0/p1 in",
                    f"{d5['sticks_from_2pid=0'][0]:.6f} .. {d5['sticks_to_2pid=0'][0]:.6f}"))
    summary.append(("5", "R=0, 2pid=0: stable band p0/p1, wave law (s pi = 157)",
                    f"{d5['stability_wave_2pid=0'][0]:.6f} .. {d5['existence_wave_2pid=0'][0]:.6f}"))
    summary.append(("5", "R=0, 2pid=0.03: stable band p0/p1",
                    f"{d5['stability_exact_2pid=0.03'][0]:.6f} .. {d5['existence_2pid=0.03'][0]:.6f}"))
    done("fig5")

    # Fig. 6
    d6 = fig6_data(max(6, int(24 * f)))
    _write_columns(out / "fig6.csv", d6)
    ax = fig6_plot(d6)
    _save(ax.figure, out / "fig6.png")
    i5 = int(np.argmin(np.abs(d6["R"] - 0.5)))
    for tag in ("inf", "10.1", "10.01"):
        summary.append(("6", f"R={d6['R'][i5]:.2f}, s pi={tag}: edge paper / exact / wave law",
                        f"{d6[f'paper_spi={tag}'][i5]:.5f} / {d6[f'exact_spi={tag}'][i5]:.5f}"
                        f" / {d6[f'wave_spi={tag}'][i5]:.5f}"))
    done("fig6")

    # Fig. 7
    rows7 = fig7_data(max(10, int(100 * f)))
    _write_rows(out / "fig7.csv", rows7)
    ax = fig7_plot(rows7)
    _save(ax.figure, out / "fig7.png")
    summary.append(("7", "stable one-impact orbits found", str(sum(r["stable"] for r in rows7))))
    summary.append(("7", "orbits sampled / inadmissible",
                    f"{len(rows7)} / {sum(not r['admissible'] for r in rows7)}"))
    done("fig7")

    # Fig. 8
    d8 = fig8_data(max(8, int(40 * f)))
    _write_columns(out / "fig8.csv", d8)
    ax, _ = fig8_plot(d8)
    _save(ax.figure, out / "fig8.png")
    summary.append(("8", "R=0, 2pid=0: kappa* (closed form sqrt 2)",
                    f"{d8['existence_2pid=0'][0]:.10f}"))
    summary.append(("8", "max |root-found - closed form|, 2pid=0",
                    f"{np.max(np.abs(d8['existence_2pid=0'] - d8['closed_form_2pid=0'])):.1e}"))
    done("fig8")
    return summary
