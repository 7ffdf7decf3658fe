"""Sweeps on dask.distributed into zarr: spec validation, chunking, seeds, the store,
resumption after SIGKILL, the CLI and the plots.

The cluster tests share one real ``LocalCluster`` of 2 worker processes on loopback.
"""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import impactbar
from impactbar import BarModel, CosineLoad, periodic_orbits
from impactbar.sweeps import (
    SweepSpec,
    chunk_slices,
    compute_chunk,
    load_spec,
    motion_classes,
    open_sweep,
    parse_spec,
    point_done,
    run_sweep,
    sweep_progress,
)

xr = pytest.importorskip("xarray")
distributed = pytest.importorskip("distributed")

SRC = Path(impactbar.__file__).resolve().parents[1]
EXAMPLES = sorted((Path(__file__).parents[2] / "examples").glob("sweep_*.toml"))


def base_doc(task="orbits", **top):
    doc = {
        "task": task,
        "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
        "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
        "axes": {"R": {"start": 0.0, "stop": 0.9, "num": 10}, "p0": {"values": [0.2, 0.3, 0.4]}},
    }
    doc.update(top)
    return doc


def mc_doc(task="montecarlo", **opts):
    doc = base_doc(task, chunk_points=2)
    doc["model"] = {"s": 10.0, "d": 0.005, "R": 0.8, "n_modes": 0}
    doc["axes"] = {"p0": {"values": [0.6, 1.2, 1.5]}, "R": {"values": [0.5, 0.8]}}
    doc[task] = opts
    return doc


def toml_text(doc) -> str:
    """A tiny TOML writer for the specs of these tests (tables of scalars and inline tables)."""
    def val(v):
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {val(x)}" for k, x in v.items()) + " }"
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return repr(v)

    lines = [f"{k} = {val(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    for k, v in doc.items():
        if isinstance(v, dict):
            lines.append(f"[{k}]")
            lines += [f"{kk} = {val(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def cli(*args, **kw):
    env = dict(os.environ, PYTHONPATH=str(SRC), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "impactbar.cli", *map(str, args)], env=env,
                          capture_output=True, text=True, **kw)


@pytest.fixture(scope="module")
def client():
    import logging

    from distributed import Client, LocalCluster

    with (LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                       dashboard_address=None, silence_logs=logging.ERROR) as cluster,
          Client(cluster) as cl):
        yield cl


# -- the spec ------------------------------------------------------------------------------------
@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_specs_are_valid(path):
    spec = load_spec(path)
    assert spec.n_points > 1
    assert parse_spec(spec.to_dict()) == spec


def test_spec_normalises_and_round_trips():
    spec = parse_spec(base_doc())
    assert spec.shape == (10, 3)
    assert [a.name for a in spec.axes] == ["R", "p0"]
    assert spec.axes[0].values == tuple(np.linspace(0.0, 0.9, 10))
    assert spec.options == {"max_orbits": 2}
    assert spec.chunk_points == 32768  # every point in the rigid closed forms (closed_form_task)
    assert parse_spec(_with(base_doc(), ("model", "n_modes"), 2)).chunk_points == 400
    again = parse_spec(json.loads(spec.to_json()))
    assert again == spec and again.to_json() == spec.to_json()
    model, load = spec.point((3, 1))
    assert model == BarModel(100.0, 0.0, spec.axes[0].values[3], 0)
    assert (load.p0, load.pk, load.k) == (0.3, 1.0, 1)
    assert parse_spec(mc_doc()).options == {"starts": 100, "periods": 200.0, "seed": 0, "window": 0.25}
    k_axis = base_doc(axes={"k": {"values": [1, 3]}})
    assert parse_spec(k_axis).options["max_orbits"] == 6


def _with(doc, path, value):
    *head, last = path
    d = doc
    for k in head:
        d = d[k]
    if value is _DELETE:
        del d[last]
    else:
        d[last] = value
    return doc


_DELETE = object()


@pytest.mark.parametrize(
    "path, value, match",
    [
        (("colour",), "red", r"unknown top-level key.*colour"),
        (("task",), "chaos", r"task must be one of"),
        (("task",), _DELETE, r"missing top-level key 'task'"),
        (("model", "mass"), 1.0, r"\[model\] unknown key.*mass"),
        (("model", "R"), _DELETE, r"\[model\] missing key.*R"),
        (("model", "R"), 1.5, r"\[model\] R must be in \[0, 1\]"),
        (("model", "n_modes"), 1.5, r"\[model\] n_modes must be an integer"),
        (("load", "q"), 1.0, r"\[load\] unknown key.*'q'.*cosine"),
        (("load", "kind"), "sine", r"\[load\] kind must be one of"),
        (("load", "kind"), ["cosine"], r"\[load\] kind must be one of"),  # unhashable: not a TypeError
        (("load", "kind"), {"a": 1}, r"\[load\] kind must be one of"),
        (("load", "pk"), _DELETE, r"\[load\] missing key.*pk"),
        (("load", "k"), 0, r"\[load\] k must be an integer in \[1"),
        (("axes", "kappa"), {"values": [1.2]}, r"\[axes\] 'kappa' is not a field"),
        (("axes", "R"), {"start": 0.0, "stop": 1.2, "num": 5}, r"\[axes\] R = 1.2: R must be in"),
        (("axes", "R"), {"start": 0.0, "num": 5}, r"\[axes\] R must have keys"),
        (("axes", "R"), {"values": []}, r"\[axes\] R.values must be a non-empty list"),
        (("axes", "R"), {"values": [0.1, 0.1]}, r"\[axes\] R: values must be distinct"),
        (("axes", "n_modes"), {"start": 0, "stop": 3, "num": 3}, r"\[axes\] n_modes: .*integers"),
        (("axes",), {}, r"\[axes\] must name at least one field"),
        (("montecarlo",), {"starts": 10}, r"\[montecarlo\] is given but task = 'orbits'"),
        (("orbits",), {"max_orbit": 3}, r"\[orbits\] unknown key.*max_orbit"),
        (("orbits",), {"max_orbits": 0}, r"\[orbits\] max_orbits must be an integer in \[1"),
        (("chunk_points",), 0, r"chunk_points must be an integer in \[1"),
    ],
)
def test_bad_spec_is_refused_naming_the_key(path, value, match):
    with pytest.raises(ValueError, match=match):
        parse_spec(_with(base_doc(), path, value))


@pytest.mark.parametrize(
    "task, opts, match",
    [
        ("montecarlo", {"starts": 0}, r"\[montecarlo\] starts must be an integer in \[1"),
        ("montecarlo", {"periods": -1.0}, r"\[montecarlo\] periods must be in \(0"),
        ("montecarlo", {"window": 1.5}, r"\[montecarlo\] window must be in \(0, 1\]"),
        ("montecarlo", {"keep": 3}, r"\[montecarlo\] unknown key.*keep"),
        ("bifurcation", {"keep": 0}, r"\[bifurcation\] keep must be an integer in \[1"),
        ("bifurcation", {"seed": -1}, r"\[bifurcation\] seed must be an integer in \[0"),
    ],
)
def test_bad_task_options_are_refused(task, opts, match):
    with pytest.raises(ValueError, match=match):
        parse_spec(mc_doc(task, **opts))


def test_square_and_fourier_loads():
    doc = base_doc(load={"kind": "square", "q": 1.0, "kappa": 1.2},
                   axes={"kappa": {"values": [1.1, 1.5]}, "R": {"values": [0.0, 0.5]}})
    spec = parse_spec(doc)
    assert spec.options["max_orbits"] == 2
    assert spec.point((1, 0))[1].kappa == 1.5
    with pytest.raises(ValueError, match=r"\[axes\] kappa = 2.5: kappa must be in \[1, 2\]"):
        parse_spec(_with(doc, ("axes", "kappa"), {"values": [2.5]}))
    doc = base_doc(load={"kind": "fourier", "p0": 0.3, "coefficients": [[1.0, 0.0], 0.0, [0.0, 0.2]]},
                   axes={"p0": {"values": [0.3, 0.4]}})
    spec = parse_spec(doc)
    assert spec.options["max_orbits"] == 6
    assert np.allclose(spec.point((1,))[1].harmonics(3), [1.0, 0.0, 0.2j])
    assert parse_spec(json.loads(spec.to_json())) == spec
    with pytest.raises(ValueError, match=r"\[axes\] 'coefficients' is not a field"):
        parse_spec(_with(doc, ("axes", "coefficients"), {"values": [1.0]}))


def test_load_spec_reports_toml_errors(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("task = orbits\n")
    with pytest.raises(ValueError, match="not valid TOML"):
        load_spec(bad)
    with pytest.raises(ValueError, match="cannot read spec"):
        load_spec(tmp_path / "missing.toml")


# -- chunks and the per-chunk computation ----------------------------------------------------------
@pytest.mark.parametrize("shape, points", [((10, 3), 20), ((7,), 3), ((5, 4, 3), 7), ((4, 4), 400),
                                           ((3, 5), 1)])
def test_chunks_tile_the_grid(shape, points):
    axes = {name: {"values": [0.1 + 0.1 * i for i in range(n)]}
            for name, n in zip(("R", "p0", "pk"), shape, strict=False)}
    spec = parse_spec(base_doc(axes=axes, chunk_points=points))
    assert np.prod(spec.chunk_shape) <= max(points, 1) or spec.chunk_shape == (1,) * len(shape)
    count = np.zeros(shape, dtype=int)
    for c in range(spec.n_chunks):
        sl = chunk_slices(spec, c)
        assert all(s.stop - s.start <= cs for s, cs in zip(sl, spec.chunk_shape, strict=True))
        count[sl] += 1
    assert np.all(count == 1)
    with pytest.raises(ValueError, match="chunk must be"):
        chunk_slices(spec, spec.n_chunks)


def test_orbits_chunk_equals_periodic_orbits():
    spec = parse_spec(base_doc(chunk_points=9))
    c = 1
    out = compute_chunk(spec, c)
    sl = chunk_slices(spec, c)
    assert out["phase"].shape == (sl[0].stop - sl[0].start, 3, 2)
    for i in range(sl[0].start, sl[0].stop):
        for j in range(3):
            local = (i - sl[0].start, j)
            orbits = periodic_orbits(BarModel(100.0, 0.0, spec.axes[0].values[i], 0),
                                     CosineLoad(spec.axes[1].values[j], 1.0, 1))
            assert out["n_orbits"][local] == len(orbits)
            assert not out["failed"][local]
            for k in range(2):
                if k < len(orbits):
                    o = orbits[k]
                    # the chunk's vectorised closed form and the single call's scalar one agree to
                    # rounding (numpy's and libm's elementary functions may differ in the last bit)
                    for name in ("phase", "impact_velocity", "max_abs_multiplier"):
                        assert out[name][(*local, k)] == pytest.approx(getattr(o, name), rel=1e-12, abs=1e-14)
                    assert out["stable"][(*local, k)] == o.stable
                    assert out["schur_stable"][(*local, k)] == o.schur_stable
                    assert out["admissible"][(*local, k)] == o.admissible
                else:
                    assert np.isnan(out["phase"][(*local, k)]) and not out["stable"][(*local, k)]


def test_a_resonant_point_is_marked_failed_not_fatal():
    doc = base_doc(model={"s": 1.0, "d": 0.0, "R": 0.5, "n_modes": 2},
                   axes={"s": {"values": [1.0 / np.pi, 2.0]}})
    out = compute_chunk(parse_spec(doc), 0)
    assert out["failed"].tolist() == [True, False]
    assert out["n_orbits"][0] == 0 and np.all(np.isnan(out["phase"][0]))
    assert out["n_orbits"][1] > 0


@pytest.mark.parametrize("task, opts", [("montecarlo", {"starts": 3, "periods": 40.0, "seed": 5}),
                                        ("bifurcation", {"periods": 40.0, "keep": 5, "seed": 5})])
def test_results_do_not_depend_on_chunking(task, opts):
    """Each point is seeded from (seed, flat index): chunks of 1 and of 6 points agree exactly."""
    whole = compute_chunk(parse_spec(_with(mc_doc(task, **opts), ("chunk_points",), 6)), 0)
    spec1 = parse_spec(_with(mc_doc(task, **opts), ("chunk_points",), 1))
    assert spec1.n_chunks == 6
    for c in range(6):
        part = compute_chunk(spec1, c)
        sl = chunk_slices(spec1, c)
        for name, arr in part.items():
            np.testing.assert_array_equal(arr, whole[name][sl], err_msg=name)
    other = compute_chunk(parse_spec(mc_doc(task, **{**opts, "seed": 6})), 0)
    key = "fraction" if task == "montecarlo" else "impact_velocity"
    assert not np.array_equal(np.nan_to_num(other[key]), np.nan_to_num(whole[key][chunk_slices(spec1, 0)]))
    if task == "montecarlo":
        assert whole["fraction"].shape == (3, 2, len(motion_classes()))
        np.testing.assert_allclose(whole["fraction"].sum(axis=-1), 1.0)
    else:
        assert whole["impact_velocity"].shape == (3, 2, 5)
        assert np.all(whole["n_impacts"] >= np.sum(np.isfinite(whole["impact_velocity"]), axis=-1))


# -- the store, on a real cluster ------------------------------------------------------------------
def test_orbits_store_layout_and_resume(client, tmp_path):
    spec = parse_spec(base_doc(chunk_points=9))
    out = tmp_path / "o.zarr"
    run = run_sweep(spec, out, client=client, progress=False)
    assert run.complete and run.computed == spec.n_chunks == 4 and run.already_done == 0
    ds = xr.open_zarr(out)
    assert dict(ds.sizes) == {"R": 10, "p0": 3, "orbit": 2, "chunk": 4}
    for name in ("phase", "admissible", "stable", "schur_stable", "max_abs_multiplier", "impact_velocity"):
        assert ds[name].dims == ("R", "p0", "orbit")
    assert ds["n_orbits"].dims == ("R", "p0")
    assert ds["phase"].encoding["chunks"] == (3, 3, 2)
    np.testing.assert_array_equal(ds["R"].values, spec.axes[0].values)
    assert json.loads(ds.attrs["impactbar_sweep_spec"]) == spec.to_dict()
    assert ds.attrs["impactbar_version"] == impactbar.__version__
    assert ds["chunk_done"].values.tolist() == [1, 1, 1, 1]
    assert point_done(ds).values.all()
    for c in range(spec.n_chunks):
        want = compute_chunk(spec, c)
        for name, arr in want.items():
            np.testing.assert_array_equal(ds[name].values[chunk_slices(spec, c)], arr, err_msg=name)
    assert sweep_progress(out) == (4, 4)
    # rerun: nothing left to do
    again = run_sweep(spec, out, client=client, progress=False)
    assert (again.already_done, again.computed) == (4, 0)
    # another sweep into the same store is refused unless overwritten
    other = parse_spec(_with(base_doc(chunk_points=9), ("model", "s"), 50.0))
    with pytest.raises(ValueError, match=r"holds a different sweep \(differs in \['model'\]\).*--overwrite"):
        run_sweep(other, out, client=client, progress=False)
    run = run_sweep(other, out, client=client, progress=False, overwrite=True)
    assert run.computed == 4
    assert json.loads(open_sweep(out).attrs["impactbar_sweep_spec"])["model"]["s"] == 50.0
    # a folder that is not a sweep store is never touched
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "keep.txt").write_text("x")
    with pytest.raises(ValueError, match="not an impactbar sweep store"):
        run_sweep(spec, tmp_path / "data", client=client, progress=False, overwrite=True)
    assert (tmp_path / "data" / "keep.txt").exists()


@pytest.mark.parametrize("task, opts", [("montecarlo", {"starts": 4, "periods": 40.0, "seed": 2}),
                                        ("bifurcation", {"periods": 40.0, "keep": 8, "seed": 2})])
def test_montecarlo_and_bifurcation_stores(client, tmp_path, task, opts):
    spec = parse_spec(mc_doc(task, **opts))
    out = tmp_path / f"{task}.zarr"
    run_sweep(spec, out, client=client, progress=False)
    ds = xr.open_zarr(out)
    if task == "montecarlo":
        assert ds["fraction"].dims == ("p0", "R", "motion")
        assert list(ds["motion"].values) == list(motion_classes())
        np.testing.assert_allclose(ds["fraction"].sum("motion").values, 1.0)
        for name in ("interval_mean", "interval_std", "run_spread"):
            assert ds[name].dims == ("p0", "R")
    else:
        assert ds["impact_velocity"].dims == ("p0", "R", "impact") and ds.sizes["impact"] == 8
        ph = ds["impact_phase"].values
        assert np.all((ph[np.isfinite(ph)] >= 0) & (ph[np.isfinite(ph)] < 1))
    for c in range(spec.n_chunks):
        for name, arr in compute_chunk(spec, c).items():
            np.testing.assert_array_equal(ds[name].values[chunk_slices(spec, c)], arr, err_msg=name)
    png = tmp_path / f"{task}.png"
    assert impactbar.plot_sweep(out, png) == png and png.stat().st_size > 1000
    impactbar.plot_sweep(out, tmp_path / "one.png", select={"R": 0.8})


def _done_count(path: Path) -> int:
    try:
        return sweep_progress(path)[0]
    except (ValueError, OSError, KeyError):
        return 0


def _sigkill_after(n_done: int, out: Path, spec_file: Path, *options) -> int:
    """Run ``impactbar sweep`` in a new session, SIGKILL it and everything it started once
    ``n_done`` chunks are stored; return the chunks stored then."""
    env = dict(os.environ, PYTHONPATH=str(SRC))
    proc = subprocess.Popen([sys.executable, "-m", "impactbar.cli", "sweep", str(spec_file), "--out",
                             str(out), *options, "--no-progress"], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while _done_count(out) < n_done:
            assert proc.poll() is None, proc.stderr.read().decode()
            assert time.monotonic() < deadline, "the sweep made no progress"
            time.sleep(0.01)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    return _done_count(out)


def _slow_doc():
    """A 3,200-point rigid orbits sweep in 160 chunks whose every point has p0 = 0 (the end arrives
    at rest): the closed form leaves those to the general path (about 0.5 ms a point), so that a
    run lasts long enough to be killed midway (800 points in 40 chunks were all stored before the
    driver could be killed on a quiet machine)."""
    doc = base_doc(chunk_points=20, axes={"R": {"start": 0.05, "stop": 0.95, "num": 40},
                                          "d": {"start": 0.0, "stop": 0.2, "num": 80}})
    doc["load"]["p0"] = 0.0
    return doc


def test_sigkill_midway_then_resume_equals_uninterrupted(client, tmp_path):
    """A sweep killed with SIGKILL (the driver and anything it started) keeps its finished chunks;
    rerunning the same command completes it, identical to an uninterrupted run."""
    doc = _slow_doc()
    spec_file = tmp_path / "spec.toml"
    spec_file.write_text(toml_text(doc))
    spec = load_spec(spec_file)
    assert spec.n_chunks == 160
    addr = client.scheduler.address
    out = tmp_path / "killed.zarr"
    killed_at = _sigkill_after(5, out, spec_file, "--scheduler", addr)
    assert 5 <= killed_at < spec.n_chunks, "killed too late to test resumption; enlarge the grid"
    # the partial store opens and plots (chunks not done are blank)
    part = xr.open_zarr(out)
    assert int(point_done(part).sum()) < spec.n_points
    impactbar.plot_sweep(out, tmp_path / "partial.png")
    # resume with the same command
    res = cli("sweep", spec_file, "--out", out, "--scheduler", addr, "--no-progress", timeout=300)
    assert res.returncode == 0, res.stderr
    found = int(res.stdout.split("(")[1].split(" found")[0])
    assert found >= killed_at
    assert sweep_progress(out) == (spec.n_chunks, spec.n_chunks)
    # an uninterrupted run of the same spec
    ref = tmp_path / "ref.zarr"
    run_sweep(spec, ref, client=client, progress=False)
    a, b = xr.open_zarr(out).load(), xr.open_zarr(ref).load()
    xr.testing.assert_identical(a, b)
    for name in a.data_vars:
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


# -- cheap closed-form sweeps in threads of the driver ---------------------------------------------
def test_closed_form_task_picks_the_threads_executor():
    """Only sweeps whose every point takes the rigid closed forms run in threads by default."""
    from impactbar.sweeps.spec import closed_form_task

    assert closed_form_task(parse_spec(base_doc()))
    square = base_doc()
    square["load"] = {"kind": "square", "q": 1.0, "kappa": 1.2}
    square["axes"] = {"kappa": {"values": [1.0, 1.5]}}
    assert closed_form_task(parse_spec(square))
    assert closed_form_task(parse_spec(_with(base_doc(), ("axes", "n_modes"), {"values": [0]})))
    assert not closed_form_task(parse_spec(_with(base_doc(), ("axes", "n_modes"), {"values": [0, 2]})))
    assert not closed_form_task(parse_spec(_with(base_doc(), ("model", "n_modes"), 2)))
    assert not closed_form_task(parse_spec(_with(base_doc(), ("model", "impact"), "wave")))
    assert not closed_form_task(parse_spec(mc_doc(starts=2, periods=10.0)))
    fourier = base_doc()
    fourier["load"] = {"kind": "fourier", "p0": 0.3, "coefficients": [1.0, 0.2]}
    fourier["axes"] = {"R": {"values": [0.0, 0.5]}}
    assert not closed_form_task(parse_spec(fourier))


@pytest.mark.parametrize("load", [{"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 2},
                                  {"kind": "square", "q": 1.0, "kappa": 1.3}])
def test_threads_executor_store_equals_cluster_store(client, tmp_path, monkeypatch, load):
    """The same store, byte for byte in its data and checksums, from threads of the driver (the
    default for a closed-form sweep: no cluster is started) and from the dask cluster."""
    from impactbar.sweeps import run as run_module

    doc = base_doc(chunk_points=7)
    doc["load"] = load
    if load["kind"] == "square":
        doc["axes"] = {"R": {"start": 0.0, "stop": 0.9, "num": 10}, "kappa": {"values": [1.0, 1.5, 1.9]}}
    spec = parse_spec(doc)

    def no_cluster(*a):
        raise AssertionError("a closed-form sweep started a cluster")

    monkeypatch.setattr(run_module, "_connect", no_cluster)
    a = run_sweep(spec, tmp_path / "threads.zarr", n_workers=2, progress=False)
    assert a.complete and a.computed == spec.n_chunks
    b = run_sweep(spec, tmp_path / "dask.zarr", client=client, progress=False)
    assert b.complete
    ta, tb = xr.open_zarr(tmp_path / "threads.zarr").load(), xr.open_zarr(tmp_path / "dask.zarr").load()
    xr.testing.assert_identical(ta, tb)
    for name in ta.data_vars:
        np.testing.assert_array_equal(ta[name].values, tb[name].values, err_msg=name)
    assert (ta["chunk_checksum"].values >= 0).all()
    with pytest.raises(ValueError, match="executor must be one of"):
        run_sweep(spec, tmp_path / "x.zarr", executor="processes", progress=False)
    with pytest.raises(ValueError, match="no client or scheduler"):
        run_sweep(spec, tmp_path / "x.zarr", client=client, executor="threads", progress=False)
    assert not (tmp_path / "x.zarr").exists()


def test_plain_zarr_writes_equal_the_batched_ones(tmp_path, monkeypatch):
    """Where zarr has no internal event-loop runner (``zarr.core.sync``), the chunks, checksums and
    flags go one write at a time through zarr's public API: the same store."""
    from impactbar.sweeps import store as store_module

    spec = parse_spec(base_doc(chunk_points=7))
    a = run_sweep(spec, tmp_path / "batched.zarr", n_workers=2, progress=False)
    monkeypatch.setattr(store_module, "_zarr_sync", lambda: None)
    b = run_sweep(spec, tmp_path / "plain.zarr", n_workers=2, progress=False)
    assert a.complete and b.complete
    ta, tb = xr.open_zarr(tmp_path / "batched.zarr").load(), xr.open_zarr(tmp_path / "plain.zarr").load()
    xr.testing.assert_identical(ta, tb)
    assert (tb["chunk_done"].values == 1).all() and (tb["chunk_checksum"].values >= 0).all()


@pytest.mark.parametrize("doc", [
    mc_doc(starts=2, periods=10.0),
    _with(_with(base_doc(chunk_points=3), ("axes", "n_modes"), {"values": [0, 1]}), ("axes", "k"),
          {"values": [1, 3]}),
    {"task": "bifurcation", "model": {"s": 10.0, "d": 0.005, "R": 0.8, "n_modes": 0},
     "load": {"kind": "square", "q": 0.5, "kappa": 1.2},
     "axes": {"kappa": {"start": 1.0, "stop": 1.5, "num": 7}}},
], ids=["montecarlo", "orbits", "bifurcation"])
def test_store_created_with_zarr_alone_equals_xarrays(tmp_path, monkeypatch, doc):
    """The store written with zarr alone (the default: xarray and dask.array are not imported)
    equals, file for file and byte for byte, the one xarray's to_zarr writes from the template."""
    from impactbar.dynamics.implementations import implementation
    from impactbar.sweeps import store

    spec = parse_spec(doc)
    files = {}
    for via in (True, False):
        path = tmp_path / f"{via}.zarr"
        with implementation("sweeps.create_store", "reference" if via else "fast"):
            store._create_store(spec, path)
        files[via] = {f.relative_to(path): f.read_bytes() for f in sorted(path.rglob("*")) if f.is_file()}
    # the same layout with any supported xarray: variables, dimensions, dtypes and coordinates
    ta, tb = xr.open_zarr(tmp_path / "True.zarr"), xr.open_zarr(tmp_path / "False.zarr")
    assert set(files[True]) == set(files[False])
    assert dict(ta.sizes) == dict(tb.sizes) and set(ta.data_vars) == set(tb.data_vars)
    layout = [{n: (t[n].dims, t[n].dtype) for n in t.data_vars} for t in (ta, tb)]
    assert layout[0] == layout[1]
    xr.testing.assert_identical(ta.coords.to_dataset().load(), tb.coords.to_dataset().load())
    if tuple(int(x) for x in xr.__version__.split(".")[:2]) >= (2026, 9):
        # byte for byte with the xarray the format was matched against (older releases encode
        # booleans as int8 and give every array a 0.0 fill value: unwritten chunks read as 0, not NaN)
        assert files[True] == files[False]
    # the root, every variable, the flags and checksums, the axes (and montecarlo's motion classes)
    n_json = 1 + len(spec.variables()) + 2 + len(spec.axes) + (spec.task == "montecarlo")
    assert sum(p.name == "zarr.json" for p in files[False]) == n_json


def test_closed_form_sweep_imports_neither_dask_nor_xarray(tmp_path):
    """A closed-form sweep in a fresh process: no cluster, and neither distributed, dask nor
    xarray is imported (their start-up is most of a short sweep's time)."""
    code = ("import sys\nfrom impactbar.sweeps import parse_spec, run_sweep\n"
            f"spec = parse_spec({base_doc()!r})\n"
            f"run = run_sweep(spec, {str(tmp_path / 's.zarr')!r}, n_workers=2, progress=False)\n"
            "assert run.complete\n"
            "print(sorted(m for m in ('distributed', 'dask', 'xarray') if m in sys.modules))\n")
    env = dict(os.environ, PYTHONPATH=str(SRC))
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "[]"
    assert bool(open_sweep(tmp_path / "s.zarr")["chunk_done"].all())


def test_threads_executor_interrupted_keeps_finished_chunks_and_resumes(tmp_path, monkeypatch):
    """Ctrl-C in the middle of a sweep run in threads: the chunks stored before it are kept
    (flagged, checksummed), the lock is released, and rerunning completes the store, identical
    to an uninterrupted run."""
    from impactbar.sweeps import run as run_module

    spec = parse_spec(base_doc(chunk_points=3))  # 10 chunks
    ref = tmp_path / "ref.zarr"
    run_sweep(spec, ref, executor="threads", n_workers=1, progress=False)
    real = run_module.compute_chunk

    def interrupted(spec, chunk):
        if chunk == 6:
            raise KeyboardInterrupt
        return real(spec, chunk)

    monkeypatch.setattr(run_module, "compute_chunk", interrupted)
    out = tmp_path / "out.zarr"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, out, n_workers=1, progress=False)
    stored, total = sweep_progress(out)
    # one thread computes in order: chunks 0-5 finished first, chunk 6 failed; chunk 7 (queued
    # behind it) may have finished in the same batch, and is then stored too
    done = xr.open_zarr(out)["chunk_done"].values
    assert total == 10 and stored in (6, 7) and stored == int(done.sum())
    assert done[:6].all() and not done[6] and not done[8:].any()
    assert not (tmp_path / ".out.zarr.lock").exists()
    monkeypatch.setattr(run_module, "compute_chunk", real)
    res = run_sweep(spec, out, n_workers=2, progress=False)
    assert res.already_done == stored and res.computed == 10 - stored
    a, b = xr.open_zarr(out).load(), xr.open_zarr(ref).load()
    xr.testing.assert_identical(a, b)
    for name in a.data_vars:
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


def test_threads_executor_sigkill_midway_then_resume_equals_uninterrupted(tmp_path):
    """A closed-form sweep (threads of the driver) killed with SIGKILL keeps its finished chunks;
    rerunning the same command completes it, identical to an uninterrupted run."""
    doc = _slow_doc()
    spec_file = tmp_path / "spec.toml"
    spec_file.write_text(toml_text(doc))
    spec = load_spec(spec_file)
    assert spec.n_chunks == 160
    out = tmp_path / "killed.zarr"
    killed_at = _sigkill_after(3, out, spec_file, "--workers", "1")
    assert 3 <= killed_at < spec.n_chunks, "killed too late to test resumption; enlarge the grid"
    res = cli("sweep", spec_file, "--out", out, "--workers", "2", "--no-progress", timeout=300)
    assert res.returncode == 0, res.stderr
    assert int(res.stdout.split("(")[1].split(" found")[0]) >= killed_at
    ref = tmp_path / "ref.zarr"
    run_sweep(spec, ref, n_workers=2, progress=False)
    a, b = xr.open_zarr(out).load(), xr.open_zarr(ref).load()
    xr.testing.assert_identical(a, b)
    for name in a.data_vars:
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)
    assert int(a["n_orbits"].sum()) > 0


# -- the command line ----------------------------------------------------------------------------
def test_cli_refuses_a_bad_spec_before_any_work(tmp_path):
    doc = base_doc()
    doc["model"]["R"] = 1.5
    spec_file = tmp_path / "bad.toml"
    spec_file.write_text(toml_text(doc))
    res = cli("sweep", spec_file, "--out", tmp_path / "r.zarr", timeout=60)
    assert res.returncode == 2
    assert "[model] R must be in [0, 1]; got 1.5" in res.stderr
    assert not (tmp_path / "r.zarr").exists()
    res = cli("sweep", spec_file, "--out", tmp_path / "r.zarr", "--workers", "2", "--scheduler",
              "tcp://127.0.0.1:1", timeout=60)
    assert res.returncode == 2 and "not allowed with argument" in res.stderr


def test_cli_own_local_cluster_then_plot(tmp_path):
    doc = base_doc(chunk_points=10)
    spec_file = tmp_path / "s.toml"
    spec_file.write_text(toml_text(doc))
    out = tmp_path / "r.zarr"
    res = cli("sweep", spec_file, "--out", out, "--workers", "2", timeout=300)
    assert res.returncode == 0, res.stderr
    assert "4/4 chunks stored (0 found, 4 computed" in res.stdout
    assert "chunk" in res.stderr  # the progress bar
    ds = xr.open_zarr(out)
    assert int(ds["n_orbits"].sum()) > 0
    png = tmp_path / "chart.png"
    res = cli("plot", out, "--out", png, timeout=120)
    assert res.returncode == 0, res.stderr
    assert png.stat().st_size > 1000
    res = cli("plot", out, "--out", png, "--select", "p0=0.3", timeout=120)
    assert res.returncode == 0, res.stderr
    res = cli("plot", out, "--out", png, "--select", "q=1", timeout=120)
    assert res.returncode == 2 and "--select q: not an axis" in res.stderr


def test_plot_needs_a_selection_beyond_two_axes(client, tmp_path):
    doc = base_doc(axes={"R": {"values": [0.0, 0.5]}, "p0": {"values": [0.3, 0.4]},
                         "pk": {"values": [1.0, 1.1]}})
    out = tmp_path / "three.zarr"
    run_sweep(parse_spec(doc), out, client=client, progress=False)
    with pytest.raises(ValueError, match=r"at most 2 axes.*--select"):
        impactbar.plot_sweep(out, tmp_path / "x.png")
    impactbar.plot_sweep(out, tmp_path / "x.png", select={"pk": 1.0})
    with pytest.raises(ValueError, match="not an impactbar sweep store"):
        impactbar.plot_sweep(tmp_path, tmp_path / "y.png")


def test_spec_dataclass_is_frozen_and_validates():
    spec = parse_spec(base_doc())
    with pytest.raises(AttributeError):
        spec.task = "montecarlo"
    with pytest.raises(ValueError, match="task must be one of"):
        SweepSpec(task="x", model=spec.model, load=spec.load, axes=spec.axes)


def test_every_load_of_the_table_sweeps():
    """The spec takes every kind of the table of loads (``load.params.record()``): a piecewise-constant
    load's arrays too, its orbits those of periodic_orbits."""
    from impactbar import PiecewiseConstantLoad

    load = PiecewiseConstantLoad([0.0, 2.0], [1.0, -0.5])
    doc = base_doc(model={"s": 10.0, "d": 0.05, "R": 0.5, "n_modes": 1}, load=load.params.record(),
                   axes={"R": {"values": [0.3, 0.5]}})
    spec = parse_spec(doc)
    assert json.loads(spec.to_json())["load"] == load.params.record()
    assert spec.point((1,))[1] == load
    out = compute_chunk(spec, 0)
    for i, R in enumerate((0.3, 0.5)):
        orbits = periodic_orbits(BarModel(10.0, 0.05, R, 1), load)
        assert out["n_orbits"][i] == len(orbits) > 0
        np.testing.assert_array_equal(out["phase"][i, :len(orbits)], [o.phase for o in orbits])
    with pytest.raises(ValueError, match=r"\[axes\] 'levels' is not a field"):
        parse_spec({**doc, "axes": {"levels": {"values": [1.0]}}})
