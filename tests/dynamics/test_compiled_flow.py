"""The compiled evaluation of the modal flow (``FourierLoad.flow``, ``PiecewiseConstantLoad.flow``,
used by the certified admissibility search) against the numpy path it replaces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, FourierLoad, SquareWaveLoad
from impactbar.dynamics.implementations import use_reference
from impactbar.orbits.one_impact import _periodic_orbits_general


def _both_flows(monkeypatch, load, w2, d, t0, q0, v0, t):
    fast = load.flow(w2, d, t0, q0, v0)(t)
    with use_reference("loads.flow"):
        ref = load.flow(w2, d, t0, q0, v0)(t)
    return fast, ref


def test_compiled_flow_equals_numpy_flow(monkeypatch):
    """Random models (rigid mode, d = 0, several harmonics, complex amplitudes), scalar and array
    times: the same states to rounding."""
    rng = np.random.default_rng(11)
    for _ in range(40):
        n = int(rng.integers(0, 25))
        d = 0.0 if rng.random() < 0.3 else float(rng.uniform(0.0, 0.6))
        model = BarModel(float(rng.uniform(0.3, 8.0)), d, 0.5, n)
        K = int(rng.integers(1, 5))
        load = FourierLoad(float(rng.uniform(-0.5, 1.0)), rng.normal(size=K) + 1j * rng.normal(size=K))
        w2 = model.frequencies**2
        q0, v0 = rng.normal(size=n + 1), rng.normal(size=n + 1)
        t0 = float(rng.uniform(0.0, 2.0 * math.pi))
        times = rng.uniform(t0 - 1.0, t0 + 7.0, size=int(rng.integers(1, 70)))
        for t in (float(rng.uniform(t0, t0 + 7.0)), times):
            (qf, vf), (qr, vr) = _both_flows(monkeypatch, load, w2, d, t0, q0, v0, t)
            assert qf.shape == qr.shape == (n + 1, np.size(t))
            scale = 1.0 + np.max(np.abs(qr)) + np.max(np.abs(vr))
            assert np.max(np.abs(qf - qr)) < 1e-12 * scale
            assert np.max(np.abs(vf - vr)) < 1e-12 * scale


def test_compiled_piecewise_flow_equals_numpy_flow(monkeypatch):
    """Square waves on random models, times on both sides of the jumps and before the start."""
    rng = np.random.default_rng(12)
    for _ in range(40):
        n = int(rng.integers(0, 30))
        d = 0.0 if rng.random() < 0.3 else float(rng.uniform(0.0, 0.6))
        model = BarModel(float(rng.uniform(0.3, 8.0)), d, 0.5, n)
        load = SquareWaveLoad(float(rng.uniform(0.2, 2.0)), float(rng.uniform(1.0, 2.0)))
        w2 = model.frequencies**2
        q0, v0 = rng.normal(size=n + 1), rng.normal(size=n + 1)
        t0 = float(rng.uniform(0.0, 2.0 * math.pi))
        times = np.concatenate((rng.uniform(t0 - 0.5, t0 + 2.0 * math.pi, size=int(rng.integers(1, 70))),
                                [t0, t0 + 2.0 * math.pi]))
        for t in (float(rng.uniform(t0, t0 + 6.0)), times):
            (qf, vf), (qr, vr) = _both_flows(monkeypatch, load, w2, d, t0, q0, v0, t)
            assert qf.shape == qr.shape == (n + 1, np.size(t))
            scale = 1.0 + np.max(np.abs(qr)) + np.max(np.abs(vr))
            assert np.max(np.abs(qf - qr)) < 1e-12 * scale
            assert np.max(np.abs(vf - vr)) < 1e-12 * scale


def test_overdamped_modes_keep_the_numpy_flow(monkeypatch):
    """A model with an overdamped flexible mode is not folded: the numpy path evaluates it."""
    model, load = BarModel(0.2, 1.5, 0.5, 3), CosineLoad(0.4, 1.0)
    w2 = model.frequencies**2
    assert np.any((w2 > 0) & (w2 < 0.25 * model.d**2))
    (qf, vf), (qr, vr) = _both_flows(monkeypatch, load, w2, model.d, 0.3, np.ones(4), -np.ones(4),
                                     np.linspace(0.3, 6.0, 9))
    assert np.array_equal(qf, qr) and np.array_equal(vf, vr)
    load = SquareWaveLoad(0.5, 1.3)
    (qf, vf), (qr, vr) = _both_flows(monkeypatch, load, w2, model.d, 0.3, np.ones(4), -np.ones(4),
                                     np.linspace(0.3, 6.0, 9))
    assert np.array_equal(qf, qr) and np.array_equal(vf, vr)


@pytest.mark.parametrize("n_modes, square", [(1, False), (4, False), (8, False), (20, False),
                                             (2, True), (8, True), (16, True)])
def test_periodic_orbits_with_compiled_flow_equal_numpy_path(monkeypatch, n_modes, square):
    """Same orbits, admissibility verdicts, clearances and multipliers to 1e-10 with the compiled flow
    and bounds of the certified search as with the numpy path."""
    rng = np.random.default_rng(100 + n_modes)
    seen = set()
    for _ in range(6):
        model = BarModel(float(rng.uniform(1.0, 6.0)), float(rng.uniform(0.0, 0.2)),
                         float(rng.uniform(0.0, 0.9)), n_modes)
        if square:
            load = SquareWaveLoad(float(rng.uniform(0.3, 1.5)), float(rng.uniform(1.0, 1.9)))
        else:
            load = CosineLoad(float(rng.uniform(0.2, 0.7)), float(rng.uniform(0.5, 1.5)))
        fast = _periodic_orbits_general(model, load)
        with use_reference("loads.flow", "admissibility.bound"):
            ref = _periodic_orbits_general(model, load)
        assert len(fast) == len(ref)
        seen.update(g.admissibility for g in ref)
        for o, g in zip(fast, ref, strict=True):
            assert o.phase == pytest.approx(g.phase, abs=1e-10)
            assert o.admissibility == g.admissibility
            assert o.stable == g.stable
            if math.isfinite(g.clearance):
                assert o.clearance == pytest.approx(g.clearance, rel=1e-10, abs=1e-12)
            else:
                assert o.clearance == g.clearance
            assert o.clearance_error == pytest.approx(g.clearance_error, rel=1e-8, abs=1e-12)
            assert np.allclose(np.sort_complex(o.multipliers), np.sort_complex(g.multipliers),
                               rtol=1e-10, atol=1e-10)
            assert np.allclose(o.state_after_impact, g.state_after_impact, rtol=1e-10, atol=1e-12)
    assert "admissible" in seen  # the comparison covered orbits whose verdict needs the search


def test_phased_column_equals_numpy_flow():
    """``fourier_column`` with the phases given (``phased``: the certified search's bisection, the
    folded modes' phases stepped by rotations) against the numpy flow: the same states to rounding
    from the exact phases, and from phases carried down 30 levels of halving steps as the
    bisection carries them (random rigid, folded and damped modes, several harmonics)."""
    from impactbar.dynamics._load_flow import fourier_column

    rng = np.random.default_rng(5)
    for _ in range(10):
        n = int(rng.integers(1, 40))
        d = 0.0 if rng.random() < 0.3 else float(rng.uniform(0.0, 0.5))
        model = BarModel(float(rng.uniform(0.5, 6.0)), d, 0.5, n)
        K = int(rng.integers(1, 4))
        load = FourierLoad(float(rng.uniform(-0.5, 1.0)), rng.normal(size=K) + 1j * rng.normal(size=K))
        w2 = model.frequencies**2
        t0 = float(rng.uniform(0.0, 6.0))
        q0, v0 = rng.normal(size=n + 1), rng.normal(size=n + 1)
        flow = load.flow(w2, d, t0, q0, v0).kernel_args
        with use_reference("loads.flow"):
            reference = load.flow(w2, d, t0, q0, v0)
        lam, M = flow[5][1], n + 1
        q, v = np.empty((M, 1)), np.empty((M, 1))
        ck, sk = np.empty(K), np.empty(K)
        mid, half = t0 + float(rng.uniform(0.0, 6.0)), 1.0
        C, S = np.cos(lam * (mid - t0)), np.sin(lam * (mid - t0))
        for level in range(31):
            if level:  # a random path down the bisection
                half *= 0.5
                sg = 1.0 if rng.random() < 0.5 else -1.0
                ch, sh = np.cos(lam * half), np.sin(lam * half)
                C, S = C * ch - sg * (S * sh), S * ch + sg * (C * sh)
                mid += sg * half
            if level in (0, 30):
                fourier_column(mid, q, v, np.int64(0), ck, sk, flow, C, S, np.bool_(True))
                qr, vr = reference(mid)
                scale = 1.0 + np.max(np.abs(qr)) + np.max(np.abs(vr))
                assert np.max(np.abs(q - qr)) < 1e-12 * scale and np.max(np.abs(v - vr)) < 1e-12 * scale
        assert np.max(np.abs(C * C + S * S - 1.0)) < 1e-13


@pytest.mark.parametrize("n, d", [(0, 0.0), (0, 0.3), (6, 0.0), (6, 0.2), (3, 9.0)])
def test_flow_parts_shared_by_mean_loads_give_each_load_its_own_floats(n, d):
    """Loads that differ only in the mean load share their flow's parts (a chart's load factors): the
    flow and the periodic state of each, from the parts another load computed, are the floats it
    computes alone (the store emptied first), to the bit; the shared parts are never written."""
    from impactbar.loads import fourier

    w2 = BarModel(2.3, d, 0.5, n).frequencies ** 2
    t = np.array([0.4, 2.0, 7.5])
    q0, v0 = np.linspace(-0.2, 0.3, n + 1), np.linspace(0.1, -0.4, n + 1)

    def states(load):
        flow = load.flow(w2, d, 0.4, q0, v0)
        return (*flow(t), *load.periodic_state(w2, d, t))

    loads = [FourierLoad(p0, [0.0, 0.7 - 0.2j, 0.0, 0.3]) for p0 in (0.9, -0.35, 0.0)]
    alone = []
    for load in loads:
        fourier._SHARED_FLOW_PARTS.clear()
        alone.append(states(load))
    fourier._SHARED_FLOW_PARTS.clear()
    states(CosineLoad(0.1, 1.0))  # another harmonic: parts of its own
    first = states(FourierLoad(2.5, [0.0, 0.7 - 0.2j, 0.0, 0.3]))
    parts = [np.copy(a) for p in fourier._SHARED_FLOW_PARTS.values() for a in p if isinstance(a, np.ndarray)]
    assert len(fourier._SHARED_FLOW_PARTS) == 2 and len(first) == 4
    for load, own in zip(loads, alone, strict=True):
        for x, y in zip(states(load), own, strict=True):
            assert np.array_equal(x.view(np.uint64), y.view(np.uint64))
    after = [a for p in fourier._SHARED_FLOW_PARTS.values() for a in p if isinstance(a, np.ndarray)]
    assert len(fourier._SHARED_FLOW_PARTS) == 2
    assert all(np.array_equal(a, b) for a, b in zip(after, parts, strict=True))
