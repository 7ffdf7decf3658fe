"""Short reprs of every result type: the kind, the key numbers and the stability in one
or a few lines that do not grow with the data; the arrays on request (``to_dict`` and the
attributes)."""

import dataclasses
import json
import math

import numpy as np
import pytest

from impactbar import (
    BarModel,
    BilinearRock,
    CosineLoad,
    PeriodicOrbit,
    RodRock,
    RodSegment,
    find_orbit,
    periodic_orbits,
    single_blow,
)


def test_orbit_repr_is_one_line_of_its_key_numbers():
    orbits = periodic_orbits(BarModel(s=3.0, d=0.0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))
    o = orbits[1]
    text = repr(o)
    assert "\n" not in text and len(text) < 160
    assert text.startswith("PeriodicOrbit(1 impact in 1 load period, ")
    assert f"phase {o.phase:.4f}" in text and f"impact velocity {o.impact_velocity:.6g}" in text
    assert "admissible" in text and ", stable" in text and f"max|mu| {o.max_abs_multiplier:.5f}" in text
    assert "not stable" in repr(orbits[0])  # the other orbit of the pair
    # the arrays on request: to_dict has them, JSON-ready
    d = o.to_dict()
    assert d["multipliers"] == [[m.real, m.imag] for m in o.multipliers.tolist()]
    json.dumps(d)


def test_orbit_repr_does_not_grow_with_the_modes_and_names_each_impact():
    many = periodic_orbits(BarModel(s=3.0, d=0.05, R=0.6, n_modes=40), CosineLoad(0.9, 1.0))
    assert all(len(repr(o)) < 160 for o in many)
    two = find_orbit(BarModel(3.0, 0.05, 0.8, 4), CosineLoad(0.45, 1.0), 2, 2)
    text = repr(two)
    assert text.startswith("PeriodicOrbit(2 impacts in 2 load periods, phases [")
    assert "impact velocities [" in text and text.count(",") < 12


def test_orbit_list_repr_is_a_line_per_orbit_and_bounded():
    orbits = periodic_orbits(BarModel(s=3.0, d=0.0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))
    lines = repr(orbits).splitlines()
    assert lines[0] == "OrbitList of 2 orbits:" and lines[1:] == [f"  {o!r}" for o in orbits]
    assert repr(periodic_orbits(BarModel(s=3.0, d=0.0, R=0.6, n_modes=0), CosineLoad(90, 1.0))) \
        == "OrbitList([])"
    many = periodic_orbits(BarModel(s=3.0, d=0.0, R=0.6, n_modes=0), CosineLoad(0.1, 1.0, 8))
    assert len(many) == 16
    lines = repr(many).splitlines()
    assert len(lines) == 14 and lines[-1] == "  ... and 4 more"


def test_a_subclass_extends_the_orbit_repr():
    """The hook a subclass with fields of its own uses (a driven orbit: its period)."""

    @dataclasses.dataclass(frozen=True, eq=False, repr=False)
    class Timed(PeriodicOrbit):
        period_s: float = 0.0

        def _repr_items(self):
            return [*super()._repr_items(), f"period {self.period_s:g} s"]

    o = periodic_orbits(BarModel(s=3.0, d=0.0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))[1]
    timed = Timed(**{f.name: getattr(o, f.name) for f in dataclasses.fields(o)}, period_s=0.02)
    assert repr(timed) == repr(o).replace("PeriodicOrbit(", "Timed(")[:-1] + ", period 0.02 s)"


def test_blow_repr_is_short_and_its_numbers_come_on_request():
    law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
    blow = single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, t_max=39.0,
                       record_field=True)
    assert blow.field.size > 10_000  # the arrays a dataclass repr printed
    text = repr(blow)
    assert "\n" not in text and len(text) < 200 and text.startswith("Blow(ended by ")
    assert f"work on rock {blow.work_on_rock:.4g}" in text and f"efficiency {blow.efficiency:.4g}" in text
    d = blow.to_dict()
    json.dumps(d)
    assert d["work_on_rock"] == blow.work_on_rock and d["energy_error"] == blow.energy_error
    assert set(d) >= {"available_energy", "permanent_penetration", "duration", "piston_cells"}


def test_event_repr_is_one_line():
    from impactbar import continue_orbit

    start = periodic_orbits(BarModel(s=3.0, d=0.0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))[1]
    fold = continue_orbit(start, "p0", to=1.5).events[0]
    text = repr(fold)
    assert text.startswith("BranchEvent('fold' at p0 = 1.27323954") and "multiplier 1" in text
    assert fold.to_dict()["multiplier"] == [fold.multiplier.real, fold.multiplier.imag]
    assert math.isclose(fold.to_dict()["phase"], fold.orbit.phase)
    assert np.isfinite(fold.value)


@pytest.mark.parametrize("kind", ["cosine", "square"])
def test_cli_orbit_table_is_the_declared_columns(kind, capsys):
    from impactbar.cli import main

    main(["orbits", "--load", kind, "--n-modes", "1"])
    out = capsys.readouterr().out.splitlines()
    header = out[2].split()
    assert header == ["phase", "impact", "vel.", "admissibility", "clearance", "stable", "max|mu|", "paper"]
    assert len(out) > 3
