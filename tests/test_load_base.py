"""The load's base is narrow and knows none of its subclasses: a load written here with the required
hooks alone finds, refines and continues its orbits, and what a solver may know beyond them is what
the load returns in its abilities (none here)."""

import inspect
import re

import numpy as np
import pytest

import impactbar
from impactbar import BarModel, FourierLoad, continue_orbit, find_orbit, periodic_orbits, simulate
from impactbar.loads import Load
from impactbar.loads import base as load_base
from impactbar.loads.abilities import compiled_kind, exact_flow, jumps, left_limit, periodic_state


class TwoHarmonics(Load):
    """``p0 + a cos t + b sin 2t``, written with the required hooks alone (and ``p0``, ``_key``); its
    modal response is the closed form of eq. 8 computed here, not the package's."""

    def __init__(self, p0, a, b):
        self._set(p0=p0, a=a, b=b)

    def _key(self):
        return (self.p0, self.a, self.b)

    def _terms(self):
        return np.array([1.0, 2.0]), np.array([self.a, -1j * self.b])  # p = p0 + Re sum p_k e^{ikt}

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        return self.p0 + self.a * np.cos(t) + self.b * np.sin(2.0 * t)

    def harmonics(self, n=None):
        k, pk = self._terms()
        out = np.zeros(2 if n is None else n, dtype=complex)
        out[: min(out.size, 2)] = pk[: out.size]
        return out

    @property
    def sup_abs(self):
        return abs(self.p0) + abs(self.a) + abs(self.b)

    @property
    def sup_oscillation(self):
        return abs(self.a) + abs(self.b)

    def variation(self, mid, half):
        half = np.asarray(half, dtype=float)
        return self(mid), np.minimum((abs(self.a) + 2.0 * abs(self.b)) * half, 2.0 * self.sup_oscillation)

    def _particular(self, w2, d, t):
        """The periodic response and its velocity, shape (M, T), rigid mode (``w2 = 0``) without
        its mean part."""
        k, pk = self._terms()
        h = pk[None, :] / (w2[:, None] + 1j * d * k[None, :] - k[None, :] ** 2)
        e = np.exp(1j * np.outer(k, t))
        q, v = (h @ e).real, ((h * 1j * k) @ e).real
        q[w2 > 0] += self.p0 / w2[w2 > 0, None]
        return q, v

    def propagate(self, w2, d, t0, q0, v0, t):
        w2 = np.asarray(w2, dtype=float)
        t = np.atleast_1d(np.asarray(t, dtype=float))
        qp0, vp0 = self._particular(w2, d, [t0])
        qp, vp = self._particular(w2, d, t)
        dq, dv = np.asarray(q0, float) - qp0[:, 0], np.asarray(v0, float) - vp0[:, 0]
        tau = t - t0
        q, v = np.empty_like(qp), np.empty_like(vp)
        for i, w in enumerate(w2):
            if w == 0.0:  # q'' + d q' = p0 + oscillation: exp(-d tau) and the mean's ramp
                e = np.exp(-d * tau)
                b = (1.0 - e) / d if d else tau
                c = (tau - b) / d if d else 0.5 * tau**2
                q[i] = qp[i] + dq[i] + b * dv[i] + self.p0 * c
                v[i] = vp[i] + e * dv[i] + self.p0 * b
            else:  # an underdamped mode: the homogeneous solution in closed form
                lam = np.sqrt(w - 0.25 * d * d)
                e, C, S = np.exp(-0.5 * d * tau), np.cos(lam * tau), np.sin(lam * tau)
                q[i] = qp[i] + e * (dq[i] * C + (dv[i] + 0.5 * d * dq[i]) / lam * S)
                v[i] = vp[i] + e * (dv[i] * C - (w * dq[i] + 0.5 * d * dv[i]) / lam * S)
        return q, v

    def rigid_velocity(self, d, t):
        k, pk = self._terms()
        e = np.exp(1j * np.multiply.outer(np.asarray(t, dtype=float), k))
        return (e @ (pk / (d + 1j * k))).real


MODEL = BarModel(s=10.0, d=0.05, R=0.5, n_modes=2)
MINE = TwoHarmonics(0.3, 1.0, 0.2)
SAME = FourierLoad(0.3, [1.0, -0.2j])  # the package's load of the same numbers (its compiled paths)


def test_a_load_with_the_required_hooks_alone_runs():
    """Its one-impact orbits, an orbit refined by ``find_orbit`` and a branch in ``R`` against those
    of the package's Fourier load of the same harmonics; it declares no ability, no parameter and no
    kernel, so the simulator, which needs one, refuses it in one line."""
    assert set(vars(TwoHarmonics)) & set(Load.__abstractmethods__) == set(Load.__abstractmethods__)
    own = MINE.abilities
    assert (own.kernel, own.cosine, own.pieces, own.orders, own.period) == (None, None, None, None, 2 * np.pi)
    assert MINE.params.parameter_table() == () and compiled_kind(MINE) is None
    ref, got = periodic_orbits(MODEL, SAME), periodic_orbits(MODEL, MINE)
    assert len(ref) == len(got) > 0
    for a, b in zip(ref, got, strict=True):
        assert a.admissibility == b.admissibility
        np.testing.assert_allclose(b.phase, a.phase, rtol=0.0, atol=1e-10)
        np.testing.assert_allclose(b.impact_velocity, a.impact_velocity, rtol=1e-10)
        np.testing.assert_allclose(np.abs(b.multipliers), np.abs(a.multipliers), rtol=1e-8)
    o = find_orbit(MODEL, MINE, guess=got[0])
    assert o.phase == pytest.approx(got[0].phase, abs=1e-10)
    branch = continue_orbit(o, "R", to=0.6, max_points=20)
    assert branch.values[-1] == pytest.approx(0.6, abs=1e-12)
    end = branch.orbits[-1]
    at = min(periodic_orbits(MODEL.with_(R=0.6), SAME), key=lambda x: abs(x.phase - end.phase))
    assert end.phase == pytest.approx(at.phase, abs=1e-8)
    assert end.impact_velocity == pytest.approx(at.impact_velocity, rel=1e-8)
    with pytest.raises(ValueError, match="^load must be"):
        simulate(MODEL, MINE, impactbar.InitialState.rigid(-0.5, 0.0), 1.0)


def test_the_general_answers_from_the_required_hooks():
    """Without abilities of its own a load's left limit is its value, it has no jumps, and its flow
    and periodic response come from ``propagate``: against the Fourier load's closed forms."""
    t = np.linspace(0.0, 7.0, 9)
    w2 = MODEL.frequencies**2
    np.testing.assert_array_equal(left_limit(MINE, t), MINE(t))
    assert jumps(MINE, 0.0, 10.0).size == 0
    q0, v0 = np.array([0.1, -0.2, 0.05]), np.array([0.3, 0.0, -0.1])
    got = exact_flow(MINE, w2, MODEL.d, 0.4, q0, v0)(t + 0.4)
    ref = exact_flow(SAME, w2, MODEL.d, 0.4, q0, v0)(t + 0.4)
    np.testing.assert_allclose(got[0], ref[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(got[1], ref[1], rtol=0, atol=1e-12)
    got, ref = periodic_state(MINE, w2[1:], MODEL.d, t), periodic_state(SAME, w2[1:], MODEL.d, t)
    np.testing.assert_allclose(got[0], ref[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(got[1], ref[1], rtol=0, atol=1e-12)


def _subclass_names() -> set[str]:
    def walk(cls):
        return {cls}.union(*(walk(sub) for sub in cls.__subclasses__()))

    return {c.__name__ for c in walk(Load) if c.__module__.startswith("impactbar.")} - {"Load"}


def test_the_base_names_no_subclass():
    """The module of :class:`Load` names none of the package's loads (not in code, not in a
    docstring), nor walks a class's ancestors or descendants: what a solver needs to know of a load's
    form, the load returns."""
    names = _subclass_names()
    assert {"CosineLoad", "FourierLoad", "SquareWaveLoad", "PiecewiseConstantLoad"} <= names
    source = inspect.getsource(load_base)
    found = sorted(n for n in names if re.search(rf"\b{n}\b", source))
    assert found == []
    assert not re.search(r"__mro__|__subclasses__|\bmro\(", source)
