"""The parameter protocol (:mod:`impactbar.parameters`): a load with a parameter declared in this file
alone is listed, its orbit found and simulated, continued and swept with no line in continuation/,
sweeps/ or cli/; a drive's and an impact law's parameters go through the same functions; refusals
name the parameter."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import impactbar as ib
from impactbar import BarModel, CosineLoad, Parameter, PositionSwitchedDrive
from impactbar._shared.schema import Field, Schema
from impactbar._shared.validate import check_real
from impactbar.loads import LOADS, LoadTraits, register_load
from impactbar.parameters import check_continuable, parameter_value, parameters, with_parameter

TWO_PI = 2.0 * math.pi


class RatioCosineLoad(CosineLoad):
    """``p0 (1 + ratio cos(k t))``: a cosine load whose amplitude is given relative to its mean, a
    parameter, ``ratio``, that no other part of the package declares."""

    traits = LoadTraits(
        kind="ratio-cosine", description="p0 (1 + ratio cos(k t))",
        parameters=Schema(Field("p0", "mean load"), Field("ratio", "amplitude over mean load"),
                          Field("k", "order of the harmonic, >= 1", "", dtype="i8")),
        continuation_parameters=("p0", "ratio"),
        parameter_ranges={"ratio": {"low": 0.0, "low_open": True}, "k": {"low": 1, "high": 4096}})

    def __init__(self, p0, ratio, k=1):
        ratio = check_real("ratio", ratio, lo=0.0, lo_open=True)
        super().__init__(p0, p0 * ratio, k)
        self._set(ratio=ratio)


MODEL = BarModel(s=10.0, d=0.05, R=0.5, n_modes=4)
LOAD = RatioCosineLoad(0.3, 1.0 / 0.3)  # pk = 1


def _start():
    """The orbit on the side of the stable one (as tests/continuation starts its branch in p0)."""
    return next(o for o in ib.periodic_orbits(MODEL, LOAD) if math.cos(o.phase) < 0)


def _nearest(orbits, phase):
    return min(orbits, key=lambda o: abs(math.remainder(o.phase - phase, TWO_PI)))


def test_the_new_parameter_is_listed_with_its_declaration():
    table = parameters(MODEL, LOAD)
    assert list(table) == ["s", "d", "R", "n_modes", "p0", "ratio", "k"]
    p = table["ratio"]
    assert isinstance(p, Parameter)
    assert p.value == pytest.approx(1.0 / 0.3) and p.unit == "" and p.continuable and not p.integer
    assert (p.low, p.low_open, p.high) == (0.0, True, math.inf)
    assert p.description == "amplitude over mean load"
    assert not table["k"].continuable and table["k"].integer
    assert parameter_value(MODEL, LOAD, "ratio") == p.value
    model, load = with_parameter(MODEL, LOAD, "ratio", 2.0)
    assert model is MODEL and type(load) is RatioCosineLoad
    assert load.ratio == 2.0 and load.pk == pytest.approx(0.6)


def test_the_new_load_is_simulated_and_its_orbit_found():
    """``find_orbit`` under the new load lands on an orbit :func:`impactbar.periodic_orbits` lists;
    ``simulate`` from it repeats it, and runs as under the cosine load of the same numbers, to the
    bit."""
    o = ib.find_orbit(MODEL, LOAD)
    ref = _nearest(ib.periodic_orbits(MODEL, LOAD), o.phase)
    assert o.phase == pytest.approx(ref.phase, abs=1e-8)
    assert o.impact_velocity == pytest.approx(ref.impact_velocity, abs=1e-8)
    t0 = float(o.impact_times[0])
    start = ib.InitialState(*o.modal_state_after_impact)
    run = ib.simulate(MODEL, LOAD, start, t0 + 3.5 * o.period, t0=t0)
    assert run.n_impacts == 3
    np.testing.assert_allclose(run.impact_times, t0 + o.period * np.arange(1, 4), rtol=0, atol=1e-7)
    np.testing.assert_allclose(run.impact_velocities, o.impact_velocity, rtol=1e-7)
    plain = ib.simulate(MODEL, CosineLoad(LOAD.p0, LOAD.pk, LOAD.k), start, t0 + 3.5 * o.period, t0=t0)
    assert np.array_equal(plain.impact_times, run.impact_times)
    assert np.array_equal(plain.impact_velocities, run.impact_velocities)


def test_the_new_parameter_is_continued():
    """A branch in ``ratio``; each point against the orbits found afresh at that ratio (1e-8)."""
    start = _start()
    branch = ib.continue_orbit(start, "ratio", to=2.5, max_points=60)
    assert branch.parameter == "ratio" and len(branch) > 3
    assert branch.values[-1] == pytest.approx(2.5, abs=1e-12) or branch.status != "reached"
    for v, o in list(zip(branch.values, branch.orbits, strict=True))[:: max(1, len(branch) // 4)]:
        assert type(o.load) is RatioCosineLoad and o.load.ratio == v
        ref = _nearest(ib.periodic_orbits(MODEL, RatioCosineLoad(0.3, v)), o.phase)
        assert o.phase == pytest.approx(ref.phase, abs=1e-8)
        assert o.impact_velocity == pytest.approx(ref.impact_velocity, abs=1e-8)


def test_the_new_parameter_is_swept(tmp_path):
    """A small sweep in ``ratio`` through the sweeps' Python API, the load registered by its kind;
    each point's orbits against :func:`impactbar.periodic_orbits` at that ratio."""
    pytest.importorskip("xarray")
    pytest.importorskip("zarr")
    from impactbar.sweeps import open_sweep, parse_spec, run_sweep

    register_load(RatioCosineLoad)
    try:
        spec = parse_spec({"task": "orbits", "model": {"s": 10.0, "d": 0.05, "R": 0.5, "n_modes": 2},
                           "load": {"kind": "ratio-cosine", "p0": 0.3, "ratio": 3.0, "k": 1},
                           "axes": {"ratio": {"values": [2.0, 3.0, 4.0]}}})
        model, load = spec.point((1,))
        assert type(load) is RatioCosineLoad and load.ratio == 3.0
        run_sweep(spec, tmp_path / "ratio.zarr", executor="threads", n_workers=1, progress=False)
        ds = open_sweep(tmp_path / "ratio.zarr")
        assert ds["ratio"].values.tolist() == [2.0, 3.0, 4.0]
        for i, ratio in enumerate((2.0, 3.0, 4.0)):
            refs = ib.periodic_orbits(BarModel(10.0, 0.05, 0.5, 2), RatioCosineLoad(0.3, ratio))
            n = int(ds["n_orbits"].values[i])
            assert n == len(refs) > 0
            phases = np.sort(ds["phase"].values[i][:n])
            np.testing.assert_allclose(phases, np.sort([o.phase for o in refs]), atol=1e-8)
        with pytest.raises(ValueError, match=r"\[axes\] ratio = -1.0: ratio must be in \(0, inf\)"):
            parse_spec({**spec.to_dict(), "axes": {"ratio": {"values": [-1.0]}}})
    finally:
        LOADS.pop("ratio-cosine", None)


def test_register_load_refuses_a_taken_kind_and_a_non_load():
    class Other(RatioCosineLoad):
        traits = LoadTraits(kind="cosine")

    with pytest.raises(ValueError, match="kind 'cosine' is already the load CosineLoad"):
        register_load(Other)
    with pytest.raises(ValueError, match="subclass of Load"):
        register_load(int)


def test_a_drive_and_a_law_go_through_the_same_functions():
    valve = PositionSwitchedDrive(stroke=1.0, ret=0.5, switch_out=1.0)
    table = parameters(MODEL, valve)
    assert [n for n in table if n not in ("s", "d", "R", "n_modes")] == list(valve.traits.parameters)
    assert parameter_value(MODEL, valve, "switch_out") == 1.0
    model, drive = with_parameter(MODEL, valve, "switch_out", 0.5)
    assert model is MODEL and drive == PositionSwitchedDrive(stroke=1.0, ret=0.5, switch_out=0.5)
    with pytest.raises(ValueError, match=r"stroke must be in \(0, 1e\+100\]; got -1"):
        with_parameter(MODEL, valve, "stroke", -1.0)

    law = ib.RodRock(segments=[ib.RodSegment(length=2.0, impedance=2.0)],
                     rock=ib.BilinearRock(k=20.0, k_u=200.0))
    rock = MODEL.with_(impact=law)
    table = parameters(rock, LOAD)
    assert {"rock.k", "rock.k_u", "bit_mass", "feed", "segment0.length"} <= set(table)
    model, load = with_parameter(rock, LOAD, "rock.k", 30.0)
    assert model.law.rock.k == 30.0 and load is LOAD
    with pytest.raises(ValueError, match=r"feed must be in \[0, inf\); got -1"):
        with_parameter(rock, LOAD, "feed", -1.0)
    # a segment's length is smooth on the exact blows, not on the lattice's cell grid
    assert check_continuable(rock.with_(impact=law.__class__(**{**_fields(law), "method": "exact"})),
                             LOAD, "segment0.length").value == 2.0
    lattice = rock.with_(impact=law.__class__(**{**_fields(law), "method": "lattice"}))
    assert not parameters(lattice, LOAD)["segment0.length"].continuable
    with pytest.raises(ValueError, match=r"segment0.length' \(.*\) cannot be continued: .*whole cells"):
        check_continuable(lattice, LOAD, "segment0.length")


def _fields(law):
    import dataclasses

    return {f.name: getattr(law, f.name) for f in dataclasses.fields(law) if f.init}


def test_refusals_name_the_parameter():
    with pytest.raises(ValueError, match=r"parameter must be one of \('s', 'd', 'R', 'n_modes', 'p0', "
                                         r"'ratio', 'k'\) \(of the BarModel and the RatioCosineLoad\); "
                                         r"got 'phase'"):
        with_parameter(MODEL, LOAD, "phase", 1.0)
    with pytest.raises(ValueError, match="got 'phase'"):
        parameter_value(MODEL, LOAD, "phase")
    with pytest.raises(ValueError, match="None is not a part of a problem"):
        parameters(MODEL, None)
    with pytest.raises(ValueError, match=r"ratio must be in \(0, inf\); got 0"):
        with_parameter(MODEL, LOAD, "ratio", 0.0)
    with pytest.raises(ValueError, match=r"R must be in \[0, 1\]; got 1.5"):
        with_parameter(MODEL, LOAD, "R", 1.5)
    with pytest.raises(ValueError, match=r"k must be an integer in \[1, 4096\]"):
        with_parameter(MODEL, LOAD, "k", 0)
    with pytest.raises(ValueError, match=r"'n_modes' \(flexible modes kept\) cannot be continued: it "
                                         "takes integer values"):
        check_continuable(MODEL, LOAD, "n_modes")
    start = _start()
    with pytest.raises(ValueError, match="parameter must be one of .*'ratio'.*got 'switch_out'"):
        ib.continue_orbit(start, "switch_out", to=2.0)


def test_the_continuation_views_are_the_protocol():
    """The names :mod:`impactbar.continuation` kept (``parameter_value``, ``with_parameter``) read
    and change a parameter declared in this file as the protocol does."""
    from impactbar.continuation import parameter_value as pv
    from impactbar.continuation import with_parameter as wp

    assert pv(MODEL, LOAD, "ratio") == parameter_value(MODEL, LOAD, "ratio")
    assert wp(MODEL, LOAD, "ratio", 2.0) == with_parameter(MODEL, LOAD, "ratio", 2.0)
    with pytest.raises(ValueError, match="parameter must be one of"):
        pv(MODEL, LOAD, "k")  # an integer: swept, not continued


def test_the_command_line_takes_any_parameter_the_parts_declare(tmp_path, capsys):
    """``impactbar continue --parameter`` has no list of its own: a name no part declares is refused
    with the protocol's list, before any orbit is sought; an integer one is refused as not
    continuable."""
    from impactbar.cli import main

    out = str(tmp_path / "c")
    assert main(["continue", "--parameter", "stroke", "--to", "0.8", "--out", out]) == 2
    err = capsys.readouterr().err
    assert "--parameter stroke: parameter must be one of ('s', 'd', 'R', 'n_modes', 'p0', 'pk', 'k')" in err
    assert main(["continue", "--parameter", "n_modes", "--to", "3", "--out", out]) == 2
    assert "'n_modes' (flexible modes kept) cannot be continued" in capsys.readouterr().err


def test_the_si_names_map_onto_the_circuit_drives_parameters():
    """Each config key in SI (:data:`impactbar.physical.circuit.SI_PARAMETERS`, the one table from SI
    names to dimensionless ones) names a parameter the circuit drive declares, and the protocol sets
    the value :meth:`CircuitDrifter.to_dimensionless` gives (the rock's keys need a drill string)."""
    pytest.importorskip("pint")
    from impactbar.physical.circuit import ROCK_SI_PARAMETERS, SI_PARAMETERS, circuit_preset

    drifter = circuit_preset("circuit-drifter")
    model, drive = drifter.model(), drifter.drive()
    table = parameters(model, drive)
    for key, (name, _unit, example) in SI_PARAMETERS.items():
        if key in ROCK_SI_PARAMETERS:
            continue
        assert name in table, key
        parameter, value = drifter.to_dimensionless(key, example.strip("'"))
        assert parameter == name
        if table[name].value is None or key == "chambers.front_area":
            continue  # (a field the preset leaves unset; the front area sets a ratio of areas)
        _, changed = with_parameter(model, drive, name, value)
        assert parameter_value(model, changed, name) == pytest.approx(value, rel=1e-12)
    # a relief valve that never opens: an infinite cracking pressure passes the record's check and
    # the supply's constructor takes it
    _, no_relief = with_parameter(model, drive, "relief_pressure", math.inf)
    assert parameter_value(model, no_relief, "relief_pressure") == math.inf
    with pytest.raises(ValueError, match="precharge must be"):
        with_parameter(model, drive, "precharge", math.inf)


ROD = ib.RodRock(segments=[ib.RodSegment(length=2.0, impedance=2.0),
                           ib.RodSegment(length=1.0, impedance=1.0)], rock=ib.BilinearRock(k=20.0, k_u=200.0))


def test_a_set_of_changes_is_checked_as_a_set():
    """:func:`with_parameters` applies every change, then validates the result once: the order of
    the changes does not matter, and a set whose result is refused is refused whatever its order."""
    from impactbar.parameters import with_parameters

    rock = MODEL.with_(impact=ROD)
    for changes in ({"rock.k": 400.0, "rock.k_u": 800.0}, {"rock.k_u": 800.0, "rock.k": 400.0}):
        model, load = with_parameters(rock, LOAD, changes)
        assert model.law.rock == ib.BilinearRock(k=400.0, k_u=800.0) and load is LOAD
    for changes in ({"rock.k": 5.0, "rock.k_u": 10.0}, {"rock.k_u": 10.0, "rock.k": 5.0}):
        assert with_parameters(rock, LOAD, changes)[0].law.rock == ib.BilinearRock(k=5.0, k_u=10.0)
    for changes in ({"rock.k": 400.0, "rock.k_u": 300.0}, {"rock.k_u": 300.0, "rock.k": 400.0}):
        with pytest.raises(ValueError, match="k_u"):
            with_parameters(rock, LOAD, changes)
    # the bar's fields and the law's together, and a part's static range still refused at once
    model, _ = with_parameters(rock, LOAD, {"segment1.length": 3.0, "R": 0.25, "rock.k": 30.0})
    assert (model.R, model.law.segments[1].length, model.law.rock.k) == (0.25, 3.0, 30.0)
    with pytest.raises(ValueError, match=r"R must be in \[0, 1\]; got 2"):
        with_parameters(rock, LOAD, {"rock.k": 30.0, "R": 2.0})


def test_a_circuits_relief_and_pre_charge_change_together():
    """The pre-charge must stay below the relief pressure: both lowered at once is accepted in
    either order (the relief was checked alone against the old pre-charge)."""
    pytest.importorskip("pint")
    from impactbar.parameters import with_parameters
    from impactbar.physical.circuit import circuit_preset

    drifter = circuit_preset("circuit-drifter")
    model, drive = drifter.model(), drifter.drive()
    assert parameter_value(model, drive, "precharge") > 0.5
    for changes in ({"relief_pressure": 0.5, "precharge": 0.25}, {"precharge": 0.25, "relief_pressure": 0.5}):
        _, changed = with_parameters(model, drive, changes)
        assert (parameter_value(model, changed, "relief_pressure"),
                parameter_value(model, changed, "precharge")) == (0.5, 0.25)
    with pytest.raises(ValueError, match="precharge must be below the relief pressure 0.5; got 0.6"):
        with_parameters(model, drive, {"precharge": 0.6, "relief_pressure": 0.5})


def _problems():
    from impactbar.physical.circuit import circuit_preset

    drifter = circuit_preset("circuit-drifter")
    return [(MODEL, LOAD), (MODEL.with_(impact=ROD), ib.SquareWaveLoad(0.5, 1.5)),
            (MODEL, PositionSwitchedDrive(stroke=1.0, ret=0.5, switch_out=1.0)),
            (drifter.model(), drifter.drive())]


_EXTREME = (5e-324, -5e-324, 1e-310, 1e-300, 1e-160, 1e-100, 1e-20, 0.0, -0.0, 1e100, 1e300,
            1.7976931348623157e308, -1.7976931348623157e308, math.inf, -math.inf, math.nan)


def _set_and_read_back(model, forcing, name, value):
    """Either the changed problem's parameters read back, or a one-line ``ValueError``."""
    try:
        changed = with_parameter(model, forcing, name, value)
    except ValueError as exc:
        assert "\n" not in str(exc), str(exc)
        return
    table = parameters(*changed)
    assert table[name].value == value or table[name].value == pytest.approx(value, rel=1e-12)
    assert parameter_value(*changed, name) == table[name].value


def test_extreme_values_give_a_problem_or_a_one_line_error():
    """Every parameter of four problems set to each extreme float gives either a problem whose
    parameters read back, or a one-line ``ValueError`` (a rod segment of 5e-324 piston lengths,
    accepted, made reading the table back divide by zero)."""
    pytest.importorskip("pint")
    for model, forcing in _problems():
        for name, p in parameters(model, forcing).items():
            for value in _EXTREME:
                _set_and_read_back(model, forcing, name, int(value) if p.integer and math.isfinite(value)
                                   else value)
    with pytest.raises(ValueError, match=r"segment0.length must be in \[1e-100, 1e\+100\]; got 5e-324"):
        with_parameter(MODEL.with_(impact=ROD), LOAD, "segment0.length", 5e-324)
    with pytest.raises(ValueError, match=r"^s must be in \(0, inf\), not subnormal .*; got 5e-324$"):
        with_parameter(MODEL, LOAD, "s", 5e-324)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problem=st.integers(0, 3), index=st.integers(0, 64), value=st.floats())
def test_any_float_gives_a_problem_or_a_one_line_error(problem, index, value):
    """As above for any float (hypothesis)."""
    pytest.importorskip("pint")
    model, forcing = _problems()[problem]
    names = [n for n, p in parameters(model, forcing).items() if not p.integer]
    _set_and_read_back(model, forcing, names[index % len(names)], value)
