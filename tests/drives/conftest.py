"""Fixtures shared by the tests of the circuit's parts (leak, cushion, check valve, spool valve, a
part written in a test file): the preset drifter's orbit that each part is measured against, and the
example's drifter on the drill string and rock (``examples/circuit_drifter_rock.toml``). Both are
computed once per session: frozen values, read and never changed by the tests."""

import tomllib

import pytest
from circuit_parts_reference import ROCK_EXAMPLE, preset_orbit

from impactbar.physical import CircuitDrifter


@pytest.fixture(scope="session")
def preset():
    """``(model, drive, orbit)``: the preset drifter's rigid piston, its circuit and its orbit."""
    return preset_orbit()


@pytest.fixture(scope="session")
def rock_drifter():
    """``(model, drive)`` of the drifter on the drill string and rock."""
    with open(ROCK_EXAMPLE, "rb") as f:
        d = CircuitDrifter.from_config(tomllib.load(f))
    return d.model(), d.drive()
