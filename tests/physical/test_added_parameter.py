"""A parameter added to a circuit part's declaration, once, in the parameter tree
(:mod:`impactbar.physical.tree`): the piston's viscous damping ``damping.coefficient``, a config key
that sets no dimensionless parameter until its field declares one (``d = c / (m Omega)``, eq. 2).
Declared here alone, it is swept in a design map, continued, optimised and set from the command line
by its dotted SI name, with no line elsewhere."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from config_toml import config_toml

pytest.importorskip("pint")

from impactbar.cli import main  # noqa: E402
from impactbar.physical import build, continue_circuit, optimize_drifter, read_config, tree, with_values  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")

KEY = "damping.coefficient"


@pytest.fixture(scope="module")
def config_file(tmp_path_factory):
    """The preset with its piston damped, 5 N s/m, as a file."""
    path = tmp_path_factory.mktemp("added") / "damped.toml"
    path.write_text(config_toml(with_values(read_config("circuit-drifter")[0], {KEY: "5 N*s/m"})))
    return path


@pytest.fixture(scope="module")
def drifter(config_file):
    return build(read_config(str(config_file))[0])


@pytest.fixture
def declared(monkeypatch):
    """The field's declaration with its dimensionless parameter: ``d`` of the bar model, in the
    damping scale ``m Omega``."""
    field = replace(tree.FIELDS[KEY], parameter="d", holder="model",
                    scale=lambda d: 1.0 / (d.bar.mass_kg * d.omega_rad_s))
    monkeypatch.setitem(tree.FIELDS, KEY, field)
    return field


def test_undeclared_it_is_refused_with_the_reason(drifter):
    with pytest.raises(ValueError, match=f"parameter {KEY} cannot be continued: it sets no dimensionless"):
        continue_circuit(drifter, KEY, "6 N*s/m", max_points=3)


def test_declared_it_sets_the_models_damping(drifter, declared):
    name, value = drifter.to_dimensionless(KEY, "5 N*s/m")
    assert name == "d" and value == drifter.model().d
    assert drifter.from_dimensionless(KEY, value) == pytest.approx(5.0, rel=1e-15)


def test_declared_it_is_continued(drifter, declared, tmp_path, capsys):
    """``continue_circuit`` and ``impactbar continue CONFIG --parameter damping.coefficient``: the
    branch in N s/m, its first point the config's own orbit."""
    b = continue_circuit(drifter, KEY, "6 N*s/m", max_points=3)
    assert b.unit == "N*s/m" and b.values[0] == pytest.approx(5.0, rel=1e-12) and len(b) >= 2
    assert b.blow_frequency_Hz[0] == pytest.approx(drifter.orbit().blow_frequency_Hz, rel=1e-9)
    assert np.all(np.diff(b.values) > 0.0)


def test_declared_it_is_set_from_the_command_line(config_file, declared, tmp_path, capsys):
    out = tmp_path / "cont"
    assert main(["continue", str(config_file), "--parameter", KEY, "--to", "6 N*s/m", "--max-points", "3",
                 "--out", str(out)]) == 0
    rows = (out / "branch.csv").read_text().splitlines()
    assert rows[0].startswith(f"{KEY} (N*s/m),") and "period_dimensionless" in rows[0]
    assert float(rows[1].split(",")[0]) == pytest.approx(5.0, rel=1e-12)


def test_declared_it_is_swept(config_file, declared):
    """A design map's axis in the declared unit, each point the fresh orbit of the config there."""
    from impactbar.sweeps import parse_spec
    from impactbar.sweeps.map_task import compute_map_chunk

    spec = parse_spec({"task": "operating_point", "config": str(config_file), "chain": "default",
                       "axes": {KEY: {"values": ["4 N*s/m", "6 N*s/m"]}}})
    assert spec.axes[0].unit == "N*s/m" and spec.axes[0].values == (4.0, 6.0)
    got = compute_map_chunk(spec, spec.n_chunks - 1)["blow_frequency"]
    fresh = build(with_values(read_config(str(config_file))[0], {KEY: "6 N*s/m"})).orbit()
    assert got.ravel()[-1] == pytest.approx(fresh.blow_frequency_Hz, rel=1e-9)


def test_declared_it_is_optimised(config_file, declared, capsys):
    """``optimize_drifter`` and ``impactbar optimize --vary damping.coefficient=...``: a tiny search
    within the bounds."""
    res = optimize_drifter(str(config_file), {KEY: ("4 N*s/m", "6 N*s/m")}, objective="impact_power",
                           max_evaluations=3, progress=False)
    assert 4.0 <= res.optimum["values"][KEY] <= 6.0
    assert math.isfinite(res.optimum["objectives"]["impact_power_kW"])
    assert main(["optimize", str(config_file), "--vary", f"{KEY}=4 N*s/m:6 N*s/m", "--objective",
                 "impact_power", "--max-evaluations", "3", "--json"]) == 0
    assert 4.0 <= json.loads(capsys.readouterr().out)["optimum"]["values"][KEY] <= 6.0
