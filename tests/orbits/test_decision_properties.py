"""Every verdict decided by a sign or a threshold (admissibility, grazing,
separation under the wave law, sticking, the degenerate-family test, the simulator's impact and
stick detection) is the same at every load scale (the model is linear in the load, so each verdict
must be) and does not flip under a perturbation of the parameters far below the verdict's own
margin. Both impact laws; hypothesis with few examples, so it runs in the default suite."""

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import impactbar as ib

TWO_PI = 2.0 * math.pi
FEW = settings(max_examples=15, deadline=None, derandomize=True,
               suppress_health_check=[HealthCheck.too_slow])

laws = st.sampled_from(["paper", "wave"])
models = st.builds(ib.BarModel, s=st.floats(0.6, 30), d=st.sampled_from([0.0, 0.05, 0.5]),
                   R=st.floats(0.0, 0.95), n_modes=st.sampled_from([0, 0, 1, 3]), impact=laws)
loads = st.one_of(st.builds(ib.CosineLoad, st.floats(-0.3, 1.5), st.floats(0.2, 2.0)),
                  st.builds(ib.SquareWaveLoad, st.floats(0.2, 2.0), st.floats(1.05, 1.97)))


def _scaled(load, L):
    if isinstance(load, ib.SquareWaveLoad):
        return ib.SquareWaveLoad(load.q * L, load.kappa)
    return ib.CosineLoad(load.p0 * L, load.pk * L)


def _orbits(model, load):
    try:
        return ib.periodic_orbits(model, load)
    except ValueError:  # undamped resonance, or R = 1 with d = 0 and flexible modes
        return None


def _verdicts(orbits):
    return [(round(o.phase, 6), o.multiplicity, str(o.admissibility)) for o in orbits]


@FEW
@given(model=models, load=loads, exponent=st.sampled_from([-12, -6, 6, 12]))
def test_orbit_verdicts_are_the_same_at_every_load_scale(model, load, exponent):
    """Admissibility (penetration, backward impact, grazing, sticking, the wave law's separation),
    multiplicities and degenerate families of :func:`periodic_orbits`."""
    orbits = _orbits(model, load)
    if orbits is None:
        return
    L = 10.0**exponent
    scaled = ib.periodic_orbits(model, _scaled(load, L))
    assert _verdicts(scaled) == _verdicts(orbits)
    np.testing.assert_allclose(np.ravel(scaled.families), np.ravel(orbits.families), atol=1e-9)
    for a, b in zip(orbits, scaled, strict=True):
        assert b.impact_velocity == a.impact_velocity * L or \
            abs(b.impact_velocity - a.impact_velocity * L) <= 1e-8 * L * max(1.0, abs(a.impact_velocity))
        if a.admissibility != "grazing":  # at zero impact velocity the saltation term is 1/0: the
            # multipliers of an exactly grazing orbit are rounding noise at any scale
            np.testing.assert_allclose(b.multipliers, a.multipliers, rtol=1e-7, atol=1e-9)


def _margin(o, load):
    """How far an orbit's verdict is from its threshold, in units of the load: the impact velocity
    and the clearance (a verdict with a small margin may flip under a perturbation)."""
    scale = max(abs(load.q) if isinstance(load, ib.SquareWaveLoad) else abs(load.p0) + abs(load.pk),
                1e-300)
    c = abs(o.clearance) if np.isfinite(o.clearance) else math.inf
    return min(abs(o.impact_velocity), c) / scale


@FEW
@given(model=models, load=loads, which=st.sampled_from(["R", "s", "d"]), sign=st.sampled_from([-1, 1]))
def test_orbit_verdicts_do_not_flip_under_a_tiny_perturbation(model, load, which, sign):
    """A relative perturbation of 1e-10 of one parameter keeps every orbit and its verdict, unless
    the orbit is within 1e-6 of a threshold (impact velocity or clearance), or two orbits are about
    to merge (a fold: phases within 1e-3, or a double root)."""
    orbits = _orbits(model, load)
    if orbits is None:
        return
    eps = 1e-10 * sign
    kw = {"s": model.s, "d": model.d, "R": model.R, "n_modes": model.n_modes, "impact": model.impact}
    kw[which] = kw[which] * (1 + eps) if kw[which] else (abs(eps) if which == "d" else kw[which])
    if which == "R":
        kw["R"] = min(kw["R"], 1.0)
    other = _orbits(ib.BarModel(**kw), load)
    if other is None:
        return
    ph = np.sort([o.phase for o in orbits])
    if any(o.multiplicity != 1 for o in orbits) or (ph.size > 1 and np.min(np.diff(ph)) < 1e-3):
        return
    if any(_margin(o, load) < 1e-6 for o in orbits) or model.R == 0.0 and which != "R":
        return
    assert len(other) == len(orbits)
    for a, b in zip(orbits, other, strict=True):
        assert abs(b.phase - a.phase) < 1e-6
        assert b.admissibility == a.admissibility


@settings(max_examples=6, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(model=st.builds(ib.BarModel, s=st.floats(0.8, 10), d=st.sampled_from([0.0, 0.1]),
                       R=st.sampled_from([0.0, 0.5, 0.9]), n_modes=st.sampled_from([0, 1]),
                       impact=st.just("wave")),
       load=loads, e=st.floats(-1.0, -0.01), v=st.floats(-1.0, 1.0),
       exponent=st.sampled_from([-6, 6]))
def test_wave_simulation_verdicts_are_the_same_at_every_load_scale(model, load, e, v, exponent):
    """The wave law's simulator: impacts, the contact's separation and the stick verdicts at the
    same times for the load and the initial state scaled together (the paper law's twin is in
    tests/test_guarantees.py)."""
    L = 10.0**exponent
    try:
        ref = ib.simulate(model, load, ib.InitialState.rigid(e, v, model.n_modes), 20.0)
    except ValueError:
        return
    tr = ib.simulate(model, _scaled(load, L), ib.InitialState.rigid(e * L, v * L, model.n_modes), 20.0)
    assert tr.n_impacts == ref.n_impacts
    np.testing.assert_allclose(tr.impact_times, ref.impact_times, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(tr.end_displacement(np.linspace(tr.t0, tr.t_end, 201)),
                               L * ref.end_displacement(np.linspace(ref.t0, ref.t_end, 201)),
                               rtol=1e-6, atol=1e-9 * L)
