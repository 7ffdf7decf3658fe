r"""One parameter protocol for every part of a problem: the bar (:class:`~impactbar.BarModel`), its
impact law, the load or the drive.

Each part declares its own parameters in one place, its method ``parameter_table()``, as
:class:`Parameter` records (a dotted name, the current value, its unit, bounds, a description and
whether the problem is smooth in it), and changes one by ``with_parameter(name, value)``, a copy
validated again by the constructors; a part may hold these methods in an object of its own,
``params`` (a load's :class:`~impactbar.loads.params.LoadParameters`). The functions here work on a
``(model, forcing)`` pair alone (the model holds its impact law and lists the law's parameters
beside its own), with no case for any particular law, load or drive: continuation
(:func:`~impactbar.continue_orbit`), sweeps and the command line reach every part's parameters
through them, so a parameter a part declares is continuable, sweepable and settable with no line
elsewhere.

Examples
--------
>>> from impactbar import BarModel, CosineLoad
>>> from impactbar.parameters import parameter_value, parameters, with_parameter
>>> model, load = BarModel(s=10.0, d=0.3, R=0.5, n_modes=4), CosineLoad(0.3, 1.0)
>>> p = parameters(model, load)["R"]
>>> p.value, p.unit, p.range_text, p.description, p.continuable
(0.5, '', '[0, 1]', 'restitution coefficient', True)
>>> model, load = with_parameter(model, load, "p0", 0.4)
>>> parameter_value(model, load, "p0")
0.4
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, replace
from typing import NamedTuple

from .validate import check_int, check_real

__all__ = ["Parameter", "parameters", "parameter_value", "with_parameter",
           "with_parameters", "check_continuable", "table_of"]


@dataclass(frozen=True)
class Parameter:
    r"""One parameter of a part of a problem (the bar, its impact law, a load or a drive).

    Parameters
    ----------
    name : str
        Its dotted name, unique over the parts of one problem (``"R"``, ``"p0"``, ``"rock.k"``,
        ``"segment0.length"``, ``"precharge"``).
    value : float, int or None
        Its current value (``None`` where the part has none now: a valve's ``delay`` where its two
        delays differ, a circuit's ``pump_flow`` under a supply held at a pressure).
    unit : str, optional
        ``""`` for a dimensionless parameter (every parameter of the dimensionless model, eq. 2),
        else an SI unit string pint parses (``"MPa"``, ``"L/min"``).
    low, high : float, optional
        Its allowed range (default unbounded); the constructors may refuse more (a value that
        depends on another parameter: ``rock.k`` at most ``rock.k_u``).
    low_open, high_open : bool, optional
        Whether the range's ends are excluded.
    description : str, optional
        A short description.
    continuable : bool, optional
        Whether the problem is smooth in it, so that a branch of orbits can be followed in it
        (``False`` for an integer, or a rod segment's length on the lattice's cell grid).
    integer : bool, optional
        Whether it takes integer values (``n_modes``, a cosine load's order ``k``).
    reason : str, optional
        Why it is not continuable (the message of :func:`check_continuable`).

    Examples
    --------
    >>> p = Parameter("R", 0.5, low=0.0, high=1.0, description="restitution coefficient")
    >>> p.check(0.8)
    0.8
    >>> p.range_text
    '[0, 1]'
    """

    name: str
    value: float | int | None
    unit: str = ""
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    description: str = ""
    continuable: bool = True
    integer: bool = False
    reason: str = ""

    @property
    def range_text(self) -> str:
        """The allowed range as text, ``"[0, 1]"``, ``"(0, inf)"``."""
        lo = "(" if self.low_open or self.low == -math.inf else "["
        hi = ")" if self.high_open or self.high == math.inf else "]"
        return f"{lo}{self.low:g}, {self.high:g}{hi}"

    def check(self, value) -> float | int:
        """The value checked against the range (a float, an int for an integer parameter).

        Parameters
        ----------
        value : float or int

        Returns
        -------
        float or int

        Raises
        ------
        ValueError
            Naming the parameter and its range, for a value outside it, not a finite number, or a
        subnormal float (nonzero and below 2.2e-308 in magnitude: it keeps too few digits, and the
        model's products of it underflow to 0, a division by zero later).
        """
        lo = None if self.low == -math.inf else self.low
        hi = None if self.high == math.inf else self.high
        if hi is None and not self.high_open and not self.integer and isinstance(value, float) \
                and value == math.inf:
            return value  # (unbounded above and closed: the constructor decides, e.g. no relief valve)
        if isinstance(value, float) and math.isinf(value) and not self.integer:  # (where no bound says so)
            raise ValueError(f"{self.name} must be a finite real number in {self.range_text}; got {value}")
        if self.integer:
            v = check_int(self.name, value, lo=None if lo is None else math.ceil(lo),
                          hi=None if hi is None else math.floor(hi))
        else:
            v = check_real(self.name, value, lo=lo, hi=hi, lo_open=self.low_open, hi_open=self.high_open)
            if v != 0.0 and abs(v) < sys.float_info.min:
                raise ValueError(f"{self.name} must be in {self.range_text}, not subnormal (nonzero "
                                 f"below {sys.float_info.min:.3g} in magnitude: too few digits); got {v}")
        return v

    def at(self, value) -> Parameter:
        """The record with its current value (a part's table built from a class-level declaration)."""
        return replace(self, value=value)


def _declarer(part):
    """What holds ``part``'s ``parameter_table`` and ``with_parameter(s)``: its ``params`` object
    where it has one (a load, a drive), else the part itself."""
    return getattr(part, "params", None) or part


def table_of(part, *args) -> dict[str, Parameter]:
    """The parameters a part declares (its ``parameter_table(*args)``), by name.

    Parameters
    ----------
    part : object
        A model, a load, a drive or an impact law.
    *args
        Passed on (a law's table takes the model it sits in).

    Returns
    -------
    dict of str to Parameter

    Raises
    ------
    ValueError
        For an object that declares no parameters (no ``parameter_table``: not a part), or a name
        declared twice.
    """
    declare = getattr(_declarer(part), "parameter_table", None)
    if declare is None:
        raise ValueError(f"{part!r} is not a part of a problem (a model, a load, a drive or an impact "
                         "law): it declares no parameter_table()")
    out: dict[str, Parameter] = {}
    for p in declare(*args):
        if p.name in out:
            raise ValueError(f"{type(part).__name__} declares the parameter {p.name!r} twice")
        out[p.name] = p
    return out


class _Owned(NamedTuple):
    """A parameter with the index of the part that declares it (0: the model, 1: the forcing)."""

    part: int
    parameter: Parameter


def _owners(model, forcing) -> dict[str, _Owned]:
    """Each parameter of the pair with the index of its part (0: the model, 1: the forcing)."""
    out: dict[str, _Owned] = {}
    for i, part in enumerate((model, forcing)):
        for name, p in table_of(part).items():
            if name in out:
                raise ValueError(f"parameter {name!r} is declared by both the model and the "
                                 f"{type(forcing).__name__}: names must be unique over a problem")
            out[name] = _Owned(i, p)
    return out


def parameters(model, forcing) -> dict[str, Parameter]:
    """Every parameter of a problem: the bar's, its impact law's and the forcing's (a load or a
    drive), by dotted name, in the parts' order.

    Parameters
    ----------
    model : BarModel
    forcing : Load or Drive

    Returns
    -------
    dict of str to Parameter

    Examples
    --------
    >>> from impactbar import BarModel, SquareWaveLoad
    >>> list(parameters(BarModel(s=10.0, d=0.3, R=0.5, n_modes=4), SquareWaveLoad(0.5, 1.5)))
    ['s', 'd', 'R', 'n_modes', 'q', 'kappa']
    """
    return {name: p for name, (_, p) in _owners(model, forcing).items()}


def unknown(model, forcing, names, name: str) -> ValueError:
    """The error for a name that is not one of ``names``, the parameters of the problem: it lists
    them and names the parts' types."""
    return ValueError(f"parameter must be one of {tuple(names)} (of the {type(model).__name__} and the "
                      f"{type(forcing).__name__}); got {name!r}")


def _find(model, forcing, name: str) -> _Owned:
    owners = _owners(model, forcing)
    if name not in owners:
        raise unknown(model, forcing, owners, name)
    return owners[name]


def parameter_value(model, forcing, name: str):
    """The current value of one parameter of a problem.

    Parameters
    ----------
    model, forcing : BarModel, and Load or Drive
        The problem.
    name : str
        One of :func:`parameters`.

    Returns
    -------
    float, int or None
        In the parameter's unit (``None`` where the part has no value for it now).

    Raises
    ------
    ValueError
        For an unknown name (the message lists the allowed ones).

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad
    >>> parameter_value(BarModel(s=10.0, d=0.3, R=0.5, n_modes=4), CosineLoad(0.3, 1.0), "pk")
    1.0
    """
    return _find(model, forcing, name).parameter.value


def with_parameter(model, forcing, name: str, value):
    """The problem with one parameter changed: the value checked against the parameter's range,
    then the part's copy validated again by its constructors.

    Parameters
    ----------
    model : BarModel
    forcing : Load or Drive
    name : str
        One of :func:`parameters`.
    value : float or int
        The new value, in the parameter's unit.

    Returns
    -------
    (BarModel, Load or Drive)
        The part that holds the parameter copied, the other one as it was.

    Raises
    ------
    ValueError
        For an unknown name (the allowed ones listed), a value outside the parameter's range (the
        name and the range given) or one a constructor refuses.

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad
    >>> model, load = BarModel(s=10.0, d=0.3, R=0.5, n_modes=4), CosineLoad(0.3, 1.0)
    >>> with_parameter(model, load, "R", 0.25)[0].R
    0.25
    >>> with_parameter(model, load, "R", 2.0)
    Traceback (most recent call last):
    ...
    ValueError: R must be in [0, 1]; got 2.0
    """
    i, p = _find(model, forcing, name)
    p.check(value)
    if i == 0:
        return model.with_parameter(name, value), forcing
    return model, _declarer(forcing).with_parameter(name, value)


def with_parameters(model, forcing, changes: dict):
    """The problem with several parameters changed as a set: every change applied, then the result
    validated once, so that the order of ``changes`` does not matter (``rock.k`` and ``rock.k_u``
    raised together past the old ``rock.k_u``, a circuit's relief pressure lowered with its
    pre-charge).

    Each value is first checked against its parameter's range as declared now; a value outside a
    range is still accepted where the range depends on another parameter changed with it (the
    bound of ``rock.k_u`` is ``rock.k``) and the changed problem's ranges hold it.

    Parameters
    ----------
    model : BarModel
    forcing : Load or Drive
    changes : dict of str to float or int

    Returns
    -------
    (BarModel, Load or Drive)

    Raises
    ------
    ValueError
        As :func:`with_parameter`: an unknown name, a value that is not a finite number, or a
        changed problem that a constructor refuses or whose ranges do not hold the new values.

    Examples
    --------
    >>> from impactbar import BarModel, BilinearRock, CosineLoad, RodRock, RodSegment
    >>> law = RodRock(segments=[RodSegment(length=2.0, impedance=2.0)], rock=BilinearRock(k=20.0, k_u=200.0))
    >>> model, load = BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law), CosineLoad(0.3, 1.0)
    >>> with_parameters(model, load, {"rock.k": 400.0, "rock.k_u": 800.0})[0].law.rock
    BilinearRock(k=400.0, k_u=800.0)
    """
    owners = _owners(model, forcing)
    bad = [n for n in changes if n not in owners]
    if bad:
        raise unknown(model, forcing, owners, bad[0])
    if len(changes) == 1:
        ((name, value),) = changes.items()
        return with_parameter(model, forcing, name, value)
    refused = [e for e in (_refusal(owners[n].parameter, v) for n, v in changes.items()) if e is not None]
    by_part: tuple[dict, dict] = ({}, {})
    for name in owners:  # (the parts' declaration order)
        if name in changes:
            by_part[owners[name].part][name] = changes[name]
    try:
        model_changes, forcing_changes = by_part
        new = (_changed(model, model_changes), _changed(forcing, forcing_changes))
    except (ValueError, TypeError, ArithmeticError):
        if refused:
            raise refused[0] from None
        raise
    if refused:  # (a range that depends on another changed parameter: the changed problem's ranges)
        ranges = _owners(*new)
        for name, value in changes.items():
            ranges[name].parameter.check(value)
    return new


def _refusal(p: Parameter, value) -> ValueError | None:
    """The error of ``p.check(value)``, or ``None``; raised at once where it is not about the range
    (not a finite real number, subnormal, an integer's range), which no other change can lift."""
    try:
        p.check(value)
    except ValueError as exc:
        if p.integer:
            raise
        try:
            replace(p, low=-math.inf, high=math.inf, low_open=True, high_open=True).check(value)
        except ValueError:
            raise exc from None
        return exc
    return None


def _changed(part, changes: dict):
    """The part with ``changes`` applied at once (its ``with_parameters``; one by one through
    ``with_parameter`` for a part that declares no such method)."""
    if not changes:
        return part
    several = getattr(_declarer(part), "with_parameters", None)
    if several is not None:
        return several(changes)
    for name, value in changes.items():
        part = _declarer(part).with_parameter(name, value)
    return part


def check_continuable(model, forcing, name: str) -> Parameter:
    """The parameter, where a branch of orbits can be followed in it (the problem smooth in it).

    Parameters
    ----------
    model : BarModel
    forcing : Load or Drive
    name : str

    Returns
    -------
    Parameter

    Raises
    ------
    ValueError
        For an unknown name, or one declared not continuable (the message gives the reason).
    """
    _, p = _find(model, forcing, name)
    if not p.continuable:
        why = p.reason or ("it takes integer values" if p.integer else "the problem is not smooth in it")
        raise ValueError(f"parameter {name!r} ({p.description}) cannot be continued: {why}")
    return p

