"""The drill with the parts a drifter has on the preset's ramped valve
(``examples/circuit_drill_parts.toml``): its parts where the designer looks (``impactbar drifter``'s
header lists them; the histories hold each part's node pressure and flow) and a return line fed by a
cushion (its port ``"none"``).

- Each part's flow in the histories against its law evaluated here on the histories' pressures and
  gap (a laminar leak's ``G dp``, an orifice's ``K phi(dp)``, the cushion's ``K g(y) phi(dp)`` with
  ``g`` interpolated by numpy), and the return line's balance: over the periodic orbit the oil the
  cushion passes into it is the oil it drains (their means over the period within 1e-3).
- The drive's own histories carry the parts' nodes and flows by their symbols.
"""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import trapezoid

from impactbar.cli.drifter import _circuit_header
from impactbar.physical import load, read_config
from impactbar.physical.circuit import CircuitDrifter

DRILL = Path(__file__).resolve().parents[2] / "examples" / "circuit_drill_parts.toml"
P_TR = 0.2e6  # the example's [oil] transition_pressure (Pa)


def phi(dp):
    return dp * (dp * dp + P_TR ** 2) ** -0.25


@pytest.fixture(scope="module")
def drill():
    return load(DRILL)


@pytest.fixture(scope="module")
def histories(drill):
    return drill.orbit().histories(2001)


def test_header_lists_each_part_with_its_nodes_and_values_as_written(drill):
    lines = _circuit_header(drill).splitlines()
    parts = [ln.strip() for ln in lines if ln.strip().startswith("part ")]
    assert parts == [
        "part cushion (cushion): valve_return -> cushion -> return_line; volume 0.0125 L, coefficient "
        "7.5e-06 m^3/s/Pa^0.5, gaps 27 mm, 36 mm, 45 mm, openings 1, 0.4, 0.1",
        "part return_line (return_accumulator): return_line -> tank; volume 0.3 L, flow_coefficient 2e-05 "
        "m^3/s/Pa^0.5, precharge 0.2 MPa, gas_volume 0.5 L, polytropic_exponent 1.4",
        "part land (laminar_leak): rear -> front; conductance 1.5e-13 m^3/s/Pa",
        "part front_guide (laminar_leak): front -> tank; conductance 1.5e-13 m^3/s/Pa",
        "part check (check_valve): front -> supply; coefficient 3.75e-06 m^3/s/Pa^0.5, cracking_pressure "
        "0.05 MPa, opening_span 0.05 MPa"]


def test_header_shows_a_value_left_in_si_in_the_display_unit():
    cfg = read_config(str(DRILL))[0]
    cfg["parts"]["cushion"]["volume"] = "1.25e-5 m^3"  # in SI: shown in litres
    cfg["parts"]["land"]["conductance"] = "3e-13 m^3/s/Pa"
    lines = _circuit_header(CircuitDrifter.from_config(cfg))
    assert "volume 0.0125 L, coefficient" in lines and "conductance 3e-13 m^3/s/Pa" in lines


def test_histories_hold_each_parts_pressure_and_flow_by_its_law(drill, histories):
    h = histories
    assert {"p_cushion_Pa", "p_return_line_Pa", "q_cushion_m3_s", "q_return_line_m3_s", "q_land_m3_s",
            "q_front_guide_m3_s", "q_check_m3_s"} <= set(h)
    tank = 0.3e6
    np.testing.assert_allclose(h["q_land_m3_s"], 1.5e-13 * (h["p_r_Pa"] - h["p_f_Pa"]), rtol=1e-12,
                               atol=1e-19)
    np.testing.assert_allclose(h["q_front_guide_m3_s"], 1.5e-13 * (h["p_f_Pa"] - tank), rtol=1e-12)
    np.testing.assert_allclose(h["q_return_line_m3_s"], 2e-5 * phi(h["p_return_line_Pa"] - tank),
                               rtol=1e-10)
    g = np.interp(h["gap_m"], [0.027, 0.036, 0.045], [1.0, 0.4, 0.1])
    np.testing.assert_allclose(h["q_cushion_m3_s"],
                               7.5e-6 * g * phi(h["p_cushion_Pa"] - h["p_return_line_Pa"]),
                               rtol=1e-9, atol=1e-15)
    dp = h["p_f_Pa"] - h["p_s_Pa"]
    opening = np.clip((dp - 0.05e6) / 0.05e6, 0.0, 1.0)
    np.testing.assert_allclose(h["q_check_m3_s"], 3.75e-6 * opening * phi(dp), rtol=1e-9, atol=1e-15)
    assert h["q_check_m3_s"].max() > 1e-4  # (the check valve opens on the orbit)


def test_the_return_line_drains_what_the_cushion_passes_it(histories):
    h = histories
    t = h["t_s"]
    into, out = (trapezoid(h[k], t) / t[-1] for k in ("q_cushion_m3_s", "q_return_line_m3_s"))
    assert abs(into - out) < 1e-3 * out
    # (L/min: the pump's 70 L/min less the front guide's 0.2 to the tank, within 1 %: the circuit's
    # balances are of volumes, V p' / beta + V' = Q, not of mass)
    assert abs(into * 6e4 - 69.8) < 0.7


def test_drive_histories_carry_the_parts_nodes_and_flows(drill):
    import dataclasses

    from impactbar import InitialState, simulate

    o = drill.orbit().orbit
    y, M = np.asarray(o.states_after_impact[0]), o.model.n_modes + 1
    drive = dataclasses.replace(o.drive, start_pressures=tuple(o.drive_states[0]))
    h = drive.histories(simulate(o.model, drive, InitialState(y[:M], y[M:]), 0.5 * o.period))
    assert {"p_cushion", "p_return_line", "q_cushion", "q_return_line", "q_land", "q_check"} <= set(h)
    assert h["q_land"].shape == h["t"].shape
