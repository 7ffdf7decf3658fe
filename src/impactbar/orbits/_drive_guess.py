"""The default start of a flexible bar's one-impact orbit under the valve (issue 40, theory §10):
the rigid orbit lifted to the modes, then a settled run from rest."""

from __future__ import annotations

import numpy as np

from ..simulation import InitialState, simulate

__all__ = ["default_chain", "solve_from", "SETTLE_PERIODS"]

def solve_from(problem, guess, tol, max_iter, orbit_of):
    """Newton from ``guess`` (:meth:`OrbitProblem.initial`), the solution's orbit (``orbit_of``)."""
    X0 = problem.initial(guess, tol, max_iter)
    X = problem.solve(X0, tol, max_iter)
    times, start = X[problem.positive], X0[problem.positive]
    if times.size and float(np.sum(times)) < 1e-6 * float(np.sum(start)):
        # the flights shrank to nothing (a root of the equations, not a motion; issue 42: it was
        # returned as a "backward impact" orbit of period 3e-9, a different one at each scale)
        raise ValueError(f"find_orbit: Newton reached a degenerate solution (flights of total length "
                         f"{float(np.sum(times)):.3g} from {float(np.sum(start)):.3g} at the guess), not a "
                         "periodic motion; give a guess (e.g. simulate(...) under the drive)")
    return orbit_of(problem, X)


#: the rigid orbit's periods simulated from rest by the default guess chain (issue 40)
SETTLE_PERIODS = 200


def default_chain(problem, tol, max_iter, orbit_of):
    """The default start of a flexible bar's one-impact orbit under the valve (issue 40): the rigid
    orbit lifted to the modes; where Newton fails from it or reaches an orbit that is not admissible
    and stable, a run from rest over ``SETTLE_PERIODS`` rigid periods whose last impacts are one
    valve cycle apart and settled (to 1e-6) as the guess. Returns the first admissible, stable orbit,
    else the first admissible one, else the first found; else raises, naming what it tried."""
    model, drive = problem.model, problem.drive
    found, tried = [], []

    def attempt(label, guess):
        try:
            orbit = solve_from(problem, guess, tol, max_iter, orbit_of)
        except ValueError as exc:
            tried.append(f"{label}: {str(exc).split(':')[-1].strip()}")
            return None
        found.append(orbit)
        tried.append(f"{label}: {'stable' if orbit.stable else 'unstable'}, {orbit.admissibility}")
        return orbit if orbit.stable else None

    if (best := attempt("the rigid orbit lifted to the modes", None)) is not None:
        return best
    period = float(drive.rigid_orbit(model.R)["period"])
    try:
        run = simulate(model, drive, InitialState.rigid(0.0, 0.0, model.n_modes), SETTLE_PERIODS * period)
        gaps = np.diff(np.asarray(run.impact_times)[-6:])
        settled = gaps.size == 5 and float(np.ptp(gaps)) <= 1e-6 * float(np.mean(gaps))
    except ValueError as exc:
        settled, run = False, None
        tried.append(f"a run from rest: {exc}")
    if settled:
        if (best := attempt("a run from rest, settled", run)) is not None:
            return best
    elif run is not None:
        tried.append(f"a run from rest over {SETTLE_PERIODS} rigid periods: not settled on one impact a "
                     "cycle")
    for orbit in (*[o for o in found if o.admissible], *found):
        return orbit
    raise ValueError("find_orbit found no one-impact orbit of the flexible bar from its default guesses ("
                     + "; ".join(tried) + "); give a guess: an orbit, simulate(...) under the drive once "
                     "settled, or a tuple (states, h1, h3)")
