"""The coupled blow in the periodic orbits of a drive with state under a law whose contact takes time
(theory §11, "The coupled blow"): the shooting problem's map through a blow
(:class:`~impactbar.orbits.driven.ShootingProblem`) and its Jacobian by central differences."""

from __future__ import annotations

import numpy as np

from ..drives.base import DriveState
from ..laws.abilities import CoupledBlow

__all__ = ["coupled_blow", "blow_piece", "blow_state", "blow_jacobian", "FD_STEP_BLOW", "FD_STEP_EXACT_BLOW"]

#: central-difference step of the coupled blow's Jacobian, relative to the modal and the drive's
#: components' largest sizes: the blow is integrated at rtol 1e-10 (noise / step ~1e-5) and its
#: truncation is O(step^2)
FD_STEP_BLOW = 1e-5
#: the central-difference step where the blows are exact (``RodRock``'s exact blows under a drive):
#: their noise is some 1e-11 of the state (the force's splines, the flights' tolerance), 1e-6 in the
#: multipliers at ``FD_STEP_BLOW``; at 1e-3 the noise is some 1e-8 and the truncation as small (on
#: the circuit on rock the multipliers at steps 1e-4, 3e-4 and 1e-3 agree to 1e-7, at 1e-5 they are
#: 5e-7 to 1.1e-6 off; the lattice's blows, smooth to 1e-9 at 1e-5, keep ``FD_STEP_BLOW``)
FD_STEP_EXACT_BLOW = 1e-3


def coupled_blow(model, drive, t, q, v, state, settings=None):
    """The coupled blow of an arrival at ``t`` in ``(q, q')`` with the drive's ``state``
    (:func:`impactbar.simulation.blows.driven_blow`).

    Returns
    -------
    y : numpy.ndarray, shape (2 N + 2 + k,)
        ``(q, q', z)`` after the blow and the drive's map at its end.
    t_after : float
        Where the blow ends.
    after : DriveState
        The drive's state after the map.
    blow : BlowPiece
        The blow as a piece of the period (:class:`~impactbar.simulation.blows.BlowPiece`).
    """
    out, res, after = blow_state(model, drive, t, q, v, state, settings)
    return out, res.t_release, after, blow_piece(model, t, q, v, res)


def blow_piece(model, t, q, v, res):
    """The blow ``res`` (:func:`blow_state`'s) of an arrival at ``t`` in ``(q, q')`` as a piece of
    the period (:class:`~impactbar.simulation.blows.BlowPiece`)."""
    from ..simulation.blows import BlowPiece

    c = model.end_weights
    qa = np.array(q, dtype=float)
    qa[0] -= float(c @ qa)
    return BlowPiece(t, res.t_release, res.record, (qa, np.array(v, dtype=float)), res.pieces, c,
                     (res.q_after.copy(), res.v_after.copy()))


def blow_state(model, drive, t, q, v, state, settings=None):
    """The coupled blow of :func:`coupled_blow` without its piece (the blows whose pieces nobody keeps:
    the Jacobian's, the settling's, the residuals').

    Parameters
    ----------
    model : BarModel
        Under a law whose contact takes time (:meth:`~impactbar.laws.abilities.CoupledBlow.driven_contact`).
    drive : Drive
        A drive with state that follows a blow (its ability ``end_flight``).
    t : float
        Time of the arrival (model units).
    q, v : array_like, shape (N + 1,)
        Modal positions and velocities at the arrival (the end moved onto the stop first).
    state : DriveState
        The drive's state as the piston arrives.
    settings : FlightSettings, optional
        The drive's integrator over the blow (default the drive's own).

    Returns
    -------
    y : numpy.ndarray, shape (2 N + 2 + k,)
        ``(q, q', z)`` after the blow and the drive's map at its end.
    res : DrivenContact
        The law's blow (:meth:`~impactbar.laws.abilities.CoupledBlow.driven_contact`).
    after : DriveState
        The drive's state after the map.
    """
    from ..simulation.blows import driven_blow

    res, after = driven_blow(model, drive, state, t, q, v, settings)
    return np.concatenate((res.q_after, res.v_after, after.z)), res, after


def blow_jacobian(model, drive, t, q, v, state, settings=None, *, forward=None, blow=None) -> np.ndarray:
    """The Jacobian of the coupled blow's map ``(q, q', z)`` at arrival ``->`` after it: where the
    law's blows are exact, from the law's tangent of the blow
    (:meth:`~impactbar.laws.abilities.CoupledBlow.driven_tangent`) where it covers the blow; else by
    central differences (steps ``FD_STEP_BLOW``, or ``FD_STEP_EXACT_BLOW`` where the law's blows are exact,
    times the largest modal and drive components, each group by its own scale; the map puts ``q_0``
    on the stop first, so its column is 0): the blow is
    autonomous (the drive's force follows its state), so it has no time derivative. ``4 N + 12 +
    2 (k - 4)`` blows; with ``forward``, by forward differences from it, half as many.

    Parameters
    ----------
    model, drive, t, q, v, state, settings
        As :func:`blow_state`.
    forward : numpy.ndarray, shape (2 N + 2 + k,), optional
        The blow's map at the point itself (:func:`blow_state`'s ``y`` with the same arguments):
        forward differences from it, their error ``O(FD_STEP_BLOW)`` where the central differences'
        is ``O(FD_STEP_BLOW^2)``, for a Jacobian that only steers Newton's method (no tangent).
    blow : tuple, optional
        ``(res, after)`` of :func:`blow_state` with the same arguments (the blow at the point, for the
        tangent; solved here where not given).

    Returns
    -------
    numpy.ndarray, shape (2 N + 2 + k, 2 N + 2 + k)
    """
    M = model.n_modes + 1
    y = np.concatenate((q, v, state.z))
    n = y.size
    if forward is not None and np.shape(forward) != (n,):
        raise ValueError(f"forward must have shape ({n},); got {np.shape(forward)}")
    scale = np.empty(n)
    scale[:2 * M] = max(float(np.max(np.abs(y[:2 * M]))), 1e-300)
    scale[2 * M:] = max(float(np.max(np.abs(y[2 * M:]))), 1e-300)
    G = np.zeros((n, n))

    def solve(yy):
        st = DriveState(state.mode, yy[2 * M:].copy())
        y_after, _, _ = blow_state(model, drive, t, yy[:M], yy[M:2 * M], st, settings)
        return y_after

    blow_method = getattr(model.law, "blow_method", None)
    exact = forward is None and blow_method is not None and blow_method(model) == "exact"
    coupled = model.law.ability(CoupledBlow)  # (a law's blow coupled to a drive, and its tangent)
    if exact and coupled is not None:
        tangent = coupled.driven_tangent
        if blow is None:
            _, res, after = blow_state(model, drive, t, q, v, state, settings)
        else:
            res, after = blow
        exact_G = tangent(model, drive, res, after, state)
        if exact_G is not None:
            return exact_G
    step = FD_STEP_EXACT_BLOW if exact else FD_STEP_BLOW
    for j in range(n):
        if j == 0 and float(model.end_weights[0]) == 1.0:  # q_0 along the section: no effect
            continue
        h = step * scale[j]
        yp = y.copy()
        yp[j] += h
        if forward is not None:
            G[:, j] = (solve(yp) - forward) / h
            continue
        ym = y.copy()
        ym[j] -= h
        G[:, j] = (solve(yp) - solve(ym)) / (2.0 * h)
    return G
