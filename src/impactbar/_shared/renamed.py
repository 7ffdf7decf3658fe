"""Public names that were renamed: the old name still resolves, with a :class:`DeprecationWarning`
that names the new one (as numpy keeps an expired alias for a release before removing it)."""

from __future__ import annotations

import warnings

#: old public name of a module's attribute -> its new name ("switched" was the word for both the
#: motion under a drive and the valve drive: the motion under a drive is now "driven", the valve drive
#: ``PositionSwitchedDrive``); :func:`renamed` resolves each in the modules that export the new one
RENAMED_PUBLIC_NAMES = {
    "SwitchedOrbit": "DrivenOrbit",
    "find_switched_orbit": "find_driven_orbit",
    "SwitchedTrajectory": "DrivenTrajectory",
    # one sweep spec class for the dimensionless bar and a drifter's design map
    "DrifterMapSpec": "SweepSpec",
    "parse_map_spec": "parse_spec",
    # the outputs' table of old names (this one and it were both called RENAMED)
    "RENAMED": "RENAMED_OUTPUTS",
}


#: each old attribute of a result, to the attributes now that :func:`renamed_attribute` gave it, as
#: the result types' modules declare them (one old name may have been two types' quantities:
#: ``peak_stress_Pa`` is ``PhysicalOrbit.peak_piston_stress_Pa`` and ``OptimalPiston.peak_rod_stress_Pa``)
RENAMED_ATTRIBUTES: dict[str, list[str]] = {}


def renamed(module, name: str):
    """The value of the renamed public ``name`` in ``module`` (its new name's), with a
    :class:`DeprecationWarning`; ``None`` where ``name`` was never renamed.

    Parameters
    ----------
    module : module
        The package whose ``__getattr__`` asks (its new name must resolve in it).
    name : str
        The attribute asked for.

    Returns
    -------
    object or None
    """
    new = RENAMED_PUBLIC_NAMES.get(name)
    if new is None or new not in getattr(module, "__all__", ()):
        return None
    warnings.warn(f"{module.__name__}.{name} is renamed {new}; the old name will be removed",
                  DeprecationWarning, stacklevel=3)
    return getattr(module, new)


def renamed_attribute(old: str, new: str, value=None) -> property:
    """A result's attribute under the name it had before: a read-only property that gives the
    attribute ``new`` (or ``value(obj)``) with a :class:`DeprecationWarning` naming it; the rename
    is recorded in :data:`RENAMED_ATTRIBUTES`.

    Parameters
    ----------
    old : str
        The name it had (the property's).
    new : str
        The name it has now.
    value : callable, optional
        ``value(obj)``: the old attribute's value where it is not ``new``'s as it is (another unit).

    Returns
    -------
    property

    Examples
    --------
    >>> import warnings
    >>> class Result:
    ...     impact_energy_J = 2.5
    ...     blow_energy_J = renamed_attribute("blow_energy_J", "impact_energy_J")
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     Result().blow_energy_J, str(caught[0].message)
    (2.5, 'blow_energy_J is now called impact_energy_J')
    """

    targets = RENAMED_ATTRIBUTES.setdefault(old, [])
    if new not in targets:
        targets.append(new)

    def get(obj):
        warnings.warn(f"{old} is now called {new}", DeprecationWarning, stacklevel=2)
        return getattr(obj, new) if value is None else value(obj)

    get.__name__ = old
    get.__doc__ = f":attr:`{new}` under the name it had before (a ``DeprecationWarning``)."
    return property(get)
