"""The preset drifter's oil circuit as one composition of parts (``impactbar.drives.circuit.preset``),
built by ``compose_parts`` as any extra part is.

- The composed network against the one the drive wired by hand before (frozen here: the parts'
  records with the node numbers front 0, rear 1, supply 2, tank 3 and the preset's energy and event
  slots written as literals): the same records in the same order, to the bit, in every mode, for the
  preset, a held supply, no accumulator, no relief valve, and with an extra part on the valve's
  return port.
- A part that replaces the preset's valve by name (``replaces = ("valve",)``): written here as the
  valve's record of another coefficient, its network and a run are those of the drive whose valve
  has that coefficient (to the bit); a replacing valve with a node of its own numbers it after the
  preset's, the tank after it; replacing a part the circuit does not have, or twice, or leaving the
  valve's return port taken with no part offering it, is refused by name.
"""

import dataclasses
import itertools

import numpy as np
import pytest

from impactbar import InitialState, simulate
from impactbar.drives.circuit import NODE, VALVE, Accumulator, CircuitPart, ReturnAccumulator, record
from impactbar.drives.circuit import _network as NW
from impactbar.drives.circuit.composition import compose_parts
from impactbar.drives.circuit.preset import PORTS, PRESET_NODES, PRESET_PARTS
from impactbar.physical import circuit_preset


@pytest.fixture(scope="module")
def drifter():
    return circuit_preset("circuit-drifter")


def _network_before(drive, mode, line=None):
    """The drive's network as ``HydraulicCircuitDrive._network`` wired it by hand before the preset
    was a composition of parts (frozen): ``line`` a return line on the valve's return port (node 3,
    the tank then node 4, its integrands 8 and 9, its event slot 3)."""
    target, moving, acc, rel = mode[:4]
    ch, va, su, oil, ac = drive.chambers, drive.valve, drive.supply, drive.oil, drive.accumulator
    front, rear, supply = 0, 1, 2
    tank, ret = (4, 3) if line is not None else (3, 3)
    n_energy, n_events = (10, 4) if line is not None else (8, 3)
    tau = va.switching_time
    recs = ch.records(front, rear, oil.bulk_modulus, front_energy=4, rear_energy=5)
    recs += su.records(supply, tank, front, oil, relief_open=bool(rel),
                       energies={"pump": 0, "orifices": 2, "tank": 3, "compression": 6}, relief_event=2)
    recs += va.records(supply, rear, ret, oil.transition_pressure,
                       rate=(1.0 if target else -1.0) / tau if moving else 0.0,
                       opening=(1 if target else -1) if moving else 0, energy=2, event=0)
    has_acc = ac is not None and ac.volume > 0 and not su.held
    gas = Accumulator(precharge=ac.precharge if ac is not None else 1.0, volume=ac.volume if has_acc else 0.0,
                      polytropic_exponent=ac.polytropic_exponent if ac is not None else 1.4)
    recs += gas.records(supply, holding=bool(acc), watched=has_acc, energy=7, event=1)
    if line is not None:
        lgas = Accumulator(line.precharge, line.gas_volume, line.polytropic_exponent)
        recs += [NW.record(NW.NODE, id=3, volume=line.volume, beta=oil.bulk_modulus, compression_energy=8),
                 *lgas.records(3, holding=bool(mode[4]), watched=line.gas_volume > 0.0, energy=9, event=3),
                 NW.record(NW.ORIFICE, source=3, target=tank, coefficient=line.flow_coefficient,
                           ptr2=oil.transition_pressure ** 2, energy=2)]
    return NW.compose(recs, 4 if line is not None else 3, n_energy, n_events, 1)


def _variants(drive):
    su = drive.supply
    return {"preset": drive,
            "held": dataclasses.replace(drive, supply=dataclasses.replace(su, pump_flow=None, pressure=1.5)),
            "no accumulator": dataclasses.replace(drive, accumulator=None),
            "no relief": dataclasses.replace(drive, supply=dataclasses.replace(su, relief_pressure=np.inf)),
            "slower ramp": drive.with_(switching_time=3.0 * drive.valve.switching_time)}


def _bits(a):
    return np.asarray(a, dtype=float).view(np.int64)


def test_the_preset_is_composed_of_its_parts_and_gives_the_network_wired_before(drifter):
    drive = drifter.drive()
    names = ["chambers", "supply", "valve", "accumulator", "relief"]
    assert [p.name for p in drive._composition.parts] == names and [p.name for p in PRESET_PARTS] == names
    assert PRESET_NODES == ("front", "rear", "supply", "tank") and PORTS == {"valve_return": "tank"}
    checked = 0
    for name, d in _variants(drive).items():
        assert d.layout == drive.layout and d._composition.events == ("ramp_end", "accumulator", "relief")
        for mode in [(t, m, a, r) for t in (0, 1) for m in (0, 1) for a in (0, 1) for r in (0, 1)]:
            got, want = d._network(mode), _network_before(d, mode)
            assert np.array_equal(_bits(got), _bits(want)), (name, mode)
            checked += 1
    assert checked == 5 * 16


def test_an_extra_part_on_the_valve_return_port_gives_the_network_wired_before(drifter):
    line = ReturnAccumulator(volume=0.3, flow_coefficient=1.2, precharge=0.02, gas_volume=0.5)
    drive = dataclasses.replace(drifter.drive(), extra_parts=(line,))
    comp = drive._composition
    assert comp.nodes == {"front": 0, "rear": 1, "supply": 2, "return_line": 3, "tank": 4}
    assert comp.ports == {"valve_return": 3}
    assert comp.events == ("ramp_end", "accumulator", "relief", "return_line.gas")
    assert drive.layout.energies[-2:] == ("return_line", "return_line.gas")
    for mode in itertools.product((0, 1), repeat=5):
        assert np.array_equal(_bits(drive._network(mode)), _bits(_network_before(drive, mode, line))), mode


@dataclasses.dataclass(frozen=True)
class ThrottledValve(CircuitPart):
    """The preset valve's record with a coefficient of its own: a part that replaces the preset's
    ``valve`` by name (its ramp's end its event, the return port offered as the valve's)."""

    coefficient: float

    name = "throttled_valve"
    replaces = ("valve",)
    events = ("ramp_end",)
    offers = {"valve_return": "tank"}

    def records(self, slots, oil):
        target, moving = slots.mode[0], slots.flags["ramp_end"]
        tau = 0.05  # (the drive's switching time below)
        return [record(VALVE, pressure_port=slots.nodes["supply"], work_port=slots.nodes["rear"],
                       return_port=slots.ports["valve_return"], coefficient=self.coefficient,
                       ptr2=oil.transition_pressure ** 2,
                       rate=(1.0 if target else -1.0) / tau if moving else 0.0,
                       open=(1 if target else -1) if moving else 0, energy=slots.energy["orifices"],
                       event=slots.events["ramp_end"])]


def test_a_part_replaces_the_preset_valve_by_name(drifter):
    drive = drifter.drive().with_(switching_time=0.05)
    k = 1.5 * drive.valve.coefficient
    replaced = dataclasses.replace(drive, extra_parts=(ThrottledValve(k),))
    reference = drive.with_(valve_coefficient=k)  # (the preset's valve of that coefficient)
    assert [p.name for p in replaced._composition.parts] == [
        "chambers", "supply", "throttled_valve", "accumulator", "relief"]
    assert replaced.layout == reference.layout
    assert replaced._composition.events == reference._composition.events
    for mode in [(t, m, a, r) for t in (0, 1) for m in (0, 1) for a in (0, 1) for r in (0, 1)]:
        assert np.array_equal(_bits(replaced._network(mode)), _bits(reference._network(mode))), mode
        assert not np.array_equal(replaced._network(mode), drive._network(mode))
    model = drifter.model().with_(n_modes=0)
    start = InitialState.rigid(0.0, 0.0)
    a, b = simulate(model, replaced, start, 20.0), simulate(model, reference, start, 20.0)
    assert a.n_impacts >= 2 and np.array_equal(a.impact_times, b.impact_times)
    assert np.array_equal(a.impact_velocities, b.impact_velocities)


@dataclasses.dataclass(frozen=True)
class PilotValve(ThrottledValve):
    """:class:`ThrottledValve` with a pilot node of its own (a volume on the supply's pressure)."""

    name = "pilot_valve"
    nodes = ("pilot",)
    symbols = ("p_pilot",)

    def records(self, slots, oil):
        return [record(NODE, id=slots.nodes["pilot"], volume=0.1, beta=oil.bulk_modulus),
                record(NW.ORIFICE, source=slots.nodes["supply"], target=slots.nodes["pilot"], coefficient=0.1,
                       ptr2=oil.transition_pressure ** 2, energy=slots.energy["orifices"]),
                *super().records(slots, oil)]


def test_a_replacing_valve_with_a_node_numbers_it_after_the_preset_nodes(drifter):
    drive = dataclasses.replace(drifter.drive(), extra_parts=(PilotValve(2.0),))
    comp = drive._composition
    assert comp.nodes == {"front": 0, "rear": 1, "supply": 2, "pilot": 3, "tank": 4}
    assert drive.layout.state_names == ("p_f", "p_r", "p_s", "p_pilot", "x_v")
    net = drive._network((1, 0, 0, 0))
    assert int(net[NW.NW_NSTATE]) == 4 and int(net[NW.NW_NNODE]) == 5


def test_replacing_what_the_circuit_does_not_have_is_refused():
    @dataclasses.dataclass(frozen=True)
    class Spool(ThrottledValve):
        replaces = ("spool",)

    with pytest.raises(ValueError, match="replaces the circuit's parts by name.*got 'spool'"):
        compose_parts((Spool(1.0),), PRESET_PARTS)
    with pytest.raises(ValueError, match="each once.*got 'valve'"):
        compose_parts((ThrottledValve(1.0), ThrottledValve(2.0)), PRESET_PARTS)

    @dataclasses.dataclass(frozen=True)
    class Plain(ThrottledValve):
        offers = {}

    line = ReturnAccumulator(volume=0.3, flow_coefficient=1.2, precharge=0.02, gas_volume=0.5)
    with pytest.raises(ValueError, match=r"takes a port of \(\)"):
        compose_parts((Plain(1.0), line), PRESET_PARTS)
