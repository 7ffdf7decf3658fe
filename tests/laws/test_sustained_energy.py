"""The wave law's sustained contact: its energy integrals in closed form against an
independent Gauss-Legendre quadrature of the same motion, and the run's account closing.

Before, the integrals were the quadrature below on panels as fine as the fastest transient: 12 s per
load period at s = 50 with 40 modes, eight times the simulation."""

import math

import numpy as np
import pytest
from scipy.integrate import quad_vec

from impactbar import BarModel, CosineLoad, InitialState, SquareWaveLoad, simulate
from impactbar.laws.wave.sustained import sustained_contact


def quadrature(sc, tau):
    """``(work, rod, damping, advance)`` by scipy's adaptive ``quad_vec`` of the exact states of
    every piece (the states, not the closed form's exponentials, are integrated)."""
    out = np.zeros(4)
    t_end = sc.t0 + tau
    for p in sc._pieces:
        a, b = p.ta, min(p.tb, t_end)
        if b <= a:
            break

        def integrands(t, p=p):
            v = p.states(np.array([t]))[sc.N:, 0]
            ut1 = sc.c @ v
            pn = float(sc.load(np.array([t]))[0]) if p.level is None else p.level
            return np.array([pn * (sc.kappa @ v), sc.impedance * ut1 * ut1,
                             sc.model.d * (sc.kappa @ (v * v)), ut1])

        out += quad_vec(integrands, a, b, epsabs=1e-14, epsrel=1e-12, limit=2000)[0]
    return out


@pytest.mark.parametrize("load", [CosineLoad(3.0, 1.0), CosineLoad(3.0, 2.0, k=2),
                                  SquareWaveLoad(2.0, 1.8)], ids=repr)
@pytest.mark.parametrize("s, d, R, N", [(3.0, 0.1, 0.5, 4), (6.0, 0.3, 0.2, 6)])
def test_closed_form_integrals_match_quadrature(load, s, d, R, N):
    model = BarModel(s, d, R, N, impact="wave")
    rng = np.random.default_rng(N)
    q, v = 1e-4 * rng.normal(size=N + 1), 1e-3 * rng.normal(size=N + 1)
    v[0] = 1.0  # the struck end moving into the rod, the modes ringing a little
    q[0] = -float(model.end_weights[1:] @ q[1:])
    sc = sustained_contact(model, load, 0.3, q, v, 0.3 + 9.0)
    assert sc.duration > 0.9  # pressed for a while (most over two load pieces)
    for tau in (0.5 * sc.duration, sc.duration):
        closed = np.array(sc._integrals(tau))
        ref = quadrature(sc, tau)
        assert closed == pytest.approx(ref, rel=1e-10, abs=1e-12 * np.max(np.abs(ref)))


def test_energy_account_closes_at_large_s_fast(monkeypatch):
    """The case of ``benchmarks/bench_energy.py`` (s = 50, 40 modes, a pressing load): the account
    closes to rounding and the sustained contacts' integrals need no quadrature (the closed form is
    O(N^2) a piece): the states are evaluated at a handful of times (the quadrature asked for
    160,000 a load period)."""
    from impactbar.laws.wave import sustained

    times = []
    inner = sustained._Piece.states

    def counted(self, t):
        times.append(np.size(t))
        return inner(self, t)

    monkeypatch.setattr(sustained._Piece, "states", counted)
    model = BarModel(50.0, 0.1, 0.5, 40, impact="wave")
    tr = simulate(model, CosineLoad(2.0, 1.0), InitialState.rigid(-0.5, 0.0, n_modes=40),
                  4 * math.pi)
    times.clear()
    acc = tr.energy
    assert 0 < sum(times) < 100
    assert acc.relative_residual < 1e-9
    assert acc.damping_loss > 0.0 and acc.impact_loss > 0.0
