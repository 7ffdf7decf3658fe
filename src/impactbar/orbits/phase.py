"""The phase equation of one-impact orbits (paper eq. 14, theory §4): its right-hand
factor ``G(d, R)``, its residual, and every root ``phase`` in ``[0, 2 pi)``. The equation is the
paper law's (:mod:`impactbar.laws.paper.phase`); here the solvers' check of their inputs and the
public entry points."""

from __future__ import annotations

from .._shared.forcing import check_family
from ..laws.paper.phase import phase_G as phase_G
from ..laws.paper.phase import phase_residual as phase_residual
from ..laws.paper.phase import phase_roots as _phase_roots
from ..loads import Load
from ..model import BarModel

__all__ = ["phase_G", "phase_residual", "phase_roots"]


def _check_inputs(model, load):
    if not isinstance(model, BarModel):
        raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
    check_family(load, "load", hint=" (a drive is not periodic in time: the phase equation and the "
                 "one-impact orbits of a periodic load do not apply; use find_orbit(model, drive), unknown "
                 "period, theory §10, or simulate)")


def phase_roots(model: BarModel, load: Load, *, closed_form: bool = True) -> list[tuple[float, int]]:
    """Every root of the phase equation in ``[0, 2 pi)``, with its multiplicity (1, or 2 at a fold).

    Roots are enclosed with certainty: ``|F'| = (1 + R)|p - p0 - d V| <= 2 (1 + R) sup|p - p0|``
    bounds the slope of the residual, so an interval whose midpoint residual exceeds that bound
    times its half-width holds no root (see ``_certified``). Enclosed roots are refined by Brent's
    method; a cluster without a sign change is a double root when the residual's extremum there is
    zero to rounding.

    Parameters
    ----------
    model : BarModel
    load : Load
    closed_form : bool
        Use the closed form for a load with a single harmonic (default); ``False`` forces the
        certified search (used by the tests to check one against the other).

    Returns
    -------
    list of (float, int)
        ``(phase, multiplicity)`` sorted by phase.

    Raises
    ------
    ValueError
        For a model that is not a :class:`~impactbar.BarModel` or a load that is not a periodic
        :class:`~impactbar.Load`.
    """
    _check_inputs(model, load)
    return _phase_roots(model, load, closed_form=closed_form)
