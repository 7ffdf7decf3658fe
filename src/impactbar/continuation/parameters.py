"""Continuation parameters: the fields of :class:`BarModel` and of the loads (paper eqs. 2, 33, 34)."""

from __future__ import annotations

from .._shared.validate import check_real
from ..loads import CosineLoad, FourierLoad, Load, SquareWaveLoad
from ..model import BarModel

__all__ = ["PARAMETERS", "parameter_value", "with_parameter"]

#: Parameters a branch can be continued in: BarModel fields and load fields.
PARAMETERS = ("p0", "pk", "R", "d", "s", "q", "kappa")

def parameter_value(model: BarModel, load: Load, name: str) -> float:
    """Current value of a continuation parameter.

    Parameters
    ----------
    model : BarModel
    load : Load
    name : str
        ``"s"``, ``"d"``, ``"R"`` (eqs. 2, 10), ``"p0"``, ``"pk"`` (a :class:`CosineLoad`, eq. 33;
        ``"p0"`` also of a :class:`FourierLoad`), ``"q"``, ``"kappa"`` (a :class:`SquareWaveLoad`,
        eq. 34).

    Returns
    -------
    float

    Raises
    ------
    ValueError
        For a name outside :data:`PARAMETERS` or one the load does not have.
    """
    _check_parameter(model, load, name)
    if name in ("R", "d", "s"):
        return float(getattr(model, name))
    return float(getattr(load, name))


def with_parameter(model: BarModel, load: Load, name: str, value: float):
    """The model and load with one parameter changed (validated again by their constructors).

    Parameters
    ----------
    model : BarModel
    load : Load
    name : str
        As in :func:`parameter_value`.
    value : float
        The new value.

    Returns
    -------
    (BarModel, Load)

    Raises
    ------
    ValueError
        For a name the model and load do not have, or a value outside its allowed range (for
        example ``R`` outside ``[0, 1]``, ``kappa`` outside ``[1, 2]``).
    """
    _check_parameter(model, load, name)
    if name in ("R", "d", "s"):
        return model.with_(**{name: value}), load
    if isinstance(load, CosineLoad):
        args = {"p0": load.p0, "pk": load.pk}
        args[name] = value
        return model, CosineLoad(args["p0"], args["pk"], load.k)
    if isinstance(load, SquareWaveLoad):
        args = {"q": load.q, "kappa": load.kappa}
        args[name] = value
        return model, SquareWaveLoad(args["q"], args["kappa"])
    return model, FourierLoad(value, load.harmonics())  # p0 of a FourierLoad


def _check_parameter(model, load, name):
    if name not in PARAMETERS:
        raise ValueError(f"parameter must be one of {PARAMETERS}; got {name!r}")
    if name in ("R", "d", "s"):
        return
    ok = {CosineLoad: ("p0", "pk"), SquareWaveLoad: ("q", "kappa")}
    for cls, names in ok.items():
        if isinstance(load, cls):
            if name not in names:
                raise ValueError(f"parameter {name!r} is not a field of {cls.__name__}; use one of "
                                 f"{names + ('R', 'd', 's')}")
            return
    if isinstance(load, FourierLoad) and name == "p0":
        return
    raise ValueError(f"parameter {name!r} cannot be continued for a {type(load).__name__}; "
                     "use R, d or s (or p0 for a FourierLoad)")


def _target(parameter, start, to):
    """The checked target value ``to`` of a continuation in ``parameter`` from ``start``."""
    to = check_real("to", to)
    if to == start:
        raise ValueError(f"to must differ from the start value {parameter} = {start}")
    return to
