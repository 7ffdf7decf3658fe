"""Continuation parameters: the fields of :class:`BarModel` and of the loads (paper eqs. 2, 33, 34),
and those of the rod-rock law (theory §4d)."""

from __future__ import annotations

import dataclasses
import re

from .._shared.validate import check_real
from ..loads import LOADS, Load
from ..model import BarModel

__all__ = ["PARAMETERS", "ROCK_PARAMETERS", "parameter_value", "with_parameter"]

#: The BarModel fields a branch can be continued in.
MODEL_PARAMETERS = ("R", "d", "s")
#: Parameters a branch can be continued in: BarModel fields and the loads' continuation parameters
#: (:attr:`impactbar.Load.continuation_parameters` of the table of loads).
PARAMETERS = tuple(dict.fromkeys((*MODEL_PARAMETERS,
                                  *(p for cls in LOADS.values() for p in cls.continuation_parameters))))

#: Parameters of a model with ``impact=RodRock(...)`` (theory §4d), in the law's units: the rock's
#: loading and unloading stiffnesses (``"rock.k"`` alone, ``k_u`` kept, so ``k <= k_u``), the bit's
#: mass, the feed force, and ``"segment<i>.length"`` (``i`` from 0 at the shank; the default
#: ``blow_time`` follows the lengths). :func:`~impactbar.continue_orbit` takes all but the lengths
#: (the blow's cell grid rounds them to whole cells: the orbit changes in steps with a length);
#: :func:`~impactbar.continuation.simulated_diagram` takes them all.
ROCK_PARAMETERS = ("rock.k", "rock.k_u", "bit_mass", "feed", "segment<i>.length")

_SEGMENT = re.compile(r"segment(\d+)\.length")

def parameter_value(model: BarModel, load: Load, name: str) -> float:
    """Current value of a continuation parameter.

    Parameters
    ----------
    model : BarModel
    load : Load
    name : str
        ``"s"``, ``"d"``, ``"R"`` (eqs. 2, 10), ``"p0"``, ``"pk"`` (a :class:`CosineLoad`, eq. 33;
        ``"p0"`` also of a :class:`FourierLoad`), ``"q"``, ``"kappa"`` (a :class:`SquareWaveLoad`,
        eq. 34); under the rod-rock law also ``"rock.k"``, ``"rock.k_u"``, ``"bit_mass"``,
        ``"feed"``, ``"segment0.length"``, ... (:data:`ROCK_PARAMETERS`).

    Returns
    -------
    float

    Raises
    ------
    ValueError
        For a name outside :data:`PARAMETERS` or one the load does not have.

    Examples
    --------
    >>> from impactbar import BarModel, BilinearRock, CosineLoad, RodRock, RodSegment
    >>> law = RodRock(segments=[RodSegment(length=2.0, impedance=2.0)],
    ...               rock=BilinearRock(k=20.0, k_u=200.0))
    >>> model = BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law)
    >>> load = CosineLoad(0.3, 1.0)
    >>> parameter_value(model, load, "rock.k"), parameter_value(model, load, "segment0.length")
    (20.0, 2.0)
    """
    if _is_rock(model, name):
        return _rock_value(model.law, name)
    _check_parameter(model, load, name)
    if name in MODEL_PARAMETERS:
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
        example ``R`` outside ``[0, 1]``, ``kappa`` outside ``[1, 2]``, ``rock.k`` above
        ``rock.k_u``).

    Examples
    --------
    >>> from impactbar import BarModel, BilinearRock, CosineLoad, RodRock, RodSegment
    >>> law = RodRock(segments=[RodSegment(length=2.0, impedance=2.0)],
    ...               rock=BilinearRock(k=20.0, k_u=200.0))
    >>> model, load = with_parameter(BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law),
    ...                              CosineLoad(0.3, 1.0), "rock.k", 30.0)
    >>> model.law.rock
    BilinearRock(k=30.0, k_u=200.0)
    """
    if _is_rock(model, name):
        return model.with_(impact=_rock_with(model.law, name, float(value))), load
    _check_parameter(model, load, name)
    if name in MODEL_PARAMETERS:
        return model.with_(**{name: value}), load
    return model, load.with_(**{name: value})


def _is_rock(model, name) -> bool:
    """Whether ``name`` is a rod-rock parameter (checked against the model's law: a ``ValueError``
    naming the law for a model without one)."""
    if name not in ("rock.k", "rock.k_u", "bit_mass", "feed") and not _SEGMENT.fullmatch(str(name)):
        return False
    from ..laws.rodrock import RodRock

    law = getattr(model, "law", None)
    if not isinstance(law, RodRock):
        raise ValueError(f"parameter {name!r} is one of the rod-rock law's {ROCK_PARAMETERS}; the model "
                         f"has impact={getattr(model, 'impact', None)!r}")
    match = _SEGMENT.fullmatch(name)
    if match and int(match.group(1)) >= len(law.segments):
        raise ValueError(f"parameter {name!r}: the rod has {len(law.segments)} segment(s), "
                         f"segment0 to segment{len(law.segments) - 1}")
    return True


def _rock_value(law, name) -> float:
    if name.startswith("rock."):
        return float(getattr(law.rock, name[5:]))
    match = _SEGMENT.fullmatch(name)
    if match:
        return float(law.segments[int(match.group(1))].length)
    return float(getattr(law, name))


def _rock_with(law, name, value):
    """The law with one parameter changed (validated again by the constructors)."""
    if name.startswith("rock."):
        return dataclasses.replace(law, rock=dataclasses.replace(law.rock, **{name[5:]: value}))
    match = _SEGMENT.fullmatch(name)
    if match:
        i = int(match.group(1))
        segs = list(law.segments)
        segs[i] = dataclasses.replace(segs[i], length=value)
        return dataclasses.replace(law, segments=segs)
    return dataclasses.replace(law, **{name: value})


def _check_parameter(model, load, name, *, continuation=False):
    """Whether ``name`` is a parameter of the model and load; for ``continuation`` also that the
    problem is smooth in it (not a segment length: the blow's cell grid rounds the segments to
    whole cells, so the blow changes in steps with a length)."""
    if _is_rock(model, name):
        if continuation and _SEGMENT.fullmatch(name):
            raise ValueError(f"parameter {name!r} cannot be continued: the blow's cell grid rounds the "
                             "segments' travel times to whole cells, so the orbit changes in steps "
                             "with a length; follow it with simulated_diagram or find_orbit at each "
                             "length")
        return
    if name not in PARAMETERS:
        raise ValueError(f"parameter must be one of {PARAMETERS}; got {name!r}")
    if name in MODEL_PARAMETERS:
        return
    names = getattr(load, "continuation_parameters", ())
    if name not in names:
        raise ValueError(f"parameter {name!r} is not a field of {type(load).__name__} that can be "
                         f"continued; use one of {(*names, *MODEL_PARAMETERS)}")


def _target(parameter, start, to):
    """The checked target value ``to`` of a continuation in ``parameter`` from ``start``."""
    to = check_real("to", to)
    if to == start:
        raise ValueError(f"to must differ from the start value {parameter} = {start}")
    return to
