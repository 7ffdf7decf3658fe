"""Contour labels a reader can tell apart: distinct, upright and inside the axes."""

import numpy as np
import pytest


def test_contour_labels_are_distinct_upright_and_inside():
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt

    from impactbar.plotting import label_contours

    # levels 45.6, 45.9, 46.2, ...: "%.0f" reads two of them as "46"
    x, y = np.linspace(60.0, 80.0, 5), np.linspace(6.0, 14.0, 5)
    X, Y = np.meshgrid(x, y)
    f = 45.0 + 0.1 * (X - 60.0) + 0.1 * np.sin(Y)
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    lines = ax.contour(x, y, f, levels=np.arange(45.3, 47.2, 0.3))
    texts = label_contours(ax, lines, "Hz")
    labels = [t.get_text() for t in texts]
    assert labels and len(set(labels)) == len(labels) and all(s.endswith(" Hz") for s in labels)
    assert all(-90.0 <= ((t.get_rotation() + 180.0) % 360.0) - 180.0 <= 90.0 for t in texts)
    fig.canvas.draw()
    frame = ax.get_window_extent()
    for t in texts:
        box = t.get_window_extent()
        assert frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1
    plt.close(fig)


def test_circuit_branch_diagram_marks_the_branch_points():
    pytest.importorskip("matplotlib")
    from types import SimpleNamespace

    import matplotlib.pyplot as plt

    from impactbar.plotting import plot_circuit_branch

    branch = SimpleNamespace(values=np.array([1e-3, 1.1e-3, 1.2e-3]), unit="m**3/s",
                             parameter="supply.pump_flow", stable=np.array([True, True, False]),
                             blow_frequency_Hz=np.array([40.0, 42.0, 44.0]),
                             impact_energy_J=np.array([100.0, 110.0, 120.0]), events=[])
    axes = plot_circuit_branch(branch)
    for ax in axes:
        data = [ln for ln in ax.get_lines() if ln.get_label() in ("stable", "unstable")]
        assert data and all(ln.get_marker() not in ("None", "", None) for ln in data)
    plt.close(axes[0].figure)


def test_circuit_run_valve_as_a_band_and_its_legend_outside_the_data():
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    from impactbar.plotting import plot_circuit_run

    t = np.linspace(0.0, 2.0, 20001)  # 100 periods of 20 ms
    run = {"histories": {"t_s": t, "p_f_Pa": 1e7 + 0 * t, "p_r_Pa": 8e6 + 0 * t, "p_s_Pa": 1.2e7 + 0 * t,
                         "gap_m": 0.01 * np.abs(np.sin(np.pi * 50 * t)),
                         "x_v": ((t * 50) % 1 > 0.5).astype(float)},
           "impact_times_s": np.arange(0.0, 2.0, 0.02), "impact_velocities_m_s": np.full(100, 10.0)}
    axes = plot_circuit_run(run)
    fig = axes[0].figure
    twin = [a for a in fig.axes if a not in list(axes)]
    assert twin and any(isinstance(c, PolyCollection) for c in twin[0].collections)
    assert not [ln for ln in twin[0].get_lines()]  # no valve line over the panel
    fig.canvas.draw()
    legend = axes[1].get_legend()
    assert legend.get_window_extent().y0 >= axes[1].get_window_extent().y1 - 1.0
    assert "valve opening" in [t.get_text() for t in legend.get_texts()]
    plt.close(fig)
