"""The entry points of the orbit solvers: :func:`find_orbit` (``m`` impacts in ``n`` load periods, by
Newton's method on the segment problem of :mod:`impactbar.orbits.multi_impact`, from the starts its
guess gives) and :func:`periodic_orbits` (the one-impact orbits under every law: from the law's phase
equation, :mod:`impactbar.orbits.one_impact`, or, for a law without one, by Newton's method from
guesses, :func:`periodic_orbits_by_newton`). They are here together since each calls the other: the
one-impact orbits are find_orbit's default guess, and find_orbit finds them where there is no phase
equation. Each holds its table from forcing family to solver (``FIND_ORBIT``, ``PERIODIC_ORBITS``).
"""

from __future__ import annotations

import math

import numpy as np

from .._shared.forcing import dispatch
from .._shared.threads import single_threaded_blas
from .._shared.validate import check_int, check_real
from ..drives.base import Drive, FlightSettings
from ..drives.flight import solver_settings
from ..laws.abilities import PhaseEquation, newton_start
from ..loads import Load
from ..model import BarModel
from ._assemble import _build
from ._newton import POLISH_ITERATIONS, _chord, _converge, _converge_built
from .multi_impact import _as_segments, _doubling_guesses, _repeat, _Segments, _unknowns_from, contact_window
from .one_impact import OrbitList, _check_modes, phase_equation_orbits
from .orbit import PeriodicOrbit
from .phase import _check_inputs

__all__ = ["find_orbit", "periodic_orbits", "periodic_orbits_by_newton", "rock_periodic_orbits"]

TWO_PI = 2.0 * math.pi


def _guesses(problem: _Segments, guess):
    """Candidate unknown vectors from the user's guess, best first, and a vector to avoid (the
    undoubled orbit repeated, when starting across a period doubling) or None."""
    m, n = problem.m, problem.n
    if guess is None:
        if m != n:
            raise ValueError(f"guess is required for impacts={m} != periods={n}")
        orbits = [o for o in periodic_orbits(problem.model, problem.load) if np.isfinite(o.phase)]
        if not orbits:
            raise ValueError("guess is required: there is no one-impact orbit to start from")
        orbits.sort(key=lambda o: (not o.stable, not o.admissible, o.max_abs_multiplier))
        return [_unknowns_from(problem, *_repeat(np.array([o.phase]), o.state_after_impact[None, :],
                                                 1, n)) for o in orbits], None
    if hasattr(guess, "orbit") and hasattr(guess, "kind") and hasattr(guess, "multiplier"):
        guess = guess.orbit  # a BranchEvent: its orbit (a period doubling's starts the doubled one)
    if isinstance(guess, PeriodicOrbit):
        times, states, m0, n0 = _as_segments(guess)
        if m % m0 or n % n0 or m // m0 != n // n0:
            raise ValueError(f"guess has {m0} impacts in {n0} periods; it can start an orbit with "
                             f"impacts={m0}*j, periods={n0}*j, not impacts={m}, periods={n}")
        reps = m // m0
        mu = guess.multipliers
        near_pd = np.any((mu.real < -0.5) & (np.abs(mu.imag) <= 1e-9 * np.maximum(1.0, np.abs(mu))))
        if reps == 2 and near_pd:
            starts, avoid = _doubling_guesses(problem, guess)
            return starts, avoid
        return [_unknowns_from(problem, *_repeat(times, states, n0, reps))], None
    if hasattr(guess, "impact_times") and hasattr(guess, "modal_state"):  # a Trajectory
        ti = np.asarray(guess.impact_times)
        if ti.size < m + 1:
            raise ValueError(f"guess (a Trajectory) has {ti.size} impacts; at least impacts + 1 = "
                             f"{m + 1} are needed")
        span = ti[-1] - ti[-1 - m]
        if abs(span - TWO_PI * n) > 0.25 * TWO_PI:
            raise ValueError(f"guess: the last {m} impact intervals of the Trajectory span "
                             f"{span:.6g}, far from 2 pi periods = {TWO_PI * n:.6g}")
        times = ti[-1 - m:-1]
        q, v = guess.modal_state(times + problem.T)  # where each flight starts
        states = np.vstack((q, v)).T
        if states.shape[1] != 2 * problem.M:
            raise ValueError("guess: the Trajectory's model has another number of modes")
        return [_unknowns_from(problem, times, states)], None
    if isinstance(guess, tuple) and len(guess) == 2:
        times, states = guess
        return [_unknowns_from(problem, times, states)], None
    raise ValueError("guess must be a PeriodicOrbit (MultiImpactOrbit), a Trajectory or a tuple "
                     f"(impact_times, states_after_impact); got {type(guess).__name__}")


def find_orbit(model: BarModel, load: Load | Drive, impacts: int = 1, periods: int = 1, guess=None, *,
               tol: float = 1e-12, max_iter: int = 40,
               settings: FlightSettings | None = None) -> PeriodicOrbit:
    r"""A periodic motion with ``impacts`` impacts in ``periods`` load periods, by Newton's method on
    the exact impact map (eqs. 8, 10, 11; theory §4, §5, §7).

    Each flight is the closed-form motion of the modal oscillators (eq. 8); the unknowns are the impact
    times and the states just after them, the conditions are contact at each impact and the impact law
    (eq. 10, or the wave law of theory §4b) between consecutive flights, closing after :math:`2\pi n` (``n
    = periods``). The Jacobian is exact (fundamental matrix, vector field at both ends of each flight, the
    wave law's drive rate); the multipliers are the eigenvalues of the product of the ``impacts``
    impact-map Jacobians with their saltation terms.

    Parameters
    ----------
    model : BarModel
        Either impact law: the paper's (eq. 10) or the wave law (``impact="wave"``, theory §4b),
        where each impact lasts :math:`2/s` and the flights start at the windows' ends.
    load : Load
        Any load of period :math:`2\pi`.
    impacts : int
        :math:`m \ge 1`, impacts per period of the motion.
    periods : int
        :math:`n \ge 1`, load periods per period of the motion.
    guess : optional
        Where Newton starts:

        - ``None``: the one-impact orbits of :func:`periodic_orbits`, repeated (``impacts ==
          periods`` only), stable ones first;
        - a :class:`~impactbar.continuation.BranchEvent`: its orbit (a period-doubling event
          starts the doubled orbit, as below);
        - a :class:`PeriodicOrbit` with ``m0`` impacts in ``n0``
          periods, repeated ``j`` times for ``impacts = j m0``, ``periods = j n0``; for ``j = 2``
          and a guess with a real multiplier below ``-1/2`` the copies are pushed apart along its
          eigenvector, so that an orbit near or past its period doubling gives the doubled orbit
          (a ``ValueError`` if Newton only finds the guess again);
        - a :class:`Trajectory`: its last ``impacts`` impacts (they must span about
          :math:`2\pi n` with ``n = periods``);
        - a tuple ``(impact_times, states_after_impact)`` of shapes ``(m,)`` and ``(m, 2 N + 2)``
          (under the wave law, the states at the windows' ends).
    tol : float
        Relative tolerance of the Newton step.
    max_iter : int
        Newton iterations per start, from 1 to 1000; a start stops earlier when the residual has not
        halved in 40 iterations.
    settings : FlightSettings, optional
        With a :class:`~impactbar.Drive` whose state is integrated, how its flights are
        (:class:`~impactbar.drives.FlightSettings`; the oil circuit's
        :class:`~impactbar.drives.circuit.CircuitFlightSettings`, its tolerances and options);
        default the drive's :attr:`~impactbar.Drive.integrator`. The orbit keeps them (its
        continuation follows them). Not with a load (its flights are closed forms).

    Returns
    -------
    PeriodicOrbit
        With ``impacts`` and ``periods`` as asked (``MultiImpactOrbit`` is another name for it).

    Raises
    ------
    ValueError
        For bad arguments (named), an unknown impact law, wave-law windows that do not fit
        (:math:`2m/s \ge 2\pi n`), a problem of more than ``MAX_UNKNOWNS = 6000``
        unknowns ``2 (n_modes + 1) impacts`` (its dense Jacobian), or when Newton does not
        converge from any start derived from ``guess`` (or only back onto the undoubled orbit).

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, find_orbit
    >>> o = find_orbit(BarModel(s=10, d=0, R=0.5, n_modes=4), CosineLoad(0.1, 1.0))
    >>> round(o.phase, 4), o.impacts
    (3.0367, 1)

    With a :class:`~impactbar.Drive` in place of the load (e.g. a
    :class:`~impactbar.PositionSwitchedDrive`) the system is autonomous and the period is unknown
    (theory §10): the result is a :class:`~impactbar.DrivenOrbit`, a :class:`PeriodicOrbit`
    (``impacts`` per period; ``periods`` ignored; under every impact law), from
    :func:`~impactbar.orbits.find_driven_orbit`.
    """
    max_iter = check_int("max_iter", max_iter, lo=1, hi=1000)
    solver = dispatch(FIND_ORBIT, load)
    return solver(model, load, impacts, periods, guess, tol, max_iter,
                  **solver_settings(settings, load, solver is _drive_orbit))


def _drive_orbit(model, drive, impacts, periods, guess, tol, max_iter, settings=None) -> PeriodicOrbit:
    """:func:`find_orbit` under a drive: an autonomous orbit of unknown period (theory §10;
    ``periods`` has no meaning there), its flights by ``settings``."""
    from .driven_search import find_driven_orbit  # (the drives' machinery, loaded on first use)

    return find_driven_orbit(model, drive, impacts, guess, tol=min(tol, 1e-13), max_iter=max(max_iter, 50),
                               settings=settings)


def _load_orbit(model, load, impacts, periods, guess, tol, max_iter) -> PeriodicOrbit:
    """:func:`find_orbit` under a periodic load: Newton on the segment problem (theory §7)."""
    _check_inputs(model, load)
    m = check_int("impacts", impacts, lo=1, hi=4096)
    n = check_int("periods", periods, lo=1, hi=4096)
    tol = check_real("tol", tol, lo=0.0, lo_open=True, hi=1e-3)
    _check_law(model, load)
    if not m * contact_window(model) < TWO_PI * n:
        raise ValueError(f"impacts={m} contact windows of 2/s = {contact_window(model):.6g} do not fit "
                         f"in periods={n} load periods (wave law: s must exceed m/(pi n))")
    problem = _Segments(model, load, m, n)
    starts, avoid = _guesses(problem, guess)
    coarse = newton_start(model.law).coarse_model(model)
    with single_threaded_blas():
        if coarse is not None and guess is not None:  # a guess of the motion: Newton on this model
            for u0 in starts:  # (its exact Jacobian costs a few blows) while it converges at once
                orbit = _converge_built(problem, u0, avoid, tol, min(max_iter, DIRECT_ITERATIONS))
                if orbit is not None:
                    return orbit
        if coarse is not None:  # Newton on the cheaper model first, its orbits polished on this one
            rough = _Segments(coarse, load, m, n)
            near = [u for u in (_converge(rough, u0, avoid, tol, max_iter) for u0 in starts) if u is not None]
            for u0 in near:
                _, DF, _ = rough.evaluate(u0)
                u = _chord(problem, u0, DF, avoid, tol)
                if u is None:
                    u = _converge(problem, u0, avoid, tol, min(max_iter, POLISH_ITERATIONS))
                if u is not None:
                    return _build(problem, u)
        for u0 in starts:
            orbit = _converge_built(problem, u0, avoid, tol, max_iter)
            if orbit is not None:
                return orbit
    raise ValueError(f"find_orbit: Newton did not converge to an orbit with {m} impacts in {n} "
                     "periods from the guess" + (" (only to the undoubled orbit)" if avoid is not None
                                                  else ""))


def _check_law(model, load):
    """Refuse at once a law without an impact map (``LawNotSupported``) or a load its map cannot
    take (a ``ValueError``, from one impact state from rest; not under a law with a coarse model,
    whose map is a whole blow: there the first residual refuses such a load)."""
    from ..laws.base import ContactLaw, LawNotSupported, not_provided

    law = model.law
    if type(law).impact_map is ContactLaw.impact_map:
        raise LawNotSupported(not_provided(law, "impact_map"))
    start = newton_start(law)
    if start.coarse_model(model) is None:
        start.impact_state(model, load, 0.0, np.zeros(2 * model.n_modes + 2))


#: Newton iterations on the law's own model from a given guess before the coarse model is tried
#: (:func:`find_orbit`; a guess near the orbit converges in three to five)
DIRECT_ITERATIONS = 8


# ------------------------------------------------------------------------------------------------
# the one-impact orbits of every law (find_orbit's default guess): from the law's phase equation, or
# by Newton's method from guesses where it has none (both here, since each calls the other)
# ------------------------------------------------------------------------------------------------
def periodic_orbits(model: BarModel, load: Load | Drive, *, window=None,
                    settings: FlightSettings | None = None) -> OrbitList:
    r"""Every one-impact-per-period steady state of the bar under the load (paper Section 2).

    Each root ``phase`` of the phase equation (eq. 14) in :math:`[0, 2\pi)` gives one orbit: the flexible
    modes' start state solves the periodicity and impact conditions (eqs. 10-13) exactly, mode by
    mode; the rigid mode strikes at :math:`2\pi p_0/(1 + R)` and its constant is fixed by contact
    :math:`u(1, 0) = 0` (:func:`~impactbar.orbits.one_impact.phase_equation_orbits`; under the wave law
    its own phase equation, theory §4b). Under a law without a phase equation
    (not the ability :class:`~impactbar.laws.abilities.PhaseEquation`, e.g. the rod-rock law) the
    orbits come from Newton's method from guesses instead (:func:`periodic_orbits_by_newton`): the
    orbits found, not a certified set.

    Parameters
    ----------
    model : BarModel
    load : Load
        Any load of period :math:`2\pi`: ``CosineLoad``, ``SquareWaveLoad``, ``FourierLoad``, ...;
        or a :class:`~impactbar.Drive` (theory §10): every one-impact orbit with a period in
        ``window`` (:func:`~impactbar.orbits.drive_orbits`).
    window : (float, float), optional
        Under a drive only: the periods searched.
    settings : FlightSettings, optional
        Under a drive with state only: how its flights are integrated (:func:`find_orbit`).

    Returns
    -------
    OrbitList
        A ``list`` of :class:`PeriodicOrbit` sorted by phase, empty when none exists (e.g. above the
        fold, eq. 38); ``.to_dataframe()`` and ``.to_xarray()`` make it a table. Where the phase
        equation holds on a whole interval (a degenerate family, wave law), ``.families`` holds
        the interval and one orbit with ``multiplicity = 0`` stands for it, at its middle.

    Raises
    ------
    ValueError
        For inputs of the wrong type, or at an undamped resonance :math:`s n \pi = k` (eq. 16).

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, periodic_orbits
    >>> orbits = periodic_orbits(BarModel(s=10, d=0, R=0.5, n_modes=4), CosineLoad(0.5, 1.0))
    >>> [round(o.phase, 4) for o in orbits]
    [0.5511, 2.5905]
    """
    solver = dispatch(PERIODIC_ORBITS, load)
    return solver(model, load, window, **solver_settings(settings, load, solver is _drive_orbits))


def _drive_orbits(model, drive, window, settings=None) -> OrbitList:
    """:func:`periodic_orbits` under a drive: every one-impact orbit in a window of periods (theory
    §10), its flights by ``settings``."""
    from .driven_search import drive_orbits  # (the drives' machinery, loaded on first use)

    return drive_orbits(model, drive, window, settings=settings)


def _load_orbits(model, load, window) -> OrbitList:
    """:func:`periodic_orbits` under a periodic load: the law's phase equation, or Newton from
    guesses."""
    if window is not None:
        raise ValueError("window is for a drive's orbits (unknown period); a load's period is 2 pi")
    _check_inputs(model, load)
    _check_modes(model)
    if model.law.ability(PhaseEquation) is None:  # the blow is a numerical map: Newton from guesses
        return periodic_orbits_by_newton(model, load)
    return phase_equation_orbits(model, load)


#: the solver of :func:`find_orbit` for each forcing family (the one place it is chosen)
FIND_ORBIT = {"load": _load_orbit, "drive": _drive_orbit}
#: the solver of :func:`periodic_orbits` for each forcing family (the one place it is chosen)
PERIODIC_ORBITS = {"load": _load_orbits, "drive": _drive_orbits}

#: load periods of the simulation guess
SETTLE_PERIODS = 60


def _paper_guesses(model: BarModel, load: Load) -> list:
    """The one-impact orbits of the law's paper-equivalent bar, stable ones first, each at its phase
    with the state it has one window after its impact (where this law's flight starts)."""
    law = model.law
    paper = newton_start(law).paper_equivalent(model)
    T = law.window(model)
    guesses = []
    for o in sorted(periodic_orbits(paper, load), key=lambda o: (not o.stable, o.phase)):
        if not np.isfinite(o.phase):
            continue
        q, v = o.modal_state(np.array([T]))
        guesses.append((np.array([o.phase]), np.concatenate((q[:, 0], v[:, 0]))[None, :]))
    return guesses


def _simulated_guess(model: BarModel, load: Load):
    """A simulation from rest over :data:`SETTLE_PERIODS` load periods, if it has settled to one
    impact per period; else ``None``. It starts a gap of 0.1 times the problem's force scale (the
    load's bound, or the law's feed where larger) from the stop, so that the guess is the same
    motion at every scale of the load (the problem is homogeneous of degree one in it)."""
    from ..simulation import InitialState, simulate  # the simulator, loaded where a guess needs it

    scale = max(float(load.sup_abs), float(getattr(model.law, "feed", 0.0))) or 1.0
    try:
        tr = simulate(model, load, InitialState.rigid(-0.1 * scale, 0.0, n_modes=model.n_modes),
                      TWO_PI * SETTLE_PERIODS)
    except ValueError:
        return None
    ti = np.asarray(tr.impact_times)
    if ti.size < 4 or not np.allclose(np.diff(ti[-4:]), TWO_PI, atol=1e-3):
        return None
    return tr


def periodic_orbits_by_newton(model: BarModel, load: Load) -> OrbitList:
    """The one-impact orbits under a law without a phase equation, by Newton's method from guesses
    (theory §4d, §10): :func:`~impactbar.periodic_orbits` for such a model (e.g.
    ``impact=RodRock(...)``).

    The blow is a numerical map (for the rod-rock law, characteristics on the cell grid,
    :meth:`~impactbar.RodRock.impact_map`), so there is no closed-form phase equation to search:
    each orbit is found by :func:`~impactbar.find_orbit` (one impact in one period, the flight's
    start ``q_0`` among the unknowns where the law's flights may start off the stop) from two kinds
    of guesses:

    1. the one-impact orbits of the law's paper-equivalent bar
       (:meth:`~impactbar.laws.abilities.NewtonStart.paper_equivalent`: the same bar and load under
       the paper's law with the restitution this law's contact gives; for the rod-rock law a rigid
       piston's rebound from its rod and rock, ``R = -rebound_velocity / V`` at ``V = 1``, clipped to
       ``[0, 0.95]``), each taken at its phase with the state it has one window
       (:meth:`~impactbar.laws.ContactLaw.window`) after the impact, where this law's flight starts;
    2. where none of those gives a stable orbit, the end of a simulation from rest (60 load
       periods, started a gap of 0.1 times the load's bound from the stop), if it has settled to
       one impact per period.

    Steps and starts scale with the load (the finite-difference steps of the impact map are
    relative to the state), so that the orbits found are the same at every scale of the load.

    Where the law has a cheaper model of the same motion
    (:meth:`~impactbar.laws.abilities.NewtonStart.coarse_model`: the rod-rock law's exact blows on
    the lattice), each guess goes to it first and its orbit is polished on the law's own model.
    Orbits found twice (phases within ``1e-7``) are kept once. Guesses from which Newton does not
    converge give nothing: the list holds the orbits found, not a certified set of all of them.

    Parameters
    ----------
    model : BarModel
        Under a law without the ability :class:`~impactbar.laws.abilities.PhaseEquation` (any law
        with ``window``, ``impact_map`` and ``contact`` is accepted).
    load : Load
        Of period ``2 pi``.

    Returns
    -------
    OrbitList
        Sorted by phase; each a :class:`~impactbar.PeriodicOrbit` of :func:`~impactbar.find_orbit`
        (multipliers of the law's impact map, admissibility, the law's record per blow in
        ``contacts``). Empty when no guess converges.

    Raises
    ------
    ValueError
        For a model or load :func:`~impactbar.find_orbit` refuses (named).

    Examples
    --------
    >>> import impactbar as ib
    >>> law = ib.RodRock(segments=[ib.RodSegment(length=10.0, impedance=2.0)],
    ...                  rock=ib.BilinearRock(k=60.0, k_u=1e6), blow_time=2.0)
    >>> model = ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=0, impact=law)
    >>> load = ib.PiecewiseConstantLoad([0.0, 1.0, 3.0], [-1.0, 2.0, 0.0])
    >>> orbits = ib.periodic_orbits(model, load)  # calls periodic_orbits_by_newton
    >>> [(round(o.phase, 4), o.stable) for o in orbits]
    [(2.6008, False), (3.5461, True)]
    """
    found = []
    coarse = newton_start(model.law).coarse_model(model)
    starts = _paper_guesses(model if coarse is None else coarse, load)
    with single_threaded_blas():
        for guess in [*starts, None]:
            if guess is None:
                if any(o.stable for o in found):
                    break
                guess = _simulated_guess(model, load)
                if guess is None:
                    break
            try:
                if coarse is not None:  # the cheaper model's orbit from the guess, or none
                    guess = find_orbit(coarse, load, 1, 1, guess=guess)
                orbit = find_orbit(model, load, 1, 1, guess=guess)
            except ValueError:
                continue
            if all(abs(math.remainder(orbit.phase - o.phase, TWO_PI)) > 1e-7 for o in found):
                found.append(orbit)
    out = OrbitList(sorted(found, key=lambda o: o.phase))
    out._families = ()
    return out


#: :func:`periodic_orbits_by_newton` under the name it had in ``impactbar.laws`` (the rod-rock law's)
rock_periodic_orbits = periodic_orbits_by_newton

