"""The design map's figure: what a reader sees of its refined edges."""

import numpy as np
import pytest


def test_edge_diamonds_on_the_border_are_not_clipped():
    xr = pytest.importorskip("xarray")
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt

    from impactbar.plotting.maps import plot_operating_map

    x, y = np.array([1.0, 2.0, 3.0]), np.array([10.0, 20.0])
    z = np.arange(6.0).reshape(2, 3)
    ds = xr.Dataset(
        {"status": (("b", "a"), np.zeros((2, 3), dtype=int)), "impact_energy": (("b", "a"), z),
         "edge_value": ("edge", [1.5]), "edge_axis": ("edge", [1]),
         "edge_index": (("edge", "k"), [[0, 0]])},
        coords={"a": x, "b": y}, attrs={"axes": ["b", "a"]})
    ax = plot_operating_map(ds, ("b", "a"), variable="impact_energy")
    diamonds = [ln for ln in ax.get_lines() if ln.get_marker() == "D"]
    assert len(diamonds) == 1
    assert list(diamonds[0].get_xydata()[0]) == [1.5, 10.0]  # on the lower border
    assert diamonds[0].get_clip_on() is False
    plt.close(ax.figure)
