"""The wave law's window at many modes: the drive's moments in closed form against the
compiled moments they replace from 48 modes on (Gauss-Legendre quadrature, or for a
piecewise-constant load the kernel's own closed form in product form, also checked against quad),
the contact scan by type-I DCT/DST against the dense modal sums, and the admissibility search's
plateau exclusion (compiled) against the numpy search at 128 modes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, FourierLoad, SquareWaveLoad, periodic_orbits
from impactbar.dynamics.implementations import use_reference
from impactbar.laws.wave import _window as KW
from impactbar.laws.wave import impact
from impactbar.laws.wave._characteristics import _Contact

LOADS = [CosineLoad(0.6, 1.0), FourierLoad(0.5, [1.0, 0.0, 0.3j]), SquareWaveLoad(1.0, 1.4),
         SquareWaveLoad(0.7, 1.9)]


@pytest.mark.parametrize("load", LOADS, ids=lambda x: type(x).__name__)
@pytest.mark.parametrize("s", [0.35, 3.0, 10.0])
def test_closed_form_moments_match_the_quadrature(monkeypatch, load, s):
    for t0 in (0.1, 2.5, 6.2):
        for n in (48, 200):
            fast = impact.window_drive(s, 0.4, n, load, t0, derivative=True)
            with monkeypatch.context() as mp:
                mp.setattr(impact, "_exact_moments", lambda *a: None)
                ref = impact.window_drive(s, 0.4, n, load, t0, derivative=True)
            scale = max(float(np.max(np.abs(ref[1]))), 1.0)
            for x, y in zip(fast, ref, strict=True):
                # rounding: the rates carry n pi times the moments' rounding
                np.testing.assert_allclose(x, y, rtol=0.0, atol=5e-14 * scale * n)


def test_closed_form_moment_of_a_constant_drive_is_exact():
    # a level held over the whole window: int_1^2 cos(n pi theta) = 0, int_1^2 sin = ((-1)^n - 1)/(n pi),
    # so h_n = 0 and g_n = (1 - (-1)^n) / (s^2 (n pi)^2) (R = 0, s = 2)
    g, h = impact.window_drive(2.0, 0.0, 64, SquareWaveLoad(1.0, 1.4), 0.1)
    n = np.arange(1, 65)
    np.testing.assert_allclose(h[1:], 0.0, atol=1e-15)
    assert h[0] == pytest.approx(0.5, abs=1e-15)  # int_1^2 P / s
    expected = (1.0 - (-1.0) ** n) / (4.0 * (math.pi * n) ** 2)
    np.testing.assert_allclose(g[1:], expected, rtol=1e-12, atol=1e-17)


@pytest.mark.parametrize("n", [1, 16, 17, 100, 300])
def test_dct_scan_matches_the_dense_sums(n):
    rng = np.random.default_rng(n)
    for load in LOADS[:2]:
        for s in (0.4, 3.0, 10.0):
            q = rng.normal(size=n + 1) / (1.0 + np.arange(n + 1))
            v = rng.normal(size=n + 1) / (1.0 + np.arange(n + 1))
            c = _Contact(s, 0.5, q, v, load, 1.3)
            hg = KW.scan_step(c.N, float(c.p.rate))
            grid = np.unique(np.concatenate([np.linspace(0.0, 1.0, math.ceil(1.0 / hg) + 1),
                                             np.linspace(1.0, 2.0, math.ceil(1.0 / hg) + 1)]))
            fast = c._A_uniform(grid, math.ceil(1.0 / hg))
            assert fast is not None
            np.testing.assert_allclose(fast, c.A(grid), rtol=0.0, atol=1e-13 * c.scale)


@pytest.mark.parametrize("load", [CosineLoad(0.6, 1.0), CosineLoad(0.3, 1.0, 2)], ids=["k1", "k2"])
def test_wave_law_many_modes_same_clearance_as_the_numpy_search(load):
    # s = 3, R = 0.5: the second orbit's flight rests on a plateau after the window, where the
    # end's velocity stays below L h down to tiny intervals (the second-order margin excludes them)
    model = BarModel(3.0, 0.0, 0.5, 128, impact="wave")
    fast = periodic_orbits(model, load)
    with use_reference("admissibility.search"):
        ref = periodic_orbits(model, load)
    assert len(fast) == len(ref) > 0
    for o, g in zip(fast, ref, strict=True):
        assert o.admissibility == g.admissibility
        assert o.clearance == pytest.approx(g.clearance, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("n", [1, 16, 47])
def test_compiled_moments_of_a_piecewise_constant_drive_against_quad(n):
    """The compiled window moments of a piecewise-constant load (closed form between the jumps)
    against scipy's adaptive quadrature of ``P(theta) cos(n pi theta)`` and ``... sin ...`` over each
    half of the window, split at the jumps."""
    from scipy.integrate import quad

    from impactbar.laws.wave._characteristics import _GL_W, _GL_X, _WindowLoad

    for load in LOADS[2:]:
        for s, t0 in ((0.35, 0.1), (3.0, 2.5), (10.0, 6.2), (33.0, 1.38)):
            wl = _WindowLoad(load, s, t0)
            jumps = np.ascontiguousarray(wl.jumps)
            mc, ms = np.zeros((1, 2, n + 1)), np.zeros((1, 2, n + 1))
            KW.window_moments(tuple(load.kernel_view), s, 0.0, np.array([t0]), jumps, _GL_X, _GL_W,
                              mc, ms)
            mc, ms = mc[0], ms[0]

            def drive(th, load=load, s=s, t0=t0):
                return float(load(t0 + th / s))

            for half in (0, 1):
                inside = jumps[(jumps > half) & (jumps < half + 1)]
                edges = np.concatenate(([half], inside, [half + 1]))
                for k in range(n + 1):
                    for weight, got in (("cos", mc[half, k]), ("sin", ms[half, k])):
                        ref = sum(quad(drive, a, b, weight=weight, wvar=k * math.pi, epsabs=1e-14)[0]
                                  for a, b in zip(edges[:-1], edges[1:], strict=True))
                        assert got == pytest.approx(ref, abs=1e-13)


@pytest.mark.parametrize("load", LOADS[:2], ids=lambda x: type(x).__name__)
def test_one_compiled_call_for_many_starts_is_each_start_to_the_bit(load):
    """The moments of many windows (a load without jumps) in one compiled call: each start's
    moments as the call for that start alone gives them, to the bit, in that start's rows."""
    from impactbar.laws.wave._characteristics import _GL_W, _GL_X

    s, M = 3.0, 9
    t0s = 2.0 * math.pi * np.arange(7) / 7 + 0.3
    view = tuple(load.kernel_view)
    jumps = np.empty(0)
    mc, ms = np.zeros((t0s.size, 2, M)), np.zeros((t0s.size, 2, M))
    KW.window_moments(view, s, 1.7, t0s, jumps, _GL_X, _GL_W, mc, ms)
    for i in range(t0s.size):
        c1, s1 = np.zeros((1, 2, M)), np.zeros((1, 2, M))
        KW.window_moments(view, s, 1.7, t0s[i:i + 1], jumps, _GL_X, _GL_W, c1, s1)
        assert np.array_equal(mc[i], c1[0]) and np.array_equal(ms[i], s1[0])
        assert np.all(np.abs(c1[0, :, 0] - (mc[i - 1, :, 0] if i else 0.0)) > 0.0)  # each its own


@pytest.mark.parametrize("load", LOADS, ids=lambda x: type(x).__name__)
@pytest.mark.parametrize("n", [0, 8, 48])
def test_many_starts_are_each_start_to_the_bit(load, n):
    """The phase series' drives at all its starts at once: the single start's numbers, to the bit
    (the compiled quadrature for a Fourier load below 48 modes, start by start otherwise)."""
    t0s = 2.0 * math.pi * np.arange(7) / 7 + 0.3
    g, h = impact.window_drives(3.0, 0.4, n, load, t0s)
    assert g.shape == h.shape == (7, n + 1)
    for i, t0 in enumerate(t0s):
        g1, h1 = impact.window_drive(3.0, 0.4, n, load, float(t0))
        assert np.array_equal(g[i], g1) and np.array_equal(h[i], h1)


def test_many_starts_of_a_constant_drive():
    # a constant p0 over the window: h_0 = (1 - R) p0 / s (the momentum it gives), h_n = 0 for
    # n >= 1 (int cos(n pi theta) vanishes over [0, 1] and [1, 2] alike)
    g, h = impact.window_drives(3.0, 0.4, 5, FourierLoad(0.7, [0.0]), np.array([0.2, 4.0]))
    np.testing.assert_allclose(h[:, 0], 0.6 * 0.7 / 3.0, rtol=1e-14)
    np.testing.assert_allclose(h[:, 1:], 0.0, atol=1e-15)


@pytest.mark.parametrize("k", [1, 3, 10])
@pytest.mark.parametrize("n", [0, 1, 8, 20])
def test_tabled_moments_are_the_kernels_to_the_bit(k, n):
    """The phase series' moments of a load of one harmonic or none from its tabled nodes (one table
    per window, starts and harmonic, the mean load added at each node) against the compiled
    quadrature at each node: the same floats, the sign of every zero included, at mean loads of both
    signs and zero."""
    rng = np.random.default_rng(7 + k + n)
    cases = ((10.1 / math.pi, 0.014, 1.0), (0.7, -0.3, 0.4 - 0.9j), (50.0, 0.0, -2.0), (3.0, 1.3, 0.5j),
             (2.0, 0.8, 0.0), (2.0, -0.0, 0.0))  # (the last two a constant load: no harmonic)
    for s, p0, pk in cases:
        load = FourierLoad(p0, [0.0] * (k - 1) + [pk])
        view, rate = load.abilities.kernel.view, float(k) / s
        for t0s in (2.0 * math.pi * np.arange(2 * k + 1) / (2 * k + 1), rng.uniform(-9.0, 9.0, 5)):
            ref = impact._kernel_moments(tuple(view), s, rate, t0s, np.empty(0), n + 1)
            got = impact._tabled_moments(view, s, rate, t0s, n + 1)
            for x, y in zip(got, ref, strict=True):
                assert x.shape == y.shape == (t0s.size, 2, n + 1)
                assert np.array_equal(x.view(np.uint64), y.view(np.uint64))


@pytest.mark.parametrize("n", [0, 3, 8])
def test_a_constant_drive_at_one_start_is_the_kernels_to_the_bit(monkeypatch, n):
    """A constant load's single window (the wave law's existence edge takes it) from the tabled nodes,
    with its rates, against the compiled quadrature at each node: the same floats, at any start."""
    load = FourierLoad(0.45, [0.0])
    tabled = [impact.window_drive(2.7, 0.3, n, load, t0, derivative=True) for t0 in (0.0, 1.3, -4.0)]
    with monkeypatch.context() as mp:
        mp.setattr(impact, "_tabled_moments", lambda view, s, rate, t0s, M: impact._kernel_moments(
            tuple(view), s, rate, t0s, np.empty(0), M))
        ref = [impact.window_drive(2.7, 0.3, n, load, t0, derivative=True) for t0 in (0.0, 1.3, -4.0)]
    for got, want in zip(tabled, ref, strict=True):
        for x, y in zip(got, want, strict=True):
            assert np.array_equal(x.view(np.uint64), y.view(np.uint64))
