"""The compiled certified admissibility search (``orbits/_admissibility_search.py``) against the numpy search
it replaces, and the search (both paths) against the rigid bar's closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactbar.orbits.admissibility as admissibility
from impactbar import BarModel, CosineLoad, FourierLoad, SquareWaveLoad, find_orbit
from impactbar.dynamics.implementations import use_reference
from impactbar.orbits.one_impact import _periodic_orbits_general
from impactbar.orbits.rigid import STATUS, rigid_square_orbits


@pytest.fixture(autouse=True)
def _machine_code(monkeypatch):
    """The search's machine code from its first call, as after ``impactbar warmup`` (with an empty
    cache a process's first searches would take its interpreted twin, which gives the same bits)."""
    from impactbar.dynamics import _tiers

    monkeypatch.setattr(_tiers._PROCESS, "eager", True)


def _both(monkeypatch, fn):
    """``fn()`` with the compiled search, then with the numpy search."""
    fast = fn()
    with use_reference("admissibility.search"):
        ref = fn()
    return fast, ref


def _assert_same_verdicts(fast, ref):
    assert len(fast) == len(ref)
    for o, g in zip(fast, ref, strict=True):
        assert o.phase == g.phase  # the search does not touch the phases
        assert o.admissibility == g.admissibility
        if math.isfinite(g.clearance):
            assert o.clearance == pytest.approx(g.clearance, rel=1e-10, abs=1e-12)
        else:
            assert o.clearance == g.clearance
        assert o.clearance_error == pytest.approx(g.clearance_error, rel=1e-8, abs=1e-12)


@pytest.mark.parametrize("square", [False, True])
def test_compiled_search_equals_numpy_search(monkeypatch, square):
    """Random flexible bars (R = 0 and d = 0 included), cosine, two-harmonic and square-wave loads:
    the same admissibility verdicts, clearances to 1e-10 and error bounds."""
    rng = np.random.default_rng(211 + square)
    seen = set()
    for _ in range(14):
        n = int(rng.integers(0, 24))
        d = 0.0 if rng.random() < 0.25 else float(rng.uniform(0.0, 0.3))
        R = 0.0 if rng.random() < 0.2 else float(rng.uniform(0.0, 0.95))
        model = BarModel(float(rng.uniform(0.7, 6.0)), d, R, n)
        if square:
            load = SquareWaveLoad(float(rng.uniform(0.3, 1.5)), float(rng.uniform(1.0, 1.95)))
        elif rng.random() < 0.5:
            load = CosineLoad(float(rng.uniform(0.1, 0.8)), float(rng.uniform(0.3, 1.5)))
        else:
            load = FourierLoad(float(rng.uniform(0.2, 0.8)), [rng.uniform(0.3, 1.0), 0.3j * rng.random()])
        try:
            fast, ref = _both(monkeypatch, lambda m=model, f=load: _periodic_orbits_general(m, f))
        except ValueError:  # an undamped resonance (eq. 16)
            continue
        _assert_same_verdicts(fast, ref)
        seen.update(g.admissibility for g in ref)
    assert {"admissible", "penetrates"} <= seen


def test_compiled_search_equals_numpy_search_wave_law_and_multi_impact(monkeypatch):
    """The wave law's shorter flight (``horizon < 2 pi``, departure at rest) and the flights of a
    two-impact orbit take the same search."""
    for model, load in ((BarModel(6.0, 0.05, 0.4, 6, impact="wave"), CosineLoad(0.5, 1.0)),
                        (BarModel(4.0, 0.1, 0.6, 8, impact="wave"), SquareWaveLoad(0.8, 1.4))):
        fast, ref = _both(monkeypatch, lambda model=model, load=load: _periodic_orbits_general(model, load))
        assert len(ref) > 0
        _assert_same_verdicts(fast, ref)
    model, load = BarModel(3.0, 0.05, 0.8, 4), CosineLoad(0.45, 1.0)
    fast, ref = _both(monkeypatch, lambda: find_orbit(model, load, impacts=2, periods=2))
    assert fast.admissibility == ref.admissibility
    assert fast.clearance == pytest.approx(ref.clearance, rel=1e-10, abs=1e-12)


def test_unknown_load_takes_the_numpy_search(monkeypatch):
    """A load subclass with its own evaluation is not compiled: the numpy search decides it."""

    class Shifted(CosineLoad):
        def __call__(self, t):
            return super().__call__(t)

    calls = []
    real = admissibility._numpy_search
    monkeypatch.setattr(admissibility, "_numpy_search", lambda *a: calls.append(1) or real(*a))
    model = BarModel(3.0, 0.1, 0.5, 3)
    orbits = _periodic_orbits_general(model, Shifted(0.5, 1.0))
    assert len(calls) == len(orbits) > 0
    calls.clear()
    _periodic_orbits_general(model, CosineLoad(0.5, 1.0))
    assert calls == []


@pytest.mark.parametrize("compiled", [True, False])
def test_two_close_zeros_in_one_interval(choose, compiled):
    """Regression: two zeros of the end's velocity in one narrow interval of the search. Newton
    found the minimum and missed the maximum next to it, so the clearance was off by 1.2e-6 while
    claiming 8e-12. The general path must match the rigid closed form (theory §5) within its own
    error bound."""
    choose("admissibility.search", compiled)
    d, R, q, kappa = 0.0, 0.4285396081429238, 0.9627273973468053, 1.527670318231706
    ref = rigid_square_orbits(d, R, q, kappa)
    orbits = _periodic_orbits_general(BarModel(1.0, d, R, 0), SquareWaveLoad(q, kappa))
    assert len(orbits) == int(ref.n_orbits[0]) == 2
    for j, o in enumerate(orbits):
        assert o.admissibility == STATUS[int(ref.status[0, j])]
        assert abs(o.clearance - ref.clearance[0, j]) <= o.clearance_error
        assert o.clearance == pytest.approx(ref.clearance[0, j], rel=1e-10, abs=1e-12)
        assert o.clearance_error == pytest.approx(ref.clearance_error[0, j], rel=1e-9)  # one convention


@pytest.mark.parametrize("compiled", [True, False])
def test_general_search_equals_rigid_square_closed_form(choose, compiled):
    """Rigid bars under random square waves, where the end's velocity has kinks at the jumps: the
    general search's clearance equals the closed form within its error bound, on both paths."""
    choose("admissibility.search", compiled)
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(40):
        d = 0.0 if rng.random() < 0.4 else float(rng.uniform(0.0, 0.3))
        R, q = float(rng.uniform(0.05, 0.95)), float(rng.uniform(0.3, 1.5))
        kappa = float(rng.uniform(1.0, 1.9))
        ref = rigid_square_orbits(d, R, q, kappa)
        if ref.fallback[0]:
            continue
        orbits = _periodic_orbits_general(BarModel(1.0, d, R, 0), SquareWaveLoad(q, kappa))
        assert len(orbits) == int(ref.n_orbits[0])
        for j, o in enumerate(orbits):
            assert o.admissibility == STATUS[int(ref.status[0, j])]
            if math.isfinite(o.clearance):
                assert abs(o.clearance - ref.clearance[0, j]) <= o.clearance_error + 1e-13
                checked += 1
    assert checked > 20


def test_transfer_cache_keeps_each_model_apart():
    """One load used with many models in turn (more than the cache holds, and back again) gives the
    states a fresh load gives: the cached transfer functions are keyed by the model."""
    load = FourierLoad(0.4, [0.8, 0.2 - 0.1j])
    rng = np.random.default_rng(3)
    models = [BarModel(float(rng.uniform(0.5, 6.0)), float(rng.uniform(0.0, 0.3)), 0.5, int(n))
              for n in rng.integers(1, 12, size=11)]
    for model in models + models[:3]:
        w2 = model.frequencies**2
        q0 = rng.normal(size=w2.size)
        args = (w2, model.d, 0.3, q0, -q0, np.linspace(0.3, 6.0, 7))
        fresh = FourierLoad(0.4, [0.8, 0.2 - 0.1j])
        for a, b in zip(load.propagate(*args), fresh.propagate(*args), strict=True):
            assert np.array_equal(a, b)


@pytest.mark.parametrize("compiled", [True, False])
def test_clearance_equals_dense_sampling(choose, compiled):
    """The pruned search against an independent brute force: ``g'`` sampled on a fine grid, every
    sign change refined by Brent's method, the largest ``g`` there. Flexible bars, both loads."""
    from scipy.optimize import brentq

    choose("admissibility.search", compiled)
    cases = [(BarModel(5.0, 0.1, 0.5, 8), CosineLoad(0.6, 1.0)),
             (BarModel(2.0, 0.05, 0.7, 6), CosineLoad(0.3, 1.0)),
             (BarModel(5.0, 0.1, 0.5, 16), SquareWaveLoad(1.0, 1.2)),
             (BarModel(1.5, 0.02, 0.3, 5), SquareWaveLoad(0.7, 1.6))]
    checked = 0
    for model, load in cases:
        w2, c = model.frequencies**2, model.end_weights
        M = model.n_modes + 1
        for o in _periodic_orbits_general(model, load):
            def state(t, o=o, model=model, load=load, w2=w2, M=M):
                y = o.state_after_impact
                return load.propagate(w2, model.d, o.phase, y[:M], y[M:], o.phase + np.atleast_1d(t))

            t = np.linspace(1e-9, 2.0 * math.pi - 1e-9, 40001)
            q, v = state(t)
            g1 = c @ v
            roots = [brentq(lambda x, c=c, state=state: float(c @ state(x)[1][:, 0]), t[i], t[i + 1],
                            xtol=1e-15)
                     for i in np.flatnonzero(np.sign(g1[:-1]) * np.sign(g1[1:]) < 0)]
            assert roots
            brute = max(float(c @ state(r)[0][:, 0]) for r in roots)
            assert o.clearance == pytest.approx(brute, abs=1e-9)
            checked += 1
    assert checked >= 6


def test_enclose_zeros_prune_keeps_exactly_what_it_is_told():
    """``enclose_zeros(prune=...)``: without a prune every zero of ``sin(5 t)`` is enclosed; a
    prune that keeps ``t > 3`` leaves exactly the zeros past 3, each still enclosed."""
    from impactbar.dynamics.certified import enclose_zeros

    def joint(mid, half):
        return np.sin(5.0 * mid), np.full(np.shape(mid), 5.0)

    zeros = np.arange(0, 11) * math.pi / 5.0  # 0 and 2 pi included
    full = enclose_zeros(None, None, 0.0, 2.0 * math.pi, joint=joint, min_width=1e-6)
    assert len(full) == zeros.size
    part = enclose_zeros(None, None, 0.0, 2.0 * math.pi, joint=joint, min_width=1e-6,
                         prune=lambda mids, half, fm, lip: mids > 3.0)
    inside = zeros[zeros > 3.0 + 1e-3]
    assert len(part) == inside.size
    assert all(lo <= z <= hi for z, (lo, hi) in zip(inside, part, strict=True))


def test_start_state_is_periodic_under_fourier_loads():
    """The flexible modes' start state (from the periodic response, eqs. 10-13) is the fixed point of
    one period's flow followed by the impact law: ``q+ = q-``, ``v+ = -R v-`` mode by mode, to 1e-12."""
    from impactbar.laws.paper.periodic import _start_state

    rng = np.random.default_rng(5)
    for _ in range(12):
        n = int(rng.integers(1, 20))
        model = BarModel(float(rng.uniform(0.5, 6.0)), float(rng.uniform(0.01, 0.4)),
                         float(rng.uniform(0.0, 0.95)), n)
        load = FourierLoad(float(rng.uniform(0.2, 0.8)), rng.normal(size=2) + 1j * rng.normal(size=2))
        phase = float(rng.uniform(0.0, 2.0 * math.pi))
        y = _start_state(model, load, phase)
        M = n + 1
        q, v = load.propagate(model.frequencies[1:] ** 2, model.d, phase, y[1:M], y[M + 1:],
                              [phase + 2.0 * math.pi])
        scale = 1.0 + np.max(np.abs(y))
        assert np.max(np.abs(y[1:M] - q[:, 0])) < 1e-12 * scale
        assert np.max(np.abs(y[M + 1:] + model.R * v[:, 0])) < 1e-12 * scale


def test_third_derivative_bound_holds():
    """The bound of ``|g'''|`` behind the single-zero certificate is above ``|g'''|`` sampled on its
    interval (``g''' = c . (p' - d q'' - w2 q')``, exact from the flow), for random flights."""
    rng = np.random.default_rng(9)
    for _ in range(20):
        n = int(rng.integers(0, 12))
        model = BarModel(float(rng.uniform(0.5, 5.0)), float(rng.uniform(0.0, 0.3)), 0.5, n)
        k = np.array([1.0, 2.0])
        pk = rng.normal(size=2) + 1j * rng.normal(size=2)
        load = FourierLoad(float(rng.uniform(-0.5, 0.8)), pk)
        w2, c = model.frequencies**2, model.end_weights
        w, M = np.sqrt(w2), n + 1
        q0, v0 = rng.normal(size=M), rng.normal(size=M)
        mid, half = np.array([float(rng.uniform(0.5, 5.0))]), np.array([float(rng.uniform(1e-3, 0.2))])
        q, v = load.propagate(w2, model.d, 0.0, q0, v0, mid)
        center, delta = load.variation(mid, half)
        slope = admissibility._load_slope(load)[0]
        L3 = admissibility._third_bound(w, w2, model.d, np.abs(c), load.sup_abs, q, v, center, delta,
                                        half, slope)
        t = np.linspace(mid[0] - half[0], mid[0] + half[0], 201)
        qs, vs = load.propagate(w2, model.d, 0.0, q0, v0, t)
        p1 = (np.exp(1j * np.outer(t, k)) @ (1j * k * pk)).real
        acc = load(t)[None, :] - model.d * vs - w2[:, None] * qs
        g3 = c @ (p1[None, :] - model.d * acc - w2[:, None] * vs)
        assert np.max(np.abs(g3)) <= L3[0] * (1.0 + 1e-12)


def test_no_disk_cache_keeps_the_compiled_search(monkeypatch):
    """Whether numba's cache folder is writable chooses no algorithm: without a disk cache (numba
    then compiles in memory) the compiled search still decides, with the same verdicts as the numpy
    search; and the package reads ``_event_loop.CACHE`` nowhere but as numba's ``cache=`` option."""
    import ast
    import pathlib

    import impactbar
    import impactbar.dynamics._event_loop as kernel

    model, load = BarModel(4.0, 0.1, 0.5, 6), CosineLoad(0.5, 1.0)
    with use_reference("admissibility.search"):
        ref = _periodic_orbits_general(model, load)
    calls = []
    real = admissibility._numpy_search
    monkeypatch.setattr(admissibility, "_numpy_search", lambda *a: calls.append(1) or real(*a))
    monkeypatch.setattr(kernel, "CACHE", False)
    fast = _periodic_orbits_general(model, load)
    assert calls == [] and len(fast) > 0
    _assert_same_verdicts(fast, ref)
    uses = []
    for path in pathlib.Path(impactbar.__file__).parent.rglob("*.py"):
        tree = ast.parse(path.read_text())
        allowed = {id(k.value) for k in ast.walk(tree) if isinstance(k, ast.keyword) and k.arg == "cache"}
        allowed |= {id(t) for n in ast.walk(tree) if isinstance(n, ast.Assign) for t in n.targets}
        uses += [f"{path.name}:{n.lineno}" for n in ast.walk(tree)
                 if (isinstance(n, ast.Name) and n.id == "CACHE" or isinstance(n, ast.Attribute)
                     and n.attr == "CACHE") and id(n) not in allowed]
    assert uses == []


def test_one_compiled_search_serves_every_load():
    """The compiled search is compiled once, whatever the load (cosine of any order, several
    harmonics, square wave, cached transfer functions or fresh ones): its arguments always have
    the same numba types, so no load makes a user wait for a second compilation."""
    from impactbar.orbits import _admissibility_search

    loads = [CosineLoad(0.6, 1.0), CosineLoad(0.4, 1.0, k=2), SquareWaveLoad(1.0, 1.2),
             FourierLoad(0.5, [1.0, 0.0, 0.2j])]
    for n_modes in (0, 3, 8):  # the rigid bar by the general path too (a one-row transfer function)
        model = BarModel(5.0, 0.1, 0.5, n_modes)
        for load in loads + loads:  # the second time, the loads' cached transfer functions
            _periodic_orbits_general(model, load)
    assert len(_admissibility_search.admissibility_search.signatures) == 1


def test_newton_leaves_an_interval_once_it_converged_or_left_it():
    """``_newton_stationary`` on ``g = cos t`` (one mode, ``w2 = 1``, no load): the interval
    holding the zero ``pi`` of ``g'`` converges to it; one without a zero fails after one
    evaluation (its first step leaves it) and is not evaluated again while the other iterates."""
    seen = []

    def states(t):
        t = np.asarray(t, dtype=float)
        seen.append(t.size)
        return np.cos(t)[None, :], -np.sin(t)[None, :]

    lo, hi = np.array([2.9, 1.0]), np.array([3.3, 1.4])
    t, ok = admissibility._newton_stationary(states, lambda t: np.zeros(np.shape(t)), 0.0, np.ones(1),
                                             np.ones(1), 0.0, lo, hi)
    assert ok.tolist() == [True, False]
    assert t[0] == pytest.approx(math.pi, abs=1e-12)
    assert seen[0] == 2 and all(n == 1 for n in seen[1:]) and len(seen) > 2


def test_searches_in_threads_keep_their_own_phase_buffers(monkeypatch):
    """The bisection's store of the modes' phases (``_admissibility_search.phase_buffers``) is kept per
    thread and reused from one search to the next: searches that run at once in threads (the
    kernel releases the GIL, as a threaded dask sweep runs it) give bit for bit what they give
    one after another, and a thread reuses its own buffers."""
    from concurrent.futures import ThreadPoolExecutor

    from impactbar.orbits import _admissibility_search

    calls = []
    search = _admissibility_search.admissibility_search

    def capture(*args):
        calls.append(args)
        return search(*args)

    monkeypatch.setattr(_admissibility_search, "admissibility_search", capture)
    for s, load in ((3.0, CosineLoad(0.6, 1.0)), (2.0, CosineLoad(0.5, 1.2)), (4.0, CosineLoad(0.7, 0.9))):
        _periodic_orbits_general(BarModel(s, 0.0, 0.5, 96, impact="wave"), load)
    monkeypatch.undo()
    assert len(calls) >= 4

    def run(args):
        bufs = _admissibility_search.phase_buffers(args[7][0].size)
        return search(*args[:8], bufs, args[9]), bufs

    serial = [run(a)[0] for a in calls]
    with ThreadPoolExecutor(4) as pool:
        threaded = list(pool.map(run, calls * 3))
    assert [r for r, _ in threaded] == serial * 3
    assert _admissibility_search.phase_buffers(96) is _admissibility_search.phase_buffers(96)
    assert len({id(b) for _, b in threaded} - {id(_admissibility_search.phase_buffers(96))}) <= 4
