"""Stability of one-impact orbits: the verdict (theory §5, §7) and the paper's Schur criterion
(Section 3, eqs. 25-32), which the orbit solvers apply to every one-impact orbit. The exact Floquet
multipliers are the laws' (:mod:`impactbar.laws.paper.stability` for eq. 10, with the building
blocks every law shares in :mod:`impactbar.dynamics.monodromy`); their public names are re-exported
here."""

from __future__ import annotations

import math

import numpy as np

from ..dynamics.monodromy import period_fundamental as period_fundamental
from ..dynamics.monodromy import sort_multipliers as sort_multipliers
from ..laws.paper.stability import floquet_multipliers as floquet_multipliers
from ..laws.paper.stability import impact_map_jacobian as impact_map_jacobian
from ..loads import Load
from ..loads.abilities import periodic_state
from ..model import BarModel

__all__ = ["impact_map_jacobian", "floquet_multipliers", "period_fundamental", "sort_multipliers",
           "schur_blocks", "schur_test", "quadratic_roots"]

TWO_PI = 2.0 * math.pi

#: A multiplier within this of the unit circle is marginal: the orbit is not called stable.
MARGINAL = 1e-9


def stable_verdict(admissible: bool, multipliers) -> bool:
    """The stability verdict of a periodic orbit (theory §5, §7): admissible, and every Floquet
    multiplier inside the unit circle by more than :data:`MARGINAL`."""
    return bool(admissible and np.all(np.abs(multipliers) < 1.0 - MARGINAL))


def schur_blocks(model: BarModel, load: Load, phase: float) -> np.ndarray:
    """The paper's quadratic blocks ``a2 xi^2 + a1 xi + a0`` (eqs. 27, 29-31), one per mode.

    The rigid block uses (eqs. 29, 30), with the harmonic sums in closed form:
    ``p0 sigma = (1/pi) sum_n (-1)^n v_n(phase)`` with ``v_n`` the periodic velocity response of mode
    ``n`` to the load, and ``p0 S2 = p(phase+) - p0 - d V(phase)``. Both are multiplied through by
    ``p0``, which leaves the roots unchanged and keeps ``p0 = 0`` finite. The flexible blocks use
    eq. 31 (valid for ``s >> 1``).

    Returns
    -------
    numpy.ndarray, shape (N + 1, 3)
        Rows ``(a2, a1, a0)``; row 0 is the rigid block.
    """
    N = model.n_modes
    d, R = model.d, model.R
    p0 = load.p0
    e2 = math.exp(-TWO_PI * d)
    if N > 0:
        w2 = model.frequencies[1:] ** 2
        _, vper = periodic_state(load, w2, d, [phase])
        if model.piston is None:
            sig = float(np.sum((-1.0) ** np.arange(1, N + 1) * vper[:, 0])) / math.pi
        else:  # (c_n / 2 for the stepped piston's (-1)^n, theory §12)
            sig = float(model.end_weights[1:] @ vper[:, 0]) / (2.0 * math.pi)
    else:
        sig = 0.0
    S2 = float(load(phase)) - p0 - d * float(load.rigid_velocity(d, phase))
    y = TWO_PI * d
    bracket = 1.0 - 0.5 * y if y < 1e-8 else -math.expm1(-y) / y  # series: no denormal quotient
    blocks = np.empty((N + 1, 3))
    blocks[0, 0] = p0 + (1.0 + R) * sig
    blocks[0, 1] = (-(1.0 + R * R * e2) * p0 - bracket * (1.0 + R) ** 2 * S2
                    - (1.0 - R * e2) * (1.0 + R) * sig)
    blocks[0, 2] = R * e2 * (R * p0 - (1.0 + R) * sig)
    if N > 0:
        lam = np.sqrt((model.frequencies[1:] ** 2 - 0.25 * d * d).astype(complex))
        blocks[1:, 0] = 1.0
        blocks[1:, 1] = -(1.0 - R) * math.exp(-math.pi * d) * np.cos(TWO_PI * lam).real
        blocks[1:, 2] = -R * e2
    return blocks


def schur_test(blocks: np.ndarray) -> bool:
    """Schur's conditions (eq. 28) on every block: ``|a0/a2| < 1`` and ``|a1/(a0 + a2)| < 1``."""
    a2, a1, a0 = blocks[:, 0], blocks[:, 1], blocks[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        ok = (np.abs(a0) < np.abs(a2)) & (np.abs(a1) < np.abs(a0 + a2))
    return bool(np.all(ok))


def quadratic_roots(blocks: np.ndarray) -> np.ndarray:
    """Both roots of each block ``a2 xi^2 + a1 xi + a0``, shape ``(2 (N + 1),)`` complex."""
    a2, a1, a0 = (blocks[:, j].astype(complex) for j in range(3))
    disc = np.sqrt(a1 * a1 - 4.0 * a2 * a0)
    # the numerically stable pair
    sgn = np.where((np.conj(a1) * disc).real >= 0.0, 1.0, -1.0)
    qq = -0.5 * (a1 + sgn * disc)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # a2 subnormal: inf
        r1 = np.where(a2 != 0, qq / a2, complex(np.inf, 0.0))  # a2 = 0: a root at infinity
        r2 = np.where(qq != 0, a0 / qq, 0.0)
    return np.column_stack((r1, r2)).ravel()
