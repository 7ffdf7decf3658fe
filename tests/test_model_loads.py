"""BarModel and load validation; loads against exact quadrature and scipy integration."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from impactbar import BarModel, CosineLoad, FourierLoad, PiecewiseConstantLoad, SquareWaveLoad
from modal_reference import solve_modal

TWO_PI = 2 * math.pi


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"s": 0.0}, "s"),
        ({"s": -1.0}, "s"),
        ({"s": float("nan")}, "s"),
        ({"s": "10"}, "s"),
        ({"d": -0.1}, "d"),
        ({"d": float("inf")}, "d"),
        ({"R": 1.5}, "R"),
        ({"R": -0.01}, "R"),
        ({"n_modes": -1}, "n_modes"),
        ({"n_modes": 2.5}, "n_modes"),
        ({"n_modes": True}, "n_modes"),
        ({"n_modes": 10**6}, "n_modes"),
    ],
)
def test_bar_model_rejects_bad_input(kwargs, name):
    args = {"s": 10.0, "d": 0.0, "R": 0.5, "n_modes": 4} | kwargs
    with pytest.raises(ValueError, match=rf"^{name} "):
        BarModel(**args)


def test_bar_model_is_frozen_and_exact():
    m = BarModel(s=2, d=0, R=1, n_modes=3)
    assert isinstance(m.s, float) and m.n_modes == 3
    with pytest.raises(AttributeError):
        m.s = 3.0
    assert np.allclose(m.frequencies, 2 * math.pi * np.arange(4))
    assert m.end_weights.tolist() == [1, -2, 2, -2]
    assert np.allclose(m.shape_functions(1.0), m.end_weights)
    with pytest.raises(ValueError, match="unknown"):
        m.with_(k=1)


@pytest.mark.parametrize(
    ("factory", "name"),
    [
        (lambda: CosineLoad(float("nan"), 1.0), "p0"),
        (lambda: CosineLoad(0.1, "a"), "pk"),
        (lambda: CosineLoad(0.1, 1.0, 0), "k"),
        (lambda: CosineLoad(0.1, 1.0, 1.5), "k"),
        (lambda: SquareWaveLoad(0.0, 1.5), "q"),
        (lambda: SquareWaveLoad(1.0, 2.5), "kappa"),
        (lambda: SquareWaveLoad(1.0, 0.9), "kappa"),
        (lambda: FourierLoad(0.1, [1.0, float("inf")]), "coefficients"),
    ],
)
def test_loads_reject_bad_input(factory, name):
    with pytest.raises(ValueError, match=name):
        factory()


def test_square_wave_values_mean_and_harmonics():
    sq = SquareWaveLoad(2.0, 1.3)
    t = np.array([0.0, 1.0, 1.3 * math.pi - 1e-9, 1.3 * math.pi, 6.0, TWO_PI, TWO_PI + 1.0])
    assert sq(t).tolist() == [2.0, 2.0, 2.0, -2.0, -2.0, 2.0, 2.0]
    assert sq.p0 == pytest.approx(2.0 * 0.3)
    pk = sq.harmonics(5)
    for k in range(1, 6):  # p_k = (1/pi) int p(t) e^{-ikt} dt
        re = quad(lambda t, k=k: float(sq(t)) * math.cos(k * t), 0, TWO_PI, points=[1.3 * math.pi])[0]
        im = quad(lambda t, k=k: -float(sq(t)) * math.sin(k * t), 0, TWO_PI, points=[1.3 * math.pi])[0]
        assert pk[k - 1] == pytest.approx(complex(re, im) / math.pi, abs=1e-10)
    generic = PiecewiseConstantLoad([0.0, 1.3 * math.pi], [2.0, -2.0])
    assert np.allclose(generic.harmonics(5), pk)


def test_cosine_is_a_one_harmonic_fourier_load():
    c = CosineLoad(0.2, 0.7, 3)
    t = np.linspace(0, 7, 50)
    assert np.allclose(c(t), 0.2 + 0.7 * np.cos(3 * t))
    assert c.harmonics().tolist() == [0, 0, 0.7]
    assert c.load_factor == pytest.approx(3 * 0.2 / 0.7)


@settings(max_examples=20, deadline=None)
@given(d=st.floats(0.0, 2.0), t=st.floats(0.0, TWO_PI))
def test_rigid_velocity_solves_its_equation(d, t):
    """V' + d V = p - p0 (finite differences), for a smooth and a piecewise load."""
    for load in (FourierLoad(0.1, [1.0, 0.5j]), SquareWaveLoad(1.0, 1.4)):
        if isinstance(load, SquareWaveLoad) and min(abs(t - 1.4 * math.pi), t, TWO_PI - t) < 1e-3:
            continue
        h = 1e-5
        dV = (load.rigid_velocity(d, t + h) - load.rigid_velocity(d, t - h)) / (2 * h)
        resid = dV + d * load.rigid_velocity(d, t) - (load(t) - load.p0)
        assert abs(resid) < 1e-6


@pytest.mark.parametrize("load", [CosineLoad(0.3, 1.0, 2), SquareWaveLoad(1.0, 1.4),
                                  FourierLoad(0.2, [1.0, 0.3j, -0.2])])
@pytest.mark.parametrize("d", [0.0, 0.05, 3.0, 50.0])
def test_flow_against_scipy(load, d):
    """The closed-form flow in every damping regime (under-, critically, over-damped, rigid)."""
    w2 = np.array([0.0, 9.87, 400.0, (d / 2) ** 2])
    q0 = np.array([0.1, -0.2, 0.01, 0.3])
    v0 = np.array([0.5, 0.1, -1.0, 0.2])
    ts = np.array([0.7, 1.5, 3.3, 8.0])
    q, v = load.propagate(w2, d, 0.7, q0, v0, ts)
    _, _, ref, _ = solve_modal(w2, d, load, np.concatenate([q0, v0]), 0.7, 8.0, ts=ts)
    assert np.allclose(q, ref[:4], atol=1e-9)
    assert np.allclose(v, ref[4:], atol=1e-9)


@pytest.mark.parametrize("d", [5e-324, 5e-323, 1e-310, 1e-9, 0.3])
def test_b_integral_at_denormal_damping(d):
    """``b(tau) = (1 - e^{-d tau})/d`` without a division by a denormal ``d`` (floating-point errors
    raise in the tests): equal to its integral ``int_0^tau e^{-d t} dt`` by quadrature."""
    from impactbar.dynamics.modal import b_integral

    tau = np.array([0.0, 0.1, 1.0, 6.0])
    ref = [quad(lambda t: math.exp(-d * t), 0.0, x, epsabs=1e-15)[0] for x in tau]
    assert np.allclose(b_integral(d, tau), ref, rtol=1e-12, atol=1e-15)
    assert float(b_integral(d, 2.0)) == pytest.approx(quad(lambda t: math.exp(-d * t), 0.0, 2.0)[0],
                                                      rel=1e-12)


@pytest.mark.parametrize("impact", ["paper", "wave"])
def test_scales_that_overflow_are_refused_at_the_boundary(impact):
    """s with s pi (the rigid bar's scale) not finite, or d with d**2 not finite, is refused with a
    ValueError naming the parameter; the largest accepted values give finite orbits."""
    from impactbar import CosineLoad, periodic_orbits

    top = float(np.finfo(float).max)
    s_max = top / math.pi
    while not math.isfinite(s_max * math.pi):  # the largest s whose s pi is finite (Python floats)
        s_max = math.nextafter(s_max, 0.0)
    s_over = math.nextafter(s_max, math.inf)
    assert not math.isfinite(s_over * math.pi)
    load = CosineLoad(0.5, 1.0)
    orbits = periodic_orbits(BarModel(s_max, 0.1, 0.5, 0, impact=impact), load)
    assert len(orbits) == 2 and all(np.isfinite(o.phase) and o.admissible for o in orbits)
    for s in (s_over, 9e307, top):
        with pytest.raises(ValueError, match=r"^s must be in \(0, 5\.72223e\+307\]"):
            BarModel(s, 0.1, 0.5, 0, impact=impact)
    d_max = math.sqrt(top)
    while not math.isfinite(d_max * d_max):
        d_max = math.nextafter(d_max, 0.0)
    BarModel(1.0, d_max, 0.5, 4, impact=impact)
    for d in (math.nextafter(d_max, math.inf), 1e300):
        with pytest.raises(ValueError, match=r"^d must be in \[0, 1\.34078e\+154\]"):
            BarModel(1.0, d, 0.5, 4, impact=impact)


# ------------------------------------------------------------------------------------------------
# the table of loads: what each load declares
# ------------------------------------------------------------------------------------------------
TABLE_EXAMPLES = [CosineLoad(0.3, 1.0, 2), SquareWaveLoad(1.0, 1.2), FourierLoad(0.2, [0.5, 0.1j, 0.0]),
                  PiecewiseConstantLoad([0.0, 2.0, 4.0], [1.0, -0.5, 0.25])]


def test_the_table_holds_every_load_class_by_its_kind():
    from impactbar.loads import LOADS

    assert {type(ld) for ld in TABLE_EXAMPLES} == set(LOADS.values())
    for kind, cls in LOADS.items():
        traits = cls.traits
        assert traits.kind == kind and traits.description and traits.parameters
        assert set(traits.continuation_parameters) <= set(traits.parameters.names)


@pytest.mark.parametrize("load", TABLE_EXAMPLES, ids=lambda ld: ld.traits.kind)
def test_a_record_reads_back_as_the_same_load(load):
    import json

    from impactbar.loads import load_from_record

    record = load.params.record()
    assert record["kind"] == load.traits.kind and list(record)[1:] == list(load.traits.parameters.names)
    assert json.loads(json.dumps(record)) == record  # plain JSON
    assert load_from_record(record) == load
    assert load.params.with_() == load


@pytest.mark.parametrize(
    ("record", "match"),
    [({"p0": 0.3}, "missing key 'kind'"), ({"kind": "sine"}, "kind must be one of"),
     ({"kind": ["cosine"]}, "kind must be one of"), ({"kind": "cosine", "p0": 0.3, "pk": 1.0},
                                                     r"missing key\(s\) \['k'\]"),
     ({"kind": "square", "q": 1.0, "kappa": 1.2, "k": 1}, r"unknown key\(s\) \['k'\]"),
     ({"kind": "square", "q": -1.0, "kappa": 1.2}, "q must be")])
def test_a_bad_record_names_the_key(record, match):
    from impactbar.loads import load_from_record

    with pytest.raises(ValueError, match=match):
        load_from_record(record)


def test_with_changes_parameters_and_validates():
    assert CosineLoad(0.3, 1.0, 2).params.with_(pk=2.0) == CosineLoad(0.3, 2.0, 2)
    assert FourierLoad(0.2, [0.5, 0.1j]).params.with_(p0=0.4) == FourierLoad(0.4, [0.5, 0.1j])
    with pytest.raises(ValueError, match="kappa"):
        SquareWaveLoad(1.0, 1.2).params.with_(kappa=2.5)
    with pytest.raises(ValueError, match="not parameter"):
        SquareWaveLoad(1.0, 1.2).params.with_(pk=1.0)


def test_declared_forms_and_periods_against_the_loads_values():
    t = np.linspace(0.0, TWO_PI, 101)
    for load in TABLE_EXAMPLES + [FourierLoad(0.5, [0.0, 2.0])]:
        own = load.abilities
        cosine, square, pieces = own.cosine, own.square, own.pieces
        if cosine is not None:
            p0, pk, k = cosine
            np.testing.assert_allclose(load(t), p0 + pk * np.cos(k * t), atol=1e-14)
        if square is not None:
            q, kappa = square
            np.testing.assert_array_equal(load(t), np.where(t % TWO_PI < kappa * math.pi, q, -q))
        if pieces is not None:
            breaks, levels = pieces
            np.testing.assert_array_equal(load(breaks), levels)
        else:
            assert np.all(np.isfinite(load.harmonics()))
        T = own.period
        np.testing.assert_allclose(load(t + T), load(t), atol=1e-13)
    assert FourierLoad(0.5, [0.0, 2.0]).abilities.cosine == (0.5, 2.0, 2)
    assert FourierLoad(0.5, [0.0, 2.0]).abilities.period == math.pi
    assert FourierLoad(0.5, [1j]).abilities.cosine is None  # a sine is no cosine form
    assert CosineLoad(0.3, 1.0, 3).abilities.max_one_impact_orbits == 6


def test_a_subclass_with_its_own_evaluation_gets_no_compiled_view():
    class Shifted(CosineLoad):
        def __call__(self, t):
            return super().__call__(np.asarray(t) + 0.1)

    from impactbar.dynamics.compiled_views import FOURIER, PIECEWISE
    from impactbar.loads.abilities import compiled_kind

    cosine = CosineLoad(0.3, 1.0)
    assert compiled_kind(cosine, "__call__", "flow") == FOURIER == compiled_kind(cosine)
    assert compiled_kind(SquareWaveLoad(1.0, 1.2), "__call__") == PIECEWISE
    assert compiled_kind(Shifted(0.3, 1.0), "flow") == FOURIER == compiled_kind(Shifted(0.3, 1.0))
    assert compiled_kind(Shifted(0.3, 1.0), "__call__", "flow") is None


def test_loads_differing_only_in_the_mean_share_their_transfer_functions():
    """``H_nk p_k`` does not depend on ``p0``: a chart's load factors (a new load each) share it, the
    same floats as each load's own ``p_k / (w^2 + i k d - k^2)`` (eq. 8), and the periodic state and
    flow of each load the same bits as with nothing shared; a resonance is refused for every load."""
    from impactbar.loads import fourier

    w2 = (3.3 * np.pi * np.arange(9)) ** 2
    d = 0.02
    a, b = CosineLoad(0.3, 1.0, 10), CosineLoad(0.7, 1.0, 10)
    ha = a._transfer(w2, d)
    assert b._transfer(w2, d) is ha
    k = np.array([10.0])
    np.testing.assert_array_equal(ha, 1.0 / (w2[:, None] + 1j * k * d - k**2))
    q = np.zeros(9)
    shared = b.periodic_state(w2, d, [0.4]), b.flow(w2, d, 0.4, q + 0.1, q - 0.2)([1.0, 5.0])
    fourier._SHARED_TRANSFERS.clear()
    fresh = CosineLoad(0.7, 1.0, 10)
    alone = fresh.periodic_state(w2, d, [0.4]), fresh.flow(w2, d, 0.4, q + 0.1, q - 0.2)([1.0, 5.0])
    for x, y in zip(shared, alone, strict=True):
        for u, v in zip(x, y, strict=True):
            np.testing.assert_array_equal(u, v)
    res = np.array([0.0, 9.0])  # w^2 = k^2 = 9 undamped
    for p0 in (0.1, 0.2):
        with pytest.raises(ValueError, match="undamped resonance"):
            CosineLoad(p0, 1.0, 3)._transfer(res, 0.0)
