"""The last Newton steps of a periodic orbit of the shooting problem whose flights integrate the
variational equations (:class:`.driven.ShootingProblem`, the oil circuit; theory §11): the closing
step from the chord's root and, where the flights' state is a plain flight of its own, the check of
the root by the multipliers' flight.

The chord (:func:`~impactbar.drives.orbitproblem.chord`) takes plain flights at the drive's
tolerance and Jacobians that only steer (Magnus' coarser steps, ``STEER_THETA``). The orbit is the
root of the variational flights, whose state is integrated a thousand times finer: the closing step
is one Newton step with a steering flight there, and for a one-impact orbit the chord hands over
to it already after a Newton step below :data:`CLOSING_HANDOVER` (that iterate's error of the order
of the step's square). The multipliers' flight from the root then gives Newton's next step with
the exact Jacobian; it must be below :data:`CLOSING_CHECK` times the tolerance, else it is taken
and the flight flown again, so that the orbit returned is the root its own multipliers' flight
confirms. Where the chord's plain flights are the root's (:func:`root_settings`), the motion followed
to a start is handed over sooner (:func:`settle_handover`) and the chord's first step takes the
steering flight's residual (:func:`first_residual`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..drives.orbitproblem import at_rounding_floor, step_size

__all__ = ["SETTLE_HANDOVER", "SETTLE_LIFTED", "SETTLE_RTOL", "CLOSING_HANDOVER", "LIFTED_HANDOVER",
           "CLOSING_CHECK", "STEER_ERROR", "CLOSING_STEPS", "ROOT_HANDOVER", "LOOSE_FIRST",
           "ROOT_SETTLE_RTOL", "STEER_PHI_ATOL", "close", "settle_start", "least_impacts",
           "LOOSE_CURVATURE", "loose_contraction", "checked_root", "root_settings", "settle_handover",
           "loose_settings", "settle_settings", "steer_settings", "first_residual"]

#: How closely the impact velocities of the motion followed to a start agree, impact after impact,
#: before Newton's method takes over (a drive whose flights integrate the variational equations).
SETTLE_HANDOVER = 1e-4
#: Impacts followed from the rigid piston's orbit, its modes at rest, to a flexible piston's Newton
#: start where the drive's flights are variational (others settle as from rest).
SETTLE_LIFTED = 3
#: The integrator's relative tolerance while the motion is followed to a start for Newton (a drive
#: whose flights integrate the variational equations: Newton's flights keep the drive's tolerance).
SETTLE_RTOL = 1e-7
#: The size of a Newton step (relative to the unknowns, as Newton's steps are measured) after which
#: the chord hands a one-impact orbit over to its closing step (the preset ``circuit-drifter``'s first
#: steps with 4, 8 and 16 modes: 7.2e-5, 7.8e-5 and 7.7e-5, the iterates then some 3e-8 and 4e-8
#: from the root).
CLOSING_HANDOVER = 2e-4
#: The same for the rigid piston's orbit that a flexible piston's start lifts (a start only: followed
#: three impacts at the loose tolerance after).
LIFTED_HANDOVER = 1e-3
#: The largest Newton step, in the tolerance (``1e-10`` at the drive's own), that the multipliers'
#: flight may find at a root before another Newton step is taken (the preset's orbits with 4, 8 and
#: 16 modes: 4e-13, 6e-12 and 1.2e-11 after the chord handed over).
CLOSING_CHECK = 0.1
#: A bound on the steering Jacobians' error (``STEER_THETA``) as the closing step meets it: the
#: residual it leaves over its own size. After the closing step, chord steps with its Jacobian (a
#: plain flight at the variational state's tolerance each, a quarter of the multipliers' flight)
#: follow while this times the last step could exceed what the check allows, at most
#: :data:`CLOSING_STEPS` of them. Measured on the preset with one of ten parameters changed (pump
#: flow, pre-charge, switch-out, front volume, bulk modulus, valve coefficient, switching time) and 2
#: to 16 modes: from 1e-6 to 6e-3 (1.7e-5, 1.4e-4 and 2.7e-4 on the preset with 4, 8 and 16 modes);
#: with 1e-3 none of those 40 orbits flew the multipliers' flight twice, where without the chord
#: steps 12 did, and the preset's orbits take none of them (closing steps of 3e-8 to 5e-8).
STEER_ERROR = 1e-3
CLOSING_STEPS = 4
#: How closely the impact velocities of the motion followed to a start agree, impact after impact,
#: before the chord takes over where its plain flights are the orbit's root's (:func:`root_settings`),
#: in place of :data:`SETTLE_HANDOVER` (1e-4): its first step then takes the
#: steering flight's residual (:func:`first_residual`), a Newton step from a start this far off. The
#: spool drill (``examples/circuit_drill_spool.toml``) from rest, its start carried to the relief
#: valve's setting: from the second impact after, its impact velocities 5.3e-4, 1.4e-4 and 2.9e-5
#: from the one before (each impact a period of 29 flights at the loose tolerance); handed over at the
#: 1.4e-4, its orbit 1.3e-10 from one at ``rtol = 1e-12`` (as at the 2.9e-5); at the 5.3e-4 (1e-3)
#: 3.0e-10, the chord's Jacobian taken that much farther from the root contracting its steps less.
ROOT_HANDOVER = 3e-4
#: The size of the steering flight's residual (relative to the unknowns, at least 1) above which the
#: chord's first step takes it where its plain flights are the root's (:func:`first_residual`): ten
#: times the loose flights' tolerance (``SETTLE_RTOL``, 1e-7), so that the first step, larger than
#: the residual's error, never ends the chord at that residual's root (the chord's tolerance, 1e-9 at
#: the drive's, being far below it); its next steps take the root's flights and correct that error.
LOOSE_FIRST = 1e-6
#: The integrator's relative tolerance while the motion is followed to a start where the chord's plain
#: flights are the orbit's root's (:func:`settle_settings`), in place of :data:`SETTLE_RTOL` (1e-7;
#: ``atol`` scaled as much). That motion only leads to the hand-over (its impact velocities agreeing to
#: :data:`ROOT_HANDOVER`, 3e-4) and the drift's tests (1e-4); the root is the chord's. On the spool
#: drill (``examples/circuit_drill_spool.toml``) its impact velocities lie 0.8e-5 to 3.0e-5 (relative)
#: from those at 1e-7, changing by at most 1.3e-5 from one impact to the next (3e-6: 0.3e-5 to 0.75e-5;
#: 1e-4: 1.5e-4 to 2.9e-4, at the tests' own size), the same 8 impacts followed, 6,435 of the orbit's
#: 27,778 CVODE steps saved and the orbit as near one at ``rtol = 1e-12`` (1.4e-10 of the unknowns,
#: 1.3e-10 before; ``benchmarks/HISTORY.md``).
ROOT_SETTLE_RTOL = 1e-5
#: CVODE's absolute tolerance on the fundamental matrix of the chord's steering flight where the
#: chord's plain flights are the orbit's root's (:func:`steer_settings`), in place of the state's
#: (``1e-9`` at :data:`SETTLE_RTOL`): that matrix only steers the chord, whose root is the plain
#: flights', so its rows (the small volumes' pressures, some 90 % of the variational steps' limits)
#: need not hold CVODE's error test; the state and the energies, whose residual the chord's first step
#: takes (:func:`first_residual`), keep theirs. On the spool drill (``examples/circuit_drill_spool.toml``)
#: the steering period's 2,625 CVODE steps fall to 1,705 (1e-7: 2,011; 1e-6: 1,861; 1e-4: 1,668), the
#: chord's steps as many (one plain period at the root's tolerance) and its orbit as near one at
#: ``rtol = 1e-12`` (1.4e-10 of the unknowns; ``benchmarks/HISTORY.md``).
STEER_PHI_ATOL = 1e-5
#: How much the chord's contraction grows with its first step's size (relative, as Newton's steps
#: are measured) where that step took the steering flight's residual and the plain flights are the
#: orbit's root's (:func:`loose_contraction`): the Jacobian, taken at the start, is then some
#: ``LOOSE_CURVATURE * s1`` off the one at the first iterate. On the spool drill
#: (``examples/circuit_drill_spool.toml``, and at 40 and 50 L/min of pump flow, from rest and from the
#: relief valve's setting) the third step over the second was 1.1e-5 to 1.9e-2, 0.3 to 18 times the
#: first step's size (``benchmarks/HISTORY.md``); a five-fold margin.
LOOSE_CURVATURE = 100.0

_UNSET = object()


def root_settings(problem):
    """The integrator of the plain flights whose root is the orbit of ``problem`` (a
    :class:`.driven.ShootingProblem`), its drive's ``OwnFlight.root_settings`` with the problem's
    settings, made once a problem: the chord's residuals then take those flights and its root needs
    no closing step (:meth:`.driven.ShootingProblem.solve`); ``None`` where the drive has none, with
    coupled blows, or where the variational flights' state is a plain flight of its own (the checked
    root's).

    Parameters
    ----------
    problem : ShootingProblem

    Returns
    -------
    FlightSettings or None
    """
    out = problem.__dict__.get("_root_settings", _UNSET)
    if out is _UNSET:
        own = problem.drive.abilities.flight if problem.variational else None
        wanted = own is not None and own.root_settings is not None and not problem.coupled \
            and not problem.state_flights
        out = own.root_settings(problem.model, problem.settings) if wanted else None
        problem._root_settings = out
    return out


def settle_handover(problem, default: float) -> float:
    """How closely the impact velocities of the motion followed to a start of ``problem`` agree before
    the chord takes over: :data:`ROOT_HANDOVER` where its plain flights are the orbit's root's
    (:func:`root_settings`), else ``default`` (the shooting problem's own).

    Parameters
    ----------
    problem : ShootingProblem
    default : float
        The relative agreement otherwise (dimensionless).

    Returns
    -------
    float
    """
    return ROOT_HANDOVER if root_settings(problem) is not None else default


def settle_start(problem, q, v):
    """The drive's state from which the motion of ``problem`` is followed to Newton's start without a
    guess, the piston at rest on the stop (``q``, ``v``): where the chord's plain flights are the
    orbit's root's (:func:`root_settings`), the drive's ``OwnFlight.charged_start`` where it gives one
    (the oil circuit's supply at its relief valve's setting: on the spool drill,
    ``examples/circuit_drill_spool.toml``, 5 impacts followed where 8 were from the pre-charge, 4 of
    them charging the supply before its drift was carried to the relief's setting), else the drive's
    ``start``.

    Parameters
    ----------
    problem : ShootingProblem
    q, v : numpy.ndarray, shape (M,)
        The piston's modal displacements and velocities (scaled).

    Returns
    -------
    DriveState
    """
    own = problem.drive.abilities.flight
    if root_settings(problem) is not None and own.charged_start is not None:
        state = own.charged_start(problem.model, q, v)
        if state is not None:
            return state
    return problem.drive.start(problem.model, q, v)


def least_impacts(problem, m: int) -> int:
    """How many impacts of the motion followed to a start of ``problem`` (``m`` impacts a period) must
    be passed before their velocities' agreement may hand it over: ``2 m + 2``, or ``2 m + 1`` where
    the chord's plain flights are the orbit's root's (:func:`root_settings`), the motion followed from
    the drive's charged start (:func:`settle_start`) and the chord's first step taking the steering
    flight's residual: on the spool drill (``examples/circuit_drill_spool.toml``) the fourth impact's
    velocity agrees with the third's to 4.3e-5, the fifth's with the fourth's to 7.9e-6, and handed
    over at the fourth the chord's first step is 1.6e-5 where it was 1.5e-6, its steps as many (one
    plain period at the root's tolerance) and the orbit 1.5e-10 from one at ``rtol = 1e-12`` (1.0e-10
    at the fifth; ``benchmarks/HISTORY.md``).

    Parameters
    ----------
    problem : ShootingProblem
    m : int
        Impacts a period.

    Returns
    -------
    int
    """
    return 2 * m + (1 if root_settings(problem) is not None else 2)


def loose_settings(settings):
    """The integrator at :data:`SETTLE_RTOL` (its ``atol`` scaled as much): the flights that only lead
    to Newton's start or steer it.

    Parameters
    ----------
    settings : FlightSettings
        The drive's flights (the orbit's tolerance).

    Returns
    -------
    FlightSettings
        ``settings`` with ``rtol`` at least :data:`SETTLE_RTOL`.
    """
    return dataclasses.replace(settings, rtol=max(settings.rtol, SETTLE_RTOL),
                               atol=max(settings.atol, SETTLE_RTOL * settings.atol / settings.rtol))


def settle_settings(problem, loose):
    """The integrator of the motion followed to a start of ``problem`` (``loose`` its flights at
    :data:`SETTLE_RTOL`, ``None`` for a drive without variational flights): at
    :data:`ROOT_SETTLE_RTOL` (``atol`` scaled as much) where the chord's plain flights are the orbit's
    root's (:func:`root_settings`), else ``loose`` itself.

    Parameters
    ----------
    problem : ShootingProblem
    loose : FlightSettings or None
        The flights at the loose tolerance (:func:`loose_settings`).

    Returns
    -------
    FlightSettings or None
    """
    if loose is None or root_settings(problem) is None or loose.rtol >= ROOT_SETTLE_RTOL:
        return loose
    return dataclasses.replace(loose, rtol=ROOT_SETTLE_RTOL, atol=ROOT_SETTLE_RTOL * loose.atol / loose.rtol)


def steer_settings(problem, loose):
    """The integrator of the chord's steering flight of ``problem`` (``loose`` its flights at
    :data:`SETTLE_RTOL`): its fundamental matrix at :data:`STEER_PHI_ATOL` where the chord's plain
    flights are the orbit's root's (:func:`root_settings`) and ``loose`` takes a tolerance of its own
    for it (a ``phi_atol``: the oil circuit's, :class:`~impactbar.drives.circuit.CircuitFlightSettings`),
    else ``loose`` itself.

    Parameters
    ----------
    problem : ShootingProblem
    loose : FlightSettings
        The flights at the loose tolerance (:func:`loose_settings`).

    Returns
    -------
    FlightSettings
    """
    if root_settings(problem) is None or not hasattr(loose, "phi_atol"):
        return loose
    return dataclasses.replace(loose, phi_atol=STEER_PHI_ATOL)


def first_residual(problem, X, steer, r):
    """The residual the chord's first step takes at ``X`` from the steering flight with ``steer``
    (``r`` that flight's; theory §11): ``r`` where that flight's state is the chord's plain flights'
    (the preset's tolerances make it so) or where those flights are the root's
    (:func:`root_settings`, the variational flights carrying the Jacobian) and ``r`` is above
    :data:`LOOSE_FIRST` of the unknowns (its error, of the loose tolerance's order, taken out by the
    chord's next steps: a plain period at the root's tolerance saved, some 5,200 CVODE steps on the
    spool drill); else ``None`` (the chord flies it).

    Parameters
    ----------
    problem : ShootingProblem
    X : numpy.ndarray, shape (m n,)
        The chord's start.
    steer : FlightSettings
        The steering flight's integrator.
    r : numpy.ndarray, shape (m n,)
        That flight's residual at ``X``.

    Returns
    -------
    numpy.ndarray or None
    """
    if root_settings(problem) is not None:
        size = float(np.max(np.abs(r) / np.maximum(1.0, np.abs(X))))
        return r if size > LOOSE_FIRST else None
    plain = problem._state_settings(steer)  # (a plain flight reads no Magnus step)
    own = plain is not None and dataclasses.replace(plain, magnus_theta=None) == \
        dataclasses.replace(problem.settings, magnus_theta=None)
    return r if own else None


def loose_contraction(problem):
    """A bound on the chord's contraction after a first step of size ``s1`` that took the steering
    flight's residual (:func:`first_residual`), where the plain flights are the orbit's root's
    (:func:`root_settings`): ``STEER_ERROR + LOOSE_CURVATURE * s1``, the steering Jacobian's own
    error (:data:`STEER_ERROR`) and its change over that step (:data:`LOOSE_CURVATURE`). The chord's
    second step, its first from the root's flights, measures that residual's error (some 2e-7 on the
    spool drill, whatever the start), not the contraction; the bound times it predicts the third
    (:func:`~impactbar.drives.orbitproblem.chord`'s ``first_bound``). ``None`` elsewhere.

    Parameters
    ----------
    problem : ShootingProblem

    Returns
    -------
    callable or None
        ``bound(s1) -> float`` (dimensionless), or ``None``.
    """
    return _contraction if root_settings(problem) is not None else None


def _contraction(size: float) -> float:
    return STEER_ERROR + LOOSE_CURVATURE * size


_SINGULAR = "find_orbit: the Jacobian of the periodic-orbit problem is singular at its root"


def close(problem, X, last, tol: float = 0.0) -> np.ndarray:
    """The closing step from the chord's iterate ``X`` (``last`` the chord's last Jacobian): one Newton
    step with a steering flight at the drive's tolerance (with coupled blows, the chord's Jacobian and
    the variational flights' state); with ``tol`` (a root that :func:`checked_root` checks), chord
    steps with that Jacobian on the variational flights' state (``problem.root_value``, one plain
    flight each) after it while :data:`STEER_ERROR` times the last step exceeds :data:`CLOSING_CHECK`
    times ``tol``, as long as the steps shrink by half.

    Parameters
    ----------
    problem : ShootingProblem
    X : numpy.ndarray, shape (m n,)
        The chord's last iterate.
    last : numpy.ndarray, shape (m n, m n)
        The chord's last Jacobian.
    tol : float, optional
        The tolerance of the check (0: the closing step alone).

    Returns
    -------
    numpy.ndarray, shape (m n,)

    Raises
    ------
    ValueError
        Where the Jacobian is singular, or a flight fails.
    """
    # the root of the plain flights is not the variational flights' (their steps differ: the
    # integrator's error, 4e-8 in the residual of the 4-mode circuit); one Newton step with the
    # variational flight moves it there. The step is that small with coupled blows (3e-10 of the
    # unknowns on the rod and rock) that a Jacobian off by 1e-2 leaves 3e-12: the chord's then (a
    # column of the blow's Jacobian costs a blow), and the flight's only its state's
    if problem.coupled:
        r, J = problem._variational_value(X, problem._steer(problem.settings)), last
    else:
        r, J = problem.steering_residual(X)
    before = math.inf
    for _ in range(CLOSING_STEPS):
        try:
            step = np.linalg.solve(J, -r)
        except np.linalg.LinAlgError:
            raise ValueError(_SINGULAR) from None
        X, size = X + step, step_size(step, X, problem.positive)
        if not tol or STEER_ERROR * size <= CLOSING_CHECK * tol or size > 0.5 * before:
            return X
        r, before = problem.root_value(X), size
    return X


def checked_root(problem, X, tol: float, max_iter: int) -> np.ndarray:
    """``X`` where the multipliers' flight from it (kept: the orbit's data take it) gives a Newton
    step of at most :data:`CLOSING_CHECK` times ``tol`` (relative to the unknowns' sizes, as Newton's
    steps), else that step taken and checked again (Newton's method with the exact Jacobian), stopped
    as :func:`~impactbar.drives.orbitproblem.newton` stops at the rounding floor of a poorly
    conditioned orbit (a step below 1e-9 that shrinks by less than a quarter).

    Parameters
    ----------
    problem : ShootingProblem
        A one-impact problem.
    X : numpy.ndarray, shape (n,)
    tol : float
        Relative tolerance of Newton's steps.
    max_iter : int

    Returns
    -------
    numpy.ndarray, shape (n,)

    Raises
    ------
    ValueError
        Where the Jacobian is singular, a flight fails or ``max_iter`` steps do not converge.
    """
    tau, mode = problem.blocks[0]
    last = math.inf
    for _ in range(max_iter):
        y_after, _, _, _, _, _, Phi = problem._flight(tau, mode, X, keep=True, variational=True)
        try:
            step = np.linalg.solve(Phi - np.eye(problem.n), X - y_after)
        except np.linalg.LinAlgError:
            raise ValueError(_SINGULAR) from None
        size = step_size(step, X, problem.positive)
        if size <= CLOSING_CHECK * tol or at_rounding_floor(size, last):
            return X
        X, last = X + step, size
    raise ValueError(f"find_orbit did not converge in {max_iter} Newton steps after the chord")
