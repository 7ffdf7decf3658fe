"""A parameter added to a circuit part, in this file alone: a part kind written here (a leak whose
orifice a new field ``opening`` throttles), registered in one line, its new field declared once with
its class (:class:`~impactbar.drives.circuit.PartField`). By its dotted SI name
``parts.bleed.opening`` it is set in a configuration, continued, swept in a design map, optimised,
and set from the command line (``impactbar continue`` and ``impactbar optimize --vary``), with no
line elsewhere; each result checked against fresh orbits of the configuration changed by hand."""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import pytest
from config_toml import config_toml

pytest.importorskip("pint")

from impactbar.cli import main  # noqa: E402
from impactbar.drives.circuit import Leak, PartField  # noqa: E402
from impactbar.drives.circuit import _network as NW  # noqa: E402
from impactbar.drives.circuit.composition import node_of  # noqa: E402
from impactbar.physical import (  # noqa: E402
    build,
    continue_circuit,
    optimize_drifter,
    read_config,
    register_part,
    with_values,
)

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")

KEY = "parts.bleed.opening"


@dataclass(frozen=True)
class ThrottledLeak(Leak):
    """A leak whose orifice is open by the fraction ``opening`` (the new field): its flow
    ``opening K phi(p_a - p_b)``."""

    opening: float = 1.0

    si_fields = (*Leak.si_fields, PartField("opening", "", "0.5", "one", low=0.0, high=1.0, low_open=False,
                                            high_open=False, default=1.0,
                                            description="the orifice's open fraction"))

    def records(self, slots, oil) -> list:
        return [NW.record(NW.ORIFICE, source=node_of(slots, self, "source"),
                          target=node_of(slots, self, "target"),
                          coefficient=self.opening * self.flow_coefficient,
                          ptr2=oil.transition_pressure ** 2, energy=slots.energy[self.name])]


def _config(opening="0.5") -> dict:
    """The preset with a bleed from the supply to the tank, its orifice half open."""
    register_part("throttled_leak", ThrottledLeak)
    config = read_config("circuit-drifter")[0]
    config["parts"] = {"bleed": {"kind": "throttled_leak", "source": "supply", "target": "tank",
                                 "flow_coefficient": "4e-8 m^3/s/Pa^0.5", "opening": opening}}
    return config


@pytest.fixture(scope="module")
def config_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("bleed") / "bleed.toml"
    path.write_text(config_toml(_config()))
    return path


@pytest.fixture(scope="module")
def drifter():
    return build(_config())


def _fresh(opening):
    return build(with_values(_config(), {KEY: opening})).orbit()


def test_the_new_field_is_set_and_changes_the_orbit(drifter):
    """Set by its dotted name, the new field reaches the part (dimensionless: the scale ``one``), and
    the orbit moves with it (the bleed takes the pump's flow: a wider opening, a lower frequency)."""
    (part,) = drifter.drive().extra_parts
    assert type(part) is ThrottledLeak and part.opening == 0.5
    changed = build(with_values(drifter.config, {KEY: 0.9}))
    assert changed.drive().extra_parts[0].opening == 0.9
    assert changed.orbit().blow_frequency_Hz < drifter.orbit().blow_frequency_Hz * (1.0 - 1e-4)


def test_it_is_continued(drifter):
    b = continue_circuit(drifter, KEY, 0.6, max_points=4)
    assert b.unit == "" and b.values[0] == pytest.approx(0.5, rel=1e-12) and len(b) >= 2
    assert b.blow_frequency_Hz[0] == pytest.approx(drifter.orbit().blow_frequency_Hz, rel=1e-9)
    assert b.blow_frequency_Hz[-1] == pytest.approx(_fresh(float(b.values[-1])).blow_frequency_Hz, rel=1e-8)


def test_it_is_continued_from_the_command_line(config_file, tmp_path):
    out = tmp_path / "cont"
    assert main(["continue", str(config_file), "--parameter", KEY, "--to", "0.6", "--max-points", "3",
                 "--out", str(out)]) == 0
    rows = (out / "branch.csv").read_text().splitlines()
    # (a bare number: no unit in the header)
    assert rows[0].startswith(f"{KEY},") and "period_dimensionless" in rows[0]
    assert float(rows[1].split(",")[0]) == pytest.approx(0.5, rel=1e-12)


def test_it_is_swept_in_a_design_map():
    from impactbar.sweeps import parse_spec
    from impactbar.sweeps.map_task import compute_map_chunk

    spec = parse_spec({"task": "operating_point", "config": _config(), "chain": "default",
                       "axes": {KEY: {"values": [0.25, 0.75]}}})
    assert spec.axes[0].values == (0.25, 0.75)
    got = np.concatenate([np.ravel(compute_map_chunk(spec, c)["blow_frequency"])
                          for c in range(spec.n_chunks)])
    want = [_fresh(v).blow_frequency_Hz for v in (0.25, 0.75)]
    assert got == pytest.approx(want, rel=1e-9)


def test_it_is_optimised_and_from_the_command_line(config_file, capsys):
    res = optimize_drifter(_config(), {KEY: (0.25, 0.75)}, objective="impact_power", max_evaluations=3,
                           progress=False)
    assert 0.25 <= res.optimum["values"][KEY] <= 0.75
    fresh = _fresh(res.optimum["values"][KEY])
    assert res.optimum["objectives"]["impact_power_kW"] == pytest.approx(fresh.impact_power_kW, rel=1e-8)
    assert main(["optimize", str(config_file), "--vary", f"{KEY}=0.25:0.75", "--objective", "impact_power",
                 "--max-evaluations", "3", "--json"]) == 0
    assert 0.25 <= json.loads(capsys.readouterr().out)["optimum"]["values"][KEY] <= 0.75
