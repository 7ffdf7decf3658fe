"""Results as tables: ``to_dataframe()`` / ``to_xarray()`` carry the same numbers as the objects,
with ``long_name`` and ``units`` on every variable; sweep stores label every variable and axis."""

import math

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, InitialState, SquareWaveLoad, periodic_orbits, simulate
from impactbar.orbits import OrbitList


@pytest.fixture(scope="module")
def orbits():
    return periodic_orbits(BarModel(s=5.0, d=0.1, R=0.5, n_modes=8), CosineLoad(0.6, 1.0))


def test_orbit_list_is_a_list_and_a_table(orbits):
    assert isinstance(orbits, OrbitList) and isinstance(orbits, list)
    assert orbits == list(orbits) and len(orbits) == 2
    df = orbits.to_dataframe()
    assert list(df.index) == [0, 1] and df.index.name == "orbit"
    for i, o in enumerate(orbits):
        row = df.loc[i]
        assert row["phase"] == o.phase and row["impact_velocity"] == o.impact_velocity
        assert row["admissibility"] == o.admissibility and bool(row["stable"]) == o.stable
        assert row["max_abs_multiplier"] == o.max_abs_multiplier and row["R"] == 0.5
    cols = df.attrs["columns"]
    assert cols["phase"]["units"] == "rad" and cols["impact_velocity"]["units"] == "1"


def test_orbit_list_to_xarray_has_long_names_and_units(orbits):
    ds = orbits.to_xarray()
    assert ds.sizes["orbit"] == 2
    np.testing.assert_array_equal(ds["phase"].values, [o.phase for o in orbits])
    for name in list(ds.data_vars) + ["orbit"]:
        assert "long_name" in ds[name].attrs and "units" in ds[name].attrs, name


def test_empty_orbit_list_keeps_the_columns():
    none = periodic_orbits(BarModel(s=5.0, d=0.1, R=0.5, n_modes=2), CosineLoad(60.0, 1.0))
    assert none == [] and isinstance(none, OrbitList)
    df = none.to_dataframe()
    assert len(df) == 0 and "phase" in df and df["stable"].dtype == bool


def test_orbit_time_series_matches_the_orbit(orbits):
    o = orbits[1]
    df = o.to_dataframe(n=16)
    t = df.index.to_numpy()
    assert t[0] == 0.0 and t[-1] == pytest.approx(2 * math.pi) and len(t) == 17
    np.testing.assert_allclose(df["end_displacement"], o.end_displacement(t[:-1].tolist() + [t[-1]]),
                               atol=1e-12)
    assert df["end_displacement"].iloc[0] == pytest.approx(0.0, abs=1e-12)  # contact at the impact
    assert df["end_velocity"].iloc[-1] == pytest.approx(o.impact_velocity, rel=1e-9)
    ds = o.to_xarray(nx=5, nt=7)
    assert ds["displacement"].dims == ("t", "x")
    np.testing.assert_allclose(ds["displacement"].sel(x=1.0).values, ds["displacement"].values[:, -1])
    x, tt = np.meshgrid(ds["x"].values, ds["t"].values)
    np.testing.assert_allclose(ds["displacement"].values, o.displacement(x, tt), atol=1e-12)
    assert ds["displacement"].attrs["units"] == "1" and ds.attrs["phase"] == o.phase
    with pytest.raises(ValueError, match="n must be"):
        o.to_dataframe(n=0)


def test_trajectory_table_is_the_impacts():
    bar = BarModel(s=10.0, d=0.03 / 6.283, R=0.5, n_modes=2)
    tr = simulate(bar, CosineLoad(0.8, 1.0), InitialState.rigid(-0.5, 0.0, n_modes=2), t_end=30.0)
    df = tr.to_dataframe()
    assert len(df) == tr.n_impacts > 0
    np.testing.assert_array_equal(df["time"], tr.impact_times)
    np.testing.assert_array_equal(df["velocity"], tr.impact_velocities)
    assert df.attrs["status"] == tr.status and df.attrs["t_end"] == tr.t_end
    ds = tr.to_xarray(n=40)
    np.testing.assert_array_equal(ds["impact_time"].values, tr.impact_times)
    np.testing.assert_allclose(ds["end_displacement"].values, tr.end_displacement(ds["t"].values))
    assert ds["end_displacement"].max() <= 1e-12  # the stop is never crossed
    for name in ds.data_vars:
        assert {"long_name", "units"} <= set(ds[name].attrs), name


def test_experiment_table_is_the_classes():
    from impactbar.simulation.experiments import hydraulic_setup, run_experiment

    model, load = hydraulic_setup(n_modes=0)
    res = run_experiment(model, load, starts=5, periods=30, seed=1, workers=1)
    df = res.to_dataframe()
    assert list(df["kind"]) == [c.kind for c in res.classes]
    ds = res.to_xarray()
    assert float(ds["fraction"].sum()) == pytest.approx(1.0)
    for m, f in res.fractions.items():
        assert float(ds["fraction"].sel(motion=m)) == f
    np.testing.assert_array_equal(ds["interval"].values, res.intervals)
    assert ds["interval"].attrs["units"] == "load periods"
    assert isinstance(load, SquareWaveLoad)


def test_sweep_store_labels_every_variable_and_axis():
    from impactbar.sweeps import parse_spec
    from impactbar.sweeps.store import _template

    for task, extra in (("orbits", {}), ("montecarlo", {"montecarlo": {"starts": 2, "periods": 5}}),
                        ("bifurcation", {"bifurcation": {"periods": 5}})):
        spec = parse_spec({"task": task, "model": {"s": 10.0, "d": 0.01, "R": 0.5, "n_modes": 0},
                           "load": {"kind": "cosine", "p0": 0.3, "pk": 1.0, "k": 1},
                           "axes": {"R": {"start": 0.0, "stop": 0.5, "num": 2}}, **extra})
        ds = _template(spec)
        for name in list(ds.data_vars) + list(ds.coords):
            attrs = ds[name].attrs
            assert attrs.get("long_name") and "units" in attrs, (task, name)
        assert ds["R"].attrs["long_name"] == "restitution coefficient"
    assert _template(parse_spec({"task": "orbits", "model": {"s": 10.0, "d": 0.0, "R": 0.5, "n_modes": 0},
                                 "load": {"kind": "cosine", "p0": 0.3, "pk": 1.0, "k": 1},
                                 "axes": {"p0": {"start": 0.2, "stop": 0.3, "num": 2}}}))["phase"].attrs[
        "units"] == "rad"


def test_si_simulation_table_and_the_csv_written_through_it(tmp_path):
    from impactbar import physical
    from impactbar.cli.simulate import write_impacts

    res = physical.simulate(physical.preset("pneumatic-drill"), periods=4)
    df = res.to_dataframe()
    np.testing.assert_array_equal(df["time_s"], res.impact_times_s)
    np.testing.assert_array_equal(df["impact_energy_J"], res.impact_energies_J)
    # energy per blow m v^2 / 2, from the velocities
    np.testing.assert_allclose(df["impact_energy_J"],
                               0.5 * res.hammer.mass_kg * df["impact_velocity_m_s"] ** 2, rtol=1e-12)
    assert df.attrs["columns"]["impact_energy_J"]["units"] == "J"
    write_impacts(res, tmp_path / "impacts.csv")
    lines = (tmp_path / "impacts.csv").read_text().splitlines()
    assert lines[0] == "impact,time_s,impact_velocity_m_s,impact_energy_J"
    assert len(lines) == len(df) + 1
    first = lines[1].split(",")
    assert first[0] == "0" and float(first[1]) == pytest.approx(df["time_s"].iloc[0], rel=1e-8)
    assert res.to_xarray()["time_s"].attrs["units"] == "s"


def test_si_orbit_list_is_a_table():
    from impactbar import physical

    hammer = physical.preset("pneumatic-drill")
    found = physical.orbits(hammer)
    assert isinstance(found, list) and isinstance(found, physical.PhysicalOrbitList)
    df = found.to_dataframe()
    assert len(df) == len(found) == 2
    for i, o in enumerate(found):
        assert df.loc[i, "impact_energy_J"] == o.impact_energy_J and bool(df.loc[i, "stable"]) == o.stable
    # the rigid mode's identity v = F_mean / (f m (1 + R)) (theory §1, SI scaling); the flexible
    # modes of this stiff piston add about 2e-5 at the struck end
    v = hammer.mean_force_N / (hammer.frequency_Hz * hammer.mass_kg * (1 + hammer.R))
    np.testing.assert_allclose(df["impact_velocity_m_s"], v, rtol=1e-4)
    assert df.attrs["columns"]["impact_power_kW"]["units"] == "kW"
    assert found.to_xarray()["peak_piston_stress_Pa"].attrs["units"] == "Pa"
