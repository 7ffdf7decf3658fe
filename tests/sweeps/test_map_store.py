"""A design map's store never lies and its spec takes what a designer gives: a resume after a
variable's metadata, a coordinate or a flag array was lost recomputes or rewrites it (never reports
it found), integer config keys as axes, a grid too large refused before any work, and a plot's
``--select`` with units and the held axis named."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

pytest.importorskip("zarr")
pytest.importorskip("xarray")
pytest.importorskip("pint")

from impactbar.sweeps import map_edges, open_sweep, parse_spec, run_map  # noqa: E402
from impactbar.sweeps.grid import MAX_CHUNKS, MAX_GRID_POINTS  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")

# the cheapest map: the rigid valve drifter, 2 x 2 points in 2 chunks
AXES = {"valve.supply_pressure": {"values": ["18 MPa", "20 MPa"]},
        "valve.delay": {"values": ["0 ms", "0.1 ms"]}}


def _spec(axes=None):
    return parse_spec({"task": "operating_point", "config": "hydraulic-drifter", "axes": axes or AXES})


def _run(spec, store):
    return run_map(spec, store, executor="threads", n_workers=1, progress=False)


def _arrays(path) -> dict:
    import zarr

    g = zarr.open_group(str(path), mode="r", use_consolidated=False)
    return {name: np.asarray(a[...]) for name, a in g.arrays()}


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    store = tmp_path_factory.mktemp("map") / "whole.zarr"
    res = _run(_spec(), store)
    assert res.complete and res.computed == 2
    return store


def _copy(finished, tmp_path):
    out = tmp_path / "damaged.zarr"
    shutil.copytree(finished, out)
    return out


def _assert_same(finished, store):
    a, b = _arrays(finished), _arrays(store)
    assert a.keys() == b.keys()
    for name in a:
        assert a[name].dtype == b[name].dtype and a[name].tobytes() == b[name].tobytes(), name


@pytest.mark.parametrize("lost", ["blow_frequency/zarr.json", "blow_frequency", "status/zarr.json",
                                  "chunk_done/zarr.json", "chunk_checksum/zarr.json"])
def test_a_resume_recomputes_a_variable_whose_metadata_is_lost(finished, tmp_path, lost):
    """Before: the root's consolidated metadata still listed the variable, the resume read it
    through that copy and counted both chunks found (exit 0), then the edges' step consolidated the
    folder afresh without it: the variable gone, the next rerun a KeyError."""
    store = _copy(finished, tmp_path)
    target = store / lost
    shutil.rmtree(target) if target.is_dir() else target.unlink()
    res = _run(_spec(), store)
    # status is 0 (its fill value) everywhere: its chunks read back right without their files
    assert res.complete and res.computed == (0 if lost.startswith("status") else 2)
    _assert_same(finished, store)
    ds = open_sweep(store)
    name = lost.split("/")[0]
    assert name in ds and ds[name].shape == (2, 2) or name.startswith("chunk_")
    res = _run(_spec(), store)  # and the next rerun finds everything
    assert (res.already_done, res.computed) == (2, 0)
    assert len(map_edges(store)) == len(map_edges(finished))


@pytest.mark.parametrize("damage", ["deleted", "overwritten", "garbage", "metadata"])
def test_a_resume_rewrites_the_axes_from_the_spec(finished, tmp_path, damage):
    """Before: a deleted coordinate chunk resumed to an axis of NaN, one overwritten with 0.5 was
    kept, random bytes raised zstd's RuntimeError."""
    import zarr

    store = _copy(finished, tmp_path)
    axis = store / "valve.delay"
    if damage == "deleted":
        shutil.rmtree(axis / "c")
    elif damage == "overwritten":
        zarr.open_array(store=str(store), path="valve.delay", mode="r+")[...] = 0.5
    elif damage == "garbage":
        (axis / "c" / "0").write_bytes(np.random.default_rng(0).bytes(50))
    else:
        (axis / "zarr.json").write_text("{not json")
    res = _run(_spec(), store)
    assert (res.already_done, res.computed) == (2, 0)  # the data are intact: nothing recomputed
    _assert_same(finished, store)
    assert open_sweep(store)["valve.delay"].values.tolist() == [0.0, 1e-4]


def test_integer_keys_take_integer_axes(tmp_path):
    """Before: n_modes = [0, 2] was refused ("got 0.0 (float)")."""
    spec = _spec({"valve.supply_pressure": {"values": ["20 MPa"]}, "model.n_modes": {"values": [0, 2]}})
    assert spec.axes[1].values == (0, 2) and all(type(v) is int for v in spec.axes[1].values)
    assert parse_spec(json.loads(spec.to_json())) == spec  # the stored spec reads back the same
    assert _spec({"model.n_modes": {"start": 0, "stop": 4, "num": 3}}).axes[0].values == (0, 2, 4)
    for table in ({"values": [0, 2.5]}, {"start": 0, "stop": 4, "num": 4}):
        with pytest.raises(ValueError, match=r"^\[axes\] model.n_modes takes integers .*got (2.5|1.33)"):
            _spec({"model.n_modes": table})
    res = _run(spec, tmp_path / "modes.zarr")
    assert res.complete
    ds = open_sweep(tmp_path / "modes.zarr")
    assert ds["model.n_modes"].dtype.kind == "i" and ds["model.n_modes"].values.tolist() == [0, 2]
    assert np.all(ds["status"].values == 0)
    # the rigid piston (0 modes) is the preset's worked example: 47.19 Hz at 20 MPa
    assert float(ds["blow_frequency"][0, 0]) == pytest.approx(47.19, abs=0.01)


def test_an_integer_rock_key_is_an_axis():
    spec = parse_spec({"task": "operating_point", "config": "examples/circuit_drifter_rock.toml",
                       "axes": {"rock.cells_per_piston": {"values": [8, 12]}}})
    assert spec.axes[0].values == (8, 12)


def test_a_dimensionless_grid_too_large_builds_no_point(monkeypatch):
    """The point count is asked before each axis value is checked by building its point: a mistyped
    size of 19,303 values along one of three axes took 10 s of CPU (21,008 points built), hours
    at worse sizes, before its refusal."""
    from impactbar.sweeps import bar_spec

    def built(*args, **kwargs):
        raise AssertionError("a point was built for an axis value of a grid refused for its size")

    monkeypatch.setattr(bar_spec, "_build", built)
    with pytest.raises(ValueError, match=r"^\[axes\] R \(1696\) x s \(9\) x d \(19303\) make 294640992 grid "
                                         rf"points; the limit is {MAX_GRID_POINTS}"):
        parse_spec({"task": "orbits", "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
                    "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
                    "axes": {"R": {"start": 0.0, "stop": 0.9, "num": 1696},
                             "s": {"start": 1.0, "stop": 100.0, "num": 9},
                             "d": {"start": 0.0, "stop": 0.1, "num": 19303}}})


def test_a_grid_too_large_is_refused_before_any_work(tmp_path):
    """Before: three axes of 10,000 values passed, created the store and died of a MemoryError."""
    axes = {"valve.supply_pressure": {"start": "18 MPa", "stop": "20 MPa", "num": 10_000},
            "valve.delay": {"start": "0 ms", "stop": "0.1 ms", "num": 10_000},
            "stop.restitution": {"start": 0.1, "stop": 0.3, "num": 10_000}}
    with pytest.raises(ValueError, match=r"^\[axes\] valve.supply_pressure \(10000\) x valve.delay "
                                         r"\(10000\) x stop.restitution \(10000\) make 1000000000000 "
                                         rf"grid points; the limit is {MAX_GRID_POINTS}"):
        _spec(axes)
    assert not list(tmp_path.iterdir())
    # the dimensionless sweeps too, and the number of work chunks
    load = {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1}
    model = {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0}
    with pytest.raises(ValueError, match=r"R \(20000\) x s \(10000\) make 200000000 grid points"):
        parse_spec({"task": "orbits", "load": load, "model": model,
                    "axes": {"R": {"start": 0, "stop": 0.9, "num": 20_000},
                             "s": {"start": 1, "stop": 100, "num": 10_000}}})
    with pytest.raises(ValueError, match=rf"^chunk_points = 1: .* make 2000000 work chunks; the limit is "
                                         rf"{MAX_CHUNKS}: raise chunk_points"):
        parse_spec({"task": "orbits", "load": load, "model": model, "chunk_points": 1,
                    "axes": {"R": {"start": 0, "stop": 0.9, "num": 2000},
                             "s": {"start": 1, "stop": 100, "num": 1000}}})


def test_select_takes_a_quantity_and_the_plot_names_the_held_axis(finished, tmp_path, monkeypatch):
    """Before: only the SI number was taken (``"20 MPa"`` refused), and the line did not say where
    the other axis was held."""
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt

    from impactbar.sweeps import plot_sweep
    from impactbar.sweeps.plot import reduce_axes

    ds = open_sweep(finished)
    for value in ("19.5 MPa", 2e7, "0.02 GPa"):
        red, dims = reduce_axes(ds, {"valve.supply_pressure": value}, 1)
        assert dims == ("valve.delay",) and float(red["valve.supply_pressure"]) == 2e7
    with pytest.raises(ValueError, match=r"^--select valve.delay must be in s as the axis"):
        reduce_axes(ds, {"valve.delay": "3 MPa"}, 1)
    titles = []
    close = plt.close

    def keep(fig):
        titles.extend(ax.get_title() for ax in fig.axes)
        close(fig)

    monkeypatch.setattr(plt, "close", keep)
    plot_sweep(finished, tmp_path / "line.png", select={"valve.delay": "0.1 ms"})
    assert any(t.endswith("held at valve.delay = 0.1 ms") for t in titles), titles


def test_the_held_axis_is_in_the_unit_the_config_wrote(finished, tmp_path, monkeypatch):
    """The 1-D plot's title named the held axis in SI ("held at valve.delay = 0.0001 s",
    "valve.supply_pressure = 2e+07 Pa"), where the config writes ms and MPa and the map's edge lines
    print those; a dimensionless sweep keeps its bare number."""
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt

    from impactbar import CosineLoad
    from impactbar.sweeps import plot_sweep, run_sweep

    titles = []
    close = plt.close

    def keep(fig):
        titles.append([ax.get_title() for ax in fig.axes])
        close(fig)

    monkeypatch.setattr(plt, "close", keep)
    plot_sweep(finished, tmp_path / "a.png", select={"valve.delay": 1e-4})
    plot_sweep(finished, tmp_path / "b.png", select={"valve.supply_pressure": "20 MPa"})
    spec = parse_spec({"task": "orbits", "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
                       "load": CosineLoad(0.5, 1.0).params.record(),
                       "axes": {"R": {"values": [0.2, 0.9]}, "s": {"values": [50.0, 100.0]}}})
    run_sweep(spec, tmp_path / "r.zarr", progress=False)
    plot_sweep(tmp_path / "r.zarr", tmp_path / "c.png", select={"s": 100.0})
    assert "held at valve.delay = 0.1 ms" in titles[0][0], titles
    assert "held at valve.supply_pressure = 20 MPa" in titles[1][0], titles
    assert "held at s = 100" in titles[2][0], titles


def test_the_cli_select_takes_a_quantity(finished, tmp_path):
    pytest.importorskip("matplotlib")
    from impactbar.cli.plot import _selection

    assert _selection(["valve.delay = 0.1 ms", "valve.supply_pressure=2e7"]) == {
        "valve.delay": "0.1 ms", "valve.supply_pressure": 2e7}
