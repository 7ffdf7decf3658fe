"""The drive's narrow base: :class:`impactbar.Drive` holds the hooks every solver calls, what a class
declares in one :class:`~impactbar.DriveTraits`, its parameters in one ``params`` object and its
optional numerics in one :class:`~impactbar.drives.DriveAbilities` that the solvers look up where
they dispatch on them. A drive written here with the required hooks alone finds its orbit (checked
against the rigid piston's closed form, theory §10); abilities a drive written here returns are
found by the solvers (its own orbit problem, its compiled loop handed the driver's data of its
levels); a class written the old way (a ``state_size`` of its own, no traits) is refused."""

import dataclasses
from dataclasses import dataclass

import numpy as np
import pytest
from test_new_drive import TwoLevel, rigid_closed_form  # (the test's directory is on the path)

from impactbar import BarModel, Drive, DriveTraits, InitialState, find_orbit, simulate
from impactbar.drives import CompiledLoop, DriveAbilities, OwnFlight, Quadratures
from impactbar.drives.base import FlightKernel
from impactbar.orbits.driven import ShootingProblem
from impactbar.parameters import parameters, with_parameter


@dataclass(frozen=True)
class Toggle(Drive):
    """``+stroke`` toward the stop until an impact, then ``-ret`` until the gap rises through ``x1``:
    the five required hooks and nothing else (the functions of ``test_new_drive.TwoLevel``)."""

    stroke: float
    ret: float
    x1: float

    start = TwoLevel.start
    force = TwoLevel.force
    events = TwoLevel.events
    jump = TwoLevel.jump
    impact = TwoLevel.impact


def members(cls):
    return sorted(n for n in dir(cls) if not (n.startswith("__") and n.endswith("__"))
                  and n != "_abc_impl" and n not in dir(object))


def test_the_base_holds_the_hooks_the_traits_the_params_and_the_abilities():
    assert set(Drive.__abstractmethods__) == {"start", "force", "events", "jump", "impact"}
    assert members(Drive) == ["abilities", "events", "family", "force", "impact", "jump", "mode_name",
                              "params", "rate", "start", "traits", "with_"]


@pytest.mark.parametrize("a_s, a_r, x1, R", [(1.0, 1.0, 1.0, 0.215), (2.0, 0.5, 0.3, 0.6)])
def test_a_drive_with_the_required_hooks_alone_finds_its_orbit(a_s, a_r, x1, R):
    drive = Toggle(a_s, a_r, x1)
    assert drive.abilities == DriveAbilities() and drive.traits == DriveTraits()
    assert drive.traits.piecewise_constant and drive.params.parameter_table() == ()
    o = find_orbit(BarModel(s=10.0, d=0.0, R=R, n_modes=0), drive)
    v, T = rigid_closed_form(a_s, a_r, x1, R)
    assert o.impacts == 1 and o.admissibility == "admissible"
    assert o.impact_velocity == pytest.approx(v, rel=1e-12)
    assert o.period == pytest.approx(T, rel=1e-12)
    assert o.multipliers[0] == pytest.approx(R * R, abs=1e-8)


@dataclass(frozen=True)
class OwnProblem(Toggle):
    """:class:`Toggle` with an orbit problem of its own (the generic shooting problem, counted)."""

    calls: list = dataclasses.field(default_factory=list, compare=False, repr=False)

    traits = DriveTraits(parameters=("stroke", "ret", "x1"),
                         parameter_ranges={"x1": {"low": 0.0, "low_open": True, "description": "switch"}})

    @property
    def abilities(self):
        return DriveAbilities(orbit_problem=self._problem)

    def _problem(self, model, impacts, constant_load):
        self.calls.append((impacts, constant_load(0.5).p0))
        return ShootingProblem(model, self, impacts)


def test_an_orbit_problem_among_the_abilities_is_the_orbit_solvers():
    model = BarModel(s=10.0, d=0.0, R=0.3, n_modes=0)
    drive = OwnProblem(1.0, 1.0, 1.0)
    o = find_orbit(model, drive)
    assert drive.calls and drive.calls[0] == (1, 0.5)
    v, T = rigid_closed_form(1.0, 1.0, 1.0, 0.3)
    assert o.impact_velocity == pytest.approx(v, rel=1e-12) and o.period == pytest.approx(T, rel=1e-12)
    # its parameters through the protocol: the records of its traits, copies by its with_
    p = parameters(model, drive)["x1"]
    assert (p.value, p.range_text, p.description) == (1.0, "(0, inf)", "switch")
    _, moved = with_parameter(model, drive, "x1", 2.0)
    assert moved == OwnProblem(1.0, 1.0, 2.0)
    with pytest.raises(ValueError, match="x1 must be in"):
        with_parameter(model, drive, "x1", -1.0)


@dataclass(frozen=True)
class Looped(Toggle):
    """:class:`Toggle` with a compiled loop that records what the simulator hands it and declines
    (``None``: the simulator's loop in Python runs)."""

    seen: list = dataclasses.field(default_factory=list, compare=False, repr=False)

    @property
    def abilities(self):
        return DriveAbilities(compiled_loop=CompiledLoop((self.stroke, -self.ret), self._build))

    def _build(self, model, kernel):
        self.seen.append(kernel)


@pytest.mark.parametrize("n_modes", [0, 2])
def test_a_compiled_loop_among_the_abilities_is_handed_its_levels(n_modes):
    model = BarModel(s=10.0, d=0.05, R=0.3, n_modes=n_modes)
    start = InitialState.rigid(-0.5, 0.3, n_modes)
    looped = Looped(1.0, 0.5, 0.8)
    run = simulate(model, looped, start, 30.0)
    ref = simulate(model, Toggle(1.0, 0.5, 0.8), start, 30.0)
    assert len(looped.seen) == 1 and isinstance(looped.seen[0], FlightKernel)
    assert len(looped.seen[0].loads) == 2 and looped.seen[0].rigid == (n_modes == 0)
    assert run.n_impacts == ref.n_impacts > 5
    np.testing.assert_array_equal(run.impact_times, ref.impact_times)  # (the same loop: to the bit)


def test_the_circuit_declares_its_state_and_its_own_numerics():
    from impactbar.drives.circuit import Chambers, HydraulicCircuitDrive, Oil, Supply, Valve

    drive = HydraulicCircuitDrive(Chambers(0.5, 0.4, 0.2), Valve(0.048, 2.0, 0.05),
                                  Supply(None, pressure=2.0, hose_volume=1.0, front_coefficient=2.0,
                                         tank_pressure=0.03), Oil(140.0, 0.01))
    traits, own = drive.traits, drive.abilities
    assert traits.state_size == 4 and not traits.piecewise_constant and traits.integrator.method == "CVODE"
    assert isinstance(own.flight, OwnFlight) and own.flight.variational and own.end_flight is not None
    assert isinstance(own.quadratures, Quadratures) and own.quadratures.count == drive.layout.n_energy
    assert own.quadratures.piston_work == drive.layout.energy["piston"]
    assert own.compiled_loop is None and own.orbit_problem is None and own.border_tests is not None
    table = {p.name: p.value for p in drive.params.parameter_table()}
    assert table["pump_flow"] is None and table["switching_time"] == 0.05  # (a held supply has no pump)


def test_a_drive_declared_the_old_way_is_refused():
    with pytest.raises(ValueError, match=r"Old\.state_size: a drive declares it in traits = DriveTraits"):
        class Old(Toggle):
            state_size = 1

    with pytest.raises(ValueError, match=r"Own\.orbit_problem: a drive declares it in an abilities property"):
        class Own(Toggle):
            def orbit_problem(self, model, impacts, constant_load):
                return None

    class New(Toggle):  # (the new way: declared in its traits)
        traits = DriveTraits(state_size=1, state_names=("p",))

    assert New.traits.state_size == 1


@pytest.mark.parametrize("kwargs, match", [
    ({"state_size": -1}, "state_size must be an integer >= 0"),
    ({"state_size": 1.5}, "state_size must be an integer >= 0"),
    ({"parameters": "p"}, "parameters must be a sequence of strings"),
    ({"state_size": 2, "state_names": ("a",)}, "state_names must name the 2 states"),
    ({"kind": 3}, "kind must be a string"),
])
def test_traits_refuse_bad_declarations(kwargs, match):
    with pytest.raises(ValueError, match=match):
        DriveTraits(**kwargs)
