"""The tangent-linear blow (theory §12, ``laws.rodrock.tangent``): its primal run is the lattice's
blow (``rod_rock_blow``) to rounding, and its derivatives of the work on the rock and of every
step's shank force along directions of the piston's cell impedances are central finite
differences of ``rod_rock_blow`` where the blow is smooth (two step sizes agreeing first), with a
massless bit and with a bit mass, with and without a feed, on a long rod and on a short stepped
rod whose waves come back (the piston leaving the shank and striking it again, the bit lifting off
the rock and landing on it again)."""

import numpy as np
import pytest

from impactbar import SteppedPiston
from impactbar.laws.rodrock.blow import blow_grid, rod_rock_blow
from impactbar.laws.rodrock.tangent import rod_rock_blow_tangent

LONG = ([20.0], [1.0], [1.0])
SHORT = ([0.75, 2.25], [1.4, 0.7], [1.0, 1.0])
CASES = {  # rod, k, k_u, bit mass, feed, t_max
    "massless, Lundberg's rock": (LONG, 0.6, 6e11, 0.0, 0.0, 44.0),
    "massless, feed": (LONG, 1.5, 6.0, 0.0, 0.1, 44.0),
    "bit mass, underdamped": (LONG, 6.0, 30.0, 0.3, 0.0, 44.0),
    "short stepped rod, massless": (SHORT, 2.0, 12.0, 0.0, 0.0, 12.0),
    "short stepped rod, bit mass and feed": (SHORT, 2.0, 12.0, 0.2, 0.05, 12.0),
}


def _design(n_p, rng):
    """Cell impedances of mean 1 (the piston's mass 1) and three directions that keep the mass."""
    Z = np.exp(0.3 * rng.standard_normal(n_p))
    D = rng.standard_normal((n_p, 3))
    return Z / Z.mean(), D - D.mean(axis=0)


def _blow(case, Z):
    rod, k, k_u, m, f, T = CASES[case]
    return rod_rock_blow(1.0, 1.0, *rod, k, k_u, m, f, cells_per_piston=Z.size, t_max=T,
                         piston=SteppedPiston(np.ones(Z.size), Z))


def _central(case, Z, d, h):
    up, down = _blow(case, Z + h * d), _blow(case, Z - h * d)
    n = min(up.shank_forces.size, down.shank_forces.size)
    return ((up.work_on_rock - down.work_on_rock) / (2 * h),
            (up.shank_forces[:n] - down.shank_forces[:n]) / (2 * h))


@pytest.mark.parametrize("case", list(CASES))
def test_the_tangent_is_the_lattices_derivative(case):
    """(A design of its own per case, drawn once: where a switch of the schedule lies within the
    differences' step of a design, the two differences disagree and the test says so.)"""
    rod, k, k_u, m, f, T = CASES[case]
    Z, D = _design(16, np.random.default_rng(sum(map(ord, case))))
    cells = blow_grid(1.0, *rod, 16, SteppedPiston(np.ones(16), Z)).Z[:16]  # rod_rock_blow's cells
    tb = rod_rock_blow_tangent(1.0, 1.0, *rod, k, k_u, m, f, cells, D, t_max=T)
    blow = _blow(case, Z)
    # the primal run: the lattice's blow to rounding (the rod's uniform segments delay lines)
    assert tb.work_on_rock == pytest.approx(blow.work_on_rock, rel=1e-13)
    np.testing.assert_allclose(tb.shank_forces, blow.shank_forces, rtol=0, atol=1e-13)
    assert tb.energy_at_impact == pytest.approx(blow.energy_at_impact, rel=1e-14)
    assert np.abs(tb.energy_tangent).max() < 1e-14  # the directions keep the mass
    assert tb.ended_by == blow.ended_by
    # central differences at h and h/2, and Richardson's extrapolation of the two (O(h^4))
    (w1, s1), (w2, s2) = (zip(*[_central(case, Z, d, h) for d in D.T], strict=True) for h in (1e-5, 5e-6))
    w1, w2 = np.array(w1), np.array(w2)
    w = (4 * w2 - w1) / 3
    scale = np.abs(w).max()
    assert np.abs(w1 - w2).max() < 1e-7 * scale  # smooth here: the two differences agree
    assert np.abs(tb.work_tangent - w).max() < 1e-7 * scale
    for a in range(D.shape[1]):
        n = min(s1[a].size, s2[a].size, tb.shank_forces.size)
        s = (4 * s2[a][:n] - s1[a][:n]) / 3
        scale = np.abs(s).max()
        assert np.abs(s1[a][:n] - s2[a][:n]).max() < 1e-6 * scale
        assert np.abs(tb.shank_tangents[:n, a] - s).max() < 1e-7 * scale


def test_the_cases_cross_the_schedules_switches():
    """The cases are not all smooth-sailing: the piston leaves the shank and strikes it again, and
    the bit lifts off the rock and lands on it again, in the short rod's; the bit with mass
    oscillates on its branches (unloading, then loading again)."""
    Z, _ = _design(16, np.random.default_rng(3))
    short = _blow("short stepped rod, massless", Z)
    contact = short.shank_forces > 0.0
    assert np.any(contact[:-1] & ~contact[1:]) and np.sum(~contact[:-1] & contact[1:]) >= 1
    lifted = short.bit_forces == 0.0
    assert np.any(lifted[1:] & ~lifted[:-1]) and np.any(~lifted[1:] & lifted[:-1])
    ringing = _blow("bit mass, underdamped", Z)
    p = ringing.penetrations
    assert np.any(np.diff(np.sign(np.diff(p[p.size // 8:])))) != 0


@pytest.mark.parametrize("kwargs, match", [
    (dict(piston_impedances=[]), "piston_impedances"),
    (dict(piston_impedances=[1.0, -1.0]), "piston_impedances"),
    (dict(piston_impedances=[1.0, np.nan]), "piston_impedances"),
    (dict(directions=np.ones((3, 1))), "directions"),
    (dict(directions=[1.0, np.inf]), "directions"),
    (dict(V=0.0), "V"),
    (dict(t_max=-1.0), "t_max"),
    (dict(energy_fraction=-1e-9), "energy_fraction"),
])
def test_arguments_checked(kwargs, match):
    args = dict(s=1.0, V=1.0, lengths=[20.0], impedances=[1.0], speeds=[1.0], k=0.6, k_u=6.0,
                bit_mass=0.0, feed=0.0, piston_impedances=[1.0, 1.0], directions=[1.0, -1.0], t_max=4.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        rod_rock_blow_tangent(**args)


BIT_CASES = {  # bp = (Z, k, k_u, m, feed), bs = (p, w, branch, p_max, R_max, p_perm, work), E, dt, end
    "massless: loading on": ((1.0, 2.0, 12.0, 0.0, 0.0), (0.3, 0.0, 0, 0.3, 0.6, 0.25, 0.1), 1.0, 0.1, 0),
    "massless: unloading": ((1.0, 2.0, 12.0, 0.0, 0.0), (0.3, 0.0, 0, 0.3, 0.6, 0.25, 0.1), 0.4, 0.1, 1),
    "massless: lift-off": ((1.0, 2.0, 12.0, 0.0, 0.0), (0.27, 0.0, 1, 0.3, 0.6, 0.25, 0.1), -0.5, 0.1, 2),
    "massless: reloading": ((1.0, 2.0, 12.0, 0.0, 0.0), (0.28, 0.0, 1, 0.3, 0.6, 0.25, 0.1), 1.0, 0.1, 0),
    "massless: landing": ((1.0, 2.0, 12.0, 0.0, 0.0), (0.24, 0.5, 2, 0.3, 0.6, 0.25, 0.1), 0.5, 0.1, 1),
    "mass: unloading": ((1.0, 6.0, 30.0, 0.2, 0.0), (0.1, 0.5, 0, 0.1, 0.6, 0.08, 0.1), 0.2, 0.2, 1),
    "mass: lift-off": ((1.0, 6.0, 30.0, 0.2, 0.0), (0.27, -1.0, 1, 0.3, 1.8, 0.24, 0.1), -0.5, 0.1, 2),
    "mass: landing": ((1.0, 6.0, 30.0, 0.2, 0.0), (0.23, 0.5, 2, 0.3, 1.8, 0.24, 0.1), 0.5, 0.1, 1),
    "mass: reloading": ((1.0, 6.0, 30.0, 0.2, 0.0), (0.29, 0.5, 1, 0.3, 1.8, 0.24, 0.1), 2.0, 0.1, 0),
    "mass: unloading, overdamped": ((1.0, 0.5, 30.0, 0.2, 0.0), (0.1, 0.5, 0, 0.1, 0.05, 0.098, 0.1), 0.0,
                                    0.6, 2),
}
ROWS = (0, 1, 3, 4, 5, 6)  # the bit's state that moves: p, w, p_max, R_max, p_perm, work


@pytest.mark.parametrize("case", list(BIT_CASES))
def test_the_bits_step_tangent_is_its_derivative(case):
    """One step of the bit on the rock (``bit_step``, compiled) across each switch of the bilinear
    law inside the step: its tangent against central differences in every state variable and in
    the input ``E`` (underdamped and overdamped bits, and every branch's closed form)."""
    import numba

    from impactbar.laws.rodrock import _rockloop, _rocktangent

    # (both are link-only, compiled into the loops that call them: called here through kernels)
    bit_step = numba.njit(lambda bs, bp, e, dt: _rockloop.bit_step(bs, bp, e, dt))
    bit_step_tangent = numba.njit(lambda bs, bp, dbs, e, de, dt, scratch, J: _rocktangent.bit_step_tangent(
        bs, bp, dbs, e, de, dt, scratch, J))
    bp, bs0, E, dt, end = BIT_CASES[case]
    bp, bs0 = np.array(bp), np.array(bs0, dtype=float)

    def step(bs, e):
        bs = bs.copy()
        bit_step(bs, bp, e, dt)
        return bs

    assert step(bs0, E)[2] == end and (end != bs0[2]) == ("on" not in case)  # the switch is crossed
    nv = len(ROWS) + 1
    bs, dbs, dE = bs0.copy(), np.zeros((7, nv)), np.zeros(nv)
    for a, r in enumerate(ROWS):
        dbs[r, a] = 1.0
    dE[-1] = 1.0
    bit_step_tangent(bs, bp, dbs, E, dE, dt, np.zeros((5, nv)), np.zeros((2, 4)))
    np.testing.assert_array_equal(bs, step(bs0, E))  # the primal step, number for number
    h = 1e-6
    for a in range(nv):
        d = np.zeros(7)
        if a < len(ROWS):
            d[ROWS[a]] = 1.0
        up, down = step(bs0 + h * d, E + h * dE[a]), step(bs0 - h * d, E - h * dE[a])
        fd = (up - down)[list(ROWS)] / (2 * h)
        np.testing.assert_allclose(dbs[list(ROWS), a], fd, rtol=1e-6, atol=1e-7)
