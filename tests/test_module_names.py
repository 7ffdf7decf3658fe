"""Modules are named by the concept they hold: one word per concept, and the public entry points in
modules named for what they do.

- "driven" is the motion under a drive (autonomous, its period unknown) in the solvers: the
  ``driven*`` modules of :mod:`impactbar.orbits`, :mod:`impactbar.simulation` and
  :mod:`impactbar.continuation`;
- "valve" is the position-switched drive, the hydraulic drifter's valve: the package
  ``drives/valve/`` and the orbit solvers' ``valve_*`` modules of its closed-form problem;
- no module is named "kernel" (nearly every compiled module holds numba kernels): each is named for
  what it computes (``_event_loop``, ``_flight``, ``_admissibility_search``, ...).
"""

import importlib
from pathlib import Path

import impactbar

TOP = Path(impactbar.__file__).parent

#: each public entry point and the module that defines it, named for what it does
ENTRY_POINTS = {
    ("impactbar.orbits", "find_orbit"): "impactbar.orbits.find",
    ("impactbar.orbits", "periodic_orbits"): "impactbar.orbits.find",
    ("impactbar.orbits", "find_driven_orbit"): "impactbar.orbits.driven_search",
    ("impactbar.orbits", "drive_orbits"): "impactbar.orbits.driven_search",
    ("impactbar.orbits", "DrivenOrbit"): "impactbar.orbits.driven_orbit",
    ("impactbar.simulation", "simulate"): "impactbar.simulation.simulate",
    ("impactbar.simulation", "DrivenTrajectory"): "impactbar.simulation.driven_trajectory",
    ("impactbar.continuation", "continue_orbit"): "impactbar.continuation.one_parameter",
    ("impactbar.continuation", "continue_bifurcation"): "impactbar.continuation.two_parameter",
    ("impactbar.drives", "PositionSwitchedDrive"): "impactbar.drives.valve.drive",
}


def _parts() -> set[str]:
    """The name of every module and package of impactbar (without ``.py``)."""
    return {part.removesuffix(".py") for p in TOP.rglob("*.py") if "__pycache__" not in p.parts
            for part in p.relative_to(TOP).parts}


def test_no_module_is_named_kernel():
    assert sorted(part for part in _parts() if "kernel" in part) == []


def test_switched_names_no_module():
    """The word "switched" named both the motion under a drive (a ``switched`` module each in the
    orbits, the simulation and the continuation) and the valve drive (the drives' package
    ``switched``): now "driven" and "valve", and no module or package says "switched"."""
    assert sorted(part for part in _parts() if "switched" in part) == []
    for package in ("orbits", "simulation", "continuation"):
        assert (TOP / package / "driven.py").is_file(), package
    assert (TOP / "drives" / "valve" / "__init__.py").is_file()


def test_entry_points_live_in_modules_named_for_them():
    where = {f"{package}.{name}": getattr(importlib.import_module(package), name).__module__
             for package, name in ENTRY_POINTS}
    assert where == {f"{package}.{name}": module for (package, name), module in ENTRY_POINTS.items()}



def test_renamed_public_names_resolve_to_the_new_ones_with_a_warning():
    """The motion under a drive is "driven" in the public names too (``DrivenOrbit``,
    ``find_driven_orbit``, ``DrivenTrajectory``); each old "switched" name still resolves, to the
    same object, with a DeprecationWarning naming the new one, and is not advertised; so does the
    outputs' table of old names, once ``RENAMED`` as the module attributes' table was (now
    ``RENAMED_OUTPUTS`` and ``RENAMED_PUBLIC_NAMES``)."""
    import pytest

    from impactbar._shared.renamed import RENAMED_PUBLIC_NAMES as NEW

    homes = {"SwitchedOrbit": ("impactbar", "impactbar.orbits"), "find_switched_orbit": ("impactbar.orbits",),
             "SwitchedTrajectory": ("impactbar", "impactbar.simulation"),
             "DrifterMapSpec": ("impactbar.sweeps",), "parse_map_spec": ("impactbar.sweeps",),
             "RENAMED": ("impactbar.physical.outputs",)}
    assert set(homes) == set(NEW)
    for old, packages in homes.items():
        for package in packages:
            module = importlib.import_module(package)
            with pytest.warns(DeprecationWarning, match=f"{package}.{old} is renamed {NEW[old]}"):
                value = getattr(module, old)
            assert value is getattr(module, NEW[old])
            assert old not in module.__all__ and old not in dir(module)
    with pytest.raises(AttributeError):
        getattr(impactbar, "find_switched_orbit")  # noqa: B009 (never a top-level name)
