"""The blow of a stepped piston under the rod-rock law (theory §12), on the lattice and by
the exact solver: the uniform piston as one segment to the bit, and a two-segment piston on a long
rod of its head's impedance against the characteristics' closed form (the staircase ``Z_h V/2``,
then ``(1 + R) R^k`` of it, the transmitted and reflected steps at the neck), with the energy
conserved; the exact blow against the bit's equation integrated by scipy under that staircase, the
uniform piston cut into segments of one impedance, and its own momentum balance."""

import math

import numpy as np
import pytest

import impactbar as ib
from impactbar import SteppedPiston


def _model(segments, k=2.5, k_u=25.0, s=2.0, bit_mass=0.0, feed=0.0):
    law = ib.RodRock(segments=[ib.RodSegment(*g) for g in segments], rock=ib.BilinearRock(k=k, k_u=k_u),
                     bit_mass=bit_mass, feed=feed)
    return ib.BarModel(s=s, d=0.0, R=0.0, n_modes=0, impact=law)


#: a stepped rod, a bit with mass, a feed, an incommensurate grid (210 cells per piston): the numbers
#: of main before the piston could be stepped (commit b8549c5), to the bit
_MAIN = dict(efficiency=0.7257595769003089, rebound_velocity=-0.3592861267873046,
             permanent_penetration=0.4948635376842481, piston_energy=0.08489169942726464)


@pytest.mark.parametrize("piston", [None, SteppedPiston([2.5], [7.0])], ids=["none", "one-segment"])
def test_uniform_piston_unchanged_to_the_bit(piston):
    model = _model([(0.7, 1.3), (3.1, 0.8, 1.05)], k=3.0, k_u=20.0, bit_mass=0.05, feed=0.1)
    b = ib.single_blow(model, 1.1, piston=piston)
    for name, value in _MAIN.items():
        assert getattr(b, name) == value, name
    assert b.piston_cells == 210 and b.times.size == 19541
    # fsum: correctly rounded, so the checksum does not depend on numpy's summation order
    assert math.fsum(b.shank_forces) == 612.900173250668
    ref = ib.single_blow(model, 1.1)
    for name in ("shank_forces", "junction_forces", "bit_forces", "penetrations"):
        assert np.array_equal(getattr(b, name), getattr(ref, name))


def _head_rod_blow(lengths, impedances, s=2.0, V=1.3, t_max=3.0, record_field=False, method="lattice"):
    """The piston (tail first, head at the struck end) on a rod of its head's impedance, so long
    that nothing returns from the rock within ``t_max``."""
    piston = SteppedPiston(lengths, impedances)
    mu = piston.mass_per_length
    model = _model([(40.0, float(mu[-1]))], s=s)
    blow = ib.single_blow(model, V, t_max=t_max, piston=piston, record_field=record_field, method=method)
    return piston, blow


def _closed_form(piston, s, V, t):
    """The shank's force of a two-segment piston on a rod of its head's impedance: the head's relief
    wave ``Z_h V/2`` enters the rod whole; at the neck it is reflected with ``R = (Z_t - Z_h)/(Z_t +
    Z_h)`` and transmitted with ``1 + R``; the tail's wave returns from the free driven end with
    the sign changed, through the neck (``1 - R``) into the head and the rod, and again into the tail
    (``-R``): ``N = Z_h V/2`` for ``t < 2 l_h/s``, then ``Z_h V/2 (1 + R) R^k`` for
    ``2 l_h/s + 2 k l_t/s <= t < 2 l_h/s + 2 (k + 1) l_t/s`` while it presses; 0 once separated."""
    (l_t, l_h), (mu_t, mu_h) = piston.lengths, piston.mass_per_length
    Zt, Zh = s * mu_t, s * mu_h
    R = (Zt - Zh) / (Zt + Zh)
    dN = 0.5 * Zh * V
    k = np.floor((t - 2 * l_h / s) / (2 * l_t / s))
    n = np.where(t < 2 * l_h / s, dN, dN * (1 + R) * R ** np.maximum(k, 0))
    first_pull = np.flatnonzero(n < 0)
    if first_pull.size:
        n[first_pull[0]:] = 0.0
    return n


@pytest.mark.parametrize("method", ["lattice", "exact"])
@pytest.mark.parametrize("lengths, impedances", [([0.75, 0.25], [1.0, 2.0]),  # light tail: R = -1/3
                                                 ([0.5, 0.5], [3.0, 1.0]),  # heavy tail: R = 1/2
                                                 ([0.375, 0.625], [1.0, 1.5])])  # R = -1/5
def test_two_segment_staircase_against_the_closed_form(lengths, impedances, method):
    s, V = 2.0, 1.3
    piston, blow = _head_rod_blow(lengths, impedances, s=s, V=V, method=method)
    assert blow.length_error == 0.0 and blow.method == method
    t_mid = blow.times[:-1] + 0.5 * blow.cell_time
    expect = _closed_form(piston, s, V, t_mid)
    scale = 0.5 * s * piston.mass_per_length[-1] * V
    np.testing.assert_allclose(blow.shank_forces, expect, rtol=0, atol=4e-15 * scale)
    # the energy: the rod's waves carry int N^2/Z_h dt, the piston keeps the rest, to rounding
    # (the steps fall on the samples: the sums are the integrals)
    Zh = s * piston.mass_per_length[-1]
    into_rod = float(np.sum(expect ** 2)) * blow.cell_time / Zh
    assert blow.energy_error < 1e-14
    if method == "lattice":
        rod_waves = float(np.sum(blow.rod_waves[0] ** 2 + blow.rod_waves[1] ** 2)) * blow.cell_time / Zh
    else:  # (the rod's energy: its waves, nothing having reached the rock's far end)
        rod_waves = blow.rod_energy + blow.work_on_rock
    assert rod_waves == pytest.approx(into_rod, rel=1e-13)
    assert blow.piston_energy == pytest.approx(0.5 * V * V - into_rod, abs=1e-14)
    # the momentum: the piston's mean velocity is V less the shank's impulse (its mass 1)
    impulse = float(np.sum(expect)) * blow.cell_time
    assert blow.rebound_velocity == pytest.approx(V - impulse, abs=1e-14)


def test_transmitted_and_reflected_steps_at_the_neck():
    """Inside the piston (the recorded field, cells 0..7 from the driven end; the neck between
    cells 5 and 6): the tail carries the transmitted ``(1 + R) Z_h V/2`` once the relief wave has
    passed and before the free end's reflection returns; the head ``Z_h V/2`` before the neck's
    reflection reaches it, ``(1 + R) Z_h V/2`` after."""
    s, V = 2.0, 1.3
    piston, blow = _head_rod_blow([0.75, 0.25], [1.0, 2.0], s=s, V=V, t_max=1.0, record_field=True)
    assert blow.method == "lattice" and blow.piston_cells == 8 and blow.cell_time == 1 / 16
    Zt, Zh = s * piston.mass_per_length
    R = (Zt - Zh) / (Zt + Zh)
    dN = 0.5 * Zh * V
    f = blow.field
    # the relief front reaches cell j (distance (7 - j)/8 .. (8 - j)/8 from the shank) after 8 - j
    # steps; the free end's reflection is back at tail cell 2 after 8 + 3 steps
    np.testing.assert_allclose(f[6:11, 2], (1 + R) * dN, rtol=1e-15)
    assert np.all(f[:6, 2] == 0.0)
    # head cell 6: relieved after 2 steps, the neck's reflection there after 3, the tail's after 14
    assert f[2, 6] == pytest.approx(dN, rel=1e-15)
    np.testing.assert_allclose(f[3:14, 6], (1 + R) * dN, rtol=1e-15)


def test_the_exact_neck_steps_and_the_sampled_field():
    """The exact blow's force at the neck (its junction 1): nothing until the relief front arrives
    at ``l_h/s``, then the transmitted ``(1 + R) Z_h V/2`` until the free end's reflection returns
    ``2 l_t/s`` later; the sampled field's cells shared out by the segments' lengths."""
    s, V = 2.0, 1.3
    piston, blow = _head_rod_blow([0.75, 0.25], [1.0, 2.0], s=s, V=V, t_max=1.0, record_field=True,
                                  method="exact")
    Zt, Zh = s * piston.mass_per_length
    R = (Zt - Zh) / (Zt + Zh)
    dN = 0.5 * Zh * V
    t = np.linspace(0.0, 1.0, 401)[1:-1]
    neck = blow.exact.junction_force(1, t)
    arrive, back = 0.25 / s, 0.25 / s + 2 * 0.75 / s
    inside = (t > arrive + 1e-9) & (t < back - 1e-9)
    np.testing.assert_allclose(neck[inside], (1 + R) * dN, rtol=1e-14)
    assert np.all(neck[t < arrive - 1e-9] == 0.0)
    assert blow.piston_cells == 32 and blow.field.shape[1] == 32 + blow.segment_cells[0]
    np.testing.assert_allclose(blow.cell_edges[:33], np.linspace(-1.0, 0.0, 33), atol=1e-15)


def _bit_under_staircase(piston, s, V, k, k_u, Z_b, t_rod, t_end):
    """A massless bit on a semi-infinite rod of the head's impedance under the closed-form staircase
    (``_closed_form``) delayed by the rod's travel time: ``Z_b p' = 2 F - k p`` while loading,
    ``2 F - k_u (p - p_max) - k p_max`` once the bit turns back, by scipy's ``solve_ivp`` (DOP853,
    rtol 1e-13) between the staircase's steps, to ``t_end``. Returns what the rock dissipated,
    ``k (1 - k/k_u) p_max^2 / 2``, its elastic energy at ``t_end`` and ``p_max``."""
    from scipy.integrate import solve_ivp

    (l_t, l_h) = piston.lengths
    steps = [0.0, 2 * l_h / s] + [2 * l_h / s + 2 * j * l_t / s for j in range(1, 400)]
    steps = [t for t in steps if t + t_rod < t_end] + [t_end - t_rod]
    p, loading, p_max = 0.0, True, 0.0
    forces = _closed_form(piston, s, V, 0.5 * (np.array(steps[:-1]) + np.array(steps[1:])))
    for a, b, F in zip(steps[:-1], steps[1:], forces, strict=True):
        if loading and 2 * F <= k * p:  # the bit turns back at this step
            loading, p_max = False, p

        def rate(t, y, F=float(F), loading=loading, p_max=p_max):
            if loading:
                return [(2 * F - k * y[0]) / Z_b]
            return [(2 * F - max(k_u * (y[0] - p_max) + k * p_max, 0.0)) / Z_b]

        sol = solve_ivp(rate, (a + t_rod, b + t_rod), [p], method="DOP853", rtol=1e-13, atol=1e-16)
        p = float(sol.y[0, -1])
    force = max(k_u * (p - p_max) + k * p_max, 0.0)
    return 0.5 * k * (1.0 - k / k_u) * p_max ** 2, force ** 2 / (2 * k_u), p_max


@pytest.mark.parametrize("lengths, impedances", [([0.75, 0.25], [1.0, 2.0]), ([0.5, 0.5], [3.0, 1.0])])
def test_a_stepped_piston_on_a_semi_infinite_rod_against_the_bits_equation(lengths, impedances):
    """Lundberg's idealisation with a stepped piston: the rock meets the staircase wave once; the
    exact blow's largest penetration, the rock's dissipated work and its elastic energy at the
    blow's end against an independent integration."""
    s, V, k, k_u = 2.0, 1.3, 2.5, 25.0
    piston = SteppedPiston(lengths, impedances)
    Zh = s * float(piston.mass_per_length[-1])
    model = _model([(3.0, float(piston.mass_per_length[-1]))], k=k, k_u=k_u, s=s)
    blow = ib.single_blow(model, V, piston=piston, semi_infinite=True)
    assert blow.method == "exact" and blow.ended_by in ("separated", "spent") and blow.exact.recontacts == 0
    dissipated, stored, p_max = _bit_under_staircase(piston, s, V, k, k_u, Zh, 3.0 / s, blow.duration)
    assert blow.max_penetration == pytest.approx(p_max, rel=1e-11)
    assert blow.work_on_rock - blow.rock_stored_energy == pytest.approx(dissipated, rel=1e-11)
    assert blow.rock_stored_energy == pytest.approx(stored, rel=1e-8, abs=1e-13)
    assert blow.energy_error < 1e-13


def _stepped_rod(**kw):
    return _model([(0.75, 1.4), (2.25, 0.7)], k=2.0, k_u=12.0, **kw)


def test_the_uniform_piston_cut_into_segments_of_one_impedance_is_the_uniform_piston():
    """A stepped rod with the piston striking again: a cut where the impedance does not change
    (off the samples) reflects nothing, so every result is the uniform piston's."""
    model = _stepped_rod()
    uniform = ib.single_blow(model, 1.1)
    cut = ib.single_blow(model, 1.1, piston=SteppedPiston([0.3, 0.45, 0.25], [2.0, 2.0, 2.0]),
                         method="exact")
    assert uniform.method == cut.method == "exact" and cut.exact.recontacts == uniform.exact.recontacts >= 1
    for name in ("efficiency", "work_on_rock", "rebound_velocity", "piston_energy", "max_penetration",
                 "permanent_penetration"):
        assert getattr(cut, name) == pytest.approx(getattr(uniform, name), rel=1e-13, abs=1e-15), name
    np.testing.assert_allclose(cut.peak_forces()[0], uniform.peak_forces()[0], rtol=1e-13)
    np.testing.assert_allclose(cut.peak_forces()[1], uniform.peak_forces()[1], rtol=1e-13)


def test_the_exact_stepped_blow_balances_momentum_and_energy():
    """Three segments with re-contacts: the rebound velocity (from the waves' momenta) is the
    impact velocity less the shank's impulse (its force history integrated by Gauss-Legendre
    between its break points), and the energy account closes; the refined lattice (the piston's
    steps on its cells) agrees with the efficiency, and with the rebound within its error: the
    force at each re-contact times that contact's lag on the lattice's grid."""
    model = _stepped_rod()
    piston = SteppedPiston([0.25, 0.5, 0.25], [1.0, 2.0, 1.3])
    b = ib.single_blow(model, 1.0, piston=piston)
    assert b.method == "exact" and b.ended_by in ("separated", "lifted") and b.exact.recontacts == 2
    assert b.energy_error < 1e-13
    breaks = b.exact.junction_breaks(b.exact.contact_junction)
    x, w = np.polynomial.legendre.leggauss(20)
    impulse = sum(0.5 * (hi - lo) * float(w @ b.shank_force(0.5 * (lo + hi) + 0.5 * (hi - lo) * x))
                  for lo, hi in zip(breaks[:-1], breaks[1:], strict=True))
    assert b.rebound_velocity == pytest.approx(1.0 - impulse, abs=1e-14)
    lattice = ib.single_blow(model, 1.0, piston=piston, cells_per_piston=1024, t_max=b.duration)
    assert lattice.efficiency == pytest.approx(b.efficiency, rel=1e-13)
    lag = 2 * 1.0 / (2.0 * 1024)  # a contact starts at most one cell late on each of the two
    assert abs(lattice.rebound_velocity - b.rebound_velocity) <= float(np.max(b.shank_forces)) * lag


def test_piston_argument_checked():
    model = _model([(40.0, 1.0)])
    with pytest.raises(ValueError, match="piston must be a SteppedPiston"):
        ib.single_blow(model, 1.0, piston=[0.5, 0.5])


def test_rounded_piston_keeps_its_mass():
    """On a grid its steps do not fit (cells_per_piston=10 for a step at 0.33), the piston's
    segments are rounded to whole cells, the length error reported, the mass kept 1 (``V^2/2`` at
    impact) and the energy account closed."""
    model = _model([(3.0, 1.0)], bit_mass=0.1, feed=0.05)
    b = ib.single_blow(model, 1.0, piston=SteppedPiston([0.33, 0.67], [1.0, 2.0]), cells_per_piston=10)
    assert b.length_error == pytest.approx(abs(0.3 - 0.33) / 0.33, rel=1e-12)
    assert b.energy_at_impact == pytest.approx(0.5, rel=1e-15)
    assert b.energy_error < 1e-12


def test_auto_carries_a_stepped_piston_exactly_without_a_feed():
    """``method="auto"``: a stepped piston by the exact solver, as the uniform one; with a feed or a
    ``cells_per_piston``, the lattice."""
    piston = SteppedPiston([0.5, 0.5], [1.0, 2.0])
    assert ib.single_blow(_model([(3.0, 1.0)]), 1.0, piston=piston).method == "exact"
    assert ib.single_blow(_model([(3.0, 1.0)], feed=0.05), 1.0, piston=piston).method == "lattice"
    assert ib.single_blow(_model([(3.0, 1.0)]), 1.0, piston=piston, cells_per_piston=16).method == "lattice"
