"""An output declared once (:func:`impactbar.physical.outputs.register_output`) reaches every tool:
a design map's store, the optimiser's constraints and the CLI's summary (text and JSON). The output
here is the blows per minute, checked against 60 s over the period the same store, record or summary
gives."""

from __future__ import annotations

import json

import pytest

from impactbar.cli import main
from impactbar.physical import optimize_drifter
from impactbar.physical.outputs import OUTPUTS, Output, register_output, unregister_output

pytest.importorskip("zarr")
pytest.importorskip("xarray")
pytest.importorskip("pint")

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")

NAME = "blows_per_minute"


@pytest.fixture(scope="module", autouse=True)
def added():
    """The output, registered for this module's tests only."""
    out = register_output(Output(NAME, "1/min", "blows per minute",
                                 lambda r: 60.0 * r.point.blow_frequency_Hz, views={"store", "summary"},
                                 key=NAME))
    yield out
    unregister_output(NAME)
    assert NAME not in OUTPUTS


def test_a_map_stores_the_added_output(tmp_path):
    from impactbar.sweeps import open_sweep, parse_spec, run_map

    spec = parse_spec({"task": "operating_point", "config": "circuit-drifter",
                       "axes": {"supply.pump_flow": {"values": ["60 L/min", "75 L/min"]}}})
    assert NAME in spec.variables().names
    run_map(spec, tmp_path / "m.zarr", executor="threads", n_workers=1, progress=False)
    ds = open_sweep(tmp_path / "m.zarr")
    assert ds[NAME].attrs["units"] == "1/min" and ds[NAME].attrs["long_name"] == "blows per minute"
    assert list(ds["status"].values.ravel()) == [0, 0]
    assert ds[NAME].values == pytest.approx(60.0 / ds["period"].values, rel=1e-14)


def test_the_optimiser_takes_the_added_output_as_a_constraint():
    vary = {"valve.switch_out": ("20 mm", "23 mm")}
    res = optimize_drifter("circuit-drifter", vary, objective="impact_power",
                           constraints={NAME: "3500 1/min"}, max_evaluations=3, progress=False)
    for rec in (res.baseline, res.optimum):
        c = rec["constraints"][NAME]
        assert c["unit"] == "1/min" and c["limit"] == 3500.0
        assert c["value"] == pytest.approx(60.0 * rec["objectives"]["blow_frequency_Hz"], rel=1e-14)
        assert c["margin"] == pytest.approx(3500.0 - c["value"], rel=1e-14)
    assert f"{NAME} (limit 3500)" in res.table()
    # at least a rate above the start's: the start misses it, the constraint named
    with pytest.raises(ValueError, match=f"infeasible start: constraint min_{NAME} = "):
        optimize_drifter("circuit-drifter", vary, objective="impact_power",
                         constraints={f"min_{NAME}": "1e5 1/min"}, max_evaluations=3, progress=False)


def test_the_cli_summary_shows_the_added_output(capsys):
    assert main(["drifter", "--preset", "circuit-drifter", "--json"]) == 0
    orbit = json.loads(capsys.readouterr().out)["orbit"]
    assert orbit[NAME] == pytest.approx(6e4 / orbit["period_ms"], rel=1e-14)
    assert main(["drifter", "--preset", "circuit-drifter"]) == 0
    assert f"blows per minute: {orbit[NAME]:.6g} 1/min" in capsys.readouterr().out
