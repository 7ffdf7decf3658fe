"""Plots that show the answer: a branch's default ordinate separates the two
sides of a fold; the wave-law force plot has no offset axis and one legend entry per distinct wave."""

import dataclasses

import matplotlib
import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, continue_orbit, periodic_orbits
from impactbar import physical as ph
from impactbar.plotting.physical import plot_force_waves

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


@pytest.fixture(scope="module")
def folded_branch():
    # the rigid bar's one-impact branch folds at p0 = (1 + R)/(pi (1 - R)) = 0.955 (R = 0.5)
    model = BarModel(s=10.0, d=0.05, R=0.5, n_modes=0)
    start = next(o for o in periodic_orbits(model, CosineLoad(0.5, 1.0)) if np.cos(o.phase) < 0)
    return continue_orbit(start, "p0", to=1.2)  # turns at the fold, stops back below 0.5


def test_branch_plot_default_separates_the_fold(folded_branch):
    b = folded_branch
    assert any(e.kind == "fold" for e in b.events)
    k = int(np.argmax(b.values))  # the fold
    assert 0 < k < len(b) - 1
    # a parameter value met on both sides of the fold
    p = 0.5 * (b.values[k] + max(b.values[0], b.values[-1]))
    before = np.interp(p, b.values[:k + 1], np.unwrap(b.phases, axis=0)[:k + 1, 0])
    after = np.interp(p, b.values[k:][::-1], np.unwrap(b.phases, axis=0)[k:, 0][::-1])
    v1 = np.interp(p, b.values[:k + 1], b.impact_velocities[:k + 1, 0])
    v2 = np.interp(p, b.values[k:][::-1], b.impact_velocities[k:, 0][::-1])
    assert v1 == pytest.approx(v2, rel=1e-6)  # impact velocity: both sides on one line
    assert abs(before - after) > 0.1  # the phase keeps them apart
    ax = b.plot()
    assert ax.get_ylabel() == "phase (rad)"
    ys = np.concatenate([ln.get_ydata() for ln in ax.get_lines() if len(ln.get_xdata()) > 1])
    np.testing.assert_allclose(np.sort(ys), np.sort(np.concatenate([
        ln.get_ydata() for ln in b.plot(y="phase").get_lines() if len(ln.get_xdata()) > 1])))
    assert np.min(np.abs(ys - before)) < 0.05 and np.min(np.abs(ys - after)) < 0.05
    plt.close("all")


def test_force_plot_no_offset_and_one_entry_for_identical_waves():
    """The pneumatic drill under the wave law settles into identical blows, their waves a plateau
    of ~259 kN with a ripple of tens of newtons: one legend entry, plain tick labels."""
    h = dataclasses.replace(ph.preset("pneumatic-drill"), impact="wave")
    res = ph.simulate(h, periods=40)
    assert res.blow_statistics().settled
    fig, ax = plt.subplots()
    plot_force_waves(res, ax)
    fig.canvas.draw()
    assert ax.yaxis.get_major_formatter().get_offset() == ""
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert len(ax.get_lines()) == len(labels)
    blows = np.flatnonzero(res.is_blow())[-8:]
    assert labels == ["blows " + ", ".join(map(str, blows))]
    y = ax.get_lines()[0].get_ydata()
    assert 200 < np.min(y) and np.ptp(y) < 0.1  # kN: a ripple of < 100 N on the plateau
    # without the offset switched off, matplotlib would put this curve on an offset axis
    fig2, ax2 = plt.subplots()
    ax2.plot(ax.get_lines()[0].get_xdata(), y)
    fig2.canvas.draw()
    assert ax2.yaxis.get_major_formatter().get_offset() != ""
    plt.close(fig)
