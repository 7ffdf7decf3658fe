"""A part added to the drifter's oil circuit, defined in this file alone: a return line between the
valve's return port and the tank (a volume of oil with a pressure state, a gas accumulator on it and
an orifice to the tank), given to ``HydraulicCircuitDrive(..., extra_parts=(line,))`` as network
records only (no edit of the drive or of a kernel).

- The drive's layout, mode and events come from the composed network: the line's pressure a state
  after ``p_s``, its compression and gas work two energy terms, its accumulator a flag of the mode.
- ``simulate``: the energy account closes (the pump's work = the piston's, the openings', the tank's,
  the oil's compression and the gas's, the line's terms in their terms).
- ``find_orbit``: an admissible orbit whose restart repeats it (the rigid piston, and two flexible
  modes); over one period from its state the
  line's equations written out here with numpy, integrated by scipy's ``solve_ivp`` flight by flight
  (the mode of each read from its states, the circuit's state carried from flight to flight),
  reproduce the orbit's state.
- The line tending to nothing (a small volume, no gas, a wide orifice): the orbit tends to the
  preset's, at first order in the orifice's ``1/K``.
- ``continue_orbit`` along the line's coefficient against ``find_orbit`` at the branch's end, and a
  small sweep of the line's volume.
- ``run_sweep`` over the line's volume (a ``[drive]`` table naming a factory of the drifter with the
  line, entered by ``register_drive(factory, kind=...)``): each point's orbit against a fresh
  ``find_orbit``.
- The coupled blows (the wave and the rod-rock laws) run a drive with extra parts: the energy account
  closes over a run with blows, the line's accumulator an event inside them or not.
"""

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from test_circuit_network import _numpy_field as numpy_return_field  # (the line's equations, with numpy)

from impactbar import BilinearRock, InitialState, RodRock, RodSegment, continue_orbit, find_orbit, simulate
from impactbar.drives import DRIVES, register_drive
from impactbar.drives.circuit import Accumulator, CircuitPart
from impactbar.drives.circuit import _network as NW
from impactbar.drives.circuit.composition import compose_parts
from impactbar.drives.circuit.layout import PRESET
from impactbar.drives.circuit.preset import PRESET_PARTS
from impactbar.physical import circuit_preset

RET = "return_accumulator"


@dataclasses.dataclass(frozen=True)
class ReturnLine(CircuitPart):
    """A return line: a node of oil volume ``volume`` between the valve's return port and the tank, a
    gas accumulator ``gas`` on it, drained to the tank through an orifice of ``coefficient``."""

    volume: float
    gas: Accumulator
    coefficient: float

    nodes = ("return",)
    symbols = ("p_ret",)
    energies = (("return", "compression"), ("return_gas", "accumulator"))
    events = (RET,)
    ports = {"valve_return": "return"}
    parameters = {"return_volume": "volume", "return_coefficient": "coefficient"}

    def records(self, slots, oil):
        n, en = slots.nodes["return"], slots.energy
        return [NW.record(NW.NODE, id=n, volume=self.volume, beta=oil.bulk_modulus,
                          compression_energy=en["return"]),
                *self.gas.records(n, holding=slots.flags[RET], watched=self.gas.volume > 0,
                                  energy=en["return_gas"], event=slots.events[RET]),
                NW.record(NW.ORIFICE, source=n, target=slots.nodes["tank"], coefficient=self.coefficient,
                          ptr2=oil.transition_pressure ** 2, energy=en["orifices"])]


LINE = ReturnLine(volume=0.3, gas=Accumulator(precharge=0.08, volume=0.5, polytropic_exponent=1.3),
                  coefficient=1.2)


@pytest.fixture(scope="module")
def drifter():
    return circuit_preset("circuit-drifter")


@pytest.fixture(scope="module")
def model(drifter):
    return drifter.model().with_(n_modes=0)


@pytest.fixture(scope="module")
def drive(drifter):
    return dataclasses.replace(drifter.drive(), extra_parts=(LINE,))


@pytest.fixture(scope="module")
def orbit(model, drive):
    return find_orbit(model, drive)


def _restart(orbit, periods):
    z, y = orbit.drive_states[0], np.asarray(orbit.states_after_impact[0])
    M = orbit.model.n_modes + 1
    drive = dataclasses.replace(orbit.drive, start_pressures=tuple(z))
    return simulate(orbit.model, drive, InitialState(y[:M], y[M:]), periods * orbit.period)


def test_the_layout_mode_and_events_come_from_the_network(drifter, model, drive):
    L = drive.layout
    assert drifter.drive().layout is PRESET
    assert L.states == ("front", "rear", "supply", "return", "spool")
    assert L.state_names == ("p_f", "p_r", "p_s", "p_ret", "x_v")
    assert L.energies == PRESET.energies + ("return", "return_gas")
    assert (drive.state_size, drive.n_quadratures) == (5, 10)
    assert {"return_volume", "return_coefficient"} <= set(drive.parameters)
    start = drive.start(model, np.zeros(1), np.zeros(1))
    assert len(start.mode) == 5 and start.z[L["return"]] == drive.supply.tank_pressure
    assert start.mode[4] == 0  # (the tank's pressure below the line's pre-charge: the gas holds no oil)
    names = [e.name for e in drive.events((1, 0, 1, 0, 1))]
    assert RET in names
    # the event's flag toggled by its jump, the rest kept
    ev = next(e for e in drive.events((1, 0, 1, 0, 1)) if e.name == RET)
    assert drive.jump((1, 0, 1, 0, 1), start.z, ev, 0.0, np.zeros(1), np.zeros(1)).mode == (1, 0, 1, 0, 0)
    assert drive.with_(return_volume=0.7).extra_parts[0].volume == 0.7
    assert drive.value("return_coefficient") == LINE.coefficient
    with pytest.raises(ValueError, match="extra_parts must be CircuitPart"):
        dataclasses.replace(drive, extra_parts=("line",))
    with pytest.raises(ValueError, match="one part each"):
        compose_parts((LINE, LINE), PRESET_PARTS)


def test_simulate_closes_the_energy_account(model, drive):
    run = simulate(model, drive, InitialState.rigid(0.0, 0.0), 20.0)
    assert run.n_impacts > 10
    acc = drive.energy(run)
    assert abs(acc["relative_residual"]) < 1e-10
    total = sum(p.energies() for p in run.pieces if hasattr(p, "energies"))
    at = drive.layout.energy
    oil = sum(total[at[k]] for k in ("front", "rear", "supply", "return"))
    assert acc["compression"] == pytest.approx(oil, rel=1e-14)
    assert acc["accumulator"] == pytest.approx(total[at["gas"]] + total[at["return_gas"]], rel=1e-14)
    assert total[at["return_gas"]] != 0.0  # (the line's gas takes and gives oil)
    balance = acc["piston"] + acc["orifices"] + acc["tank"] + acc["compression"] + acc["accumulator"]
    assert balance == pytest.approx(acc["pump"], rel=1e-10)


def test_the_orbit_is_admissible_its_restart_repeats_it_and_its_account_closes(orbit):
    assert orbit.admissible and orbit.stable
    run = _restart(orbit, 20.5)
    assert run.n_impacts == 20
    assert np.allclose(np.diff(run.impact_times), orbit.period, rtol=1e-8)
    assert np.allclose(run.impact_velocities, orbit.impact_velocity, rtol=1e-8)
    one = _restart(orbit, 1.0)
    acc = orbit.drive.energy(one)
    assert abs(acc["relative_residual"]) < 1e-8
    # the line's gas over a closed cycle: its work is a function of its state (zero to the tolerance)
    total = sum(p.energies() for p in one.pieces if hasattr(p, "energies"))
    assert abs(total[orbit.drive.layout.energy["return_gas"]]) < 1e-6 * acc["pump"]
    assert "return_accumulator" in orbit.drive.border_tests(one.pieces)


def test_a_flexible_piston_with_the_line(model, drive):
    """Two flexible modes: the account closes over a run, the orbit is admissible and its restart
    repeats it (the periods to 1e-7, the impact velocities to the flexible orbits' accuracy)."""
    flexible = model.with_(n_modes=2)
    run = simulate(flexible, drive, InitialState.rigid(0.0, 0.0, n_modes=2), 20.0)
    assert run.n_impacts > 10 and abs(drive.energy(run)["relative_residual"]) < 1e-10
    orbit = find_orbit(flexible, drive)
    assert orbit.admissible
    again = _restart(orbit, 5.5)
    assert again.n_impacts == 5
    assert np.allclose(np.diff(again.impact_times), orbit.period, rtol=1e-7)
    # (the impact velocities of the flexible restart drift within 1e-6: measured 2.4e-7 for the preset
    # drifter's own orbit, 8e-7 with the line)
    assert np.allclose(again.impact_velocities, orbit.impact_velocity, rtol=3e-6)
    assert abs(orbit.drive.energy(_restart(orbit, 1.0))["relative_residual"]) < 1e-8


def _numpy_field(drive, model, mode, y):
    """The drifter with the return line, its equations written out with numpy
    (``test_circuit_network._numpy_field``): ``y'`` of ``(q, q', p_f, p_r, p_s, p_ret, x_v, E)``, the
    energy integrands in the layout's order."""
    return numpy_return_field(drive, model, mode, drive.extra_parts[0], y)[0]


def test_one_period_of_the_numpy_equations_reproduces_the_orbit(orbit):
    """Flight by flight over one period from the orbit's state: each flight's mode read from its own
    states (the spool ramping or at rest, each pressure against its level at the flight's middle),
    the circuit's state carried from one flight's end to the next (the pressures and the spool are
    continuous through events and impacts), the bar's taken at each flight's start from the run (its
    impact map is not the circuit's); the energy terms summed."""
    drive, model = orbit.drive, orbit.model
    L = drive.layout
    run = _restart(orbit, 1.0)
    pieces = [p for p in run.pieces if hasattr(p, "energies") and p.t_end > p.t0]
    assert len(pieces) >= 3
    M = 1
    n = L.size(M)
    z = np.array(orbit.drive_states[0], dtype=float)
    E = np.zeros(L.n_energy)
    for p in pieces:
        xv0, xv1 = p.y[0, 2 * M + L["spool"]], p.y[-1, 2 * M + L["spool"]]
        moving = int(xv1 != xv0)
        target = int(xv1 > xv0) if moving else int(round(xv0))
        zm = p.drive_state(0.5 * (p.t0 + p.t_end))[:, 0]
        ps, pret = zm[L["supply"]], zm[L["return"]]
        mode = (target, moving, int(ps >= drive.accumulator.precharge),
                int(ps > drive.supply.relief_pressure), int(pret >= LINE.gas.precharge))
        y0 = np.concatenate((p.y[0, :2 * M], z, np.zeros(L.n_energy)))
        sol = solve_ivp(lambda t, y, mode=mode: _numpy_field(drive, model, mode, y), (p.t0, p.t_end), y0,
                        method="Radau", rtol=1e-11, atol=1e-13)
        assert sol.success
        z = sol.y[2 * M:n, -1]
        E += sol.y[n:, -1]
        assert np.allclose(sol.y[:2 * M, -1], p.y[-1, :2 * M], rtol=1e-6, atol=1e-8)
    assert np.allclose(z, orbit.drive_states[0], rtol=1e-6, atol=1e-8), z - orbit.drive_states[0]
    want = sum(p.energies() for p in pieces)
    assert np.allclose(E, want, rtol=1e-6, atol=1e-8 * abs(want[0]))


def test_a_vanishing_line_tends_to_the_preset(drifter, model):
    """A line of small volume, no gas, a wide orifice ``K``: the return port's pressure above the
    tank's by ``(Q / K)^2``; the orbit tends to the preset's (measured: period 1.0e-4 apart at
    ``K = 100``, 1.0e-5 at 1000)."""
    preset = find_orbit(model, drifter.drive())
    err = []
    for K in (1e2, 1e3):
        line = ReturnLine(volume=1e-3, gas=Accumulator(precharge=0.08, volume=0.0), coefficient=K)
        o = find_orbit(model, dataclasses.replace(drifter.drive(), extra_parts=(line,)))
        z, z0 = o.drive_states[0], preset.drive_states[0]
        L = o.drive.layout
        err.append(max(abs(o.period / preset.period - 1), abs(o.impact_velocity / preset.impact_velocity - 1),
                       *(abs(z[L[k]] / z0[PRESET[k]] - 1) for k in ("front", "rear", "supply"))))
    assert err[1] < 3e-5
    assert 5 < err[0] / err[1] < 20  # (first order in 1/K)


def test_continuation_along_the_lines_coefficient_and_a_sweep_of_its_volume(orbit):
    branch = continue_orbit(orbit, "return_coefficient", 0.8)
    assert str(branch.status) == "reached" and branch.values[-1] == pytest.approx(0.8)
    end = branch.orbits[-1]
    again = find_orbit(orbit.model, orbit.drive.with_(return_coefficient=0.8))
    assert end.period == pytest.approx(again.period, rel=1e-8)
    assert np.allclose(end.drive_states[0], again.drive_states[0], rtol=1e-7, atol=1e-9)
    # a small sweep of the line's volume: each orbit admissible, its account closed over a period
    for volume in (0.1, 1.0):
        o = find_orbit(orbit.model, orbit.drive.with_(return_volume=volume))
        assert o.admissible
        assert abs(o.drive.energy(_restart(o, 1.0))["relative_residual"]) < 1e-8


def test_the_coupled_blows_run_extra_parts(model, drive):
    rock = RodRock(segments=[RodSegment(length=2.0, impedance=1.0)],
                   rock=BilinearRock(k=0.63 * model.s ** 2, k_u=6.3 * model.s ** 2), feed=0.05)
    for law in ("wave", rock):
        run = simulate(model.with_(impact=law), drive, InitialState.rigid(-0.06, 0.0), 20.0)
        assert run.n_impacts >= 3 and len(run.impacts) == run.n_impacts
        assert abs(drive.energy(run)["relative_residual"]) < 1e-12
        assert drive.energy(run)["accumulator"] != 0.0  # (the line's gas and the supply's)


def drifter_with_line(volume=LINE.volume, coefficient=LINE.coefficient):
    """The preset drifter with the return line (``LINE``'s gas), its volume and coefficient given: a
    factory of the table of drives (its arguments a ``[drive]`` table's numbers)."""
    line = dataclasses.replace(LINE, volume=volume, coefficient=coefficient)
    return dataclasses.replace(circuit_preset("circuit-drifter").drive(), extra_parts=(line,))


@pytest.fixture
def factory_registered():
    register_drive(drifter_with_line, kind="drifter-return-line")
    yield
    DRIVES.pop("drifter-return-line", None)


def test_a_sweep_of_the_lines_volume(factory_registered, model, tmp_path):
    """A ``[drive]`` table naming the factory, an axis over the line's own parameter
    ``return_volume`` (the drive's ``with_``, not the factory's argument): each point's stored orbit
    against a fresh ``find_orbit`` of the drive built here."""
    pytest.importorskip("xarray")
    pytest.importorskip("zarr")
    from impactbar.sweeps import open_sweep, parse_spec, run_sweep

    volumes = (0.1, 1.0)
    doc = {"task": "orbits", "model": {"s": model.s, "d": model.d, "R": model.R, "n_modes": 0},
           "drive": {"kind": "drifter-return-line", "coefficient": 1.2},
           "axes": {"return_volume": {"values": list(volumes)}}, "orbits": {"max_orbits": 2}}
    spec = parse_spec(doc)
    assert parse_spec(spec.to_dict()) == spec
    assert spec.point((1,)) == (model, drifter_with_line(volume=1.0, coefficient=1.2))
    run_sweep(spec, tmp_path / "line.zarr", executor="threads", n_workers=1, progress=False)
    ds = open_sweep(tmp_path / "line.zarr")
    assert ds["return_volume"].values.tolist() == list(volumes) and not ds["failed"].values.any()
    for i, volume in enumerate(volumes):
        ref = find_orbit(model, drifter_with_line(volume=volume))
        assert int(ds["n_orbits"].values[i]) == 1
        assert ds["impact_velocity"].values[i, 0] == pytest.approx(ref.impact_velocity, rel=1e-8)
        assert bool(ds["stable"].values[i, 0]) == ref.stable
        assert bool(ds["admissible"].values[i, 0]) == ref.admissible
    # (the two volumes give orbits apart: the axis reached the line)
    assert abs(ds["impact_velocity"].values[0, 0] / ds["impact_velocity"].values[1, 0] - 1) > 1e-7

    # (the factory's argument is not a parameter of the drive: the axis takes the drive's names)
    with pytest.raises(ValueError, match=r"\[axes\] 'volume' is not a field .*'return_coefficient'"):
        parse_spec({**doc, "axes": {"volume": {"values": [0.5]}}})
    with pytest.raises(ValueError, match=r"^\[drive\] the drive 'drifter-return-line' takes keys of "
                                         r"drifter_with_line: .*'gas'"):
        parse_spec({**doc, "drive": {**doc["drive"], "gas": 0.5}})


def test_register_drive_checks_a_factory():
    with pytest.raises(ValueError, match="kind must be a non-empty string"):
        register_drive(drifter_with_line, kind="")
    with pytest.raises(ValueError, match="cls must be a function returning a Drive"):
        register_drive(ReturnLine, kind="x")
    with pytest.raises(ValueError, match="kind 'position-switched' is already the drive PositionSwitched"):
        register_drive(drifter_with_line, kind="position-switched")
    def the_line(volume):
        return dataclasses.replace(LINE, volume=volume)

    register_drive(the_line, kind="not-a-drive")
    try:
        from impactbar.sweeps.parts import drive_table

        with pytest.raises(ValueError, match=r"^\[drive\] kind 'not-a-drive': the_line must return a Drive; "
                                             r"got ReturnLine$"):
            drive_table({"kind": "not-a-drive", "volume": 0.5})
    finally:
        DRIVES.pop("not-a-drive")
