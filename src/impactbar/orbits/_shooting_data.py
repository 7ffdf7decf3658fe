"""The data of a periodic orbit of the shooting problem (:class:`.driven.ShootingProblem`): its
period, flights, impacts, switches and multipliers, from its unknowns (theory §10)."""

from __future__ import annotations

import math

import numpy as np

from ..drives.orbitproblem import OrbitData, sorted_multipliers

__all__ = ["block_mode", "event_pattern", "on_section", "orbit_data", "start_mode", "start_modes",
           "starts_on_stop"]


def starts_on_stop(problem, y) -> bool:
    """Whether a block's flight of ``problem`` from the unknowns ``y`` (its first ``M`` the modal
    positions) starts from their projection on the section ``c . q = 0`` (theory §10): always where
    every flight starts on the stop (the law's ``flight_starts_on_stop``), else where the end is on
    or beyond the stop. A blow that left the end off the stop (the rod-rock law's, ended where the
    piston is free for good behind the shank's new rest position: theory §11, "The coupled blow") has
    its flight start there, so that the orbit is the motion a run from its state repeats.

    Parameters
    ----------
    problem : ShootingProblem
    y : array_like, shape (n,)
        A block's unknowns ``(q, q', z)``.

    Returns
    -------
    bool
    """
    return problem.on_stop or float(problem.model.end_weights @ np.asarray(y[:problem.M], dtype=float)) >= 0.0


def on_section(problem, y) -> tuple[np.ndarray, bool]:
    """Where a block's flight of ``problem`` from the unknowns ``y`` starts: its modal positions,
    projected on the section ``c . q = 0`` where it starts from there (:func:`starts_on_stop`; the
    unknowns' perturbations leave the section), and whether it does.

    Parameters
    ----------
    problem : ShootingProblem
        Its ``M`` modal coordinates, its model's end weights ``c`` and its law's trait.
    y : array_like, shape (n,)
        The block's unknowns, the modal positions first.

    Returns
    -------
    q : numpy.ndarray, shape (M,)
        A new array: the modal positions the flight starts from.
    onto : bool
        Whether they were projected on the section.
    """
    q = np.array(y[:problem.M], dtype=float)
    onto = starts_on_stop(problem, q)
    if onto:
        q[0] -= float(problem.model.end_weights @ q)
    return q, onto


def block_mode(problem, mode, y):
    """The mode a block's flight of ``problem`` from the unknowns ``y`` starts in: the block's
    ``mode`` as :func:`start_mode` sets it from the flight's start (:func:`on_section`). Every place
    that flies, reports or returns a block's start mode takes this one (the flights, the event pattern,
    the blocks of a found orbit), so that the orbit's discrete state agrees with its continuous state.

    Parameters
    ----------
    problem : ShootingProblem
    mode : hashable
        The block's mode (fixed from the guess).
    y : array_like, shape (n,)
        The block's unknowns ``(q, q', z)``.

    Returns
    -------
    hashable
        ``mode`` itself where the state agrees with it.
    """
    M = problem.M
    q, _ = on_section(problem, y)
    return start_mode(problem.drive, mode, q, y[M:2 * M], y[2 * M:])


def start_modes(problem, X) -> list:
    """The mode each block's flight of ``problem`` from the unknowns ``X`` starts in: its mode in
    ``problem.blocks`` (fixed from the guess) as its state there says (:func:`block_mode`: the oil
    circuit's watched levels' flags turned to the side of the level its state is on).

    Parameters
    ----------
    problem : ShootingProblem
    X : numpy.ndarray, shape (m n,)
        The unknowns: the states after each of the ``m`` impacts, stacked.

    Returns
    -------
    list
        One mode per block, in order.
    """
    n = problem.n
    return [block_mode(problem, mode, X[k * n:(k + 1) * n]) for k, (_, mode) in enumerate(problem.blocks)]


def event_pattern(problem, X) -> tuple:
    """The period's sequence of the drive's discrete states at the unknowns ``X`` of ``problem``:
    per block the mode its flight starts in (:func:`start_modes`), then each event's name and the
    mode after it, in order (the events on an arrival's root among them).

    Parameters
    ----------
    problem : ShootingProblem
    X : numpy.ndarray, shape (m n,)
        The unknowns.

    Returns
    -------
    tuple
        ``("start", mode)`` for each block, followed by its events' ``(name, mode after)``.
    """
    n = problem.n
    out = []
    for k, ((tau, _), mode) in enumerate(zip(problem.blocks, start_modes(problem, X), strict=True)):
        out.append(("start", mode))
        _, _, _, _, _, events, *_ = problem._flight(tau, mode, X[k * n:(k + 1) * n], keep=True)
        out += [(e.name, after) for _, e, after, _ in events]
    return tuple(out)


def start_mode(drive, mode, q, v, z):
    """The mode a block's flight starts in: the block's ``mode`` (fixed from the guess, theory §10)
    as the drive's ability ``start_mode`` sets it from the state at the start (the oil circuit's
    watched levels' flags, :func:`impactbar.drives.circuit.watch.consistent_mode`), else ``mode``.
    As the parameters move the block's state to the other side of a level (a check valve's full
    opening reached just before the impact, and no longer), the fixed flag said the level was
    passed while the state had not passed it: the flight then watched the level from the wrong
    side, never crossed it and went on in a piece of the opening's law far outside its range.

    Parameters
    ----------
    drive : Drive
    mode : hashable
        The block's mode.
    q, v, z : numpy.ndarray
        The flight's start: modal displacements (on the section), velocities, the drive's state.

    Returns
    -------
    hashable
        ``mode`` itself where the state agrees with it.
    """
    own = drive.abilities.start_mode
    return mode if own is None else own(mode, q, v, z)


def orbit_data(problem, X, multipliers: bool = True) -> OrbitData:
    """The period, durations, states, switches and the multipliers of the return map on the section
    after the impacts (the product of the blocks' Jacobians projected on ``c . q = 0`` times the
    drive's states) of the solution ``X`` of ``problem``.

    Parameters
    ----------
    problem : ShootingProblem
    X : numpy.ndarray, shape (m n,)
        The unknowns: the states after each of the ``m`` impacts.
    multipliers : bool, optional
        Without them, ``nan`` in their place and no monodromy (no Jacobian computed).

    Returns
    -------
    OrbitData
    """
    model, drive, n, m, M = problem.model, problem.drive, problem.n, problem.impacts, problem.M
    c = model.end_weights
    Phi = None
    if not multipliers:
        mu = np.full(n - 1, math.nan)
    elif problem.variational and m == 1:  # one flight gives the Jacobian and (kept) the data below
        tau, mode = problem.blocks[0]
        _, _, _, _, _, _, Phi = problem._flight(tau, mode, X[:n], keep=True, variational=True)
    else:
        _, J = problem.residual(X)
        Phi = np.eye(n)
        for k in range(m):  # the blocks' Jacobians (their diagonal blocks; with m = 1, J = DP - I)
            Phi = (J[k * n:(k + 1) * n, k * n:(k + 1) * n] + (np.eye(n) if m == 1 else 0.0)) @ Phi
    if Phi is not None and starts_on_stop(problem, X[:M]):  # (Phi's column along c . q zero)
        a = np.concatenate((c, np.zeros(M + problem.k)))
        Q, _ = np.linalg.qr(np.column_stack((a / np.linalg.norm(a), np.eye(n))))
        B = Q[:, 1:n]
        mu = sorted_multipliers(np.linalg.eigvals(B.T @ Phi @ B))
    elif Phi is not None:  # a flight from off the stop: Phi maps the flow there to 0, one multiplier
        mu = sorted_multipliers(np.linalg.eigvals(Phi))[:n - 1]  # 0 (the least, left out)
    before, velocities, times, durations, switch_t, crossings, forces = [], [], [], [], [], [], []
    shift = 0.0
    window = float(model.law.window(model))
    blows = []  # each blow's duration (the window's but where a blow ends by its own test)
    for k in range(m):
        tau, mode = problem.blocks[k]
        y = X[k * n:(k + 1) * n]
        y_after, t_after, _, arrival, _, events = problem._flight(tau, mode, y, keep=True)
        t_arr, qa, va, st = arrival
        before.append(np.concatenate((qa, va)))
        velocities.append(float(c @ va))
        times.append(float(shift + t_arr - tau))
        forces.append(float(drive.force(st.mode, st.z, qa, va)))
        last = tau
        prev_name = drive.mode_name(mode)
        for te, _, mode_after, speed in events:
            durations.append(te - last)
            last = te
            name = drive.mode_name(mode_after)
            if name != prev_name:
                switch_t.append(shift + te - tau)
            prev_name = name
            if not math.isnan(speed):
                crossings.append(speed)
        durations.append(t_arr - last)
        blows.append(float(t_after - t_arr))
        shift += t_after - tau
    blocks = X.reshape(m, n)
    if window and not all(math.isclose(b, window, rel_tol=1e-9) for b in blows):
        window = max(blows)  # (the rod-rock law's blows under a drive with state: where the piston is free)
    return OrbitData(period=float(shift), durations=np.array(durations),
                     states_after=blocks[:, :2 * M].copy(),
                     states_before=np.array(before), impact_velocities=np.array(velocities),
                     impact_times=np.array(times), drive_states=blocks[:, 2 * M:].copy(), multipliers=mu,
                     trivial_multiplier=1.0, switch_times=np.array(switch_t),
                     switch_velocity=min(crossings) if crossings else math.nan, contact_time=window,
                     contact_forces=np.array(forces), monodromy=Phi)
