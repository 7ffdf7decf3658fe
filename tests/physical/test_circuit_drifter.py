"""The drifter with its oil circuit in SI: ``impactbar.physical.circuit``.

The operating point of the preset against numbers computed here independently of the SI layer: the
SI outputs against the dimensionless orbit times the scales written out here, the oil's work on the
piston over a period against the energy the blow takes (the rigid, undamped piston's kinetic energy
before the impact less after it), the mean supply pressure between the extremes of its history.
"""

import math

import pytest
from scipy.integrate import trapezoid

from impactbar.physical.circuit import CIRCUIT_PRESETS, CircuitDrifter, circuit_preset


@pytest.fixture(scope="module")
def point():
    return circuit_preset("circuit-drifter").orbit()


def test_preset_operating_point(point):
    d = point.drifter
    m = 7850 * math.pi / 4 * 0.045 ** 2 * 0.44854236
    om = math.sqrt(1e7 * 5.6e-4 / (m * 0.44854236))
    assert d.omega_rad_s == pytest.approx(om, rel=1e-12)
    o = point.orbit
    assert point.blow_frequency_Hz == pytest.approx(om / o.period, rel=1e-12)
    assert point.impact_velocity_m_s == pytest.approx(0.44854236 * om * o.impact_velocity, rel=1e-12)
    assert point.impact_energy_J == pytest.approx(0.5 * m * point.impact_velocity_m_s ** 2, rel=1e-9)
    assert point.stable and 40 < point.blow_frequency_Hz < 55 and 8 < point.impact_velocity_m_s < 12
    acc = point.energy_account
    assert abs(acc["relative_residual"]) < 1e-10
    # the oil's work on the piston over a period is what the impact takes: (1 - R^2) m v^2 / 2
    assert acc["piston"] == pytest.approx((1 - 0.215 ** 2) * point.impact_energy_J, rel=1e-7)
    assert 0 < point.hydraulic_efficiency < 1
    h = point.histories(2001)
    p = point.mean_supply_pressure_Pa
    assert h["p_s_Pa"].min() < p < h["p_s_Pa"].max()
    assert trapezoid(h["p_s_Pa"], h["t_s"]) / point.period_s == pytest.approx(p, rel=1e-5)
    assert h["V_r_m3"].min() > 0 and h["x_v"].min() >= 0 and h["x_v"].max() <= 1
    low = point.minimum_pressures_Pa  # the extremes of the interpolants, below the sampled ones
    for name, key in (("front", "p_f_Pa"), ("rear", "p_r_Pa"), ("supply", "p_s_Pa")):
        assert 0 < low[name] <= h[key].min() < low[name] + 1e3
    assert not point.cavitates


def test_indicator_diagrams_enclose_the_oils_work_on_the_piston(point):
    """The areas of the chambers' p-V loops (trapezoids over the sampled histories) against the
    energy account's ``piston`` term (a quadrature carried along the integration): second order in
    the spacing, their Richardson limit equal to 1e-8; the rear chamber drives, the front one takes
    work back (a loop run anticlockwise)."""
    acc = point.energy_account["piston"]
    errs = {n: point.indicator_work_J(n)["piston"] / acc - 1.0 for n in (2000, 4000, 8000, 16000)}
    assert abs(errs[4000]) < 2e-6
    assert 3.5 < errs[2000] / errs[4000] < 4.5 and 3.5 < errs[8000] / errs[16000] < 4.5
    assert abs((4.0 * errs[16000] - errs[8000]) / 3.0) < 1e-8
    w = point.indicator_work_J()
    assert w["rear"] > acc > 0 > w["front"] and w["piston"] == w["rear"] + w["front"]


def test_the_operating_point_figure(point):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    axes = point.plot(points=500)
    assert axes.shape == (4,)
    h = point.histories(500)
    rear = axes[2].get_lines()[0]
    assert rear.get_xdata() == pytest.approx(h["V_r_m3"] * 1e6)
    assert rear.get_ydata() == pytest.approx(h["p_r_Pa"] / 1e6)
    assert f"{point.indicator_work_J(histories=h)['rear']:.4g} J" in axes[2].get_title()
    plt.close("all")
    with pytest.raises(ValueError, match="points"):
        point.plot(points=1)


def test_a_branch_in_the_precharge_in_si(point):
    """``continue_circuit`` in ``accumulator.precharge``: its start is the operating point, its end
    the operating point of a drifter configured afresh at the end's pre-charge (through the config's
    units, not the branch's conversion); the figure draws what the arrays hold."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from impactbar.physical import continue_circuit

    b = continue_circuit(point.drifter, "accumulator.precharge", "10.4 MPa")
    assert b.branch.status == "reached" and len(b) >= 3
    assert b.values[0] == pytest.approx(1e7, rel=1e-12) and b.values[-1] == pytest.approx(1.04e7, rel=1e-9)
    assert b.blow_frequency_Hz[0] == pytest.approx(point.blow_frequency_Hz, rel=1e-9)
    assert b.impact_energy_J[0] == pytest.approx(point.impact_energy_J, rel=1e-9)
    end = circuit_preset("circuit-drifter", accumulator={"precharge": f"{float(b.values[-1])!r} Pa"}).orbit()
    assert b.blow_frequency_Hz[-1] == pytest.approx(end.blow_frequency_Hz, rel=1e-8)
    assert b.impact_energy_J[-1] == pytest.approx(end.impact_energy_J, rel=1e-8)
    assert b.stable.all() and np.all(b.max_abs_multiplier < 1.0) and b.events == []
    assert "accumulator.precharge from 10 MPa to 10.4 MPa" in repr(b)
    axes = b.plot()
    line = axes[1].get_lines()[0]
    assert line.get_xdata() == pytest.approx(b.values / 1e6)
    assert line.get_ydata() == pytest.approx(b.impact_energy_J)
    assert axes[1].get_xlabel() == "accumulator.precharge (MPa)"
    plt.close("all")
    with pytest.raises(ValueError, match="accumulator.precharge"):
        continue_circuit(point.drifter, "accumulator.precharge", 12.0)
    with pytest.raises(ValueError, match="to must be a number"):
        continue_circuit(point.drifter, "precharge", "12 MPa")


def test_from_config_errors():
    cfg = CIRCUIT_PRESETS["circuit-drifter"]
    with pytest.raises(ValueError, match="unknown section"):
        CircuitDrifter.from_config({**cfg, "pump": {}})
    with pytest.raises(ValueError, match="missing key supply.pump_flow"):
        CircuitDrifter.from_config({**cfg, "supply": {k: v for k, v in cfg["supply"].items()
                                                      if k != "pump_flow"}})
    with pytest.raises(ValueError, match="chambers.front_area"):
        circuit_preset("circuit-drifter", chambers={"front_area": "6 cm^2"})
    with pytest.raises(ValueError, match="precharge"):
        circuit_preset("circuit-drifter", accumulator={"precharge": "30 MPa"})
    with pytest.raises(ValueError, match="valve.flow_coefficient"):
        circuit_preset("circuit-drifter", valve={"flow_coefficient": "6e-6 m^3/s"})
    with pytest.raises(ValueError, match="unknown circuit preset"):
        circuit_preset("nope")


def test_readme_numbers_and_the_example_config(point):
    import tomllib
    from pathlib import Path

    line = (f"{point.blow_frequency_Hz:.1f} Hz, {point.impact_energy_J:.0f} J, "
            f"{point.mean_supply_pressure_Pa / 1e6:.1f} MPa, efficiency {point.hydraulic_efficiency:.2f}")
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    assert f"# {line}\n" in readme
    example = Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter.toml"
    with open(example, "rb") as f:
        assert CircuitDrifter.from_config(tomllib.load(f)) == point.drifter  # the preset's numbers


def test_cli_orbits_prints_the_operating_point(point, capsys):
    from impactbar.cli import main

    example = __import__("pathlib").Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter.toml"
    assert main(["orbits", str(example)]) == 0
    out = capsys.readouterr().out
    assert f"blow frequency {point.blow_frequency_Hz:.4g} Hz" in out and "stable" in out
