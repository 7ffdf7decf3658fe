"""``impactbar continue`` on a drifter: every column of ``branch.csv`` and ``events.csv`` is a declared
quantity (a config key of the parameter tree, an output of the registry, a field of the dimensionless
orbit or the continuation parameter), one name has one unit, and the columns hold what the orbit
computed directly holds (theory §10, §11: periods in 1/Omega, velocities in L Omega)."""

import math
import re
from pathlib import Path

import pytest

from impactbar import find_orbit, physical
from impactbar.cli import main
from impactbar.continuation.branch import BranchEvent
from impactbar.orbits.orbit import ORBIT_FIELDS
from impactbar.physical import tree
from impactbar.physical.outputs import OUTPUTS

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter.toml"
#: how a column of the dimensionless orbit says it is dimensionless where an output has its name
SUFFIX = "_dimensionless"


def _declared(column: str, parameter: str, fields) -> tuple[str, str, str | None]:
    """``(stem, unit, unit written in the name)`` of a column, from the declarations alone (a config
    key, an output, one of ``fields``: a complex one as its ``_real`` and ``_imag`` parts); fails
    for a column nothing declares."""
    m = re.fullmatch(r"(\S+) \((.+)\)", column)
    if m:  # a config key in the unit --to was given in
        key, unit = m.groups()
        assert tree.declared(key) is not None or key.startswith("parts."), column
        return key, unit, unit
    for o in OUTPUTS.values():
        for key, unit in ((o.shown_key, o.shown_unit), (o.key, o.unit)):
            if column == key:
                return o.name, unit, (unit if key != o.name else None)
    if column.endswith(SUFFIX) and column[:-len(SUFFIX)] in fields.names:
        return column[:-len(SUFFIX)], fields[column[:-len(SUFFIX)]].units, "1"
    if column in fields.names:
        return column, fields[column].units, None
    part = re.fullmatch(r"(\w+)_(real|imag)", column)
    if part and part[1] in fields.names and fields[part[1]].dtype == "c16":
        return part[1], fields[part[1]].units, None
    if column == parameter:  # the dimensionless continuation parameter, by its own name
        return column, "1", None
    raise AssertionError(f"column {column!r} is not declared (registry, tree or orbit fields)")


def _check_names(header: list[str], parameter: str, fields=ORBIT_FIELDS) -> None:
    """One name, one unit: a name that does not write its unit is not an output's name in another
    unit (a bare ``impact_velocity`` beside the registry's, in m/s), and two columns of one stem in
    different units each write their unit."""
    seen = {}
    for column in header:
        stem, unit, written = _declared(column, parameter, fields)
        if written is None and stem in OUTPUTS:
            assert OUTPUTS[stem].unit in ("", "1", unit), f"{column!r}: dimensionless, but the output " \
                f"{stem!r} is in {OUTPUTS[stem].unit}"
        for other, (other_unit, other_written) in seen.get(stem, {}).items():
            assert other_unit == unit or (written and other_written), f"{column!r} and {other!r}"
        seen.setdefault(stem, {})[column] = (unit, written)


def _read(path: Path) -> tuple[list[str], list[dict]]:
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    return header, [dict(zip(header, line.split(","), strict=True)) for line in lines[1:]]


def test_a_valve_drifters_branch(tmp_path):
    """The valve drifter continued in its delay: the columns are declared, and the last point is the
    orbit found directly at its delay."""
    assert main(["continue", "--preset", "hydraulic-drifter", "--parameter", "delay", "--to", "0.1",
                 "--max-points", "4", "--brute", "0", "--out", str(tmp_path)]) == 0
    header, rows = _read(tmp_path / "branch.csv")
    _check_names(header, "delay")
    events, _ = _read(tmp_path / "events.csv")
    _check_names(events, "delay", BranchEvent.fields)
    d = physical.drifter_preset("hydraulic-drifter")
    last = rows[-1]
    drive = d.drive()
    o = find_orbit(d.model(), drive.__class__(drive.stroke, drive.ret, drive.switch_out,
                                              float(last["delay"])))
    assert float(last["impact_velocity_dimensionless"]) == pytest.approx(o.impact_velocity, rel=1e-8)
    assert float(last["period_dimensionless"]) == pytest.approx(o.period, rel=1e-8)
    assert last["stable"] == str(o.stable)


def test_a_circuit_drifters_branch(tmp_path):
    """The circuit drifter of the example continued in its pump flow: the columns are declared, the
    first point is the operating point's orbit, and its dimensionless period and impact velocity,
    scaled by 1/Omega and L Omega, give the SI columns' blow frequency and impact energy."""
    assert main(["continue", str(EXAMPLE), "--parameter", "supply.pump_flow", "--to", "72 L/min",
                 "--max-points", "3", "--out", str(tmp_path)]) == 0
    header, rows = _read(tmp_path / "branch.csv")
    d = physical.load(EXAMPLE)
    parameter, _ = d.to_dimensionless("supply.pump_flow", "72 L/min")
    _check_names(header, parameter)
    events, _ = _read(tmp_path / "events.csv")
    _check_names(events, parameter, BranchEvent.fields)
    first = rows[0]
    orbit = d.orbit().orbit
    assert float(first["impact_velocity_dimensionless"]) == pytest.approx(orbit.impact_velocity, rel=1e-9)
    period_s = float(first["period_dimensionless"]) / d.omega_rad_s
    assert float(first["blow_frequency_Hz"]) == pytest.approx(1.0 / period_s, rel=1e-9)
    v = float(first["impact_velocity_dimensionless"]) * d.bar.length_m * d.omega_rad_s
    assert float(first["impact_energy_J"]) == pytest.approx(0.5 * d.bar.mass_kg * v * v, rel=1e-9)
    assert math.isclose(float(first["supply.pump_flow (L/min)"]), 70.0, rel_tol=1e-9)


def test_the_check_sees_a_bare_name_in_two_units():
    """The check fails on the header a drifter's branch.csv had: a bare ``impact_velocity`` (the
    dimensionless orbit's) where the registry's ``impact_velocity`` is in m/s, and an undeclared
    ``period``."""
    with pytest.raises(AssertionError, match="impact_velocity"):
        _check_names(["delay", "impact_velocity", "stable"], "delay")
    with pytest.raises(AssertionError, match="period"):
        _check_names(["delay", "period"], "delay")
