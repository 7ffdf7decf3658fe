"""The oil circuit's layout (``HydraulicCircuitDrive.layout``): the Python side reads the circuit's
states and energy terms by name, and the names agree with the compiled kernel's order.

Checked against independent numbers: the kernel's own vector field (the piston's acceleration at
rest is the force ``p_r - alpha p_f``, the spool's rate its ramp, the pump's integrand ``p_s Q_p``,
the piston's ``-p w'``), evaluated at a state whose components all differ; and the consumers' source,
searched for the literal indices they read the layout by before.
"""

import dataclasses
import pathlib
import re

import numpy as np
import pytest

import circuit_field_reference as K
from impactbar.drives.circuit import (
    Accumulator,
    Chambers,
    CircuitEnergy,
    HydraulicCircuitDrive,
    Oil,
    Supply,
    Valve,
)
from impactbar.drives.circuit.drive import _rate_model
from impactbar.drives.circuit.layout import PRESET, CircuitLayout

SRC = pathlib.Path(__file__).resolve().parents[2] / "src" / "impactbar"

#: the Python consumers of the circuit's layout (the compiled kernels and the network keep their own)
CONSUMERS = ("drives/circuit/drive.py", "drives/circuit/flight.py", "drives/circuit/endflight.py",
             "physical/circuit.py", "physical/sensitivity.py", "simulation/blows.py", "sweeps/map_task.py")

#: literal reads of the preset's layout that went through it before
LITERAL = {
    "a circuit state by number": r"\bz\[\s*\d",
    "an energy term by number": r"\bE\[\s*\d",
    "the kernel's energy count": r"\bN_ENERGY\b",
    "the flight's state size": r"M \+ 4\b",
    "a state's extremes by number": r"extremes\(\s*\d",
    "a state of drive_state by number": r"drive_state\([^)]*\)\[\s*\d",
    "the pump's work by number": r"_energies\(\)\[\s*\d",
    "a pressure minimum by number": r"\(\d, \"(front|rear|supply|spool)\"\)",
    "a blow's column by number": r"\bY\[\s*[1-6]\s*\]|\b1:5\]|\[-1, [56]\b|\)\[[56]\]|\[6:",
    "the state count": r"state_size = 4|np\.empty\(\(4,",
}


def literal_reads(text: str) -> list:
    """``(what, line)`` of each literal read of the layout in ``text``."""
    return [(what, line.strip()) for line in text.splitlines() for what, pat in LITERAL.items()
            if re.search(pat, line)]


def test_the_patterns_find_the_reads_they_name():
    before = ('return float(z[1] - self.chambers.area_ratio * z[0])\n'
              'return self.y[-1, 2 * self.M + 4:2 * self.M + 4 + K.N_ENERGY].copy()\n'
              'for k, name in ((0, "front"), (1, "rear"), (2, "supply"))}\n'
              'E = self._energies()[0]\n'
              'return Y[2] - self.alpha * Y[1]\n'
              'ps = np.asarray(p.drive_state(t)[2], dtype=float) - p_rel\n')
    found = {what for what, _ in literal_reads(before)}
    assert found == {"a circuit state by number", "the kernel's energy count", "the flight's state size",
                     "a pressure minimum by number", "the pump's work by number", "a blow's column by number",
                     "a state of drive_state by number"}


@pytest.mark.parametrize("path", CONSUMERS)
def test_consumers_read_the_layout_by_name(path):
    assert literal_reads((SRC / path).read_text()) == []


def pumped():
    return HydraulicCircuitDrive(
        Chambers(area_ratio=0.5, rear_volume=0.4, front_volume=0.2),
        Valve(switch_out=0.048, coefficient=2.0, switching_time=0.05),
        Supply(pump_flow=0.07, hose_volume=1.0, front_coefficient=2.0, tank_pressure=0.03),
        Oil(bulk_modulus=70.0, transition_pressure=0.01),
        Accumulator(precharge=0.5, volume=2.0))


def test_layout_names_follow_the_kernel():
    drive = pumped()
    L = drive.layout
    assert L is PRESET and drive.state_names == L.state_names == ("p_f", "p_r", "p_s", "x_v")
    assert drive.state_size == L.n_states == 4 and drive.n_quadratures == L.n_energy == K.N_ENERGY
    z = np.array([0.31, 0.77, 1.13, 0.4])  # all different: a wrong index changes the numbers
    q, v = np.array([0.0]), np.array([0.0])
    mode = (1, 1, 1, 0)  # the spool ramping open, the accumulator holding oil
    Y = np.concatenate((q, v, z, np.zeros(K.N_ENERGY)))
    out = np.empty_like(Y)
    K.field_at(Y[None, :], K.preset_par(drive, _rate_model(1), mode), out[None, :])
    force = out[1]  # the piston's acceleration at rest: the force (theory §11), from the kernel
    assert drive.force(mode, z, q, v) == force
    assert force == z[L["rear"]] - 0.5 * z[L["front"]] == z[L["p_r"]] - 0.5 * z[L["p_f"]]
    rates = drive.rate(mode, z, q, v)
    assert rates[L["spool"]] == 1.0 / 0.05 and np.count_nonzero(rates == 1.0 / 0.05) == 1
    E = drive.quadratures(mode, z, q, v)
    assert E[L.energy["pump"]] == z[L.supply] * 0.07
    assert E[L.energy["piston"]] == 0.0  # at rest
    v1 = np.array([0.2])
    E1 = drive.quadratures(mode, z, q, v1)
    assert E1[L.energy["piston"]] == pytest.approx(-drive.force(mode, z, q, v1) * -v1[0], rel=1e-15)
    terms = np.arange(1.0, 9.0)
    acc = CircuitEnergy.from_terms(terms, L)
    assert acc["pump"] == 1.0 and acc["compression"] == 5.0 + 6.0 + 7.0 and acc["accumulator"] == 8.0


def test_histories_and_events_by_name():
    drive = pumped()
    L = drive.layout
    z = np.array([0.31, 0.77, 0.45, 0.4])
    events = {e.name: e for e in drive.events((1, 1, 0, 0))}
    assert events["ramp_end"].function(0.0, None, None, z) == z[L["spool"]] - 1.0
    assert events["accumulator"].function(0.0, None, None, z) == 0.45 - 0.5
    assert drive.jump((1, 1, 0, 0), z, events["ramp_end"], 0.0, None, None).z[L["spool"]] == 1.0


def test_layout_refuses_bad_names():
    with pytest.raises(ValueError, match="states must be distinct"):
        CircuitLayout(("a", "a"), ("x", "y"), ("e",))
    with pytest.raises(ValueError, match="state_names must name"):
        CircuitLayout(("a", "b"), ("x",), ("e",))
    with pytest.raises(KeyError, match="no state 'gas'"):
        PRESET["gas"]


def test_start_pressures_in_the_layouts_order():
    L = PRESET
    drive = dataclasses.replace(pumped(), start_pressures=(0.31, 0.77, 1.13, 0.4))
    st = drive.start(None, np.array([-0.08]), np.zeros(1))  # out past the switch: the valve opening
    assert st.mode[:2] == (1, 1)  # ramping from 0.4 towards open
    assert [st.z[L[k]] for k in ("p_f", "p_r", "p_s", "x_v")] == [0.31, 0.77, 1.13, 0.4]
    assert drive.force(st.mode, st.z, None, None) == 0.77 - 0.5 * 0.31
    for bad in ((0.31, 0.77, 1.13, 1.5), (0.31, 0.77), (0.31, 0.77, 1.13, 0.4, 0.0), (0.31, 80.0, 1.0)):
        with pytest.raises(ValueError, match="start_pressures must"):
            dataclasses.replace(pumped(), start_pressures=bad)
