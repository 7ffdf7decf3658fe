"""One sweep spec class for both kinds of map: a sweep of the paper's dimensionless bar and a drifter's
design map in SI are each built through :class:`impactbar.sweeps.SweepSpec`, run into a store, and
two of their points checked against the orbit found directly (and the bar's against its closed form)."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("zarr")
pytest.importorskip("xarray")

from impactbar import BarModel, CosineLoad, periodic_orbits  # noqa: E402
from impactbar.physical.loader import build, read_config, with_values  # noqa: E402
from impactbar.physical.outputs import output_values, outputs  # noqa: E402
from impactbar.sweeps import Axis, SweepSpec, open_sweep, parse_spec, run_sweep  # noqa: E402
from impactbar.sweeps.map_spec import config_axis  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")


def _run(spec, store):
    res = run_sweep(spec, store, executor="threads", n_workers=1, progress=False)
    assert res.complete
    return open_sweep(store)


def test_a_dimensionless_map_through_the_one_class(tmp_path):
    """The rigid bar under ``p0 + cos t`` (eq. 33), restitution R: over one period T = 2 pi of a
    one-impact orbit the load's impulse p0 T returns the velocity (1 + R) v, and the bar returns to the
    wall: v = p0 T / (1 + R) and sin(t0) = p0 T (1 - R) / (2 (1 + R)) at the impact phase t0 (two
    orbits: t0 and pi - t0)."""
    R = 0.5
    spec = SweepSpec(task="orbits", model={"s": 100.0, "d": 0.0, "R": R, "n_modes": 0},
                     load=CosineLoad(p0=0.4, pk=1.0, k=1).params.record(), axes=(Axis("p0", (0.3, 0.4)),))
    assert spec.space.fields == ("model", "load", "rock", "law", "drive")
    ds = _run(spec, tmp_path / "bar.zarr")
    assert ds["p0"].attrs["units"] == "1" and ds["impact_velocity"].dims == ("p0", "orbit")
    T = 2 * math.pi
    for i, p0 in enumerate((0.3, 0.4)):
        direct = periodic_orbits(BarModel(s=100.0, d=0.0, R=R, n_modes=0), CosineLoad(p0=p0, pk=1.0, k=1))
        n = int(ds["n_orbits"][i])
        assert n == len(direct) == 2
        got_v = np.sort(ds["impact_velocity"].values[i, :n])
        got_t = np.sort(ds["phase"].values[i, :n])
        np.testing.assert_allclose(got_v, sorted(o.impact_velocity for o in direct), rtol=1e-12)
        np.testing.assert_allclose(got_t, sorted(o.phase for o in direct), rtol=1e-12)
        np.testing.assert_allclose(got_v, p0 * T / (1 + R), rtol=1e-12)
        s0 = p0 * T * (1 - R) / (2 * (1 + R))
        np.testing.assert_allclose(got_t, [math.asin(s0), math.pi - math.asin(s0)], rtol=1e-12)


def test_a_design_map_in_si_through_the_one_class(tmp_path):
    """The drifter with its oil circuit over its pump flow: each point the operating point found
    directly from the config with the flow set (the default chain, the same computation: 1e-9
    relative), in SI with its units; the blow frequency the inverse of the period."""
    config = read_config("circuit-drifter")[0]
    flows = ("60 L/min", "80 L/min")
    axis = config_axis(config, "supply.pump_flow", {"values": list(flows)})
    spec = SweepSpec(task="operating_point", config=config, axes=(axis,), options={"chain": "default"})
    assert spec.options == {"refine_edges": False, "chain": "default"} and spec.extra_size == 0
    assert parse_spec(spec.to_dict()) == spec  # the TOML's shape reads back to the same spec
    ds = _run(spec, tmp_path / "map.zarr")
    assert ds["supply.pump_flow"].attrs["units"] == "m3/s"
    assert ds["blow_frequency"].attrs["units"] == "Hz" and ds["impact_velocity"].attrs["units"] == "m/s"
    stored = outputs("store", "circuit", False)
    for i, q in enumerate(flows):
        point = build(with_values(config, {"supply.pump_flow": q})).orbit()
        values = output_values(point, stored)
        for o in stored:
            want = o.to_si(values[o.name])
            assert ds[o.name].values[i].item() == pytest.approx(want, rel=1e-9, nan_ok=True), (o.name, q)
        assert float(ds["blow_frequency"][i] * ds["period"][i]) == pytest.approx(1.0, rel=1e-12)
        assert int(ds["status"][i]) == 0 and int(ds["origin"][i]) == 0


def test_the_machine_is_the_task_s_and_the_other_s_fields_are_refused():
    config = read_config("circuit-drifter")[0]
    with pytest.raises(ValueError, match=r"^task = 'orbits' sweeps the dimensionless bar: it takes no "
                                         r"\['config'\]"):
        SweepSpec(task="orbits", model={"s": 100.0, "d": 0.0, "R": 0.5, "n_modes": 0},
                  load=CosineLoad(p0=0.4, pk=1.0, k=1).params.record(), axes=(Axis("p0", (0.3,)),),
                  config=config)
    with pytest.raises(ValueError, match=r"^task = 'settle' sweeps a drifter's config: it takes no "
                                         r"\['model'\]"):
        SweepSpec(task="settle", model={"s": 100.0}, config=config,
                  axes=(config_axis(config, "supply.pump_flow", {"values": ["60 L/min"]}),))


def test_a_question_the_spec_s_machine_cannot_answer_is_a_one_line_value_error():
    """A design map has no dimensionless parameters (its axes are config keys), and neither kind of
    spec has an axis it was not given: each a ``ValueError`` naming what is allowed."""
    design = parse_spec({"task": "operating_point", "config": "circuit-drifter",
                         "axes": {"supply.pump_flow": {"values": ["60 L/min", "70 L/min"]}}})
    with pytest.raises(ValueError, match="its axes are the config's dotted keys"):
        design.parameters()
    bar = parse_spec({"task": "orbits", "model": {"s": 1.37, "d": 0.02, "R": 0.8, "n_modes": 0},
                      "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
                      "axes": {"p0": {"values": [0.5, 0.6]}}})
    assert "p0" in bar.parameters()
    for spec, axis in ((design, "supply.pump_flow"), (bar, "p0")):
        for ask in (spec.axis_attrs, lambda name, spec=spec: spec.axis_text(name, 1.0)):
            with pytest.raises(ValueError, match=f"one of \\['{axis}'\\]; got 'x'"):
                ask("x")
    assert design.axis_attrs("supply.pump_flow")["units"] == "m3/s" and bar.axis_attrs("p0")["units"] == "1"
