"""``operating_point_sensitivities``: the implicit function theorem's derivatives of the rigid circuit
drifter's operating point against central differences of fresh orbits (each solved from rest, no
shared state with the derivatives but the config), the first-order distance to the relief border
against the border the flights meet, and the bad inputs one line each."""

from __future__ import annotations

import json

import pytest

from impactbar.physical import build, operating_point_sensitivities, read_config, with_values
from impactbar.physical.sensitivity import RESIDUAL_STEP, _figures

pytest.importorskip("pint")

#: The relative error of a fresh orbit's figures: Newton stops at steps of 10 rtol = 1e-9 of the
#: circuit's integrator; a fresh orbit and one continued from a neighbour differ by up to 2.3e-9 of
#: each figure on the preset. With four times that, the central difference of two fresh orbits at
#: p +- h carries up to NOISE |F| / h of noise; the truncation, O(h^2) = 1e-6 relative at
#: h = 1e-3 |p|, gets TRUNCATION. (Measured: the differences are at most 2.4e-9 |F| / h.)
NOISE = 1e-8
TRUNCATION = 1e-5


@pytest.fixture(scope="module")
def preset():
    cfg, _ = read_config("circuit-drifter")
    return cfg, build(cfg).orbit()


@pytest.mark.parametrize("key, unit, value", [("accumulator.precharge", "Pa", 10e6),
                                              ("valve.switch_out", "m", 21.5e-3),
                                              ("chambers.rear_volume", "m**3", 1e-4)])
def test_derivatives_match_central_differences_of_fresh_orbits(preset, key, unit, value):
    cfg, orbit = preset
    s = operating_point_sensitivities(cfg, [key], orbit=orbit)
    assert s.values[key] == pytest.approx(value, rel=1e-14)
    h = RESIDUAL_STEP * value
    assert s.steps[key] == pytest.approx(h, rel=1e-14)
    plus, minus = (_figures(build(with_values(cfg, {key: f"{value + sign * h!r} {unit}"})).orbit())
                   for sign in (1.0, -1.0))
    assert set(plus) == set(s.derivatives)
    for name, F in s.figures.items():
        cd = (plus[name] - minus[name]) / (2.0 * h)
        tol = TRUNCATION * abs(cd) + NOISE * abs(F) / h
        assert abs(s.derivatives[name][key] - cd) <= tol, (name, s.derivatives[name][key], cd, tol)


def test_figures_and_state_are_the_orbits(preset):
    cfg, orbit = preset
    s = operating_point_sensitivities(cfg, ["valve.switch_out", "accumulator.precharge"], orbit=orbit)
    assert s.figures["blow_frequency_Hz"] == orbit.blow_frequency_Hz
    assert s.figures["mean_supply_pressure_Pa"] == orbit.mean_supply_pressure_Pa
    assert s.state.shape == (6, 2)
    assert s.flights == 8
    # the valve's opening at the impact is 1 whatever the key: its derivative vanishes
    assert abs(s.state[5, 0]) < 1e-12
    # a longer stroke, a slower blow; the elasticity of the frequency about -0.47 (the table's)
    assert s.elasticities()["blow_frequency_Hz"]["valve.switch_out"] == pytest.approx(-0.4688, abs=2e-3)
    table = s.table()
    assert "valve.switch_out" in table
    # every row: its name (one word: the borders' too, "accumulator_margin_Pa"), the value, a derivative a key
    assert all(len(row.split()) == 2 + len(s.keys) for row in table.splitlines()[1:]), table
    assert "accumulator_margin_Pa" in table


def test_relief_border_is_met_where_its_first_order_distance_says(preset):
    """The relief valve starts opening at about 75.5 L/min (the design map's edge between 70 and 75
    L/min up to 7.2 MPa of pre-charge, 75 to 80 above): a step to 0.8 of the predicted distance is
    still smooth, one to 1.2 of it crosses the border and is refused."""
    cfg, orbit = preset
    key = "supply.pump_flow"
    s = operating_point_sensitivities(cfg, [key], orbit=orbit)
    dist = s.distance_to_border()["relief"][key]
    assert 4.5 / 6e4 < dist < 6.5 / 6e4
    assert s.distance_to_border()["accumulator"][key] < 0.0  # more flow raises the least supply pressure
    fraction = dist / s.values[key]
    operating_point_sensitivities(cfg, [key], orbit=orbit, relative_step=0.8 * fraction)
    with pytest.raises(ValueError, match=r"^supply.pump_flow does not enter smoothly here: .*relief"):
        operating_point_sensitivities(cfg, [key], orbit=orbit, relative_step=1.2 * fraction)


def test_the_distance_to_a_border_reads_in_the_unit_the_config_wrote(preset):
    """``distance_to_border()`` gave only SI (``7.9e-05`` m^3/s for some 4.7 L/min); ``shown=True``
    gives it in the config's unit of each key (``"70 L/min"``: L/min), else the display unit."""
    import dataclasses

    cfg, orbit = preset
    keys = ["supply.pump_flow", "accumulator.precharge"]
    s = operating_point_sensitivities(cfg, keys, orbit=orbit)
    si, shown = s.distance_to_border(), s.distance_to_border(shown=True)
    flow, pre = si["relief"]["supply.pump_flow"], si["accumulator"]["accumulator.precharge"]
    assert 4.5 < flow * 6e4 < 6.5
    assert shown["relief"]["supply.pump_flow"] == f"{flow * 6e4:+.4g} L/min"
    assert shown["accumulator"]["accumulator.precharge"] == f"{pre / 1e6:+.4g} MPa"
    # a config in other units: the figures in those units (bar, L/s), the same distances
    wrote = with_values(cfg, {"supply.pump_flow": "1.1666666666666667 L/s",
                              "accumulator.precharge": "100 bar"})
    other = dataclasses.replace(s, config=wrote).distance_to_border(shown=True)
    assert other["relief"]["supply.pump_flow"] == f"{flow * 1e3:+.4g} L/s"
    assert other["accumulator"]["accumulator.precharge"] == f"{pre / 1e5:+.4g} bar"


@pytest.mark.parametrize("keys, kwargs, message", [
    (["valve.switch_in"], {}, r"valve.switch_in is not given in the config"),
    (["oil.colour"], {}, r"not a parameter the optimiser varies"),
    ("valve.switch_out", {}, r"keys must be a non-empty sequence"),
    (["valve.switch_out", "valve.switch_out"], {}, r"keys must be distinct"),
    (["valve.switch_out"], {"relative_step": 0.5}, r"relative_step must be in \(0, 0.1\]"),
    (["accumulator.precharge"], {"relative_step": 0.1, "config": {"accumulator": {"precharge": "24 MPa"}}},
     r"accumulator.precharge at .* is out of its range"),
])
def test_bad_inputs_one_line_each(preset, keys, kwargs, message):
    cfg, orbit = preset
    changes = kwargs.pop("config", None)
    if changes is not None:
        cfg = with_values(cfg, {f"{sec}.{k}": v for sec, d in changes.items() for k, v in d.items()})
        orbit = None
    with pytest.raises(ValueError, match=message) as err:
        operating_point_sensitivities(cfg, keys, orbit=orbit, **kwargs)
    assert "\n" not in str(err.value)


def test_an_orbit_of_another_design_is_refused(preset):
    cfg, orbit = preset
    with pytest.raises(ValueError, match="orbit must be the config's own operating point"):
        operating_point_sensitivities(with_values(cfg, {"valve.switch_out": "22 mm"}), ["valve.switch_out"],
                                      orbit=orbit)


def test_without_multipliers_the_same_derivatives_less_the_multipliers(preset):
    cfg, orbit = preset
    keys = ["valve.switch_out", "accumulator.precharge"]
    full = operating_point_sensitivities(cfg, keys, orbit=orbit)
    part = operating_point_sensitivities(cfg, keys, orbit=orbit, multipliers=False)
    assert set(full.figures) - set(part.figures) == {"max_multiplier"}
    for name, F in part.figures.items():
        for key in keys:  # the figures read off plain flights instead of variational ones: their noise
            tol = NOISE * abs(F) / full.steps[key]
            assert abs(part.derivatives[name][key] - full.derivatives[name][key]) <= tol, (name, key)


def test_slsqp_with_these_gradients_reaches_an_optimum_that_fresh_orbits_confirm():
    """Impact power over the switch point and the rear chamber's volume: SLSQP stops at the switch
    point's upper bound and a rear volume whose neighbours 3 % either side, each a fresh orbit, give
    less power (by 1.6e-4 kW of 13.2 kW: the objective is flat there; COBYLA's optimum lies 0.1 %
    away), after fewer designs than COBYLA needs (7 against 19; benchmarks/bench_optimize_slsqp.py)."""
    from impactbar.physical import optimize_drifter

    vary = {"valve.switch_out": ("20 mm", "23 mm"), "chambers.rear_volume": ("0.06 L", "0.2 L")}
    res = optimize_drifter("circuit-drifter", vary, objective="impact_power", method="slsqp", progress=False)
    assert res.gradients >= 1 and res.evaluations <= 10
    assert res.gain > 0.02
    values = res.optimum["values"]
    assert values["valve.switch_out"] == pytest.approx(23e-3, rel=1e-9)
    best = res.optimum["objectives"]["impact_power_kW"]
    cfg = res.config
    for factor in (0.97, 1.03):
        volume = values["chambers.rear_volume"] * factor
        near = build(with_values(cfg, {"chambers.rear_volume": f"{volume!r} m**3"})).orbit()
        assert near.impact_power_kW < best, (factor, near.impact_power_kW - best)
    inside = build(with_values(cfg, {"valve.switch_out": "22.9 mm"})).orbit()
    assert inside.impact_power_kW < best


def test_optimize_drifter_refuses_an_unknown_method():
    from impactbar.physical import optimize_drifter

    with pytest.raises(ValueError,
                       match=r"^method must be 'cobyla', 'slsqp', 'differential_evolution' or 'multistart'; "
                       r"got 'bfgs'$"):
        optimize_drifter("circuit-drifter", {"valve.switch_out": ("20 mm", "23 mm")},
                         objective="impact_power", method="bfgs")


def test_cli_optimize_with_slsqp_counts_its_gradients(tmp_path, capsys):
    from impactbar.cli import main

    out = tmp_path / "result.json"
    assert main(["optimize", "circuit-drifter", "--vary", "valve.switch_out=20mm:23 mm", "--objective",
                 "impact_power", "--method", "slsqp", "--max-evaluations", "3", "--quiet", "--out",
                 str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["gradients"] >= 1 and doc["gain"] > 0.0
    assert "gradients" in capsys.readouterr().out


@pytest.mark.slow
def test_flexible_piston_derivatives_match_central_differences_to_half_a_per_cent():
    """Two modes: the end's velocity at impact rings with them, so the default step is
    FLEXIBLE_STEP (3e-4) and the derivatives are good to about half a per cent (measured: 0.49 %
    for the impact velocity by the switch point, against central differences of continued orbits at
    the same step); 1 % allowed, besides the orbits' noise."""
    from impactbar.physical.sensitivity import FLEXIBLE_STEP

    cfg = with_values(read_config("circuit-drifter")[0], {"model.n_modes": 2})
    orbit = build(cfg).orbit()
    keys = {"valve.switch_out": "m", "chambers.rear_volume": "m**3"}
    s = operating_point_sensitivities(cfg, list(keys), orbit=orbit)
    for key, unit in keys.items():
        p, h = s.values[key], s.steps[key]
        assert h == pytest.approx(FLEXIBLE_STEP * p, rel=1e-14)
        plus, minus = (_figures(build(with_values(cfg, {key: f"{p + sign * h!r} {unit}"})).orbit(guess=orbit))
                       for sign in (1.0, -1.0))
        for name, F in s.figures.items():
            cd = (plus[name] - minus[name]) / (2.0 * h)
            tol = 1e-2 * abs(cd) + NOISE * abs(F) / h
            assert abs(s.derivatives[name][key] - cd) <= tol, (key, name, s.derivatives[name][key], cd)


def test_the_gradients_slsqp_receives_match_central_differences_of_what_it_evaluates(monkeypatch):
    """What SLSQP is handed at the start, the objective's gradient and the constraints' Jacobian in
    the variables scaled by their bounds (the objective over the start's, its sign flipped), against
    central differences (a step of 1e-3 of each span either side) of the objective and the
    constraints SLSQP evaluates there: each design a new orbit of a design built by ``with_values``.
    (On the example rock drifter they agree to 4e-4 relative; its SLSQP searches stall on a border
    of the blow, not on its gradients: benchmarks/HISTORY.md.)"""
    import types

    import numpy as np
    import scipy.optimize

    from impactbar.physical import optimize_drifter

    seen = {}

    def capture(fun, x0, jac=None, constraints=(), **kwargs):
        x0 = np.asarray(x0, dtype=float)
        g, dg = constraints[0]["fun"], constraints[0]["jac"]
        seen.update(jac=jac(x0), cjac=dg(x0))
        du = 1e-3
        cd_f, cd_g = [], []
        for j in range(x0.size):
            e = np.zeros(x0.size)
            e[j] = du
            cd_f.append((fun(x0 + e) - fun(x0 - e)) / (2.0 * du))
            cd_g.append((g(x0 + e) - g(x0 - e)) / (2.0 * du))
        seen.update(cd_f=np.array(cd_f), cd_g=np.array(cd_g).T, x0=x0)
        return types.SimpleNamespace(message="captured", x=x0)

    monkeypatch.setattr(scipy.optimize, "minimize", capture)
    vary = {"valve.switch_out": ("20 mm", "23 mm"), "chambers.rear_volume": ("0.06 L", "0.2 L")}
    optimize_drifter("circuit-drifter", vary, objective="impact_power", method="slsqp", progress=False)
    assert np.all((seen["x0"] > 0.01) & (seen["x0"] < 0.99))  # both sides of each step inside the bounds
    assert seen["jac"].shape == seen["cd_f"].shape and seen["cjac"].shape == seen["cd_g"].shape
    assert np.max(np.abs(seen["cd_f"])) > 1e-2  # the objective moves: its sign and scale are checked
    for got, want in ((seen["jac"], seen["cd_f"]), (seen["cjac"], seen["cd_g"])):
        # (the largest multiplier's modulus by the rear volume agrees to 1.1e-3; the others to 1e-4)
        assert np.allclose(got, want, rtol=3e-3, atol=1e-4 * np.max(np.abs(want))), (got, want)


def test_a_circuit_drifter_gives_its_configs_numbers():
    """The :class:`CircuitDrifter` that ``continue_circuit`` takes is accepted as the config it was
    read from, with the same numbers to the bit; one changed after it was read is refused."""
    import dataclasses

    from impactbar.physical.circuit import circuit_preset

    keys = ["valve.switch_out", "supply.pump_flow"]
    drifter = circuit_preset("circuit-drifter")
    a = operating_point_sensitivities("circuit-drifter", keys, multipliers=False)
    b = operating_point_sensitivities(drifter, keys, multipliers=False)
    assert a.figures == b.figures and a.derivatives == b.derivatives and a.steps == b.steps
    assert a.derivatives["blow_frequency_Hz"]["valve.switch_out"] != 0.0
    changed = dataclasses.replace(drifter, n_modes=2)
    with pytest.raises(ValueError, match="changed after"):
        operating_point_sensitivities(changed, keys)
