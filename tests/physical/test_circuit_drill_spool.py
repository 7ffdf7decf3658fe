"""The example drill with all the parts, its main valve a pilot-operated spool
(``examples/circuit_drill_spool.toml``): no ``[valve]`` table (the spool stands in for it), the cushion
taking the spool's return port, its orbit's numbers (``impactbar drifter``'s, quoted in the tutorial)
and two checks of them:

- the ramped valve plays no part: the drill's ``[valve]`` table added gives the same orbit, bit for bit;
- the oil balance at the return line: over the periodic orbit the oil the cushion passes into it (all
  the rear chamber's return through the spool) is the oil it drains (their means within 1e-3);
- the control chamber's: its pilot ports' mean volume flows differ by its compression over a period,
  the loop integral of ``p_c dV_c`` over ``beta T`` (a compressible oil of constant bulk modulus keeps
  ``int V/beta dp``, not the volume of oil that flowed), and the spool's velocity is its position's rate.
"""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import trapezoid

from impactbar.cli.drifter import _circuit_header
from impactbar.physical import load, read_config
from impactbar.physical.circuit import CircuitDrifter
from impactbar.physical.units import to_si

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SPOOL = EXAMPLES / "circuit_drill_spool.toml"


@pytest.fixture(scope="module")
def drill():
    return load(SPOOL)


@pytest.fixture(scope="module")
def orbit(drill):
    return drill.orbit()


def test_the_spool_drill_reads_without_a_valve_table_its_cushion_on_the_spools_return(drill):
    assert "valve" not in read_config(str(SPOOL))[0]
    header = _circuit_header(drill)
    assert "switch_out" not in header.splitlines()[1]  # (the spool's pilot ports switch it)
    assert "part main_spool (spool_valve): valve_return -> main_spool; mass 0.2 kg, stroke 8 mm" in header
    assert "part cushion (cushion): valve_return -> cushion -> return_line" in header


def test_the_spool_drills_orbit_and_the_valve_table_playing_no_part(orbit):
    assert orbit.stable
    assert orbit.blow_frequency_Hz == pytest.approx(45.71262426822849, rel=1e-6)
    assert orbit.impact_velocity_m_s == pytest.approx(11.350639573551165, rel=1e-6)
    assert orbit.impact_energy_J == pytest.approx(360.74365444546777, rel=1e-6)
    assert orbit.hydraulic_efficiency == pytest.approx(0.5303828860213802, rel=1e-6)
    cfg = read_config(str(SPOOL))[0]
    cfg["valve"] = read_config(str(EXAMPLES / "circuit_drill_parts.toml"))[0]["valve"]
    assert CircuitDrifter.from_config(cfg).orbit().period_s == orbit.period_s


def test_the_return_line_drains_what_the_cushion_passes_over_a_period(orbit):
    h = orbit.histories(4001)
    t = h["t_s"]
    into, out = (trapezoid(h[k], t) / (t[-1] - t[0]) for k in ("q_cushion_m3_s", "q_return_line_m3_s"))
    assert into > 5e-4  # (about 0.8 L/s of return flow)
    assert into == pytest.approx(out, rel=1e-3)


def test_the_pilot_ports_differ_by_the_control_chambers_compression_over_a_period(drill, orbit):
    """Over a period ``int (q_in - q_out) dt = int V/beta dp = -oint p dV / beta`` for the control
    chamber (volume ``V_c + A_c x_s``, pressure ``p_c``): the pilot ports' mean flows are not equal
    (1.4 % apart here) but differ by the work the chamber's oil does on the spool's large end over
    ``beta T``, closed here to 1e-3 by the trapezoidal rule on 20,001 samples (3e-4 measured)."""
    h = orbit.histories(20001)
    t = h["t_s"]
    period = t[-1] - t[0]
    into, out = (trapezoid(h[k], t) / period for k in ("q_main_spool_0_m3_s", "q_main_spool_1_m3_s"))
    cfg = read_config(str(SPOOL))[0]
    spool = cfg["parts"]["main_spool"]
    area = to_si("large_area", spool["large_area"], "m**2", "")
    stroke = to_si("stroke", spool["stroke"], "m", "")
    beta = to_si("bulk_modulus", cfg["oil"]["bulk_modulus"], "Pa", "")
    p, x = h["p_main_spool_Pa"], h["x_v"]
    work = float(np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(x))) * area * stroke  # oint p dV (J)
    assert 28.0 < work < 32.0  # (some 30 J a period, as theory §11 says: 29.75 J)
    assert 0.013 < abs(into / out - 1.0) < 0.016  # (1.4 % apart: 1.44 %)
    assert into - out == pytest.approx(-work / (beta * period), rel=1e-3)


def test_the_spools_velocity_is_the_rate_of_its_position(orbit):
    h = orbit.histories(20001)
    assert "v_main_spool_Pa" not in h
    stroke = to_si("stroke", read_config(str(SPOOL))[0]["parts"]["main_spool"]["stroke"], "m", "")
    t, v, x = h["t_s"], h["v_main_spool_m_s"], h["x_v"] * stroke
    travelled = np.concatenate(([0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))))
    assert 0.5 < np.max(np.abs(v)) < 50.0  # (m/s: its 8 mm stroke in a fraction of a millisecond)
    assert np.max(np.abs(travelled - (x - x[0]))) < 1e-3 * stroke
