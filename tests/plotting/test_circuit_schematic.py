"""The oil circuit's schematic (theory §11): every part drawn and named, a drifter's SI values on
its parts, and the valve's switch points placed to scale along the stroke axis."""

import matplotlib
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from impactbar import physical  # noqa: E402
from impactbar.plotting import plot_circuit_schematic  # noqa: E402

#: a name on each part of the circuit (theory §11, ``impactbar.drives.circuit.parts``)
PARTS = ("pump", "supply node", "gas accumulator", "relief valve", "tank", "front orifice", "main valve",
         "rear (stroke)", "front (return)", "piston", "switch_out", "switch_in", "impact position")


def _texts(ax):
    return " | ".join(t.get_text() for t in ax.texts)


def _marks(ax):
    """The x position of each stroke-axis mark, by its gid."""
    return {ln.get_gid(): ln.get_xdata()[0] for ln in ax.get_lines() if ln.get_gid()}


def test_every_part_is_drawn_and_named_without_a_drifter():
    ax = plot_circuit_schematic()
    text = _texts(ax)
    for part in PARTS:
        assert part in text, part
    assert "$Q_p$" in text and "$p_0$" in text and "$K_f$" in text  # the symbols of theory §11
    assert set(_marks(ax)) == {"impact", "switch_out", "switch_in"}
    plt.close("all")


def test_a_drifters_values_label_its_parts_and_the_switch_points_sit_to_scale():
    d = physical.circuit_preset("circuit-drifter", valve={"switch_in": "8 mm"})
    fig, ax = plt.subplots()
    assert plot_circuit_schematic(d, ax=ax) is ax
    text = _texts(ax)
    for part in PARTS:
        assert part in text, part
    # the preset's config strings, back from the SI values the drifter holds
    for shown in ("70 L/min", "0.25 L", "$p_0$ = 10 MPa", "$V_0$ = 0.5 L", "$n$ = 1.4", "25 MPa",
                  "30 L/min/MPa", "0.3 MPa", "5.6 cm²", "2.8 cm²", "0.1 L", "0.05 L", "1 ms",
                  "switch_out\n21.5 mm", "switch_in\n8 mm", "5.6 kg"):
        assert shown in text, shown
    x = _marks(ax)
    # gaps grow away from the stop: both switch points left of the impact, in the gaps' ratio
    assert x["switch_out"] < x["switch_in"] < x["impact"]
    assert (x["impact"] - x["switch_out"]) / (x["impact"] - x["switch_in"]) == pytest.approx(21.5 / 8)
    plt.close("all")


def test_without_switch_in_the_valve_returns_at_impact():
    ax = plot_circuit_schematic(physical.circuit_preset("circuit-drifter"))
    assert "returns at impact" in _texts(ax)
    assert set(_marks(ax)) == {"impact", "switch_out"}
    plt.close("all")


def test_a_machine_without_an_oil_circuit_is_refused():
    with pytest.raises(ValueError, match="drifter must be a CircuitDrifter"):
        plot_circuit_schematic(physical.drifter_preset("hydraulic-drifter"))
    with pytest.raises(ValueError, match="drifter must be a CircuitDrifter"):
        plot_circuit_schematic({"rear_area_m2": 1.0})


def test_a_spool_in_the_valves_place_is_drawn_as_the_spool_without_the_ramped_valves_switches():
    d = physical.load("examples/circuit_drill_spool.toml")
    ax = plot_circuit_schematic(d)
    text = _texts(ax)
    assert "main valve: main_spool" in text and "pilot-operated spool" in text
    # the ramped valve's placeholder values (never switched) are not drawn: no K_v, tau_v, switch points
    assert "$K_v$" not in text and "tau_v" not in text and "switch_out" not in text
    assert set(_marks(ax)) == {"impact"}
    plt.close("all")
