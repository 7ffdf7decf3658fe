"""The oil circuit drawn from its configuration: the nodes and the parts in the figure are the
config's (the preset's four nodes and five parts, each ``[parts.<name>]`` table's part and node)."""

from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from impactbar import physical  # noqa: E402
from impactbar.physical.config import read_toml  # noqa: E402
from impactbar.plotting import plot_circuit_graph  # noqa: E402

DRILL = Path(__file__).resolve().parents[2] / "examples" / "circuit_drill_parts.toml"
PRESET_PARTS = {"pump", "front feed", "valve (stroke)", "valve (return)", "relief valve"}


def _drawn(ax, what):
    return {t.get_gid().split(":", 1)[1] for t in ax.texts if (t.get_gid() or "").startswith(what)}


def test_the_drills_figure_has_the_configs_nodes_and_parts():
    tables = read_toml(DRILL)["parts"]
    ax = plot_circuit_graph(physical.load(DRILL))
    own = {"cushion", "return_line"}  # (the kinds with a node of their own)
    assert _drawn(ax, "node:") == {"supply", "front", "rear", "tank"} | own
    assert _drawn(ax, "part:") == PRESET_PARTS | {f"{n} ({t['kind']})" for n, t in tables.items()}
    # the valve returns into the cushion's node, which drains into the return line
    arrows = {t.get_text() for t in ax.texts}
    assert "valve (return)" in arrows
    plt.close(ax.figure)


def test_the_parts_edges_join_the_nodes_the_config_names():
    g = physical.circuit_graph(physical.load(DRILL))
    edges = {(e.source, e.target, e.label) for e in g.edges}
    assert {("rear", "cushion", "valve (return)"), ("cushion", "return_line", "cushion (cushion)"),
            ("return_line", "tank", "return_line (return_accumulator)"),
            ("rear", "front", "land (laminar_leak)"), ("front", "tank", "front_guide (laminar_leak)"),
            ("front", "supply", "check (check_valve)")} <= edges
    assert len(edges) == 5 + 5


def test_the_preset_has_no_parts_and_a_drawing_on_given_axes():
    d = physical.circuit_preset("circuit-drifter")
    fig, ax = plt.subplots()
    assert plot_circuit_graph(d, ax=ax) is ax
    assert _drawn(ax, "node:") == {"supply", "front", "rear", "tank"}
    assert _drawn(ax, "part:") == PRESET_PARTS
    plt.close(fig)


def test_a_machine_without_a_circuit_is_refused():
    with pytest.raises(ValueError, match="drifter must be a drifter with its oil circuit"):
        plot_circuit_graph(physical.drifter_preset("hydraulic-drifter"))


def test_a_spool_in_the_valves_place_is_drawn_with_its_ports_and_no_ramped_valve():
    d = physical.load(DRILL.with_name("circuit_drill_spool.toml"))
    assert d.valve_stand_in == "main_spool"
    assert physical.circuit_preset("circuit-drifter").valve_stand_in is None
    edges = {(e.source, e.target, e.label) for e in physical.circuit_graph(d).edges}
    assert not any(label.startswith("valve (") for *_, label in edges)
    spool = "main_spool (spool_valve)"
    # its main ports and pilot ports as its records join them: the return side into the cushion,
    # which takes the valve's return port
    assert {("supply", "rear", f"{spool} main port P"), ("rear", "cushion", f"{spool} main port T"),
            ("supply", "main_spool", f"{spool} pilot supply port"),
            ("main_spool", "cushion", f"{spool} pilot return port")} <= edges
    ax = plot_circuit_graph(d)
    assert "node:main_spool" in {t.get_gid() for t in ax.texts}
    plt.close(ax.figure)
