"""Continuation parameters: thin views of the parameter protocol (:mod:`impactbar.parameters`) for a
branch of orbits: the real parameters of the bar (eq. 2), of the load (eqs. 33, 34) or drive, and of
the impact law (the rod-rock law's, theory §4d), each declared by its part alone."""

from __future__ import annotations

from .._shared import parameters as protocol
from .._shared.validate import check_real
from ..laws import RodRock
from ..loads import LOADS, Load
from ..model import BarModel

__all__ = ["PARAMETERS", "ROCK_PARAMETERS", "parameter_value", "with_parameter"]

#: The BarModel fields a branch can be continued in: its declared real numbers (``s``, ``d``, ``R``
#: of :attr:`BarModel.parameters`; ``n_modes``, an integer, is swept, not continued).
MODEL_PARAMETERS = tuple(f.name for f in BarModel.parameters if not f.dtype.startswith("i"))
#: Parameters a branch can be continued in: BarModel fields and the loads' continuation parameters
#: (the ``traits.continuation_parameters`` of the table of loads), as listed by their classes;
#: the parameters of one problem: :func:`impactbar.parameters.parameters`.
PARAMETERS = tuple(dict.fromkeys((*MODEL_PARAMETERS, *(p for cls in LOADS.values()
                                                       for p in cls.traits.continuation_parameters))))

#: Parameters of a model with ``impact=RodRock(...)`` (theory §4d), in the law's units: the rock's
#: loading and unloading stiffnesses (``"rock.k"`` alone, ``k_u`` kept, so ``k <= k_u``), the bit's
#: mass, the feed force, and ``"segment<i>.length"`` (``i`` from 0 at the shank; the default
#: ``blow_time`` follows the lengths). :func:`~impactbar.continue_orbit` takes all but the lengths
#: on the lattice (the blow's cell grid rounds them to whole cells: the orbit changes in steps with
#: a length); :func:`~impactbar.continuation.simulated_diagram` takes them all
#: (:meth:`RodRock.parameter_table`; kept as the law's list of names).
ROCK_PARAMETERS = RodRock.parameters


def _real(model, forcing, name):
    """The record of a real parameter of the problem (a ``ValueError`` listing them for any other
    name: an integer parameter such as ``n_modes`` is swept, not continued)."""
    table = protocol.parameters(model, forcing)
    p = table.get(name)
    if p is None or p.integer:
        raise protocol.unknown(model, forcing, (n for n, q in table.items() if not q.integer), name)
    return p


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
        ``"feed"``, ``"segment0.length"``, ... (:data:`ROCK_PARAMETERS`); any real parameter a part
        of the problem declares (:func:`impactbar.parameters.parameters`).

    Returns
    -------
    float
        The parameter's value (dimensionless, or in the law's units).

    Raises
    ------
    ValueError
        For a name that is not a real parameter of the model and load (the message lists them).

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
    value = _real(model, load, name).value
    return None if value is None else float(value)


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
    _real(model, load, name)
    return protocol.with_parameter(model, load, name, value)


def _check_parameter(model, load, name, *, continuation=False):
    """Whether ``name`` is a real parameter of the model and load; for ``continuation`` also that
    the problem is smooth in it (its record's ``continuable``: not a segment length on the lattice,
    whose cell grid rounds the segments to whole cells, so the blow changes in steps with a length)."""
    _real(model, load, name)
    if continuation:
        protocol.check_continuable(model, load, name)


def _target(parameter, start, to, model=None, load=None):
    """The checked target value ``to`` of a continuation in ``parameter`` from ``start``; with
    ``model`` and ``load``, a target outside the parameter's allowed range is refused where the start
    sits at the end of that range on the target's side (no branch can leave it that way; a target
    beyond a range the branch can enter stops the branch at its end, status ``"parameter range"``)."""
    to = check_real("to", to)
    if to == start:
        raise ValueError(f"to must differ from the start value {parameter} = {start}")
    if model is not None:
        try:
            with_parameter(model, load, parameter, to)
        except ValueError as outside:
            near = start + 1e-9 * (to - start) if start != 0.0 else 1e-12 * to
            try:
                with_parameter(model, load, parameter, near)
            except ValueError:
                raise ValueError(f"to = {to:g} is outside the allowed range of {parameter} and the start "
                                 f"{parameter} = {start:g} is at its end: no branch leaves it that "
                                 f"way ({outside})") from None
    return to
