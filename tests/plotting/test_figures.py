"""Figures fit for print: every curve family named, legends off the data, no text under 8 pt, both
dampings told apart, nothing invisible, no histogram of rounding noise, no raw TeX."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402
from matplotlib.text import Text  # noqa: E402

from impactbar import paper  # noqa: E402


def texts(fig):
    return [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()]


def assert_readable(fig):
    fig.canvas.draw()
    for t in texts(fig):
        assert t.get_fontsize() >= 8, (t.get_text(), t.get_fontsize())
        if "$" not in t.get_text():  # mathtext ($...$, log-axis ticks) renders; bare TeX does not
            assert "_{" not in t.get_text() and "\\" not in t.get_text(), t.get_text()


def assert_legends_off_the_data(fig):
    """No legend box overlaps a plotted point of its own axes."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        leg = ax.get_legend()
        if leg is None:
            continue
        box = leg.get_window_extent(renderer)
        for line in ax.get_lines():
            xy = line.get_xydata()
            xy = xy[np.all(np.isfinite(xy), axis=1)]
            if len(xy) == 0:
                continue
            pix = ax.transData.transform(xy)
            inside = ((pix[:, 0] > box.x0) & (pix[:, 0] < box.x1) & (pix[:, 1] > box.y0)
                      & (pix[:, 1] < box.y1))
            assert not inside.any(), (ax.get_title(), line.get_label())


@pytest.fixture(scope="module")
def rows4():
    return paper.fig4_data(n=10)


@pytest.fixture(scope="module")
def rows7():
    return paper.fig7_data(n=10)


def test_fig4_names_every_R_curve(rows4):
    ax = paper.fig4_plot(rows4)
    fig = ax.figure
    cbar = [a for a in fig.axes if a is not ax]
    assert len(cbar) == 1
    ticks = [t.get_text() for t in cbar[0].get_yticklabels()]
    assert ticks == [f"{r:.1f}" for r in paper.R_CURVES]
    assert "R" in cbar[0].get_ylabel()
    # one colour per R, so each curve family is told apart
    colours = {line.get_color() if isinstance(line.get_color(), str) else tuple(line.get_color())
               for line in ax.get_lines() if line.get_label().startswith("_")}
    assert len(colours) >= len(paper.R_CURVES)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["stable (exact multipliers)", "unstable", "inadmissible"]
    assert_readable(fig)
    assert_legends_off_the_data(fig)


def test_fig7_legend_has_no_stable_entry(rows7):
    assert not any(r["stable"] for r in rows7)
    ax = paper.fig7_plot(rows7)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "stable (exact multipliers)" not in labels and "unstable" in labels
    assert_readable(ax.figure)
    assert_legends_off_the_data(ax.figure)


def test_fig5_dampings_distinguishable_and_sticking_band_visible():
    data = paper.fig5_data(n=8)
    ax, ax_shift, ax_r0 = paper.fig5_plot(data)
    fig = ax.figure
    lines = {line.get_label(): line for line in ax.get_lines()}
    a, b = lines["existence edge (fold), 2πd = 0"], lines["existence edge (fold), 2πd = 0.03"]
    assert to_rgba(a.get_color()) != to_rgba(b.get_color())
    assert a.get_marker() != b.get_marker()
    # the shift panel shows what the main panel cannot: a difference of a few percent
    shift = ax_shift.get_lines()[0].get_ydata()
    assert np.nanmax(np.abs(shift)) > 0.1
    # the R = 0 panel: the sticking part as a bar wide enough to see (> 5 % of the axis)
    bars = [p for p in ax_r0.patches if to_rgba(p.get_facecolor())[:3] == to_rgba("tab:red")[:3]]
    assert len(bars) == 2
    width = ax_r0.get_xlim()[1] - ax_r0.get_xlim()[0]
    for p in bars:
        assert p.get_width() / width > 0.05
    assert data["sticks_from_2pid=0"][0] == pytest.approx(1 / np.sqrt(1 + np.pi**2), abs=1e-6)
    assert_readable(fig)
    assert_legends_off_the_data(fig)


def test_fig8_closed_form_visible_under_the_root_found_line():
    data = paper.fig8_data(n=8)
    ax, _ = paper.fig8_plot(data)
    lines = {line.get_label(): line for line in ax.get_lines()}
    closed = next(v for k, v in lines.items() if k.startswith("closed form"))
    found = lines["root-found edge, 2πd = 0"]
    assert to_rgba(closed.get_color())[:3] != (1.0, 1.0, 1.0)  # not white on white
    assert closed.get_linewidth() >= 3 * found.get_linewidth()
    assert closed.get_zorder() <= found.get_zorder()
    assert_readable(ax.figure)
    assert_legends_off_the_data(ax.figure)


def test_fig6_readable():
    ax = paper.fig6_plot(paper.fig6_data(n=4))
    assert len(ax.get_legend().get_texts()) == 10  # existence + 3 s pi x (paper, exact, wave law)
    assert_readable(ax.figure)
    assert_legends_off_the_data(ax.figure)


def test_reproduce_reports_progress_and_keeps_the_csv_format(tmp_path):
    seen = []
    paper.reproduce(tmp_path, quick=True, progress=seen.append)
    assert seen == ["fig4", "fig5", "fig6", "fig7", "fig8"]
    head = (tmp_path / "fig4.csv").read_text().splitlines()[0]
    assert head == "R,x,branch,phase,stable,schur_stable,admissible,admissibility,max_abs_multiplier"
    head5 = (tmp_path / "fig5.csv").read_text().splitlines()[0]
    assert head5.startswith("R,existence_2pid=0,stability_exact_2pid=0,")
    for i in range(4, 9):
        assert (tmp_path / f"fig{i}.png").stat().st_size > 10_000


class _Result:
    """An ExperimentResult stand-in with given intervals."""

    def __init__(self, intervals):
        self.intervals = np.asarray(intervals)
        self.interval_mean = float(np.mean(intervals))
        self.interval_std = float(np.std(intervals))
        self.impact_pairs = np.column_stack((np.full(4, 2.0), np.full(4, 2.0 + 1e-13)))


def test_interval_plot_does_not_histogram_rounding_noise(rng):
    from impactbar.plotting import plot_impact_map, plot_intervals

    noisy = 1.0 + 1e-12 * rng.standard_normal(500)  # a periodic motion, impact times to rounding
    ax = plot_intervals(_Result(noisy))
    assert len(ax.patches) == 1  # one bar at the period
    assert ax.patches[0].get_height() == 500
    spread = 0.9 + 0.2 * rng.random(500)  # a real spread: a histogram
    ax2 = plot_intervals(_Result(spread))
    assert len(ax2.patches) >= 10
    ax3 = plot_impact_map(_Result(noisy))
    assert_readable(ax3.figure)
    assert "v(i+1)" in ax3.get_ylabel()
    plt.close("all")


@pytest.mark.parametrize("fig", ["fig4", "fig8"])  # (a colorbar; two axes sharing x)
def test_a_png_is_drawn_once_and_is_what_savefig_writes(fig, tmp_path, monkeypatch):
    """The paper's PNG writer makes the constrained layout itself and draws the figure once; its file is
    byte for byte matplotlib's own ``savefig`` of the same figure (which runs the layout in a draw with
    the drawing switched off, then draws again)."""
    from matplotlib.figure import Figure

    from impactbar.plotting.paper import _save

    data = getattr(paper, f"{fig}_data")(10)

    def figure():
        ax = getattr(paper, f"{fig}_plot")(data)
        return (ax[0] if isinstance(ax, tuple) else ax).figure

    figure().savefig(tmp_path / "savefig.png", dpi=130)
    draws, draw = [], Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, renderer: draws.append(1) or draw(self, renderer))
    _save(figure(), tmp_path / "once.png", dpi=130)
    assert len(draws) == 1
    assert (tmp_path / "once.png").read_bytes() == (tmp_path / "savefig.png").read_bytes()
