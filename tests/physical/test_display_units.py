"""What a designer reads: SI values shown in the unit the config wrote, else the key table's display unit."""

from types import SimpleNamespace

import pytest

from impactbar.physical.circuit_branch import CircuitBranch
from impactbar.physical.display_units import format_si
from impactbar.physical.loader import build, read_config, with_values


@pytest.mark.parametrize(("value", "unit", "written", "shown"), [
    (0.0015545502243099316, "m**3/s", "80 L/min", "93.273 L/min"),   # 0.00155455 * 60000
    (0.00116667, "m**3/s", None, "70.0002 L/min"),                    # the display unit
    (-0.00010000000000000003, "m**3", "0.0001 m**3", "-0.1 L"),       # written in SI: display unit
    (2.5e7, "Pa", "25 MPa", "25 MPa"),
    (0.1, "m", "4 in", "3.93701 in"),                                 # 0.1 / 0.0254
    (0.5, "", 0.4, "0.5"),
])
def test_format_si_in_the_written_or_display_unit(value, unit, written, shown):
    assert format_si(value, unit, written) == shown


def test_negative_volume_error_quotes_litres_not_si_repr():
    cfg = read_config("circuit-drifter")[0]
    with pytest.raises(ValueError, match=r"front_volume must be positive; got -0\.1 L$"):
        build(with_values(cfg, {"chambers.front_volume": "-0.00010000000000000003 m**3"}), None)


def test_circuit_branch_repr_in_display_units():
    fake = SimpleNamespace(values=[0.00116667, 0.00141667], events=[], status="done")
    branch = CircuitBranch(SimpleNamespace(from_dimensionless=lambda p, x: x, key_field=lambda p: p),
                           "supply.pump_flow",
                           "m**3/s", fake)
    assert repr(branch) == "CircuitBranch(supply.pump_flow from 70.0002 L/min to 85.0002 L/min, " \
                           "2 points, 0 events, done)"


def test_optimiser_changes_are_written_in_the_configs_unit_and_read_back_exactly():
    from impactbar.physical.display_units import written_quantity
    from impactbar.physical.units import to_si

    rng = __import__("numpy").random.default_rng(3)
    written = 0
    for x in rng.uniform(0.001, 0.002, 50):
        text = written_quantity(float(x), "m**3/s", "80 L/min")
        assert to_si("q", text, "m**3/s", "") == float(x)  # bit-identical designs
        written += text.endswith(" L/min")
    assert written >= 40
    assert written_quantity(0.0015545502243099316, "m**3/s", "80 L/min") == "93.27301345859587 L/min"
