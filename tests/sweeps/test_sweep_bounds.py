"""A sweep spec whose extra dimension would make huge work chunks is refused when it is parsed,
naming the key and the bound (``max_orbits = 1000000000`` once allocated 7.45 GiB)."""


import pytest

from impactbar.cli import main
from impactbar.sweeps.bar_spec import MAX_CHUNK_VALUES
from impactbar.sweeps.spec import parse_spec


def _doc(task="orbits", chunk_points=None, **opts):
    doc = {
        "task": task,
        "model": {"s": 10.0, "d": 0.01, "R": 0.5, "n_modes": 0},
        "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
        "axes": {"R": {"values": [0.5]}},
        task: opts,
    }
    if chunk_points is not None:
        doc["chunk_points"] = chunk_points
    return doc


def test_huge_max_orbits_refused_before_allocating():
    with pytest.raises(ValueError, match=r"\[orbits\] max_orbits = 1000000000: a work chunk of 1 grid "
                                         r"points would hold 1e\+09 values per variable \(7.45 GiB\); "
                                         r"the limit is 4194304 .*at most 2 one-impact orbits"):
        parse_spec(_doc(max_orbits=1_000_000_000))


def test_an_integer_beyond_the_float_range_is_one_line():  # a fuzz campaign reproducer
    with pytest.raises(ValueError, match=r"max_orbits = 1000.*inf values per variable"):
        parse_spec(_doc(max_orbits=10**400))


def test_the_bound_counts_the_chunk_points():
    doc = _doc(max_orbits=MAX_CHUNK_VALUES // 4, chunk_points=4)
    doc["axes"] = {"R": {"values": [0.1, 0.2, 0.3, 0.4]}}
    assert parse_spec(doc).options["max_orbits"] == MAX_CHUNK_VALUES // 4  # exactly at the bound
    doc["axes"]["R"]["values"].append(0.5)  # chunks stay at 4 points: still fine
    parse_spec(doc)
    doc["bifurcation"] = doc.pop("orbits")
    doc["task"] = "bifurcation"
    doc["bifurcation"] = {"keep": MAX_CHUNK_VALUES // 4 + 1}
    with pytest.raises(ValueError, match=r"\[bifurcation\] keep = 1048577: a work chunk of 4 grid"):
        parse_spec(doc)


def test_cli_sweep_gives_one_line(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text('task = "orbits"\n[model]\ns = 10.0\nd = 0.01\nR = 0.5\nn_modes = 0\n'
                    '[load]\nkind = "cosine"\np0 = 0.5\npk = 1.0\nk = 1\n'
                    '[axes]\nR = { values = [0.5] }\n[orbits]\nmax_orbits = 1000000000\n')
    rc = main(["sweep", str(spec), "--out", str(tmp_path / "out.zarr")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "max_orbits = 1000000000" in err[0], err
