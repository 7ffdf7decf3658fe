"""The laminar leak, the cushion and the check valve as kinds of a drifter's config
(``[parts.<name>]`` with ``kind = "laminar_leak"``, ``"cushion"``, ``"check_valve"``;
``impactbar.physical.circuit_parts``).

- Each table builds the Python API's part with the dimensionless values its SI values and the
  drifter's scales give (m^3/s/Pa over the relief coefficient's scale ``P / Q``, m^3/s/Pa^0.5 over
  the orifice's ``sqrt(P) / Q``, pressures over ``P = 10 MPa``, volumes over ``A_r L``, gaps over
  the bar's length), and the orbit of the built drifter is that part's orbit to the bit.
- Its keys ``parts.<name>.<field>`` through ``with_values`` and the optimiser's variables
  (``design_bounds``: each bound built) and ``impactbar optimize --vary`` (three designs).
- A value out of range refused in one line naming ``parts.<name>.<field>``.
"""

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from impactbar import find_orbit
from impactbar.drives.circuit import CheckValve, Cushion, LaminarLeak
from impactbar.physical import build, circuit_preset, read_config, with_values
from impactbar.physical.design_keys import design_bounds

P = 1.0e7  # (the pressure scale, Pa)
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

TABLES = {
    "laminar_leak": {"kind": "laminar_leak", "source": "rear", "target": "front",
                     "conductance": "6e-12 m^3/s/Pa"},
    "cushion": {"kind": "cushion", "volume": "1.25e-5 m^3", "coefficient": "7.5e-6 m^3/s/Pa^0.5",
                "gaps": ["0.027 m", "0.036 m", "0.045 m"], "openings": [1.0, 0.4, 0.1]},
    "check_valve": {"kind": "check_valve", "source": "front", "target": "supply",
                    "coefficient": "3.75e-6 m^3/s/Pa^0.5", "cracking_pressure": "50000 Pa",
                    "opening_span": "50000 Pa"},
}


def _python_part(kind, d):
    """The Python API's part, its values made dimensionless here with the drifter's scales, each as
    its scale's steps are written (a division by a scale, not a product by its inverse)."""
    orifice = math.sqrt(P) / d.flow_scale_m3_s
    if kind == "laminar_leak":
        return LaminarLeak("rear", "front", conductance=6e-12 * P / d.flow_scale_m3_s, name="p")
    if kind == "cushion":
        return Cushion(volume=1.25e-5 / d.volume_scale_m3, coefficient=7.5e-6 * orifice,
                       gaps=tuple(y / d.bar.length_m for y in (0.027, 0.036, 0.045)),
                       openings=(1.0, 0.4, 0.1), name="p")
    return CheckValve("front", "supply", coefficient=3.75e-6 * orifice, cracking_pressure=50000.0 / P,
                      opening_span=50000.0 / P, name="p")


def _config(kind, **changes):
    cfg = read_config("circuit-drifter")[0]
    cfg["parts"] = {"p": {**TABLES[kind], **changes}}
    return cfg


@pytest.mark.parametrize("kind", list(TABLES))
def test_a_kind_s_table_builds_the_python_part_and_its_orbit_to_the_bit(kind):
    d = build(_config(kind))
    want = _python_part(kind, d)
    (got,) = d.drive().extra_parts
    assert got == want
    model = d.model().with_(n_modes=0)
    a = find_orbit(model, d.drive())
    b = find_orbit(model, dataclasses.replace(circuit_preset("circuit-drifter").drive(), extra_parts=(want,)))
    assert a.period == b.period and a.impact_velocity == b.impact_velocity
    assert np.array_equal(a.drive_states[0], b.drive_states[0])
    assert a.period != find_orbit(model, circuit_preset("circuit-drifter").drive()).period  # (it acts)


KEYS = [("laminar_leak", "conductance", "1.2e-11 m^3/s/Pa", 1.2e-11),
        ("cushion", "volume", "2e-5 m^3", 2e-5),
        ("cushion", "coefficient", "1e-5 m^3/s/Pa^0.5", 1e-5),
        ("check_valve", "coefficient", "2e-6 m^3/s/Pa^0.5", 2e-6),
        ("check_valve", "cracking_pressure", "0.1 MPa", 1e5),
        ("check_valve", "opening_span", "0.2 MPa", 2e5)]


@pytest.mark.parametrize(("kind", "field", "value", "si"), KEYS)
def test_with_values_sets_a_kind_s_key(kind, field, value, si):
    key = f"parts.p.{field}"
    d = build(with_values(_config(kind), {key: value}))
    assert dict(d.parts[0].values)[field] == pytest.approx(si, rel=1e-15)
    assert d.drive().value(f"p.{field}") == d.to_dimensionless(key, value)[1]  # (one conversion, to the bit)


def test_with_values_sets_a_cushion_s_lists():
    changes = {"parts.p.gaps": ["20 mm", "40 mm"], "parts.p.openings": [1, 0.5]}
    d = build(with_values(_config("cushion"), changes))
    (part,) = d.drive().extra_parts
    assert part.gaps == pytest.approx((0.02 / d.bar.length_m, 0.04 / d.bar.length_m), rel=1e-15)
    assert part.openings == (1.0, 0.5)


@pytest.mark.parametrize(("kind", "field", "low", "high"),
                         [("laminar_leak", "conductance", "3e-12 m^3/s/Pa", "1e-11 m^3/s/Pa"),
                          ("cushion", "volume", "1e-5 m^3", "2e-5 m^3"),
                          ("check_valve", "cracking_pressure", "0.02 MPa", "0.1 MPa")])
def test_the_optimiser_takes_a_kind_s_key_as_a_variable(kind, field, low, high):
    key = f"parts.p.{field}"
    bounds = design_bounds(_config(kind), {key: (low, high)})
    assert bounds[key]["start"] == dict(build(_config(kind)).parts[0].values)[field]
    assert bounds[key]["low"] < bounds[key]["start"] < bounds[key]["high"]


def test_impactbar_optimize_varies_a_check_valve_s_key(tmp_path, capsys):
    from impactbar.cli import main

    cfg, out = tmp_path / "d.toml", tmp_path / "r.json"
    table = "".join(f"{k} = {json.dumps(v)}\n" for k, v in TABLES["check_valve"].items())
    cfg.write_text((EXAMPLES / "circuit_drifter.toml").read_text() + f"\n[parts.p]\n{table}")
    argv = ["optimize", str(cfg), "--vary", "parts.p.cracking_pressure=0.02MPa:0.1MPa", "--objective",
            "impact_power", "--max-evaluations", "3", "--quiet", "--out", str(out)]
    assert main(argv) == 0
    doc = json.loads(out.read_text())
    assert 2e4 <= doc["optimum"]["values"]["parts.p.cracking_pressure"] <= 1e5


BAD = [("laminar_leak", {"conductance": "-1e-12 m^3/s/Pa"}, r"parts.p.conductance must be in \[0, inf\)"),
       ("laminar_leak", {"conductance": "1e-12 m^3/s/Pa^0.5"}, "parts.p.conductance"),
       ("cushion", {"volume": "0 m^3"}, r"parts.p.volume must be in \(0, inf\)"),
       ("cushion", {"openings": [1.0, 1.5, 0.1]}, r"parts.p.openings must be in \[0, 1\]; got 1.5"),
       ("cushion", {"gaps": ["45 mm", "36 mm", "27 mm"]}, "parts.p.gaps must be one or more increasing"),
       ("cushion", {"gaps": "27 mm"}, "parts.p.gaps must be a list"),
       ("check_valve", {"opening_span": "0 Pa"}, r"parts.p.opening_span must be in \(0, inf\)"),
       ("check_valve", {"cracking_pressure": "-1 Pa"}, r"parts.p.cracking_pressure must be in \[0, inf\)"),
       ("check_valve", {"target": "front"}, "parts.p.target must be another node")]


@pytest.mark.parametrize(("kind", "change", "message"), BAD)
def test_a_bad_value_is_refused_in_one_line_naming_its_key(kind, change, message):
    with pytest.raises(ValueError, match=message) as info:
        build(_config(kind, **change))
    assert "\n" not in str(info.value)
