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

from ._shared.columns import IV_HI, IV_LO
from .laws.wave.periodic import wave_existence_edge
from .loads import CosineLoad, SquareWaveLoad
from .model import BarModel
from .orbits.charts import (
    hydraulic_existence_edge,
    pneumatic_existence_edge,
    pneumatic_stability_curve,
)
from .orbits.find import periodic_orbits
from .orbits.orbit import PeriodicOrbit
from .plotting.paper import (
    R_CURVES,
    _save,
    fig4_plot,
    fig5_plot,
    fig6_plot,
    fig7_plot,
    fig8_plot,
)

__all__ = ["reproduce", "fig4_data", "fig5_data", "fig6_data", "fig7_data", "fig8_data", "fig4_plot",
           "fig5_plot", "fig6_plot", "fig7_plot", "fig8_plot",
           "hydraulic_edge_closed_form"]

TWO_PI = 2.0 * math.pi
RIGID = BarModel(s=50.0, d=0.0, R=0.0, n_modes=0)  # the paper's s -> infinity limit


#: an orbit's columns in the figures' rows (the CSV format of ``impactbar paper``, kept as it is)
_ROW_FIELDS = PeriodicOrbit.fields.select(names=("phase", "stable", "schur_stable", "admissible",
                                                 "admissibility", "max_abs_multiplier"))


def _orbit_rows(model, load, x, R):
    rows = []
    orbits = periodic_orbits(model, load)
    for i, o in enumerate(orbits):
        cosine = load.abilities.cosine
        if cosine is not None:  # branch 0: load falling through its mean at impact
            _, pk, k = cosine
            branch = 0 if math.cos(k * o.phase) * pk < 0 else 1
        else:
            branch = i
        rows.append({"R": R, "x": x, "branch": branch, **_ROW_FIELDS.record(o)})
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
    (lo, _), (_, hi) = bad[0], bad[-1]
    return lo, hi


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
        out[f"sticks_from_2pid={tag}"] = seg[:, IV_LO]
        out[f"sticks_to_2pid={tag}"] = seg[:, IV_HI]
        wave = model.with_(impact="wave")
        out[f"existence_wave_2pid={tag}"] = np.array([wave_existence_edge(wave.with_(R=float(r)))
                                                      for r in R])
        out[f"stability_wave_2pid={tag}"] = pneumatic_stability_curve(wave, R).y
    return out


def fig6_data(n: int = 19, n_modes: int = 8) -> dict:
    """Fig. 6 curves for ``k = 10``: existence edge, and the stability edge by the paper's criterion
    and by the exact multipliers for ``s pi`` in ``{inf, 10.1, 10.01}``, on ``n`` restitutions from
    0 to 0.9 (the default's step 0.05 holds ``R = 0.5``, where the summary quotes the edges)."""
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


def reproduce(out_dir, *, quick: bool = False, progress=None, dpi: int = 130,
              format: str = "png") -> list[tuple[str, str, str]]:
    """Compute and write Figs. 4-8 as ``figN.png`` (or ``.pdf``, ``.svg``) and ``figN.csv`` in
    ``out_dir``.

    Parameters
    ----------
    out_dir : str or path-like
        Created if missing.
    quick : bool
        Fewer points per curve (for tests).
    progress : callable, optional
        Called with the figure's name (``"fig4"``, ...) when that figure is done.
    dpi : int, optional
        Resolution of the PNG figures, in ``[1, 1200]`` (default 130).
    format : {"png", "pdf", "svg"}, optional
        File format of the figures (default ``"png"``).

    Returns
    -------
    list of (str, str, str)
        Summary rows ``(figure, quantity, value)``.

    Raises
    ------
    ValueError
        For a ``format`` or ``dpi`` out of range.

    Examples
    --------
    >>> import os, tempfile
    >>> from impactbar.paper import reproduce
    >>> out = tempfile.mkdtemp()
    >>> rows = reproduce(out, quick=True, format="svg")
    >>> sorted(os.listdir(out))[:4]
    ['fig4.csv', 'fig4.svg', 'fig5.csv', 'fig5.svg']
    >>> rows[1]
    ('4', 'R=0: admissible stable orbits sampled', '4')
    """
    if format not in ("png", "pdf", "svg"):
        raise ValueError(f"format must be one of 'png', 'pdf', 'svg'; got {format!r}")
    if not 1 <= dpi <= 1200:
        raise ValueError(f"dpi must be in [1, 1200]; got {dpi}")
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    f = 0.3 if quick else 1.0
    summary: list[tuple[str, str, str]] = []

    def figure(name, data, write, plot):
        """Write a figure's data (CSV) and the figure, and say it is done."""
        write(out / f"{name}.csv", data)
        ax = plot(data)
        _save((ax[0] if isinstance(ax, tuple) else ax).figure, out / f"{name}.{format}", dpi=dpi)
        if progress is not None:
            progress(name)

    rows4 = fig4_data(max(10, int(120 * f)))
    figure("fig4", rows4, _write_rows, fig4_plot)
    r0 = [r for r in rows4 if r["R"] == 0.0 and r["stable"]]
    summary.append(("4", "R=0: stable orbits that stick (paper counts them)",
                    f"{sum(not r['admissible'] for r in rows4 if r['R'] == 0.0 and r['schur_stable'])}"
                    f" of {sum(r['schur_stable'] for r in rows4 if r['R'] == 0.0)} sampled"))
    summary.append(("4", "R=0: admissible stable orbits sampled", str(len(r0))))

    d5 = fig5_data(max(8, int(40 * f)))
    figure("fig5", d5, _write_columns, fig5_plot)
    for what, lo, hi in (("R=0, 2pid=0: stable band p0/p1", "stability_exact_2pid=0", "existence_2pid=0"),
                         ("R=0, 2pid=0: inadmissible (sticks) for p0/p1 in", "sticks_from_2pid=0",
                          "sticks_to_2pid=0"),
                         ("R=0, 2pid=0: stable band p0/p1, wave law (s pi = 157)", "stability_wave_2pid=0",
                          "existence_wave_2pid=0"),
                         ("R=0, 2pid=0.03: stable band p0/p1", "stability_exact_2pid=0.03",
                          "existence_2pid=0.03")):
        summary.append(("5", what, f"{d5[lo][0]:.6f} .. {d5[hi][0]:.6f}"))

    d6 = fig6_data(19 if f >= 1 else 10)  # both grids hold R = 0.5
    figure("fig6", d6, _write_columns, fig6_plot)
    i5 = int(np.argmin(np.abs(d6["R"] - 0.5)))
    for tag in ("inf", "10.1", "10.01"):
        summary.append(("6", f"R={d6['R'][i5]:.2f}, s pi={tag}: edge paper / exact / wave law",
                        f"{d6[f'paper_spi={tag}'][i5]:.5f} / {d6[f'exact_spi={tag}'][i5]:.5f}"
                        f" / {d6[f'wave_spi={tag}'][i5]:.5f}"))

    rows7 = fig7_data(max(10, int(100 * f)))
    figure("fig7", rows7, _write_rows, fig7_plot)
    summary.append(("7", "stable one-impact orbits found", str(sum(r["stable"] for r in rows7))))
    summary.append(("7", "orbits sampled / inadmissible",
                    f"{len(rows7)} / {sum(not r['admissible'] for r in rows7)}"))

    d8 = fig8_data(max(8, int(40 * f)))
    figure("fig8", d8, _write_columns, fig8_plot)
    summary.append(("8", "R=0, 2pid=0: kappa* (closed form sqrt 2)",
                    f"{d8['existence_2pid=0'][0]:.10f}"))
    summary.append(("8", "max |root-found - closed form|, 2pid=0",
                    f"{np.max(np.abs(d8['existence_2pid=0'] - d8['closed_form_2pid=0'])):.1e}"))
    return summary
