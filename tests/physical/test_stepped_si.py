"""A stepped piston in SI: ``[bar]`` with lists of segments, :class:`SteppedBar`, and the
hammer, the drifter and the circuit drifter on its exact modes."""

import copy
import dataclasses
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

import impactbar.physical as P
from impactbar import SteppedPiston
from impactbar.physical import Bar, SteppedBar, piston_from_units

EXAMPLE = Path(__file__).parents[2] / "examples" / "stepped_drifter.toml"
STEEL = ("210 GPa", "7850 kg/m^3")


def _split(cfg, fraction=0.4):
    """``cfg`` with its uniform piston cut into two segments of the same section."""
    cfg = copy.deepcopy(cfg)
    b = cfg["bar"]
    L_mm = P.Bar.from_units(b["E"], b["density"], b["length"], diameter=b.get("diameter")).length_m * 1e3
    b["length"] = [f"{fraction * L_mm!r} mm", f"{(1.0 - fraction) * L_mm!r} mm"]
    b["diameter"] = [b["diameter"]] * 2
    return cfg


def _close(a, b, rel):
    return abs(a - b) <= rel * max(abs(a), abs(b))


# -- the piston ------------------------------------------------------------------------------------
def test_a_list_of_one_segment_is_the_uniform_bar():
    one = piston_from_units(*STEEL, ["450 mm"], diameter=["45 mm"])
    assert one == Bar.from_units(*STEEL, "450 mm", diameter="45 mm")
    cfg = copy.deepcopy(P.PRESETS["hydraulic-drill"])
    cfg["bar"]["length"], cfg["bar"]["diameter"] = ["450 mm"], ["45 mm"]
    h1, h0 = P.Hammer.from_config(cfg), P.preset("hydraulic-drill")
    assert h1 == h0 and h1.model == h0.model and h1.model.piston is None


def test_stepped_bar_mass_sections_and_first_mode_against_closed_forms():
    """Mass ``rho sum A L``, the struck end's section, and ``k_1`` of the two-segment frequency
    equation ``Z_1 tan(k l_1) + Z_2 tan(k l_2) = 0`` solved by scipy's brentq."""
    b = piston_from_units(*STEEL, ["120 mm", "330 mm"], diameter=["70 mm", "45 mm"])
    assert isinstance(b, SteppedBar) and b.n_segments == 2
    a1, a2 = math.pi * 0.07 * 0.07 / 4, math.pi * 0.045 * 0.045 / 4  # as Bar.from_units computes them
    assert b.mass_kg == pytest.approx(7850.0 * (a1 * 0.12 + a2 * 0.33), rel=1e-14)
    assert b.length_m == pytest.approx(0.45, rel=1e-15)
    assert b.area_m2 == pytest.approx(a2, rel=1e-15) and b.diameter_m == pytest.approx(0.045, rel=1e-15)
    assert b.mass_per_length_kg_m == pytest.approx(b.mass_kg / 0.45, rel=1e-15)
    assert b.impedance_N_s_m == pytest.approx(7850.0 * math.sqrt(2.1e11 / 7850.0) * a2, rel=1e-14)
    l1, l2 = 0.12 / 0.45, 0.33 / 0.45

    def f(k):
        return a1 * math.sin(k * l1) * math.cos(k * l2) + a2 * math.cos(k * l1) * math.sin(k * l2)

    grid = np.linspace(1e-3, 2 * math.pi, 4001)
    j = next(i for i in range(grid.size - 1) if f(grid[i]) * f(grid[i + 1]) < 0)
    k1 = brentq(f, grid[j], grid[j + 1], xtol=1e-15, rtol=1e-15)
    assert b.first_wavenumber == pytest.approx(k1, rel=1e-12)
    assert b.piston == SteppedPiston([0.12, 0.33], [a1, a2])
    assert "2 segments" in b.describe() and "120 mm x 38.48 cm^2" in repr(b)


@pytest.mark.parametrize("kwargs, match", [
    ({"length": ["120 mm", "330 mm"], "diameter": ["70 mm"]}, r"bar\.diameter must give one value per"),
    ({"length": ["120 mm", "-3 mm"], "diameter": "45 mm"}, r"bar\.length\[1\]"),
    ({"length": ["120 mm", "330 mm"], "diameter": ["70 mm", "0 mm"]}, r"bar\.diameter\[1\]"),
    ({"length": ["120 mm", "330 mm"], "area": ["12 cm^2", "3 mm"]}, r"bar\.area\[1\]"),
    ({"length": ["120 mm", "330 mm"]}, r"exactly one of bar\.diameter and bar\.area"),
    ({"length": [], "diameter": []}, r"at least one segment"),
])
def test_bad_segments_are_refused_by_name(kwargs, match):
    with pytest.raises(ValueError, match=match):
        piston_from_units(*STEEL, **kwargs)


def test_stepped_bar_refuses_one_segment_and_a_bad_ratio():
    with pytest.raises(ValueError, match="at least 2 segments"):
        SteppedBar(2.1e11, 7850.0, [0.3], [1e-3])
    with pytest.raises(ValueError, match="within a factor"):
        SteppedBar(2.1e11, 7850.0, [0.3, 0.1], [1.0, 1e-7])
    with pytest.raises(ValueError, match=r"lengths_m\[1\]"):
        SteppedBar(2.1e11, 7850.0, [0.3, math.nan], [1e-3, 1e-3])


# -- the hammer ------------------------------------------------------------------------------------
def test_equal_sections_give_the_uniform_hammers_orbits():
    """Two segments of one section: the stepped modes' solver (frequency equation, Brent) against the
    uniform bar's cosines, through every SI figure of the hydraulic preset's orbits."""
    h0 = P.preset("hydraulic-drill")
    h1 = P.Hammer.from_config(_split(P.PRESETS["hydraulic-drill"]))
    assert isinstance(h1.bar, SteppedBar) and h1.model.piston is not None
    assert h1.damping_ratio == pytest.approx(h0.damping_ratio, rel=1e-12)
    o0, o1 = P.orbits(h0), P.orbits(h1)
    assert len(o0) == len(o1) == 2
    for a, b in zip(o0, o1, strict=True):
        for k in ("impact_energy_J", "peak_piston_stress_Pa", "rod_energy_J", "peak_rod_stress_Pa",
                  "efficiency", "rod_advance_m"):
            assert _close(getattr(a, k), getattr(b, k), 1e-9), k
        assert a.orbit.admissible == b.orbit.admissible


def test_stepped_hammers_rod_figures_from_its_velocity_field():
    """Under eq. 10 the rod takes ``(1 - R^2)`` of the piston's kinetic energy, here integrated along
    the stepped piston with scipy's quad from the velocity field (not the modal weights), and the
    rod end advances by the stop's impulse ``(1 + R) m v_0`` over ``rho c A_s``."""
    cfg = copy.deepcopy(P.PRESETS["hydraulic-drill"])
    cfg["bar"]["length"], cfg["bar"]["diameter"] = ["120 mm", "330 mm"], ["56 mm", "45 mm"]
    cfg["model"] = {"n_modes": 8}
    h = P.Hammer.from_config(cfg)
    model, sc, b = h.model, h.scales, h.bar
    mu = model.piston.mass_per_length
    edges = np.concatenate(([0.0], np.cumsum(model.piston.lengths)))
    found = P.orbits(h)
    assert found
    for o in found:
        M = model.n_modes + 1
        v = o.orbit.state_before_impact[M:]

        def ke(x, j, v=v):
            return 0.5 * mu[j] * float(model.shape_functions(np.array([x]))[0] @ v) ** 2

        kinetic = sum(quad(ke, edges[j], edges[j + 1], args=(j,), epsabs=0, epsrel=1e-13)[0]
                      for j in range(2))
        assert o.rod_energy_J == pytest.approx((1 - h.R**2) * kinetic * sc.force_N * sc.length_m, rel=1e-10)
        impulse = (1 + h.R) * b.mass_kg * v[0] * sc.velocity_m_s
        z_stop = b.density_kg_m3 * b.wave_speed_m_s * h.stop_area_m2
        assert o.rod_advance_m == pytest.approx(impulse / z_stop, rel=1e-12)
        assert 0 < o.efficiency <= 1


def test_damping_ratio_of_a_stepped_piston_uses_its_first_mode():
    cfg = copy.deepcopy(P.PRESETS["hydraulic-drill"])
    cfg["bar"]["length"], cfg["bar"]["diameter"] = ["120 mm", "330 mm"], ["56 mm", "45 mm"]
    cfg["damping"] = {"ratio": 0.01}
    h = P.Hammer.from_config(cfg)
    assert h.damping_ratio == pytest.approx(0.01, rel=1e-13)
    # d = 2 zeta w_1 with w_1 = s k_1 the model's first flexible frequency
    assert h.d == pytest.approx(2 * 0.01 * h.model.frequencies[1], rel=1e-13)
    assert h.to_dict()["segments"]["lengths_m"] == pytest.approx([0.12, 0.33], rel=1e-15)


def test_equal_sections_under_the_wave_law_give_the_uniform_hammers_orbit():
    """Under the wave law a stepped piston's contact is the exact blow on the long rod
    (impactbar.laws.rodrock.longrod); cut into two segments of one section it is the uniform piston,
    whose contact the wave law's own characteristics solve: the stable-or-not orbit both find has the
    same phase, impact velocity, rod energy, efficiency and advance (1e-9), and the peak rod stress
    within the wave law's own estimate of its truncation error (theory §4c)."""
    cfg = copy.deepcopy(P.PRESETS["hydraulic-drill"])
    cfg["model"] = {"impact": "wave", "n_modes": 4}
    uniform = P.Hammer.from_config(cfg)
    stepped = P.Hammer.from_config(_split(cfg))
    assert type(stepped.model.law).__name__ == "SteppedLongRod"
    ref = {round(o.phase_rad, 6): o for o in P.orbits(uniform)}
    found = P.orbits(stepped)
    assert found
    for o in found:
        u = ref[round(o.phase_rad, 6)]
        for name in ("phase_rad", "impact_velocity_m_s", "rod_energy_J", "efficiency", "rod_advance_m"):
            assert getattr(o, name) == pytest.approx(getattr(u, name), rel=1e-9)
        err = u.orbit.impact.peak_force_error / u.orbit.impact.peak_force
        assert o.peak_rod_stress_Pa == pytest.approx(u.peak_rod_stress_Pa, rel=max(err, 1e-9))


def test_equal_sections_on_a_drill_string_give_the_uniform_hammers_blows():
    """A stepped piston on a drill string (the rod-rock law, theory §4d, §12): cut into two segments
    of one section it is the uniform piston, so the rod's impedances (relative to the piston's mean)
    and a simulated run's blows are the uniform hammer's; a heavier head changes them."""
    cfg = copy.deepcopy(P.PRESETS["hydraulic-drill"])
    cfg["model"] = {"n_modes": 4}
    # a rod of two piston lengths: both pistons' blows on the same grid of 8 cells a piston
    cfg["rod"] = {"segments": [{"length": "900 mm", "diameter": "45 mm"}]}
    cfg["rock"] = {"k": "400 kN/mm", "k_u": "4000 kN/mm"}
    h0, h1 = P.Hammer.from_config(cfg), P.Hammer.from_config(_split(cfg, 0.5))
    assert h1.model.piston is not None and h1.model.law.segments[0].impedance == pytest.approx(
        h0.model.law.segments[0].impedance, rel=1e-14)
    r0, r1 = P.simulate(h0, periods=6), P.simulate(h1, periods=6)
    v0, v1 = r0.trajectory.impact_velocities, r1.trajectory.impact_velocities
    assert v0.size == v1.size >= 5
    np.testing.assert_allclose(v1, v0, rtol=1e-9)
    heavy = _split(cfg, 0.5)
    heavy["bar"]["diameter"] = [heavy["bar"]["diameter"][0], "60 mm"]
    heavy["stop"] = {"restitution": 0.0}  # (the rod replaces the stop)
    r2 = P.simulate(P.Hammer.from_config(heavy), periods=6)
    assert abs(r2.trajectory.impact_velocities[-1] - v0[-1]) > 1e-3 * v0[-1]


def test_from_dimensionless_needs_the_models_piston():
    h = P.Hammer.from_config(_split(P.PRESETS["hydraulic-drill"]))
    back = P.Hammer.from_dimensionless(h.model, h.load, h.bar, stop_area_m2=h.stop_area_m2)
    assert back.model == h.model
    with pytest.raises(ValueError, match="the model's piston"):
        P.Hammer.from_dimensionless(dataclasses.replace(h.model, piston=None), h.load, h.bar)


# -- the drifters ----------------------------------------------------------------------------------
def test_equal_sections_give_the_uniform_drifters_orbit():
    cfg = copy.deepcopy(P.DRIFTER_PRESETS["hydraulic-drifter"])
    cfg["model"] = {"n_modes": 4}
    o0, o1 = P.Drifter.from_config(cfg).orbit(), P.Drifter.from_config(_split(cfg)).orbit()
    for k in ("period_s", "impact_velocity_m_s", "impact_energy_J"):
        assert _close(getattr(o0, k), getattr(o1, k), 1e-9), k


def test_equal_sections_give_the_uniform_circuit_drifters_operating_point():
    """With one flexible mode (the preset's piston is rigid, where a shape cannot matter): the stepped
    piston's modal data in the circuit's compiled kernel, each orbit from its own default start."""
    cfg = copy.deepcopy(P.CIRCUIT_PRESETS["circuit-drifter"])
    cfg["model"] = {"n_modes": 1}
    d0, d1 = P.CircuitDrifter.from_config(cfg), P.CircuitDrifter.from_config(_split(cfg))
    assert d1.model().piston is not None and d1.model().n_modes == 1
    o0 = d0.orbit()
    o1 = d1.orbit()
    for k in ("period_s", "impact_velocity_m_s", "mean_supply_pressure_Pa"):
        assert _close(getattr(o0, k), getattr(o1, k), 1e-8), k
    np.testing.assert_allclose(o1.orbit.multipliers, o0.orbit.multipliers, rtol=1e-6, atol=1e-8)
    assert repr(o1).startswith("CircuitDrifterOrbit(circuit-drifter: ") and len(repr(o1)) < 120
    assert f"mean supply {o1.mean_supply_pressure_Pa / 1e6:.4g} MPa" in repr(o1)


def test_the_stepped_drifter_example(capsys):
    """``examples/stepped_drifter.toml``: the preset drifter's mass and length within 1 g, its model the
    stepped piston of the file's numbers, an admissible orbit; ``impactbar orbits`` prints the segments."""
    from impactbar.cli import main

    with open(EXAMPLE, "rb") as fh:
        d = P.Drifter.from_config(tomllib.load(fh))
    ref = P.drifter_preset("hydraulic-drifter")
    assert d.bar.mass_kg == pytest.approx(ref.bar.mass_kg, abs=1e-3)
    assert d.bar.length_m == pytest.approx(ref.bar.length_m, rel=1e-14)
    om = math.sqrt(20e6 * 2.8e-4 / (d.bar.mass_kg * d.bar.length_m))
    model = d.model()
    assert model.s == pytest.approx(math.sqrt(2.1e11 / 7850) / (d.bar.length_m * om), rel=1e-13)
    ref_shape = SteppedPiston([150.0, 298.54236], [56.0**2, 38.3**2])
    np.testing.assert_allclose(model.piston.lengths, ref_shape.lengths, rtol=1e-14)
    np.testing.assert_allclose(model.piston.impedances, ref_shape.impedances, rtol=1e-14)
    o = d.orbit()
    assert o.orbit.admissible
    assert repr(o) == (f"DrifterOrbit(stepped-drifter: {o.blow_frequency_Hz:.4g} Hz, impact "
                       f"{o.impact_velocity_m_s:.4g} m/s, {o.impact_energy_J:.4g} J, stable)")
    assert main(["orbits", str(EXAMPLE)]) == 0
    out = capsys.readouterr().out
    assert "2 segments (150 mm x 24.63 cm^2 + 298.5 mm x 11.52 cm^2)" in out
    assert f"impact velocity {o.impact_velocity_m_s:.4g} m/s" in out
