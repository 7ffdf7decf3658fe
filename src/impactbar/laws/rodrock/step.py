"""The simulator's contact step under the rod-and-rock law (theory §4d): the exact blow's map
(:mod:`impactbar.laws.rodrock.exactmap`) or the lattice's (:mod:`impactbar.laws.rodrock.contact`),
as :meth:`~impactbar.RodRock.blow_method` chooses."""

from __future__ import annotations

import numpy as np

from .contact import BlowMap, RockContact

__all__ = ["blow_map", "fd_impact_map", "map_with_jacobians", "rock_contact"]


def rock_contact(model, load, t0: float, q, v, *, cells_per_piston: int | None = None,
                 duration: float | None = None) -> RockContact:
    """The blow of a piston arriving at the shank in modal state ``(q, q')`` at load time ``t0``,
    with the drive acting (theory §4d; the module's text states the method and its assumptions).

    Parameters
    ----------
    model : BarModel
        With ``impact=RodRock(...)``; its ``s`` and ``n_modes`` (``R`` and ``d`` play no part).
    load : Load
        The drive at ``x = 0``.
    t0 : float
        Load time of the impact.
    q, v : array_like, shape (N + 1,)
        Modal state at impact, positions from the shank (``u(1) = 0``).
    cells_per_piston : int, optional
        As :func:`~impactbar.single_blow`.
    duration : float, optional
        Length of the blow (model time; on the lattice rounded up to whole cell steps); default
        :meth:`RodRock.window`.

    Returns
    -------
    RockContact
        An :class:`~impactbar.laws.rodrock.exactmap.ExactRockContact` for the exact blows.
    """
    return blow_map(model, load, t0, cells_per_piston=cells_per_piston, duration=duration).contact(q, v)


def blow_map(model, load, t0, *, cells_per_piston=None, duration=None):
    """The contact step's map at one impact time: an
    :class:`~impactbar.laws.rodrock.exactmap.ExactBlowMap` where the law's blows are exact
    (:meth:`RodRock.blow_method`, and no ``cells_per_piston`` given), else the lattice's
    :class:`BlowMap`."""
    if cells_per_piston is None and model.law.blow_method(model) == "exact":
        from .exactmap import ExactBlowMap

        return ExactBlowMap(model, load, t0, duration=duration)
    return BlowMap(model, load, t0, cells_per_piston=cells_per_piston, duration=duration)


def map_with_jacobians(step, y_minus, t):
    """A contact step's map ``y_plus`` of the arrival state ``y_minus`` at load time ``t`` with its
    Jacobians (:meth:`RodRock.impact_map`): exact by the blow's tangent runs for an
    :class:`~impactbar.laws.rodrock.exactmap.ExactBlowMap`
    (:func:`~impactbar.laws.rodrock.exactjac.exact_impact_map`, ``2 N + 2`` tangent runs), by central
    differences (:func:`fd_impact_map`) for the lattice's :class:`BlowMap` and where the exact map
    has no derivative there (a grazing re-contact).

    Returns
    -------
    y_plus : numpy.ndarray, shape (2 N + 2,)
    jac_y : numpy.ndarray, shape (2 N + 2, 2 N + 2)
    jac_t : numpy.ndarray, shape (2 N + 2,)
    """
    from .exactmap import ExactBlowMap

    if isinstance(step, ExactBlowMap):
        from .exactjac import exact_impact_map

        out = exact_impact_map(step, y_minus, t)
        if out is not None:
            return out
    return fd_impact_map(step, y_minus, t)


def fd_impact_map(step, y_minus, t):
    """A contact step's map ``y_plus`` of the arrival state ``y_minus`` at load time ``t``, with its
    Jacobians by central finite differences (:meth:`RodRock.impact_map`): steps
    ``h = 1e-6 |y_minus|_inf`` in the state (relative: the same map at every scale of the load) and
    ``1e-6`` in ``t``, ``4 N + 6`` blows of ``step`` (a :class:`BlowMap` or an
    :class:`~impactbar.laws.rodrock.exactmap.ExactBlowMap`, with ``shifted`` for ``t``).

    Returns
    -------
    y_plus : numpy.ndarray, shape (2 N + 2,)
    jac_y : numpy.ndarray, shape (2 N + 2, 2 N + 2)
    jac_t : numpy.ndarray, shape (2 N + 2,)
    """
    y = np.array(y_minus, dtype=float)
    t = float(t)
    y_plus = step(y)
    h = 1e-6 * (float(np.max(np.abs(y))) or 1.0)  # relative: the orbit's scale is the load's
    jac = np.empty((y.size, y.size))
    for j in range(y.size):
        e = np.zeros(y.size)
        e[j] = h
        jac[:, j] = (step(y + e) - step(y - e)) / (2.0 * h)
    ht = 1e-6
    up, down = step.shifted([t + ht, t - ht])
    jt = (up(y) - down(y)) / (2.0 * ht)
    return y_plus, jac, jt
