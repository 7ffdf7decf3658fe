"""A circuit part's fields cross the edge from SI to the model's units as the tree's own fields do
(theory §11, eq. 2): each by its scale's declared steps (:func:`impactbar.physical.tree.convert`),
not by one factor, so that a part's value set in the config and the same value reached by
continuation (``to_dimensionless``) are the same number to the bit."""

from __future__ import annotations

from pathlib import Path

import pytest

from impactbar.continuation.parameters import parameter_value
from impactbar.physical import load, tree
from impactbar.physical.circuit_parts import part_kinds

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
#: the example configs with parts of their own (``[parts.<name>]``)
WITH_PARTS = sorted(p.name for p in EXAMPLES.glob("circuit_*.toml") if "[parts." in p.read_text())


def _edge(path: Path):
    """The drifter of an example config, its parts in SI and the drive's dimensionless parts by name."""
    drifter = load(path)
    return drifter, drifter.parts, {p.name: p for p in drifter.drive().extra_parts}


def test_the_examples_have_every_library_part_kind():
    """The examples below give a part of each of the library's kinds that has SI fields (so the edge
    is checked for each kind's scales)."""
    kinds = {p.kind for name in WITH_PARTS for p in load(EXAMPLES / name).parts}
    with_fields = {k for k, cls in part_kinds().items()  # (the library's: a test may register its own)
                   if cls.__module__.startswith("impactbar.") and (cls.si_fields or cls.si_lists)}
    assert {"spool_valve", "cushion", "laminar_leak", "check_valve", "return_accumulator", "leak"} <= kinds
    assert with_fields <= kinds


@pytest.mark.parametrize("name", WITH_PARTS)
def test_a_parts_config_value_is_its_scales_steps_to_the_bit(name):
    """Each SI field of each part (each element of a list field): the dimensionless value the drive
    holds is ``tree.convert(scale, drifter, si)`` to the bit, the value continuation asks for the
    same key (``to_dimensionless``) is that number too, and so is the drive's parameter
    (``parameter_value``, what continuation starts from); ``from_dimensionless`` gives the SI value
    back within an ulp."""
    drifter, parts, built = _edge(EXAMPLES / name)
    model, drive = drifter.model(), drifter.drive()
    checked = 0
    for spec in parts:
        cls, part = part_kinds()[spec.kind], built[spec.name]
        scale = {f.name: f.scale for f in (*cls.si_fields, *cls.si_lists)}
        unit = {f.name: f.unit for f in (*cls.si_fields, *cls.si_lists)}
        for key, si in spec.values:
            want = tree.convert(scale[key], drifter, si)
            dotted = f"parts.{spec.name}.{key}"
            assert getattr(part, key).hex() == want.hex(), dotted
            given = f"{si!r} {unit[key]}" if unit[key] else si
            parameter, x = drifter.to_dimensionless(dotted, given)
            assert (parameter, x.hex()) == (f"{spec.name}.{key}", want.hex()), dotted
            assert parameter_value(model, drive, parameter).hex() == want.hex(), dotted
            back = drifter.from_dimensionless(dotted, x)
            assert abs(back - si) <= 2 * abs(si) * 2.0 ** -52, dotted
            checked += 1
        for key, values in spec.lists:
            want = tuple(tree.convert(scale[key], drifter, si).hex() for si in values)
            assert tuple(x.hex() for x in getattr(part, key)) == want, f"parts.{spec.name}.{key}"
            checked += 1
    assert checked >= len(parts)


def test_a_factor_would_round_some_apart():
    """The check above can fail: for the examples' values, multiplying by a scale's factor (its steps
    applied to 1, as the part edge did) differs from the steps in the last bit for some fields."""
    apart = 0
    for name in WITH_PARTS:
        drifter = load(EXAMPLES / name)
        for spec in drifter.parts:
            scale = {f.name: f.scale for f in part_kinds()[spec.kind].si_fields}
            apart += sum(si * tree.SCALES[scale[k]](drifter) != tree.convert(scale[k], drifter, si)
                         for k, si in spec.values)
    assert apart > 0
