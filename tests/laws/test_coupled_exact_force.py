"""The coupled exact blow's drive as the exact solver takes it (theory §11, "The coupled blow": the
drive's cubic pieces): the integrator's steps, the first one after each restart some ``1e-13`` long,
as cubic pieces that follow the force the steps' Hermite interpolant gives, with no step of their
own where a short step is taken over by the next."""

import types

import numpy as np
import pytest
from coupled_reference import drifter_arrival

from impactbar.laws.rodrock.coupled_exact import _Force


def _flight(t0, edges, tiny):
    """A flight's steps over ``edges`` (a restart at each, its first step ``tiny`` long) of a smooth
    chamber pair: the rear pressure ``0.5 + 0.1 sin 300 t``, the front ``0.2 + 0.05 cos 200 t``."""
    pieces = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        t = np.concatenate(([a, a + tiny], np.linspace(a + 1e-4 * (b - a), b, 40)[1:]))
        y = np.zeros((t.size, 3))
        f = np.zeros_like(y)
        y[:, 1], f[:, 1] = 0.2 + 0.05 * np.cos(200.0 * t), -10.0 * np.sin(200.0 * t)
        y[:, 2], f[:, 2] = 0.5 + 0.1 * np.sin(300.0 * t), 30.0 * np.cos(300.0 * t)
        pieces.append(types.SimpleNamespace(t=t0 + t, y=y, f=f, alpha=0.4))
    return pieces


def _value(piece, tau):
    exps, degs, coefs = piece
    return float(np.real(np.sum(coefs * tau ** degs * np.exp(exps * tau))))


@pytest.mark.parametrize("tiny", [6e-13, 1e-11])
def test_the_drives_pieces_have_no_step_where_a_short_step_is_taken_over(tiny):
    t0, horizon = 2.0, 0.05
    edges = np.array([0.0, 0.004, 0.0113, 0.0123, 0.03, horizon])
    force = _Force(0.5 - 0.4 * 0.25, _flight(t0, edges, tiny), t0)
    starts, pieces = force.pieces(0.004, horizon)
    assert np.all(np.diff(starts) > 1e-9 * horizon)  # (no step the solver cannot take)

    def exact(t):
        return 0.5 + 0.1 * np.sin(300.0 * t) - 0.4 * (0.2 + 0.05 * np.cos(200.0 * t))

    size = 0.7
    for j in range(1, len(pieces) - 1):
        # continuous where one piece gives way to the next (the Hermite interpolant is), and on the
        # force: the steps' Hermite error, ``h^4`` (measured: 1e-7 on these steps, 1e-16 at a join)
        end = _value(pieces[j], starts[j + 1] - starts[j])
        nxt = _value(pieces[j + 1], 0.0) if j + 1 < len(pieces) - 1 else end
        assert abs(end - nxt) <= 1e-12 * size
        mid = 0.5 * (starts[j] + starts[j + 1])
        assert abs(_value(pieces[j], mid - starts[j]) - exact(mid)) <= 1e-6 * size
        assert abs(float(force(mid)[0]) - exact(mid)) <= 1e-6 * size


def test_the_drifters_coupled_blow_meets_a_drive_without_steps():
    """On ``examples/circuit_drifter_rock.toml`` the drive's integration restarts at each jump of the
    arriving wave: the drive the last iterate's blow met is continuous at every join of its pieces
    (a step there, up to a fifth of the force where a short first step's cubic was continued over
    the next step, sends the piston a jump that moves with the data and that the blow's tangent
    does not carry)."""
    model, drive, state, t0, q, v = drifter_arrival()
    blow = model.law.driven_contact(model, drive, state, t0, q, v)
    starts, pieces = blow.record._map.drive
    ends = [_value(p, b - a) for p, a, b in zip(pieces[1:-2], starts[1:-2], starts[2:-1], strict=True)]
    heads = [_value(p, 0.0) for p in pieces[2:-1]]
    size = float(np.max(np.abs(heads)))
    assert len(heads) > 1000
    assert np.max(np.abs(np.subtract(ends, heads))) <= 1e-12 * size  # (measured: 1e-14)
