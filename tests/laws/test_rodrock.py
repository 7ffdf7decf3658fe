"""The rod-and-rock law (theory §4d): single blows against Lundberg's closed forms, against
elwaspatid's characteristics on stepped rods, the semi-infinite rod's limit, the energy account."""

import contextlib
import io
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import impactbar as ib
from impactbar.laws.rodrock import lundberg_efficiency


def _model(segments, k, k_u, s=2.0, bit_mass=0.0, feed=0.0):
    law = ib.RodRock(segments=[ib.RodSegment(length=l, impedance=z) for l, z in segments],
                     rock=ib.BilinearRock(k=k, k_u=k_u), bit_mass=bit_mass, feed=feed)
    return ib.BarModel(s=s, d=0.0, R=0.0, n_modes=0, impact=law)


def _long_rod_blow(alpha, gamma, s=2.0, V=1.0, bit_mass=0.0, cells=None):
    """Equal impedances, a rod so long that its far end's reflection never returns in the blow."""
    k = alpha * s * s / 2.0
    model = _model([(60.0, 1.0)], k, gamma * k, s=s, bit_mass=bit_mass)
    assert model.law.alpha(model) == pytest.approx(alpha, rel=1e-15)
    return model, ib.single_blow(model, V, t_max=0.99 * 2 * 60.0 / s, cells_per_piston=cells)


@pytest.mark.parametrize("alpha", [0.3, 1.2564312, 4.0])
@pytest.mark.parametrize("gamma", [1.5, 10.0, 1e3])
def test_lundberg_efficiency_and_permanent_penetration(alpha, gamma):
    """Lundberg's rectangular wave on a massless bit: ``eta = (2/alpha)(1 - e^-alpha)^2 (1 - 1/gamma)``
    and the permanent penetration ``p = (2 F/k)(1 - e^-alpha)(1 - 1/gamma)`` with the incident force
    ``F = s V/2`` (the force at the end of the pulse is ``R_max = 2 F (1 - e^-alpha)``, unloading
    along ``k_u`` leaves ``R_max (1/k - 1/k_u)``), to 1e-10."""
    s, V = 2.0, 1.3
    model, blow = _long_rod_blow(alpha, gamma, s=s, V=V)
    k = model.law.rock.k
    assert abs(blow.efficiency - lundberg_efficiency(alpha, gamma)) < 1e-10
    r_max = s * V * (-math.expm1(-alpha))
    assert blow.max_penetration == pytest.approx(r_max / k, rel=1e-12)
    assert abs(blow.permanent_penetration - r_max * (1 / k - 1 / (gamma * k))) < 1e-10 * r_max / k
    assert blow.energy_error < 1e-12


def test_lundberg_maximum():
    """The closed form's maximum over alpha (gamma -> inf) is 0.8145288 at alpha = 1.2564312: the
    root of ``d eta/d alpha = 0``, i.e. ``2 alpha e^-alpha = 1 - e^-alpha``; and the solver reaches it
    for a large gamma."""
    from scipy.optimize import brentq

    a = brentq(lambda x: 2 * x * math.exp(-x) - (1 - math.exp(-x)), 0.5, 3.0, xtol=1e-15)
    assert abs(a - 1.2564312) < 1e-7
    assert abs(lundberg_efficiency(a, math.inf) - 0.8145288) < 1e-7
    _, blow = _long_rod_blow(a, 1e12)
    assert abs(blow.efficiency - 0.8145288) < 1e-7


def test_small_bit_mass_recovers_the_massless_bit():
    """A bit mass tending to 0 tends to the massless bit's efficiency (linearly in the mass)."""
    alpha, gamma = 1.2, 4.0
    _, ref = _long_rod_blow(alpha, gamma, cells=64)
    errs = []
    for m in (1e-2, 1e-3):
        _, blow = _long_rod_blow(alpha, gamma, bit_mass=m, cells=64)
        assert blow.energy_error < 1e-10
        errs.append(abs(blow.efficiency - ref.efficiency))
    assert errs[1] < 0.2 * errs[0] and errs[1] < 1e-3


@pytest.mark.parametrize("m", [1e-6, 1e-9])
def test_a_very_light_bit_stays_finite(m):
    """A bit so light that its time constant ``m/Z`` is far below the cell step (a stiff bit: the
    exponentials of its motion under- and overflow apart) still gives the massless bit's blow,
    within ``O(m)`` (a continuation in ``bit_mass`` from 0 steps to such masses), compiled and in the
    reference loop alike."""
    from impactbar.dynamics.implementations import use_reference

    alpha, gamma = 1.2, 4.0
    _, ref = _long_rod_blow(alpha, gamma, cells=64)
    _, blow = _long_rod_blow(alpha, gamma, bit_mass=m, cells=64)
    assert blow.energy_error < 1e-10
    assert abs(blow.efficiency - ref.efficiency) < 10 * m + 1e-7  # the events located to ~1e-8
    with use_reference("rock.blow"):
        _, slow = _long_rod_blow(alpha, gamma, bit_mass=m, cells=64)
    assert slow.work_on_rock == pytest.approx(blow.work_on_rock, rel=1e-10)


@pytest.mark.parametrize("ratio", [2.25, 1 / 2.25])
def test_striker_on_a_long_rod(ratio):
    """A striker of impedance 1 on a long rod of impedance ``z``: the force ``z/(1 + z) V s`` for
    ``2/s`` then 0 (z > 1; energy ratio ``4 z/(1 + z)^2``), or the staircase
    ``z/(1 + z) V s ((1 - z)/(1 + z))^n`` (z < 1; energy ratio 1)."""
    s, V = 1.0, 1.0
    model = _model([(50.0, ratio)], 1.0, 2.0, s=s)
    blow = ib.single_blow(model, V, t_max=0.99 * 2 * 50.0)
    t = np.arange(12) + 0.5  # mid-steps of 1/s... crossing times 1
    f0 = ratio / (1 + ratio) * s * V
    if ratio > 1:
        want = np.where(t < 2.0, f0, 0.0)
        assert blow.energy_into_rod / blow.energy_at_impact == pytest.approx(4 * ratio / (1 + ratio) ** 2,
                                                                             rel=1e-13)
        assert abs(blow.energy_into_rod / blow.energy_at_impact - 0.852071) < 5e-7
    else:
        want = f0 * ((1 - ratio) / (1 + ratio)) ** np.floor(t / 2.0)
        assert blow.piston_energy / blow.energy_at_impact < 1e-30
    np.testing.assert_allclose(blow.shank_force(t), want, rtol=1e-14, atol=0)


def test_si_numbers_of_a_steel_striker():
    """A 20 mm x 1 m steel striker (E = 201 GPa, rho = 7800 kg/m^3) at 5 m/s on a 30 mm rod:
    43,059.04 N for 393.98 us; the reverse, the staircase with ratio 0.384615."""
    Ey, rho, V, L = 201e9, 7800.0, 5.0, 1.0
    c = math.sqrt(Ey / rho)
    A0 = math.pi * 0.02 ** 2 / 4
    Z0 = A0 * math.sqrt(Ey * rho)
    model = _model([(20.0, 2.25)], 1.0, 2.0, s=1.0)  # s = 1: time unit L/c, force unit Z0 c
    blow = ib.single_blow(model, V / c, t_max=30.0)
    assert blow.shank_force(0.5) * Z0 * c == pytest.approx(43059.04, abs=0.005)
    assert 2 * L / c * 1e6 == pytest.approx(393.98, abs=0.005)
    assert blow.shank_force(2.5) == 0.0
    assert (1.25 / 3.25) == pytest.approx(0.384615, abs=5e-7)


@pytest.mark.slow
def test_stepped_rod_against_elwaspatid():
    """elwaspatid (Bacon's method, an independent characteristics code) on a striker and a
    three-segment rod with an anechoic far end: the force at every segment boundary to 1e-12
    relative, over the window where no boundary turns tensile (elwaspatid's boundaries carry no
    tension; ours are welded)."""
    E = pytest.importorskip("elwaspatid.elwaspatid")
    Ey, rho, V = 201e9, 7800.0, 5.0
    c = math.sqrt(Ey / rho)
    L, d = [1.0, 1.0, 0.5, 6.0], [0.02, 0.03, 0.025, 0.04]
    with contextlib.redirect_stdout(io.StringIO()):
        bar = E.BarSet([Ey] * 4, [rho] * 4, L, d, nmin=8, right="infinite")
        E.WP2(bar, incw=None, nstep=80, left="free", right="infinite", Vinit=V, contactLoss=None)
    A = [math.pi * x * x / 4 for x in d]
    Z0 = A[0] * math.sqrt(Ey * rho)
    model = _model([(x, a / A[0]) for x, a in zip(L[1:], A[1:], strict=True)], 1.0, 2.0, s=1.0)
    blow = ib.single_blow(model, V / c, cells_per_piston=16, t_max=79 / 16)
    assert blow.segment_cells == (16, 8, 96)
    n = 60  # before the first tensile boundary
    for j, seg in enumerate(bar.seg[:-1]):
        ref = -seg.Force[1:n + 1, -1]
        np.testing.assert_allclose(blow.junction_forces[:n, j] * Z0 * c, ref, rtol=0,
                                   atol=1e-12 * np.max(np.abs(ref)))
    assert blow.junction_forces[0, 0] * Z0 * c == pytest.approx(43059.04, abs=0.005)


def test_semi_infinite_rod_limit():
    """A stiff rock at the end of a long rod: within the first return trip the shank force and the
    energy into the rod are the wave law's (``wave_impact`` of a rigidly moving piston without drive,
    the rod of area ratio ``(1 + R)/(1 - R)``), to 1e-12."""
    from impactbar.laws.wave.impact import wave_impact
    from impactbar.loads import CosineLoad

    s, R, V = 3.0, 0.4, 0.7
    wave = ib.BarModel(s=s, d=0.0, R=R, n_modes=0, impact="wave")
    imp = wave_impact(wave, CosineLoad(0.0, 0.0, 1), 0.0, np.zeros(1), np.array([V]))
    z = (1 + R) / (1 - R)
    model = _model([(100.0, z)], 1e6, 2e6, s=s)
    blow = ib.single_blow(model, V, t_max=2.0 / s, cells_per_piston=8)
    t = (np.arange(16) + 0.5) / (8 * s)
    np.testing.assert_allclose(blow.shank_force(t), imp.force(t), rtol=1e-12)
    rod_e = blow.energy_at_impact - blow.piston_energy
    assert rod_e == pytest.approx(imp.rod_energy, rel=1e-12)


def test_feed_and_bit_mass_energy_account():
    """A stepped rod, a bit with mass, a feed force: the account closes to 1e-10, the efficiencies
    stay in [0, 1], the sampled penetration stays below its maximum (reached inside a step)."""
    model = _model([(1.0, 1.5), (0.5, 0.8), (3.0, 1.0)], 5.0, 20.0, s=2.0, bit_mass=0.3, feed=0.2)
    blow = ib.single_blow(model, 1.0)
    assert blow.energy_error < 1e-10
    assert 0.0 < blow.efficiency <= blow.efficiency_with_rebound <= 1.0
    assert blow.max_penetration >= blow.permanent_penetration
    assert 0.99 * blow.max_penetration <= np.max(blow.penetrations) <= blow.max_penetration


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([0.25, 0.5, 1.0, 1.5]), st.floats(0.3, 3.0)), min_size=1,
                max_size=3),
       st.floats(0.05, 20.0), st.floats(1.0, 50.0), st.sampled_from([0.0, 0.05, 0.5]),
       st.floats(0.0, 0.5))
def test_efficiency_never_exceeds_one(segments, k, gamma, bit_mass, feed):
    """Random stepped rods, rocks, bits and feeds: efficiencies in [0, 1], the account closes."""
    model = _model(segments, k, gamma * k, s=1.5, bit_mass=bit_mass, feed=feed)
    blow = ib.single_blow(model, 1.0, t_max=30.0)
    assert blow.energy_error < 1e-10
    assert -1e-12 <= blow.efficiency <= 1.0  # gamma = 1: elastic rock, no work but rounding
    assert -1e-12 <= blow.efficiency_with_rebound <= 1.0 + 1e-12


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"length": 0.0, "impedance": 1.0}, "length"),
    ({"length": 1.0, "impedance": -1.0}, "impedance"),
    ({"length": 1.0, "impedance": 1.0, "wave_speed": math.inf}, "wave_speed"),
])
def test_segment_validation(kwargs, name):
    with pytest.raises(ValueError, match=name):
        ib.RodSegment(**kwargs)


def test_rock_and_law_validation():
    with pytest.raises(ValueError, match="k_u"):
        ib.BilinearRock(k=2.0, k_u=1.0)
    with pytest.raises(ValueError, match="k must"):
        ib.BilinearRock(k=0.0, k_u=1.0)
    seg, rock = [ib.RodSegment(length=1.0, impedance=1.0)], ib.BilinearRock(k=1.0, k_u=2.0)
    with pytest.raises(ValueError, match="bit_mass"):
        ib.RodRock(segments=seg, rock=rock, bit_mass=-1.0)
    with pytest.raises(ValueError, match="feed"):
        ib.RodRock(segments=seg, rock=rock, feed=math.nan)
    with pytest.raises(ValueError, match="RodRock"):
        ib.BarModel(s=1.0, d=0.0, R=0.0, n_modes=0, impact="rodrock")
    with pytest.raises(ValueError, match="segments"):
        ib.RodRock(segments=[], rock=rock)
    law = ib.RodRock(segments=seg, rock=rock)
    assert law == ib.RodRock(segments=tuple(seg), rock=rock) and hash(law)
    with pytest.raises(ValueError, match="RodRock"):
        ib.single_blow(ib.BarModel(s=1.0, d=0.0, R=0.0, n_modes=0), 1.0)


def test_plots_of_a_blow():
    """The Lagrange diagram shows the recorded field (one mesh value per cell and step) and the loop
    the recorded rock force against the penetration."""
    import matplotlib.pyplot as plt

    model = _model([(1.0, 1.5), (2.0, 1.0)], 2.0, 8.0, s=1.0)
    blow = ib.single_blow(model, 1.0, record_field=True, t_max=6.0)
    ax = blow.plot_lagrange()
    mesh = ax.collections[0]
    assert mesh.get_array().size == blow.field.size == len(blow.shank_forces) * blow.cell_edges.size - \
        len(blow.shank_forces)
    assert blow.cell_edges[0] == -1.0 and blow.cell_edges[blow.piston_cells] == pytest.approx(0.0, abs=1e-15)
    assert blow.cell_edges[-1] == pytest.approx(3.0, rel=1e-12)
    ax2 = blow.plot_loop()
    x, y = ax2.lines[0].get_data()
    np.testing.assert_array_equal(y, blow.bit_forces)
    plt.close("all")
    with pytest.raises(ValueError, match="record_field"):
        ib.single_blow(model, 1.0, t_max=1.0).plot_lagrange()


@pytest.mark.parametrize(("segments", "bit_mass", "feed"), [
    ([(1.0, 2.25), (0.5, 0.7), (3.0, 1.0)], 0.0, 0.0),
    ([(1.0, 1.5), (0.5, 0.8), (3.0, 1.0)], 0.3, 0.2),
    ([(0.25, 0.5)], 0.05, 0.5),
])
def test_compiled_blow_matches_the_numpy_loop(segments, bit_mass, feed):
    """The compiled loop (``"rock.blow"``) against the numpy loop, its reference: same histories
    and energies to 1e-12."""
    from impactbar.dynamics.implementations import use_reference

    model = _model(segments, 3.0, 12.0, s=1.5, bit_mass=bit_mass, feed=feed)
    fast = ib.single_blow(model, 1.0, t_max=25.0, record_field=True)
    with use_reference("rock.blow"):
        ref = ib.single_blow(model, 1.0, t_max=25.0, record_field=True)
    assert fast.ended_by == ref.ended_by and fast.times.size == ref.times.size
    for name in ("junction_forces", "bit_forces", "penetrations", "field"):
        np.testing.assert_allclose(getattr(fast, name), getattr(ref, name), rtol=0, atol=1e-12)
    for name in ("work_on_rock", "piston_energy", "rod_energy", "grid_loss", "rebound_velocity"):
        assert getattr(fast, name) == pytest.approx(getattr(ref, name), rel=1e-10, abs=1e-13)


def test_readme_example():
    """The README's and RodRock's example: alpha = 1.25, gamma = 10, efficiency 0.733069."""
    law = ib.RodRock(segments=[ib.RodSegment(length=40.0, impedance=1.0)],
                     rock=ib.BilinearRock(k=2.5, k_u=25.0))
    model = ib.BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law)
    assert law.alpha(model) == 1.25
    assert round(ib.single_blow(model, 1.0, t_max=39.0).efficiency, 6) == 0.733069


def test_incommensurate_segments_converge_with_the_grid():
    """A segment of length sqrt(2) is rounded to whole cells (``length_error`` says by how much): the
    blow is then exact for the rounded rod (the same as a rod given the rounded length), and the
    efficiency converges as ``O(dt)``: within ``0.02 dt`` of a 2048-cell solution here."""
    segs = [(math.sqrt(2), 2.0), (1.0, 0.7)]
    model = _model(segs, 2.0, 8.0, s=1.0)
    ref = ib.single_blow(model, 1.0, cells_per_piston=2048, t_max=10.0)
    for n in (16, 32, 64, 128):
        blow = ib.single_blow(model, 1.0, cells_per_piston=n, t_max=10.0)
        assert 0.0 < blow.length_error <= 0.5 / (n * math.sqrt(2))
        assert abs(blow.efficiency - ref.efficiency) < 0.02 / n
        rounded = _model([(blow.segment_cells[0] / n, 2.0), (1.0, 0.7)], 2.0, 8.0, s=1.0)
        same = ib.single_blow(rounded, 1.0, cells_per_piston=n, t_max=10.0)
        assert same.length_error < 1e-12
        assert same.efficiency == pytest.approx(blow.efficiency, rel=1e-13)


def test_the_reflection_from_a_stiff_elastic_rock_throws_the_piston_back():
    """Equal impedances, an elastic (gamma = 1) and stiff rock: the piston stops after ``2/s``, still
    touching; the wave reflected whole at the bit returns at ``2 l/s`` and throws it back with
    ``-V`` (all the energy returned, no work on rock), the shank force a second pulse ``s V/2``."""
    s, V, ell = 2.0, 1.0, 3.0
    k = 1e6
    model = _model([(ell, 1.0)], k, k, s=s)
    blow = ib.single_blow(model, V, t_max=12.0 / s)
    assert blow.rebound_velocity == pytest.approx(-V, rel=1e-4)
    assert blow.piston_energy == pytest.approx(blow.energy_at_impact, rel=1e-4)
    assert abs(blow.work_on_rock) < 1e-12
    t = np.array([1.0, 3.0, 7.0, 9.0]) / s
    np.testing.assert_allclose(blow.shank_force(t), [s * V / 2, 0.0, s * V / 2, 0.0], atol=1e-3)
    assert blow.energy_error < 1e-12


def test_computations_the_law_does_not_provide_are_refused_with_a_value_error():
    """The one-impact phase equation is not provided under the rod-rock law (periodic_orbits finds
    the orbits by Newton's method instead: tests/orbits/test_rock_periodic_orbits.py): what needs it
    refuses the model with a ValueError naming ``model.impact`` (also a NotImplementedError, for law
    authors)."""
    import impactbar as ib
    from impactbar.laws.base import LawNotSupported

    law = ib.RodRock(segments=[ib.RodSegment(length=40.0, impedance=1.0)],
                     rock=ib.BilinearRock(k=2.5, k_u=25.0))
    model = ib.BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law)
    load = ib.CosineLoad(0.5, 1.0)
    from impactbar.orbits import orbit_multipliers
    from impactbar.orbits.one_impact import phase_equation_orbits

    calls = [lambda: phase_equation_orbits(model, load), lambda: orbit_multipliers(model, load, 1.0)]
    for call in calls:
        with pytest.raises(ValueError, match=r"model\.impact: the impact law 'rodrock'") as info:
            call()
        assert isinstance(info.value, LawNotSupported) and isinstance(info.value, NotImplementedError)
