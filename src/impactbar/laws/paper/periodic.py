"""The paper law's one-impact orbits (eqs. 10-13, theory §4, §7): the modal states of the orbit with a
given phase (a root of eq. 14, :mod:`impactbar.laws.paper.phase`), solved mode by mode, and its exact
multipliers. The orbit solvers (:func:`impactbar.periodic_orbits`) decide its admissibility and build
the :class:`~impactbar.PeriodicOrbit`."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..._shared.threads import single_threaded_blas
from ...dynamics.compiled_views import FOURIER
from ...dynamics.monodromy import period_fundamental
from ...loads.abilities import compiled_kind, left_limit
from ..base import BarModelLike, OrbitState
from .stability import floquet_multipliers, rigid_multipliers

if TYPE_CHECKING:
    from ...loads import Load

__all__ = ["orbit_state", "multipliers"]

TWO_PI = 2.0 * math.pi


def _start_state(model: BarModelLike, load: Load, phase: float) -> np.ndarray:
    """Modal state just after the impact of the orbit with this phase (eqs. 10-13)."""
    N = model.n_modes
    R, d = model.R, model.d
    q = np.zeros(N + 1)
    v = np.zeros(N + 1)
    if N > 0:
        w2 = model.frequencies[1:] ** 2
        p11, p12, p21, p22 = (a[1:] for a in period_fundamental(model))
        if compiled_kind(load) == FOURIER:  # fast path: a Fourier load's closed-form periodic response
            # the response from rest over one period, (I - Phi(2 pi)) y_p(phase) with y_p the
            # periodic response (what the flow from rest computes, without building it; it also
            # fixes the orbit's last bits, which the general path's propagation would change)
            qp, vp = load.abilities.periodic_state(w2, d, [phase])
            qp, vp = qp[:, 0], vp[:, 0]
            fq = qp - (p11 * qp + p12 * vp)
            fv = vp - (p21 * qp + p22 * vp)
        else:
            zeros = np.zeros(N)
            fq, fv = load.propagate(w2, d, phase, zeros, zeros, [phase + TWO_PI])
            fq, fv = fq[:, 0], fv[:, 0]
        # y = J_R (Phi y + f),  J_R = diag(1, -R)
        a11, a12, a21, a22 = 1.0 - p11, -p12, R * p21, 1.0 + R * p22
        det = a11 * a22 - a12 * a21
        if np.any(np.abs(det) < 1e-13):
            if R == 1.0 and d == 0.0:
                raise ValueError("R = 1 with d = 0 and flexible modes: a conservative bar with elastic "
                                 "impacts has a continuum of one-impact orbits, not isolated ones; "
                                 "use d > 0, R < 1 or n_modes = 0")
            raise ValueError("the periodicity conditions are singular (undamped resonance, eq. 16)")
        r1, r2 = fq, -R * fv
        q[1:] = (a22 * r1 - a12 * r2) / det
        v[1:] = (a11 * r2 - a21 * r1) / det
    v[0] = -R * TWO_PI * load.p0 / (1.0 + R)
    q[0] = -float(model.end_weights[1:] @ q[1:])
    return np.concatenate((q, v))


def _impact_states(model: BarModelLike, load: Load, phase: float, return_flow: bool = False):
    """Modal states just after (``t = 0+``) and just before (``t = 2 pi-``) the orbit's impact;
    with ``return_flow``, also the flight's flow (the load's own from ``y_plus``) where it is the
    one that gave ``y_minus`` (a Fourier load; else ``None``), for the admissibility search."""
    M = model.n_modes + 1
    y_plus = _start_state(model, load, phase)
    w2 = model.frequencies**2
    flow = None
    if compiled_kind(load) == FOURIER:  # fast path: its propagate is this flow, built once, used twice
        flow = load.abilities.flow(w2, model.d, phase, y_plus[:M], y_plus[M:])
        qm, vm = flow([phase + TWO_PI])
    else:
        qm, vm = load.propagate(w2, model.d, phase, y_plus[:M], y_plus[M:], [phase + TWO_PI])
    y_minus = np.concatenate((qm[:, 0], vm[:, 0]))
    return (y_plus, y_minus, flow) if return_flow else (y_plus, y_minus)


def orbit_state(model: BarModelLike, load: Load, phase: float) -> OrbitState:
    """The paper law's one-impact orbit with this phase (eqs. 10-13): the states just after and just
    before the impact, the exact multipliers (infinite at exact grazing) and the flight's flow for
    the admissibility search."""
    y_plus, y_minus, flow = _impact_states(model, load, phase, return_flow=True)
    try:
        mu = floquet_multipliers(model, load, phase, y_plus, y_minus)
    except ValueError:  # exact grazing: a multiplier is infinite
        mu = np.full(y_plus.size, np.inf + 0j)
    return OrbitState(state_after_impact=y_plus, state_before_impact=y_minus, multipliers=mu, flow=flow)


def multipliers(model: BarModelLike, load: Load, phase: float) -> np.ndarray:
    """Exact Floquet multipliers of the one-impact orbit with this phase under the paper's law
    (eq. 10, theory §7), without the admissibility check: in closed form for the rigid bar, else
    from the monodromy with its saltation term.

    Returns
    -------
    numpy.ndarray of complex, shape (2 N + 2,)
        Sorted by decreasing modulus.

    Raises
    ------
    ValueError
        At grazing (zero arrival velocity), where the saltation term is infinite, or where the
        periodicity conditions are singular.
    """
    y_plus, y_minus = _impact_states(model, load, phase)
    if model.n_modes == 0:  # the 2 x 2 Jacobian in closed form
        mu = rigid_multipliers(model.d, model.R, float(load(phase)), float(left_limit(load, phase)),
                               y_plus[1], y_minus[1])
        if not np.all(np.isfinite(mu)):
            raise ValueError("grazing impact (zero arrival velocity): the saltation term is infinite")
        return mu
    with single_threaded_blas():
        return floquet_multipliers(model, load, phase, y_plus, y_minus)
