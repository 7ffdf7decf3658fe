"""Sweeps under the rod-rock law: a ``[rock]`` table in the spec, rock and rod axes, the
drilling outputs stored per orbit, the store, the chart and the command line."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import impactbar
from impactbar import BarModel, BilinearRock, CosineLoad, RodRock, RodSegment, periodic_orbits
from impactbar.sweeps import compute_chunk, load_spec, open_sweep, parse_spec, run_sweep

pytest.importorskip("xarray")

SRC = Path(impactbar.__file__).resolve().parents[1]
EXAMPLE = Path(__file__).parents[2] / "examples" / "sweep_rock.toml"


def rock_doc(**axes):
    return {
        "task": "orbits",
        "model": {"s": 10.0, "d": 0.3, "R": 0.0, "n_modes": 0},
        "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
        "rock": {"k": 60.0, "k_u": 600.0, "segments": [{"length": 16.0, "impedance": 1.0}]},
        "axes": axes or {"rock.k": {"values": [30.0, 90.0]}, "segment0.length": {"values": [12.0, 16.0]}},
    }


def test_stored_blows_equal_the_orbits_of_the_law_built_directly():
    """Each point against periodic_orbits of a RodRock built by hand (not through the spec)."""
    spec = parse_spec(rock_doc())
    assert spec.model["impact"] == "rodrock" and spec.chunk_points == 4 and spec.n_chunks == 1
    out = compute_chunk(spec, 0)
    checked = 0
    for i, k in enumerate((30.0, 90.0)):
        for j, length in enumerate((12.0, 16.0)):
            law = RodRock(segments=[RodSegment(length=length, impedance=1.0)],
                          rock=BilinearRock(k=k, k_u=600.0))
            orbits = periodic_orbits(BarModel(10.0, 0.3, 0.0, 0, impact=law), CosineLoad(0.5, 1.0))
            assert out["n_orbits"][i, j] == len(orbits)
            for n, o in enumerate(orbits):
                blow = o.contacts[0]
                assert out["phase"][i, j, n] == pytest.approx(o.phase, abs=1e-12)
                assert out["stable"][i, j, n] == o.stable
                assert out["work_on_rock"][i, j, n] == pytest.approx(blow.work_on_rock, rel=1e-12)
                assert out["penetration"][i, j, n] == pytest.approx(blow.permanent_penetration, rel=1e-12)
                assert out["efficiency"][i, j, n] == pytest.approx(blow.efficiency, rel=1e-12)
                assert 0.0 < out["efficiency"][i, j, n] <= out["efficiency_with_rebound"][i, j, n] <= 1.0
                checked += 1
    assert checked >= 3
    # the rod's advance per period is the permanent penetration, and it is the work over the force
    # scale: a stiffer rock takes more work for less penetration per blow here
    assert out["penetration"][0, 1, 0] > out["penetration"][1, 1, 0]


def test_rock_spec_round_trips_and_keeps_the_law():
    spec = parse_spec(rock_doc())
    again = parse_spec(json.loads(spec.to_json()))
    assert again == spec
    model, load = spec.point((1, 0))
    assert isinstance(model.law, RodRock)
    assert model.law.rock.k == 90.0 and model.law.segments[0].length == 12.0
    assert model.law.rock.k_u == 600.0 and model.law.feed == 0.0


@pytest.mark.parametrize("change, match", [
    (lambda d: d["rock"].pop("k"), r"\[rock\] missing key\(s\) \['k'\]"),
    (lambda d: d["rock"].update(stiffness=1.0), r"\[rock\] unknown key\(s\) \['stiffness'\]"),
    (lambda d: d["rock"].update(k_u=10.0), r"\[rock\] .*k_u"),
    (lambda d: d["rock"].update(segments=[]), r"\[rock\] segments must be a non-empty list"),
    (lambda d: d["rock"].update(segments=[{"length": 1.0}]), r"\[rock\] segments\[0\] needs keys"),
    (lambda d: d["rock"].update(segments=[{"length": -1.0, "impedance": 1.0}]), r"\[rock\] .*length"),
    (lambda d: d["rock"].update(bit_mass=-1.0), r"\[rock\] bit_mass"),
    (lambda d: d["model"].update(impact="wave"), r"\[model\] impact = 'wave' but the spec has a \[rock\]"),
    (lambda d: d.pop("rock") and d["model"].update(impact="rodrock"), r"impact = 'rodrock' needs a \[rock\]"),
    (lambda d: d["axes"].update({"rock.k": {"values": [30.0, 700.0]}}), r"\[axes\] rock.k = 700.0"),
    (lambda d: d["axes"].update({"segment1.length": {"values": [1.0]}}), r"'segment1.length' is not"),
    (lambda d: d.update(rock=[1]), r"\[rock\] must be a table"),
])
def test_bad_rock_spec_is_refused_naming_the_key(change, match):
    doc = rock_doc()
    change(doc)
    with pytest.raises(ValueError, match=match):
        parse_spec(doc)


def test_rock_axes_need_a_rock_table():
    doc = rock_doc()
    del doc["rock"]
    doc["axes"] = {"rock.k": {"values": [1.0, 2.0]}}
    with pytest.raises(ValueError, match=r"'rock.k' is not a field of \[model\] or of this \[load\]"):
        parse_spec(doc)


def test_example_rock_sweep_store_chart_and_cli(tmp_path):
    """The example spec through the command line (its own process): the store holds the drilling
    outputs, the efficiency of the stable blows peaks inside the swept stiffnesses (Lundberg's optimum
    alpha = 1.26, k = 63 here, lies between 45 and 75), and the chart has both panels."""
    spec = load_spec(EXAMPLE)
    assert spec.n_points == 24
    env = dict(os.environ, PYTHONPATH=str(SRC), MPLBACKEND="Agg")
    out = tmp_path / "rock.zarr"
    res = subprocess.run([sys.executable, "-m", "impactbar.cli", "sweep", str(EXAMPLE), "--out", str(out),
                          "--workers", "1"], env=env, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    ds = open_sweep(out)
    eff = np.where(ds["stable"].values, ds["efficiency"].values, np.nan)
    column = np.nanmax(eff[:, 1, :], axis=-1)  # segment length 16: stable everywhere
    assert np.all(np.isfinite(column))
    k = ds["rock.k"].values
    assert 45.0 <= k[int(np.argmax(column))] <= 75.0
    assert np.all((column > 0.0) & (column < 1.0))
    assert "rock loading stiffness" in ds["rock.k"].attrs["long_name"]
    png = tmp_path / "rock.png"
    res = subprocess.run([sys.executable, "-m", "impactbar.cli", "plot", str(out), "--out", str(png)],
                         env=env, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    import matplotlib.image as mpimg

    assert mpimg.imread(png).shape[1] > 1.8 * mpimg.imread(png).shape[0]  # two panels side by side


def test_threads_run_equals_compute_chunk(tmp_path):
    spec = parse_spec(rock_doc())
    run_sweep(spec, tmp_path / "r.zarr", executor="threads", n_workers=1, progress=False)
    ds = open_sweep(tmp_path / "r.zarr")
    direct = compute_chunk(spec, 0)
    for name in ("work_on_rock", "penetration", "efficiency", "efficiency_with_rebound", "phase"):
        np.testing.assert_array_equal(ds[name].values, direct[name], err_msg=name)


def test_efficiency_map_refuses_a_sweep_without_rock(tmp_path):
    from impactbar.plotting import plot_efficiency_map

    spec = parse_spec({"task": "orbits", "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
                       "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
                       "axes": {"R": {"values": [0.2, 0.5]}}})
    run_sweep(spec, tmp_path / "p.zarr", progress=False)
    with pytest.raises(ValueError, match="not run under the rod-rock law"):
        plot_efficiency_map(open_sweep(tmp_path / "p.zarr"), ["R"])


def test_montecarlo_and_bifurcation_under_rock_without_warnings():
    """The other tasks under the rod-rock law: every run settles on one blow per load period
    (``k=1``), as a direct simulation shows; no RuntimeWarning leaks (the bounce test multiplied
    R = 0 by the first impact's infinite previous velocity)."""
    import warnings

    from impactbar import InitialState, simulate
    from impactbar.sweeps import motion_classes

    base = rock_doc(**{"rock.k": {"values": [30.0, 90.0]}})
    for task, opts in (("montecarlo", {"starts": 2, "periods": 20.0}),
                       ("bifurcation", {"periods": 20.0, "keep": 4})):
        doc = dict(base, task=task, **{task: opts})
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            out = compute_chunk(parse_spec(doc), 0)
        assert not out["failed"].any()
        if task == "montecarlo":
            np.testing.assert_array_equal(out["fraction"][:, motion_classes().index("k=1")], 1.0)
        else:
            np.testing.assert_allclose(np.diff(out["impact_phase"], axis=1), 0.0, atol=1e-6)
    model, load = parse_spec(doc).point((0,))
    tr = simulate(model, load, InitialState.rigid(-0.2, 0.0, 0), 40 * 2 * np.pi)
    np.testing.assert_allclose(np.diff(tr.impact_times[-4:]), 2 * np.pi, atol=1e-6)
