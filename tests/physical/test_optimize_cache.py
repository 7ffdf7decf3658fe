"""The optimiser's cache file (:class:`~impactbar.physical.optimize_cache.DesignCache`): a log of one
JSON line a design or gradient, read back to the bit; a stop at any byte of a write loses no design
written before it, and the file takes the next line cleanly; a file of the format before the log
(one JSON document) is read and written once as a log; another problem's is not read, and replaced."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from impactbar.physical.optimize_cache import DesignCache, read_cache, read_gradients


def _record(i: int) -> dict:
    """A design's record with floats that only their repr gives back exactly, nested figures and a
    non-finite one (stored as null)."""
    return {"id": json.dumps([repr(0.1 * i + 1e-17 * i)]), "ok": i % 3 != 0, "seconds": 1 / 3 + i,
            "objectives": {"impact_power_kW": math.pi * i, "tiny": 5e-324 * i},
            "constraints": {"max_multiplier": {"value": 0.9 + i / 7, "scaled": -(1 / 7) ** i}},
            "guess": None if i == 0 else json.dumps([repr(0.1 * (i - 1))]), "u": [i / 11, 1 - i / 13],
            "missing": math.nan}


def _gradient(i: int) -> dict:
    return {"objective": np.array([i / 3, -i / 7]), "constraints": np.array([[1 / 9, i / 11]])}


def _plain(record: dict) -> dict:
    """The record as read back: non-finite numbers null."""
    return json.loads(json.dumps(record).replace("NaN", "null"))


def _written(path, n: int, tag: str = "p") -> DesignCache:
    cache = DesignCache(path, tag)
    for i in range(n):
        cache.add(_record(i))
        cache.add_gradient(_record(i)["id"], "default", _gradient(i))
    cache.close()
    return cache


def test_a_log_reads_back_its_designs_and_gradients_to_the_bit(tmp_path):
    path = tmp_path / "cache.json"
    _written(path, 6)
    again = DesignCache(path, "p")
    assert list(again.designs.values()) == [_plain(_record(i)) for i in range(6)]
    g = again.gradients[(_record(4)["id"], "default")]
    np.testing.assert_array_equal(np.asarray(g["objective"]), _gradient(4)["objective"])
    np.testing.assert_array_equal(np.asarray(g["constraints"]), _gradient(4)["constraints"])
    assert read_cache(path, "p") == again.designs and read_gradients(path, "p") == again.gradients
    # each design one line appended: the file before it is kept byte for byte
    before = path.read_bytes()
    cache = DesignCache(path, "p")
    cache.add(_record(6))
    cache.close()
    after = path.read_bytes()
    assert after.startswith(before) and after[len(before):].count(b"\n") == 1
    assert len(path.read_text().splitlines()) == 1 + 2 * 6 + 1  # (the problem's line first)


def test_a_stop_at_any_byte_of_a_write_loses_no_design_written_before_it(tmp_path):
    """The file cut at each byte of its last line (a process killed in the middle of writing it):
    the designs before are read back, the cut line not; the next design written after it reads back
    too, and the line cut short is gone."""
    path = tmp_path / "cache.json"
    _written(path, 3)
    whole = path.read_bytes()
    start = whole.rstrip(b"\n").rfind(b"\n") + 1  # the last line's first byte: the third gradient's
    kept = DesignCache(path, "p")
    for cut in range(start, len(whole)):
        path.write_bytes(whole[:cut])
        cache = DesignCache(path, "p")
        assert cache.designs == kept.designs and len(cache.gradients) == 2
        cache.add(_record(7))
        cache.close()
        again = DesignCache(path, "p")
        assert list(again.designs) == [*kept.designs, _record(7)["id"]] and len(again.gradients) == 2
        assert path.read_bytes().startswith(whole[:start])  # (the lines before kept as they were)
    # a line cut before the last (the third design's, line 6): the file is damaged, said in one line
    # naming it and what to do
    path.write_bytes(whole[:start - 5] + b"\n" + whole[start:])
    with pytest.raises(ValueError, match=r"cache\.json' line 6 is not readable JSON.*delete the file"):
        DesignCache(path, "p")


def test_a_record_changed_is_written_again_with_the_next_line_and_read_as_changed(tmp_path):
    path = tmp_path / "cache.json"
    cache = DesignCache(path, "p")
    first, second = _record(1), _record(2)
    cache.add(first)
    first["border"] = {"nearest": "x", "objective": 2.5}
    cache.changed(first)
    assert "border" not in DesignCache(path, "p").designs[first["id"]]  # (not before the next line)
    cache.add(second)
    cache.close()
    again = DesignCache(path, "p")
    assert list(again.designs) == [first["id"], second["id"]]  # (the order first written)
    assert again.designs[first["id"]]["border"] == {"nearest": "x", "objective": 2.5}
    # written anew: each design once
    again.rewrite()
    assert len(path.read_text().splitlines()) == 3 and DesignCache(path, "p").designs == again.designs


def test_a_file_of_the_format_before_is_read_and_written_as_a_log(tmp_path):
    path = tmp_path / "cache.json"
    records = [_plain(_record(i)) for i in range(3)]
    grads = [dict(json.loads(json.dumps({k: v.tolist() for k, v in _gradient(1).items()})),
                  id=records[1]["id"], kind="refined")]
    path.write_text(json.dumps({"problem": "p", "evaluations": records, "gradients": grads}, indent=1))
    cache = DesignCache(path, "p")
    assert list(cache.designs.values()) == records
    assert cache.gradients == {(records[1]["id"], "refined"): grads[0]}
    assert DesignCache(path, "q").designs == {}  # (another problem's)
    cache.add(_record(5))
    cache.close()
    again = DesignCache(path, "p")
    assert list(again.designs.values()) == [*records, _plain(_record(5))]
    assert again.gradients == cache.gradients
    assert json.loads(path.read_text().splitlines()[0]) == {"impactbar_optimize_cache": 2, "problem": "p"}
    path.write_text("{not json")
    with pytest.raises(ValueError, match=r"cache\.json' is neither a cache log nor a readable JSON file"):
        DesignCache(path, "p")


def test_another_problems_log_is_not_read_and_is_replaced_on_the_first_write(tmp_path):
    path = tmp_path / "cache.json"
    _written(path, 2, tag="p")
    other = DesignCache(path, "q")
    assert other.designs == {} and other.gradients == {}
    assert len(DesignCache(path, "p").designs) == 2  # (nothing written yet: kept)
    other.add(_record(3))
    other.close()
    assert DesignCache(path, "p").designs == {} and list(DesignCache(path, "q").designs) == [_record(3)["id"]]
    # no file, an empty file, no path: nothing read; no path: nothing written
    assert DesignCache(tmp_path / "none.json", "p").designs == {}
    (tmp_path / "empty.json").write_text("")
    assert DesignCache(tmp_path / "empty.json", "p").designs == {}
    DesignCache(None, "p").add(_record(1))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache.json", "empty.json"]
