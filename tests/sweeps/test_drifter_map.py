"""Design maps of a drifter (impactbar.sweeps.map_spec, map_task, maps): each point against a fresh
``orbit()`` at its values, the spec's refusals, a resumed store bitwise equal to an uninterrupted one,
and an edge found between grid points and refined against the continuation's border-collision event."""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

pytest.importorskip("zarr")
pytest.importorskip("xarray")
pytest.importorskip("pint")

from impactbar.physical.config import config_kind  # noqa: E402
from impactbar.physical.loader import build, read_config, with_values  # noqa: E402
from impactbar.sweeps import SweepSpec, load_spec, map_edges, open_sweep, parse_spec, run_map  # noqa: E402
from impactbar.sweeps.map_task import compute_map_chunk, point_values  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")

FLOWS = ["60 L/min", "75 L/min", "90 L/min"]
PRECHARGES = ["6 MPa", "12 MPa"]


def _spec(chain="continue", **more):
    return parse_spec({"task": "operating_point", "config": "circuit-drifter", "chain": chain,
                       "axes": {"supply.pump_flow": {"values": FLOWS},
                                "accumulator.precharge": {"values": PRECHARGES}}, **more})


def _fresh(flow, precharge):
    """The operating point at the values by a fresh orbit() of the config, as a user writes it."""
    cfg = with_values(read_config("circuit-drifter")[0], {"supply.pump_flow": flow,
                                                          "accumulator.precharge": precharge})
    return point_values(build(cfg).orbit(), "circuit", False)


@pytest.fixture(scope="module")
def fresh():
    return {(i, j): _fresh(q, p) for i, q in enumerate(FLOWS) for j, p in enumerate(PRECHARGES)}


def _chunks(spec):
    out = {f.name: np.full(spec.shape, f.fill, dtype=f.dtype) for f in spec.variables()}
    for c in range(spec.n_chunks):
        block = spec.block(c)
        for name, values in compute_map_chunk(spec, c).items():
            out[name][block] = values
    return out


def test_the_spec_reads_si_values_and_dispatches_on_config():
    spec = _spec()
    assert isinstance(spec, SweepSpec)
    assert spec.shape == (3, 2) and spec.chunk_shape == (1, 2)
    assert spec.axes[0].unit == "m**3/s" and spec.axes[1].unit == "Pa"
    assert spec.axes[0].values == pytest.approx([1e-3, 1.25e-3, 1.5e-3], rel=1e-15)
    assert spec.axes[1].values == (6e6, 12e6)
    # the stored spec (SI values with their unit) reads back to the same spec
    import json

    assert parse_spec(json.loads(spec.to_json())) == spec


def test_each_point_equals_a_fresh_orbit(fresh):
    """The default chain at every point: each point is the fresh orbit() at its values (to 1e-9
    relative; the same computation); continued from its neighbour: the same orbit to the
    integrator's accuracy (Newton from another start lands within the flights' rtol, 1e-10, times
    the orbit's conditioning: some 1e-9 on this drifter, 1e-8 allowed)."""
    for chain, rtol in (("default", 1e-9), ("continue", 1e-8)):
        got = _chunks(_spec(chain))
        assert np.all(got["status"] == 0), got["failure"]
        for (i, j), want in fresh.items():
            for name, w in want.items():
                g = got[name][i, j]
                if isinstance(w, bool):
                    assert bool(g) == w, (chain, name, i, j)
                elif name.endswith("_margin"):  # a difference of two pressures: absolute, in Pa
                    assert abs(g - w) <= rtol * 3e7, (chain, name, i, j, g, w)
                else:
                    assert g == pytest.approx(w, rel=rtol, abs=1e-300), (chain, name, i, j)
        if chain == "default":
            assert np.all(got["origin"] == 0)
        else:  # a line of two points per chunk: the first by the default chain, the second continued
            assert np.all(got["origin"][:, 0] == 0) and np.all(got["origin"][:, 1] == 2)


@pytest.mark.parametrize("axes, key", [
    ({"supply.pump_flo": {"values": ["60 L/min"]}}, "supply.pump_flo"),
    ({"supply.pump_flow": {"values": ["6 MPa"]}}, "supply.pump_flow"),
    ({"supply.pump_flow": {"values": [60]}}, "supply.pump_flow"),
    ({"accumulator.precharge": {"start": "6 MPa", "stop": "-1 MPa", "num": 3}}, "accumulator.precharge"),
    ({"valve.switch_in": {"values": ["10 mm"]}}, "valve.switch_in"),
    ({"nosuch.key": {"values": [1.0]}}, "nosuch.key"),
    ({"supply.pump_flow": {"values": ["60 L/min", "60 L/min"]}}, "supply.pump_flow"),
])
def test_bad_axes_are_refused_naming_the_key(axes, key):
    with pytest.raises(ValueError) as err:
        parse_spec({"task": "operating_point", "config": "circuit-drifter", "axes": axes})
    msg = str(err.value)
    assert key in msg and "\n" not in msg


@pytest.mark.parametrize("doc, key", [
    ({"axes": {}}, "[axes]"),
    ({"axes": {k: {"values": [v]} for k, v in (("supply.pump_flow", "60 L/min"),
                                                ("accumulator.precharge", "6 MPa"),
                                                ("accumulator.volume", "0.5 L"),
                                                ("supply.hose_volume", "0.25 L"))}}, "[axes]"),
    ({"task": "orbits"}, "task"),
    ({"config": "no-such-preset"}, "config"),
    ({"extra": 1}, "extra"),
    ({"chain": "sideways"}, "chain"),
])
def test_bad_specs_are_refused_naming_the_key(doc, key):
    base = {"task": "operating_point", "config": "circuit-drifter",
            "axes": {"supply.pump_flow": {"values": ["60 L/min"]}}}
    with pytest.raises(ValueError) as err:
        parse_spec({**base, **doc})
    assert key in str(err.value)


def _store_arrays(path):
    import zarr

    g = zarr.open_group(str(path), mode="r")
    return {name: np.asarray(a[...]) for name, a in g.arrays()}


def test_a_resumed_map_is_bitwise_the_uninterrupted_one(tmp_path):
    import zarr

    spec = _spec()
    whole, part = tmp_path / "whole.zarr", tmp_path / "part.zarr"
    run_map(spec, whole, executor="threads", n_workers=1, progress=False)
    shutil.copytree(whole, part)
    # a driver killed after its first chunk: the others' flags unset, one chunk's data gone
    g = zarr.open_group(str(part), mode="r+")
    done = np.asarray(g["chunk_done"][...])
    done[1:] = 0
    g["chunk_done"][...] = done
    for f in (part / "blow_frequency" / "c").rglob("*"):
        if f.is_file() and f.parts[-2:] == ("2", "0"):
            f.unlink()
    with pytest.raises(ValueError, match="not stored yet"):
        map_edges(part)
    res = run_map(spec, part, executor="threads", n_workers=1, progress=False)
    assert (res.already_done, res.computed) == (1, 2)
    a, b = _store_arrays(whole), _store_arrays(part)
    assert a.keys() == b.keys()
    for name in a:
        assert a[name].dtype == b[name].dtype and a[name].tobytes() == b[name].tobytes(), name
    ds = open_sweep(part)
    assert ds["impact_energy"].attrs["units"] == "J" and ds["supply.pump_flow"].attrs["units"] == "m3/s"
    # drawn: two axes as filled contours, one (the other fixed) as a line; an unknown variable refused
    pytest.importorskip("matplotlib")
    from impactbar.sweeps import plot_sweep

    assert plot_sweep(part, tmp_path / "map.png", variable="hydraulic_efficiency").stat().st_size > 0
    assert plot_sweep(part, tmp_path / "line.png", select={"accumulator.precharge": 6e6}).stat().st_size > 0
    with pytest.raises(ValueError, match="no_such"):
        plot_sweep(part, tmp_path / "x.png", variable="no_such")
    # the axes in a designer's units, the store's SI values scaled on the ticks
    import matplotlib.pyplot as plt

    from impactbar.plotting.maps import plot_operating_map

    y_dim, x_dim = ds["status"].dims
    ax = plot_operating_map(ds.load(), (y_dim, x_dim), variable="mean_supply_pressure")
    shown = {"supply.pump_flow": ("L/min", 6e4), "accumulator.precharge": ("MPa", 1e-6)}
    assert ax.get_xlabel() == f"{x_dim} [{shown[x_dim][0]}]"
    assert ax.get_ylabel() == f"{y_dim} [{shown[y_dim][0]}]"
    value = float(ds[x_dim][0])
    assert ax.xaxis.get_major_formatter()(value, 0) == f"{value * shown[x_dim][1]:.6g}"
    plt.close(ax.figure)


def test_an_edge_that_is_not_there_is_refused_in_the_unit_the_config_wrote():
    """Bisection asked for an edge its two ends do not straddle said "between 0.001 and
    0.00108333": SI where the config and the axis wrote L/min."""
    from impactbar.sweeps.map_task import refine_edge

    spec = parse_spec({"task": "operating_point", "config": "circuit-drifter",
                       "axes": {"supply.pump_flow": {"values": ["60 L/min", "65 L/min"]}}})
    with pytest.raises(ValueError, match=r"^relief_opens does not change between 60 L/min and 65 L/min along "
                                         r"supply.pump_flow$"):
        refine_edge(spec, 0, (0,), "relief_opens")


@pytest.mark.slow
def test_the_relief_edge_refined_agrees_with_the_continuation(tmp_path):
    """Between 70 and 80 L/min the supply's peak reaches the relief's 25 MPa: the map records the
    edge between its two grid points, bisection puts it within 1e-6 relative, and the continuation's
    border-collision event (physical.continue_circuit, located independently on the branch) agrees."""
    from impactbar.physical import continue_circuit

    spec = parse_spec({"task": "operating_point", "config": "circuit-drifter",
                       "axes": {"supply.pump_flow": {"values": ["70 L/min", "80 L/min"]}}})
    run_map(spec, tmp_path / "m.zarr", executor="threads", n_workers=1, progress=False)
    edges = map_edges(tmp_path / "m.zarr", refine=True)
    relief = [e for e in edges if e["flag"] == "relief_opens"]
    assert len(relief) == 1 and relief[0]["index"] == (0,)
    q = relief[0]["value"]
    assert 70 / 6e4 < q < 80 / 6e4
    ds = open_sweep(tmp_path / "m.zarr")
    assert list(ds["edge_flag"].values).count("relief_opens") == 1
    assert ds["edge_value"].values[list(ds["edge_flag"].values).index("relief_opens")] == q
    # the flag on either side of the refined value, each by a fresh orbit
    for factor, opens in ((1 - 1e-5, False), (1 + 1e-5, True)):
        cfg = with_values(read_config("circuit-drifter")[0], {"supply.pump_flow": f"{q * factor!r} m^3/s"})
        assert point_values(build(cfg).orbit(), "circuit", False)["relief_opens"] is opens
    branch = continue_circuit(build(read_config("circuit-drifter")[0]), "supply.pump_flow", "80 L/min")
    events = [e["value"] for e in branch.events if "relief" in e["kind"]]
    assert len(events) == 1
    assert math.isclose(events[0], q, rel_tol=1e-5)


def test_a_map_of_the_valve_drifter_equals_its_fresh_orbits():
    """The valve drifter (no oil circuit: no pressures stored) over its supply pressure and switch."""
    spec = parse_spec({"task": "operating_point", "config": "hydraulic-drifter",
                       "axes": {"valve.supply_pressure": {"values": ["15 MPa", "20 MPa"]},
                                "valve.switch_out": {"start": "15 mm", "stop": "25 mm", "num": 3}}})
    assert config_kind(spec.config) == "drifter" and "mean_supply_pressure" not in spec.variables().names
    got = _chunks(spec)
    assert np.all(got["status"] == 0)
    config = read_config("hydraulic-drifter")[0]
    for i, p in enumerate(("15 MPa", "20 MPa")):
        for j, x in enumerate(("15 mm", "20 mm", "25 mm")):
            want = point_values(build(with_values(config, {"valve.supply_pressure": p,
                                                           "valve.switch_out": x})).orbit(), "drifter", False)
            for name, w in want.items():
                assert got[name][i, j] == pytest.approx(w, rel=1e-9), (name, i, j)


def test_the_cavitation_edge_refined_is_the_root_of_the_least_front_pressure(tmp_path):
    """A front opening 30 times narrower than the preset's starves the front chamber: at 2e-7
    m^3/s/Pa^0.5 its least absolute pressure is below 0 (the orbit kept, ``cavitates`` set), at
    3e-7 above. The bisected edge is where that pressure, a smooth function of the coefficient, is 0:
    Brent's method on it (fresh orbits, no bisection) finds the same coefficient."""
    from scipy.optimize import brentq

    key = "supply.front_flow_coefficient"
    spec = parse_spec({"task": "operating_point", "config": "circuit-drifter",
                       "axes": {key: {"values": ["2e-7 m^3/s/Pa^0.5", "3e-7 m^3/s/Pa^0.5"]}}})
    run_map(spec, tmp_path / "m.zarr", executor="threads", n_workers=1, progress=False)
    ds = open_sweep(tmp_path / "m.zarr")
    assert list(ds["cavitates"].values) == [True, False] and list(ds["status"].values) == [0, 0]
    edges = map_edges(tmp_path / "m.zarr", refine=True)
    assert [e["flag"] for e in edges] == ["cavitates"]
    config = read_config("circuit-drifter")[0]

    def least_front(k):
        machine = build(with_values(config, {key: f"{k!r} m^3/s/Pa^0.5"}))
        return machine.orbit(allow_cavitation=True).minimum_pressures_Pa["front"]

    root = brentq(least_front, 2e-7, 3e-7, xtol=1e-15, rtol=1e-10)
    assert math.isclose(edges[0]["value"], root, rel_tol=2e-6)


@pytest.mark.slow
def test_a_map_on_the_rock_stores_the_rock_figures_of_fresh_orbits():
    """The circuit drifter on its drill string and rock (examples/circuit_drifter_rock.toml, read
    relative to the spec's folder): the rock's figures in SI beside the circuit's, each point the
    fresh orbit's (the second continued from the first, to the integrator's accuracy)."""
    from pathlib import Path

    examples = Path(__file__).parents[2] / "examples"
    spec = parse_spec({"task": "operating_point", "config": str(examples / "circuit_drifter_rock.toml"),
                       "axes": {"supply.pump_flow": {"values": ["70 L/min", "75 L/min"]}}})
    got = _chunks(spec)
    assert list(got["status"]) == [0, 0] and list(got["origin"]) == [0, 1]
    config = read_config(examples / "circuit_drifter_rock.toml")[0]
    for i, flow in enumerate(("70 L/min", "75 L/min")):
        want = point_values(build(with_values(config, {"supply.pump_flow": flow})).orbit(), "circuit", True)
        assert want["work_on_rock"] > 0 and want["drilling_rate"] > 0
        for name, w in want.items():
            if isinstance(w, bool):
                assert bool(got[name][i]) == w, name
            elif not name.endswith("_margin"):
                assert got[name][i] == pytest.approx(w, rel=1e-7), (name, i)


def test_the_command_line_refuses_a_bad_axis_in_one_line_before_any_work(tmp_path, capsys):
    """A spec whose config is a file beside it (read relative to the spec's folder); an axis in the
    wrong unit: exit status 2, one line naming the key, no store made."""
    from pathlib import Path

    from impactbar.cli import main
    from impactbar.sweeps import load_spec

    examples = Path(__file__).parents[2] / "examples"
    (tmp_path / "mine.toml").write_text((examples / "circuit_drifter.toml").read_text())
    good = tmp_path / "good.toml"
    good.write_text('task = "operating_point"\nconfig = "mine.toml"\n[axes]\n'
                    '"chambers.front_area" = { start = "2.6 cm^2", stop = "3 cm^2", num = 3 }\n')
    spec = load_spec(good)
    assert spec.axes[0].unit == "m**2" and spec.axes[0].values == pytest.approx([2.6e-4, 2.8e-4, 3e-4])
    bad = tmp_path / "bad.toml"
    bad.write_text(good.read_text().replace('stop = "3 cm^2"', 'stop = "3 cm"'))
    assert main(["sweep", str(bad), "--out", str(tmp_path / "m.zarr")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "chambers.front_area" in err[0]
    assert not (tmp_path / "m.zarr").exists()


def test_the_command_line_prints_the_edges_in_the_unit_the_config_wrote(tmp_path, capsys):
    """``impactbar sweep``'s ``edge:`` lines: the relief edge between 70 and 80 L/min of a config
    that writes its pump flow in L/s, in L/s (the store keeps SI, 0.00116667 m^3/s); the map's axis
    written in L/min does not change it."""
    from pathlib import Path

    from impactbar.cli import main

    example = (Path(__file__).parents[2] / "examples" / "circuit_drifter.toml").read_text()
    mine = example.replace('pump_flow = "70 L/min"', 'pump_flow = "1.1666666666666667 L/s"')
    assert mine != example
    (tmp_path / "mine.toml").write_text(mine)
    (tmp_path / "map.toml").write_text('task = "operating_point"\nconfig = "mine.toml"\n[axes]\n'
                                       '"supply.pump_flow" = { values = ["70 L/min", "80 L/min"] }\n')
    assert main(["sweep", str(tmp_path / "map.toml"), "--out", str(tmp_path / "m.zarr"), "--quiet"]) == 0
    edges = [line for line in capsys.readouterr().out.splitlines() if line.startswith("edge:")]
    assert edges == ["edge: relief_opens changes along supply.pump_flow between 1.16667 L/s and 1.33333 L/s "
                     "(at grid index [0])"], edges


def test_the_readme_map_prints_what_the_readme_shows(tmp_path, monkeypatch, capsys):
    """The README's design-map example, run as it stands, prints the lines the README quotes."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    section = text[text.index("### Design maps of a drifter"):]
    code = re.search(r"```python\n(.*?)```", section, flags=re.S).group(1)
    shown = re.search(r"```text\n(.*?)```", section, flags=re.S).group(1)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md, design map", "exec"), {"__name__": "__readme__"})
    assert capsys.readouterr().out == shown
    # edges found again without refining keep the refined value the run stored
    from impactbar.sweeps import map_edges

    again = map_edges(tmp_path / "map.zarr")
    assert len(again) == 1 and f"{again[0]['value'] * 6e4:.2f}" in shown


@pytest.mark.slow
def test_the_docs_example_map(tmp_path):
    """The numbers the page "Design maps" quotes of ``examples/sweep_map_circuit_drifter.toml``'s map
    (441 points, about a minute of CPU time)."""
    from pathlib import Path

    spec = load_spec(Path(__file__).resolve().parents[2] / "examples" / "sweep_map_circuit_drifter.toml")
    run_map(spec, tmp_path / "map.zarr", executor="threads", n_workers=1, progress=False)
    ds = open_sweep(tmp_path / "map.zarr")
    assert ds["status"].dims == ("accumulator.precharge", "supply.pump_flow")
    assert bool(ds["stable"].values.all()) and not bool(ds["cavitates"].values.any())
    flags = list(ds["edge_flag"].values)
    assert len(flags) == 26 and set(flags) == {"relief_opens", "accumulator_empties"}
    q = ds["supply.pump_flow"].values * 6e4
    eff, freq = ds["hydraulic_efficiency"].values, ds["blow_frequency"].values
    pre = ds["accumulator.precharge"].values
    relief = (ds["edge_flag"].values == "relief_opens") & (ds["edge_axis"].values == 1)  # along the flow
    for i, low in zip(ds["edge_index"].values[relief], ds["edge_low"].values[relief] * 6e4, strict=True):
        assert low == pytest.approx(70.0 if pre[i[0]] <= 7.2e6 + 1.0 else 75.0, rel=1e-12)
    assert relief.sum() == pre.size  # one edge at every pre-charge
    assert np.all((eff[:, q < 70] > 0.49) & (eff[:, q < 70] < 0.6))  # "about 0.5 to 0.6"
    assert np.all((eff[:, -1] > 0.25) & (eff[:, -1] < 0.26))
    assert 47.5 < freq[:, q >= 75].min() and freq[:, q >= 75].max() < 51.5
    acc = ds["edge_flag"].values == "accumulator_empties"
    axis = ds["edge_axis"].values[acc]
    index = ds["edge_index"].values[acc]
    at_50 = [i for a, i in zip(axis, index, strict=True) if a == 0 and i[1] == 0]  # along the pre-charge
    assert len(at_50) == 1
    assert pre[at_50[0][0]] < 13.3e6 < pre[at_50[0][0] + 1]
