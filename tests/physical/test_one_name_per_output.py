"""One quantity, one name and one long name: every output the registry
(:mod:`impactbar.physical.outputs`) declares appears in every view (the SI results' ``to_dict`` and
tables, the design maps' stored variables and their attributes, the dimensionless sweep's, the
sensitivities, the optimiser's objectives and constraints, the operating point's and a blow's figures)
under its name, or its name with its unit (its key), and with its long name; a name it had before
(:data:`~impactbar.physical.outputs.RENAMED_OUTPUTS`) still reads it, with a ``DeprecationWarning``.

The views are walked, not listed: each schema's fields, and the figures an output is read from,
found by reading each output from a recording stand-in of an operating point and of a blow (an
output that is a figure read as it is must be named as the figure: ``peak_rod_stress`` is read
from ``peak_rod_stress_Pa``; two outputs that read one figure are one quantity twice)."""

from __future__ import annotations

import warnings

import pytest

from impactbar.physical.optimize_drifter import DEFAULT_CONSTRAINTS, IDEAL_CONSTRAINTS, OBJECTIVES
from impactbar.physical.optimize_outputs import constraint_output
from impactbar.physical.outputs import OUTPUTS, RENAMED_OUTPUTS, current_keys, current_name, output_by_key
from impactbar.physical.results import PHYSICAL_ORBIT_FIELDS
from impactbar.physical.sensitivity import FIGURE_UNITS
from impactbar.sweeps.map_spec import map_variables
from impactbar.sweeps.store import _var_attrs
from impactbar.sweeps.tasks import _ROCK


class Read:
    """A stand-in that records the path by which it was read (``point.pump_power_kW``,
    ``rock["work_on_rock_J"]``); anything computed from it raises or gives another object."""

    def __init__(self, *path):
        self.path = path

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        if name == "get":  # (a dict's get(key, default): a read of key)
            return lambda key, default=None: Read(*self.path, key)
        return Read(*self.path, name)

    def __getitem__(self, key):
        return Read(*self.path, key)

    def __call__(self, *args, **kwargs):
        return Read(*self.path, "()")

    def __iter__(self):
        raise TypeError("a recorded reading is not iterable")


#: where an output reads a figure as it is: an operating point's attribute, its rock figures, a blow's
_SOURCES = {("point",): "an operating point's attribute", ("rock",): "the rock figures",
            (): "a blow's figures"}


def figures_read() -> list:
    """``(output, where, figure)`` for each output that is a figure read as it is."""
    found = []
    for o in OUTPUTS.values():
        for fn, start in ((o.of, Read()), (o.blow, Read())):
            if fn is None:
                continue
            try:
                got = fn(start)
            except Exception:  # computed from several figures, or not a plain read
                continue
            if isinstance(got, Read) and got.path[:-1] in _SOURCES:
                found.append((o, _SOURCES[got.path[:-1]], got.path[-1]))
    return found


def test_an_output_read_from_a_figure_is_named_as_the_figure():
    read = figures_read()
    assert len(read) >= 15  # (the walk sees the figures: the point's, the rock's, a blow's)
    wrong = [f"{o.name} (key {o.key}) reads {where}' {figure!r}" for o, where, figure in read
             if figure != o.key]
    assert not wrong, "one quantity under two names:\n" + "\n".join(wrong)
    by_figure: dict = {}
    for o, where, figure in read:
        by_figure.setdefault((where, figure), set()).add(o.name)
    twice = {k: v for k, v in by_figure.items() if len(v) > 1}
    assert not twice, f"one figure declared as two outputs: {twice}"


def _views() -> list:
    """``(view, name, long name, units)`` of every field of every view that shows outputs."""
    rows = [("PhysicalOrbit", f.name, f.long_name, f.units) for f in PHYSICAL_ORBIT_FIELDS]
    for kind in ("drifter", "circuit"):
        for rock in (False, True):
            for task in ("operating_point", "settle"):
                for f in map_variables(kind, rock, task):
                    attrs = _var_attrs(f.name, f.long_name, f.units)
                    rows.append((f"map store ({kind}, {task})", f.name, attrs["long_name"], None))
    rows += [("sweep store (rock)", f.name, _var_attrs(f.name, f.long_name, f.units)["long_name"], None)
             for f in _ROCK]
    rows += [("sensitivities", key, None, None) for key in FIGURE_UNITS]
    rows += [("objectives", key, long_name, unit) for key, unit, long_name in OBJECTIVES.values()]
    return rows


def _output_named(name: str):
    """The output whose name, key or display key ``name`` is, ``None`` for none."""
    return next((o for o in OUTPUTS.values() if name in (o.name, o.key, o.shown_key)), None)


def test_each_view_names_an_output_by_its_name_and_long_name():
    rows = _views()
    stale = [f"{view}: {name}" for view, name, _, _ in rows
             if name in RENAMED_OUTPUTS or any(name.startswith(f"{k}_") for k in RENAMED_OUTPUTS)]
    assert not stale, f"a view still says an old name: {stale}"
    seen = 0
    bad = []
    for view, name, long_name, _ in rows:
        o = _output_named(name)
        if o is None:
            continue
        seen += 1
        if long_name is not None and long_name != o.long_name:
            bad.append(f"{view}: {name} is {long_name!r}, the registry's {o.name} {o.long_name!r}")
    assert seen >= 40
    assert not bad, "one quantity, two long names:\n" + "\n".join(bad)


def test_the_constraints_are_named_by_their_outputs():
    """Each constraint is its output's name or key (``min_<name>``: at least it): a constraint
    named otherwise is one quantity under a second name."""
    for name in (*DEFAULT_CONSTRAINTS, *IDEAL_CONSTRAINTS):
        assert name not in RENAMED_OUTPUTS
        c = constraint_output(name)
        assert name in (c.output.name, c.output.key, f"min_{c.output.name}"), \
            f"constraint {name!r} limits the output {c.output.name!r}: name it by it"
        if name == f"min_{c.output.name}":
            assert c.sense == -1, f"{name}: min_<name> is at least the limit"


def test_an_output_that_is_a_least_value_is_held_at_least_by_its_own_name():
    """An output that is a least value over the period (``min_rear_pressure``, ``minimum_pressure``,
    ``min_chamber_volume``) given as a constraint by its own name bounds it from below, as the named
    constraints do: ``{"min_rear_pressure": "0.5 MPa"}`` is no cavitation margin read the other way
    round. Walked over the registry; the margin's sign checked on numbers."""
    from impactbar.physical.optimize_problem import _constrained

    least = [n for n, o in OUTPUTS.items() if n.startswith(("min_", "minimum_")) and o.of is not None
             and o.dtype == "f8"]
    assert {"min_rear_pressure", "min_front_pressure", "min_supply_pressure", "minimum_pressure",
            "min_chamber_volume"} <= set(least)
    for name in least:
        c = constraint_output(name)
        assert c is not None and c.output.name == name and c.sense == -1, (name, c)
        rec = _constrained({}, {name: 2.0e6}, {name: 1.0e6})  # the value above its least limit: met
        assert rec["constraints"][name]["margin"] == 1.0e6 and rec["feasible"], name
        rec = _constrained({}, {name: 0.5e6}, {name: 1.0e6})
        assert rec["constraints"][name]["margin"] == -0.5e6 and not rec["feasible"], name


def test_a_constraint_given_by_its_old_name_limits_the_same_output_on_the_same_side():
    with pytest.warns(DeprecationWarning, match="constraint 'min_pressure' is now called 'minimum_pressure'"):
        old = constraint_output("min_pressure")
    assert old == constraint_output("minimum_pressure") and old.sense == -1


@pytest.mark.parametrize("old", sorted(RENAMED_OUTPUTS))
def test_an_old_name_reads_the_output_with_a_deprecation_warning(old):
    new = RENAMED_OUTPUTS[old]
    o = OUTPUTS[new]
    with pytest.warns(DeprecationWarning, match=f"'{old}' is now called '{new}'"):
        assert output_by_key(old) is o
    with pytest.warns(DeprecationWarning, match=f"'{old}_{o.unit}' is now called '{o.key}'" if o.key != new
                      else f"'{old}' is now called"):
        assert output_by_key(old if o.key == new else f"{old}_{o.unit}") is o
    with pytest.warns(DeprecationWarning, match=f"constraint 'min_{old}' is now called 'min_{new}'"):
        assert constraint_output(f"min_{old}").output is o
    with pytest.warns(DeprecationWarning, match=f"'{old}' is now called '{new}'"):
        assert current_keys({old: 1.0, "stable": True}) == {new: 1.0, "stable": True}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the names now: no warning, the same object back
        record = {new: 1.0}
        assert current_name(new) == new and current_keys(record) is record


def test_an_old_store_opens_with_the_names_now(tmp_path):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("zarr")
    from impactbar.sweeps.store import _ATTR_SPEC, open_sweep

    ds = xr.Dataset({"peak_incident_stress": ("x", [2.0e8]), "rock_efficiency": ("x", [0.7]),
                     "stable": ("x", [True])})
    ds.attrs[_ATTR_SPEC] = "{}"
    ds.to_zarr(tmp_path / "old.zarr")
    with pytest.warns(DeprecationWarning, match="variable 'rock_efficiency' is now called 'efficiency'"):
        opened = open_sweep(tmp_path / "old.zarr")
    assert set(opened.data_vars) == {"peak_rod_stress", "efficiency", "stable"}
    assert float(opened["peak_rod_stress"][0]) == 2.0e8


def test_an_old_cache_reads_its_records_under_the_names_now(tmp_path):
    import json

    from impactbar.physical.optimize_cache import read_cache

    path = tmp_path / "cache.json"
    path.write_text(json.dumps({"problem": "t", "evaluations": [
        {"id": 0, "objectives": {"blow_efficiency": 0.8, "work_on_rock_J": 200.0},
         "constraints": {"peak_incident_stress": {"value": 2e8, "limit": 2.5e8}}}]}))
    with pytest.warns(DeprecationWarning, match="'blow_efficiency' is now called 'efficiency'"):
        (record,) = read_cache(path, "t").values()
    assert record["objectives"] == {"efficiency": 0.8, "work_on_rock_J": 200.0}
    assert list(record["constraints"]) == ["peak_rod_stress"]


def test_a_constraint_given_by_its_old_name_limits_the_output():
    from pathlib import Path

    from impactbar.physical import build, read_config
    from impactbar.physical.optimize_problem import _limits

    cfg, folder = read_config(str(Path(__file__).parents[2] / "examples" / "circuit_drifter_rock.toml"))
    drifter = build(cfg, folder)
    with pytest.warns(DeprecationWarning, match="'peak_incident_stress' is now called 'peak_rod_stress'"):
        old = _limits({"peak_incident_stress": "250 MPa", "min_drilling_rate": "2.5 m/min"}, drifter)
    assert old == _limits({"peak_rod_stress": "250 MPa", "min_drilling_rate": "2.5 m/min"}, drifter)
    assert old["peak_rod_stress"] == 250e6


def test_the_valve_drifters_old_power_reads_the_impact_power():
    """The valve drifter's ``percussive_power_kW`` was the circuit drifter's ``impact_power_kW`` (the
    kinetic energy at impact times the blow frequency): one name now, the old one a warning."""
    from impactbar.physical import drifter_preset

    o = drifter_preset("hydraulic-drifter").orbit()
    assert o.impact_power_kW == o.impact_energy_J * o.blow_frequency_Hz / 1e3
    assert "impact_power_kW" in o.summary() and "percussive_power_kW" not in o.summary()
    with pytest.warns(DeprecationWarning, match="percussive_power_kW is now called impact_power_kW"):
        assert o.percussive_power_kW == o.impact_power_kW


def _result_names() -> dict:
    """The values the SI result types declare, by type: the one-impact orbit's
    (:class:`~impactbar.physical.PhysicalOrbit`) and the piston design's
    (:class:`~impactbar.physical.OptimalPiston`)."""
    import dataclasses

    from impactbar.physical import OptimalPiston, PhysicalOrbit

    return {"PhysicalOrbit": {f.name for f in PHYSICAL_ORBIT_FIELDS} | {f.name for f in
                                                                       dataclasses.fields(PhysicalOrbit)},
            "OptimalPiston": {f.name for f in dataclasses.fields(OptimalPiston)}}


def test_a_name_two_results_share_is_one_outputs_key():
    """A name two result types both use is one quantity: the registry's key of it (the stress in the
    piston at impact and the rod's incident peak were both ``peak_stress_Pa``)."""
    (a, b) = _result_names().values()
    shared = a & b
    assert shared  # (the walk sees both types' fields)
    keys = {o.key for o in OUTPUTS.values()}
    assert not shared - keys, f"one name, two quantities: {sorted(shared - keys)}"


@pytest.mark.parametrize(("cls", "old", "new"), [
    ("OptimalPiston", "peak_stress_Pa", "peak_rod_stress_Pa"),
    ("OptimalPiston", "uniform_peak_stress_Pa", "uniform_peak_rod_stress_Pa"),
    ("PhysicalOrbit", "peak_stress_Pa", "peak_piston_stress_Pa"),
    ("PhysicalOrbit", "blow_energy_J", "impact_energy_J"),
    ("SimulationResult", "blow_energies_J", "impact_energies_J"),
    ("BlowStatistics", "mean_blow_energy_J", "mean_impact_energy_J"),
])
def test_a_results_old_attribute_reads_the_new_one_with_a_deprecation_warning(cls, old, new):
    import impactbar.physical as ph

    class Stand(getattr(ph, cls)):  # (the attribute alone, without solving a blow or an orbit)
        def __init__(self):
            pass

    stand = Stand()
    object.__setattr__(stand, new, 123.25)
    with pytest.warns(DeprecationWarning, match=f"{old} is now called {new}"):
        assert getattr(stand, old) == 123.25


def test_the_hammers_orbit_names_what_it_shares_with_a_drifters_as_the_registry_does():
    """Each output both drifters have and read as an operating point's attribute is read from the
    hammer's one-impact orbit (:class:`~impactbar.physical.PhysicalOrbit`) by the same key (it said
    ``blow_energy_J`` for ``impact_energy_J`` and ``power_W`` for ``impact_power_kW``), and its value
    is the closed form's: the energy :math:`m v^2/2`, the power that times the blow frequency. The
    old names read the same numbers, bit for bit, with a ``DeprecationWarning``."""
    from impactbar import physical as ph
    from impactbar.physical.outputs import Reading

    hammer = ph.preset("pneumatic-drill")
    o = ph.orbits(hammer)[0]
    v, fb = o.impact_velocity_m_s, o.blow_frequency_Hz
    energy = 0.5 * hammer.mass_kg * v * v
    closed = {"impact_energy": energy, "impact_power": energy * fb / 1e3, "blow_frequency": fb,
              "impact_velocity": v}
    shared = [out for out, where, _ in figures_read() if where == "an operating point's attribute"
              and out.machines == {"drifter", "circuit"} and out.name != "period"]  # (no period field)
    assert {"impact_energy", "impact_power"} <= {out.name for out in shared}
    reading = Reading(o)
    for out in shared:
        value = out.of(reading)  # (an AttributeError: the hammer's orbit names it otherwise)
        if out.name in closed:
            assert value == pytest.approx(closed[out.name], rel=1e-12), out.name
    with pytest.warns(DeprecationWarning, match="blow_energy_J is now called impact_energy_J"):
        assert o.blow_energy_J == o.impact_energy_J
    with pytest.warns(DeprecationWarning, match="power_W is now called impact_power_kW"):
        assert o.power_W == o.impact_energy_J * o.blow_frequency_Hz


#: the prefixes of a figure over a run's blows: ``mean_impact_energy_J`` is the mean of
#: ``impact_energy_J``, ``last_impact_energy_J`` its last blow's
_OVER_BLOWS = ("mean_", "last_")


def _run_views() -> tuple[dict, float, float]:
    """A simulated run's views of its numbers, ``{view: {name: (value, long name or None)}}`` (its
    table, :meth:`~impactbar.physical.SimulationResult.to_dataframe`; its blow statistics; the CLI's
    ``summary.json``), of a stand-in run of the pneumatic drill: 20 blows of 30 m/s, one every 50 ms;
    and the closed forms of its kinetic energy at impact (J) and its impact power (kW), the energy
    :math:`m v^2/2` over the interval. The run is built by position: its fields' names are what is
    tested."""
    import numpy as np

    from impactbar import physical as ph
    from impactbar.cli.simulate import summarize

    h = ph.preset("pneumatic-drill")
    t = 0.05 * np.arange(1, 21)
    v = np.full(t.size, 30.0)
    run = ph.SimulationResult(h, None, 1.0, t, v, 0.5 * h.mass_kg * v * v)
    df = run.to_dataframe()
    columns = df.attrs["columns"]
    views = {"run table": {c: (float(df[c].iloc[-1]), columns[c]["long_name"]) for c in df.columns},
             "blow statistics": {k: (x, None) for k, x in run.blow_statistics().to_dict().items()},
             "summary.json": {k: (x, None) for k, x in summarize(run).items()}}
    energy = 0.5 * h.mass_kg * 900.0
    return views, energy, energy / 0.05 / 1e3


def test_a_runs_views_name_its_impact_energy_and_power_by_the_registrys_keys():
    """A simulated run's table, blow statistics and CLI summary give its kinetic energy at impact and
    its impact power (the closed forms of a run of equal blows) under the registry's keys
    (``impact_energy_J``, ``impact_power_kW``: in kW, not W; a mean or the last blow's with its
    prefix) and long names: they said ``blow_energy_J``, ``mean_blow_energy_J`` and ``mean_power_W``.
    Found by value, not by name: every number of each view that is one of the closed forms (the
    power in W or kW) is checked."""
    import math

    views, energy, power_kW = _run_views()
    targets = {"impact_energy": (energy,), "impact_power": (power_kW, 1e3 * power_kW)}
    found, wrong = set(), []
    for view, figures in views.items():
        for name, (value, long_name) in figures.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                continue
            for output, values in targets.items():
                if not any(value == pytest.approx(x, rel=1e-12) for x in values):
                    continue
                o = OUTPUTS[output]
                stem = next((name[len(p):] for p in _OVER_BLOWS if name.startswith(p)), name)
                found.add((view, output))
                if stem != o.key or value != pytest.approx(values[0], rel=1e-12):
                    wrong.append(f"{view}: {name} = {value!r} is the {output} ({o.key}, {o.unit})")
                elif long_name is not None and long_name != o.long_name:
                    wrong.append(f"{view}: {name} is {long_name!r}, the registry's {o.long_name!r}")
    assert {(v, "impact_energy") for v in views} <= found  # (the walk sees each view's energy)
    assert {("blow statistics", "impact_power"), ("summary.json", "impact_power")} <= found
    assert not wrong, "one quantity under two names:\n" + "\n".join(wrong)


def test_a_runs_old_power_reads_the_impact_power_in_watts():
    """``BlowStatistics.mean_power_W`` (W) reads ``mean_impact_power_kW`` times 1000 with a
    ``DeprecationWarning``; the old keys of the registry's outputs map to the keys now with the
    factor between their units (:func:`~impactbar.physical.outputs.renamed_key`)."""
    import numpy as np

    from impactbar import physical as ph
    from impactbar.physical.outputs import renamed_key

    h = ph.preset("pneumatic-drill")
    t = 0.05 * np.arange(1, 21)
    v = np.full(t.size, 30.0)
    stats = ph.SimulationResult(h, None, 1.0, t, v, 0.5 * h.mass_kg * v * v).blow_statistics()
    with pytest.warns(DeprecationWarning, match="mean_power_W is now called mean_impact_power_kW"):
        watts = stats.mean_power_W
    assert watts == pytest.approx(0.5 * h.mass_kg * 900.0 / 0.05, rel=1e-14)
    assert watts / 1e3 == pytest.approx(stats.mean_impact_power_kW, rel=1e-15)
    assert renamed_key("power_W") == ("impact_power_kW", 1e3)
    assert renamed_key("blow_energy_J") == ("impact_energy_J", 1.0)
    assert renamed_key("min_percussive_power_kW") == ("min_impact_power_kW", 1.0)
    assert renamed_key("pump_power_kW") == ("pump_power_kW", 1.0)  # (the name now: as it is)
