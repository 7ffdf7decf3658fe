"""The wave-resolved impact on a long rod (theory §4b) against closed forms for a uniform piston, an
independent characteristics lattice written here, the energy balance, and finite differences."""

import math

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, SquareWaveLoad
from impactbar.laws.wave.impact import wave_impact, window_drive
from wave_reference import random_state

NO_DRIVE = CosineLoad(0.0, 0.0)


def lattice(s, R, q, v, load, t0, J):
    """Characteristics lattice of ``J`` cells, time step = cell crossing time ``1/(s J)``: the Riemann
    invariants ``v -+ s u_x`` move exactly one node per step, so without separation the lattice is
    exact at its nodes. Drive at ``x = 0``, rod impedance at ``x = 1``; separated, the end is free
    and the gap is summed by rectangles (first order in ``1/J``).

    The initial strain is the modal sum plus the static correction that carries the drive's force
    ``p(t0)`` at ``x = 0`` (theory §4c): the strain ``-p (1 - x)/s^2`` less its first ``N`` sine
    terms.

    Returns the nodes, ``v - s u_x`` and ``v + s u_x`` at the end of the window, and the interface
    force at every step."""
    def p(m):
        return float(load(t0 + m / (J * s)))

    n = np.arange(q.size)
    x = np.arange(J + 1) / J
    vel = np.cos(np.pi * np.outer(x, n)) @ (v * np.where(n == 0, 1.0, 2.0))
    se = -np.sin(np.pi * np.outer(x, n)) @ (2 * s * np.pi * n * q)
    static = -p(0) / s * (1 - x)  # s u_x of the static strain, less its sine terms n <= N
    se += static + np.sin(np.pi * np.outer(x, n[1:])) @ (2 * p(0) / (s * np.pi * n[1:]))
    al, be = vel - se, vel + se

    al[0] = be[0] + 2 * p(0) / s
    be[J] = -R * al[J]
    on, gap = True, 0.0
    F = [0.5 * s * (1 + R) * al[J]]
    for m in range(1, 2 * J + 1):
        al = np.concatenate(([0.0], al[:-1]))
        be = np.concatenate((be[1:], [0.0]))
        al[0] = be[0] + 2 * p(m) / s
        A = al[J]
        if on and A < 0:
            on, gap = False, 0.0
        elif not on:
            gap -= A / J
            on = gap <= 0 and A >= 0
        be[J] = -R * A if on else A
        F.append(0.5 * s * (1 + R) * A if on else 0.0)
    return x, al, be, np.array(F)


# ---------------------------------------------------------------- uniform piston, closed forms ----
@pytest.mark.parametrize("R", [0.0, 0.3, 0.8])
def test_uniform_piston_closed_forms(R):
    s, vel, N = 7.0, 1.7, 5
    model = BarModel(s=s, d=0.0, R=R, n_modes=N)
    q, v = np.zeros(N + 1), np.zeros(N + 1)
    v[0] = vel
    imp = wave_impact(model, NO_DRIVE, 0.4, q, v)
    Z, Zs = s, s * (1 + R) / (1 - R)
    np.testing.assert_allclose(imp.contact, [[0.0, 2.0 / s]], rtol=0, atol=1e-15)  # 2 L / C
    assert imp.v_after[0] == pytest.approx(-R * vel, abs=1e-15)
    np.testing.assert_allclose(imp.v_after[1:], 0.0, atol=1e-15)
    np.testing.assert_allclose(imp.q_after, 0.0, atol=1e-15)
    plateau = Z * Zs * vel / (Z + Zs)
    assert imp.peak_force == pytest.approx(plateau, rel=1e-14)
    assert imp.min_force == pytest.approx(plateau, rel=1e-14)
    np.testing.assert_allclose(imp.force(np.linspace(0, 2 / s, 7)), plateau, rtol=1e-14)
    E0 = 0.5 * vel**2
    assert imp.rod_energy == pytest.approx((1 - R**2) * E0, rel=1e-14)
    assert imp.efficiency == pytest.approx(1 - R**2, rel=1e-14)
    assert imp.impulse == pytest.approx((1 + R) * vel, rel=1e-14)  # momentum v - (-R v)
    assert imp.advance == pytest.approx(imp.impulse / Zs, rel=1e-14)
    assert imp.peak_rod_stress == pytest.approx(plateau / ((1 + R) / (1 - R)), rel=1e-14)
    smax, smin = imp.piston_stress_extremes()
    assert smax == pytest.approx(plateau, rel=1e-13)
    assert abs(smin) < 1e-13 * plateau


# ---------------------------------------------------------------- the -R law, against the lattice -
@pytest.mark.parametrize("seed", range(4))
def test_no_drive_fields_times_minus_R(seed):
    rng = np.random.default_rng(seed)
    N = int(rng.integers(1, 10))
    s, R = float(rng.uniform(2, 30)), float(rng.uniform(0, 0.95))
    model = BarModel(s=s, d=0.0, R=R, n_modes=N)
    q, v = random_state(rng, model, 0.1)
    imp = wave_impact(model, NO_DRIVE, 0.0, q, v)
    assert imp.separations == 0
    np.testing.assert_allclose(imp.q_after[1:], -R * q[1:], rtol=0, atol=1e-15 * np.abs(q).max())
    np.testing.assert_allclose(imp.v_after, -R * v, rtol=0, atol=1e-14)
    J = 400
    x, al, be, F = lattice(s, R, q, v, NO_DRIVE, 0.0, J)
    vel, strain = imp.fields(x)
    inner = slice(1, -1)  # the ends are corners of the characteristics net, not nodes of the field
    np.testing.assert_allclose(vel[inner], 0.5 * (al + be)[inner], rtol=0, atol=1e-13)
    np.testing.assert_allclose(s * strain[inner], 0.5 * (be - al)[inner], rtol=0, atol=1e-13)
    np.testing.assert_allclose(imp.force(np.arange(2 * J) / (J * s)), F[:-1], rtol=0, atol=1e-12 * s)
    # and the whole field is -R times the field before (positions from the rod end)
    n = np.arange(N + 1)
    v_before = np.cos(np.pi * np.outer(x, n)) @ (v * np.where(n == 0, 1.0, 2.0))
    np.testing.assert_allclose(vel[inner], -R * v_before[inner], rtol=0, atol=1e-13)


@pytest.mark.parametrize("load, t0", [
    (CosineLoad(40.0, 60.0, k=3), 0.7),
    (SquareWaveLoad(10.0, 1.4), 2 * math.pi - 0.05),  # a jump 0.05 after contact starts
    (SquareWaveLoad(10.0, 1.4), 1.4 * math.pi - 0.15),  # a jump in the window's second half
])
def test_drive_against_lattice(rng, load, t0):
    s, R, N = 10.0, 0.4, 6
    model = BarModel(s=s, d=0.0, R=R, n_modes=N)
    q, v = random_state(rng, model, 0.05)
    v[0] += 3.0
    imp = wave_impact(model, load, t0, q, v)
    assert imp.separations == 0 and imp.drive_work != 0.0
    J = 1000  # the jump falls between nodes: compare away from its characteristic
    x, al, be, F = lattice(s, R, q, v, load, t0, J)
    vel, strain = imp.fields(x)
    err = np.abs(vel - 0.5 * (al + be))[1:-1]
    assert np.sum(err > 1e-12) <= 2
    ok = np.abs(imp.force(np.arange(2 * J) / (J * s)) - F[:-1]) < 1e-11 * s
    assert np.sum(~ok) <= 2


def test_early_separation_against_lattice(rng):
    s, R, N = 25.0, 0.6, 8
    model = BarModel(s=s, d=0.0, R=R, n_modes=N)
    q, v = random_state(rng, model, 3.0)
    for load in (NO_DRIVE, SquareWaveLoad(60.0, 1.5)):
        imp = wave_impact(model, load, 1.0, q, v)
        assert imp.separations >= 1
        sw = imp.contact.ravel()
        sw = sw[(sw > 0) & (sw < 2 / s)] * s
        for J in (1000, 2000):
            x, al, be, F = lattice(s, R, q, v, load, 1.0, J)
            on = F[:-1] > 0
            lat_sw = np.flatnonzero(np.diff(on.astype(int))) / J
            assert lat_sw.size == sw.size
            np.testing.assert_allclose(lat_sw, sw, rtol=0, atol=2.0 / J)
            # the lattice decides each switch at the node after it; away from the characteristics
            # of the switches its nodes carry the exact field
            vel, strain = imp.fields(x)
            bad = np.abs(vel - 0.5 * (al + be)) > 1e-9
            bad |= np.abs(s * strain - 0.5 * (be - al)) > 1e-9
            images = np.concatenate((1 - sw[sw < 1], sw[sw > 1] - 1))
            near = np.min(np.abs(x[:, None] - images[None, :]), axis=1) <= 1.5 / J
            assert not np.any(bad[1:-1] & ~near[1:-1])


def test_single_early_separation_closed_form():
    """``u_t = v0 + 2 v1 cos(pi x)`` with ``v1 < 0``: the arriving invariant ``v0 - 2 v1 cos(pi theta)``
    falls to zero at ``cos(pi theta) = v0 / (2 v1)``, the force with it, and contact is not regained
    within the window (closed form of the gap)."""
    s, R = 10.0, 0.5
    model = BarModel(s=s, d=0.0, R=R, n_modes=1)
    q, v = np.zeros(2), np.array([-0.2, -0.6])  # u_t(1) = v0 - 2 v1 = 1
    imp = wave_impact(model, NO_DRIVE, 0.0, q, v)
    th = math.acos(v[0] / (2 * v[1])) / math.pi
    np.testing.assert_allclose(imp.contact, [[0.0, th / s]], rtol=1e-13)
    assert imp.separations == 1
    # gap = -int_th^2 A / s, A = v0 + 2 v1 cos(pi theta) on both halves
    gap = -(v[0] * (2 - th) + 2 * v[1] * math.sin(math.pi * th) / math.pi) / s
    assert imp.gap == pytest.approx(gap, rel=1e-13)
    assert imp.q_after[0] + 2 * (-1) * imp.q_after[1] == pytest.approx(-gap, rel=1e-13)
    # rod energy: (1 - R^2)/4 int_0^th A^2
    A2 = (v[0] ** 2 * th - 4 * v[0] * v[1] * math.sin(math.pi * th) / math.pi
          + 4 * v[1] ** 2 * (th / 2 + math.sin(2 * math.pi * th) / (4 * math.pi)))
    assert imp.rod_energy == pytest.approx(0.25 * (1 - R**2) * A2, rel=1e-13)
    J = 2000
    x, al, be, F = lattice(s, R, q, v, NO_DRIVE, 0.0, J)
    assert np.flatnonzero(F[:-1] <= 0)[0] / J == pytest.approx(th, abs=1.0 / J)
    vel, _ = imp.fields(x)
    np.testing.assert_allclose(vel[1:-1], 0.5 * (al + be)[1:-1], rtol=0, atol=10.0 / J)


# ---------------------------------------------------------------- energy per impact ---------------
@pytest.mark.parametrize("amplitude", [0.05, 3.0])
@pytest.mark.parametrize("load", [NO_DRIVE, CosineLoad(30.0, 50.0), SquareWaveLoad(60.0, 1.3)])
def test_energy_balance(rng, amplitude, load):
    s, R, N = 15.0, 0.3, 7
    model = BarModel(s=s, d=0.0, R=R, n_modes=N)
    for t0 in (0.3, 2 * math.pi - 0.04, 1.3 * math.pi - 0.1):
        q, v = random_state(rng, model, amplitude)
        imp = wave_impact(model, load, t0, q, v)
        lhs = imp.energy_before + imp.drive_work
        rhs = imp.energy_after_field + imp.rod_energy
        assert abs(lhs - rhs) < 1e-10 * max(lhs, 1.0)
        assert imp.energy_after <= imp.energy_after_field * (1 + 1e-12) + 1e-15  # Bessel
        if load is NO_DRIVE and imp.separations == 0:
            assert imp.energy_after == pytest.approx(imp.energy_after_field, rel=1e-12)
            assert imp.rod_energy == pytest.approx((1 - R**2) * imp.energy_before, rel=1e-12)


def test_energy_balance_inside_the_window(rng):
    s, R, N = 12.0, 0.5, 6
    model = BarModel(s=s, d=0.0, R=R, n_modes=N)
    load = SquareWaveLoad(40.0, 1.5)
    for amplitude in (0.05, 3.0):
        q, v = random_state(rng, model, amplitude)
        imp = wave_impact(model, load, 2 * math.pi - 0.07, q, v)
        for t in np.linspace(0, 2 / s, 7):
            work, rod, field = imp.account(t)
            assert abs(imp.energy_before + work - field - rod) < 1e-10 * imp.energy_before
            qt, vt = imp.state_at(t)
            e = 0.5 * vt[0] ** 2 + np.sum(vt[1:] ** 2 + (s * np.pi * np.arange(1, N + 1) * qt[1:]) ** 2)
            assert e <= field * (1 + 1e-12)  # the projection never adds energy
        assert imp.account(2 / s) == pytest.approx((imp.drive_work, imp.rod_energy,
                                                   imp.energy_after_field), rel=1e-13)


# ---------------------------------------------------------------- drive part and its derivative ---
@pytest.mark.parametrize("load", [CosineLoad(0.4, 1.0, k=2), SquareWaveLoad(1.0, 1.5)])
def test_window_drive_derivative(load):
    s, R, N = 3.0, 0.5, 5
    for t0 in (0.2, 2 * math.pi - 0.3):
        g, h, dg, dh = window_drive(s, R, N, load, t0, derivative=True)
        eps = 1e-6
        gp, hp = window_drive(s, R, N, load, t0 + eps)
        gm, hm = window_drive(s, R, N, load, t0 - eps)
        np.testing.assert_allclose(dg, (gp - gm) / (2 * eps), rtol=0, atol=1e-7)
        np.testing.assert_allclose(dh, (hp - hm) / (2 * eps), rtol=0, atol=1e-7)


def test_constant_drive_on_uniform_piston():
    """A constant drive ``P`` adds to the rigid velocity ``(1 - R) P T / 2`` (the impulse of the
    half window that reaches the rod, exactly: ``h_0 = P (1 - R)/s``)."""
    s, R, P = 8.0, 0.25, 3.0
    g, h = window_drive(s, R, 0, CosineLoad(P, 0.0), 1.0)
    assert h[0] == pytest.approx(P * (1 - R) / s, rel=1e-14)


# ---------------------------------------------------------------- bad input ------------------------
def test_bad_input():
    model = BarModel(s=5.0, d=0.0, R=0.5, n_modes=2)
    with pytest.raises(ValueError, match="shape"):
        wave_impact(model, NO_DRIVE, 0.0, np.zeros(2), np.zeros(3))
    with pytest.raises(ValueError, match="towards the rod"):
        wave_impact(model, NO_DRIVE, 0.0, np.zeros(3), np.array([-1.0, 0.0, 0.0]))
    with pytest.raises(ValueError, match="finite"):
        wave_impact(model, NO_DRIVE, 0.0, np.zeros(3), np.array([np.nan, 0.0, 0.0]))


@pytest.mark.parametrize("load", [CosineLoad(0.4, 1.3, 3), SquareWaveLoad(1.5, 1.3)])
def test_window_load_integral_against_the_load_flow(load):
    """The drive's integral over the window (closed form, piece by piece) against the load's own
    exact rigid-mode flow ``q'' = p``."""
    from impactbar.laws.wave.impact import _WindowLoad

    for s, t0 in ((0.3, 5.0), (7.0, 2 * math.pi - 0.1), (7.0, 1.0)):
        th = np.linspace(0, 2, 13)
        _, v = load.propagate(np.zeros(1), 0.0, t0, np.zeros(1), np.zeros(1), t0 + th / s)
        np.testing.assert_allclose(_WindowLoad(load, s, t0).integral(th), s * v[0], rtol=0, atol=1e-13)


# ---------------------------------------------------------------- external reference: elwaspatid --
@pytest.mark.slow
def test_against_elwaspatid(rng):
    """elwaspatid (Bacon's method for 1-D rods, an independent characteristics code) on a
    non-uniform piston: a piston of unit impedance with the velocity and strain fields of a random
    modal state strikes a rod of area ``(1 + R)/(1 - R)`` with an anechoic far end. Its interface
    force and its final piston velocity agree with the characteristics solution at its nodes.
    (Needs ``pip install elwaspatid``; units with ``E = rho = L = A = 1`` and ``s = 1``.)"""
    E = pytest.importorskip("elwaspatid.elwaspatid")
    R, N, J = 0.4, 5, 200
    model = BarModel(s=1.0, d=0.0, R=R, n_modes=N)
    q, v = random_state(rng, model, 0.05)
    imp = wave_impact(model, NO_DRIVE, 0.0, q, v)
    assert imp.separations == 0
    area_rod = (1 + R) / (1 - R)
    bar = E.BarSet([1.0, 1.0], [1.0, 1.0], [1.0, 3.0],
                   [math.sqrt(4 / math.pi), math.sqrt(4 * area_rod / math.pi)], nmin=J,
                   right="infinite")
    piston = bar.seg[0]
    x = piston.x - piston.x[0]
    n = np.arange(N + 1)
    vel0 = np.cos(np.pi * np.outer(x, n)) @ (v * np.where(n == 0, 1.0, 2.0))
    strain0 = -np.sin(np.pi * np.outer(x, n)) @ (2 * np.pi * n * q)
    original = E.Segment.initCalc

    def init(self, nT, Vo=0):  # the piston's initial fields (elwaspatid's force: E A u_x)
        original(self, nT, Vo)
        if self is piston:
            self.Veloc[0, :] = vel0
            self.Force[0, :] = strain0

    E.Segment.initCalc = init
    try:
        wp = E.WP2(bar, incw=np.zeros(0), nstep=2 * J + 1, left="free", contactLoss=None)
    finally:
        E.Segment.initCalc = original
    F = -piston.Force[:, -1]  # compression positive
    np.testing.assert_allclose(F[1:], imp.force(np.minimum(wp.time[1:], 2.0)), rtol=0, atol=1e-12)
    vel, _ = imp.fields(x)
    np.testing.assert_allclose(piston.Veloc[2 * J, 1:-1], vel[1:-1], rtol=0, atol=1e-12)


@pytest.mark.parametrize("load", [SquareWaveLoad(0.2, 1.3), CosineLoad(0.1, 2.0, 2)],
                         ids=["square", "cosine"])
def test_scalar_root_search_matches_the_array_forms(load):
    """The contact solver's scalar evaluations in its root searches (``A1``, ``Acum1``) against its
    array forms, on random states that separate and re-contact: same contact intervals and
    post-window states to 1e-12, on the search points and at random points."""
    from impactbar.laws.wave.impact import _Contact

    rng = np.random.default_rng(7)
    separated = 0
    for _ in range(40):
        N = int(rng.integers(0, 10))
        s, R = float(rng.uniform(2.0, 60.0)), float(rng.uniform(0.0, 0.9))
        q = rng.normal(size=N + 1) * rng.uniform(0.0, 1.0) / (1.0 + np.arange(N + 1)) ** 2 / s
        v = rng.normal(size=N + 1) * 0.3 / (1.0 + np.arange(N + 1))
        c = BarModel(s=s, d=0.0, R=R, n_modes=N).end_weights
        q[0] -= c @ q
        if c @ v < 0.0:
            v[0] -= 2.0 * (c @ v)
        t0 = float(rng.uniform(0.0, 2.0 * math.pi))
        out = []
        for fast in (True, False):
            sol = _Contact(s, R, q, v, load, t0, fast=fast).solve()
            qa, va = sol.post_state(q, v, window_drive(s, R, N, load, t0))
            out.append((sol, qa, va))
        (f, qf, vf), (g, qg, vg) = out
        assert f.contact.shape == g.contact.shape
        np.testing.assert_allclose(f.contact, g.contact, rtol=0, atol=1e-12)
        assert f.gap_theta == pytest.approx(g.gap_theta, abs=1e-12)
        scale = 1.0 + np.max(np.abs(np.concatenate((qg, vg))))
        np.testing.assert_allclose(np.concatenate((qf, vf)), np.concatenate((qg, vg)), rtol=0,
                                   atol=1e-12 * scale)
        separated += len(f.contact) != 1 or f.contact[0, 1] < 2.0
        th = np.concatenate((rng.uniform(0.0, 2.0, 8), [0.0, 1.0, 2.0], 1.0 + f.p.jumps[f.p.jumps < 1.0]))
        for x in th:
            for left in (False, True):
                assert f.A1(x, left) == pytest.approx(float(g.A(np.array([x]), left=left)[0]),
                                                      rel=1e-12, abs=1e-12 * f.scale)
            assert f.Acum1(x) == pytest.approx(float(g.Acum(x)[0]), rel=1e-12, abs=1e-12 * f.scale)
    assert separated >= 10  # the searches were exercised


def test_held_window_is_the_solvers():
    """``wave.held_window``: a window the tabulated scan calls held throughout is one the
    characteristics solver holds throughout, with the same bits (contact, gap, post-window state,
    and the integrals its solver, built when asked, gives), over random arrivals from near grazing
    to fast ones under smooth and square-wave drives; and the fast path does take windows (its
    solver is not built until asked) and leaves the separating ones to the solver."""
    from impactbar.dynamics.implementations import use_reference

    rng = np.random.default_rng(20)
    loads = [CosineLoad(0.3, 1.0), CosineLoad(0.1, 2.0, 2), SquareWaveLoad(0.2, 1.3)]
    held = separated = 0
    for i in range(120):
        N = int(rng.integers(0, 40))
        model = BarModel(s=float(rng.uniform(2.0, 60.0)), d=0.0, R=float(rng.uniform(0.0, 0.9)), n_modes=N)
        q, v = random_state(rng, model, float(rng.uniform(0.0, 0.3 if i % 2 else 3.0)))
        speed = float(10.0 ** rng.uniform(-3.0, 1.5))  # arrival speed: near grazing to fast
        q, v = speed * q, speed * v
        load, t0 = loads[i % 3], float(rng.uniform(0.0, 2.0 * math.pi))
        fast = wave_impact(model, load, t0, q, v)
        lazy = "_solver" not in fast.__dict__
        with use_reference("wave.held_window"):
            ref = wave_impact(model, load, t0, q, v)
        assert "_solver" in ref.__dict__
        for name in ("contact", "q_after", "v_after"):
            assert np.array_equal(getattr(fast, name), getattr(ref, name)), name
        assert fast.gap == ref.gap and fast.separations == ref.separations
        if lazy:
            held += 1
            assert fast.separations == 0 and fast.gap == 0.0
            for name in ("impulse", "rod_energy", "drive_work", "energy_before", "peak_force"):
                assert getattr(fast, name) == getattr(ref, name), name
        separated += ref.separations > 0
    assert held >= 20 and separated >= 10, (held, separated)


# ------------------------------------------------------------------ quadrature panels and states ---
def test_the_panels_equal_the_panel_by_panel_rule(rng):
    """The quadrature's panels, built in one array operation, are those of the rule written panel by
    panel (Gauss-Legendre, 20 nodes, each piece between breaks cut into equal panels no wider than
    ``h``), to the bit."""
    from impactbar.laws.wave._characteristics import _panels

    gx, gw = np.polynomial.legendre.leggauss(20)

    def by_panel(lo, hi, breaks, h):
        pts = np.unique([lo, hi] + [b for b in breaks if lo < b < hi])
        xs, ws = [np.empty(0)], [np.empty(0)]
        for a, b in zip(pts[:-1], pts[1:], strict=True):
            m = max(1, math.ceil((b - a) / h))
            half = 0.5 * (b - a) / m
            for k in range(m):
                mid = a + half * (2.0 * k + 1.0)
                xs.append(mid + half * gx)
                ws.append(half * gw)
        return np.concatenate(xs), np.concatenate(ws)

    for _ in range(200):
        lo, hi = np.sort(rng.uniform(-2.0, 3.0, 2))
        breaks = list(rng.uniform(-3.0, 4.0, rng.integers(0, 60))) + [lo, hi, 0.5, 0.5]
        h = 10.0 ** rng.uniform(-2.0, 0.5)
        x, w = _panels(lo, hi, breaks, h)
        xr, wr = by_panel(lo, hi, breaks, h)
        assert x.size > 0 and np.array_equal(x, xr) and np.array_equal(w, wr)
    x, w = _panels(0.5, 0.5, [0.2], 0.1)
    assert x.size == 0 and w.size == 0


def test_the_states_sampled_through_a_window_equal_a_fresh_projection(rng):
    """A window asked for its state again reads it from the fields' moments tabulated along the
    characteristics: at every time, the switches and the drive's jumps included, it is the first
    call's projection of a fresh window (the fields' quadrature at that time) to 1e-13 of the
    state's scale; and a copy of the window with other fields (``smoothed``) tabulates its own."""
    s, R, N = 12.0, 0.5, 6
    model = BarModel(s=s, d=0.0, R=R, n_modes=N)
    load = SquareWaveLoad(40.0, 1.5)
    t0 = 2 * math.pi - 0.07
    q, v = random_state(rng, model, 3.0)
    imp = wave_impact(model, load, t0, q, v)
    assert imp.separations > 0 and imp._solver.p.jumps.size > 0
    sol = imp._solver
    special = np.concatenate((sol.switches(), sol.p.jumps, 1.0 + sol.p.jumps[sol.p.jumps < 1.0]))
    th = np.unique(np.concatenate((np.linspace(0.0, 2.0, 23), special)))
    sampled = [imp.state_at(x / s) for x in th]
    assert "_line_moments" in sol.__dict__  # the later calls read the tables
    for x, (qs, vs) in zip(th, sampled, strict=True):
        qf, vf = wave_impact(model, load, t0, q, v).state_at(x / s)  # a fresh window's first call
        scale = np.max(np.abs(np.concatenate((qf * s * np.pi * np.arange(N + 1), vf))))
        assert np.max(np.abs(vs - vf)) < 1e-13 * scale
        assert np.max(np.abs(qs[1:] - qf[1:])) * s * np.pi < 1e-13 * scale
        assert abs(qs[0] - qf[0]) < 1e-13 * max(abs(qf[0]), 1.0 / s)
    smooth = sol.smoothed()
    smooth.state_at(0.3)
    for x in (0.7, 1.4):
        np.testing.assert_allclose(np.concatenate(smooth.state_at(x)),
                                   np.concatenate(smooth._state_by_panels(x)), rtol=0, atol=1e-13 * scale)
    assert np.max(np.abs(smooth.state_at(1.4)[1] - sol.state_at(1.4)[1])) > 1e-6 * scale
