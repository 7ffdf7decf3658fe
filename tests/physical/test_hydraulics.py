"""A circuit part's flow coefficient from its datasheet (``physical.flow_coefficient``): the
coefficient passes the datasheet's flow at its pressure drop under the law the circuit uses."""

import math

import pytest

from impactbar import physical
from impactbar.drives.circuit.kinds._flow import phi


def test_the_turbulent_coefficient_passes_the_nominal_flow():
    K = physical.flow_coefficient("60 L/min", "5 bar")
    assert K * math.sqrt(5e5) == pytest.approx(60e-3 / 60, rel=1e-14)
    # the same from pint quantities, and in other units of the same dimensions
    ureg = physical.units.registry()
    assert physical.flow_coefficient(ureg.Quantity(1e-3, "m^3/s"), ureg.Quantity(0.5, "MPa")) == \
        pytest.approx(K, rel=1e-14)
    # the preset's valve edge (7.5e-6 m^3/s/Pa^0.5) passes 318.2 L/min at 5 bar
    assert physical.flow_coefficient(f"{7.5e-6 * math.sqrt(5e5) * 6e4} L/min", "5 bar") == \
        pytest.approx(7.5e-6, rel=1e-12)


@pytest.mark.parametrize("ptr", ["0.5 MPa", "2 MPa", "0 Pa"])
def test_under_the_smoothed_law_the_coefficient_passes_the_nominal_flow_exactly(ptr):
    """With the oil's transition pressure the coefficient passes Q_n at dp_n through the circuit's
    own smoothed orifice function (its compiled kernel's)."""
    K = physical.flow_coefficient("60 L/min", "5 bar", transition_pressure=ptr)
    p_tr = physical.units.to_si("p", ptr, "Pa", "")
    assert K * phi(5e5, p_tr**2) == pytest.approx(1e-3, rel=1e-13)
    if p_tr > 0:
        assert K > physical.flow_coefficient("60 L/min", "5 bar")  # the smoothing passes less


def test_the_relief_coefficient_is_linear():
    assert physical.flow_coefficient("100 L/min", "2 MPa", law="linear") * 2e6 == \
        pytest.approx(100e-3 / 60, rel=1e-14)


@pytest.mark.parametrize("args, kwargs, message", [
    (("60", "5 bar"), {}, "flow needs a unit"),
    (("60 L/min", "5 m"), {}, "pressure_drop must be a pressure"),
    (("-60 L/min", "5 bar"), {}, "flow must be positive"),
    (("60 L/min", "0 bar"), {}, "pressure_drop must be positive"),
    (("60 L/min", "5 bar"), {"law": "laminar"}, "law must be one of"),
    (("60 L/min", "5 bar"), {"law": "linear", "transition_pressure": "1 MPa"}, "transition_pressure is for"),
    (("60 L/min", "5 bar"), {"transition_pressure": "-1 MPa"}, "transition_pressure must be >= 0"),
])
def test_bad_input_is_named(args, kwargs, message):
    with pytest.raises(ValueError, match=message):
        physical.flow_coefficient(*args, **kwargs)
