"""A cluster's workers pointed at one shared numba cache folder (filled once) instead of each
compiling: the plugin, the sweep's option, and their refusals."""

import logging
import os

import pytest

from impactbar.cli import main
from impactbar.sweeps import numba_cache_plugin, parse_spec, run_sweep, use_numba_cache
from impactbar.sweeps.run import _connect

pytest.importorskip("distributed")

RIGID = {"task": "orbits", "model": {"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
         "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1}, "axes": {"R": {"values": [0.2, 0.5]}}}


def _folders(client) -> set:
    """Each worker's ``NUMBA_CACHE_DIR`` and the cache folder its numba reads."""

    def seen():
        from numba.core import config

        return os.environ.get("NUMBA_CACHE_DIR"), config.CACHE_DIR

    return set(client.run(seen).values())


def test_the_plugin_sets_the_workers_cache_folder(tmp_path):
    from distributed import Client, LocalCluster

    folder = tmp_path / "shared numba"
    with (LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                       dashboard_address=None, silence_logs=logging.ERROR) as cluster,
          Client(cluster) as cl):
        assert (str(folder), str(folder)) not in _folders(cl)
        use_numba_cache(cl, folder)
        assert _folders(cl) == {(str(folder), str(folder))}  # both workers, in numba's own config
        # a sweep on a running scheduler does the same (registering again replaces the plugin)
        other = tmp_path / "other"
        with _connect(cluster.scheduler_address, None, other) as remote:
            assert _folders(remote) == {(str(other), str(other))}


def test_a_local_cluster_starts_its_workers_with_the_cache_folder(tmp_path):
    with _connect(None, 1, str(tmp_path)) as cl:
        assert _folders(cl) == {(str(tmp_path), str(tmp_path))}


def test_the_plugin_takes_an_absolute_folder():
    assert numba_cache_plugin("relative").folder == os.path.abspath("relative")


def test_bad_cache_folders_are_refused_before_any_work(tmp_path):
    spec = parse_spec(RIGID)
    a_file = tmp_path / "f"
    a_file.write_text("")
    with pytest.raises(ValueError, match="numba_cache .* is a file, not a folder"):
        run_sweep(spec, tmp_path / "a.zarr", numba_cache=a_file, executor="dask")
    with pytest.raises(ValueError, match="numba_cache must be a folder path"):
        run_sweep(spec, tmp_path / "a.zarr", numba_cache=3, executor="dask")
    with pytest.raises(ValueError, match="computed in threads of this process"):
        run_sweep(spec, tmp_path / "a.zarr", numba_cache=tmp_path)  # the rigid closed forms: threads
    assert not (tmp_path / "a.zarr").exists()


def test_the_command_line_refuses_a_file_as_the_cache(tmp_path, capsys):
    spec = tmp_path / "s.toml"
    spec.write_text('task = "orbits"\n[model]\ns = 100.0\nd = 0.0\nR = 0.5\nn_modes = 2\n'
                    '[load]\nkind = "cosine"\np0 = 0.5\npk = 1.0\nk = 1\n[axes.R]\nvalues = [0.2, 0.5]\n')
    a_file = tmp_path / "f"
    a_file.write_text("")
    assert main(["sweep", str(spec), "--out", str(tmp_path / "o.zarr"), "--numba-cache", str(a_file)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("impactbar sweep: error:") and "is a file, not a folder" in err[-1]
