"""The periodic orbits of a drive: :func:`find_driven_orbit` (one orbit, from a guess or the
default chain of starts) and :func:`drive_orbits` (every one-impact orbit in a window of periods),
theory §10.

:func:`drive_orbits` (what :func:`impactbar.periodic_orbits` calls with a
:class:`~impactbar.Drive` in place of the load) lists the one-impact orbits of the drive's own
search (:meth:`~impactbar.drives.OrbitProblem.search`); :func:`default_orbit` is
:func:`~impactbar.orbits.find_driven_orbit`'s chain of starts without a guess: the drive's default
start, the end of a run from rest on the stop, that search.
"""

from __future__ import annotations

import math

import numpy as np

from .._shared.forcing import check_family
from .._shared.validate import check_int, check_real
from ..drives.base import FlightSettings
from ..drives.flight import solver_settings
from ..drives.orbitproblem import OrbitProblem
from ..laws.abilities import newton_start
from ..model import BarModel
from ._settling import surfaces_ahead
from .driven import DrivenOrbit, orbit_of, orbit_problem
from .one_impact import OrbitList

__all__ = ["find_driven_orbit", "drive_orbits", "default_orbit", "SETTLE_RUN_IMPACTS", "SETTLE_RUN_TOL"]


def find_driven_orbit(model: BarModel, drive, impacts: int = 1, guess=None, *, tol: float = 1e-13,
                        max_iter: int = 50, newton: str = "chord",
                        settings: FlightSettings | None = None) -> DrivenOrbit:
    """The periodic motion with ``m`` impacts per period under a drive (theory §10).

    Called by :func:`impactbar.find_orbit` when its load is a :class:`~impactbar.Drive`. Between
    consecutive impacts the drive goes through its cycle (for the valve: stroke ``tau``, return until
    the switch crossing, return ``tau``, stroke until the impact); with ``m >= 2`` the intervals may
    differ (a period-2 motion after a period doubling), and the unknowns hold the ``m`` states after
    the impacts (multiple shooting). The problem is the drive's own or the generic shooting problem
    (module docstring).

    Parameters
    ----------
    model : BarModel
        Rigid or flexible bar, under any impact law: the paper's (eq. 10), or a contact that takes
        time, the wave law (theory §4b) or the rod-rock law (§4d), held under the drive's force
        (theory §10; the orbit's ``state`` is then where the contact ends, and ``contacts`` holds
        the blows). A drive with state (the oil circuit) takes these laws with each blow solved together
        with its state (theory §11, "The coupled blow"), the blow's Jacobian by central differences;
        with the rod-rock law's exact blows, the orbit without a guess is found on the lattice and
        polished on the exact blows (:meth:`~impactbar.orbits.driven.ShootingProblem.polish`).
    drive : Drive
    impacts : int
        Impacts per period ``m >= 1``; with ``m >= 2`` a ``guess`` is needed for the valve.
    guess : DrivenOrbit, DrivenTrajectory, tuple or None
        Where Newton starts: an orbit (e.g. from a nearby parameter; a one-impact orbit is repeated
        ``m`` times, which Newton keeps unless the halves are perturbed), a run of
        :func:`impactbar.simulate` under the drive that has settled (the valve: its last ``m``
        complete valve cycles, the states just after their impacts with the modal coordinates and
        the flight times between the switches, rigid or flexible bar, the paper's law; a generic
        drive: the run continued from its end to its next impacts), a tuple (the valve:
        ``(states, h1, h3)``, states after the impacts, shape ``(m, 2 N + 2)`` or ``(2 N + 2,)``
        for ``m = 1``, and the free flight durations, shape ``(m,)``), or ``None`` (``m = 1``): the
        default chain below.
    tol : float
        Relative tolerance of the Newton step (a generic drive with state: at least ten times the
        integrator's ``rtol``).
    max_iter : int
        Largest number of Newton steps.
    newton : {"chord", "full"}
        Where the drive's flights integrate the variational equations (the oil circuit): ``"chord"``
        (default), the residuals by plain flights with the Jacobian of one variational flight at a
        looser tolerance, then one Newton step with the variational flight at the drive's tolerance;
        ``"full"``, a variational flight at every Newton step (the way before, several times the
        cost). The same orbit (to about 1e-12 of the unknowns) and multipliers (to their own noise,
        about 1e-7: the variational flight's steps move with the unknowns) either way
        (:class:`~impactbar.orbits.driven.ShootingProblem`).
    settings : FlightSettings, optional
        How a drive's flights with state are integrated (the oil circuit's
        :class:`~impactbar.drives.circuit.CircuitFlightSettings`: its tolerances and options), every
        flight of the search (the run from rest of the default chain too); default the drive's
        :attr:`~impactbar.Drive.integrator`. Kept by the orbit's problem (``orbit.problem.settings``).

    Returns
    -------
    DrivenOrbit

    Raises
    ------
    ValueError
        On a bad argument, ``impacts >= 2`` without a guess (the valve), a simulated run as the guess
        under a law other than the paper's (the valve), or when Newton does not converge.

    Examples
    --------
    The rigid piston of theory §10 (``v = sqrt(2 x1 (a_s + a_r) / (1 - R^2))``, multiplier ``R^2``):

    >>> from impactbar import BarModel, PositionSwitchedDrive, find_orbit
    >>> o = find_orbit(BarModel(s=10, d=0, R=0.215, n_modes=0),
    ...                PositionSwitchedDrive(stroke=1, ret=1, switch_out=1))
    >>> round(o.period, 6), round(o.impact_velocity, 6), round(float(o.multipliers[0]), 6)
    (4.569933, 2.047892, 0.046225)

    The same orbit as a two-impact one (its two intervals equal, the period doubled):

    >>> o2 = find_orbit(o.model, o.drive, impacts=2, guess=o)
    >>> o2.impacts, round(o2.period / o.period, 12), round(o2.blow_frequency * o.period, 12)
    (2, 2.0, 1.0)
    """
    if not isinstance(model, BarModel):
        raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
    check_family(drive, "drive", "drive")
    m = check_int("impacts", impacts, lo=1)
    tol = check_real("tol", tol, lo=0.0, lo_open=True)
    max_iter = check_int("max_iter", max_iter, lo=1)
    solver_settings(settings, drive, True)  # (a FlightSettings or None)
    problem = orbit_problem(model, drive, m, settings, newton=newton)
    if guess is None and m == 1:  # the default chain (the rigid orbit, a run from rest, the search)
        polished = _from_coarse(model, drive, problem, tol, max_iter, newton, settings)
        return polished if polished is not None else default_orbit(model, drive, problem, tol, max_iter)
    return _motion(orbit_of(problem, _solve(problem, problem.initial(guess, tol, max_iter), tol, max_iter)))


def _from_coarse(model: BarModel, drive, problem, tol: float, max_iter: int, newton: str, settings=None):
    """Where each impact is a blow coupled to the drive's state and the law has a cheaper model of
    the same motion (:meth:`~impactbar.laws.abilities.NewtonStart.coarse_model`: the rod-rock law's
    exact blows under the oil circuit, whose lattice costs some 1 % of a blow), the orbit found on
    that model (the default chain, every settling flight's blow its) and polished on this one
    (:meth:`~impactbar.orbits.driven.ShootingProblem.polish`); ``None`` where there is no such
    model, or no orbit on it, or the polish does not converge (the default chain on this model then
    answers)."""
    start = newton_start(model.law)
    coarse = start.coarse_model(model) if getattr(problem, "coupled", False) else None
    if coarse is None or not hasattr(problem, "polish"):
        return None
    try:
        rough = _coarse_orbit(coarse, start.coarse_start(model), drive, tol, max_iter, newton, settings)
        return _motion(orbit_of(problem, problem.polish(rough, tol, max_iter)))
    except ValueError:
        return None


def _coarse_orbit(coarse: BarModel, first, drive, tol: float, max_iter: int, newton: str, settings=None):
    """:func:`_from_coarse`'s orbit on ``coarse``: polished from the orbit of ``first`` (a cheaper
    model still, :meth:`~impactbar.laws.abilities.NewtonStart.coarse_start`; its default chain)
    where given and that polish converges, else by the default chain on ``coarse``. Its monodromy
    only starts a chord: its blows' columns by forward differences (``forward_blows``)."""
    problem = orbit_problem(coarse, drive, 1, settings, newton=newton)
    problem.forward_blows = True
    if first is not None:
        lower = orbit_problem(first, drive, 1, settings, newton=newton)
        lower.forward_blows = True
        try:
            rough = default_orbit(first, drive, lower, tol, max_iter)
            return _motion(orbit_of(problem, problem.polish(rough, tol, max_iter)))
        except ValueError:
            pass
    return default_orbit(coarse, drive, problem, tol, max_iter)


#: The slowest arrival at the stop that is a blow (the simulator's ``REST_SPEED``: a slower rebound
#: ends in rest on the stop), in the model's velocity unit.
MIN_IMPACT_SPEED = 1e-9


def _motion(orbit: DrivenOrbit) -> DrivenOrbit:
    """``orbit``, refused where it is no motion: a period that is not positive or an arrival slower
    than :data:`MIN_IMPACT_SPEED` (a fixed point of the equations with the piston resting on the stop,
    its blows shrunk to nothing: the oil circuit's run from rest settles onto one where the bounces
    on the stop die away, period 0 and impact velocity 1e-27)."""
    v = np.asarray(orbit.impact_velocities, dtype=float)
    slowest = float(np.min(v)) if v.size else 0.0
    if not (math.isfinite(orbit.period) and orbit.period > 0.0) or not slowest > MIN_IMPACT_SPEED:
        raise ValueError(f"find_orbit: Newton reached a degenerate solution (period {orbit.period:.3g}, "
                         f"impact velocity {slowest:.3g}): the piston resting on the stop, not a periodic "
                         "motion with a blow")
    problem = orbit._problem
    blocks = getattr(problem, "blocks", None)
    if blocks:  # the shooting problem: each section's mode as its state says
        for (_, mode), y in zip(blocks, np.asarray(orbit._unknowns).reshape(len(blocks), -1), strict=True):
            if not surfaces_ahead(problem.drive, mode, y, problem.M, 1e-9):
                raise ValueError("find_orbit: Newton reached a solution whose drive's mode at an impact is "
                                 f"not the one its state gives ({problem.drive.mode_name(mode)} with a "
                                 "switching surface of the drive already crossed), not a motion of the drive")
    return orbit


def _solve(problem: OrbitProblem, X0, tol: float, max_iter: int):
    """Newton from ``X0``; a degenerate root (the flights shrunk to nothing: a root of the
    equations, not a motion; the fuzzing campaign found one returned as a "backward impact" orbit of period
    3e-9, a different one at each scale) is refused."""
    X = problem.solve(X0, tol, max_iter)
    times, start = X[problem.positive], X0[problem.positive]
    if times.size and float(np.sum(times)) < 1e-6 * float(np.sum(start)):
        raise ValueError(f"find_orbit: Newton reached a degenerate solution (flights of total length "
                         f"{float(np.sum(times)):.3g} from {float(np.sum(start)):.3g} at the guess), not a "
                         "periodic motion; give a guess (e.g. simulate(...) under the drive)")
    return X


#: impacts of the simulation from rest in the default guess chain of :func:`find_driven_orbit`
SETTLE_RUN_IMPACTS = 200
#: relative agreement of the last impact velocities at which that run counts as settled
SETTLE_RUN_TOL = 1e-3


def _settled_run(model: BarModel, drive, settings=None):
    """A run of :func:`impactbar.simulate` from rest on the stop (``SETTLE_RUN_IMPACTS`` impacts,
    the flights by ``settings``) and whether its last impact velocities repeat every impact to
    ``SETTLE_RUN_TOL`` (a one-impact motion it settles on)."""
    from ..simulation import InitialState, simulate  # the simulator, loaded where a guess needs it

    run = simulate(model, drive, InitialState.rigid(0.0, 0.0, n_modes=model.n_modes), 1e6,
                   max_impacts=SETTLE_RUN_IMPACTS, settings=settings)
    vi = np.asarray(run.impact_velocities)
    settled = vi.size >= 8 and bool(np.all(np.abs(np.diff(vi[-6:])) <= SETTLE_RUN_TOL * np.abs(vi[-1])))
    return run, settled


def default_orbit(model: BarModel, drive, problem: OrbitProblem, tol: float, max_iter: int) -> DrivenOrbit:
    """:func:`find_driven_orbit` without a guess, one impact per period: the first admissible,
    stable orbit of (1) the drive's default start (:meth:`OrbitProblem.initial` of ``None``: the
    valve's rigid orbit), (2) the end of a run from rest on the stop (:func:`_settled_run`; skipped
    where (1) already is that run, :attr:`OrbitProblem.starts_from_rest`), (3) the systematic
    search :func:`drive_orbits` (its stable orbit nearest in period to the first orbit found, or
    the one of smallest spectral radius). Without a stable one, the first admissible orbit found in
    that order, then (1)'s orbit if it converged; else a ``ValueError`` that says what was tried."""
    tried: list[str] = []
    found: list[DrivenOrbit] = []

    def attempt(what, start):
        try:
            X0 = start()
            if problem.settled_into is not None:  # (the motion followed: another period)
                k, followed = problem.settled_into
                what += f" (into {k} impacts per period by its {followed}th)"
            X = _solve(problem, X0, tol, max_iter)
            orbit = _motion(orbit_of(problem, X))
        except ValueError as err:
            tried.append(f"{what}: {err}")
            return None
        found.append(orbit)
        tried.append(f"{what}: converged to a{'n' if orbit.admissible else ' non-'}admissible"
                     f"{', stable' if orbit.stable else ', unstable'} orbit of period {orbit.period:.6g}")
        return orbit if orbit.stable else None

    first = attempt(getattr(problem, "default_start", "the drive's default start"),
                    lambda: problem.initial(None, tol, max_iter))
    if first is not None:
        return first
    if not getattr(problem, "starts_from_rest", False):
        try:
            run, settled = _settled_run(model, drive, getattr(problem, "settings", None))
        except ValueError as err:
            tried.append(f"a run from rest on the stop: {err}")
        else:
            what = (f"the end of a run from rest on the stop ({run.n_impacts} impacts, "
                    f"{'settled' if settled else 'not settled'} to one impact per period)")
            orbit = attempt(what, lambda: problem.initial(run, tol, max_iter))
            if orbit is not None:
                return orbit
    count = problem.resonances() if hasattr(problem, "resonances") else 0.0
    try:
        if count > MAX_DEFAULT_RESONANCES:
            raise ValueError(f"skipped: its default window holds about {count:.3g} resonances of the "
                             f"flexible modes (more than {MAX_DEFAULT_RESONANCES}); call "
                             "periodic_orbits(model, drive, window=...) with a narrower window")
        listed = _searched(problem, None, tol, 20)
    except ValueError as err:
        tried.append(f"the search of every orbit: {err}")
    else:
        if listed is None:
            tried.append("the search of every orbit: none for this drive")
        else:
            stable = [o for o in listed if o.stable]
            lo, hi = listed.window
            n_adm = sum(o.admissible for o in listed)
            tried.append(f"the search of every orbit (periods {lo:.6g} to {hi:.6g}): {len(listed)} orbits, "
                         f"{n_adm} admissible, {len(stable)} stable")
            if stable:
                ref = found[0].period if found else None
                return min(stable, key=lambda o: (abs(o.period - ref) if ref is not None else 0.0,
                                                  float(np.max(np.abs(o.multipliers)))))
            found += [o for o in listed if o.admissible]
    for orbit in found:
        if orbit.admissible:
            return orbit
    if found:
        return found[0]
    raise ValueError("find_orbit found no periodic orbit of the drive with one impact per period; tried "
                     + "; ".join(tried))


#: The most resonances of the flexible modes in the default window for ``find_orbit``'s default
#: chain to end with the search of every orbit (the two drives on which the rigid orbit alone failed
#: as a start, tests/drives/test_drive_orbits.py, hold 500 and 2,340; a fuzz case
#: with a period of 1,789 held 74,000 and took minutes)
MAX_DEFAULT_RESONANCES = 10_000


def drive_orbits(model: BarModel, drive, window=None, *, tol: float = 1e-13, max_iter: int = 20,
                 settings: FlightSettings | None = None):
    r"""Every one-impact periodic orbit of a drive with a period in a window (theory §10):
    :func:`impactbar.periodic_orbits` with a :class:`~impactbar.Drive` in place of the load.

    The drive's periodic-orbit problem (:func:`~impactbar.orbits.driven.orbit_problem`) searches its own
    solutions (:meth:`~impactbar.drives.OrbitProblem.search`); each is polished by Newton's method
    on the full problem (:func:`find_driven_orbit`'s) and becomes a :class:`DrivenOrbit` with
    its admissibility, multipliers and stability; orbits found twice (periods within ``1e-9``
    relative) are kept once.

    For the valve of :class:`~impactbar.PositionSwitchedDrive` under the paper's impact law (eq. 10)
    with every flexible mode underdamped, a one-impact orbit is, for given flight times, the
    solution of linear equations mode by mode, and two equations remain in the period ``T`` and the
    stroke's flight ``h3`` (:mod:`impactbar.orbits.valve_search`). Their roots are searched on
    ``T`` in ``window`` times ``0 < h3 < T - delay_in - delay_out`` by bisection with exclusion by
    bounds of the Jacobian (interval arithmetic on the closed forms, the mean-value theorem) and
    each root is certified by the Krawczyk test, unique in a box around it.

    What is certified: every root of the equations in the window is listed once, except in the
    intervals of :attr:`OrbitList.unresolved` (a double root at a fold, or an undamped resonance
    ``T = 2 k / (s n)``), where Newton's roots are listed uncertified (``OrbitList.certified``);
    the interval arithmetic is not rounded outward, so "certified" holds up to a floor of ``1e-12``
    of the terms' size. What is not: the admissibility of a flexible bar's orbit is decided on a
    grid finer than the stiffest mode's period (exact on the rigid bar, theory §10), and a motion
    with a period outside the window, with chatter or with several impacts per period is not
    sought. A drive without a search of its own (another drive, another impact law, an overdamped
    mode) gives the orbits of :func:`find_driven_orbit`'s default chain instead (the orbits found,
    not a certified set; ``window`` is then ``None``).

    Parameters
    ----------
    model : BarModel
    drive : Drive
    window : (float, float), optional
        ``(T_min, T_max)``, the periods searched (model time, eq. 2), ``0 < T_min < T_max``. Default
        for the valve: a tenth to ten times the period of the rigid piston's orbit (the rigid bar
        of the same damping, restitution and delays), above the sum of the delays.
    tol : float
        Relative tolerance of the polishing Newton steps.
    max_iter : int
        Most Newton steps per orbit.
    settings : FlightSettings, optional
        How a drive's flights with state are integrated (:func:`find_driven_orbit`).

    Returns
    -------
    OrbitList
        :class:`DrivenOrbit` by increasing period, with :attr:`OrbitList.window`,
        :attr:`OrbitList.certified` and :attr:`OrbitList.unresolved`.

    Raises
    ------
    ValueError
        For a bad model, drive or window (named), or a search that needs too many cells at once
        (an undamped bar with a wide window).

    Examples
    --------
    >>> from impactbar import BarModel, PositionSwitchedDrive, periodic_orbits
    >>> orbits = periodic_orbits(BarModel(3, 0.1, 0.6, 6), PositionSwitchedDrive(1, 0.5, 0.15))
    >>> [(round(o.period, 6), o.stable) for o in orbits if o.admissible]
    [(0.310076, False), (0.954607, False), (1.609243, True)]
    >>> len(orbits), all(orbits.certified), orbits.unresolved
    (7, True, ())
    """
    if not isinstance(model, BarModel):
        raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
    check_family(drive, "drive", "drive")
    if window is not None:
        try:
            lo, hi = (float(w) for w in window)
        except (TypeError, ValueError):
            raise ValueError(f"window must be a pair (T_min, T_max) of periods; got {window!r}") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
            raise ValueError(f"window must hold finite periods 0 < T_min < T_max; got {window!r}")
        window = (lo, hi)
    tol = check_real("tol", tol, lo=0.0, lo_open=True)
    max_iter = check_int("max_iter", max_iter, lo=1)
    solver_settings(settings, drive, True)
    problem = orbit_problem(model, drive, 1, settings)
    out = _searched(problem, window, tol, max_iter)
    if out is None:  # no search of the drive's own: the default chain's orbit
        out = OrbitList([find_driven_orbit(model, drive, 1, tol=tol, max_iter=max(max_iter, 50),
                                             settings=settings)])
        out._certified, out._unresolved, out._window = (False,), (), None
    return out


def _searched(problem: OrbitProblem, window, tol: float, max_iter: int) -> OrbitList | None:
    """The orbits of the problem's own search (:meth:`OrbitProblem.search`), polished and merged
    (:func:`drive_orbits`); ``None`` where the problem has no search."""
    found = problem.search(window)
    if found is None:
        return None
    orbits, cert = [], []
    for X0, ok in zip(found.starts, found.certified, strict=True):
        try:
            X = problem.solve(np.asarray(X0, dtype=float), tol, max_iter)
        except ValueError:
            continue
        orbit = orbit_of(problem, X)
        same = [k for k, o in enumerate(orbits) if abs(o.period - orbit.period) <= 1e-9 * orbit.period]
        if same:
            cert[same[0]] = cert[same[0]] or bool(ok)
            continue
        orbits.append(orbit)
        cert.append(bool(ok))
    order = np.argsort([o.period for o in orbits], kind="stable")
    out = OrbitList([orbits[k] for k in order])
    out._certified = tuple(cert[k] for k in order)
    out._unresolved = tuple(found.unresolved)
    out._window = tuple(found.window)
    return out
