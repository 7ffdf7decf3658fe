"""The formulas in the docstrings of the central API are math (``:math:``), which the site renders,
not code text: a double-backquoted span that reads as a formula (a power, a comparison, pi, a sum
or an integral) is reported with its object.

The central API is a short list from the core and every public object of ``impactbar.physical`` and
``impactbar.drives``: the names in their ``__all__``, the public classes and functions of their public
modules, the public methods and properties of those classes, and the modules' own docstrings,
collected here so that a new one is checked without being listed."""

import functools
import importlib
import inspect
import pkgutil
import re
from types import SimpleNamespace

import pytest

import impactbar as ib
import impactbar.drives
import impactbar.physical
from impactbar.laws.paper.stability import floquet_multipliers
from impactbar.orbits import valve_search
from impactbar.orbits.valve_segment import ValveProblem

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


def _public_modules(*packages):
    """The packages and their public modules (no part of the name private), imported."""
    modules = list(packages)
    for package in packages:
        for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
            if not any(part.startswith("_") for part in info.name.split(".")):
                modules.append(importlib.import_module(info.name))
    return modules


def _public_api(*packages, modules=False):
    """Every class and function in the packages' ``__all__`` (with ``modules``, also those defined,
    with a public name, in one of their public modules), and the public methods and properties,
    defined in the package, of those classes; each once."""
    candidates = [getattr(package, name) for package in packages for name in package.__all__]
    for module in _public_modules(*packages) if modules else []:
        candidates += [obj for name, obj in vars(module).items()
                       if not name.startswith("_") and getattr(obj, "__module__", None) == module.__name__]
    found = {}
    for obj in candidates:
        if not (inspect.isclass(obj) or inspect.isfunction(obj)):
            continue  # a constant (a preset table, a limit): no docstring of its own
        found.setdefault(id(obj), obj)
        if not inspect.isclass(obj):
            continue
        package = obj.__module__.split(".")[:2]
        for member in dir(obj):
            if member.startswith("_"):
                continue
            function = _unwrap(inspect.getattr_static(obj, member))
            if function is not None and function.__module__.split(".")[:2] == package:
                found.setdefault(id(function), function)
    return list(found.values())


CORE = [ib.BarModel, ib.BarModel.frequencies, ib.BarModel.end_weights, ib.BarModel.shape_functions,
        ib.InitialState, ib.InitialState.from_fields, ib.simulate, ib.periodic_orbits, ib.find_orbit,
        floquet_multipliers]
#: what must have a docstring: the core list and what the two packages export
DOCUMENTED = CORE + _public_api(impactbar.physical, impactbar.drives)
#: the valve drive's orbit numerics (in orbits/, beside the load's): their problem and its search
VALVE_ORBITS = _public_api(valve_search, SimpleNamespace(__all__=["ValveProblem"], ValveProblem=ValveProblem))
#: what is checked for formulas: also the public helpers of the packages' public modules (some,
#: the flights' accessors, have no docstring of their own), and the valve's orbit numerics
CENTRAL = CORE + _public_api(impactbar.physical, impactbar.drives, modules=True) + VALVE_ORBITS
#: the modules of the two packages, whose docstrings the site renders above their objects
MODULES = _public_modules(impactbar.physical, impactbar.drives)


def _name(obj):
    function = obj.fget if isinstance(obj, property) else obj
    return getattr(function, "__qualname__", repr(obj))


def _doc(obj):
    return inspect.getdoc(obj.fget if isinstance(obj, property) else obj) or ""


@pytest.mark.parametrize("obj", CENTRAL, ids=lambda o: f"{getattr(o, '__module__', '')}.{_name(o)}")
def test_central_docstrings_write_formulas_as_math(obj):
    doc = _doc(obj)
    assert doc or not any(obj is documented for documented in DOCUMENTED), "no docstring"
    assert formula_spans(doc) == []


@pytest.mark.parametrize("module", MODULES, ids=lambda m: m.__name__)
def test_module_docstrings_write_formulas_as_math(module):
    assert formula_spans(inspect.getdoc(module) or "") == []


def test_the_pattern_finds_a_formula_in_code_text():
    assert formula_spans("frequencies ``s n pi`` and ``0 <= R <= 1``; code ``impact='wave'``") == \
        ["s n pi", "0 <= R <= 1"]


def test_the_text_between_two_spans_and_a_typed_string_are_no_formula():
    assert formula_spans("``rho`` (kg/m^3), ``E`` and ``Bar.from_units(\"7850 kg/m^3\")``") == []
    assert formula_spans("``a``, kg/m^3, ``m v^2 / 2``") == ["m v^2 / 2"]


def test_the_public_api_holds_the_methods_and_properties_of_the_classes():
    names = {_name(obj) for obj in CENTRAL}
    # (the two drifters' time scale, scales and model come from their shared base)
    assert {"Hammer.from_config", "Hammer.blow_frequency_Hz", "Drifter.stroke_force_N",
            "_ScaledDrifter.omega_rad_s",
            "PositionSwitchedDrive.rigid_orbit", "flow_coefficient", "Drive.rate", "Accumulator",
            "CircuitEnergy", "OneImpactEquations", "ValveProblem.search"} <= names
    assert not any(name.rsplit(".", 1)[-1].startswith("_") for name in names)
