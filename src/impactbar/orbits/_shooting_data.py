"""The data of a periodic orbit of the shooting problem (:class:`.driven.ShootingProblem`): its
period, flights, impacts, switches and multipliers, from its unknowns (theory §10)."""

from __future__ import annotations

import math

import numpy as np

from ..drives.orbitproblem import OrbitData, sorted_multipliers

__all__ = ["orbit_data", "start_mode", "starts_on_stop"]


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
