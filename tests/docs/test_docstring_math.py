"""The formulas in the docstrings of the central API are math (``:math:``), which the site renders,
not code text: a double-backquoted span that reads as a formula (a power, a comparison, pi, a sum
or an integral) is reported with its object.

The central API is a short list from the core and every public object of ``impactbar.physical`` and
``impactbar.drives``: the names in their ``__all__`` and the public methods and properties of their
public classes, collected here so that a new one is checked without being listed."""

import functools
import inspect
import re

import pytest

import impactbar as ib
import impactbar.drives
import impactbar.physical
from impactbar.laws.paper.stability import floquet_multipliers

#: a double-backquoted span, ``...``, taken pair by pair (the text between two spans is no span)
SPAN = re.compile(r"``(.+?)``", re.S)
#: what makes a span a formula: an operator of mathematics or a Greek letter by name
FORMULA = re.compile(r"\^|<=|>=|\bpi\b|\bsum\b|\bint_|\bsqrt\b|\bexp\(")
#: a quoted string in a span: a Python expression the user types (``"7850 kg/m^3"``), code
QUOTED = re.compile(r"\"[^\"]*\"|'[^']*'")


def formula_spans(doc):
    """The double-backquoted spans of ``doc`` that read as formulas, in order."""
    return [span for span in SPAN.findall(doc) if FORMULA.search(span) and not QUOTED.search(span)]


def _unwrap(attribute):
    """The function behind a class attribute (a method, static or class method, property), or None."""
    if isinstance(attribute, (staticmethod, classmethod)):
        attribute = attribute.__func__
    if isinstance(attribute, property):
        attribute = attribute.fget
    if isinstance(attribute, functools.cached_property):
        attribute = attribute.func
    return attribute if inspect.isfunction(attribute) else None


def _public_api(*packages):
    """Every class and function in the packages' ``__all__`` and the public methods and properties,
    defined in the package, of those classes; each once."""
    found = {}
    for package in packages:
        for name in package.__all__:
            obj = getattr(package, name)
            if not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue  # a constant (a preset table, a limit): no docstring of its own
            found.setdefault(id(obj), obj)
            if not inspect.isclass(obj):
                continue
            for member in dir(obj):
                if member.startswith("_"):
                    continue
                function = _unwrap(inspect.getattr_static(obj, member))
                if function is not None and function.__module__.startswith(package.__name__ + "."):
                    found.setdefault(id(function), function)
    return list(found.values())


CORE = [ib.BarModel, ib.BarModel.frequencies, ib.BarModel.end_weights, ib.BarModel.shape_functions,
        ib.InitialState, ib.InitialState.from_fields, ib.simulate, ib.periodic_orbits, ib.find_orbit,
        floquet_multipliers]
CENTRAL = CORE + _public_api(impactbar.physical, impactbar.drives)


def _name(obj):
    function = obj.fget if isinstance(obj, property) else obj
    return getattr(function, "__qualname__", repr(obj))


def _doc(obj):
    return inspect.getdoc(obj.fget if isinstance(obj, property) else obj) or ""


@pytest.mark.parametrize("obj", CENTRAL, ids=lambda o: f"{getattr(o, '__module__', '')}.{_name(o)}")
def test_central_docstrings_write_formulas_as_math(obj):
    doc = _doc(obj)
    assert doc, "no docstring"
    assert formula_spans(doc) == []


def test_the_pattern_finds_a_formula_in_code_text():
    assert formula_spans("frequencies ``s n pi`` and ``0 <= R <= 1``; code ``impact='wave'``") == \
        ["s n pi", "0 <= R <= 1"]


def test_the_text_between_two_spans_and_a_typed_string_are_no_formula():
    assert formula_spans("``rho`` (kg/m^3), ``E`` and ``Bar.from_units(\"7850 kg/m^3\")``") == []
    assert formula_spans("``a``, kg/m^3, ``m v^2 / 2``") == ["m v^2 / 2"]


def test_the_public_api_holds_the_methods_and_properties_of_the_classes():
    names = {_name(obj) for obj in CENTRAL}
    assert {"Hammer.from_config", "Hammer.blow_frequency_Hz", "Drifter.omega_rad_s",
            "PositionSwitchedDrive.rigid_orbit", "flow_coefficient", "Drive.rate"} <= names
    assert not any(name.rsplit(".", 1)[-1].startswith("_") for name in names)
