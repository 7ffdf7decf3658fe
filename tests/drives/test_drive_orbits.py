"""Every one-impact orbit of the valve: ``periodic_orbits(model, drive)`` against a
brute-force scan of an independent formulation, the default guess chain of ``find_orbit`` and a
simulated run of the flexible bar as a guess.

The reference (:func:`_reference`) writes the one-impact orbit's conditions afresh: each flexible
mode's flow by the eigen-decomposition of its 2x2 matrix (complex exponentials, not the library's
real closed forms), its periodic motion by a batched linear solve of the period map, the rigid
mode's flights by the textbook forms. A grid over the period ``T`` and the stroke's flight ``h3``
brackets the roots (cells where both conditions change sign), ``scipy.optimize.root`` refines each.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import root
from test_new_drive import Push  # tests/drives is on the path (pytest's rootdir-relative import)

from impactbar import (
    BarModel,
    InitialState,
    PositionSwitchedDrive,
    find_orbit,
    periodic_orbits,
    simulate,
)

#: two cases of the valve: 6 modes without a delay, 8 modes with one
VALVE_CASES = [(BarModel(3, 0.1, 0.6, 6), PositionSwitchedDrive(1, 0.5, 0.15)),
               (BarModel(10, 0.02, 0.3, 8), PositionSwitchedDrive(2, 1, 0.2, delay=0.05))]


def _reference(model, drive, T, h):
    """``(F1, F2)`` at the points ``(T, h3)``: the rigid coordinate's return over the period and the
    gap at the switch crossing minus ``switch_out``, with every mode's periodic motion."""
    T, h = np.broadcast_arrays(np.asarray(T, dtype=float), np.asarray(h, dtype=float))
    d, R = model.d, model.R
    ps, pr, x1 = drive.stroke, -drive.ret, drive.switch_out
    t_in, t_out = drive.delay_in, drive.delay_out
    h1 = T - t_in - t_out - h
    flights = ((ps, np.full(T.shape, t_in)), (pr, h1), (pr, np.full(T.shape, t_out)), (ps, h))
    # the rigid mode: v(t) = v0 e^{-dt} + p (1 - e^{-dt}) / d, x(t) = x0 + (v0 - p/d)(1 - e^{-dt})/d + p t/d
    a_v, b_v, a_x, b_x = np.ones(T.shape), np.zeros(T.shape), np.zeros(T.shape), np.zeros(T.shape)
    cross = None
    for k, (p, t) in enumerate(flights):
        e = np.exp(-d * t)
        g = (1.0 - e) / d
        a_x, b_x = a_x + a_v * g, b_x + (b_v - p / d) * g + p * t / d
        a_v, b_v = a_v * e, b_v * e + p * g
        if k == 1:
            cross = (a_x.copy(), b_x.copy())
    v0 = -R * b_v / (1.0 + R * a_v)  # v0 = -R v(T-)
    F1 = a_x * v0 + b_x
    dx_cross = cross[0] * v0 + cross[1]
    # the flexible modes: z' = A z + (0, p), A = [[0, 1], [-w^2, -d]]
    w2 = (model.s * np.pi * np.arange(1, model.n_modes + 1)) ** 2
    c = model.end_weights[1:]
    end = np.zeros(T.shape)
    Jm = np.diag([1.0, -R])
    for wn, cn in zip(w2, c, strict=True):
        lam, V = np.linalg.eig(np.array([[0.0, 1.0], [-wn, -d]]))
        Vi = np.linalg.inv(V)
        Phi = np.broadcast_to(np.eye(2), T.shape + (2, 2)).astype(complex)
        gz = np.zeros(T.shape + (2,), dtype=complex)
        for p, t in flights:
            E = np.einsum("ij,...j,jk->...ik", V, np.exp(lam * t[..., None]), Vi)
            s = np.array([p / wn, 0.0])
            Phi = E @ Phi
            gz = np.einsum("...ij,...j->...i", E, gz - s) + s
        A = np.eye(2) - Jm @ Phi
        z0 = np.linalg.solve(A.real, np.einsum("ij,...j->...i", Jm, gz.real)[..., None])[..., 0]
        end += cn * z0[..., 0]
    q0 = -end  # contact at the impact: c . q = 0
    F2 = -(q0 + dx_cross) - x1
    return F1, F2


def _brute_force(model, drive, window, nT=500, nh=260):
    """The roots ``(T, h3)`` with ``T`` in ``window`` and ``h1, h3 > 0``, from a grid scan of
    :func:`_reference` (cells where both conditions change sign) refined by ``scipy.optimize.root``."""
    tau = drive.delay_in + drive.delay_out
    Ts = np.linspace(window[0], window[1], nT)
    hs = np.linspace(0.0, window[1] - tau, nh)[1:]
    TT, HH = np.meshgrid(Ts, hs, indexing="ij")
    with np.errstate(all="ignore"):
        F1, F2 = _reference(model, drive, TT, HH)

    def changes(F):
        corners = np.stack((F[:-1, :-1], F[1:, :-1], F[:-1, 1:], F[1:, 1:]))
        return (corners.min(axis=0) <= 0.0) & (corners.max(axis=0) >= 0.0)

    cells = np.argwhere(changes(F1) & changes(F2))
    roots = []
    for i, j in cells:
        x0 = np.array([0.5 * (Ts[i] + Ts[i + 1]), 0.5 * (hs[j] + hs[j + 1])])
        def fun(x):
            return np.array([f[()] for f in _reference(model, drive, x[0], x[1])])

        T, h = root(fun, x0, tol=1e-13).x
        if not (np.max(np.abs(fun((T, h)))) < 1e-10 and window[0] <= T <= window[1] and 0.0 < h < T - tau):
            continue
        if not any(abs(T - r[0]) < 1e-8 and abs(h - r[1]) < 1e-8 for r in roots):
            roots.append((T, h))
    return sorted(roots)


def _listed(orbits):
    return [(o.period, o.durations[3]) for o in orbits]


@pytest.mark.parametrize("model, drive, window, nT", [
    (BarModel(3, 0.1, 0.6, 6), PositionSwitchedDrive(1, 0.5, 0.15), (0.2, 3.0), 500),
    (BarModel(5, 0.05, 0.4, 4), PositionSwitchedDrive(1, 1, 0.3, delay_out=0.1, delay_in=0.02), (0.4, 4.0),
     500),
    (BarModel(2, 0.3, 0.5, 3), PositionSwitchedDrive(1.5, 1, 0.4, delay=0.1), (0.3, 6.0), 500),
    pytest.param(BarModel(10, 0.02, 0.3, 8), PositionSwitchedDrive(2, 1, 0.2, delay=0.05), (0.8, 1.8), 2000,
                 marks=pytest.mark.slow),  # (its close pairs of roots need a fine grid: 11 s)
])
def test_every_orbit_is_listed_against_a_brute_force_scan(model, drive, window, nT):
    orbits = periodic_orbits(model, drive, window=window)
    assert orbits.window == window and orbits.unresolved == () and all(orbits.certified)
    listed = _listed(orbits)
    brute = _brute_force(model, drive, window, nT)
    assert len(brute) >= 3
    for T, h in brute:  # nothing missed
        assert any(abs(T - a) < 1e-9 and abs(h - b) < 1e-9 for a, b in listed), (T, h, listed)
    for (T, h), o in zip(listed, orbits, strict=True):  # nothing spurious: roots of the reference
        F1, F2 = _reference(model, drive, T, h)
        assert abs(F1) < 1e-10 and abs(F2) < 1e-10
        assert o.durations[1] > 0.0 and o.durations[3] > 0.0
    assert len(listed) == len(brute)
    assert [o.period for o in orbits] == sorted(o.period for o in orbits)


@pytest.mark.parametrize("model, drive", VALVE_CASES)
def test_the_stable_orbit_from_the_default_and_from_a_run(model, drive):
    orbits = periodic_orbits(model, drive)
    stable = [o for o in orbits if o.stable]
    assert stable and all(o.admissible for o in stable)
    assert any(not o.stable and o.admissible for o in orbits)  # listed with the unstable ones
    default = find_orbit(model, drive)
    assert default.stable and default.admissible
    match = [o for o in stable if abs(o.period - default.period) <= 1e-12 * o.period]
    assert len(match) == 1
    assert np.max(np.abs(match[0].state - default.state)) <= 1e-12
    # a run started near each stable orbit stays by it, and reads back as a guess of that orbit: it
    # starts in the return flight (where the valve's state is the one simulate starts from, return
    # with nothing pending), its flexible modes' velocities 1e-3 off
    for o in stable:
        t = o.durations[0] + 0.5 * o.durations[1]
        q, v = (a[:, 0] for a in o.modal_state(np.array([t])))
        v[1:] *= 1.001
        run = simulate(model, drive, InitialState(q, v), 25.0 * o.period)
        found = find_orbit(model, drive, guess=run)
        assert abs(found.period - o.period) <= 1e-12 * o.period
        assert np.max(np.abs(found.state - o.state)) <= 1e-12


def test_a_flexible_run_from_rest_is_a_guess():
    # the first of VALVE_CASES: the run from rest settles on the stable orbit (its multiplier ~ -0.95); on
    # the previous main a flexible run was refused ("read for the rigid bar only")
    model, drive = VALVE_CASES[0]
    run = simulate(model, drive, InitialState.rigid(0.0, 0.0, n_modes=model.n_modes), 60.0)
    orbit = find_orbit(model, drive, guess=run)
    assert orbit.stable and orbit.period == pytest.approx(1.6092428304821, abs=1e-12)
    assert np.max(np.abs(orbit.multipliers)) == pytest.approx(0.94870436, abs=1e-7)
    # the run's own periodic motion: its last impacts repeat the orbit's period
    assert np.diff(run.impact_times[-2:])[0] == pytest.approx(orbit.period, rel=1e-3)


def test_the_default_chain_says_what_it_tried():
    with pytest.raises(ValueError, match=r"found no periodic orbit.*tried the motion from rest on the stop.*"
                                         r"the search of every orbit: none for this drive"):
        find_orbit(BarModel(10, 0.1, 0.5, 0), Push(-1.0))  # away from the stop: no orbit
    # the valve's first start, the rigid piston's orbit, fails on the first of VALVE_CASES (the
    # default found its orbit above by the chain's next start, the run from rest): Newton's steps
    # wander, none in five halving the smallest before it, and it gives up (before: after 50 steps)
    from impactbar.orbits.driven import orbit_problem

    problem = orbit_problem(*VALVE_CASES[0])
    with pytest.raises(ValueError, match="Newton stalled"):
        problem.solve(problem.initial(None, 1e-13, 50), 1e-13, 50)


def test_window_is_checked():
    model, drive = VALVE_CASES[0]
    for bad in [(2.0, 1.0), (0.0, 1.0), (1.0, np.inf), "wide", (1.0,)]:
        with pytest.raises(ValueError, match="window"):
            periodic_orbits(model, drive, window=bad)
    from impactbar import CosineLoad

    with pytest.raises(ValueError, match="window"):
        periodic_orbits(model, CosineLoad(0.5, 1.0), window=(1.0, 2.0))


def test_orbit_list_tables():
    model, drive = VALVE_CASES[0]
    frame = periodic_orbits(model, drive).to_dataframe()
    assert len(frame) == 7 and frame["stable"].sum() == 1


@pytest.mark.parametrize("model, drive", [*VALVE_CASES, (BarModel(5, 0.05, 0.4, 4),
                                                         PositionSwitchedDrive(1, 1, 0.3, delay_out=0.1,
                                                                               delay_in=0.02))])
def test_reduced_equations_are_the_segment_problem(model, drive, rng):
    # the search's two equations in (T, h3) (orbits/valve_search.py) against the segment
    # residual (orbits/valve_segment.py): the state they build satisfies every periodicity row
    # but the rigid position's, whose misfit is F1, and the switch row is F2; their Jacobian
    # against central differences; their interval enclosure over a box holds sampled Jacobians
    from impactbar.orbits.valve_search import OneImpactEquations
    from impactbar.orbits.valve_segment import _residual

    eq = OneImpactEquations(model, drive)
    M = model.n_modes + 1
    for _ in range(3):
        T = rng.uniform(1.0, 5.0)
        h = rng.uniform(0.1, T - eq.tau - 0.1)
        F, J, _ = eq.point(T, h)
        r, _ = _residual(model, drive, eq.state(T, h))
        assert np.max(np.abs(r[1:2 * M])) < 1e-12
        assert r[0] == pytest.approx(-F[0, 0], abs=1e-12) and r[2 * M] == pytest.approx(F[0, 1], abs=1e-12)
        e = 1e-6
        dT = (eq.point(T + e, h)[0] - eq.point(T - e, h)[0])[0] / (2 * e)
        dh = (eq.point(T, h + e)[0] - eq.point(T, h - e)[0])[0] / (2 * e)
        assert np.max(np.abs(np.column_stack((dT, dh)) - J[0])) < 1e-6 * max(1.0, np.max(np.abs(J)))
        rT, rh = 0.05, 0.03
        box = eq.jacobian_box(np.array([T]), np.array([h]), np.array([rT]), np.array([rh]))
        _, Js, _ = eq.point(rng.uniform(T - rT, T + rT, 500), rng.uniform(h - rh, h + rh, 500))
        for i in range(2):
            for j in range(2):
                lo, hi = box[i][j].lo[0] - 1e-12, box[i][j].hi[0] + 1e-12
                assert np.all((Js[:, i, j] >= lo) & (Js[:, i, j] <= hi))


def test_undamped_resonances_are_reported():
    model, drive = BarModel(3, 0.0, 0.6, 2), PositionSwitchedDrive(1, 0.5, 0.15)
    orbits = periodic_orbits(model, drive, window=(0.5, 1.5))
    reasons = {r for _, _, r in orbits.unresolved}
    assert reasons == {"resonance"}
    for lo, hi, _ in orbits.unresolved:  # each holds a resonance T = 2 k / (s n)
        k_n = 0.5 * model.s * np.arange(1, 3) * 0.5 * (lo + hi)
        assert np.min(np.abs(k_n - np.round(k_n))) < 1e-6
    with pytest.raises(ValueError, match="undamped resonances"):
        periodic_orbits(BarModel(10, 0.0, 0.5, 8), PositionSwitchedDrive(1, 1, 1))


def test_the_default_chain_skips_a_search_it_cannot_afford(monkeypatch):
    """A fuzz case (``benchmarks/fuzz_campaign.py``): strokes of 0.03 against a return of 732, a period near
    2000, and one mode at s = 8.3: the default window held about 74,000 resonances and the chain's
    last step, the search of every orbit, took minutes. Past ``MAX_DEFAULT_RESONANCES`` it is
    skipped (find_orbit answers from its first steps or says what it tried); the second of
    ``VALVE_CASES`` (2,340 in its window) still reaches the search."""
    import impactbar.orbits.driven_search as ss

    calls = []
    real = ss._searched
    monkeypatch.setattr(ss, "_searched", lambda *a: calls.append(1) or real(*a))
    model = BarModel(8.312238249550228, 0.0018142798082551258, 0.889269330963702, 1)
    drive = PositionSwitchedDrive(0.03426521879195014, 731.6706397390018, 1.63858368445898)
    orbit = find_orbit(model, drive)
    assert calls == [] and np.isfinite(orbit.period)
    model, drive = VALVE_CASES[1]
    assert find_orbit(model, drive).stable and calls == [1]


def test_the_orbit_solvers_choose_the_valve_problem_from_their_table():
    """The valve's segment problem is the orbit solvers' (``orbits.driven.ORBIT_PROBLEMS``), not
    the drive's: the drive brings no ``orbit_problem`` among its abilities; a subclass that brings
    one keeps it, one that does not gets the table's; a drive outside the table gets the generic
    shooting."""
    from impactbar.drives import DriveAbilities
    from impactbar.orbits.driven import ORBIT_PROBLEMS, ShootingProblem, orbit_problem
    from impactbar.orbits.valve_segment import ValveProblem

    model, drive = VALVE_CASES[1]
    assert drive.abilities.orbit_problem is None
    assert ORBIT_PROBLEMS[PositionSwitchedDrive] is ValveProblem
    assert type(orbit_problem(model, drive, 2)) is ValveProblem

    class Plain(PositionSwitchedDrive):
        pass

    class Own(PositionSwitchedDrive):
        @property
        def abilities(self):
            return DriveAbilities(orbit_problem=lambda model, m, load: ShootingProblem(model, self, m))

    args = dict(stroke=2.0, ret=1.0, switch_out=0.2, delay=0.05)
    assert type(orbit_problem(model, Plain(**args), 1)) is ValveProblem
    assert type(orbit_problem(model, Own(**args), 1)) is ShootingProblem
    assert type(orbit_problem(model, Push(0.5), 1)) is ShootingProblem
