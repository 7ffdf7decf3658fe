"""Parts added to a drifter's oil circuit by its configuration (``[parts.<name>]``,
``impactbar.physical.circuit_parts``; theory §13).

- A return line with a large low-pressure accumulator and a wide orifice to the tank tends to the
  preset's orbit, at first order in ``1/K_ret`` (measured: 6.4e-6, 1.8e-6, 4.7e-7 at K_ret = 5.12e-3,
  2.05e-2, 8.19e-2 m^3/s/Pa^0.5, orders 0.90 and 0.98).
- The preset with a leak of coefficient 0 gives today's orbit.
- The example's orbit repeats under ``simulate`` restarted from it over 20 periods; its energy account
  closes, the return line's oil and gas terms (functions of its pressure) vanishing over the period.
- Its keys ``parts.<name>.<field>`` through ``with_values``, a design map, continuation and
  ``impactbar optimize --vary``.
- A kind registered with one line; the configuration's mistakes refused in one line naming the key.
"""

import copy
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from impactbar import InitialState, simulate
from impactbar.drives.circuit import Leak
from impactbar.physical import (
    build,
    circuit_preset,
    continue_circuit,
    load,
    read_config,
    register_part,
    with_values,
)

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter_return_line.toml"
K_UNIT = "m^3/s/Pa^0.5"


def _with_parts(**tables):
    cfg = read_config("circuit-drifter")[0]
    cfg["parts"] = tables
    return cfg


def _return_line(K):
    """A large accumulator (2 L of gas, pre-charged below the tank's pressure) on a short line."""
    return {"kind": "return_accumulator", "volume": "0.05 L", "flow_coefficient": f"{K!r} {K_UNIT}",
            "precharge": "0.1 MPa", "gas_volume": "2 L"}


@pytest.fixture(scope="module")
def preset():
    return circuit_preset("circuit-drifter").orbit()


@pytest.fixture(scope="module")
def example():
    return load(EXAMPLE).orbit()


def _apart(o, base):
    return max(abs(o.period_s / base.period_s - 1), abs(o.impact_velocity_m_s / base.impact_velocity_m_s - 1),
               *(abs(o.pressures_at_impact_Pa[k] / v - 1) for k, v in base.pressures_at_impact_Pa.items()))


def test_a_large_return_accumulator_on_a_short_line_tends_to_the_preset(preset):
    err = [_apart(build(_with_parts(line=_return_line(K))).orbit(), preset)
           for K in (5.12e-3, 2.048e-2, 8.192e-2)]
    orders = [math.log(a / b) / math.log(4.0) for a, b in zip(err, err[1:], strict=False)]
    assert err[-1] < 1e-6
    assert all(0.8 < q < 1.2 for q in orders), (err, orders)  # (first order in 1/K_ret)


def test_a_part_whose_effect_vanishes_gives_todays_orbit(preset):
    d = build(_with_parts(seal=dict(kind="leak", source="rear", target="front",
                                    flow_coefficient=f"0 {K_UNIT}")))
    assert d.drive().extra_parts == (Leak(0.0, "rear", "front", name="seal"),)
    o = d.orbit()
    assert _apart(o, preset) < 1e-9  # (measured 3e-10: another generated code, the same equations)
    assert o.orbit.drive.layout.energies[-1] == "seal"


def _restart(orbit, periods):
    z, y = orbit.drive_states[0], np.asarray(orbit.states_after_impact[0])
    M = orbit.model.n_modes + 1
    drive = dataclasses.replace(orbit.drive, start_pressures=tuple(z))
    return simulate(orbit.model, drive, InitialState(y[:M], y[M:]), periods * orbit.period)


def test_the_example_s_orbit_repeats_and_its_account_closes(example):
    o = example.orbit
    assert o.drive.layout.states == ("front", "rear", "supply", "return_line", "spool")
    # the line's least pressure over the period, among the oil's: at its least the line's inflow (from
    # the rear chamber, above it) is its outflow to the tank, so it lies between the two
    least = example.minimum_pressures_Pa
    assert set(least) == {"front", "rear", "supply", "return_line"}
    assert 0.3e6 < least["return_line"] < least["rear"] and not example.cavitates
    run = _restart(o, 20.5)
    assert run.n_impacts == 20
    assert np.allclose(np.diff(run.impact_times), o.period, rtol=1e-6, atol=0.0)
    assert np.allclose(run.impact_velocities, o.impact_velocity, rtol=1e-6, atol=0.0)
    one = _restart(o, 1.0)
    total = sum(p.energies() for p in one.pieces if hasattr(p, "energies"))
    at = o.drive.layout.energy
    pump = total[at["pump"]]
    acc = o.drive.energy(one)
    balance = acc["piston"] + acc["orifices"] + acc["tank"] + acc["compression"] + acc["accumulator"]
    assert abs(balance - acc["pump"]) < 1e-8 * pump
    # the line's oil (a fixed volume) and its gas: work that is a function of the line's pressure,
    # nothing over a period of the orbit
    assert abs(total[at["return_line"]]) < 1e-8 * pump
    assert abs(total[at["return_line.gas"]]) < 1e-8 * pump
    assert total[at["seal_leak"]] > 0.0  # (the seal's loss, in the orifices' term)
    assert acc["orifices"] == pytest.approx(total[at["orifices"]] + total[at["seal_leak"]], rel=1e-14)


def test_with_values_and_continuation_take_a_part_s_key(example):
    cfg = read_config(EXAMPLE)[0]
    changed = build(with_values(cfg, {"parts.return_line.gas_volume": "0.8 L"}))
    assert dict(changed.parts[0].values)["gas_volume"] == pytest.approx(0.8e-3, rel=1e-15)
    assert changed.drive().value("return_line.gas_volume") == pytest.approx(
        0.8e-3 / changed.volume_scale_m3, rel=1e-15)
    branch = continue_circuit(example.drifter, "parts.return_line.gas_volume", "0.8 L")
    assert branch.unit == "m**3" and branch.values[-1] == pytest.approx(0.8e-3, rel=1e-12)
    assert branch.points[-1].period_s == pytest.approx(changed.orbit().period_s, rel=1e-8)


def test_the_sensitivities_take_a_part_s_key(example):
    """d(blow frequency)/d(gas volume) by the implicit function theorem against a central difference
    of two fresh orbits (1 % either side: the difference's error is second order, some 1e-4)."""
    from impactbar.physical import operating_point_sensitivities

    key = "parts.return_line.gas_volume"
    s = operating_point_sensitivities(EXAMPLE, [key], orbit=example)
    assert s.units[key] == "m**3"
    cfg = read_config(EXAMPLE)[0]
    f = [build(with_values(cfg, {key: f"{v!r} L"})).orbit().blow_frequency_Hz for v in (0.495, 0.505)]
    assert s.derivatives["blow_frequency_Hz"][key] == pytest.approx((f[1] - f[0]) / 0.01e-3, rel=1e-3)


def test_a_design_map_sweeps_a_part_s_key():
    from impactbar.sweeps import parse_spec
    from impactbar.sweeps.map_task import compute_map_chunk, point_values

    cfg = read_config(EXAMPLE)[0]
    values = ["0.3 L", "0.9 L"]
    spec = parse_spec({"task": "operating_point", "config": cfg, "chain": "default",
                           "axes": {"parts.return_line.gas_volume": {"values": values}}})
    assert spec.axes[0].unit == "m**3" and spec.axes[0].values == pytest.approx((3e-4, 9e-4), rel=1e-15)
    got = {}
    for c in range(spec.n_chunks):
        for name, v in compute_map_chunk(spec, c).items():
            got.setdefault(name, []).extend(np.ravel(v))
    for i, value in enumerate(values):
        want = point_values(build(with_values(cfg, {"parts.return_line.gas_volume": value})).orbit(),
                            "circuit", False)
        assert got["blow_frequency"][i] == pytest.approx(want["blow_frequency"], rel=1e-9)
    assert got["blow_frequency"][0] != got["blow_frequency"][1]


def test_impactbar_optimize_varies_a_part_s_key(tmp_path, capsys):
    from impactbar.cli import main

    out = tmp_path / "r.json"
    argv = ["optimize", str(EXAMPLE), "--vary", "parts.return_line.gas_volume=0.3L:1L", "--objective",
            "impact_power", "--max-evaluations", "3", "--quiet", "--out", str(out)]
    assert main(argv) == 0
    assert "parts.return_line.gas_volume" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert 0.3e-3 <= doc["optimum"]["values"]["parts.return_line.gas_volume"] <= 1e-3
    assert doc["baseline"]["changes"] == {"parts.return_line.gas_volume": "0.5 L"}


BAD = [
    ({"kind": "pipe"}, "parts.p.kind must be one of return_accumulator, leak"),
    ({"kind": "leak", "source": "rear", "target": "back", "flow_coefficient": f"1e-8 {K_UNIT}"},
     "parts.p.target must be one of the nodes front, rear, supply, tank; got 'back'"),
    ({"kind": "leak", "source": "rear", "flow_coefficient": f"1e-8 {K_UNIT}"}, "missing key parts.p.target"),
    ({"kind": "leak", "source": "rear", "target": "front", "flow_coefficient": f"-1e-8 {K_UNIT}"},
     r"parts.p.flow_coefficient must be in \[0, inf\); got -1e-08"),
    ({"kind": "leak", "source": "rear", "target": "front", "flow_coefficient": "1e-8"},
     "parts.p.flow_coefficient needs a unit: it must be a flow coefficient"),
    ({"kind": "leak", "source": "rear", "target": "front", "flow_coefficient": f"1e-8 {K_UNIT}", "area": 1},
     "unknown key parts.p.area; a leak takes kind, source, target, flow_coefficient"),
    ({**_return_line(1e-4), "port": "tank"},
     "parts.p.port must be one of the ports valve_return, none; got 'tank'"),
    ({**_return_line(1e-4), "polytropic_exponent": 2.5}, r"parts.p.polytropic_exponent must be in \[1, 2\]"),
]


@pytest.mark.parametrize(("table", "message"), BAD)
def test_a_part_s_mistake_is_refused_in_one_line_naming_its_key(table, message):
    with pytest.raises(ValueError, match=message) as info:
        build(_with_parts(p=table))
    assert "\n" not in str(info.value)


def test_two_parts_taking_one_port_and_a_node_of_another_part():
    with pytest.raises(ValueError, match="parts.b.port: the port valve_return is taken by parts.a already"):
        build(_with_parts(a=_return_line(1e-4), b=_return_line(1e-4)))
    # a leak into the return line's node: another part's node, by its name
    d = build(_with_parts(a=_return_line(1e-4), leak=dict(kind="leak", source="rear", target="a",
                                                          flow_coefficient=f"1e-9 {K_UNIT}")))
    assert d.drive().extra_parts[1].target == "a"
    with pytest.raises(ValueError, match="unknown key parts.a.kind"):
        with_values(copy.deepcopy(d.config), {"parts.a.kind": "leak"})
    with pytest.raises(ValueError, match=r"parts.c.volume: a part's key is parts.<name>.<key>, of a part"):
        with_values(d.config, {"parts.c.volume": "1 L"})


def test_the_docs_list_the_part_kinds_keys():
    from impactbar.physical import circuit_parts

    table = circuit_parts.markdown_table()
    assert "| `parts.<return_accumulator>.gas_volume` | m^3 | volume |" in table
    assert "| `parts.<leak>.flow_coefficient` | m^3/s/Pa^0.5 | orifice |" in table
    assert table in (Path(__file__).resolve().parents[2] / "docs" / "physical.md").read_text()


@dataclasses.dataclass(frozen=True)
class Bypass(Leak):
    """A leak from the supply to the tank by default: a kind of the user's, registered in one line."""

    source: str = "supply"
    target: str = "tank"
    name: str = "bypass"


def test_a_kind_is_registered_in_one_line():
    register_part("bypass", Bypass)
    d = build(_with_parts(by={"kind": "bypass", "flow_coefficient": f"2e-8 {K_UNIT}"}))
    (part,) = d.drive().extra_parts
    assert type(part) is Bypass and (part.source, part.target) == ("supply", "tank")
    assert part.flow_coefficient == pytest.approx(2e-8 * math.sqrt(1e7) / d.flow_scale_m3_s, rel=1e-15)
    with pytest.raises(ValueError, match="kind 'leak' is already the part Leak"):
        register_part("leak", Bypass)
    with pytest.raises(ValueError, match="cls must be a dataclass subclass of CircuitPart"):
        register_part("thing", dict)
