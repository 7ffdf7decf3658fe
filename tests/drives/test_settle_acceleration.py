"""The start of Newton for a drive with state: the motion from rest followed at a
loose tolerance, and the slow supply mode extrapolated away (Aitken's delta-squared on the Poincare
map's iterates) instead of followed for a hundred impacts."""

import numpy as np
import pytest

import impactbar.orbits._closing as C
import impactbar.orbits._settling as settling
import impactbar.orbits.shooting as S
from impactbar import find_orbit
from impactbar.physical import circuit_preset


def _iterates(A, b, y0, n):
    ys = [np.asarray(y0, dtype=float)]
    for _ in range(n):
        ys.append(A @ ys[-1] + b)
    return ys


def _map(eigenvalues, seed=3):
    rng = np.random.default_rng(seed)
    V = rng.normal(size=(len(eigenvalues), len(eigenvalues)))
    A = V @ np.diag(eigenvalues) @ np.linalg.inv(V)
    b = rng.normal(size=len(eigenvalues))
    return A, b, np.linalg.solve(np.eye(len(eigenvalues)) - A, b)


def test_dominant_limit_is_the_fixed_point_of_a_linear_map():
    """One multiplier 0.92 left (the others 1e-3 and spent after a few iterates): the limit of the
    iterates, against the fixed point of the map solved directly."""
    A, b, fixed = _map([0.92, 1e-3, -2e-3, 5e-4])
    ys = _iterates(A, b, np.zeros(4), 8)
    star = settling.dominant_limit(*ys[-4:])
    assert star is not None
    assert np.linalg.norm(star - fixed) <= 1e-9 * np.linalg.norm(fixed)
    # the plain iterates are still 0.92^8 = 0.5 of the way off
    assert np.linalg.norm(ys[-1] - fixed) > 0.1 * np.linalg.norm(fixed)


@pytest.mark.parametrize("eigenvalues", [
    [0.9 + 0.3j, 0.9 - 0.3j, 1e-3],  # a complex pair: the steps turn
    [0.999, 1e-3, 2e-3],  # too close to 1 for the limit to be trusted
    [0.9, -0.85, 1e-3],  # two modes of one size
])
def test_dominant_limit_refuses_what_one_multiplier_does_not_fit(eigenvalues):
    if np.iscomplexobj(eigenvalues):
        a, w = 0.9, 0.3
        A = np.array([[a, -w, 0.0], [w, a, 0.0], [0.0, 0.0, 1e-3]])
        b = np.array([0.3, -0.2, 0.5])
    else:
        A, b, _ = _map(eigenvalues)
    ys = _iterates(A, b, np.ones(3), 6)
    assert settling.dominant_limit(*ys[-4:]) is None


def _counting(monkeypatch):
    """A list whose one item counts the shooting problem's flights from now on."""
    count = [0]
    flight = S.ShootingProblem._flight

    def counted(self, *args, **kwargs):
        count[0] += 1
        return flight(self, *args, **kwargs)

    monkeypatch.setattr(S.ShootingProblem, "_flight", counted)
    return count


def test_the_accelerated_start_finds_the_same_operating_point_in_fewer_flights(monkeypatch):
    """The rigid preset circuit drifter: the default start with and without the extrapolation and the
    loose tolerance (DOMINANT_FIT = 0 never extrapolates; SETTLE_RTOL = the drive's tolerance),
    the same orbit to the flights' accuracy, reached with under half the flights."""
    d = circuit_preset("circuit-drifter")
    model, drive = d.model().with_(n_modes=0), d.drive()
    count = _counting(monkeypatch)
    fast = find_orbit(model, drive)
    n_fast, count[0] = count[0], 0
    monkeypatch.setattr(settling, "DOMINANT_FIT", 0.0)
    monkeypatch.setattr(C, "SETTLE_RTOL", 1e-10)
    slow = find_orbit(model, drive)
    assert fast.stable and slow.stable
    assert fast.period == pytest.approx(slow.period, rel=1e-8)
    assert fast.impact_velocity == pytest.approx(slow.impact_velocity, rel=1e-8)
    np.testing.assert_allclose(fast.drive_states[0], slow.drive_states[0], rtol=1e-8, atol=1e-10)
    assert n_fast < count[0] / 2


def _curved(kappa, n, x_star=2.26, rho_star=0.92, x0=1.0):
    """``n + 1`` iterates of a map whose slow coordinate ``x`` contracts by ``rho_star + kappa |x -
    x_star|`` toward ``x_star`` (``kappa > 0``: the multiple of the steps falls as they near it, as the
    oil circuit's supply pressure from rest; ``kappa < 0``: it grows), a fast mode spent by 1e-3 a step."""
    ys, x, fast = [], x0, 0.3
    for _ in range(n + 1):
        ys.append(np.array([x, 0.5 * x + fast, 0.2 * x - fast]))
        e = x - x_star
        x = x_star + e * (rho_star + kappa * abs(e))
        fast *= 1e-3
    return ys, np.array([x_star, 0.5 * x_star, 0.2 * x_star])


def test_a_falling_multiple_takes_the_quadratics_fixed_point_not_aitkens():
    """The steps' multiple 0.988 then 0.985 (too far apart for Aitken's limit): the fixed point of the
    quadratic through the steps, within 1e-3 of the map's own (measured 2e-4; the quadratic is the map
    along ``x`` once the fast mode is spent), where Aitken's limit from the last two steps lands twice
    the remaining distance past it."""
    ys, fixed = _curved(0.03, 5)
    star = settling.dominant_limit(*ys[-4:])
    assert star is not None
    off = np.linalg.norm(ys[-1] - fixed)
    assert np.linalg.norm(star - fixed) <= 1e-3 * off
    d2, d3 = ys[-2] - ys[-3], ys[-1] - ys[-2]
    rho = settling._ratio(d2, d3)
    aitken = ys[-1] + rho / (1.0 - rho) * d3
    assert np.linalg.norm(aitken - fixed) > 2.0 * off
    assert settling.falling_limit(*ys[-4:]) is not None


def test_a_growing_multiple_is_not_extrapolated():
    """The steps' multiple 0.79 then 0.81 (the contraction weakening toward the fixed point): nothing
    (the quadratic's fixed point would lie beyond Aitken's)."""
    ys, _ = _curved(-0.1, 5, rho_star=0.95)
    assert settling.dominant_limit(*ys[-4:]) is None


def test_a_flexible_orbit_starts_three_impacts_after_the_rigid_orbit(monkeypatch):
    """A flexible piston's default start follows the rigid orbit, its modes at rest, for
    ``SETTLE_LIFTED`` (3) impacts at the loose tolerance, not until the impact velocities agree to
    ``SETTLE_HANDOVER`` (on the preset with 4 modes they ring by some 1e-3 and took 9): the same
    orbit as from that longer start, to 1e-9 of the unknowns' size and 1e-8 in the multipliers."""
    d = circuit_preset("circuit-drifter")
    model, drive = d.model().with_(n_modes=4), d.drive()
    loose = []
    fly = S.ShootingProblem._flight

    def spy(self, tau, mode, y, **kw):
        s = kw.get("settings")
        if self.M > 1 and s is not None and s.rtol == C.SETTLE_RTOL and not kw.get("variational"):
            loose.append(tau)
        return fly(self, tau, mode, y, **kw)

    monkeypatch.setattr(S.ShootingProblem, "_flight", spy)
    short = find_orbit(model, drive)
    assert len(loose) == S.SETTLE_LIFTED == 3
    loose.clear()
    monkeypatch.setattr(S, "SETTLE_LIFTED", S.SETTLE_IMPACTS)
    long = find_orbit(model, drive)
    assert len(loose) > 3, loose  # (the agreement to SETTLE_HANDOVER: 9 measured)
    X, Xl = np.asarray(short._unknowns), np.asarray(long._unknowns)
    assert np.max(np.abs(X - Xl)) <= 1e-9 * np.max(np.abs(Xl))
    np.testing.assert_allclose(short.multipliers, long.multipliers, rtol=0, atol=1e-8)
    assert short.stable and long.stable


class _Ceiling:
    """A drive with one surface, ``z[0]`` rising through ``top``."""

    def __init__(self, top):
        from impactbar.drives.base import SurfaceEvent

        self._events = (SurfaceEvent("top", direction=1, function=lambda t, q, v, z: z[0] - top),)

    def events(self, mode):
        return self._events


@pytest.mark.parametrize("rho, carried", [(1.05, True), (1.01, False), (0.9, False)])
def test_a_map_that_expands_is_carried_to_the_surface_ahead(rho, carried):
    """A linear map of multiplier ``rho`` along ``u`` from ``y0``: steps growing by 5 % have no limit
    ahead and are carried along the last step to the surface ``z[0] = 1.5`` (where the line through the
    last two iterates meets it, solved directly: within 1e-10); a
    multiple of 1.01 (within the fit's 2 % of 1) and a contraction are left as they are."""
    u = np.array([0.0, 0.0, 1.0, 0.3])
    ys = [np.array([0.0, 0.0, 1.0, 0.0]) + 0.01 * (rho ** k - 1.0) / (rho - 1.0) * u for k in range(4)]
    star = settling.expanding_to_surface(_Ceiling(1.5), 0, *ys, 1)
    assert (star is not None) == carried
    if carried:
        d = ys[-1] - ys[-2]
        s = (1.5 - ys[-1][2]) / d[2]  # (the surface on the line y3 + s d)
        np.testing.assert_allclose(star, ys[-1] + s * d, rtol=0, atol=1e-10)
        assert star[2] <= 1.5
    assert settling.dominant_limit(*ys) is None or not carried


def test_the_spool_drills_start_carried_to_its_relief_finds_the_same_orbit_in_fewer_flights(monkeypatch):
    """The spool drill (``examples/circuit_drill_spool.toml``) from rest (its supply at the pre-charge,
    not charged to the relief's setting as ``_closing.settle_start`` has it): its supply pressure's steps
    grow impact after impact (5 % to 1.4 %) until the relief valve opens at its setting. Carried
    there at once, the same orbit as the motion followed there (``expanding_to_surface`` never
    carrying), to 1e-9 of the unknowns and 1e-8 in the multipliers, with under 2/3 of the flights
    (measured 15 periods against 26)."""
    from pathlib import Path

    from impactbar.physical import load

    d = load(Path(__file__).resolve().parents[2] / "examples" / "circuit_drill_spool.toml")
    model, drive = d.model(), d.drive()
    monkeypatch.setattr(C, "settle_start", lambda problem, q, v: problem.drive.start(problem.model, q, v))
    count = _counting(monkeypatch)
    fast = find_orbit(model, drive)
    n_fast, count[0] = count[0], 0
    monkeypatch.setattr(S, "expanding_to_surface", lambda *args: None)
    slow = find_orbit(model, drive)
    assert fast.stable and slow.stable
    X, Xs = np.asarray(fast._unknowns), np.asarray(slow._unknowns)
    assert np.max(np.abs(X - Xs)) <= 1e-9 * np.max(np.abs(Xs))
    np.testing.assert_allclose(fast.multipliers, slow.multipliers, rtol=0, atol=1e-8)
    assert n_fast < 2 * count[0] / 3, (n_fast, count[0])


def _period_speeds(cycle, n, drift=0.0, noise=0.0, seed=5):
    """``n`` impact velocities repeating ``cycle``, each cycle's values moved by ``drift`` times the
    one before's distance to its limit (a slow supply mode), with a relative noise."""
    rng = np.random.default_rng(seed)
    cycle = np.asarray(cycle, dtype=float)
    out = np.array([cycle[i % cycle.size] * (1.0 - 0.01 * drift ** (i // cycle.size)) for i in range(n)])
    return out * (1.0 + noise * rng.standard_normal(n))


@pytest.mark.parametrize("cycle", [(0.46, 0.4625), (0.5, 0.44, 0.47), (0.5, 0.5, 0.42)])
def test_other_period_finds_a_cycle_of_impacts_that_repeats(cycle):
    """A cycle of ``k`` impacts repeating to 1e-7 (the loose flights' noise), a slow drift of each
    cycle's values: ``k``; the same cycle still drifting by more than the tolerance a cycle: 0."""
    k = len(cycle)
    settled = _period_speeds(cycle, 12 * k, drift=0.3, noise=1e-7)
    assert settling.other_period(settled, 1e-4) == k
    drifting = _period_speeds(cycle, 12 * k, drift=0.999)  # (each cycle 1e-5 of its values on)
    assert settling.other_period(drifting, 1e-6) == 0


@pytest.mark.parametrize("lam", [0.5, -0.5, -0.9, -0.97, -0.99])
def test_other_period_takes_no_oscillation_that_decays_onto_one_impact(lam):
    """Impact velocities settling onto a one-impact orbit along a real multiplier ``lam`` (flipping
    sign each impact for ``lam < 0``, a cycle of two that repeats to less and less): 0 at every
    length, though near ``lam = -1`` they repeat every second impact 100 times closer than
    consecutive ones differ."""
    v = 0.46 * (1.0 + 1e-2 * lam ** np.arange(600))
    assert all(settling.other_period(v[:n], 1e-4) == 0 for n in range(2, 601))
    assert settling.other_period(np.full(20, 0.46), 1e-4) == 0
