"""``benchmarks/fingerprint.py`` compares two trees' numbers by their paths: a key an older tree
says by its old name (the outputs' ``RENAMED_OUTPUTS``, a result's renamed attribute) is read under its name
now, so a rename that moves a number in the sorted order the sha is taken in is "same (bitwise;
keys renamed: ...)", and a number that really moved still "differs" (the library's own renames,
on records made up here)."""

import importlib.util
import math
from pathlib import Path

import pytest

import impactbar.physical.results  # noqa: F401 - (the result types' renamed attributes, registered)

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "fingerprint.py"


@pytest.fixture(scope="module")
def fp():
    spec = importlib.util.spec_from_file_location("fingerprint_under_test", _PATH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _hammer(energy: float, fb: float, old: bool) -> dict:
    """A hammer's orbit record as the tree before the renames wrote it (``old``) or as it is now."""
    if old:
        return {"blow_energy_J": energy, "power_W": energy * fb, "peak_stress_Pa": 2.0e8,
                "peak_rod_stress_Pa": 1.5e8, "blow_frequency_Hz": fb}
    return {"impact_energy_J": energy, "impact_power_kW": energy * fb / 1e3, "peak_piston_stress_Pa": 2.0e8,
            "peak_rod_stress_Pa": 1.5e8, "blow_frequency_Hz": fb}


def test_renamed_keys_of_the_same_numbers_are_the_same_bitwise(fp):
    energy, fb = 812.3456789, 37.123
    mine = fp._flat({"hammer": [_hammer(energy, fb, old=False)],
                     "drifter": {"impact_power_kW": 1.25, "blows": 3}})
    theirs = fp._flat({"hammer": [_hammer(energy, fb, old=True)],
                       "drifter": {"percussive_power_kW": 1.25, "blows": 3}})
    assert [x for _, x in mine] != [x for _, x in theirs]  # (the sorted order moved the numbers)
    said = fp._compare(mine, theirs)
    assert said.startswith("same (bitwise; keys renamed: ")
    for rename in ("percussive_power_kW -> impact_power_kW", "blow_energy_J -> impact_energy_J",
                   "power_W -> impact_power_kW (/1000)", "peak_stress_Pa -> peak_piston_stress_Pa"):
        assert rename in said
    assert fp._compare(mine, mine) == "same (bitwise)"


def test_a_number_that_moved_differs_under_its_renamed_key(fp):
    energy, fb = 812.3456789, 37.123
    mine = fp._flat({"hammer": [_hammer(energy, fb, old=False)]})
    theirs = fp._flat({"hammer": [_hammer(energy * (1.0 + 1e-9), fb, old=True)]})
    said = fp._compare(mine, theirs)
    assert said.startswith("differs: largest relative ")
    worst = float(said.split()[3])
    assert worst == pytest.approx(1e-9, rel=1e-3)
    assert "(hammer/0/impact_" in said  # (the energy or the power: both moved by 1e-9)


def test_numbers_without_paths_are_compared_in_order_and_the_sha_is_of_the_numbers_alone(fp):
    mine = fp._flat({"b": [1.0, complex(2.0, -3.0)], "a": math.nan})
    assert mine == [(("a",), mine[0][1]), (("b", 0), 1.0), (("b", 1, "re"), 2.0), (("b", 1, "im"), -3.0)]
    numbers = [x for _, x in mine]
    theirs = [(None, x) for x in numbers]  # (a file an older script wrote: numbers alone)
    assert fp._compare(mine, theirs) == "same (bitwise)"
    assert fp._compare(mine, [(None, x) for x in (*numbers[:-1], -3.5)]).startswith(
        "differs: largest relative 1.43e-01 at number 3")
    assert fp._digest(numbers) == fp._digest([math.nan, 1.0, 2.0, -3.0])
