"""A drive's parameters as the parameter protocol reads them (:mod:`impactbar.parameters`):
:class:`DriveParameters`, the object :attr:`impactbar.Drive.params` returns."""

from __future__ import annotations

from collections.abc import Callable

from .._shared.parameters import Parameter

__all__ = ["DriveParameters"]


class DriveParameters:
    """The parameters of one drive, as :attr:`impactbar.Drive.params` gives them: their records
    (:meth:`parameter_table`) and copies of the drive with some changed (:meth:`with_parameter`,
    :meth:`with_parameters`, through the drive's ``with_``), from what its class declares in
    ``traits`` (``parameters``, the names of attributes; ``parameter_ranges``, name -> keyword
    arguments of :class:`~impactbar.parameters.Parameter`).

    Parameters
    ----------
    drive : Drive
    value : callable, optional
        ``value(name)``: a parameter's current value, ``None`` where the drive has none now (the oil
        circuit's ``pump_flow`` under a supply held at a pressure). Default: the attribute of that
        name as a float (``None`` kept).

    Examples
    --------
    >>> from impactbar import PositionSwitchedDrive
    >>> valve = PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    >>> [(p.name, p.value) for p in valve.params.parameter_table()][:3]
    [('stroke', 1.0), ('ret', 1.0), ('switch_out', 1.0)]
    >>> valve.params.with_parameter("ret", 2.0).ret
    2.0
    """

    __slots__ = ("_drive", "_value")

    def __init__(self, drive, value: Callable[[str], float | None] | None = None):
        self._drive = drive
        self._value = value if value is not None else self._attribute

    def _attribute(self, name: str) -> float | None:
        value = getattr(self._drive, name)
        return None if value is None else float(value)

    def parameter_table(self) -> tuple[Parameter, ...]:
        """The records of the drive's ``traits.parameters``, with their ranges.

        Returns
        -------
        tuple of Parameter
        """
        traits = self._drive.traits
        return tuple(Parameter(name, self._value(name), **traits.parameter_ranges.get(name, {}))
                     for name in traits.parameters)

    def with_parameter(self, name: str, value):
        """A copy of the drive with one of its parameters changed (its ``with_``, validated again).

        Parameters
        ----------
        name : str
            One of the drive's ``traits.parameters``.
        value : float

        Returns
        -------
        Drive

        Raises
        ------
        ValueError
            For a name that is not one of them, or a value the constructor refuses.
        """
        return self._drive.with_(**{name: value})

    def with_parameters(self, changes: dict):
        """A copy with several of the drive's parameters changed at once (its ``with_``, the result
        validated once).

        Raises
        ------
        ValueError
            As :meth:`with_parameter`.
        """
        return self._drive.with_(**changes)
