"""The formulas in the docstrings of the central API are math (``:math:``), which the site renders,
not code text: a double-backquoted span that reads as a formula (a power, a comparison, pi, a sum
or an integral) is reported with its object."""

import inspect
import re

import pytest

import impactbar as ib
from impactbar.laws.paper.stability import floquet_multipliers

#: a span ``...`` that is a formula, not code: an operator of mathematics or a Greek letter by name
FORMULA = re.compile(r"``([^`]*(?:\^|<=|>=|\bpi\b|\bsum\b|\bint_|\bsqrt\b|\bexp\()[^`]*)``")

CENTRAL = [ib.BarModel, ib.BarModel.frequencies, ib.BarModel.end_weights, ib.BarModel.shape_functions,
           ib.InitialState, ib.InitialState.from_fields, ib.simulate, ib.periodic_orbits, ib.find_orbit,
           floquet_multipliers]


def _doc(obj):
    return inspect.getdoc(obj.fget if isinstance(obj, property) else obj) or ""


@pytest.mark.parametrize("obj", CENTRAL, ids=lambda o: getattr(o, "__qualname__", None)
                         or getattr(getattr(o, "fget", None), "__qualname__", repr(o)))
def test_central_docstrings_write_formulas_as_math(obj):
    doc = _doc(obj)
    assert doc, "no docstring"
    assert FORMULA.findall(doc) == []


def test_the_pattern_finds_a_formula_in_code_text():
    assert FORMULA.findall("frequencies ``s n pi`` and ``0 <= R <= 1``; code ``impact='wave'``") == \
        ["s n pi", "0 <= R <= 1"]
