"""The hydraulic drifter in SI (theory §10): the preset of theory §10's worked example against the rigid
piston's closed form done in SI by hand, simulate against find_orbit, and the config's checks."""

import math

import pytest

from impactbar.physical.drifter import DRIFTER_PRESETS, Drifter, drifter_preset


def _closed_form_si(m, F_s, F_r, x1, R):
    """The rigid piston of theory §10 in SI: impact velocity (m/s) and period (s)."""
    a_s, a_r = F_s / m, F_r / m
    v = math.sqrt(2 * x1 * (a_s + a_r) / (1 - R * R))
    u1 = math.sqrt(R * R * v * v + 2 * a_r * x1)
    return v, (u1 - R * v) / a_r + (u1 + v) / a_s


def test_hydraulic_drifter_preset_is_the_closed_form_in_si():
    d = drifter_preset("hydraulic-drifter")
    assert d.bar.mass_kg == pytest.approx(5.6, rel=1e-8)
    assert d.stroke_force_N == pytest.approx(5600.0, rel=1e-12) == d.return_force_N
    v, T = _closed_form_si(d.bar.mass_kg, 5600.0, 5600.0, 0.0215, 0.215)
    o = d.orbit()
    assert o.impact_velocity_m_s == pytest.approx(v, rel=1e-10)
    assert o.period_s == pytest.approx(T, rel=1e-10)
    assert o.blow_frequency_Hz == pytest.approx(1 / T, rel=1e-10)
    assert o.impact_energy_J == pytest.approx(0.5 * d.bar.mass_kg * v * v, rel=1e-10)
    assert o.impact_power_kW == pytest.approx(0.5 * d.bar.mass_kg * v * v / T / 1e3, rel=1e-10)
    # the numbers of theory §10's worked example (5.6 kg exactly)
    assert round(o.impact_velocity_m_s, 6) == 9.495684 and round(1e3 * o.period_s, 6) == 21.189907
    assert round(o.blow_frequency_Hz, 2) == 47.19 and round(o.impact_energy_J, 2) == 252.47
    s = o.summary()
    assert s["stable"] and s["multiplier"] == pytest.approx(0.215**2, rel=1e-10)


def test_simulated_drifter_settles_on_the_orbit():
    d = drifter_preset("hydraulic-drifter", valve={"delay": "0.5 ms"}, damping={"coefficient": "5 N*s/m"})
    o = d.orbit()
    tr, s = d.simulate(1.0, start_gap_m=0.03)
    assert s["blows"] > 20
    assert s["blow_frequency_Hz"] == pytest.approx(o.blow_frequency_Hz, rel=1e-8)
    assert s["impact_velocity_m_s"] == pytest.approx(o.impact_velocity_m_s, rel=1e-8)
    assert s["impact_power_kW"] == pytest.approx(o.impact_power_kW, rel=1e-7)
    assert o.blow_frequency_Hz < drifter_preset("hydraulic-drifter").orbit().blow_frequency_Hz


def test_flexible_piston_is_close_to_the_rigid_one():
    """The 448 mm steel piston is stiff at these forces (s = 244): with 4 flexible modes the
    blow's frequency and energy stay within a percent of the rigid piston's."""
    rigid = drifter_preset("hydraulic-drifter").orbit()
    flex = drifter_preset("hydraulic-drifter", model={"n_modes": 4}).orbit()
    assert flex.blow_frequency_Hz == pytest.approx(rigid.blow_frequency_Hz, rel=1e-2)
    assert flex.impact_energy_J == pytest.approx(rigid.impact_energy_J, rel=1e-2)


@pytest.mark.parametrize("change, match", [
    ({"valve": {"supply_pressure": "-1 MPa"}}, "supply_pressure"),
    ({"valve": {"bogus": 1}}, "valve.bogus"),
    ({"stop": {"area": "24 cm^2"}}, "exactly one of stop.restitution and stop.area"),
    ({"valve": {"switch_out": "21.5 kg"}}, "valve.switch_out"),
    ({"valve": {"delay": "-1 ms"}}, "delay"),
    ({"model": {"n_modes": -1}}, "n_modes"),
])
def test_drifter_config_is_checked(change, match):
    with pytest.raises(ValueError, match=match):
        drifter_preset("hydraulic-drifter", **change)


def test_missing_and_unknown_sections_are_named():
    cfg = {k: dict(v) if isinstance(v, dict) else v for k, v in DRIFTER_PRESETS["hydraulic-drifter"].items()}
    del cfg["valve"]["switch_out"]
    with pytest.raises(ValueError, match="missing key valve.switch_out"):
        Drifter.from_config(cfg)
    with pytest.raises(ValueError, match=r"unknown section \[force\]"):
        Drifter.from_config({**DRIFTER_PRESETS["hydraulic-drifter"], "force": {}})
    with pytest.raises(ValueError, match="unknown drifter preset"):
        drifter_preset("nope")


def test_physical_page_quotes_the_preset_as_computed():
    import re
    from pathlib import Path

    text = re.sub(r"\s+", " ", (Path(__file__).resolve().parents[2] / "docs" / "physical.md").read_text())
    m = re.search(r"`R = 0.215`\): ([0-9.]+) m/s, ([0-9.]+) Hz, ([0-9.]+) J, ([0-9.]+) kW", text)
    o = drifter_preset("hydraulic-drifter").orbit()
    for quoted, value in zip(m.groups(), (o.impact_velocity_m_s, o.blow_frequency_Hz, o.impact_energy_J,
                                          o.impact_power_kW), strict=True):
        decimals = len(quoted.split(".")[1])
        assert abs(float(quoted) - value) <= 0.5 * 10.0**-decimals


def test_only_the_documented_presets_are_taken():
    """The documented preset alone: an undocumented name (an old one, say) is refused by name, as any
    unknown preset."""
    assert list(DRIFTER_PRESETS) == ["hydraulic-drifter"]
    with pytest.raises(ValueError, match="unknown drifter preset 'drifter-old'; known: hydraulic-"):
        drifter_preset("drifter-old")


def test_one_si_orbit_class_for_drifters_and_its_blow_frequency_counts_the_impacts():
    """The valve drifter's and the oil circuit's SI orbits are one class (the circuit's adds its
    pressures); the blow frequency is the impacts over the period: the one-impact orbit found again
    as a two-impact one (its period doubled) blows as often (it read the period alone, half)."""
    from impactbar import find_orbit
    from impactbar.physical import CircuitDrifterOrbit, DrifterOrbit, drifter_preset

    assert issubclass(CircuitDrifterOrbit, DrifterOrbit)
    d = drifter_preset("hydraulic-drifter")
    one = d.orbit()
    two = DrifterOrbit(d, find_orbit(d.model(), d.drive(), impacts=2, guess=one.orbit))
    assert two.orbit.period == pytest.approx(2 * one.orbit.period, rel=1e-10)
    assert two.blow_frequency_Hz == pytest.approx(one.blow_frequency_Hz, rel=1e-10)
    assert one.blow_frequency_Hz == pytest.approx(1.0 / one.period_s, rel=1e-14)
    assert two.summary()["blow_frequency_Hz"] == pytest.approx(one.summary()["blow_frequency_Hz"], rel=1e-10)
