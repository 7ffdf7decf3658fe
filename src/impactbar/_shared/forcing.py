r"""What forces the bar, decided once: a load (a function of time, period :math:`2\pi`, eq. 7) or a
drive (with state of its own, autonomous: the period is an output, theory §10).

Each entry point (:func:`impactbar.periodic_orbits`, :func:`impactbar.find_orbit`,
:func:`impactbar.simulate`, :func:`impactbar.continue_orbit`) holds a table from a forcing family to
the solver of that family, as scipy's ``solve_ivp`` holds ``METHODS``, and calls :func:`dispatch`
on it once; no solver asks again. A solver that takes one family alone says so by
:func:`check_family`; code that takes what a family declares asks :func:`of_family`, and code that
reuses one forcing's work for another asks :func:`alike`. A forcing declares its family by the
class attribute ``family`` (:class:`~impactbar.Load`: ``"load"``, :class:`~impactbar.Drive`:
``"drive"``): nothing here tests a class against Load or Drive. Nothing outside this module asks a
forcing's class at all (``tests/test_dispatch.py`` holds the package to it).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

__all__ = ["FAMILIES", "forcing_family", "dispatch", "check_family", "of_family", "alike"]

#: the forcing families and what each is, for the messages
FAMILIES = {
    "load": "a Load (periodic in time, e.g. CosineLoad, SquareWaveLoad)",
    "drive": "a Drive (with state of its own, e.g. PositionSwitchedDrive, HydraulicCircuitDrive)",
}


def forcing_family(forcing, name: str = "load") -> str:
    """The family ``forcing`` declares: ``"load"`` or ``"drive"``.

    Parameters
    ----------
    forcing : Load or Drive
        What forces the bar.
    name : str, optional
        The argument's name, for the message. Default ``"load"``.

    Returns
    -------
    str
        A key of :data:`FAMILIES`.

    Raises
    ------
    ValueError
        Where ``forcing`` declares no family (it is neither a load nor a drive).

    Examples
    --------
    >>> from impactbar import CosineLoad
    >>> forcing_family(CosineLoad(0.3, 1.0))
    'load'
    >>> forcing_family(1.0)
    Traceback (most recent call last):
    ...
    ValueError: load must be a Load (periodic in time, ...) or a Drive (with state of its own, ...); got float
    """
    family = getattr(type(forcing), "family", None)
    if not isinstance(family, str) or family not in FAMILIES:
        raise ValueError(f"{name} must be {' or '.join(FAMILIES.values())}; got {type(forcing).__name__}")
    return family


def dispatch(table: Mapping[str, Callable], forcing, name: str = "load") -> Callable:
    """The solver of ``table`` for ``forcing``'s family: the one decision an entry point makes.

    Parameters
    ----------
    table : mapping of str to callable
        One solver per family the entry point takes (keys of :data:`FAMILIES`).
    forcing, name
        As for :func:`forcing_family`.

    Returns
    -------
    callable
        ``table[forcing_family(forcing)]``.

    Raises
    ------
    ValueError
        Where ``forcing`` is neither a load nor a drive, or its family has no solver in ``table``.
    """
    family = forcing_family(forcing, name)
    if family not in table:
        raise ValueError(f"{name} must be {' or '.join(FAMILIES[f] for f in table)}; got a "
                         f"{type(forcing).__name__}")
    return table[family]


def check_family(forcing, family: str, name: str = "load", hint: str = "") -> None:
    """Refuse a forcing of another family than ``family``, for a solver that takes one alone.

    Parameters
    ----------
    forcing : Load or Drive
        What forces the bar.
    family : str
        The family the solver takes (a key of :data:`FAMILIES`).
    name : str, optional
        The argument's name, for the message. Default ``"load"``.
    hint : str, optional
        What to use instead, appended to the message.

    Raises
    ------
    ValueError
        Where ``forcing`` is not of ``family``.
    """
    if not of_family(forcing, family):
        raise ValueError(f"{name} must be {FAMILIES[family]}; got {type(forcing).__name__}{hint}")


def of_family(forcing, family: str) -> bool:
    """Whether ``forcing`` declares ``family`` (``False`` for what declares none).

    Parameters
    ----------
    forcing : object
        What may force the bar.
    family : str
        A key of :data:`FAMILIES`.

    Returns
    -------
    bool

    Examples
    --------
    >>> from impactbar import CosineLoad
    >>> load = CosineLoad(0.3, 1.0)
    >>> of_family(load, "load"), of_family(load, "drive"), of_family(1.0, "load")
    (True, False, False)
    """
    return getattr(type(forcing), "family", None) == family


def alike(a, b) -> bool:
    """Whether forcings ``a`` and ``b`` are of one class (two values of one kind of drive or load, whose
    states and unknowns have the same layout), so that work done for one may start the other's.

    Parameters
    ----------
    a, b : Load or Drive
        The two forcings.

    Returns
    -------
    bool

    Examples
    --------
    >>> from impactbar import CosineLoad, FourierLoad
    >>> load = CosineLoad(0.3, 1.0)
    >>> alike(load, CosineLoad(0.5, 1.0)), alike(load, FourierLoad(0.3, [1.0]))
    (True, False)
    """
    return type(a) is type(b)
